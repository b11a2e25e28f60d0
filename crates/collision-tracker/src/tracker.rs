//! [`CollisionTracker`]: the explicit, collision-safe backend behind
//! [`mesh_core::SurfaceTracker`] (Los Topos Algorithm 1 on El Topo; the stages are in
//! `step.rs`, the topological separation stage in `t1t2.rs`).
//!
//! The tracker's invariant: between steps its mesh passes `validate()` and is exactly
//! intersection-free. [`CollisionTracker::new`] checks both on the input (the whole method
//! rests on starting from an intersection-free state); each step preserves them, and a step
//! that cannot returns an error and keeps the mesh it started from.

use glam::DVec3;
use mesh_core::remesh::improve::mean_edge_length;
use mesh_core::remesh::{BlockParams, ImproveParams, Resmooth, SeparationParams, ThinRegionParams};
use mesh_core::validate::{ValidateOptions, validate};
use mesh_core::{LabeledMesh, RegionCensus, StepReport, SurfaceTracker, TrackError, VertexId};

use crate::merge::MergeOptions;
use crate::params::{AmbientFlow, CollisionParams};
use crate::relax::RelaxOptions;
use crate::resolve::ResolveOptions;
use crate::step::{StepConfig, advance_mesh};
use crate::t1t2::T1T2Options;

/// The collision-safe multi-material tracker (Da et al. 2014 on Brochu & Bridson 2009).
///
/// ```no_run
/// use collision_tracker::{CollisionParams, CollisionTracker};
/// use mesh_core::{DVec3, Label, SurfaceTracker, generators::icosphere};
///
/// let mesh = icosphere(3, DVec3::ZERO, 1.0, [Label::OUTSIDE, Label::new(1)]).unwrap();
/// let mut tracker: Box<dyn SurfaceTracker> =
///     Box::new(CollisionTracker::new(mesh, CollisionParams::default()).unwrap());
/// let proposed: Vec<DVec3> = tracker.mesh().positions().iter().map(|p| *p * 1.01).collect();
/// let report = tracker.advance(&proposed).unwrap();
/// println!("{} triangles, {:.3} s", report.triangles, report.total_seconds());
/// ```
pub struct CollisionTracker {
    mesh: LabeledMesh,
    /// Connected components and bounded shells of `mesh` (at the step's region
    /// thickness), carried between steps.
    count: RegionCensus,
    /// Vertices the last step snapped: the next step's merge zips outward from them and
    /// its T1 stage does not separate them.
    recent_snaps: Vec<VertexId>,
    params: CollisionParams,
    /// The target edge length ℓ fixed at construction.
    target_edge_length: f64,
    config: StepConfig,
}

impl CollisionTracker {
    /// A tracker around `mesh`. The mesh must pass `validate()` including the exact
    /// self-intersection test, and `params` must pass [`CollisionParams::check`]; otherwise
    /// [`TrackError::InvalidInput`] names the first problem.
    pub fn new(mesh: LabeledMesh, params: CollisionParams) -> Result<Self, TrackError> {
        params
            .check()
            .map_err(|e| TrackError::InvalidInput(e.to_string()))?;
        if mesh.num_triangles() == 0 {
            return Err(TrackError::InvalidInput(
                "the mesh has no triangles (nothing to track)".into(),
            ));
        }
        let report = validate(&mesh, &ValidateOptions::with_intersections());
        if !report.is_valid() {
            return Err(TrackError::InvalidInput(format!(
                "the collision tracker needs a valid, intersection-free mesh: {report}"
            )));
        }
        let target = match params.target_edge_length {
            Some(l) => l,
            None => mean_edge_length(&mesh),
        };
        if !(target.is_finite() && target > 0.0) {
            return Err(TrackError::InvalidInput(format!(
                "target edge length {target} (mean edge length of the mesh) is not positive"
            )));
        }
        check_scale(&mesh, target)?;
        let config = configure(&params, target);
        let count = RegionCensus::thicker_than(&mesh, config.region_thickness);
        Ok(Self {
            mesh,
            count,
            recent_snaps: Vec::new(),
            params,
            target_edge_length: target,
            config,
        })
    }

    /// The parameters in use.
    pub fn params(&self) -> &CollisionParams {
        &self.params
    }

    /// The target edge length ℓ all lengths are relative to (fixed at construction).
    pub fn target_edge_length(&self) -> f64 {
        self.target_edge_length
    }

    /// Sets (or clears) the ambient flow that ranks T1 separations by its divergence along
    /// the separation direction; call it each step for a time-dependent flow. Without a
    /// flow, separations are ranked by the surface area they remove.
    pub fn set_ambient_flow(&mut self, flow: Option<AmbientFlow>) {
        self.params.ambient_flow = flow.clone();
        self.config.t1t2.ambient_flow = flow;
    }
}

/// Derives each stage's options from the parameters and ℓ, once.
fn configure(params: &CollisionParams, l: f64) -> StepConfig {
    let mut resolve = ResolveOptions::for_length(l);
    resolve.max_halvings = params.max_halvings;
    if !params.impact_zones {
        // Ablation: no impact zones, inelastic or rigid; halving is the only fallback.
        resolve.max_zone_iterations = 0;
        resolve.rigid_fallback = false;
    }
    if let Some(p) = params.proximity_factor {
        resolve.proximity = p * l;
    }
    let merge = params.merge.then(|| {
        let mut m = MergeOptions::for_length(l);
        m.merge_distance = params.merge_distance_factor * l;
        // Merge what the flow brings together (the step passes each vertex's proposed
        // displacement as the merge's attributes): at least 1 % of the merge distance per
        // step, far above the rounding of a rigid motion.
        m.min_approach = Some(0.01 * m.merge_distance);
        m.thin_regions = Some(ThinRegionParams {
            max_volume: params.max_volume_change.unwrap_or(0.1 * l * l * l),
            max_mean_thickness: REGION_THICKNESS_FACTOR * l,
        });
        m
    });
    if let Some(m) = &merge {
        // Colliding surfaces come to rest at half the merge distance, where the merge of
        // the same step finds them (El Topo's zero-velocity impulse would leave them
        // wherever they started, up to one step's approach apart, out of merge range).
        resolve.rest_distance = (0.5 * m.merge_distance).max(resolve.proximity);
    }
    let defaults = ImproveParams::default();
    let improve = ImproveParams {
        target_edge_length: Some(l),
        min_edge_factor: params.min_edge_factor,
        max_edge_factor: params.max_edge_factor,
        // Collapses must not create edges the next split would cut again.
        collapse_max_edge_factor: defaults
            .collapse_max_edge_factor
            .min(0.9 * params.max_edge_factor),
        max_volume_change: params.max_volume_change,
        max_sweeps: params.improve_sweeps,
        split: params.improve,
        collapse: params.improve,
        flip: params.improve,
        smooth: params.improve,
        remove_degenerate: params.t2,
        // Los Topos orders vertex separation after improvement (§5, "Ordering of
        // Operations"): the t1t2 stage does it, once, over the whole mesh.
        separate: false,
        pinch: false,
        conserve_volume: params.conserve_volume,
        // Measured: the walls between pressed surfaces keep better triangles when a
        // change is smoothed one ring further (see `Resmooth`).
        resmooth: Resmooth::Neighbourhood,
        ..defaults
    };
    let t1t2 = T1T2Options {
        t1: params.t1,
        pinch: params.pinch,
        t2: params.t2,
        min_edge_length: params.min_edge_factor * l,
        max_volume_change: params.max_volume_change.unwrap_or(0.1 * l * l * l),
        separation: SeparationParams::default(),
        ambient_flow: params.ambient_flow.clone(),
    };
    // Far below the repulsion distance (10⁻³ ℓ), far above rounding.
    let min_separation = 1e-6 * l;
    let improve_blocks = BlockParams {
        margin: min_separation,
        ..params.improve_blocks.clone()
    };
    StepConfig {
        resolve,
        merge,
        improve,
        improve_blocks: improve_blocks.clone(),
        t1t2,
        validation: params.validation,
        max_displacement: params.max_displacement_factor.map(|f| f * l),
        time_budget: params.time_budget,
        collision_safety: params.collision_safety,
        min_separation,
        region_thickness: REGION_THICKNESS_FACTOR * l,
        relax: RelaxOptions {
            passes: if params.improve {
                params.relax_passes
            } else {
                0
            },
            block_side: improve_blocks.block_edges * l,
            step: 0.5,
            max_volume_change: params.max_volume_change.unwrap_or(0.1 * l * l * l),
            min_move: 1e-3 * l,
        },
    }
}

impl SurfaceTracker for CollisionTracker {
    fn name(&self) -> &str {
        "collision"
    }

    fn mesh(&self) -> &LabeledMesh {
        &self.mesh
    }

    fn advance(&mut self, proposed: &[DVec3]) -> Result<StepReport, TrackError> {
        let step = advance_mesh(
            &self.mesh,
            &self.count,
            &self.recent_snaps,
            proposed,
            &self.config,
        )?;
        self.mesh = step.mesh;
        self.count = step.census;
        self.recent_snaps = step.snapped;
        Ok(step.report)
    }
}

/// Regions thinner than this × ℓ (volume / area) are not counted as regions by the step's
/// events and are closed by the merge when they hold at most Ω: slivers between snapped
/// sheets are a few merge distances (0.02 ℓ) thick; a ball this thin (radius 0.3 ℓ) is
/// below what edges of length ℓ resolve.
const REGION_THICKNESS_FACTOR: f64 = 0.1;

/// Smallest ratio of the target edge length to the largest coordinate magnitude. Below
/// it the separations the step keeps (10⁻⁶ ℓ, see `min_separation`) come within a few
/// hundred ulps of the coordinates, and continuous collision detection, which counts
/// near misses within its rounding bound as contacts, would find contacts everywhere.
const MIN_LENGTH_TO_COORDINATE: f64 = 1e-7;

/// Refuses a mesh whose edges are too short for its distance from the origin (a unit
/// mesh translated to 10¹⁵, say), naming both numbers, instead of failing every step.
fn check_scale(mesh: &LabeledMesh, l: f64) -> Result<(), TrackError> {
    let extent = mesh
        .vertices()
        .map(|v| mesh.position(v).abs().max_element())
        .fold(0.0, f64::max);
    if l < MIN_LENGTH_TO_COORDINATE * extent {
        return Err(TrackError::InvalidInput(format!(
            "edge length {l:e} is too short for coordinates as large as {extent:e}: the \
             collision backend needs edges of at least {MIN_LENGTH_TO_COORDINATE:e} × the \
             largest coordinate (move the mesh towards the origin, or scale it up)"
        )));
    }
    Ok(())
}
