//! The coordinate range the library works in.
//!
//! The predicates are exact only while products of coordinate differences neither
//! overflow nor underflow (see the module doc of [`crate::predicates`]), and the float
//! measures around them (squared lengths and areas, volumes, the collision backend's
//! quartic CCD bounds: products of up to six differences) need the same headroom. A mesh
//! near 10³⁰⁰ makes those products infinite (ℓ = ∞, phantom intersections); a mesh near
//! 10⁻³⁰⁰ makes them zero (every triangle "of zero area"). Either way a later stage would
//! refuse it for a reason that is not the cause, so validation names the cause instead.
//!
//! The bounds are powers of two with room for degree six on both sides:
//! - every coordinate at most [`MAX_COORDINATE`] = 2¹⁰⁰ ≈ 1.3·10³⁰ in magnitude
//!   (differences of those, to the sixth power, stay below 2⁶⁰⁶);
//! - the mesh not smaller than [`MIN_EXTENT`] = 2⁻¹⁰⁰ ≈ 7.9·10⁻³¹: its largest coordinate
//!   magnitude at least that (or the mesh all zeros, which is zero-area anyway).
//!
//! The lower bound is on the mesh, not on each coordinate: a coordinate of 10⁻⁴⁵ (float32
//! export noise near a plane through the origin) is harmless in a mesh of unit size,
//! since its differences with its neighbours are of the mesh's size.

use glam::DVec3;

/// Largest coordinate magnitude supported: 2¹⁰⁰ ≈ 1.27·10³⁰.
pub const MAX_COORDINATE: f64 = f64::from_bits((1023 + 100) << 52);

/// Smallest supported size of a mesh, as its largest coordinate magnitude: 2⁻¹⁰⁰ ≈
/// 7.9·10⁻³¹.
pub const MIN_EXTENT: f64 = f64::from_bits((1023 - 100) << 52);

/// Whether every coordinate of `p` is finite and at most [`MAX_COORDINATE`] in magnitude.
#[inline]
pub fn within_max_coordinate(p: DVec3) -> bool {
    // `max_element` skips NaN (it is `f64::max`), hence the finiteness test.
    p.is_finite() && p.abs().max_element() <= MAX_COORDINATE
}

/// Whether a mesh whose largest finite coordinate magnitude is `extent` is too small for
/// the predicates (nonzero and below [`MIN_EXTENT`]).
#[inline]
pub fn below_min_extent(extent: f64) -> bool {
    extent > 0.0 && extent < MIN_EXTENT
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bounds_are_the_powers_of_two_they_claim() {
        assert_eq!(MAX_COORDINATE, 2f64.powi(100));
        assert_eq!(MIN_EXTENT, 2f64.powi(-100));
        assert!(within_max_coordinate(DVec3::new(-MAX_COORDINATE, 0.0, 1.0)));
        assert!(!within_max_coordinate(DVec3::new(0.0, 1e31, 0.0)));
        assert!(!within_max_coordinate(DVec3::new(f64::NAN, 0.0, 0.0)));
        assert!(!within_max_coordinate(DVec3::new(f64::INFINITY, 0.0, 0.0)));
        assert!(below_min_extent(1e-300) && !below_min_extent(0.0) && !below_min_extent(1e-30));
    }
}
