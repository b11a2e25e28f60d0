//! Advecting vertices through a [`VelocityField`]: forward Euler or classical RK4.

use glam::{DMat3, DVec3};
use mesh_core::{LabeledMesh, VertexId};
use rayon::prelude::*;

use super::{Flow, VelocityField};

/// Vertices per rayon task: a field evaluation costs tens to hundreds of flops, so a few
/// hundred vertices amortise the task overhead.
const MIN_VERTICES_PER_TASK: usize = 256;

/// Time integration of a vertex trajectory `dx/dt = u(x, t)`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Integrator {
    /// `x + dt·u(x, t)`: first order, one field evaluation.
    ForwardEuler,
    /// Classical fourth-order Runge–Kutta: four evaluations, error `O(dt⁴)`; what the Los
    /// Topos and El Topo papers use for the Zalesak, Enright and curl-noise tests.
    #[default]
    Rk4,
}

impl Integrator {
    /// One step of `dx/dt = u(x, t)` from `(x, t)` with step `dt`.
    #[inline]
    pub fn step(self, field: &(impl VelocityField + ?Sized), x: DVec3, t: f64, dt: f64) -> DVec3 {
        match self {
            Integrator::ForwardEuler => x + dt * field.velocity(x, t),
            Integrator::Rk4 => {
                let h = 0.5 * dt;
                let k1 = field.velocity(x, t);
                let k2 = field.velocity(x + h * k1, t + h);
                let k3 = field.velocity(x + h * k2, t + h);
                let k4 = field.velocity(x + dt * k3, t + dt);
                x + (dt / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
            }
        }
    }
}

/// Moves every live vertex along the field for one step, in parallel; dead slots keep
/// their (stale) positions so the result is indexed like the mesh's vertex slots.
pub fn advect(
    mesh: &LabeledMesh,
    field: &(impl VelocityField + ?Sized),
    integrator: Integrator,
    t: f64,
    dt: f64,
) -> Vec<DVec3> {
    let positions = mesh.positions();
    (0..positions.len())
        .into_par_iter()
        .with_min_len(MIN_VERTICES_PER_TASK)
        .map(|i| {
            let x = positions[i];
            if mesh.is_vertex_alive(VertexId::new(i as u32)) {
                integrator.step(field, x, t, dt)
            } else {
                x
            }
        })
        .collect()
}

/// An ambient [`VelocityField`] whose flow is plain advection of every vertex with one
/// [`Integrator`]. Implementing it is all such a field needs to be a [`Flow`]: the
/// blanket impl below proposes [`advect`] positions and hands the field itself to the
/// collision backend, so the ambient flows share that code instead of repeating it.
pub trait AdvectedFlow: VelocityField {
    /// Short stable name, returned by [`Flow::name`].
    const NAME: &'static str;

    /// The integrator of vertex trajectories.
    fn integrator(&self) -> Integrator;
}

impl<F: AdvectedFlow> Flow for F {
    fn name(&self) -> &str {
        F::NAME
    }

    fn propose(&self, mesh: &LabeledMesh, t: f64, dt: f64) -> Vec<DVec3> {
        advect(mesh, self, self.integrator(), t, dt)
    }

    fn velocity_field(&self, _t: f64) -> Option<&dyn VelocityField> {
        Some(self)
    }
}

/// One forward Euler step `x + dt·u` of every vertex slot, `velocities` indexed like the
/// slots (the geometric flows give dead slots zero velocity, so they stay put).
pub(crate) fn euler_step(mesh: &LabeledMesh, velocities: &[DVec3], dt: f64) -> Vec<DVec3> {
    mesh.positions()
        .iter()
        .zip(velocities)
        .map(|(&x, &u)| x + dt * u)
        .collect()
}

/// Velocity gradient by central differences with step `h` (error `O(h²)`): a reference
/// for tests and a fallback for fields without an analytic gradient.
pub fn finite_difference_gradient(
    field: &(impl VelocityField + ?Sized),
    x: DVec3,
    t: f64,
    h: f64,
) -> DMat3 {
    let column =
        |e: DVec3| (field.velocity(x + h * e, t) - field.velocity(x - h * e, t)) / (2.0 * h);
    DMat3::from_cols(column(DVec3::X), column(DVec3::Y), column(DVec3::Z))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flows::test_meshes::icosphere;
    use mesh_core::Label;

    /// `u(x) = x`: the exact flow is `x·eᵗ`, and both integrators have closed forms.
    struct Expanding;

    impl VelocityField for Expanding {
        fn velocity(&self, x: DVec3, _t: f64) -> DVec3 {
            x
        }
        fn velocity_gradient(&self, _x: DVec3, _t: f64) -> DMat3 {
            DMat3::IDENTITY
        }
    }

    #[test]
    fn integrators_match_their_taylor_polynomials() {
        let x = DVec3::new(1.0, -2.0, 0.5);
        let dt = 0.1;
        let euler = Integrator::ForwardEuler.step(&Expanding, x, 0.0, dt);
        assert!((euler - x * 1.1).length() < 1e-15);
        // RK4 on a linear ODE reproduces the degree-4 Taylor polynomial of e^dt.
        let factor = 1.0 + dt + dt * dt / 2.0 + dt.powi(3) / 6.0 + dt.powi(4) / 24.0;
        let rk4 = Integrator::Rk4.step(&Expanding, x, 0.0, dt);
        assert!((rk4 - x * factor).length() < 1e-15);
        // Local error dt⁵/120·|x| ≈ 2e-7; Euler's ≈ dt²/2·|x| ≈ 1e-2.
        assert!((rk4 - x * dt.exp()).length() < 1e-6);
        assert!((euler - x * dt.exp()).length() > 5e-3);
    }

    #[test]
    fn advect_moves_live_vertices_and_copies_dead_slots() {
        let mut mesh = icosphere(1, 1.0, [Label::new(0), Label::new(1)]);
        let dead = mesh.add_vertex(DVec3::splat(7.0)).unwrap();
        mesh.remove_vertex(dead).unwrap();
        let out = advect(&mesh, &Expanding, Integrator::ForwardEuler, 0.0, 0.5);
        assert_eq!(out.len(), mesh.vertex_capacity());
        assert_eq!(out[dead.idx()], DVec3::splat(7.0));
        for v in mesh.vertices() {
            assert!((out[v.idx()] - 1.5 * mesh.position(v)).length() < 1e-15);
        }
    }

    #[test]
    fn finite_difference_gradient_of_linear_field_is_exact() {
        let g = finite_difference_gradient(&Expanding, DVec3::new(0.3, 0.1, -4.0), 0.0, 1e-3);
        assert!(g.abs_diff_eq(DMat3::IDENTITY, 1e-12));
    }
}
