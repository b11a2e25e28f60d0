//! Layer 3, geometry: finite coordinates within the supported range
//! ([`crate::predicates::range`]), and no triangle of zero area.
//!
//! "Zero area" is decided exactly: a triangle with three distinct vertices is flat when
//! its three points are collinear, i.e. its normal `(b−a)×(c−a)` is exactly zero, i.e.
//! the exact [`orient2d_axis`] is zero along all three axes (each is the sign of one
//! normal component). Triangles with a repeated vertex are layer 1's `degenerate` and
//! triangles with a non-finite or out-of-range vertex are left to `non_finite` and
//! `out_of_range` (the exact predicates are not exact there), so each defect is reported
//! once, in its own category.

use glam::DVec3;
use rayon::prelude::*;

use super::report::{Listed, ValidationReport};
use super::topology::{CHUNK, EdgeContext};
use crate::ids::{TriId, VertexId};
use crate::mesh::LabeledMesh;
use crate::predicates::{below_min_extent, collinear, within_max_coordinate};

/// Runs layer 3.
pub(super) fn check(
    mesh: &LabeledMesh,
    coordinates: CoordinateRange,
    ctx: &EdgeContext,
    cap: usize,
    report: &mut ValidationReport,
) {
    let positions = mesh.positions();
    let parts: Vec<(Listed<VertexId>, Listed<VertexId>)> = (0..positions.len())
        .into_par_iter()
        .chunks(CHUNK)
        .map(|range| {
            let (mut non_finite, mut out_of_range) = (Listed::default(), Listed::default());
            for v in range {
                let id = VertexId::new(v as u32);
                if !mesh.is_vertex_alive(id) {
                    continue;
                }
                if !positions[v].is_finite() {
                    non_finite.push(id, cap);
                } else if !coordinates.contains(positions[v]) {
                    out_of_range.push(id, cap);
                }
            }
            (non_finite, out_of_range)
        })
        .collect();
    for (non_finite, out_of_range) in parts {
        report.non_finite.append(non_finite, cap);
        report.out_of_range.append(out_of_range, cap);
    }

    let tris = mesh.tris();
    let parts: Vec<Listed<TriId>> = (0..tris.len())
        .into_par_iter()
        .chunks(CHUNK)
        .map(|range| {
            let mut out = Listed::default();
            for t in range {
                let t = TriId::new(t as u32);
                if ctx.usable[t.idx()]
                    && mesh
                        .tri_positions(t)
                        .into_iter()
                        .all(|p| coordinates.contains(p))
                    && is_zero_area(mesh, t)
                {
                    out.push(t, cap);
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

/// The supported coordinate range for one mesh ([`crate::predicates::range`]): every
/// coordinate at most the largest, and the mesh's largest live coordinate magnitude not
/// below the smallest extent (when it is, every position fails). Found once per
/// validation by [`coordinate_range`] and shared by layers 3 and 5.
#[derive(Clone, Copy, Debug)]
pub(super) struct CoordinateRange {
    tiny: bool,
}

impl CoordinateRange {
    /// Whether `p` is finite and inside the range.
    pub fn contains(self, p: DVec3) -> bool {
        !self.tiny && within_max_coordinate(p)
    }
}

/// The [`CoordinateRange`] of `mesh`.
pub(super) fn coordinate_range(mesh: &LabeledMesh) -> CoordinateRange {
    CoordinateRange {
        tiny: below_min_extent(coordinate_extent(mesh)),
    }
}

/// The mesh's size as the range bounds measure it: the largest magnitude of any
/// coordinate of its live finite vertices (0 for an empty mesh). One parallel pass; what
/// [`crate::predicates::below_min_extent`] is asked about, here and by callers that check
/// a mesh's range before handing it on.
pub fn coordinate_extent(mesh: &LabeledMesh) -> f64 {
    let positions = mesh.positions();
    (0..positions.len())
        .into_par_iter()
        .with_min_len(CHUNK)
        .filter(|&v| mesh.is_vertex_alive(VertexId::new(v as u32)) && positions[v].is_finite())
        .map(|v| positions[v].abs().max_element())
        .reduce(|| 0.0, f64::max)
}
