//! Continuous collision detection of two moving edges.

use glam::DVec3;

#[cfg(test)]
use super::advance::Reason;
use super::advance::{PairGeometry, advance};
use super::bounded::{BVec, Moving, Quartic, dot};
use super::{CcdOptions, Impact};
use crate::proximity::{Proximity, proximity_edge_edge};

/// The edges `p0 p1` and `q0 q1`, in that order.
struct EdgeEdge;

impl PairGeometry for EdgeEdge {
    #[inline]
    fn differences([p0, p1, q0, q1]: &[DVec3; 4]) -> [DVec3; 4] {
        [*p0 - *q0, *p0 - *q1, *p1 - *q0, *p1 - *q1]
    }
    #[inline]
    fn coplanarity([p0, p1, q0, q1]: &[DVec3; 4]) -> [DVec3; 3] {
        [*p1 - *p0, *q1 - *q0, *q0 - *p0]
    }
    #[inline]
    fn proximity([p0, p1, q0, q1]: &[DVec3; 4]) -> Proximity {
        proximity_edge_edge(*p0, *p1, *q0, *q1)
    }
    /// With `n = e_p × e_q` and `w = q0 − p0`, a contact at edge parameters `s, u` has
    /// `s |n|² = (w × e_q)·n` and `u |n|² = (w × e_p)·n`, so both numerators lie in
    /// `[0, |n|²]`. One of the four differences provably negative on the interval (which
    /// also keeps the edges from being parallel) excludes a contact. Binet–Cauchy turns
    /// each into products of dot products.
    fn outside(xa: &[DVec3; 4], xb: &[DVec3; 4], m: DVec3) -> bool {
        let moving = |f: &dyn Fn(&[DVec3; 4]) -> DVec3| Moving {
            a: BVec::difference(f(xa), m),
            b: BVec::difference(f(xb), m),
        };
        let ep = moving(&|x| x[1] - x[0]);
        let eq = moving(&|x| x[3] - x[2]);
        let w = moving(&|x| x[2] - x[0]);
        let (wp, wq, pp, qq, pq) = (
            dot(&w, &ep),
            dot(&w, &eq),
            dot(&ep, &ep),
            dot(&eq, &eq),
            dot(&ep, &eq),
        );
        let s_num = Quartic::product_difference(&wp, &qq, &wq, &pq);
        let u_num = Quartic::product_difference(&wp, &pq, &wq, &pp);
        let nn = Quartic::product_difference(&pp, &qq, &pq, &pq);
        s_num.negative()
            || u_num.negative()
            || nn.minus(&s_num).negative()
            || nn.minus(&u_num).negative()
    }
    #[inline]
    fn geometric_normal([p0, p1, q0, q1]: &[DVec3; 4]) -> DVec3 {
        (*p1 - *p0).cross(*q1 - *q0)
    }
    const HULL_EDGES: &'static [(usize, usize)] = &[(0, 1), (2, 3), (0, 2), (1, 3)];
    const FIRST_LEN: usize = 2;
    const NEUTRAL_WEIGHTS: [f64; 4] = [0.5, 0.5, -0.5, -0.5];
}

/// Do the edges `p0 p1` and `q0 q1` touch during the step, moving linearly from
/// `x0 = [p0, p1, q0, q1]` at `t = 0` to `x1` at `t = 1`? Default [`CcdOptions`].
///
/// `None` is a proof that they never do (no false negatives); `Some` is a contact or a
/// near-miss within the tolerance, with a conservative time — see the
/// [module docs](super) for the guarantee, the degenerate-case policy and the fields.
/// The weights are `[1 − s, s, −(1 − u), −u]`, the normal points from edge `q` towards
/// edge `p`.
pub fn ccd_edge_edge(x0: [DVec3; 4], x1: [DVec3; 4]) -> Option<Impact> {
    advance::<EdgeEdge>(&x0, &x1, &CcdOptions::default()).map(|(hit, _)| hit)
}

/// [`ccd_edge_edge`] with explicit options.
pub fn ccd_edge_edge_with(x0: [DVec3; 4], x1: [DVec3; 4], options: &CcdOptions) -> Option<Impact> {
    advance::<EdgeEdge>(&x0, &x1, options).map(|(hit, _)| hit)
}

/// [`ccd_edge_edge`] with the reason of a report and the iteration count (for the tests).
#[cfg(test)]
pub(crate) fn ccd_edge_edge_traced(
    x0: [DVec3; 4],
    x1: [DVec3; 4],
) -> (Option<(Impact, Reason)>, u32) {
    super::advance::advance_counted::<EdgeEdge>(&x0, &x1, &CcdOptions::default())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f64, y: f64, z: f64) -> DVec3 {
        DVec3::new(x, y, z)
    }

    #[test]
    fn crossing_edges() {
        // Edge p along x at height 1 drops to height -1; edge q along y rests at 0.
        let x0 = [
            v(-1.0, 0.0, 1.0),
            v(1.0, 0.0, 1.0),
            v(0.5, -1.0, 0.0),
            v(0.5, 1.0, 0.0),
        ];
        let x1 = [
            v(-1.0, 0.0, -1.0),
            v(1.0, 0.0, -1.0),
            v(0.5, -1.0, 0.0),
            v(0.5, 1.0, 0.0),
        ];
        let hit = ccd_edge_edge(x0, x1).expect("edges cross");
        assert!(
            hit.time <= 0.5 && hit.time > 0.5 - 1e-9,
            "time {}",
            hit.time
        );
        assert!((hit.normal - DVec3::Z).length() < 1e-6);
        let w = hit.weights;
        assert!((w[0] - 0.25).abs() < 1e-6 && (w[1] - 0.75).abs() < 1e-6);
        assert!((w[2] + 0.5).abs() < 1e-6 && (w[3] + 0.5).abs() < 1e-6);
        assert!((hit.relative_normal_velocity + 2.0).abs() < 1e-6);
        // Shift q beyond p's end: the lines cross, the segments do not.
        let shift = |x: [DVec3; 4]| [x[0], x[1], x[2] + DVec3::X * 0.6, x[3] + DVec3::X * 0.6];
        assert_eq!(ccd_edge_edge(shift(x0), shift(x1)), None);
    }

    #[test]
    fn parallel_sliding_edges() {
        // Parallel edges at distance 1e-6 sliding past each other: never touch.
        let gap = v(0.0, 1e-6, 0.0);
        let x0 = [
            v(0.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(-3.0, 0.0, 0.0) + gap,
            v(-2.0, 0.0, 0.0) + gap,
        ];
        let x1 = [
            v(0.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(3.0, 0.0, 0.0) + gap,
            v(4.0, 0.0, 0.0) + gap,
        ];
        assert_eq!(ccd_edge_edge(x0, x1), None);
        // Collinear: the same motion without the gap collides when the ends meet.
        let x0c = [x0[0], x0[1], x0[2] - gap, x0[3] - gap];
        let x1c = [x1[0], x1[1], x1[2] - gap, x1[3] - gap];
        let hit = ccd_edge_edge(x0c, x1c).expect("collinear overlap");
        // q1 reaches p0 when -2 + 6t = 0.
        assert!(
            hit.time <= 1.0 / 3.0 && hit.time > 1.0 / 3.0 - 1e-9,
            "time {}",
            hit.time
        );
        // The approach is along the line (q comes from −x): the normal says so.
        assert!(
            (hit.normal - DVec3::X).length() < 1e-6,
            "normal {}",
            hit.normal
        );
        assert!(hit.relative_normal_velocity < 0.0);
    }

    #[test]
    fn endpoint_on_edge_and_degenerate_edges() {
        // p1 lands exactly on the middle of q at t = 1.
        let x0 = [
            v(0.0, 0.0, 2.0),
            v(0.0, 0.0, 1.0),
            v(-1.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
        ];
        let x1 = [
            v(0.0, 0.0, 1.0),
            v(0.0, 0.0, 0.0),
            v(-1.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
        ];
        let hit = ccd_edge_edge(x0, x1).expect("lands on q");
        assert!(hit.time <= 1.0 && hit.time > 1.0 - 1e-9);
        // A zero-length edge p passing through q.
        let x0 = [
            v(0.2, 0.0, 1.0),
            v(0.2, 0.0, 1.0),
            v(-1.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
        ];
        let x1 = [
            v(0.2, 0.0, -1.0),
            v(0.2, 0.0, -1.0),
            v(-1.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
        ];
        let hit = ccd_edge_edge(x0, x1).expect("point through segment");
        assert!(hit.time <= 0.5 && hit.time > 0.5 - 1e-9);
        // Both zero-length, missing each other.
        let x0 = [
            v(0.0, 1.0, 1.0),
            v(0.0, 1.0, 1.0),
            v(0.0, 0.0, 0.0),
            v(0.0, 0.0, 0.0),
        ];
        let x1 = [
            v(0.0, 1.0, -1.0),
            v(0.0, 1.0, -1.0),
            v(0.0, 0.0, 0.0),
            v(0.0, 0.0, 0.0),
        ];
        assert_eq!(ccd_edge_edge(x0, x1), None);
    }

    #[test]
    fn touching_at_start_and_rotating() {
        // Crossing at t = 0, then separating: a collision at time 0 by policy.
        let x0 = [
            v(-1.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(0.0, -1.0, 0.0),
            v(0.0, 1.0, 0.0),
        ];
        let x1 = [
            v(-1.0, 0.0, 1.0),
            v(1.0, 0.0, 1.0),
            v(0.0, -1.0, 0.0),
            v(0.0, 1.0, 0.0),
        ];
        let hit = ccd_edge_edge(x0, x1).expect("touching at t = 0");
        assert_eq!(hit.time, 0.0);
        assert!(hit.relative_normal_velocity <= 0.0);
        // Edge p turns above q at height 1e-4, parallel to it at t = 1/2, without touching;
        // the scene is rotated so that no coordinate axis separates.
        let h = 1e-4;
        let r = glam::DMat3::from_euler(glam::EulerRot::XYZ, 0.3, -0.7, 1.1);
        let x0 = [
            v(-1.0, -1.0, h),
            v(1.0, 1.0, h),
            v(-1.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
        ]
        .map(|x| r * x);
        let x1 = [
            v(-1.0, 1.0, h),
            v(1.0, -1.0, h),
            v(-1.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
        ]
        .map(|x| r * x);
        assert_eq!(ccd_edge_edge(x0, x1), None);
        // The same at height 0 collides (at t = 1/2 at the latest: the lines meet at the
        // origin from the start).
        let x0 = [
            v(-1.0, -1.0, 0.0),
            v(1.0, 1.0, 0.0),
            v(-1.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
        ]
        .map(|x| r * x);
        let x1 = [
            v(-1.0, 1.0, 0.0),
            v(1.0, -1.0, 0.0),
            v(-1.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
        ]
        .map(|x| r * x);
        assert!(ccd_edge_edge(x0, x1).is_some());
    }
}
