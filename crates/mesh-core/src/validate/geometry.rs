//! Layer 3, geometry: finite coordinates, and no triangle of zero area.
//!
//! "Zero area" is decided exactly: a triangle with three distinct vertices is flat when
//! its three points are collinear, i.e. its normal `(b−a)×(c−a)` is exactly zero, i.e.
//! the exact [`orient2d_axis`] is zero along all three axes (each is the sign of one
//! normal component). Triangles with a repeated vertex are layer 1's `degenerate` and
//! triangles with a non-finite vertex are left to `non_finite`, so each defect is
//! reported once, in its own category.

use rayon::prelude::*;

use super::report::{Listed, ValidationReport};
use super::topology::{CHUNK, EdgeContext};
use crate::ids::{TriId, VertexId};
use crate::mesh::LabeledMesh;
use crate::predicates::collinear;

/// Runs layer 3.
pub(super) fn check(
    mesh: &LabeledMesh,
    ctx: &EdgeContext,
    cap: usize,
    report: &mut ValidationReport,
) {
    let positions = mesh.positions();
    let parts: Vec<Listed<VertexId>> = (0..positions.len())
        .into_par_iter()
        .chunks(CHUNK)
        .map(|range| {
            let mut out = Listed::default();
            for v in range {
                let id = VertexId::new(v as u32);
                if mesh.is_vertex_alive(id) && !positions[v].is_finite() {
                    out.push(id, cap);
                }
            }
            out
        })
        .collect();
    for p in parts {
        report.non_finite.append(p, cap);
    }

    let tris = mesh.tris();
    let parts: Vec<Listed<TriId>> = (0..tris.len())
        .into_par_iter()
        .chunks(CHUNK)
        .map(|range| {
            let mut out = Listed::default();
            for t in range {
                if ctx.usable[t] && is_zero_area(mesh, TriId::new(t as u32)) {
                    out.push(TriId::new(t as u32), cap);
                }
            }
            out
        })
        .collect();
    for p in parts {
        report.zero_area.append(p, cap);
    }
}

/// Three distinct vertices, finite, exactly collinear. The triangle must be usable
/// (vertex ids in range).
pub(super) fn is_zero_area(mesh: &LabeledMesh, t: TriId) -> bool {
    let [a, b, c] = mesh.tri(t);
    if a == b || b == c || c == a {
        return false;
    }
    let [p, q, r] = mesh.tri_positions(t);
    if !(p.is_finite() && q.is_finite() && r.is_finite()) {
        return false;
    }
    collinear(p, q, r)
}
