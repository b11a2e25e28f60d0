//! Cut points (App. A): what they are called, where they lie in space, and where they go in
//! a triangle's 2D parameter frame.
//!
//! Every triangle is triangulated in the frame where its corners are `(0, 0)`, `(1, 0)`,
//! `(0, 1)` (corner order = winding order, so the frame is counter-clockwise and a CDT face
//! keeps the triangle's orientation). Coordinates are multiples of a dyadic quantum
//! `2^−bits` ([`Quantum`]):
//! - a **mesh-edge point** gets its parameter along the edge from the edge's canonical
//!   `(min id, max id)` order, quantised once, so every triangle around the edge places it
//!   identically and *exactly* on the frame edge (`(s, 0)`, `(1 − s, s)`, `(0, 1 − s)` are
//!   exactly collinear with their corners for dyadic `s`) — the paper's "integer grid face
//!   coordinates" for sorting points along an edge;
//! - a **grid-edge point** gets the barycentric coordinates of the grid line in the
//!   triangle's projection along the line (the projection the crossing test decided in),
//!   quantised and nudged strictly inside the triangle.
//!
//! Positions in space: a mesh-edge point is the mesh edge ∩ the face plane, with the
//! normal coordinate set to the plane exactly and the others clamped to the face; a
//! grid-edge point is the grid line ∩ the triangle plane (the crossing's coordinate),
//! clamped to the grid edge. Both therefore lie exactly on the grid element they belong to.

use glam::{DVec3, IVec3};
use mesh_core::VertexId;
use mesh_core::predicates::Axis;

use crate::stages::grid::Lattice;
use crate::stages::grid::primitives::{GridEdge, GridFace};

/// The corners of the parameter frame, in the triangle's vertex order.
pub(crate) const CORNER_UV: [[f64; 2]; 3] = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];

/// What a point of one triangle's triangulation is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(crate) enum PointKey {
    /// Corner `k` of the triangle (its vertex `tri[k]`).
    Corner(u8),
    /// Mesh edge `lo < hi` pierces boundary face number `face` (index into the region's
    /// boundary faces): shared by every triangle around the edge.
    MeshEdge {
        /// Smaller end.
        lo: VertexId,
        /// Larger end.
        hi: VertexId,
        /// Boundary face index.
        face: u32,
    },
    /// The triangle crosses this grid edge: owned by the one triangle.
    Grid(GridEdge),
}

/// A point of one triangle's triangulation.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LocalPoint {
    /// Its name.
    pub(crate) key: PointKey,
    /// Frame coordinates (exact dyadic).
    pub(crate) uv: [f64; 2],
    /// Position in space.
    pub(crate) pos: DVec3,
}

/// The dyadic quantum of the frame: `2^−bits`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Quantum {
    /// `2^bits` as a float.
    scale: f64,
    /// `2^bits` as an integer.
    steps: i64,
}

impl Quantum {
    /// The quantum `2^−bits`, `bits ∈ 8..=50` (checked by the caller).
    pub(crate) fn new(bits: u32) -> Self {
        let steps = 1i64 << bits;
        Self {
            scale: steps as f64,
            steps,
        }
    }

    fn to_steps(self, x: f64) -> i64 {
        // NaN casts to 0; the clamps of the callers keep the result valid.
        (x * self.scale).round() as i64
    }

    fn value_of(self, k: i64) -> f64 {
        k as f64 / self.scale
    }

    /// An edge parameter quantised strictly inside `(0, 1)`; also whether it had to be
    /// moved off an end (the point coincides with a mesh vertex).
    pub(crate) fn edge_parameter(self, t: f64) -> (f64, bool) {
        let k = self.to_steps(t);
        let c = k.clamp(1, self.steps - 1);
        (self.value_of(c), c != k)
    }

    /// Frame coordinates quantised strictly inside the triangle; also whether they had to
    /// be moved off its boundary.
    pub(crate) fn interior(self, u: f64, v: f64) -> ([f64; 2], bool) {
        let (ku, kv) = (self.to_steps(u), self.to_steps(v));
        let (mut cu, mut cv) = (ku.max(1), kv.max(1));
        let excess = cu + cv - (self.steps - 1);
        if excess > 0 {
            if cu >= cv {
                cu = (cu - excess).max(1);
            } else {
                cv = (cv - excess).max(1);
            }
        }
        ([self.value_of(cu), self.value_of(cv)], (cu, cv) != (ku, kv))
    }
}

/// The cell containing vertex position `p` under the symbolic perturbation: a grid plane
/// stands for `plane + ε^(a+1)`, so a vertex exactly on it lies in the cell below — the
/// convention of [`crate::stages::flaws::segment_pierces_face`].
pub(crate) fn vertex_cell(lattice: &Lattice, p: DVec3) -> IVec3 {
    IVec3::new(
        lattice.locate_strict(0, p.x),
        lattice.locate_strict(1, p.y),
        lattice.locate_strict(2, p.z),
    )
}

/// Where mesh edge `lo–hi` (positions in canonical order) crosses the plane of `face`:
/// the quantised parameter from `lo`, whether it was moved off an end, and the position.
pub(crate) fn mesh_edge_point(
    lattice: &Lattice,
    face: GridFace,
    plo: DVec3,
    phi: DVec3,
    quantum: Quantum,
) -> (f64, bool, DVec3) {
    let a = face.normal.index();
    let x = lattice.plane(a, face.node[a]);
    let d = phi[a] - plo[a];
    let t = if d != 0.0 {
        ((x - plo[a]) / d).clamp(0.0, 1.0)
    } else {
        0.5
    };
    let mut pos = plo + (phi - plo) * t;
    pos[a] = x;
    let (b, c) = face.normal.others();
    for m in [b, c] {
        let lo = lattice.plane(m, face.node[m]);
        let hi = lattice.plane(m, face.node[m] + 1);
        pos[m] = pos[m].clamp(lo, hi);
    }
    let (tq, moved) = quantum.edge_parameter(t);
    (tq, moved, pos)
}

/// Frame coordinates of the point at parameter `s` along the triangle's edge from corner
/// `k` to corner `k + 1`: exactly on that frame edge.
pub(crate) fn edge_uv(k: usize, s: f64) -> [f64; 2] {
    match k {
        0 => [s, 0.0],
        1 => [1.0 - s, s],
        _ => [0.0, 1.0 - s],
    }
}

/// Where grid edge `edge` crosses triangle `tri`: frame coordinates (quantised, strictly
/// inside), whether they were nudged off the boundary, and the position on the edge given
/// the crossing's approximate `coordinate` along it.
pub(crate) fn grid_edge_point(
    lattice: &Lattice,
    edge: GridEdge,
    coordinate: f64,
    tri: [DVec3; 3],
    quantum: Quantum,
) -> ([f64; 2], bool, DVec3) {
    let m = edge.axis.index();
    let node = lattice.node_position(edge.node);
    let mut pos = node;
    pos[m] = coordinate.clamp(node[m], lattice.plane(m, edge.node[m] + 1));

    let axis: Axis = edge.axis;
    let q = axis.project(node);
    let [a, b, c] = tri.map(|p| axis.project(p));
    let w = [
        (b - q).perp_dot(c - q),
        (c - q).perp_dot(a - q),
        (a - q).perp_dot(b - q),
    ];
    let sum = w[0] + w[1] + w[2];
    let (u, v) = if sum != 0.0 && sum.is_finite() {
        ((w[1] / sum).clamp(0.0, 1.0), (w[2] / sum).clamp(0.0, 1.0))
    } else {
        (1.0 / 3.0, 1.0 / 3.0)
    };
    let (uv, nudged) = quantum.interior(u, v);
    (uv, nudged, pos)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantised_points_stay_strictly_inside_and_on_edges() {
        let q = Quantum::new(40);
        let (t, moved) = q.edge_parameter(0.0);
        assert!(t > 0.0 && moved);
        let (t, moved) = q.edge_parameter(1.0);
        assert!(t < 1.0 && moved);
        let (t, moved) = q.edge_parameter(0.3);
        assert!(!moved && (t - 0.3).abs() < 1e-12);
        // Points on the hypotenuse are exactly on u + v = 1.
        let [u, v] = edge_uv(1, t);
        assert_eq!(u + v, 1.0);
        // Interior points are pushed inside.
        for (u, v) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (0.5, 0.5), (0.7, 0.6)] {
            let ([a, b], _) = q.interior(u, v);
            assert!(a > 0.0 && b > 0.0 && a + b < 1.0, "{u} {v} -> {a} {b}");
        }
    }

    #[test]
    fn vertices_on_a_plane_belong_to_the_cell_below() {
        let l = Lattice {
            origin: DVec3::ZERO,
            cell_size: 0.5,
        };
        assert_eq!(
            vertex_cell(&l, DVec3::new(0.5, 0.25, 1.0)),
            IVec3::new(0, 0, 1)
        );
    }
}
