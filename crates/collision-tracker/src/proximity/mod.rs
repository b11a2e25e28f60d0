//! Static proximity: the closest points of two mesh elements at one instant.
//!
//! El Topo (Brochu & Bridson 2009, §3.4 and §3.8) uses these queries twice: repulsion
//! impulses push apart element pairs closer than the proximity threshold, and snap merging
//! (Los Topos §7.1) splits edges and triangles at the closest points of proximate pairs. The
//! continuous collision detection in [`crate::ccd`] also calls them to choose its separating
//! directions and to report where the contact happens.
//!
//! Entry points: [`proximity_vertex_triangle`] and [`proximity_edge_edge`]; both return a
//! [`Proximity`].
//!
//! # Glossary
//!
//! - **first / second element**: the vertex and the triangle, or the edge `p0 p1` and the
//!   edge `q0 q1`, in argument order.
//! - **weights** `w`: four numbers, one per vertex in argument order, signed as in El Topo:
//!   positive on the first element, negative on the second, so that `Σ wᵢ xᵢ` is the vector
//!   from the closest point of the second element to the closest point of the first. For a
//!   vertex–triangle pair `w = [1, −α, −β, −γ]` with `(α, β, γ)` the barycentric
//!   coordinates of the closest triangle point; for an edge pair
//!   `w = [1 − s, s, −(1 − u), −u]` with the closest points `p0 + s (p1 − p0)` and
//!   `q0 + u (q1 − q0)`. The same weights distribute an impulse over the four vertices.
//! - **normal**: the unit vector along `Σ wᵢ xᵢ` (from the second element towards the
//!   first), so an impulse along it increases the distance. When the elements touch
//!   (distance 0) there is no such direction, and a documented geometric fallback is used.
//!
//! # Robustness
//!
//! The closest pair is found among candidates that are all true points of the elements
//! (clamped convex combinations): the interior solution of the normal equations when it is
//! well conditioned and feasible, otherwise the closest points of the boundary pieces
//! (point–segment queries, which treat zero-length segments as points). Parallel edges,
//! zero-length edges and zero-area triangles therefore need no special tolerance: the
//! boundary candidates cover them exactly.

mod edge_edge;
mod vertex_triangle;

pub use edge_edge::proximity_edge_edge;
pub use vertex_triangle::proximity_vertex_triangle;

use glam::DVec3;

/// The closest points of two elements, as distance, signed weights and a unit normal.
///
/// See the [module glossary](self) for the sign convention of `weights` and `normal`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Proximity {
    /// Euclidean distance between the closest points (0 when the elements touch).
    pub distance: f64,
    /// El Topo's signed weights: `Σ wᵢ xᵢ` = closest point of the first element minus
    /// closest point of the second.
    pub weights: [f64; 4],
    /// Unit vector from the second element towards the first (a fallback when touching).
    pub normal: DVec3,
}

/// Below this squared sine of the angle between two directions, the directions are
/// treated as parallel and the boundary candidates decide. The interior solution of a
/// nearly singular 2×2 system is inaccurate; the boundary candidates are exact there, so
/// the threshold only trades speed for accuracy and never affects correctness.
pub(crate) const PARALLEL_SIN2: f64 = 1e-12;

/// Parameter of the point of segment `[a, b]` closest to `p`, clamped to `[0, 1]`; a
/// zero-length (or non-finite) segment is a point, parameter 0.
#[inline]
pub(crate) fn closest_param_on_segment(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    let e = b - a;
    let ee = e.dot(e);
    if !(ee > 0.0 && ee.is_finite()) {
        return 0.0;
    }
    let s = (p - a).dot(e) / ee;
    if s.is_nan() { 0.0 } else { s.clamp(0.0, 1.0) }
}

/// The unit vector of `v`, or `None` when `v` is zero, subnormal-tiny or not finite.
#[inline]
pub(crate) fn unit(v: DVec3) -> Option<DVec3> {
    let len = v.length();
    if len > 0.0 && len.is_finite() {
        let n = v / len;
        // Guards against a denormal `len` whose quotient lost its unit length.
        if (n.length_squared() - 1.0).abs() < 1e-6 {
            return Some(n);
        }
    }
    None
}

/// Some unit vector perpendicular to the longest of `dirs` (the z axis if all vanish):
/// the normal of last resort for degenerate, touching configurations.
pub(crate) fn perpendicular_to_longest(dirs: &[DVec3]) -> DVec3 {
    let longest = dirs.iter().copied().fold(DVec3::ZERO, |best, d| {
        if d.length_squared() > best.length_squared() {
            d
        } else {
            best
        }
    });
    match unit(longest) {
        Some(d) => d.any_orthonormal_vector(),
        None => DVec3::Z,
    }
}

/// `v` with its component along `e` removed (`v` itself when `e` vanishes), projected
/// twice: one pass leaves a residue of about `u |v|` along `e`, which matters when the
/// result is much shorter than `v`; the second pass removes it.
#[inline]
pub(crate) fn off_line(v: DVec3, e: DVec3) -> DVec3 {
    let ee = e.dot(e);
    if !(ee > 0.0 && ee.is_finite()) {
        return v;
    }
    let once = v - e * (v.dot(e) / ee);
    once - e * (once.dot(e) / ee)
}

/// Builds the result from the closest-point difference `diff` (first minus second).
///
/// `feature_dir` is the same direction computed from the closest *features* (the
/// triangle normal for a face, `diff` with the edge direction projected out for an edge,
/// `diff` for a vertex). Mathematically it is parallel to `diff`; numerically it is far
/// better when the distance is tiny, because `diff` then carries a relative error of
/// `u |x| / distance` in every direction while the feature direction keeps the component
/// along the feature exactly zero up to `u`. CCD relies on this to separate elements a
/// hair apart. `fallback` is used when the elements touch.
#[inline]
pub(crate) fn finish(
    diff: DVec3,
    weights: [f64; 4],
    feature_dir: DVec3,
    fallback: impl FnOnce() -> DVec3,
) -> Proximity {
    let distance = diff.length();
    let normal = match unit(diff) {
        None => fallback(),
        Some(n) => match unit(feature_dir) {
            Some(f) if f.dot(n) > 0.0 => f,
            Some(f) if f.dot(n) < 0.0 => -f,
            _ => n,
        },
    };
    Proximity {
        distance,
        weights,
        normal,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn segment_param_clamps_and_handles_points() {
        let a = DVec3::ZERO;
        let b = DVec3::X * 2.0;
        assert_eq!(
            closest_param_on_segment(DVec3::new(1.0, 5.0, 0.0), a, b),
            0.5
        );
        assert_eq!(
            closest_param_on_segment(DVec3::new(-3.0, 0.0, 0.0), a, b),
            0.0
        );
        assert_eq!(
            closest_param_on_segment(DVec3::new(9.0, 1.0, 0.0), a, b),
            1.0
        );
        assert_eq!(closest_param_on_segment(DVec3::ONE, a, a), 0.0);
    }

    #[test]
    fn unit_rejects_zero_and_tiny() {
        assert!(unit(DVec3::ZERO).is_none());
        assert!(unit(DVec3::new(f64::NAN, 0.0, 0.0)).is_none());
        let n = unit(DVec3::new(3.0, 4.0, 0.0)).unwrap_or(DVec3::ZERO);
        assert!((n - DVec3::new(0.6, 0.8, 0.0)).length() < 1e-15);
        let p = perpendicular_to_longest(&[DVec3::X, DVec3::ZERO]);
        assert!(p.dot(DVec3::X).abs() < 1e-15 && (p.length() - 1.0).abs() < 1e-15);
        assert_eq!(perpendicular_to_longest(&[DVec3::ZERO]), DVec3::Z);
    }
}
