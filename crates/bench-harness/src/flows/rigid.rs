//! Rigid rotation about an axis through a point: the Zalesak test (a notched sphere turned
//! once around an external point must come back unchanged, sharp notch included; Los
//! Topos §8.1). `u(x) = ω a × (x − c)`, `∇u = ω [a]ₓ` (the cross-product matrix), which is
//! antisymmetric: no stretching, no divergence.

use std::f64::consts::TAU;

use glam::{DMat3, DVec3};

use super::error::{check_finite, check_finite_vec, check_positive, invalid};
use super::{AdvectedFlow, FlowError, Integrator, VelocityField};

/// Rotation about the axis `a` (unit) through `centre` at angular speed `ω` (radians per
/// unit time, counter-clockwise about `a`), advected by RK4 by default.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigidRotation {
    centre: DVec3,
    /// `ω·a`.
    omega: DVec3,
    integrator: Integrator,
}

impl RigidRotation {
    /// Rotation about `axis` (any non-zero length; normalised) through `centre` at
    /// `angular_speed`. Fails on non-finite input or a zero axis.
    pub fn new(centre: DVec3, axis: DVec3, angular_speed: f64) -> Result<Self, FlowError> {
        const NAME: &str = "rotation";
        check_finite_vec(NAME, "centre", centre)?;
        check_finite_vec(NAME, "axis", axis)?;
        check_finite(NAME, "angular_speed", angular_speed)?;
        let a = axis.normalize_or_zero();
        if a == DVec3::ZERO {
            return Err(invalid(NAME, "axis", axis, "a non-zero vector"));
        }
        Ok(RigidRotation {
            centre,
            omega: angular_speed * a,
            integrator: Integrator::Rk4,
        })
    }

    /// The Zalesak set-up: one full turn about the z axis through `centre` every `period`
    /// time units.
    pub fn zalesak(centre: DVec3, period: f64) -> Result<Self, FlowError> {
        check_positive("rotation", "period", period)?;
        Self::new(centre, DVec3::Z, TAU / period)
    }

    /// The same rotation integrated another way.
    pub fn with_integrator(mut self, integrator: Integrator) -> Self {
        self.integrator = integrator;
        self
    }
}

impl VelocityField for RigidRotation {
    fn velocity(&self, x: DVec3, _t: f64) -> DVec3 {
        self.omega.cross(x - self.centre)
    }

    fn velocity_gradient(&self, _x: DVec3, _t: f64) -> DMat3 {
        // Column j is ω × e_j.
        DMat3::from_cols(
            self.omega.cross(DVec3::X),
            self.omega.cross(DVec3::Y),
            self.omega.cross(DVec3::Z),
        )
    }
}

impl AdvectedFlow for RigidRotation {
    const NAME: &'static str = "rotation";

    fn integrator(&self) -> Integrator {
        self.integrator
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flows::test_meshes::icosphere;
    use crate::flows::{Flow, finite_difference_gradient};
    use mesh_core::Label;

    #[test]
    fn rk4_full_turn_returns_every_vertex() {
        let centre = DVec3::new(0.5, 0.5, 0.0);
        let flow = RigidRotation::zalesak(centre, 1.0).unwrap();
        let mut mesh = icosphere(2, 0.15, [Label::new(0), Label::new(1)]);
        for p in mesh.positions_mut() {
            *p += DVec3::new(0.5, 0.75, 0.1);
        }
        let start = mesh.positions().to_vec();
        let steps = 600;
        let dt = 1.0 / steps as f64;
        for k in 0..steps {
            let p = flow.propose(&mesh, k as f64 * dt, dt);
            mesh.positions_mut().copy_from_slice(&p);
        }
        let worst = start
            .iter()
            .zip(mesh.positions())
            .map(|(a, b)| a.distance(*b))
            .fold(0.0, f64::max);
        assert!(worst < 1e-8, "worst displacement after one turn {worst}");
        // Half a turn really moved them (the test above is not vacuous).
        let half = (0..steps / 2).fold(start[0], |x, k| {
            Integrator::Rk4.step(&flow, x, k as f64 * dt, dt)
        });
        assert!((half - (2.0 * centre - start[0]).with_z(start[0].z)).length() < 1e-9);
    }

    #[test]
    fn forward_euler_drifts_outwards() {
        // Euler multiplies the radius by √(1 + ω²dt²) per step: a clear, known failure.
        let flow = RigidRotation::new(DVec3::ZERO, DVec3::Z, 1.0)
            .unwrap()
            .with_integrator(Integrator::ForwardEuler);
        let x = Integrator::ForwardEuler.step(&flow, DVec3::X, 0.0, 0.1);
        assert!((x.length() - (1.01f64).sqrt()).abs() < 1e-15);
    }

    #[test]
    fn gradient_matches_finite_differences_and_is_antisymmetric() {
        let flow =
            RigidRotation::new(DVec3::new(1.0, 2.0, 3.0), DVec3::new(1.0, -1.0, 2.0), 0.7).unwrap();
        let x = DVec3::new(-0.3, 0.8, 2.0);
        let g = flow.velocity_gradient(x, 0.0);
        assert!(g.abs_diff_eq(finite_difference_gradient(&flow, x, 0.0, 1e-4), 1e-10));
        assert!((g + g.transpose()).abs_diff_eq(DMat3::ZERO, 1e-15));
        assert!(RigidRotation::new(DVec3::ZERO, DVec3::ZERO, 1.0).is_err());
        assert!(RigidRotation::zalesak(DVec3::ZERO, 0.0).is_err());
    }
}
