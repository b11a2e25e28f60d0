//! Closest point of a triangle to a vertex.

use glam::DVec3;

use super::{
    PARALLEL_SIN2, Proximity, closest_param_on_segment, finish, off_line, perpendicular_to_longest,
    unit,
};

/// Distance from vertex `p` to the closed triangle `[a, b, c]`, with El Topo's signed
/// weights `[1, −α, −β, −γ]` (`α a + β b + γ c` is the closest triangle point) and the unit
/// normal from that point towards `p`.
///
/// Why candidates instead of Voronoi-region case analysis: the closest point is either the
/// orthogonal projection (when it falls inside the triangle) or the closest point of one of
/// the three edges. The projection is used only when the triangle is well shaped (its
/// barycentric coordinates are then accurate); otherwise the three point–segment queries
/// decide, which is exact for zero-area and zero-edge triangles too.
///
/// When `p` lies on the triangle the normal is the triangle's unit normal
/// `(b − a) × (c − a)`, or — for a degenerate triangle — some unit vector perpendicular to
/// its longest edge.
pub fn proximity_vertex_triangle(p: DVec3, [a, b, c]: [DVec3; 3]) -> Proximity {
    let e1 = b - a;
    let e2 = c - a;
    let n = e1.cross(e2);
    let nn = n.dot(n);
    let fallback = || unit(n).unwrap_or_else(|| perpendicular_to_longest(&[e1, e2, c - b]));

    // Interior candidate. `nn = |e1|²|e2|² sin²θ`, so the test asks for a non-sliver triangle.
    if nn > PARALLEL_SIN2 * e1.length_squared() * e2.length_squared() && nn.is_finite() {
        let r = p - a;
        // r = β e1 + γ e2 + h n̂  ⇒  (r × e2)·n = β |n|²  and  (e1 × r)·n = γ |n|².
        let beta = r.cross(e2).dot(n) / nn;
        let gamma = e1.cross(r).dot(n) / nn;
        let alpha = 1.0 - beta - gamma;
        if beta >= 0.0 && gamma >= 0.0 && alpha >= 0.0 {
            let q = a + e1 * beta + e2 * gamma;
            return finish(p - q, [1.0, -alpha, -beta, -gamma], n, fallback);
        }
    }

    // Boundary candidates: the closest point of each edge (each a true triangle point).
    let edges = [(a, b, 0usize, 1usize), (b, c, 1, 2), (c, a, 2, 0)];
    let mut best_d2: Option<f64> = None;
    let mut best = (DVec3::ZERO, [1.0, -1.0, 0.0, 0.0], DVec3::ZERO);
    for (x, y, i, j) in edges {
        let s = closest_param_on_segment(p, x, y);
        let diff = p - (x + (y - x) * s);
        let d2 = diff.length_squared();
        // The first candidate is always taken (even with a NaN distance).
        if best_d2.is_none_or(|b| d2 < b) {
            best_d2 = Some(d2);
            let mut w = [1.0, 0.0, 0.0, 0.0];
            w[1 + i] = -(1.0 - s);
            w[1 + j] = -s;
            // Interior of the edge: the direction is perpendicular to it.
            let feature = if s > 0.0 && s < 1.0 {
                off_line(diff, y - x)
            } else {
                diff
            };
            best = (diff, w, feature);
        }
    }
    finish(best.0, best.1, best.2, fallback)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() <= 1e-12 * (1.0 + a.abs().max(b.abs()))
    }

    fn assert_consistent(p: DVec3, tri: [DVec3; 3], prox: &Proximity) {
        let w = prox.weights;
        assert!(
            close(w[0], 1.0) && close(w[1] + w[2] + w[3], -1.0),
            "weights {w:?}"
        );
        assert!(w[1..].iter().all(|&x| x <= 0.0), "weights {w:?}");
        let diff = p * w[0] + tri[0] * w[1] + tri[1] * w[2] + tri[2] * w[3];
        assert!(
            close(diff.length(), prox.distance),
            "{diff} vs {}",
            prox.distance
        );
        assert!(close(prox.normal.length(), 1.0));
        if prox.distance > 0.0 {
            assert!((diff / prox.distance - prox.normal).length() < 1e-9);
        }
    }

    #[test]
    fn regions_of_a_right_triangle() {
        let tri = [DVec3::ZERO, DVec3::X, DVec3::Y];
        // Above the interior.
        let p = DVec3::new(0.25, 0.25, 2.0);
        let r = proximity_vertex_triangle(p, tri);
        assert!(close(r.distance, 2.0));
        assert!((r.normal - DVec3::Z).length() < 1e-15);
        assert!(close(r.weights[1], -0.5) && close(r.weights[2], -0.25));
        assert_consistent(p, tri, &r);
        // Beside the hypotenuse.
        let p = DVec3::new(1.0, 1.0, 0.0);
        let r = proximity_vertex_triangle(p, tri);
        assert!(close(r.distance, 0.5f64.sqrt()));
        assert!(close(r.weights[2], -0.5) && close(r.weights[3], -0.5));
        assert_consistent(p, tri, &r);
        // Beyond a corner.
        let p = DVec3::new(-1.0, -1.0, 1.0);
        let r = proximity_vertex_triangle(p, tri);
        assert!(close(r.distance, 3f64.sqrt()));
        assert!(close(r.weights[1], -1.0));
        assert_consistent(p, tri, &r);
    }

    #[test]
    fn touching_uses_the_triangle_normal() {
        let tri = [DVec3::ZERO, DVec3::X, DVec3::Y];
        let r = proximity_vertex_triangle(DVec3::new(0.5, 0.0, 0.0), tri);
        assert_eq!(r.distance, 0.0);
        assert!((r.normal - DVec3::Z).length() < 1e-15);
    }

    #[test]
    fn degenerate_triangles() {
        // Collinear triangle: the closest point is on its longest edge.
        let tri = [DVec3::ZERO, DVec3::X * 2.0, DVec3::X];
        let p = DVec3::new(1.5, 1.0, 0.0);
        let r = proximity_vertex_triangle(p, tri);
        assert!(close(r.distance, 1.0));
        assert_consistent(p, tri, &r);
        // A point on it: the normal is some unit vector perpendicular to the segment.
        let r = proximity_vertex_triangle(DVec3::new(0.5, 0.0, 0.0), tri);
        assert_eq!(r.distance, 0.0);
        assert!(r.normal.dot(DVec3::X).abs() < 1e-15 && close(r.normal.length(), 1.0));
        // All three corners coincide.
        let tri = [DVec3::ONE; 3];
        let p = DVec3::new(1.0, 1.0, 4.0);
        let r = proximity_vertex_triangle(p, tri);
        assert!(close(r.distance, 3.0));
        assert_consistent(p, tri, &r);
    }

    #[test]
    fn sliver_matches_brute_force() {
        // A needle triangle: the projection path is skipped, the edges decide.
        let tri = [
            DVec3::ZERO,
            DVec3::new(1.0, 1e-9, 0.0),
            DVec3::new(2.0, 0.0, 0.0),
        ];
        for k in 0..20 {
            let p = DVec3::new(-0.5 + 0.15 * k as f64, 0.3, 0.2 * (k % 3) as f64);
            let r = proximity_vertex_triangle(p, tri);
            assert_consistent(p, tri, &r);
            // Brute force over a fine barycentric grid bounds the distance from above.
            let mut best = f64::INFINITY;
            for i in 0..=200 {
                for j in 0..=(200 - i) {
                    let (u, v) = (i as f64 / 200.0, j as f64 / 200.0);
                    let q = tri[0] * (1.0 - u - v) + tri[1] * u + tri[2] * v;
                    best = best.min((p - q).length());
                }
            }
            assert!(
                r.distance <= best + 1e-12 && r.distance >= best - 0.02,
                "{} vs {best}",
                r.distance
            );
        }
    }
}
