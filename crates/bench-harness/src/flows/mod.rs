//! Flows: where every vertex should go next.
//!
//! A tracker never decides how the surface moves; the caller proposes a position for
//! every vertex slot and the tracker follows as far as it safely can
//! ([`mesh_core::SurfaceTracker::advance`]). A [`Flow`] is such a caller: from the
//! current mesh, the time `t` and a step `dt` it returns one position per vertex slot
//! (indexed by [`mesh_core::VertexId`], dead slots copied unchanged, so the vector can be
//! handed to `advance` as it is).
//!
//! Two kinds of flow exist, and the split matters to the collision backend:
//!
//! - **ambient velocity fields** — [`EnrightFlow`], [`CurlNoiseFlow`], [`RigidRotation`]
//!   — are defined everywhere in space, not only on the surface. They implement
//!   [`VelocityField`] (velocity and its spatial gradient, the latter giving the T1
//!   separation strength) and integrate vertex trajectories with an [`Integrator`]
//!   (RK4 by default, as the Los Topos and El Topo tests do);
//! - **geometric flows** — [`NormalFlow`] (vertex normals or face offsetting, per
//!   material-pair speeds, [`cyclic_normal_flow`]) and [`MeanCurvatureFlow`] — depend on
//!   the surface itself and take one forward Euler step (mean curvature flow also has a
//!   backward Euler scheme, [`McfScheme`], on the shared [`CotanLaplacian`]);
//!   [`VolumePreservingTension`] adds walls and one volume constraint per bubble.
//!
//! [`Schedule`] chains flows in time (the double bubble grows then shrinks; the
//! curl-noise scene alternates normal flow and noise); [`OneShot`] and
//! [`TargetPositions`] deform everything in the first step (the inversion and copies tests).
//!
//! The submodules document each flow's conventions in full (sign of speeds, behaviour at
//! non-manifold vertices, stability); the types are re-exported here.
//!
//! Every per-vertex computation runs on rayon, reading the mesh only; nothing allocates
//! per vertex.

pub mod advect;
pub mod curl_noise;
pub mod cyclic;
pub mod enright;
pub mod error;
pub mod laplacian;
mod lsq;
pub mod mean_curvature;
pub mod normal;
pub mod one_shot;
pub mod rigid;
pub mod schedule;
pub mod speeds;
pub mod surface_tension;
#[cfg(test)]
mod test_meshes;

use glam::{DMat3, DVec3};
use mesh_core::LabeledMesh;

pub use advect::{AdvectedFlow, Integrator, advect, finite_difference_gradient};
pub use curl_noise::{CurlNoiseFlow, CurlNoiseParams};
pub use cyclic::cyclic_normal_flow;
pub use enright::EnrightFlow;
pub use error::FlowError;
pub use laplacian::CotanLaplacian;
pub use mean_curvature::{McfScheme, MeanCurvatureFlow};
pub use normal::{JunctionRule, NormalFlow, NormalScheme};
pub use one_shot::{OneShot, TargetPositions};
pub use rigid::RigidRotation;
pub use schedule::Schedule;
pub use speeds::InterfaceSpeeds;
pub use surface_tension::VolumePreservingTension;

/// Something that proposes the next position of every vertex.
///
/// Object safe, so scenes hand out `Box<dyn Flow>` and the CLI picks one by name.
pub trait Flow: Send + Sync {
    /// Short stable name, for logs and run records.
    fn name(&self) -> &str;

    /// The proposed position of every vertex slot after a step `dt` taken from time `t`:
    /// `result.len() == mesh.vertex_capacity()`, dead slots copied unchanged.
    fn propose(&self, mesh: &LabeledMesh, t: f64, dt: f64) -> Vec<DVec3>;

    /// The ambient velocity field driving the flow at time `t`, if there is one (the
    /// collision backend uses its gradient for the T1 separation strength). Geometric
    /// flows have none.
    fn velocity_field(&self, _t: f64) -> Option<&dyn VelocityField> {
        None
    }

    /// The largest step forward Euler can take on this mesh without blowing up, for
    /// flows with such a limit (mean curvature flow); `None` when any step is stable.
    fn max_stable_dt(&self, _mesh: &LabeledMesh) -> Option<f64> {
        None
    }
}

/// A velocity field defined everywhere in space, possibly time dependent.
pub trait VelocityField: Send + Sync {
    /// Velocity `u(x, t)`.
    fn velocity(&self, x: DVec3, t: f64) -> DVec3;

    /// Spatial gradient `∇u(x, t)` as the Jacobian `J` with `J·dx ≈ u(x + dx) − u(x)`:
    /// column `j` is `∂u/∂x_j` (glam matrices are column major, so `J * dx` works).
    fn velocity_gradient(&self, x: DVec3, t: f64) -> DMat3;
}
