//! [`CollisionParams`]: every knob of the collision tracker in one documented struct, and
//! [`AmbientFlow`], the optional velocity field that decides which T1 separations the flow
//! wants (Los Topos §5).
//!
//! Lengths are given relative to the target edge length ℓ, so one set of defaults fits
//! meshes of any scale: ℓ defaults to the mean edge length of the mesh handed to
//! [`crate::CollisionTracker::new`], and is then fixed for the tracker's life (remeshing
//! keeps edges near it, so it must not drift with the mesh).

use std::fmt;
use std::sync::Arc;

use glam::{DMat3, DVec3};
use mesh_core::remesh::{BlockParams, ConserveVolume};
use serde::{Deserialize, Serialize};

/// The velocity gradient `∂u_i/∂x_j` (row `i`, column `j`) of an ambient flow at a point.
pub type VelocityGradientFn = dyn Fn(DVec3) -> DMat3 + Send + Sync;

/// An ambient velocity field, given by its gradient, for the T1 separation strength
/// `d · (∇u d)` of Los Topos §5: how fast the flow pulls the mesh apart along a candidate
/// separation direction `d`. Without one the tracker ranks separations by the surface area
/// they remove (the mean-curvature-flow choice).
///
/// Cheap to clone (an [`Arc`]); a time-dependent flow is updated each step with
/// [`crate::CollisionTracker::set_ambient_flow`].
#[derive(Clone)]
pub struct AmbientFlow {
    gradient: Arc<VelocityGradientFn>,
}

impl AmbientFlow {
    /// A flow from its analytic velocity gradient.
    pub fn from_gradient(gradient: impl Fn(DVec3) -> DMat3 + Send + Sync + 'static) -> Self {
        Self {
            gradient: Arc::new(gradient),
        }
    }

    /// A flow from its velocity, differentiated by central differences of step `h`
    /// (error O(h²); a step near a tenth of the target edge length resolves the field at
    /// the scale separations act on). A non-positive or non-finite `h` falls back to 1e-6.
    pub fn from_velocity(
        velocity: impl Fn(DVec3) -> DVec3 + Send + Sync + 'static,
        h: f64,
    ) -> Self {
        let h = if h.is_finite() && h > 0.0 { h } else { 1e-6 };
        Self::from_gradient(move |p| {
            let column =
                |axis: DVec3| (velocity(p + h * axis) - velocity(p - h * axis)) / (2.0 * h);
            // Column j is ∂u/∂x_j, so row i, column j is ∂u_i/∂x_j.
            DMat3::from_cols(column(DVec3::X), column(DVec3::Y), column(DVec3::Z))
        })
    }

    /// The velocity gradient at `p`.
    pub fn gradient(&self, p: DVec3) -> DMat3 {
        (self.gradient)(p)
    }
}

impl fmt::Debug for AmbientFlow {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("AmbientFlow(<velocity gradient>)")
    }
}

/// How much checking the validate stage does after every step. A failed check is an error
/// and the tracker keeps the mesh from before the step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StepValidation {
    /// No check. Only for measurements: the pipeline is built to keep the mesh valid, the
    /// check is what proves it.
    Off,
    /// Connectivity, labels and geometry (`validate` layers 1–3): linear time.
    #[default]
    Structure,
    /// Layers 1–3 and the exact self-intersection test (layer 4), about four times the
    /// cost of `Structure`: the end-to-end proof of the intersection-free invariant.
    Exact,
}

/// Parameters of [`crate::CollisionTracker`]; every field has a documented default.
///
/// Serialisable (serde; every field optional on input), so run records and scenario files
/// carry them; the ambient flow is code, not data, and is skipped.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CollisionParams {
    /// Target edge length ℓ. Default `None`: the mean edge length of the initial mesh.
    pub target_edge_length: Option<f64>,
    /// Edges shorter than `min_edge_factor · ℓ` are collapsed. Default 0.5 (El Topo).
    pub min_edge_factor: f64,
    /// Edges longer than `max_edge_factor · ℓ` are split. Default 1.5 (El Topo).
    pub max_edge_factor: f64,
    /// Snap merging joins elements closer than `merge_distance_factor · ℓ`. Default 0.02,
    /// the merge distance of the 2024 paper's comparison with Los Topos (2 % of the mean
    /// edge length).
    pub merge_distance_factor: f64,
    /// Repulsion keeps elements at least `proximity_factor · ℓ` apart. Default `None`: the
    /// resolver's own default for ℓ ([`crate::resolve::ResolveOptions::for_length`]). It
    /// should stay below `merge_distance_factor`, or repulsion keeps surfaces from ever
    /// coming close enough to merge.
    pub proximity_factor: Option<f64>,
    /// Ω, the largest change of any label's volume one remeshing edit may cause. Default
    /// `None`: `0.1 · ℓ³` (El Topo §3.5.2).
    pub max_volume_change: Option<f64>,
    /// Snap merging of proximate surfaces (Los Topos §7). Default true.
    pub merge: bool,
    /// T1: vertex separation of irregular vertices (Los Topos §5). Default true.
    pub t1: bool,
    /// Pinching of singular vertices (El Topo §3.6) after T1. Default false: pinching has no
    /// strength test, so it pulls apart every fresh snap point of a merge still in
    /// progress (two surfaces that touch at one vertex), undoing merges the flow drives;
    /// vertex separation (`t1`) subsumes it where the motion pulls the sides apart.
    pub pinch: bool,
    /// T2: removal of zero-volume regions and collapsed triangles (Los Topos §6). Default
    /// true. Off, collapses that flatten a tetrahedron leave coincident triangles, which
    /// validation rejects; turn it off only together with `improve`.
    pub t2: bool,
    /// Mesh improvement: splits, collapses, flips, null-space smoothing (El Topo §3.5–3.6).
    /// Default true.
    pub improve: bool,
    /// Which remeshing edits cancel their volume change by a shift along the normal
    /// ([`ConserveVolume`], where the measurements of each kind are). Default: flips and
    /// smooth midpoint collapses, not smoothing moves. With that, one Enright period at
    /// El Topo's Ω = 0.1 ℓ³ changes the volume by 0.07 % (El Topo: 0.18 %), against
    /// 1.56 % with none, and 0.14 % with smoothing moves shifting too, so they stay off.
    /// The relax stage never shifts (its wall moves are bounded by Ω).
    pub conserve_volume: ConserveVolume,
    /// Bound on the sweeps of one improvement call. Default 2: one step's motion leaves
    /// little to fix, and what is left is fixed next step. (10 expanding spheres: 4 sweeps
    /// cost 1.7× the time of 2 for the same triangle quality; smoothing moves every vertex
    /// once per sweep, and each move is a CCD-checked edit.)
    pub improve_sweeps: usize,
    /// Improvement and wall relaxation on every core, by blocks of space, when they have
    /// at least `min_work` vertices to work on (`mesh_core::remesh::blocks`; each block
    /// gets its own collision guard, and blocks keep the guard's minimum distance from each
    /// other's edits).
    /// Default [`BlockParams::default`]; `passes = 0` keeps it serial.
    pub improve_blocks: BlockParams,
    /// Bound on time-step halvings in collision resolution before the step fails.
    /// Default 6 (1/64 of the step).
    pub max_halvings: u32,
    /// Largest displacement of any vertex in one step, in units of ℓ, before the step is
    /// refused with a clear error. Default `Some(8.0)`. The collision backend resolves
    /// *trajectories*: a shape teleported into another (a boolean, an inverted frame) has
    /// every swept box overlap every other, and the step would grind through all
    /// halvings before failing. Such inputs belong to the grid backend (or smaller steps).
    /// `None` disables the check.
    pub max_displacement_factor: Option<f64>,
    /// What the validate stage checks. Default [`StepValidation::Structure`].
    pub validation: StepValidation,
    /// The ambient flow whose divergence ranks T1 separations. Default `None`: rank by
    /// surface-area decrease. Not serialised (a closure).
    #[serde(skip)]
    pub ambient_flow: Option<AmbientFlow>,
    /// Impact zones (El Topo §3.8.2; the fail-safe after the impulse sweeps), inelastic and
    /// rigid. Default true. Off, collisions the sweeps leave are handled by step halving
    /// alone, and a step that still collides fails: the ablation of the fail-safe.
    pub impact_zones: bool,
    /// El Topo's `collision_safety` toggle. Default true. Off, the proposal is taken as it
    /// is (no repulsion, no CCD, no impact zones) and remeshing edits are not checked for
    /// collisions: faster, and the mesh may intersect itself — which the validation then
    /// reports when it runs the exact layer.
    pub collision_safety: bool,
    /// Wall-time budget of one step. Default `None`: unbounded (every loop is bounded, so a
    /// step ends, but on adversarial input it may take long). With `Some(b)` the budget is
    /// checked after each stage, so a step overshoots by at most one stage, and running
    /// out fails the step with [`mesh_core::TrackError::TimeBudgetExceeded`], the mesh
    /// unchanged.
    #[serde(with = "mesh_core::tracker::optional_seconds")]
    pub time_budget: Option<std::time::Duration>,
    /// Passes of wall relaxation per step (the `relax` stage: walls between two
    /// non-ambient labels smoothed, triple curves smoothed along themselves; each move
    /// bounded by Ω and checked by the collision guard). Default 2; 0 turns it off.
    pub relax_passes: usize,
}

impl Default for CollisionParams {
    fn default() -> Self {
        Self {
            target_edge_length: None,
            min_edge_factor: 0.5,
            max_edge_factor: 1.5,
            merge_distance_factor: 0.02,
            proximity_factor: None,
            max_volume_change: None,
            merge: true,
            t1: true,
            pinch: false,
            t2: true,
            improve: true,
            conserve_volume: ConserveVolume {
                flips: true,
                collapses: true,
                smoothing: false,
            },
            improve_sweeps: 2,
            improve_blocks: BlockParams::default(),
            max_halvings: 6,
            max_displacement_factor: Some(8.0),
            validation: StepValidation::Structure,
            ambient_flow: None,
            impact_zones: true,
            collision_safety: true,
            time_budget: None,
            relax_passes: 2,
        }
    }
}

/// Why a [`CollisionParams`] cannot be used.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ParamsError {
    /// A length or factor must be finite and positive.
    #[error("parameter `{name}` must be finite and positive, got {value}")]
    NotPositive {
        /// The field.
        name: &'static str,
        /// Its value.
        value: f64,
    },
    /// The edge-length band is empty or too narrow for splits and collapses to coexist.
    #[error(
        "edge length band [{min}, {max}]·ℓ: need 0 < min and 2·min < max (a split of the \
         longest allowed edge must not create edges to collapse)"
    )]
    EdgeBand {
        /// `min_edge_factor`.
        min: f64,
        /// `max_edge_factor`.
        max: f64,
    },
}

impl CollisionParams {
    /// Checks the fields that have no meaningful value outside a range.
    pub fn check(&self) -> Result<(), ParamsError> {
        let positive = |name: &'static str, value: f64| {
            if value.is_finite() && value > 0.0 {
                Ok(())
            } else {
                Err(ParamsError::NotPositive { name, value })
            }
        };
        if let Some(l) = self.target_edge_length {
            positive("target_edge_length", l)?;
        }
        positive("min_edge_factor", self.min_edge_factor)?;
        positive("max_edge_factor", self.max_edge_factor)?;
        positive("merge_distance_factor", self.merge_distance_factor)?;
        if let Some(p) = self.proximity_factor {
            positive("proximity_factor", p)?;
        }
        if let Some(o) = self.max_volume_change {
            positive("max_volume_change", o)?;
        }
        if let Some(d) = self.max_displacement_factor {
            positive("max_displacement_factor", d)?;
        }
        // Splitting an edge of length just above max gives two halves; they must not be
        // collapsed right away, or the two operations undo each other forever.
        if 2.0 * self.min_edge_factor >= self.max_edge_factor {
            return Err(ParamsError::EdgeBand {
                min: self.min_edge_factor,
                max: self.max_edge_factor,
            });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid_and_bad_values_are_named() {
        assert_eq!(CollisionParams::default().check(), Ok(()));
        let bad = CollisionParams {
            merge_distance_factor: f64::NAN,
            ..CollisionParams::default()
        };
        assert!(matches!(
            bad.check(),
            Err(ParamsError::NotPositive {
                name: "merge_distance_factor",
                ..
            })
        ));
        let band = CollisionParams {
            min_edge_factor: 0.8,
            ..CollisionParams::default()
        };
        assert!(matches!(band.check(), Err(ParamsError::EdgeBand { .. })));
    }

    #[test]
    fn finite_difference_gradient_matches_a_linear_field() {
        let a = DMat3::from_cols(
            DVec3::new(1.0, 2.0, 3.0),
            DVec3::new(-1.0, 0.5, 0.0),
            DVec3::new(0.0, 4.0, -2.0),
        );
        let flow = AmbientFlow::from_velocity(move |p| a * p, 1e-3);
        let g = flow.gradient(DVec3::new(0.3, -0.2, 0.9));
        for (x, y) in g.to_cols_array().iter().zip(a.to_cols_array()) {
            assert!((x - y).abs() < 1e-9, "{g} vs {a}");
        }
    }
}
