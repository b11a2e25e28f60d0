//! Curl noise (Bridson, Hourihan and Nordenstam 2007), as in El Topo §4.3 and the Los
//! Topos normal-flow + curl-noise test (Fig. 15): a smooth, pseudo-random velocity field
//! that is divergence-free because it is a curl.
//!
//! **Potential.** A seeded sum of `M` plane waves,
//! `ψ(x) = Σₖ aₖ sin(ωₖ·x + φₖ)`, with wave vectors `ωₖ` of random direction and length
//! `2π/ℓ · U[0.5, 1.5]` (`ℓ` the length scale), random amplitude directions `aₖ` and
//! phases `φₖ ∈ [0, 2π)`, drawn from ChaCha8 seeded by the seed — so a seed always gives
//! the same field, on every platform and thread count.
//!
//! **Field.** `u = ∇×ψ = Σₖ cos(ωₖ·x + φₖ) cₖ` with `cₖ = ωₖ × aₖ`, hence
//! `∇·u = −Σₖ sin(…) ωₖ·(ωₖ × aₖ) = 0` exactly, and the gradient is analytic:
//! `∇u = −Σₖ sin(ωₖ·x + φₖ) cₖ ωₖᵀ`. The amplitudes are scaled so the mean of `|u|²` over
//! space, `Σₖ |cₖ|²/2`, equals `amplitude²`. The field is steady (no time dependence) and
//! unbounded in space (no boundary damping).

use std::f64::consts::PI;

use glam::{DMat3, DVec3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::error::{check_positive, invalid};
use super::{AdvectedFlow, FlowError, Integrator, VelocityField};

/// Parameters of [`CurlNoiseFlow`], with documented defaults.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CurlNoiseParams {
    /// Seed of the random modes.
    pub seed: u64,
    /// Number of plane waves `M` (1 ..= [`CurlNoiseParams::MAX_MODES`]); default 16,
    /// enough for the field not to look periodic.
    pub modes: usize,
    /// Typical wavelength `ℓ`; default 0.5 (features a quarter of a unit sphere's size).
    pub length_scale: f64,
    /// Root-mean-square speed; default 1.
    pub amplitude: f64,
}

impl CurlNoiseParams {
    /// Most modes accepted: each costs a sine per evaluation, four per RK4 step.
    pub const MAX_MODES: usize = 4096;
}

impl Default for CurlNoiseParams {
    fn default() -> Self {
        CurlNoiseParams {
            seed: 0,
            modes: 16,
            length_scale: 0.5,
            amplitude: 1.0,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
struct Mode {
    omega: DVec3,
    /// `ω × a`, scaled.
    c: DVec3,
    phase: f64,
}

/// The curl-noise field (see the module doc), advected by RK4 by default.
#[derive(Clone, Debug, PartialEq)]
pub struct CurlNoiseFlow {
    params: CurlNoiseParams,
    modes: Vec<Mode>,
    integrator: Integrator,
}

/// A direction uniform on the unit sphere (uniform height, uniform azimuth).
fn random_direction(rng: &mut ChaCha8Rng) -> DVec3 {
    let z: f64 = rng.random_range(-1.0..=1.0);
    let phi: f64 = rng.random_range(0.0..2.0 * PI);
    let r = (1.0 - z * z).max(0.0).sqrt();
    DVec3::new(r * phi.cos(), r * phi.sin(), z)
}

impl CurlNoiseFlow {
    /// Draws the modes. Fails on `modes` outside `1..=MAX_MODES` or a length scale or
    /// amplitude that is not finite and positive.
    pub fn new(params: CurlNoiseParams) -> Result<Self, FlowError> {
        const NAME: &str = "curl-noise";
        if params.modes == 0 || params.modes > CurlNoiseParams::MAX_MODES {
            return Err(invalid(NAME, "modes", params.modes, "1 ..= 4096"));
        }
        let length = check_positive(NAME, "length_scale", params.length_scale)?;
        let amplitude = check_positive(NAME, "amplitude", params.amplitude)?;
        let mut rng = ChaCha8Rng::seed_from_u64(params.seed);
        let base = 2.0 * PI / length;
        let mut modes: Vec<Mode> = (0..params.modes)
            .map(|_| {
                let omega = random_direction(&mut rng) * (base * rng.random_range(0.5..1.5));
                let a = random_direction(&mut rng);
                let phase = rng.random_range(0.0..2.0 * PI);
                Mode {
                    omega,
                    c: omega.cross(a),
                    phase,
                }
            })
            .collect();
        let mean_square: f64 = modes.iter().map(|m| m.c.length_squared() / 2.0).sum();
        if mean_square > 0.0 {
            let scale = amplitude / mean_square.sqrt();
            for m in &mut modes {
                m.c *= scale;
            }
        }
        Ok(CurlNoiseFlow {
            params,
            modes,
            integrator: Integrator::Rk4,
        })
    }

    /// The same field integrated another way.
    pub fn with_integrator(mut self, integrator: Integrator) -> Self {
        self.integrator = integrator;
        self
    }

    /// The parameters it was drawn from.
    pub fn params(&self) -> &CurlNoiseParams {
        &self.params
    }
}

impl VelocityField for CurlNoiseFlow {
    fn velocity(&self, x: DVec3, _t: f64) -> DVec3 {
        self.modes
            .iter()
            .map(|m| (m.omega.dot(x) + m.phase).cos() * m.c)
            .sum()
    }

    fn velocity_gradient(&self, x: DVec3, _t: f64) -> DMat3 {
        let mut g = DMat3::ZERO;
        for m in &self.modes {
            let s = -(m.omega.dot(x) + m.phase).sin();
            // Column j of c ωᵀ is c·ω_j.
            g += DMat3::from_cols(
                m.c * (s * m.omega.x),
                m.c * (s * m.omega.y),
                m.c * (s * m.omega.z),
            );
        }
        g
    }
}

impl AdvectedFlow for CurlNoiseFlow {
    const NAME: &'static str = "curl-noise";

    fn integrator(&self) -> Integrator {
        self.integrator
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flows::finite_difference_gradient;

    fn points(seed: u64, n: usize, size: f64) -> Vec<DVec3> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        (0..n)
            .map(|_| DVec3::new(rng.random(), rng.random(), rng.random()) * size)
            .collect()
    }

    #[test]
    fn divergence_free_and_gradient_matches_finite_differences() {
        let f = CurlNoiseFlow::new(CurlNoiseParams {
            seed: 7,
            ..Default::default()
        })
        .unwrap();
        for x in points(3, 200, 2.0) {
            let g = f.velocity_gradient(x, 0.0);
            let fd = finite_difference_gradient(&f, x, 0.0, 1e-5);
            // Gradients are O(amplitude·2π/ℓ) ≈ 10; FD error O(h²·|ω|³·|c|).
            assert!(g.abs_diff_eq(fd, 1e-6), "{x}: {g} vs {fd}");
            let div = g.x_axis.x + g.y_axis.y + g.z_axis.z;
            let div_fd = fd.x_axis.x + fd.y_axis.y + fd.z_axis.z;
            assert!(div.abs() < 1e-10, "analytic divergence {div}");
            assert!(div_fd.abs() < 1e-6, "finite-difference divergence {div_fd}");
        }
    }

    #[test]
    fn deterministic_per_seed_and_different_across_seeds() {
        let p = CurlNoiseParams {
            seed: 42,
            ..Default::default()
        };
        let (a, b) = (
            CurlNoiseFlow::new(p).unwrap(),
            CurlNoiseFlow::new(p).unwrap(),
        );
        let c = CurlNoiseFlow::new(CurlNoiseParams { seed: 43, ..p }).unwrap();
        let x = DVec3::new(0.3, -0.2, 0.9);
        // Same seed: bit-identical (an exact reproduction, not an approximation).
        assert_eq!(
            a.velocity(x, 0.0).to_array().map(f64::to_bits),
            b.velocity(x, 0.0).to_array().map(f64::to_bits)
        );
        assert!((a.velocity(x, 0.0) - c.velocity(x, 0.0)).length() > 1e-3);
    }

    #[test]
    fn mean_square_speed_is_the_amplitude_squared() {
        let f = CurlNoiseFlow::new(CurlNoiseParams {
            seed: 5,
            amplitude: 2.0,
            ..Default::default()
        })
        .unwrap();
        let pts = points(9, 20_000, 20.0);
        let ms = pts
            .iter()
            .map(|&x| f.velocity(x, 0.0).length_squared())
            .sum::<f64>()
            / pts.len() as f64;
        assert!((ms / 4.0 - 1.0).abs() < 0.1, "mean |u|² = {ms}");
    }

    #[test]
    fn rejects_bad_parameters() {
        let bad = [
            CurlNoiseParams {
                modes: 0,
                ..Default::default()
            },
            CurlNoiseParams {
                length_scale: -1.0,
                ..Default::default()
            },
            CurlNoiseParams {
                amplitude: f64::NAN,
                ..Default::default()
            },
        ];
        for p in bad {
            assert!(CurlNoiseFlow::new(p).is_err(), "{p:?}");
        }
    }
}
