//! Continuous collision detection of a moving vertex against a moving triangle.

use glam::DVec3;

#[cfg(test)]
use super::advance::Reason;
use super::advance::{PairGeometry, advance};
use super::bounded::{BVec, Moving, Quartic, dot};
use super::{CcdOptions, Impact};
use crate::proximity::{Proximity, proximity_vertex_triangle};

/// The vertex `p` and the triangle `a b c`, in that order.
struct VertexTriangle;

impl PairGeometry for VertexTriangle {
    #[inline]
    fn differences([p, a, b, c]: &[DVec3; 4]) -> [DVec3; 4] {
        let (pa, pb, pc) = (*p - *a, *p - *b, *p - *c);
        [pa, pb, pc, pc]
    }
    #[inline]
    fn coplanarity([p, a, b, c]: &[DVec3; 4]) -> [DVec3; 3] {
        [*b - *a, *c - *a, *p - *a]
    }
    #[inline]
    fn proximity([p, a, b, c]: &[DVec3; 4]) -> Proximity {
        proximity_vertex_triangle(*p, [*a, *b, *c])
    }
    /// Some edge function `h = n · ((y − x) × (p − x))`, `n = (b − a) × (c − a)`, is
    /// negative on the whole interval: the vertex is strictly on the outer side of edge
    /// `x y` (and the triangle is never degenerate), so it cannot lie on the triangle, which
    /// needs all three `h ≥ 0`. By Binet–Cauchy `h = (e₁·e)(e₂·r) − (e₁·r)(e₂·e)`.
    fn outside(xa: &[DVec3; 4], xb: &[DVec3; 4], m: DVec3) -> bool {
        let moving = |f: &dyn Fn(&[DVec3; 4]) -> DVec3| Moving {
            a: BVec::difference(f(xa), m),
            b: BVec::difference(f(xb), m),
        };
        let e1 = moving(&|x| x[2] - x[1]);
        let e2 = moving(&|x| x[3] - x[1]);
        [(1usize, 2usize), (2, 3), (3, 1)].iter().any(|&(i, j)| {
            let e = moving(&|x| x[j] - x[i]);
            let r = moving(&|x| x[0] - x[i]);
            Quartic::product_difference(&dot(&e1, &e), &dot(&e2, &r), &dot(&e1, &r), &dot(&e2, &e))
                .negative()
        })
    }
    #[inline]
    fn geometric_normal([_, a, b, c]: &[DVec3; 4]) -> DVec3 {
        (*b - *a).cross(*c - *a)
    }
    const HULL_EDGES: &'static [(usize, usize)] = &[(0, 1), (1, 2), (2, 0)];
    const FIRST_LEN: usize = 1;
    const NEUTRAL_WEIGHTS: [f64; 4] = [1.0, -1.0 / 3.0, -1.0 / 3.0, -1.0 / 3.0];
}

/// Does the vertex `p` touch the triangle `a b c` during the step, moving linearly from
/// `x0 = [p, a, b, c]` at `t = 0` to `x1` at `t = 1`? Default [`CcdOptions`].
///
/// `None` is a proof that it never does (no false negatives); `Some` is a contact or a
/// near-miss within the tolerance, with a conservative time — see the
/// [module docs](super) for the guarantee, the degenerate-case policy and the fields.
/// The weights are `[1, −α, −β, −γ]`, the normal points from the triangle towards the
/// vertex.
pub fn ccd_vertex_triangle(x0: [DVec3; 4], x1: [DVec3; 4]) -> Option<Impact> {
    advance::<VertexTriangle>(&x0, &x1, &CcdOptions::default()).map(|(hit, _)| hit)
}

/// [`ccd_vertex_triangle`] with explicit options.
pub fn ccd_vertex_triangle_with(
    x0: [DVec3; 4],
    x1: [DVec3; 4],
    options: &CcdOptions,
) -> Option<Impact> {
    advance::<VertexTriangle>(&x0, &x1, options).map(|(hit, _)| hit)
}

/// [`ccd_vertex_triangle`] with the reason of a report and the iteration count (for the tests).
#[cfg(test)]
pub(crate) fn ccd_vertex_triangle_traced(
    x0: [DVec3; 4],
    x1: [DVec3; 4],
) -> (Option<(Impact, Reason)>, u32) {
    super::advance::advance_counted::<VertexTriangle>(&x0, &x1, &CcdOptions::default())
}

#[cfg(test)]
mod tests {
    use super::*;

    const TRI: [DVec3; 3] = [
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(0.0, 1.0, 0.0),
    ];

    fn still_triangle(p0: DVec3, p1: DVec3) -> ([DVec3; 4], [DVec3; 4]) {
        ([p0, TRI[0], TRI[1], TRI[2]], [p1, TRI[0], TRI[1], TRI[2]])
    }

    #[test]
    fn vertex_through_the_interior() {
        let (x0, x1) = still_triangle(DVec3::new(0.25, 0.25, 1.0), DVec3::new(0.25, 0.25, -3.0));
        let hit = ccd_vertex_triangle(x0, x1).expect("passes through the triangle");
        // True contact at t = 0.25; reported no later, and close (tolerance 1e-12).
        assert!(
            hit.time <= 0.25 && hit.time > 0.25 - 1e-9,
            "time {}",
            hit.time
        );
        assert!(
            (hit.normal - DVec3::Z).length() < 1e-6,
            "normal {}",
            hit.normal
        );
        let w = hit.weights;
        assert!(
            (w[0] - 1.0).abs() < 1e-12 && (w[1] + 0.5).abs() < 1e-6 && (w[2] + 0.25).abs() < 1e-6
        );
        assert!((hit.relative_normal_velocity + 4.0).abs() < 1e-6);
    }

    #[test]
    fn vertex_passing_beside_is_rejected() {
        let (x0, x1) = still_triangle(DVec3::new(0.75, 0.75, 1.0), DVec3::new(0.75, 0.75, -1.0));
        assert_eq!(ccd_vertex_triangle(x0, x1), None);
        // Beside by a hair (1e-9 of the size): still a proof of no contact.
        let (x0, x1) = still_triangle(
            DVec3::new(0.5 + 1e-9, 0.5, 1.0),
            DVec3::new(0.5 + 1e-9, 0.5, -1.0),
        );
        assert_eq!(ccd_vertex_triangle(x0, x1), None);
    }

    #[test]
    fn grazing_an_edge() {
        // The vertex crosses the plane exactly on the hypotenuse at t = 0.5.
        let (x0, x1) = still_triangle(DVec3::new(0.5, 0.5, 1.0), DVec3::new(0.5, 0.5, -1.0));
        let hit = ccd_vertex_triangle(x0, x1).expect("touches the edge");
        assert!(hit.time <= 0.5 && hit.time > 0.5 - 1e-9);
        assert!((hit.weights[2] + 0.5).abs() < 1e-6 && (hit.weights[3] + 0.5).abs() < 1e-6);
        // Sliding along the plane into the edge from outside, coplanar all the time.
        let (x0, x1) = still_triangle(DVec3::new(2.0, 2.0, 0.0), DVec3::new(0.0, 0.0, 0.0));
        let hit = ccd_vertex_triangle(x0, x1).expect("coplanar entry");
        assert!(
            hit.time <= 0.75 && hit.time > 0.75 - 1e-9,
            "time {}",
            hit.time
        );
        // The normal is the in-plane approach direction, not the triangle normal.
        let expect = DVec3::new(1.0, 1.0, 0.0).normalize();
        assert!(
            (hit.normal - expect).length() < 1e-6,
            "normal {}",
            hit.normal
        );
        assert!(hit.relative_normal_velocity < 0.0);
    }

    #[test]
    fn touching_at_the_ends() {
        // Starts on the triangle and leaves: a collision at t = 0 by policy.
        let (x0, x1) = still_triangle(DVec3::new(0.2, 0.2, 0.0), DVec3::new(0.2, 0.2, 1.0));
        let hit = ccd_vertex_triangle(x0, x1).expect("touching at t = 0");
        assert_eq!(hit.time, 0.0);
        // Arrives exactly at t = 1.
        let (x0, x1) = still_triangle(DVec3::new(0.2, 0.2, 1.0), DVec3::new(0.2, 0.2, 0.0));
        let hit = ccd_vertex_triangle(x0, x1).expect("touching at t = 1");
        assert!(hit.time <= 1.0 && hit.time > 1.0 - 1e-9);
        assert!((hit.normal - DVec3::Z).length() < 1e-6 && hit.relative_normal_velocity < 0.0);
    }

    #[test]
    fn moving_triangle_and_degenerate_triangles() {
        // The triangle sweeps up through a resting vertex.
        let p = DVec3::new(0.1, 0.1, 0.5);
        let up = DVec3::Z;
        let x0 = [p, TRI[0], TRI[1], TRI[2]];
        let x1 = [p, TRI[0] + up, TRI[1] + up, TRI[2] + up];
        let hit = ccd_vertex_triangle(x0, x1).expect("swept through");
        assert!(hit.time <= 0.5 && hit.time > 0.5 - 1e-9);
        // The vertex starts above the triangle: the normal points up, towards it.
        assert!(hit.normal.z > 0.99 && hit.relative_normal_velocity < 0.0);
        // A zero-area (collinear) triangle swept through the vertex.
        let seg = [
            DVec3::new(-1.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.5, 0.0, 0.0),
        ];
        let x0 = [DVec3::new(0.0, 0.0, 1.0), seg[0], seg[1], seg[2]];
        let x1 = [DVec3::new(0.0, 0.0, -1.0), seg[0], seg[1], seg[2]];
        assert!(ccd_vertex_triangle(x0, x1).is_some());
        // A point triangle missed by a vertex passing next to it.
        let x0 = [
            DVec3::new(0.0, 1.0, 1.0),
            DVec3::ZERO,
            DVec3::ZERO,
            DVec3::ZERO,
        ];
        let x1 = [
            DVec3::new(0.0, 1.0, -1.0),
            DVec3::ZERO,
            DVec3::ZERO,
            DVec3::ZERO,
        ];
        assert_eq!(ccd_vertex_triangle(x0, x1), None);
    }

    #[test]
    fn invalid_input_is_reported() {
        let (mut x0, x1) = still_triangle(DVec3::new(5.0, 5.0, 5.0), DVec3::new(6.0, 6.0, 6.0));
        x0[2].y = f64::NAN;
        let hit = ccd_vertex_triangle(x0, x1).expect("NaN is reported");
        assert_eq!(hit.time, 0.0);
        x0[2].y = 1e200;
        x0[3].x = f64::INFINITY;
        assert!(ccd_vertex_triangle(x0, x1).is_some());
    }
}
