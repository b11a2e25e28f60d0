//! The Enright test field (Enright, Fedkiw, Ferziger and Mitchell 2002; used by El Topo
//! §4.3 and Los Topos §8.1): a divergence-free swirl on the unit cube that stretches a
//! sphere at `(0.35, 0.35, 0.35)`, radius 0.15, into thin sheets, then — because the
//! field is modulated by `cos(π t / T)` — runs backwards and returns it at `t = T`:
//!
//! ```text
//! u =  2 sin²(πx) sin(2πy) sin(2πz) · cos(πt/T)
//! v = −  sin(2πx) sin²(πy) sin(2πz) · cos(πt/T)
//! w = −  sin(2πx) sin(2πy) sin²(πz) · cos(πt/T)
//! ```
//!
//! Divergence: `∂u/∂x = 2π S`, `∂v/∂y = ∂w/∂z = −π S` with `S = sin 2πx sin 2πy sin 2πz`,
//! summing to zero. The usual period is `T = 3`. (El Topo's paper writes the modulation
//! as a sine; the cosine of Enright et al. is the one that starts at full speed and returns
//! the sphere at `t = T`.)

use std::f64::consts::PI;

use glam::{DMat3, DVec3};

use super::error::check_positive;
use super::{AdvectedFlow, FlowError, Integrator, VelocityField};

/// The Enright field with period `T` (see the module doc), advected by RK4 by default.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EnrightFlow {
    period: f64,
    integrator: Integrator,
}

impl EnrightFlow {
    /// The usual period.
    pub const DEFAULT_PERIOD: f64 = 3.0;

    /// The field with period `period` (finite, > 0), integrated by RK4.
    pub fn new(period: f64) -> Result<Self, FlowError> {
        check_positive("enright", "period", period)?;
        Ok(EnrightFlow {
            period,
            integrator: Integrator::Rk4,
        })
    }

    /// The same field integrated another way.
    pub fn with_integrator(mut self, integrator: Integrator) -> Self {
        self.integrator = integrator;
        self
    }

    /// The period `T`.
    pub fn period(&self) -> f64 {
        self.period
    }

    #[inline]
    fn modulation(&self, t: f64) -> f64 {
        (PI * t / self.period).cos()
    }
}

impl Default for EnrightFlow {
    fn default() -> Self {
        EnrightFlow {
            period: Self::DEFAULT_PERIOD,
            integrator: Integrator::Rk4,
        }
    }
}

/// `(sin πq, sin 2πq, cos 2πq)`.
#[inline]
fn trig(q: f64) -> (f64, f64, f64) {
    let (s, c) = (PI * q).sin_cos();
    (s, 2.0 * s * c, c * c - s * s)
}

impl VelocityField for EnrightFlow {
    fn velocity(&self, p: DVec3, t: f64) -> DVec3 {
        let (sx, s2x, _) = trig(p.x);
        let (sy, s2y, _) = trig(p.y);
        let (sz, s2z, _) = trig(p.z);
        self.modulation(t)
            * DVec3::new(
                2.0 * sx * sx * s2y * s2z,
                -s2x * sy * sy * s2z,
                -s2x * s2y * sz * sz,
            )
    }

    fn velocity_gradient(&self, p: DVec3, t: f64) -> DMat3 {
        let (sx, s2x, c2x) = trig(p.x);
        let (sy, s2y, c2y) = trig(p.y);
        let (sz, s2z, c2z) = trig(p.z);
        // d/dq sin²(πq) = π sin 2πq; d/dq sin 2πq = 2π cos 2πq.
        let m = self.modulation(t);
        let d_dx = DVec3::new(
            2.0 * PI * s2x * s2y * s2z,
            -2.0 * PI * c2x * sy * sy * s2z,
            -2.0 * PI * c2x * s2y * sz * sz,
        );
        let d_dy = DVec3::new(
            4.0 * PI * sx * sx * c2y * s2z,
            -PI * s2x * s2y * s2z,
            -2.0 * PI * s2x * c2y * sz * sz,
        );
        let d_dz = DVec3::new(
            4.0 * PI * sx * sx * s2y * c2z,
            -2.0 * PI * s2x * sy * sy * c2z,
            -PI * s2x * s2y * s2z,
        );
        DMat3::from_cols(m * d_dx, m * d_dy, m * d_dz)
    }
}

impl AdvectedFlow for EnrightFlow {
    const NAME: &'static str = "enright";

    fn integrator(&self) -> Integrator {
        self.integrator
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flows::finite_difference_gradient;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn sample_points(seed: u64, n: usize) -> Vec<DVec3> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        (0..n)
            .map(|_| DVec3::new(rng.random(), rng.random(), rng.random()))
            .collect()
    }

    #[test]
    fn divergence_free_and_gradient_matches_finite_differences() {
        let f = EnrightFlow::default();
        for x in sample_points(1, 200) {
            let t = 0.4;
            let g = f.velocity_gradient(x, t);
            let fd = finite_difference_gradient(&f, x, t, 1e-5);
            assert!(g.abs_diff_eq(fd, 1e-7), "{x}: {g} vs {fd}");
            // Divergence = trace, analytically and by finite differences.
            let div = g.x_axis.x + g.y_axis.y + g.z_axis.z;
            let div_fd = fd.x_axis.x + fd.y_axis.y + fd.z_axis.z;
            assert!(div.abs() < 1e-12 && div_fd.abs() < 1e-7, "{div} {div_fd}");
        }
    }

    #[test]
    fn known_values_and_modulation() {
        let f = EnrightFlow::default();
        let x = DVec3::new(0.5, 0.25, 0.25);
        // sin²(π/2) = 1, sin(π/2) = 1, sin π = 0: u = 2, v = w = 0.
        assert!((f.velocity(x, 0.0) - DVec3::new(2.0, 0.0, 0.0)).length() < 1e-14);
        assert!(f.velocity(x, 1.5).length() < 1e-14, "still at t = T/2");
        assert!(
            (f.velocity(x, 3.0) + DVec3::new(2.0, 0.0, 0.0)).length() < 1e-14,
            "reversed at t = T"
        );
        assert!(EnrightFlow::new(0.0).is_err() && EnrightFlow::new(f64::NAN).is_err());
    }

    #[test]
    fn rk4_returns_points_after_one_period() {
        // The modulation makes the flow time-symmetric about T/2: over [0, T] every
        // trajectory returns to its start, up to the integration error.
        let f = EnrightFlow::new(1.0).unwrap();
        let steps = 200;
        let dt = 1.0 / steps as f64;
        for x0 in sample_points(2, 20) {
            let mut x = x0;
            for k in 0..steps {
                x = Integrator::Rk4.step(&f, x, k as f64 * dt, dt);
            }
            assert!((x - x0).length() < 1e-6, "{x0} -> {x}");
        }
    }
}
