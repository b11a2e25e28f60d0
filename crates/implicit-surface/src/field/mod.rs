//! Stage 0 — the field function `F(x, t)` (paper §1, §5).
//!
//! Convention (the paper's): the surface is the zero set `F(x, t) = 0`, and `F > 0`
//! inside. A blend of skeletons with iso-value `c` is `F = Σ wᵢ fᵢ(dᵢ) − c`, so the
//! iso-value lives inside the field and every algorithm here looks for `F = 0`.
//!
//! - [`ImplicitField`]: the trait users implement for their own `F` and `∇F`;
//! - [`skeleton`]: points and segments with a family of norms for the distance
//!   ([`Norm`]: L2, Lₚ "superellipsoid" norms) and falloff kernels ([`Falloff`]: a
//!   Wyvill-style compact polynomial and a softened `1/d²`), moved along keyframed
//!   [`Path`]s — the paper's animated skeleton-based surfaces;
//! - [`grid`]: a field sampled on a regular grid over time frames (the paper's volume
//!   data), trilinear in space, linear in time, with the analytic gradient of the
//!   interpolant;
//! - [`SphereField`]: the simplest field, for tests and examples.

pub mod grid;
pub mod skeleton;

use glam::DVec3;

pub use grid::GridField;
pub use skeleton::{Falloff, Norm, Path, Skeleton, SkeletonElement, SkeletonField};

/// An animated implicit field `F(x, t)`: the surface is `F = 0`, inside is `F > 0`.
///
/// Implement it to mesh your own shape; the follower (§2), the refinement (§3) and the
/// polygonizer only ever call these methods. `Send + Sync` because every per-vertex
/// evaluation runs on rayon.
pub trait ImplicitField: Send + Sync {
    /// `F(p, t)`.
    fn value(&self, p: DVec3, t: f64) -> f64;

    /// `∇F(p, t)` (spatial gradient; points into the inside where the surface is regular).
    fn gradient(&self, p: DVec3, t: f64) -> DVec3;

    /// Both at once; override when they share work (skeleton distances do).
    fn value_and_gradient(&self, p: DVec3, t: f64) -> (f64, DVec3) {
        (self.value(p, t), self.gradient(p, t))
    }

    /// A box `[min, max]` containing the inside `{F ≥ 0}` at time `t`, if known: the
    /// polygonizer needs one. `None` means unbounded or unknown.
    fn bounds(&self, _t: f64) -> Option<[DVec3; 2]> {
        None
    }
}

impl<T: ImplicitField + ?Sized> ImplicitField for &T {
    fn value(&self, p: DVec3, t: f64) -> f64 {
        (**self).value(p, t)
    }
    fn gradient(&self, p: DVec3, t: f64) -> DVec3 {
        (**self).gradient(p, t)
    }
    fn value_and_gradient(&self, p: DVec3, t: f64) -> (f64, DVec3) {
        (**self).value_and_gradient(p, t)
    }
    fn bounds(&self, t: f64) -> Option<[DVec3; 2]> {
        (**self).bounds(t)
    }
}

impl<T: ImplicitField + ?Sized> ImplicitField for Box<T> {
    fn value(&self, p: DVec3, t: f64) -> f64 {
        (**self).value(p, t)
    }
    fn gradient(&self, p: DVec3, t: f64) -> DVec3 {
        (**self).gradient(p, t)
    }
    fn value_and_gradient(&self, p: DVec3, t: f64) -> (f64, DVec3) {
        (**self).value_and_gradient(p, t)
    }
    fn bounds(&self, t: f64) -> Option<[DVec3; 2]> {
        (**self).bounds(t)
    }
}

/// Central finite differences of `F` with step `h`: a fallback gradient for user fields
/// that have no analytic one, and the reference the tests compare analytic gradients to.
pub fn finite_difference_gradient(
    field: &(impl ImplicitField + ?Sized),
    p: DVec3,
    t: f64,
    h: f64,
) -> DVec3 {
    let d = |e: DVec3| (field.value(p + e * h, t) - field.value(p - e * h, t)) / (2.0 * h);
    DVec3::new(d(DVec3::X), d(DVec3::Y), d(DVec3::Z))
}

/// A sphere moving at constant velocity: `F = r − |p − c(t)|`, `c(t) = c₀ + v t`. Its
/// gradient is unit length away from the centre, so Newton projection (eq. 2) lands
/// on it in one step: the reference case of the projection tests.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SphereField {
    /// Centre at `t = 0`.
    pub centre: DVec3,
    /// Velocity of the centre.
    pub velocity: DVec3,
    /// Radius.
    pub radius: f64,
}

impl SphereField {
    /// A still sphere.
    pub fn new(centre: DVec3, radius: f64) -> Self {
        Self {
            centre,
            velocity: DVec3::ZERO,
            radius,
        }
    }

    fn centre_at(&self, t: f64) -> DVec3 {
        self.centre + self.velocity * t
    }
}

impl ImplicitField for SphereField {
    fn value(&self, p: DVec3, t: f64) -> f64 {
        self.radius - (p - self.centre_at(t)).length()
    }

    fn gradient(&self, p: DVec3, t: f64) -> DVec3 {
        -(p - self.centre_at(t)).normalize_or_zero()
    }

    fn bounds(&self, t: f64) -> Option<[DVec3; 2]> {
        let c = self.centre_at(t);
        let r = DVec3::splat(self.radius.abs());
        Some([c - r, c + r])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sphere_gradient_matches_finite_differences_and_points_inside() {
        let s = SphereField {
            centre: DVec3::new(0.1, -0.2, 0.3),
            velocity: DVec3::new(1.0, 0.0, 0.0),
            radius: 0.5,
        };
        let p = DVec3::new(0.7, 0.1, -0.2);
        let g = s.gradient(p, 0.3);
        let fd = finite_difference_gradient(&s, p, 0.3, 1e-6);
        assert!((g - fd).length() < 1e-6, "{g} vs {fd}");
        assert!(g.dot(s.centre_at(0.3) - p) > 0.0);
    }
}
