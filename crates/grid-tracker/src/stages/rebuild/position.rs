//! §8.3: where the vertex on a region edge goes, from the labels and breaking points of
//! §8.1 ([`NodeLabels`]).
//!
//! The rebuilt surface has a vertex on every grid edge whose end labels differ; its
//! position along the edge is free (connectivity does not depend on it), and §8.3 picks
//! the best guess of the transition from one material to the other:
//! - one end physical, the other not: §8.3 slides the vertex to the edge's breaking point.
//!   We take the first crossing walking from the physical end, where the physical end's
//!   material ends. When the vector turns non-physical there, that is the breaking point,
//!   as in the paper. When it first passes into another physical material (the physical
//!   end outside two overlapping spheres A and B, the walk entering A alone, then the
//!   overlap), the edge's breaking point is where A's stretch meets the overlap, while
//!   the transition between the two end labels is where A begins: the first crossing.
//!   Without a crossing on the edge (a flawed node), the point equidistant from the
//!   physical end and the other end's breaking point;
//! - both non-physical: the point equidistant from the two ends' breaking points;
//! - both physical (cells remeshed for being complex, not for being non-physical; the
//!   paper leaves these to the midpoint): between the edge's first and last crossing —
//!   the mesh's own crossing when there is one, as in ordinary marching cubes — and the
//!   midpoint without crossings.
//!
//! Every position is clamped into the edge, `margin·ℓ` away from its ends, so face and
//! cell averages stay strictly inside their elements and no triangle degenerates
//! ([`super::average_cell_points`]).

use glam::DVec3;

use crate::stages::grid::Lattice;
use crate::stages::grid::primitives::GridEdge;
use crate::stages::labels::NodeLabels;

/// The §8.3 position of the vertex on `edge` (whose end labels differ), `margin·ℓ` inside
/// the edge. Missing data (a node outside the region) falls back to the midpoint.
pub fn edge_vertex_position(
    lattice: &Lattice,
    labels: &NodeLabels,
    edge: &GridEdge,
    margin: f64,
) -> DVec3 {
    let (a, b) = (edge.node, edge.end());
    let axis = edge.axis.index();
    let (pa, pb) = (lattice.node_position(a), lattice.node_position(b));
    let (lo, hi) = (pa[axis], pb[axis]);
    let mid = 0.5 * (lo + hi);
    let t = labels.edge_transitions(edge);
    let bisect = |p: Option<DVec3>, q: Option<DVec3>| match (p, q) {
        (Some(p), Some(q)) => equidistant(pa, pb, p, q).map_or(mid, |s| lo + s * (hi - lo)),
        _ => mid,
    };
    let coord = match (labels.is_physical(a), labels.is_physical(b)) {
        (true, true) => match t.and_then(|t| t.first_crossing.zip(t.last_crossing)) {
            Some((first, last)) => 0.5 * (first + last),
            None => mid,
        },
        (true, false) => t
            .and_then(|t| t.first_crossing)
            .unwrap_or_else(|| bisect(Some(pa), labels.breaking_point(b))),
        (false, true) => t
            .and_then(|t| t.last_crossing)
            .unwrap_or_else(|| bisect(labels.breaking_point(a), Some(pb))),
        (false, false) => bisect(labels.breaking_point(a), labels.breaking_point(b)),
    };
    let m = margin * (hi - lo);
    let mut p = pa;
    p[axis] = if coord.is_finite() {
        coord.clamp(lo + m, hi - m)
    } else {
        mid
    };
    p
}

/// The parameter `s` of the point `a + s·(b − a)` equidistant from `p` and `q`, when the
/// bisector plane of `p` and `q` meets the line at a finite, well-conditioned point.
fn equidistant(a: DVec3, b: DVec3, p: DVec3, q: DVec3) -> Option<f64> {
    // |x − p|² = |x − q|²  ⇔  2·x·(q − p) = |q|² − |p|², with x = a + s·d relative to a.
    let (p, q, d) = (p - a, q - a, b - a);
    let denom = d.dot(q - p);
    let s = 0.5 * (q.length_squared() - p.length_squared()) / denom;
    (denom.abs() > 1e-12 * d.length_squared() && s.is_finite()).then_some(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equidistant_point_is_equidistant() {
        let (a, b) = (DVec3::ZERO, DVec3::X);
        let (p, q) = (DVec3::new(-0.2, 0.3, 0.0), DVec3::new(0.9, -0.1, 0.4));
        let s = equidistant(a, b, p, q).expect("well conditioned");
        let x = a + s * (b - a);
        assert!((x.distance(p) - x.distance(q)).abs() < 1e-12);
        // A bisector parallel to the edge has no such point.
        assert_eq!(
            equidistant(a, b, DVec3::new(0.5, 1.0, 0.0), DVec3::new(0.5, -1.0, 0.0)),
            None
        );
    }
}
