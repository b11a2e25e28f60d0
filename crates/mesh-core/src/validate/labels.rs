//! Layer 2, labels: every triangle separates two different materials, and around every
//! edge each wedge of space is one material.
//!
//! Around an edge `lo → hi` the incident triangles, sorted radially (layer 1 did that),
//! cut space into wedges; the wedge between consecutive triangles `here` and `next` is
//! faced by `here`'s counter-clockwise side and `next`'s clockwise side
//! ([`EdgeIncidence::ccw_corner`] / [`EdgeIncidence::cw_corner`]), and both must carry
//! the same label. For an ordinary two-triangle edge this says the two triangles are
//! consistently oriented relative to their labels.

use rayon::prelude::*;

use super::report::{InconsistentEdge, Listed, SameLabel, ValidationReport};
use super::topology::{CHUNK, EdgeContext};
use crate::connectivity::EdgeIncidence;
use crate::ids::TriId;
use crate::mesh::LabeledMesh;

/// Runs layer 2 on the radially sorted edges of layer 1.
pub(super) fn check(
    mesh: &LabeledMesh,
    ctx: &EdgeContext,
    cap: usize,
    report: &mut ValidationReport,
) {
    same_label(mesh, cap, report);
    let groups = ctx.groups();
    let parts: Vec<Listed<InconsistentEdge>> = groups
        .par_chunks(CHUNK)
        .map(|chunk| {
            let mut out = Listed::default();
            for group in chunk {
                if let Some(bad) = first_bad_wedge(mesh, group) {
                    out.push(bad, cap);
                }
            }
            out
        })
        .collect();
    for p in parts {
        report.inconsistent_edges.append(p, cap);
    }
}

fn same_label(mesh: &LabeledMesh, cap: usize, report: &mut ValidationReport) {
    let alive = mesh.tri_alive_flags();
    let labels = mesh.label_pairs();
    let parts: Vec<Listed<SameLabel>> = (0..alive.len())
        .into_par_iter()
        .chunks(CHUNK)
        .map(|range| {
            let mut out = Listed::default();
            for t in range {
                let [front, back] = labels[t];
                if alive[t] && front == back {
                    out.push(
                        SameLabel {
                            tri: TriId::new(t as u32),
                            label: front,
                        },
                        cap,
                    );
                }
            }
            out
        })
        .collect();
    for p in parts {
        report.same_label_triangles.append(p, cap);
    }
}

/// The first wedge (counter-clockwise from the first triangle) whose two bounding sides
/// disagree, if any. Boundary edges (one triangle) and degenerate edges have no wedge.
fn first_bad_wedge(mesh: &LabeledMesh, group: &[EdgeIncidence]) -> Option<InconsistentEdge> {
    let m = group.len();
    if m < 2 || group[0].lo == group[0].hi {
        return None;
    }
    let tris = mesh.tris();
    (0..m).find_map(|i| {
        let (here, next) = (group[i], group[(i + 1) % m]);
        let a = mesh.corner_label(here.ccw_corner(tris));
        let b = mesh.corner_label(next.cw_corner(tris));
        (a != b).then(|| InconsistentEdge {
            edge: [here.lo, here.hi],
            tris: group.iter().map(|e| e.tri).collect(),
            wedge: [here.tri, next.tri],
            labels: [a, b],
        })
    })
}
