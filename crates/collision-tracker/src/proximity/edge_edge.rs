//! Closest points of two segments.

use glam::DVec3;

use super::{
    PARALLEL_SIN2, Proximity, closest_param_on_segment, finish, off_line, perpendicular_to_longest,
    unit,
};

/// Distance between the segments `[p0, p1]` and `[q0, q1]`, with El Topo's signed weights
/// `[1 − s, s, −(1 − u), −u]` (closest points `p0 + s (p1 − p0)` and `q0 + u (q1 − q0)`)
/// and the unit normal from the second closest point towards the first.
///
/// Why candidates: the squared distance is a convex quadratic in `(s, u)`; its minimum on
/// the unit square is either the interior stationary point or lies on one side of the
/// square, i.e. an endpoint of one segment against the other segment. The interior point is
/// used only for clearly non-parallel segments; the four endpoint queries cover parallel,
/// collinear and zero-length segments exactly.
///
/// When the segments touch, the normal is the unit `(p1 − p0) × (q1 − q0)` or, for
/// parallel or degenerate segments, some unit vector perpendicular to the longer one.
pub fn proximity_edge_edge(p0: DVec3, p1: DVec3, q0: DVec3, q1: DVec3) -> Proximity {
    let dp = p1 - p0;
    let dq = q1 - q0;
    let n = dp.cross(dq);
    let nn = n.dot(n);
    let fallback = || unit(n).unwrap_or_else(|| perpendicular_to_longest(&[dp, dq]));

    if nn > PARALLEL_SIN2 * dp.length_squared() * dq.length_squared() && nn.is_finite() {
        // p0 + s dp = q0 + u dq + h n̂ with w = q0 − p0:
        // (w × dq)·n = s |n|²  and  (w × dp)·n = u |n|².
        let w = q0 - p0;
        let s = w.cross(dq).dot(n) / nn;
        let u = w.cross(dp).dot(n) / nn;
        if (0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&u) {
            let diff = (p0 + dp * s) - (q0 + dq * u);
            return finish(diff, [1.0 - s, s, -(1.0 - u), -u], n, fallback);
        }
    }

    // Boundary of the parameter square: each endpoint against the other segment.
    let mut best_d2: Option<f64> = None;
    let mut best = (DVec3::ZERO, [1.0, 0.0, -1.0, 0.0], DVec3::ZERO);
    // `param` is the parameter on segment `e`; inside it the direction is perpendicular to `e`.
    let mut consider = |diff: DVec3, s: f64, u: f64, param: f64, e: DVec3| {
        let d2 = diff.length_squared();
        if best_d2.is_none_or(|b| d2 < b) {
            best_d2 = Some(d2);
            let feature = if param > 0.0 && param < 1.0 {
                off_line(diff, e)
            } else {
                diff
            };
            best = (diff, [1.0 - s, s, -(1.0 - u), -u], feature);
        }
    };
    for (s, p) in [(0.0, p0), (1.0, p1)] {
        let u = closest_param_on_segment(p, q0, q1);
        consider(p - (q0 + dq * u), s, u, u, dq);
    }
    for (u, q) in [(0.0, q0), (1.0, q1)] {
        let s = closest_param_on_segment(q, p0, p1);
        consider((p0 + dp * s) - q, s, u, s, dp);
    }
    finish(best.0, best.1, best.2, fallback)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-12 * (1.0 + a.abs().max(b.abs()))
    }

    fn check(p0: DVec3, p1: DVec3, q0: DVec3, q1: DVec3, expect: f64) -> Proximity {
        let r = proximity_edge_edge(p0, p1, q0, q1);
        assert!(close(r.distance, expect), "{} vs {expect}", r.distance);
        let w = r.weights;
        assert!(close(w[0] + w[1], 1.0) && close(w[2] + w[3], -1.0), "{w:?}");
        assert!(
            w[0] >= 0.0 && w[1] >= 0.0 && w[2] <= 0.0 && w[3] <= 0.0,
            "{w:?}"
        );
        let diff = p0 * w[0] + p1 * w[1] + q0 * w[2] + q1 * w[3];
        assert!(close(diff.length(), r.distance));
        assert!(close(r.normal.length(), 1.0));
        if r.distance > 0.0 {
            assert!((diff / r.distance - r.normal).length() < 1e-9);
        }
        r
    }

    #[test]
    fn skew_segments() {
        let r = check(
            DVec3::new(-1.0, 0.0, 1.0),
            DVec3::new(1.0, 0.0, 1.0),
            DVec3::new(0.0, -1.0, 0.0),
            DVec3::new(0.0, 3.0, 0.0),
            1.0,
        );
        assert!(close(r.weights[1], 0.5) && close(r.weights[3], -0.25));
        assert!((r.normal - DVec3::Z).length() < 1e-15);
        // Closest points at endpoints of both.
        check(
            DVec3::ZERO,
            DVec3::X,
            DVec3::new(2.0, 1.0, 0.0),
            DVec3::new(2.0, 5.0, 0.0),
            2f64.sqrt(),
        );
    }

    #[test]
    fn parallel_and_collinear() {
        // Parallel, overlapping in projection: distance is the line distance.
        check(
            DVec3::ZERO,
            DVec3::X * 2.0,
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(3.0, 1.0, 0.0),
            1.0,
        );
        // Anti-parallel, disjoint in projection.
        check(
            DVec3::ZERO,
            DVec3::X,
            DVec3::new(4.0, 0.0, 3.0),
            DVec3::new(2.0, 0.0, 3.0),
            10f64.sqrt(),
        );
        // Collinear, overlapping: touching, normal perpendicular to the line.
        let r = check(DVec3::ZERO, DVec3::X * 2.0, DVec3::X, DVec3::X * 3.0, 0.0);
        assert!(r.normal.dot(DVec3::X).abs() < 1e-15);
    }

    #[test]
    fn degenerate_segments() {
        // Both segments are points.
        check(
            DVec3::ONE,
            DVec3::ONE,
            DVec3::ZERO,
            DVec3::ZERO,
            3f64.sqrt(),
        );
        // One point, one segment.
        check(
            DVec3::new(0.5, 2.0, 0.0),
            DVec3::new(0.5, 2.0, 0.0),
            DVec3::ZERO,
            DVec3::X,
            2.0,
        );
        // Crossing at a point: touching, normal along the cross product.
        let r = check(
            DVec3::new(-1.0, 0.0, 0.0),
            DVec3::X,
            DVec3::new(0.0, -1.0, 0.0),
            DVec3::Y,
            0.0,
        );
        assert!((r.normal - DVec3::Z).length() < 1e-15);
    }

    #[test]
    fn nearly_parallel_matches_brute_force() {
        let (p0, p1) = (DVec3::ZERO, DVec3::new(2.0, 0.0, 0.0));
        for k in 0..12 {
            let tilt = 10f64.powi(-k);
            let q0 = DVec3::new(0.5, 0.3, 0.1);
            let q1 = DVec3::new(3.0, 0.3 + tilt, 0.1 - tilt);
            let r = proximity_edge_edge(p0, p1, q0, q1);
            let mut best = f64::INFINITY;
            for i in 0..=400 {
                for j in 0..=40 {
                    let a = p0 + (p1 - p0) * (i as f64 / 400.0);
                    let b = q0 + (q1 - q0) * (j as f64 / 40.0);
                    best = best.min((a - b).length());
                }
            }
            assert!(
                r.distance <= best + 1e-12 && r.distance >= best - 0.01,
                "{} vs {best}",
                r.distance
            );
        }
    }
}
