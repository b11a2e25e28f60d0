//! The intersection of the mesh with one grid face, as a graph (§6.2, Fig. 8).
//!
//! Under the symbolic perturbation every triangle meets a grid face in a segment or not
//! at all. A segment's two ends are of two kinds:
//! - a **grid-edge point**: the triangle crosses one of the face's four edges (the
//!   crossings filed by [`crate::stages::materials`]);
//! - a **mesh-edge point**: one of the triangle's edges pierces the face interior; all
//!   triangles around that mesh edge share the point.
//!
//! Points are graph nodes and segments graph edges. Fig. 8: in a non-degenerate
//! configuration each triangle meeting the face has exactly two end points; any other
//! count is an inconsistency (a *flawed* face). The face is *complex* when the graph has
//! a cycle: a closed curve inside the face that the grid cannot see.
//!
//! The piercing test ([`segment_pierces_face`]) uses the same perturbation and the same
//! 2D orientation formula as [`mesh_core::predicates::cross_axis_line_triangle`] for the
//! face's boundary lines, so the counts are consistent by construction: with exact
//! arithmetic, Fig. 8's inconsistencies arise only from an open or broken mesh. The
//! segments are exactly the constraints the cutting stage (§7, App. A) needs.

use glam::{DVec2, DVec3};
use mesh_core::predicates::{Axis, Sign, orient2d_sos};
use mesh_core::{LabeledMesh, TriId, VertexId};

use crate::stages::grid::primitives::GridFace;
use crate::stages::grid::{Grid, Lattice};
use crate::stages::materials::Materials;

/// An end point of a face segment.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FacePoint {
    /// Where the segment's triangle crosses boundary edge `slot` of the face (slots in the
    /// order of [`GridFace::edges`]).
    GridEdge(u8),
    /// Where mesh edge `(a, b)`, `a < b`, pierces the face interior.
    MeshEdge(VertexId, VertexId),
}

/// The part of one triangle inside one grid face.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FaceSegment {
    /// The triangle.
    pub tri: TriId,
    /// Its two end points.
    pub ends: [FacePoint; 2],
}

/// What [`intersect_face`] found.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FaceReport {
    /// Some triangle meets the face.
    pub touched: bool,
    /// The intersection graph has a cycle (§6.2: complex face).
    pub cycle: bool,
    /// A triangle meets the face in other than two points (Fig. 8: flawed face).
    pub inconsistent: bool,
}

/// Reusable buffers for [`intersect_face`], so checking many faces allocates nothing per
/// face once warmed up.
#[derive(Clone, Debug, Default)]
pub struct FaceScratch {
    points: Vec<FacePoint>,
    attach: Vec<(TriId, u32)>,
    parent: Vec<u32>,
    segments: Vec<FaceSegment>,
}

impl FaceScratch {
    /// Empty buffers.
    pub fn new() -> Self {
        Self::default()
    }

    /// The segments of the last face intersected.
    pub fn segments(&self) -> &[FaceSegment] {
        &self.segments
    }

    fn find(&mut self, mut i: u32) -> u32 {
        while self.parent[i as usize] != i {
            let up = self.parent[self.parent[i as usize] as usize];
            self.parent[i as usize] = up;
            i = up;
        }
        i
    }
}

/// Intersects the mesh with grid face `face`; the segments are left in `scratch`.
pub fn intersect_face(
    mesh: &LabeledMesh,
    grid: &Grid,
    materials: &Materials,
    face: GridFace,
    scratch: &mut FaceScratch,
) -> FaceReport {
    scratch.points.clear();
    scratch.attach.clear();
    scratch.segments.clear();
    // Every triangle touching the closed face touches both closed cells, so either
    // allocated cell lists them all; no allocated cell means no mesh here.
    let Some(cell) = face.cells().into_iter().find_map(|c| grid.cell_id(c)) else {
        return FaceReport::default();
    };
    for (slot, edge) in face.edges().into_iter().enumerate() {
        let Some(n) = grid.node_id(edge.node) else {
            continue;
        };
        for x in materials.edge_crossings(n, edge.axis) {
            scratch.attach.push((x.tri, scratch.points.len() as u32));
            scratch.points.push(FacePoint::GridEdge(slot as u8));
        }
    }
    let lattice = grid.lattice();
    for &t in grid.cell_triangles(cell) {
        let v = mesh.tri(t);
        for k in 0..3 {
            let (a, b) = (v[k], v[(k + 1) % 3]);
            if !segment_pierces_face(lattice, face, mesh.position(a), mesh.position(b)) {
                continue;
            }
            let key = FacePoint::MeshEdge(a.min(b), a.max(b));
            let i = match scratch.points.iter().position(|&p| p == key) {
                Some(i) => i,
                None => {
                    scratch.points.push(key);
                    scratch.points.len() - 1
                }
            };
            scratch.attach.push((t, i as u32));
        }
    }

    let mut report = FaceReport {
        touched: !scratch.attach.is_empty(),
        ..FaceReport::default()
    };
    scratch.attach.sort_unstable();
    scratch.parent.clear();
    scratch.parent.extend(0..scratch.points.len() as u32);
    let mut i = 0;
    while i < scratch.attach.len() {
        let t = scratch.attach[i].0;
        let run = scratch.attach[i..].iter().take_while(|a| a.0 == t).count();
        if run == 2 {
            let (p, q) = (scratch.attach[i].1, scratch.attach[i + 1].1);
            let (rp, rq) = (scratch.find(p), scratch.find(q));
            if rp == rq {
                report.cycle = true;
            } else {
                scratch.parent[rp as usize] = rq;
            }
            let ends = [scratch.points[p as usize], scratch.points[q as usize]];
            scratch.segments.push(FaceSegment { tri: t, ends });
        } else {
            report.inconsistent = true;
        }
        i += run;
    }
    report
}

/// Whether the mesh edge `u–w` pierces the interior of grid face `face`, exactly and
/// under the symbolic perturbation `p + (ε, ε², ε³)` of every grid point (so the face
/// plane is `x_a = plane + ε^(a+1)` and its bounds are shifted likewise).
pub fn segment_pierces_face(lattice: &Lattice, face: GridFace, u: DVec3, w: DVec3) -> bool {
    let a = face.normal.index();
    let corner = lattice.node_position(face.node);
    // A point exactly on the plane lies below the perturbed plane.
    if (u[a] > corner[a]) == (w[a] > corner[a]) {
        return false;
    }
    let sa = Sign::of_difference(w[a], u[a]);
    let (b, c) = face.normal.others();
    for m in [b, c] {
        let lo = corner[m];
        let hi = lattice.plane(m, face.node[m] + 1);
        if crossing_vs_bound(a, m, u, w, corner[a], lo, sa) != Sign::Positive
            || crossing_vs_bound(a, m, u, w, corner[a], hi, sa) != Sign::Negative
        {
            return false;
        }
    }
    true
}

/// Sign of `X_m − r_m`, where `X` is the point where segment `u–w` crosses the
/// perturbed plane `x_a = r_a`, and `r_m` is a perturbed bound along axis `m`.
///
/// With `D = (u_m − r_m)(w_a − u_a) + (r_a − u_a)(w_m − u_m)` we have
/// `X_m − r_m = D / (w_a − u_a)`. `D` is, up to sign, the 2D orientation of `(u, w, r)`
/// projected along the third axis `q` — the very orientation that decides whether the
/// grid line along `q` through `r` passes a projected triangle edge — evaluated with the
/// same Simulation of Simplicity tie-break, so both tests see one perturbed world.
fn crossing_vs_bound(a: usize, m: usize, u: DVec3, w: DVec3, ra: f64, rm: f64, sa: Sign) -> Sign {
    let q = 3 - a - m;
    let (f1, f2) = Axis::from_index(q).others();
    let proj = |p: DVec3| DVec2::new(p[f1], p[f2]);
    let mut r = DVec3::ZERO;
    r[a] = ra;
    r[m] = rm;
    let o = orient2d_sos(proj(u), proj(w), proj(r), f1 < f2);
    // Frame (a, m): orientation = −D; frame (m, a): orientation = D.
    if f1 == a { -(o * sa) } else { o * sa }
}

#[cfg(test)]
mod tests;
