//! The `metaballs` scene: an animated implicit surface followed by Newton projection
//! (Nesme & Bouthors 2006, Fig. 1), with the tracker under test doing the blending and
//! splitting. See the `implicit-surface` crate for the algorithm.
//!
//! - default: two skeleton segments crossing each other (the paper's Fig. 1): apart,
//!   blended into one surface while they overlap (around t = ½), split after;
//! - `--count N` (N ≥ 2): a swarm of N blobs on seeded keyframed paths (`--seed`),
//!   several blends and splits at once (use more `--steps`, e.g. 120, for N ≥ 8).
//!
//! `--resolution R`: R edges per unit length (default 8, ℓ = 0.125); the elements have
//! kernel radius 1 and a lone point is a sphere of radius ≈ 0.45. The animation spans
//! t ∈ [0, 1] over the scene's default steps (`dt = 1/40`); later times hold the last
//! keyframe.
//!
//! The flow ([`MetaballFlow`]) proposes, from the tracker's current mesh, the positions
//! projected onto `F(·, t + dt) = 0` with quasi-critical points pushed across their gap
//! or neck ([`implicit_surface::propose`]); it fits the harness's `Flow` abstraction
//! because it needs nothing but the mesh and the time. Frames are the tracker's meshes,
//! i.e. before the final re-projection the crate's own `Follower` adds.

use implicit_surface::{FollowParams, ImplicitField, SkeletonField, initial_mesh, propose, scenes};
use mesh_core::LabeledMesh;

use crate::flows::error::invalid;
use crate::flows::{Flow, FlowError};

use super::{SceneError, SceneOptions};

/// Default steps over t ∈ [0, 1].
pub const STEPS: usize = 40;

/// Proposes the projection of the current mesh onto the animated field.
pub struct MetaballFlow {
    field: SkeletonField,
    params: FollowParams,
}

impl Flow for MetaballFlow {
    fn name(&self) -> &str {
        "implicit-follow"
    }

    fn propose(&self, mesh: &LabeledMesh, t: f64, dt: f64) -> Vec<glam::DVec3> {
        match propose(mesh, &self.field, t + dt, &self.params) {
            Ok(p) => p.positions,
            Err(e) => {
                // Parameters were checked when the scene was built; a non-finite field
                // value is the only way here. Stand still rather than propose NaN.
                tracing::warn!("metaballs: projection failed, proposing no motion: {e}");
                mesh.positions().to_vec()
            }
        }
    }
}

fn scene_error(e: implicit_surface::ImplicitError) -> SceneError {
    SceneError::Flow(FlowError::InvalidParameter {
        flow: "metaballs",
        parameter: "animation",
        value: e.to_string(),
        expected: "a valid animated implicit field",
    })
}

/// The initial mesh, the flow and the time step of the scene.
pub fn build(o: &SceneOptions) -> Result<(LabeledMesh, MetaballFlow, f64), SceneError> {
    let r = o.resolution.unwrap_or(8);
    if !(2..=200).contains(&r) {
        return Err(invalid(
            "metaballs",
            "resolution",
            r,
            "2..=200 edges per unit length",
        )
        .into());
    }
    let h = 1.0 / f64::from(r);
    let anim = match o.count {
        None | Some(1) => scenes::crossing(1.1, h, STEPS),
        Some(n) => scenes::swarm(n, o.seed, h, STEPS),
    }
    .map_err(scene_error)?;
    let bounds = anim
        .field
        .bounds(anim.t0)
        .ok_or_else(|| invalid("metaballs", "field", "unbounded", "a bounded field"))?;
    let mesh = initial_mesh(&anim.field, anim.t0, bounds, h).map_err(scene_error)?;
    let params = FollowParams::new(h);
    params.check().map_err(scene_error)?;
    let dt = (anim.t1 - anim.t0) / STEPS as f64;
    Ok((
        mesh,
        MetaballFlow {
            field: anim.field,
            params,
        },
        dt,
    ))
}
