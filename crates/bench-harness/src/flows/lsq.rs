//! Rank-truncated least squares for 3 unknowns: the displacement that best satisfies a set
//! of plane-offset equations `nᵢ·x = dᵢ` with weights `wᵢ`.
//!
//! The normal equations `M x = b`, `M = Σ wᵢ nᵢ nᵢᵀ`, `b = Σ wᵢ dᵢ nᵢ`, are solved in
//! the eigenbasis of `M` keeping only eigen-directions with `λ > ratio·λ_max` (the
//! *primary space* of face offsetting, Jiao 2007). On a smooth patch all normals nearly
//! agree, `M` has one large eigenvalue and the solution moves along the normal only; along
//! a ridge or a triple curve two directions are kept and the curve moves so that every
//! sheet is offset by its own distance; at a corner all three. Directions dropped are the
//! null space: the displacement has no component there (min-norm solution), which is why
//! the solve never amplifies a nearly singular direction.

use glam::{DMat3, DVec3};
use nalgebra::Matrix3;

/// Relative eigenvalue threshold of the primary space. El Topo and Los Topos use 0.03
/// (`G_EIGENVALUE_RANK_RATIO`): normals of a smooth patch within ~10° of each other give
/// a second eigenvalue below it, a feature sharper than that is kept.
pub(crate) const RANK_RATIO: f64 = 0.03;

/// Accumulator of weighted plane equations.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PlaneLsq {
    m: DMat3,
    b: DVec3,
}

impl Default for PlaneLsq {
    /// Empty sums. (Not derived: glam's `DMat3::default()` is the identity.)
    fn default() -> Self {
        PlaneLsq {
            m: DMat3::ZERO,
            b: DVec3::ZERO,
        }
    }
}

impl PlaneLsq {
    /// Adds `w·(n·x − d)²` to the objective; `n` should be unit length.
    #[inline]
    pub(crate) fn add(&mut self, n: DVec3, d: f64, w: f64) {
        self.m += DMat3::from_cols(n * (w * n.x), n * (w * n.y), n * (w * n.z));
        self.b += n * (w * d);
    }

    /// The min-norm minimiser restricted to the primary space (see the module doc); zero
    /// when nothing was added or the sums are not finite.
    pub(crate) fn solve(&self, ratio: f64) -> DVec3 {
        let m = &self.m;
        let a = Matrix3::new(
            m.x_axis.x, m.y_axis.x, m.z_axis.x, //
            m.x_axis.y, m.y_axis.y, m.z_axis.y, //
            m.x_axis.z, m.y_axis.z, m.z_axis.z,
        );
        if !a.iter().all(|x| x.is_finite()) || !self.b.is_finite() {
            return DVec3::ZERO;
        }
        let eig = a.symmetric_eigen();
        let lambda_max = eig.eigenvalues.iter().cloned().fold(0.0, f64::max);
        if lambda_max <= 0.0 {
            return DVec3::ZERO;
        }
        let mut x = DVec3::ZERO;
        for i in 0..3 {
            let lambda = eig.eigenvalues[i];
            if lambda > ratio * lambda_max {
                let c = eig.eigenvectors.column(i);
                let e = DVec3::new(c[0], c[1], c[2]);
                x += e * (e.dot(self.b) / lambda);
            }
        }
        if x.is_finite() { x } else { DVec3::ZERO }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn three_orthogonal_planes_meet_at_their_offsets() {
        let mut l = PlaneLsq::default();
        l.add(DVec3::X, 1.0, 2.0);
        l.add(DVec3::Y, -2.0, 1.0);
        l.add(DVec3::Z, 0.5, 3.0);
        assert!((l.solve(RANK_RATIO) - DVec3::new(1.0, -2.0, 0.5)).length() < 1e-12);
    }

    #[test]
    fn nearly_parallel_planes_move_along_the_mean_normal_only() {
        // Two planes 2° apart asking for inconsistent offsets: an exact solve would shoot
        // sideways by ~ (1 − 0.9) / sin 2° ≈ 2.9; the primary space keeps only the normal.
        let a = 1f64.to_radians();
        let mut l = PlaneLsq::default();
        l.add(DVec3::new(a.sin(), 0.0, a.cos()), 1.0, 1.0);
        l.add(DVec3::new(-a.sin(), 0.0, a.cos()), 0.9, 1.0);
        let x = l.solve(RANK_RATIO);
        assert!(x.x.abs() < 1e-12 && x.y.abs() < 1e-12, "{x}");
        assert!((x.z - 0.95 / a.cos()).abs() < 1e-12, "{x}");
        // With no truncation the sideways solution appears.
        assert!(l.solve(1e-6).x.abs() > 1.0);
    }

    #[test]
    fn empty_and_non_finite_give_zero() {
        assert_eq!(PlaneLsq::default().solve(RANK_RATIO), DVec3::ZERO);
        let mut l = PlaneLsq::default();
        l.add(DVec3::X, f64::NAN, 1.0);
        assert_eq!(l.solve(RANK_RATIO), DVec3::ZERO);
    }
}
