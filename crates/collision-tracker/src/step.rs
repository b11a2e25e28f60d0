//! One time step of the collision tracker: Los Topos Algorithm 1, one function per stage.
//!
//! ```text
//! advance(proposed):
//!     check_proposal                                  lengths, finiteness
//!     resolve      (§4.2; El Topo §3.8)               collision-free motion, halving if needed   ✓
//!     merge        (§7.1)                             snap proximate surfaces together           ✓
//!     improve      (§4.3; El Topo §3.5–3.6)           split, collapse, flip, smooth, T2           ✓
//!     relax        (§8.2)                             walls and triple curves smoothed           ✓
//!     t1t2         (§5, §6; El Topo §3.6)             T2, T1 by separation strength, pinching    ✓
//!     validate                                        layers 1–3 (or 1–4) of `validate`
//! ```
//!
//! After every ✓ the working mesh is intersection-free: resolution ends in a state CCD
//! has certified, and every later edit goes through one [`CollisionGuard`] that vetoes any
//! edit whose pseudo-motion or end state would intersect. All stages work on a clone of
//! the tracker's mesh, which replaces it only when the whole step succeeded.
//!
//! Topology events: T1 and T2 come from the operations' own reports; merges and splits are
//! read off [`RegionCensus`] (surface components and bounded region shells per label, the
//! definition the grid backend uses too), compared between the start and the end of the
//! step, so that a merge is counted when two regions first touch and a split when one
//! parts — not once per snapped pair. Regions thinner than
//! [`StepConfig::region_thickness`] are not counted: snapping traps slivers of the
//! surrounding material between the sheets it joins, and the next snaps close them.
//!
//! That threshold is also why the two backends' split counts can differ on crowded scenes,
//! and neither is wrong. On `spheres --spheres 10 --seed 1` the grid backend reports 8
//! splits and this one 0. Each of the grid's splits is a new closed shell of the outside,
//! 6–42 triangles: a pocket enclosed between four or more spheres. Sampling the exact
//! union of the growing balls (spacing 0.3 ℓ; 0.18 ℓ at two of the steps) finds 1–5 such
//! pockets at each of those steps, none wider than about 0.4 ℓ: below the resolution of
//! both trackers. The grid backend's cells catch some of them as regions; here they are
//! thinner than the threshold and not counted.
//!
//! Merging and separation agree: vertices snapped in this step or the previous one (the
//! tracker carries them over) are never separated by T1, and the merge zips outward from
//! them (see [`crate::merge::snap_merge_from`]).

use std::time::Instant;

use glam::DVec3;
use mesh_core::remesh::{
    BlockParams, ImproveParams, ImproveRegion, ImproveReport, VertexAttributes, improve_in_blocks,
};
use mesh_core::validate::{ValidateOptions, validate};
use mesh_core::{LabeledMesh, RegionCensus, StepReport, TrackError, VertexId, check_proposal};
use rayon::prelude::*;

use crate::guard::{CollisionGuard, CollisionGuardOptions};
use crate::merge::{MergeOptions, snap_merge_uncounted};
use crate::params::StepValidation;
use crate::relax::{RelaxOptions, relax_walls};
use crate::resolve::{ResolveOptions, resolve_step};
use crate::t1t2::{T1T2Options, add_counts, separate_regions};

/// Everything a step needs besides the mesh, derived once from [`crate::CollisionParams`]
/// so that no stage re-derives lengths.
#[derive(Clone, Debug)]
pub(crate) struct StepConfig {
    pub resolve: ResolveOptions,
    pub merge: Option<MergeOptions>,
    pub improve: ImproveParams,
    /// Improvement and wall relaxation by blocks; its margin is `min_separation`.
    pub improve_blocks: BlockParams,
    pub t1t2: T1T2Options,
    pub validation: StepValidation,
    /// Largest displacement allowed in one step (absolute), if bounded.
    pub max_displacement: Option<f64>,
    /// Wall-time budget of one step, checked after each stage.
    pub time_budget: Option<std::time::Duration>,
    /// Remeshing and T1/T2 edits may not leave non-adjacent elements closer than this
    /// (the guard's minimum distance; see [`CollisionGuard::set_min_distance`]).
    pub min_separation: f64,
    /// El Topo's `collision_safety`: off, the proposal is taken without collision
    /// resolution and remeshing edits are not checked (the ablation; the mesh may then
    /// intersect itself).
    pub collision_safety: bool,
    /// Regions whose mean thickness (volume / area) is below this are not counted as
    /// regions in the step's merge and split events ([`RegionCensus::thicker_than`]).
    pub region_thickness: f64,
    /// Wall relaxation after improvement.
    pub relax: RelaxOptions,
}

/// What a successful step hands back to the tracker.
pub(crate) struct Advanced {
    pub mesh: LabeledMesh,
    /// The census of `mesh`, for the next step's event count.
    pub census: RegionCensus,
    pub report: StepReport,
    /// Vertices snapped by this step's merge, for the next step (see
    /// [`crate::merge::snap_merge_from`]).
    pub snapped: Vec<VertexId>,
}

/// Runs Algorithm 1 on a clone of `mesh` and returns the new mesh with its report, or the
/// first error (the caller keeps `mesh`). `before` is the census of `mesh` at
/// `config.region_thickness`, and `recent_snaps` the vertices the previous step snapped,
/// both carried from the previous step.
pub(crate) fn advance_mesh(
    mesh: &LabeledMesh,
    before: &RegionCensus,
    recent_snaps: &[VertexId],
    proposed: &[DVec3],
    config: &StepConfig,
) -> Result<Advanced, TrackError> {
    check_proposal(mesh, proposed)?;
    if let Some(limit) = config.max_displacement {
        check_displacement(mesh, proposed, limit)?;
    }
    let started = Instant::now();
    let budget = |stage: &'static str| within_budget(started, config.time_budget, stage);
    let mut report = StepReport::default();
    let mut work = mesh.clone();

    let mut motion = VertexAttributes::zeros(mesh, 3);
    report.substeps = if config.collision_safety {
        resolve(&mut work, proposed, config, &mut motion, &mut report)?
    } else {
        // Ablation (El Topo's collision_safety off): move straight to the proposal.
        let clock = Instant::now();
        let live: Vec<VertexId> = work.vertices().collect();
        for &v in &live {
            let wanted = proposed[v.idx()] - work.position(v);
            motion.get_mut(v).copy_from_slice(&wanted.to_array());
            work.set_position(v, proposed[v.idx()]);
        }
        relink_non_manifold_edges(&mut work);
        report.time_stage("resolve", clock.elapsed());
        1
    };
    budget("resolve")?;

    let mut guard = CollisionGuard::with_options(CollisionGuardOptions {
        unchecked: !config.collision_safety,
        ..CollisionGuardOptions::default()
    });

    // Snapped in the previous step and (after the merge) in this one.
    let mut snapped: Vec<VertexId> = recent_snaps.to_vec();
    if let Some(options) = &config.merge {
        let clock = Instant::now();
        snap_merge_uncounted(&mut work, &mut motion, options, &mut guard, &mut snapped).map_err(
            |e| TrackError::StageFailed {
                stage: "merge",
                reason: e.to_string(),
            },
        )?;
        report.time_stage("merge", clock.elapsed());
        budget("merge")?;
    }

    // Merging brought elements together on purpose; from here on nothing may leave two
    // of them a rounding error apart, where the next step's CCD would start in contact.
    guard.set_min_distance(Some(config.min_separation));

    if config.improve.split || config.improve.collapse || config.improve.flip {
        let clock = Instant::now();
        // Each block (and the serial pass after them) gets a guard of its own, with the
        // minimum distance; the step's guard then no longer knows the mesh.
        let improved = improve_in_blocks(
            &mut work,
            &config.improve,
            ImproveRegion::Whole,
            None,
            &mut motion,
            &config.improve_blocks,
            &guard.maker(),
        );
        guard.reset();
        count_improvement(&improved, &mut report);
        report.time_stage("improve", clock.elapsed());
        budget("improve")?;
    }

    if config.relax.passes > 0 {
        let clock = Instant::now();
        let relaxed = relax_walls(
            &mut work,
            &mut motion,
            &mut guard,
            &config.relax,
            &config.improve_blocks,
        );
        report.events.remeshing_edits += relaxed.moved as u64;
        report.time_stage("relax", clock.elapsed());
        budget("relax")?;
    }

    let clock = Instant::now();
    let counts = separate_regions(&mut work, &mut motion, &mut guard, &config.t1t2, &snapped);
    add_counts(&mut report.events, &counts);

    report.time_stage("t1t2", clock.elapsed());
    budget("t1t2")?;

    let clock = Instant::now();
    // The whole step's change: a contact made and a region parted (a region that
    // vanished by T2 is neither; RegionCensus discounts it).
    let after = RegionCensus::thicker_than(&work, config.region_thickness);
    let (merges, splits) = after.events_since(before);
    report.events.merges += merges;
    report.events.splits += splits;
    check(&work, config.validation)?;
    report.time_stage("validate", clock.elapsed());

    report.vertices = work.num_vertices();
    report.triangles = work.num_triangles();
    let carried = recent_snaps.len().min(snapped.len());
    snapped.drain(..carried);
    snapped.retain(|&v| work.is_vertex_alive(v));
    Ok(Advanced {
        mesh: work,
        census: after,
        report,
        snapped,
    })
}

/// Fails the step once `budget` has run out; `stage` is the stage just finished.
fn within_budget(
    started: Instant,
    budget: Option<std::time::Duration>,
    stage: &'static str,
) -> Result<(), TrackError> {
    match budget {
        Some(budget) if started.elapsed() >= budget => {
            Err(TrackError::TimeBudgetExceeded { stage, budget })
        }
        _ => Ok(()),
    }
}

/// Stage "resolve" (§4.2): the proposal made collision-free (repulsion, CCD impulses,
/// impact zones, time-step halving). The resolver's own split of its time is reported as
/// the stages `proximity`, `ccd` and `impact_zones`, the rest as `resolve`, so that the
/// stage times still sum to the step's time. Each vertex's *proposed* displacement goes to
/// `motion`: it is what the flow wants, which the T1 stage's strength gate and
/// collapse-consistency test read. (The resolved displacement would not do: collision
/// response stops approaching surfaces and repulsion pushes them apart, so two surfaces
/// the flow presses together would read as pulling apart, and a fresh merge would be
/// separated again.) Returns the sub-steps taken.
fn resolve(
    work: &mut LabeledMesh,
    proposed: &[DVec3],
    config: &StepConfig,
    motion: &mut VertexAttributes,
    report: &mut StepReport,
) -> Result<u32, TrackError> {
    let clock = Instant::now();
    let resolved =
        resolve_step(work, proposed, &config.resolve).map_err(|e| TrackError::StageFailed {
            stage: "resolve",
            reason: e.to_string(),
        })?;
    let r = &resolved.report;
    let moved: Vec<VertexId> = work.vertices().collect();
    for &v in &moved {
        let wanted = proposed[v.idx()] - work.position(v);
        motion.get_mut(v).copy_from_slice(&wanted.to_array());
        work.set_position(v, resolved.positions[v.idx()]);
    }
    relink_non_manifold_edges(work);
    let total = clock.elapsed().as_secs_f64();
    let parts = [
        ("proximity", r.seconds_proximity),
        ("ccd", r.seconds_ccd),
        ("impact_zones", r.seconds_zones),
    ];
    let inner: f64 = parts.iter().map(|p| p.1).sum();
    for (stage, seconds) in parts {
        report
            .stages
            .push(mesh_core::StageTiming { stage, seconds });
    }
    report.stages.push(mesh_core::StageTiming {
        stage: "resolve",
        seconds: (total - inner).max(0.0),
    });
    Ok(r.substeps.max(1))
}

/// The radial order of the triangles around a non-manifold edge depends on positions, so
/// it is recomputed after the motion. Collision-free motion cannot reorder triangles that
/// do not share the edge, but triangles that do share it are never tested against each
/// other, so this is the one connectivity fact the motion can change.
fn relink_non_manifold_edges(mesh: &mut LabeledMesh) {
    let view: &LabeledMesh = mesh;
    let mut edges: Vec<[VertexId; 2]> = view
        .triangles()
        .collect::<Vec<_>>()
        .par_iter()
        .flat_map_iter(|&t| {
            let tri = view.tri(t);
            (0..3).filter_map(move |k| {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                (a < b && view.edge_triangles(a, b).nth(2).is_some()).then_some([a, b])
            })
        })
        .collect();
    edges.par_sort_unstable();
    edges.dedup();
    for [a, b] in edges {
        mesh.relink_edge(a, b);
    }
}

/// Adds the improvement's counts to the step's events: T2 from its degenerate removal,
/// every committed split, collapse, flip and smoothing move as a remeshing edit.
fn count_improvement(improved: &ImproveReport, report: &mut StepReport) {
    let d = &improved.degenerate;
    report.events.t2 += (d.pairs_relabelled + d.pairs_removed) as u64;
    report.events.remeshing_edits +=
        (improved.split.done + improved.collapse.done + improved.flip.done + improved.smooth.done)
            as u64;
}

/// Stage "validate": the step's result must pass `validate` at the configured depth.
fn check(work: &LabeledMesh, validation: StepValidation) -> Result<(), TrackError> {
    let options = match validation {
        StepValidation::Off => return Ok(()),
        StepValidation::Structure => ValidateOptions::default(),
        StepValidation::Exact => ValidateOptions::with_intersections(),
    };
    let report = validate(work, &options);
    if report.is_valid() {
        Ok(())
    } else {
        Err(TrackError::StageFailed {
            stage: "validate",
            reason: report.to_string(),
        })
    }
}

/// Refuses a step in which some vertex moves farther than `limit`, naming the vertex and
/// the distance, before any collision work starts (see
/// [`crate::CollisionParams::max_displacement_factor`]).
fn check_displacement(
    mesh: &LabeledMesh,
    proposed: &[DVec3],
    limit: f64,
) -> Result<(), TrackError> {
    let farthest = mesh
        .vertices()
        .map(|v| (v, mesh.position(v).distance(proposed[v.idx()])))
        .max_by(|a, b| a.1.total_cmp(&b.1));
    match farthest {
        Some((v, d)) if d > limit => Err(TrackError::StageFailed {
            stage: "resolve",
            reason: format!(
                "vertex {v} would move {d:.4} in one step, more than the collision backend's \
                 limit {limit:.4} (max_displacement_factor × ℓ): it resolves trajectories, not \
                 teleports; split the step, or use the grid backend for booleans and repair"
            ),
        }),
        _ => Ok(()),
    }
}
