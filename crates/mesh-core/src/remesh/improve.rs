//! [`improve`]: the mesh-improvement driver (El Topo §3.5–3.6, Los Topos §4.3, 2024 paper
//! §8.5). It keeps edge lengths within `[min, max] × target` and triangles well shaped,
//! and resolves the degeneracies the edits leave behind:
//!
//! ```text
//! for sweep in 0..max_sweeps:
//!     split_long_edges      longest first, butterfly placement with midpoint fallback
//!     collapse_short_edges  shortest first, feature-aware
//!     flip_edges            best improvement first, Delaunay criterion
//!     smooth_vertices       null-space smoothing: every vertex in the first sweep, then
//!                           only around the edits made since the previous pass
//!     remove_degenerate     T2 and collapsed triangles
//!     separate_irregular    T1 vertex separation
//!     pinch_singular        duplicate singular vertices
//!     stop when the sweep made no topological edit (moves alone do not count)
//! ```
//!
//! Why later sweeps smooth locally: after the first pass the rest of the mesh has had its
//! smoothing, and the later sweeps exist to settle the few splits, collapses and flips the
//! previous ones triggered. Smoothing the whole mesh again in each of them (each move a
//! guarded edit) made smoothing most of the cost of `improve` and, by nudging every vertex,
//! kept a trickle of new flips alive so that the loop rarely converged.
//!
//! Each stage finds its candidates in parallel over one snapshot (edge lengths, flip gains,
//! vertex classes) and commits them serially in a deterministic order, re-checking each
//! candidate against the current mesh, so the result does not depend on the thread count
//! and no edit scans the whole mesh (the guard aside).

use std::collections::BTreeMap;

use rayon::prelude::*;

use serde::Serialize;

use crate::corner::Side;
use crate::ids::{CornerId, TriId, VertexId};
use crate::mesh::LabeledMesh;

use super::attributes::VertexAttributes;
use super::collapse::{CollapseError, CollapseParams, CollapseScratch, collapse_edge_in};
use super::degenerate::{DegenerateReport, remove_degenerate_in};
use super::edit::{Applied, Edit, EditError};
use super::features::{self, FeatureParams};
use super::flip::{self, FlipCriterion, FlipError, FlipParams, flip_edge_in};
use super::guard::{EditGuard, Veto};
use super::pinch::pinch_singular_vertices_in;
use super::separate::{
    AreaDecrease, SeparationParams, SeparationReport, SeparationStrength,
    separate_irregular_vertices_in,
};
use super::smooth::{SmoothParams, commit_moves, propose_moves};
use super::split::{SplitPlacement, SplitScratch, split_edge_in};

/// Options of [`improve`]; every field has a documented default.
#[derive(Clone, Debug, PartialEq)]
pub struct ImproveParams {
    /// Target edge length ℓ. Default `None`: the mean edge length of the mesh on entry.
    pub target_edge_length: Option<f64>,
    /// Edges shorter than `min_edge_factor · ℓ` are collapsed. Default 0.5 (El Topo).
    pub min_edge_factor: f64,
    /// Edges longer than `max_edge_factor · ℓ` are split. Default 1.5 (El Topo).
    pub max_edge_factor: f64,
    /// A collapse may not create an edge longer than `collapse_max_edge_factor · ℓ`.
    /// Default 1.35: below `max_edge_factor`, so collapses never feed the next split.
    pub collapse_max_edge_factor: f64,
    /// Ridges and corners of a patch smaller than `min_feature_factor · ℓ` are noise, not
    /// shape: a collapse of an edge that short places its ridge and corner endpoints as
    /// smooth ones (see [`CollapseParams::min_feature_size`]); feature curves are kept at
    /// every size. Default 0.25: half the shortest edge improvement keeps, so a feature
    /// the target resolution can carry is never taken for noise.
    pub min_feature_factor: f64,
    /// Ω, the largest change of any label's volume one flip, collapse, smoothing move or
    /// butterfly split may cause. Default `None`: `0.1·ℓ³` (El Topo §3.5.2).
    pub max_volume_change: Option<f64>,
    /// A collapse may change the volume of a thin, extended material (see
    /// `features::material_caps`: a plate, not a ball or a foam cell) by no more than
    /// this share of that material's volume when improvement starts. Default 0.01. Why,
    /// besides Ω: a material thinner than the target edge (a plate 0.2 thick in a mesh of
    /// 1.2-long edges) has edges improvement takes for too short and ridges it takes for
    /// noise, and one collapse within Ω = 0.1·ℓ³ removed 40 % of it; over a few steps it
    /// was flat. On a resolved material the share binds nothing (1 % of a sheet many
    /// cells wide and thick is far above Ω). 0 turns the bound off.
    pub max_material_share: f64,
    /// Bound on the sweeps. Default 8.
    pub max_sweeps: usize,
    /// Run edge splits. Default true.
    pub split: bool,
    /// Place split vertices by butterfly subdivision where the surface is smooth (else the
    /// midpoint). Default true.
    pub butterfly: bool,
    /// Run edge collapses. Default true.
    pub collapse: bool,
    /// Run edge flips. Default true.
    pub flip: bool,
    /// Run null-space smoothing (the first sweep over every vertex, later sweeps around the
    /// edits made since the previous pass). Default true.
    pub smooth: bool,
    /// Run degenerate removal (T2). Default true.
    pub remove_degenerate: bool,
    /// Run vertex separation (T1). Default true.
    pub separate: bool,
    /// Pinch singular vertices. Default true.
    pub pinch: bool,
    /// Smoothing step (fraction of the projected Laplacian). Default 0.5.
    pub smooth_step: f64,
    /// Smoothing passes per sweep. Default 1.
    pub smooth_passes: usize,
    /// Which vertices the smoothing passes after the first revisit around the edits made
    /// since. Default [`Resmooth::Corners`].
    pub resmooth: Resmooth,
    /// Flip criterion. Default [`FlipCriterion::Delaunay`].
    pub flip_criterion: FlipCriterion,
    /// Minimum flip improvement (see [`FlipCriterion`]). Default 0.01.
    pub flip_min_improvement: f64,
    /// Smallest allowed cosine between a triangle's normal before and after a collapse or
    /// smoothing move. Default 0.5 (60°).
    pub min_normal_cos: f64,
    /// Which edits cancel their volume change by a shift along the normal. Default
    /// [`ConserveVolume::OFF`]: it changes which edits pass, and with them the path of a
    /// run; on the grid backend's 100-bubble `foam-tension` test, with every kind on, one
    /// small bubble drifts 1.4 % instead of under 0.1 %. See [`ConserveVolume`] for what
    /// each kind buys and costs.
    pub conserve_volume: ConserveVolume,
    /// Vertex classification thresholds. Default [`FeatureParams::default`].
    pub features: FeatureParams,
    /// Vertex separation options. Default [`SeparationParams::default`].
    pub separation: SeparationParams,
    /// With [`ImproveRegion::Around`] and `degraded`, a triangle with an interior angle
    /// below this (degrees) is *out of shape* and seeds the work list, as does one with an
    /// edge outside the length range. Default 20°: twice the 10° quality bar, so a
    /// triangle is taken up while it is still easy to mend.
    pub seed_min_angle_deg: f64,
}

impl Default for ImproveParams {
    fn default() -> Self {
        Self {
            target_edge_length: None,
            min_edge_factor: 0.5,
            max_edge_factor: 1.5,
            collapse_max_edge_factor: 1.35,
            min_feature_factor: 0.25,
            max_volume_change: None,
            max_material_share: 0.01,
            max_sweeps: 8,
            split: true,
            butterfly: true,
            collapse: true,
            flip: true,
            smooth: true,
            remove_degenerate: true,
            separate: true,
            pinch: true,
            smooth_step: 0.5,
            smooth_passes: 1,
            resmooth: Resmooth::Corners,
            flip_criterion: FlipCriterion::Delaunay,
            flip_min_improvement: 0.01,
            min_normal_cos: 0.5,
            conserve_volume: ConserveVolume::OFF,
            features: FeatureParams::default(),
            separation: SeparationParams::default(),
            seed_min_angle_deg: 20.0,
        }
    }
}

/// Which vertices a smoothing pass after a sweep's first revisits around the edits (splits,
/// collapses, flips, separations, pinches) committed since the previous pass.
///
/// Why a choice: a smoothing move's target depends only on the vertex's one-ring, and
/// [`Resmooth::Corners`] are exactly the vertices whose ring an edit changed, so they are
/// all that needs a new move; [`Resmooth::Neighbourhood`] adds the ring around them, which
/// lets a change spread one ring further per pass. Measured side by side (release, one
/// session), `Corners` took 0.86× the wall time of `Neighbourhood` on `run double-bubble`,
/// 0.91× on grid `spheres --spheres 20 --steps 40` and 0.94× on `fix` of 6 bunnies, with the
/// worst frame's share of triangles under 10° and edge-length p99/p1 the same or better.
/// On the collision backend's spheres-20 (40 steps) it was 1.13× *slower*: the walls
/// between pressed spheres kept worse triangles (worst p99/p1 15.8 against 9.5), which
/// cost more T1 events (1073 against 816) and more merging; that backend keeps
/// `Neighbourhood`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Resmooth {
    /// The corners of the triangles the edits created and the vertices they moved.
    #[default]
    Corners,
    /// Those and every neighbour of theirs.
    Neighbourhood,
}

/// Which remeshing edits cancel the label-volume change they cause by a shift along the
/// surface normal, where the surface is smooth enough to have one (never on feature curves
/// or corners, where a shift would round them).
///
/// Why per kind: the kinds differ in what they take and in what a shift risks. Measured on
/// the collision backend, one Enright period (El Topo's test, Ω = 0.1 ℓ³): 1.56 % volume
/// change with none; 0.17 % with flips alone (Delaunay flips across the curved sheet are
/// most of the loss); 0.07 % with flips and collapses; 0.14 % with all three. Smoothing
/// shifts add nothing there, and they move vertices next to triple curves off the surface
/// the flow carries: before the harness's normal flow stopped growing fins at convex
/// junctions, such a bump on two expanding spheres (`spheres --spheres 2 --seed 10`)
/// grew into a fin half a sphere radius long. With that flow they leave the wall as
/// smooth as the other kinds (seeds 4, 9, 10).
///
/// Serialised as a table of the three kinds. Read back from that table (all three
/// required: a partial table would silently turn the missing kinds off) or from one bool,
/// the form of records and scripts written before the kinds were separate: `true` is
/// [`ConserveVolume::ALL`], `false` [`ConserveVolume::OFF`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct ConserveVolume {
    /// A flip shifts the ends of its new edge.
    pub flips: bool,
    /// A collapse to the midpoint of a smooth edge shifts the merged vertex.
    pub collapses: bool,
    /// A smoothing move shifts along the vertex normal.
    pub smoothing: bool,
}

impl<'de> serde::Deserialize<'de> for ConserveVolume {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(serde::Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Kinds {
            flips: bool,
            collapses: bool,
            smoothing: bool,
        }
        #[derive(serde::Deserialize)]
        #[serde(
            untagged,
            expecting = "a bool or a table of flips, collapses, smoothing"
        )]
        enum Form {
            Every(bool),
            Kinds(Kinds),
        }
        Ok(match Form::deserialize(d)? {
            Form::Every(true) => Self::ALL,
            Form::Every(false) => Self::OFF,
            Form::Kinds(k) => Self {
                flips: k.flips,
                collapses: k.collapses,
                smoothing: k.smoothing,
            },
        })
    }
}

impl ConserveVolume {
    /// No edit compensates: each is bounded by Ω alone.
    pub const OFF: Self = Self {
        flips: false,
        collapses: false,
        smoothing: false,
    };
    /// Every kind compensates.
    pub const ALL: Self = Self {
        flips: true,
        collapses: true,
        smoothing: true,
    };
}

/// Where [`improve_in`] works.
///
/// Why a work list: in a tracking step most of the surface is as good as after the last
/// step; sweeping all of it again (every edge measured, every vertex smoothed and examined
/// for T1 and pinching) made improvement most of every step. With `Around`, each stage
/// looks only at the work list — the seeds, whatever the motion degraded, and everything
/// an edit touched — so a step where 1 % of the mesh needs work costs about 1 % of a sweep.
#[derive(Clone, Copy, Debug)]
pub enum ImproveRegion<'a> {
    /// Every vertex in the first sweep; later sweeps where the previous one edited.
    Whole,
    /// Start from the vertices of `seeds` and, when `degraded`, of every triangle that is
    /// out of range or shape (an edge outside `[min, max] × target`, an angle below
    /// [`ImproveParams::seed_min_angle_deg`]), found by one parallel scan.
    Around {
        /// Triangles that need work (e.g. the ones a topology change created).
        seeds: &'a [TriId],
        /// Also seed with the degraded triangles of the whole mesh.
        degraded: bool,
    },
    /// Start from exactly these vertices (dead ones are skipped): a work list carried over
    /// from an earlier call, as the block driver ([`super::blocks`]) hands on the
    /// places one pass had to leave.
    Vertices(&'a [VertexId]),
}

/// Outcome counts of one operation.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct OpCounts {
    /// Edits committed.
    pub done: usize,
    /// Candidates refused by the operation's own checks (features, link condition,
    /// inversion, volume, no longer applicable).
    pub refused: usize,
    /// Edits vetoed by the guard.
    pub vetoed: usize,
}

/// What [`improve`] did.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ImproveReport {
    /// The target edge length used.
    pub target_edge_length: f64,
    /// The Ω used.
    pub max_volume_change: f64,
    /// Sweeps run.
    pub sweeps: usize,
    /// True when the last sweep made no topological edit (false: `max_sweeps` reached).
    pub converged: bool,
    /// Edge splits.
    pub split: OpCounts,
    /// Splits that wanted a butterfly position but used the midpoint.
    pub split_midpoint_fallbacks: usize,
    /// Edge collapses.
    pub collapse: OpCounts,
    /// Collapses refused or vetoed, per reason ([`CollapseError::reason`]): which check
    /// holds the mesh back when short edges stay.
    pub collapse_refusals: BTreeMap<&'static str, usize>,
    /// The guard's vetoes of every operation's edits, per kind ([`Veto::kind`]): which of
    /// the guard's checks refuses (batched smoothing counts a blamed move when it is
    /// retried alone).
    pub vetoes: BTreeMap<&'static str, usize>,
    /// Edge flips.
    pub flip: OpCounts,
    /// Smoothing moves.
    pub smooth: OpCounts,
    /// Degenerate removal (T2), summed over sweeps.
    pub degenerate: DegenerateReport,
    /// Vertex separations (T1), summed over sweeps.
    pub separations: usize,
    /// Separations vetoed by the guard.
    pub separations_vetoed: usize,
    /// Singular vertices pinched.
    pub pinched: usize,
    /// Σ over committed flips, collapses, smoothing moves and butterfly splits of the
    /// largest label volume change each caused: a bound on every label's total change
    /// from those operations (each term is ≤ Ω).
    pub volume_change_bound: f64,
    /// Blocks improved in parallel, summed over passes ([`super::blocks`]); 0 when
    /// improvement ran serially.
    pub blocks: usize,
    /// Distinct edges at the end.
    pub edges: usize,
    /// Fraction of them with length in `[min, max] × target`.
    pub edges_in_range: f64,
}

impl ImproveReport {
    /// Adds the counts of `other`, a run over another part of the mesh or a later pass
    /// over this one: operation counts, refusals, vetoes and the volume bound are summed,
    /// sweeps are the most either took, and the result converged only if both did. The
    /// end-of-run edge figures are left to the caller (they describe one mesh).
    pub fn absorb(&mut self, other: &ImproveReport) {
        let add = |a: &mut OpCounts, b: &OpCounts| {
            a.done += b.done;
            a.refused += b.refused;
            a.vetoed += b.vetoed;
        };
        self.sweeps = self.sweeps.max(other.sweeps);
        self.converged &= other.converged;
        add(&mut self.split, &other.split);
        self.split_midpoint_fallbacks += other.split_midpoint_fallbacks;
        add(&mut self.collapse, &other.collapse);
        for (k, n) in &other.collapse_refusals {
            *self.collapse_refusals.entry(k).or_default() += n;
        }
        for (k, n) in &other.vetoes {
            *self.vetoes.entry(k).or_default() += n;
        }
        add(&mut self.flip, &other.flip);
        add(&mut self.smooth, &other.smooth);
        add_degenerate(&mut self.degenerate, &other.degenerate);
        self.separations += other.separations;
        self.separations_vetoed += other.separations_vetoed;
        self.pinched += other.pinched;
        self.volume_change_bound += other.volume_change_bound;
        self.blocks += other.blocks;
    }

    /// The edits committed: splits, collapses, flips, smoothing moves, separations and
    /// pinches (the count a tracker reports as its remeshing edits).
    pub fn edits(&self) -> usize {
        self.split.done
            + self.collapse.done
            + self.flip.done
            + self.smooth.done
            + self.separations
            + self.pinched
    }
}

/// Improves the mesh (see the module doc); T1 separation uses [`AreaDecrease`] as its
/// strength (the surface-tension choice). Each edit goes through `guard`; `attrs` follow.
pub fn improve(
    mesh: &mut LabeledMesh,
    params: &ImproveParams,
    attrs: &mut VertexAttributes,
    guard: &mut dyn EditGuard,
) -> ImproveReport {
    improve_in(
        mesh,
        params,
        ImproveRegion::Whole,
        attrs,
        guard,
        &AreaDecrease,
    )
}

/// [`improve`] with a caller-chosen T1 separation strength (e.g. a velocity field's
/// divergence, [`super::VelocityDivergence`]).
pub fn improve_with(
    mesh: &mut LabeledMesh,
    params: &ImproveParams,
    attrs: &mut VertexAttributes,
    guard: &mut dyn EditGuard,
    strength: &dyn SeparationStrength,
) -> ImproveReport {
    improve_in(mesh, params, ImproveRegion::Whole, attrs, guard, strength)
}

/// [`improve_with`] over a region: the whole mesh, or a work list grown from seeds (see
/// [`ImproveRegion`]). Every stage of a sweep looks at the current work list only, and
/// the vertices each edit touches join it; the next sweep works on the neighbourhood of
/// what this one changed, and the loop stops when a sweep makes no topological edit.
pub fn improve_in(
    mesh: &mut LabeledMesh,
    params: &ImproveParams,
    region: ImproveRegion<'_>,
    attrs: &mut VertexAttributes,
    guard: &mut dyn EditGuard,
    strength: &dyn SeparationStrength,
) -> ImproveReport {
    let caps = features::material_caps(mesh, params.max_material_share);
    improve_part(
        mesh, params, region, attrs, guard, strength, true, None, &caps,
    )
}

/// [`improve_in`] with the end-of-run edge figures ([`ImproveReport::edges`],
/// [`ImproveReport::edges_in_range`]) left at zero unless `edge_figures`: they measure
/// every edge of `mesh`, which for a block of [`super::blocks`] is a copy the caller
/// throws away and measures again as a whole, so there they cost a full edge scan per
/// block for nothing.
///
/// `unfinished`, when given, receives the vertices the next sweep would have worked on
/// when the run stops at [`ImproveParams::max_sweeps`] without converging, so that a
/// caller running more passes (blocks, then the serial pass) carries them on instead of
/// dropping them.
///
/// `caps`: [`features::material_caps`] of the whole mesh (a block's copy holds pieces of
/// shells, whose volumes mean nothing), for [`ImproveParams::max_material_share`].
#[allow(clippy::too_many_arguments)]
pub(super) fn improve_part(
    mesh: &mut LabeledMesh,
    params: &ImproveParams,
    region: ImproveRegion<'_>,
    attrs: &mut VertexAttributes,
    guard: &mut dyn EditGuard,
    strength: &dyn SeparationStrength,
    edge_figures: bool,
    unfinished: Option<&mut Vec<VertexId>>,
    caps: &[(crate::ids::Label, f64)],
) -> ImproveReport {
    let mut run = Run::new(mesh, params);
    run.collapse.caps = caps.to_vec();
    // Every edit goes through the recorder, which notes where the mesh changed: the work
    // list of the rest of the sweep, of the next smoothing pass and of the next sweep.
    let mut recorder = Recorder::new(guard);
    // The current sweep's vertices, increasing, each once; `None`: the whole mesh.
    let mut work: Option<Vec<VertexId>> = match region {
        ImproveRegion::Whole => None,
        ImproveRegion::Around { seeds, degraded } => Some(run.initial_work(mesh, seeds, degraded)),
        ImproveRegion::Vertices(vertices) => {
            let mut w = vertices.to_vec();
            live_sorted(mesh, &mut w);
            Some(w)
        }
    };
    // Seconds per operation, for the debug log below.
    let mut secs = [0.0f64; 8];
    for _ in 0..params.max_sweeps {
        if let Some(w) = &work {
            tracing::debug!(work = w.len(), "improve: sweep");
        }
        if work.as_ref().is_some_and(Vec::is_empty) {
            run.report.converged = true;
            break;
        }
        run.report.sweeps += 1;
        let mut changed = 0;
        if params.split {
            let t0 = std::time::Instant::now();
            changed += run.split_long_edges(mesh, attrs, &mut recorder, work.as_deref());
            secs[0] += t0.elapsed().as_secs_f64();
            recorder.extend_work(mesh, &mut work);
        }
        if params.collapse {
            let t0 = std::time::Instant::now();
            changed += run.collapse_short_edges(mesh, attrs, &mut recorder, work.as_deref());
            secs[1] += t0.elapsed().as_secs_f64();
            recorder.extend_work(mesh, &mut work);
        }
        if params.flip {
            let t0 = std::time::Instant::now();
            changed += run.flip_edges(mesh, attrs, &mut recorder, work.as_deref());
            secs[2] += t0.elapsed().as_secs_f64();
            recorder.extend_work(mesh, &mut work);
        }
        if params.smooth {
            let t0 = std::time::Instant::now();
            run.smooth(mesh, attrs, &mut recorder, work.as_deref());
            secs[3] += t0.elapsed().as_secs_f64();
        }
        let t0 = std::time::Instant::now();
        if params.remove_degenerate {
            let d = remove_degenerate_in(mesh, attrs, &mut recorder, work.as_deref());
            let edits = d.collapsed_removed + d.pairs_relabelled + d.pairs_removed;
            run.touched(edits + d.vertices_removed);
            changed += edits;
            add_degenerate(&mut run.report.degenerate, &d);
            recorder.extend_work(mesh, &mut work);
        }
        secs[4] += t0.elapsed().as_secs_f64();
        let t0 = std::time::Instant::now();
        if params.separate {
            let s: SeparationReport = separate_irregular_vertices_in(
                mesh,
                attrs,
                &mut recorder,
                &params.separation,
                strength,
                work.as_deref(),
            );
            run.touched(s.separations);
            changed += s.separations;
            run.report.separations += s.separations;
            run.report.separations_vetoed += s.vetoed;
            recorder.extend_work(mesh, &mut work);
        }
        secs[5] += t0.elapsed().as_secs_f64();
        let t0 = std::time::Instant::now();
        if params.pinch {
            let p = pinch_singular_vertices_in(mesh, attrs, &mut recorder, work.as_deref());
            run.touched(p);
            changed += p;
            run.report.pinched += p;
        }
        secs[6] += t0.elapsed().as_secs_f64();
        let t0 = std::time::Instant::now();
        // The next sweep settles what this one changed, and only that.
        work = Some(recorder.take_sweep(mesh));
        secs[7] += t0.elapsed().as_secs_f64();
        if changed == 0 {
            run.report.converged = true;
            break;
        }
    }
    if let Some(out) = unfinished.filter(|_| !run.report.converged) {
        match &work {
            Some(w) => out.extend(w.iter().copied().filter(|&v| mesh.is_vertex_alive(v))),
            None => out.extend(mesh.vertices()),
        }
    }
    run.report.vetoes = std::mem::take(&mut recorder.vetoes);
    // Where the time went (`RUST_LOG=mesh_core=debug`): wall seconds per operation,
    // summed over the sweeps.
    tracing::debug!(
        split = secs[0],
        collapse = secs[1],
        flip = secs[2],
        smooth = secs[3],
        degenerate = secs[4],
        separate = secs[5],
        pinch = secs[6],
        next_work = secs[7],
        report = ?run.report,
        "improve: seconds per operation"
    );
    if !edge_figures {
        return run.report;
    }
    let (lo, hi) = run.range();
    let edges = run.edges(mesh);
    let (count, inside) = (
        edges.len(),
        edges
            .par_iter()
            .filter(|e| e.length >= lo && e.length <= hi)
            .count(),
    );
    run.report.edges = count;
    run.report.edges_in_range = if count == 0 {
        1.0
    } else {
        inside as f64 / count as f64
    };
    run.report
}

fn add_degenerate(sum: &mut DegenerateReport, d: &DegenerateReport) {
    sum.collapsed_removed += d.collapsed_removed;
    sum.pairs_relabelled += d.pairs_relabelled;
    sum.pairs_removed += d.pairs_removed;
    sum.vertices_removed += d.vertices_removed;
    sum.vetoed += d.vetoed;
    sum.unresolved += d.unresolved;
}

/// Forwards every edit to the caller's guard and, while `recording`, notes the vertices of
/// the triangles each committed edit creates and the vertices it moves: where the mesh
/// changed. The notes feed three work lists: the rest of the current sweep
/// ([`Recorder::extend_work`]), the next smoothing pass ([`Recorder::take_smoothing`]) and
/// the next sweep ([`Recorder::take_sweep`]).
///
/// Why smoothing follows the edits: the first sweep smooths its whole work list; after it
/// only the vertices around later splits, collapses, flips, separations and pinches need
/// smoothing again. Re-smoothing everything in every sweep made the smoothing moves most of
/// the cost of `improve`, while the few topological edits of late sweeps kept the loop
/// from converging.
struct Recorder<'g> {
    inner: &'g mut dyn EditGuard,
    recording: bool,
    /// Vertices noted this sweep, in order (repeats allowed).
    log: Vec<VertexId>,
    /// `log[..smoothed]` has been handed to a smoothing pass.
    smoothed: usize,
    /// `log[..in_work]` has joined the current sweep's work list.
    in_work: usize,
    /// The guard's vetoes, per kind ([`ImproveReport::vetoes`]).
    vetoes: BTreeMap<&'static str, usize>,
}

impl<'g> Recorder<'g> {
    fn new(inner: &'g mut dyn EditGuard) -> Self {
        Recorder {
            inner,
            recording: true,
            log: Vec::new(),
            smoothed: 0,
            in_work: 0,
            vetoes: BTreeMap::new(),
        }
    }

    /// Adds the vertices noted since the last call to the sweep's work list (the whole
    /// mesh needs no additions).
    fn extend_work(&mut self, mesh: &LabeledMesh, work: &mut Option<Vec<VertexId>>) {
        if let Some(w) = work
            && self.in_work < self.log.len()
        {
            w.extend_from_slice(&self.log[self.in_work..]);
            live_sorted(mesh, w);
        }
        self.in_work = self.log.len();
    }

    /// Counts a veto of the inner guard by kind and passes the verdict on.
    fn count(&mut self, verdict: Result<(), Veto>) -> Result<(), Veto> {
        if let Err(veto) = verdict {
            *self.vetoes.entry(veto.kind()).or_default() += 1;
        }
        verdict
    }

    /// The vertices noted since the last smoothing pass (see [`Resmooth`]), live, increasing,
    /// each once.
    fn take_smoothing(&mut self, mesh: &LabeledMesh, reach: Resmooth) -> Vec<VertexId> {
        let noted = &self.log[self.smoothed..];
        let out = match reach {
            Resmooth::Neighbourhood => neighbourhood(mesh, noted),
            Resmooth::Corners => {
                let mut out = noted.to_vec();
                live_sorted(mesh, &mut out);
                out
            }
        };
        self.smoothed = self.log.len();
        out
    }

    /// The neighbourhood of everything noted this sweep; the notes are cleared.
    fn take_sweep(&mut self, mesh: &LabeledMesh) -> Vec<VertexId> {
        let out = neighbourhood(mesh, &self.log);
        self.log.clear();
        self.smoothed = 0;
        self.in_work = 0;
        out
    }
}

/// The live vertices among `vertices` and their neighbours, in increasing order, each once.
///
/// The notes repeat each vertex many times (every triangle an edit creates names three),
/// so they are deduplicated before their rings are expanded: expanding first sorted about
/// twenty entries per note (tens of millions after a sweep of ~10⁵ collapses).
fn neighbourhood(mesh: &LabeledMesh, vertices: &[VertexId]) -> Vec<VertexId> {
    let mut unique = vertices.to_vec();
    unique.par_sort_unstable();
    unique.dedup();
    let mut out: Vec<VertexId> = unique
        .par_iter()
        .with_min_len(256)
        .filter(|&&v| mesh.is_vertex_alive(v))
        .flat_map_iter(|&v| mesh.vertex_triangles(v).flat_map(|t| mesh.tri(t)))
        .collect();
    live_sorted(mesh, &mut out);
    out
}

/// Keeps the live vertices of `vertices`, in increasing order, each once: the form of
/// every work list.
pub(super) fn live_sorted(mesh: &LabeledMesh, vertices: &mut Vec<VertexId>) {
    vertices.par_sort_unstable();
    vertices.dedup();
    vertices.retain(|&v| mesh.is_vertex_alive(v));
}

impl EditGuard for Recorder<'_> {
    fn check(&mut self, mesh: &LabeledMesh, edit: &Edit) -> Result<(), Veto> {
        let verdict = self.inner.check(mesh, edit);
        self.count(verdict)
    }

    fn offending_moves(&mut self, mesh: &LabeledMesh, edit: &Edit) -> Option<Vec<usize>> {
        self.inner.offending_moves(mesh, edit)
    }

    fn check_vertex(&mut self, mesh: &LabeledMesh, v: VertexId) -> Result<(), Veto> {
        let verdict = self.inner.check_vertex(mesh, v);
        self.count(verdict)
    }

    fn precheck(&mut self, mesh: &LabeledMesh, edit: &Edit) -> Result<(), Veto> {
        let verdict = self.inner.precheck(mesh, edit);
        self.count(verdict)
    }

    fn committed(&mut self, mesh: &LabeledMesh, edit: &Edit, applied: &Applied) {
        self.inner.committed(mesh, edit, applied);
        if self.recording {
            for &t in &applied.triangles {
                self.log.extend(mesh.tri(t));
            }
            self.log.extend(edit.moves.iter().map(|m| m.vertex));
        }
    }
}

/// One distinct edge of a snapshot.
#[derive(Clone, Copy, Debug)]
struct EdgeItem {
    a: VertexId,
    b: VertexId,
    length: f64,
    /// A feature edge (≠ 2 triangles or differing label sets).
    feature: bool,
    /// A front corner opposite the edge (valid while the connectivity is unchanged).
    corner: CornerId,
}

/// Every distinct edge once (from its lowest-id triangle), in triangle order, in parallel.
fn edge_list(mesh: &LabeledMesh) -> Vec<EdgeItem> {
    let alive = mesh.tri_alive_flags();
    (0..mesh.triangle_capacity() as u32)
        .into_par_iter()
        .filter(|&t| alive[t as usize])
        .flat_map_iter(|t| {
            let t = TriId::new(t);
            let tri = mesh.tri(t);
            let degenerate = tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2];
            (0..3).filter_map(move |k| {
                if degenerate {
                    return None;
                }
                let c = CornerId::of(t, Side::Front, k);
                let star = features::edge_star(mesh, c);
                (star.min_tri == t).then(|| {
                    let [a, b] = mesh.corner_edge(c);
                    let length = mesh.position(a).distance(mesh.position(b));
                    EdgeItem {
                        a,
                        b,
                        length,
                        feature: star.is_feature(),
                        corner: c,
                    }
                })
            })
        })
        .collect()
}

/// Every distinct edge with an end in `work` (increasing, each once) whose length passes
/// `keep`, once, in parallel; `member` is scratch, all false on entry and on return.
///
/// Why `keep`: splits and collapses want only the few edges outside the length range, and
/// the length is far cheaper than the edge's star (which deduplicates and classifies it),
/// so the filter runs first.
fn edges_at(
    mesh: &LabeledMesh,
    work: &[VertexId],
    member: &mut Vec<bool>,
    keep: &(impl Fn(f64) -> bool + Sync),
) -> Vec<EdgeItem> {
    if member.len() < mesh.vertex_capacity() {
        member.resize(mesh.vertex_capacity(), false);
    }
    for &v in work {
        member[v.idx()] = true;
    }
    let inside: &[bool] = member;
    let edges = work
        .par_iter()
        .with_min_len(64)
        .flat_map_iter(|&v| {
            mesh.vertex_corners(v).flat_map(move |c| {
                let t = c.tri();
                let tri = mesh.tri(t);
                let degenerate = tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2];
                // The two edges at v are opposite the other two corners of the triangle.
                [c.next(), c.prev()].into_iter().filter_map(move |k| {
                    if degenerate {
                        return None;
                    }
                    let [a, b] = mesh.corner_edge(k);
                    let length = mesh.position(a).distance(mesh.position(b));
                    if !keep(length) {
                        return None;
                    }
                    let w = if a == v { b } else { a };
                    if inside[w.idx()] && w < v {
                        return None;
                    }
                    let star = features::edge_star(mesh, k);
                    // Once per edge: from its lowest-id triangle, and from the lower end
                    // when both ends are in the work list.
                    (star.min_tri == t).then(|| EdgeItem {
                        a,
                        b,
                        length,
                        feature: star.is_feature(),
                        corner: k,
                    })
                })
            })
        })
        .collect();
    for &v in work {
        member[v.idx()] = false;
    }
    edges
}

/// Mean length of the distinct edges (0 for an empty mesh).
pub fn mean_edge_length(mesh: &LabeledMesh) -> f64 {
    mean_length(&edge_list(mesh))
}

fn mean_length(edges: &[EdgeItem]) -> f64 {
    if edges.is_empty() {
        return 0.0;
    }
    crate::geometry::ordered_sum(edges.len(), |i| edges[i].length) / edges.len() as f64
}

/// Fraction of the distinct edges of `mesh` whose length lies in `[lo, hi]`, with the
/// number of edges.
pub fn edge_length_fraction(mesh: &LabeledMesh, lo: f64, hi: f64) -> (f64, usize) {
    let edges = edge_list(mesh);
    let inside = edges
        .par_iter()
        .filter(|e| e.length >= lo && e.length <= hi)
        .count();
    (
        if edges.is_empty() {
            1.0
        } else {
            inside as f64 / edges.len() as f64
        },
        edges.len(),
    )
}

/// Working state of one [`improve`] call.
struct Run<'p> {
    params: &'p ImproveParams,
    report: ImproveReport,
    /// The distinct edges, rebuilt only after connectivity changed (lengths are refreshed
    /// on every use, since smoothing moves vertices without changing connectivity).
    edges: Vec<EdgeItem>,
    edges_valid: bool,
    split: SplitScratch,
    collapse: CollapseScratch,
    edit: Edit,
    volumes: Vec<(crate::ids::Label, f64)>,
    /// True once the first smoothing pass (over the whole work list) has run.
    smoothed: bool,
    /// Scratch of [`edges_at`].
    member: Vec<bool>,
}

impl<'p> Run<'p> {
    fn new(mesh: &LabeledMesh, params: &'p ImproveParams) -> Self {
        // The whole edge list only when the target needs the mean length: a run over a
        // work list never reads it otherwise, and building it visits every edge of the
        // mesh (of each block's copy, under the block driver) on every call.
        let (edges, edges_valid) = match params.target_edge_length {
            Some(_) => (Vec::new(), false),
            None => (edge_list(mesh), true),
        };
        let target = params
            .target_edge_length
            .unwrap_or_else(|| mean_length(&edges));
        let omega = params
            .max_volume_change
            .unwrap_or(0.1 * target * target * target);
        Run {
            params,
            report: ImproveReport {
                target_edge_length: target,
                max_volume_change: omega,
                ..Default::default()
            },
            edges,
            edges_valid,
            split: SplitScratch::default(),
            collapse: CollapseScratch::default(),
            edit: Edit::default(),
            volumes: Vec::new(),
            smoothed: false,
            member: Vec::new(),
        }
    }

    /// The first sweep's work list of [`ImproveRegion::Around`].
    fn initial_work(&self, mesh: &LabeledMesh, seeds: &[TriId], degraded: bool) -> Vec<VertexId> {
        initial_work(mesh, self.params, self.range(), seeds, degraded)
    }

    /// The candidate edges of a stage whose length passes `keep`: of every edge, or of
    /// those at the work list.
    fn candidate_edges(
        &mut self,
        mesh: &LabeledMesh,
        work: Option<&[VertexId]>,
        keep: &(impl Fn(f64) -> bool + Sync),
    ) -> Vec<EdgeItem> {
        match work {
            None => self
                .edges(mesh)
                .iter()
                .filter(|e| keep(e.length))
                .copied()
                .collect(),
            Some(w) => edges_at(mesh, w, &mut self.member, keep),
        }
    }

    fn range(&self) -> (f64, f64) {
        let t = self.report.target_edge_length;
        (
            self.params.min_edge_factor * t,
            self.params.max_edge_factor * t,
        )
    }

    /// Records that `edits` connectivity-changing edits were applied.
    fn touched(&mut self, edits: usize) {
        if edits > 0 {
            self.edges_valid = false;
        }
    }

    /// The current distinct edges with current lengths.
    fn edges(&mut self, mesh: &LabeledMesh) -> &[EdgeItem] {
        if self.edges_valid {
            self.edges
                .par_iter_mut()
                .for_each(|e| e.length = mesh.position(e.a).distance(mesh.position(e.b)));
        } else {
            self.edges = edge_list(mesh);
            self.edges_valid = true;
        }
        &self.edges
    }

    fn current_length(mesh: &LabeledMesh, a: VertexId, b: VertexId) -> Option<f64> {
        (mesh.is_vertex_alive(a) && mesh.is_vertex_alive(b) && flip::has_edge(mesh, a, b))
            .then(|| mesh.position(a).distance(mesh.position(b)))
    }

    /// Splits edges longer than the maximum, longest first. Returns the number of splits.
    fn split_long_edges(
        &mut self,
        mesh: &mut LabeledMesh,
        attrs: &mut VertexAttributes,
        guard: &mut dyn EditGuard,
        work: Option<&[VertexId]>,
    ) -> usize {
        let (_, hi) = self.range();
        let mut candidates = self.candidate_edges(mesh, work, &|l| l > hi);
        candidates.par_sort_unstable_by(|x, y| {
            y.length
                .total_cmp(&x.length)
                .then((x.a, x.b).cmp(&(y.a, y.b)))
        });
        let placement = if self.params.butterfly {
            SplitPlacement::Butterfly {
                features: self.params.features,
                max_volume_change: self.report.max_volume_change,
            }
        } else {
            SplitPlacement::Midpoint
        };
        let counts = &mut self.report.split;
        let before = counts.done;
        for e in candidates {
            if Self::current_length(mesh, e.a, e.b).is_none_or(|l| l <= hi) {
                counts.refused += 1;
                continue;
            }
            match split_edge_in(&mut self.split, mesh, attrs, guard, e.a, e.b, placement) {
                Ok(s) => {
                    counts.done += 1;
                    self.report.split_midpoint_fallbacks += usize::from(s.fell_back);
                    self.report.volume_change_bound += s.volume_change;
                }
                Err(EditError::Vetoed(_)) => counts.vetoed += 1,
                Err(_) => counts.refused += 1,
            }
        }
        let done = counts.done - before;
        self.touched(done);
        done
    }

    /// Collapses edges shorter than the minimum, shortest first. Returns the number done.
    fn collapse_short_edges(
        &mut self,
        mesh: &mut LabeledMesh,
        attrs: &mut VertexAttributes,
        guard: &mut dyn EditGuard,
        work: Option<&[VertexId]>,
    ) -> usize {
        let (lo, _) = self.range();
        let mut candidates = self.candidate_edges(mesh, work, &|l| l < lo);
        candidates.par_sort_unstable_by(|x, y| {
            x.length
                .total_cmp(&y.length)
                .then((x.a, x.b).cmp(&(y.a, y.b)))
        });
        let params = CollapseParams {
            features: self.params.features,
            max_volume_change: self.report.max_volume_change,
            max_edge_length: self.params.collapse_max_edge_factor * self.report.target_edge_length,
            min_feature_size: self.params.min_feature_factor * self.report.target_edge_length,
            min_normal_cos: self.params.min_normal_cos,
            conserve_volume: self.params.conserve_volume.collapses,
            ..CollapseParams::default()
        };
        let counts = &mut self.report.collapse;
        let before = counts.done;
        for e in candidates {
            if Self::current_length(mesh, e.a, e.b).is_none_or(|l| l >= lo) {
                counts.refused += 1;
                continue;
            }
            match collapse_edge_in(&mut self.collapse, mesh, attrs, guard, e.a, e.b, &params) {
                Ok(dv) => {
                    counts.done += 1;
                    self.report.volume_change_bound += dv;
                }
                Err(e) => {
                    match e {
                        CollapseError::Edit(EditError::Vetoed(_)) => counts.vetoed += 1,
                        _ => counts.refused += 1,
                    }
                    *self.report.collapse_refusals.entry(e.reason()).or_default() += 1;
                }
            }
        }
        let done = counts.done - before;
        self.touched(done);
        done
    }

    /// Flips every edge whose flip improves the criterion, best first. Returns flips done.
    fn flip_edges(
        &mut self,
        mesh: &mut LabeledMesh,
        attrs: &mut VertexAttributes,
        guard: &mut dyn EditGuard,
        work: Option<&[VertexId]>,
    ) -> usize {
        let params = FlipParams {
            criterion: self.params.flip_criterion,
            min_improvement: self.params.flip_min_improvement,
            max_volume_change: self.report.max_volume_change,
            conserve_volume: self.params.conserve_volume.flips,
            features: self.params.features,
        };
        let snapshot: &LabeledMesh = mesh;
        let mut candidates: Vec<(f64, VertexId, VertexId)> = self
            .candidate_edges(snapshot, work, &|_| true)
            .par_iter()
            .filter(|e| !e.feature)
            .filter_map(|e| {
                let q = flip::quad_at(snapshot, e.corner).ok()?;
                let gain = flip::flip_gain(snapshot, &q, params.criterion);
                (gain > params.min_improvement).then_some((gain, e.a, e.b))
            })
            .collect();
        candidates
            .par_sort_unstable_by(|x, y| y.0.total_cmp(&x.0).then((x.1, x.2).cmp(&(y.1, y.2))));
        let counts = &mut self.report.flip;
        let before = counts.done;
        for (_, a, b) in candidates {
            match flip_edge_in(
                &mut self.edit,
                &mut self.volumes,
                mesh,
                attrs,
                guard,
                a,
                b,
                &params,
            ) {
                Ok(dv) => {
                    counts.done += 1;
                    self.report.volume_change_bound += dv;
                }
                Err(FlipError::Edit(EditError::Vetoed(_))) => counts.vetoed += 1,
                Err(_) => counts.refused += 1,
            }
        }
        let done = counts.done - before;
        self.touched(done);
        done
    }

    /// Null-space smoothing passes. The first sweep smooths its whole work list (every
    /// vertex for the whole mesh, with feature-curve vertices from the edge list), later
    /// ones the neighbourhoods of the edits made since the previous pass (see
    /// [`Recorder`]).
    fn smooth(
        &mut self,
        mesh: &mut LabeledMesh,
        attrs: &mut VertexAttributes,
        recorder: &mut Recorder<'_>,
        work: Option<&[VertexId]>,
    ) {
        let params = SmoothParams {
            step: self.params.smooth_step,
            features: self.params.features,
            max_volume_change: self.report.max_volume_change,
            min_normal_cos: self.params.min_normal_cos,
            conserve_volume: self.params.conserve_volume.smoothing,
            ..SmoothParams::default()
        };
        let first = !self.smoothed;
        self.smoothed = true;
        let mut only = recorder.take_smoothing(mesh, self.params.resmooth);
        if first && let Some(w) = work {
            only.extend_from_slice(w);
            only.par_sort_unstable();
            only.dedup();
        }
        let whole = first && work.is_none();
        if !whole && only.is_empty() {
            return;
        }
        // Feature-edge counts from the edge list pay off only for the whole mesh; a work
        // list classifies its own vertices.
        let counts = whole.then(|| {
            let mut counts = vec![0u32; mesh.vertex_capacity()];
            for e in self.edges(mesh).iter().filter(|e| e.feature) {
                counts[e.a.idx()] += 1;
                counts[e.b.idx()] += 1;
            }
            counts
        });
        // Smoothing moves change no connectivity: nothing to note for the next pass.
        recorder.recording = false;
        for _ in 0..self.params.smooth_passes {
            let proposals = propose_moves(
                mesh,
                &params,
                counts.as_deref(),
                (!whole).then_some(&only[..]),
            );
            let out = commit_moves(mesh, attrs, recorder, &params, &proposals);
            self.report.smooth.done += out.moved;
            self.report.smooth.refused += out.refused;
            self.report.smooth.vetoed += out.vetoed;
            self.report.volume_change_bound += out.volume_change;
        }
        recorder.recording = true;
    }
}

/// The first work list of [`ImproveRegion::Around`]: the seeds' vertices and, when
/// `degraded`, those of every triangle with an edge outside `lo..=hi` or an angle below
/// [`ImproveParams::seed_min_angle_deg`]; increasing, each once.
pub(crate) fn initial_work(
    mesh: &LabeledMesh,
    params: &ImproveParams,
    (lo, hi): (f64, f64),
    seeds: &[TriId],
    degraded: bool,
) -> Vec<VertexId> {
    let min_angle = params.seed_min_angle_deg.to_radians();
    let alive = mesh.tri_alive_flags();
    let mut work: Vec<VertexId> = seeds
        .iter()
        .filter(|t| alive.get(t.idx()).copied().unwrap_or(false))
        .flat_map(|&t| mesh.tri(t))
        .collect();
    if degraded {
        work.par_extend(
            (0..mesh.triangle_capacity())
                .into_par_iter()
                .with_min_len(1024)
                .filter(|&t| alive[t])
                .flat_map_iter(|t| {
                    let t = TriId::new(t as u32);
                    let p = mesh.tri_positions(t);
                    let out = (0..3).any(|k| {
                        let l = p[k].distance(p[(k + 1) % 3]);
                        !(lo..=hi).contains(&l)
                    }) || crate::geometry::triangle_min_angle(&p) < min_angle;
                    out.then(|| mesh.tri(t)).into_iter().flatten()
                }),
        );
    }
    work.par_sort_unstable();
    work.dedup();
    work
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::remesh::fixtures::lcg;
    use crate::remesh::guard::NoGuard;

    #[test]
    fn edge_list_counts_each_edge_once() {
        let m = crate::remesh::split::tests::triple_edge_scene();
        // 5 vertices, 7 triangles: edges 0-1,0-2,0-3,0-4,1-2,1-3,1-4,2-3,3-4 = 9.
        assert_eq!(edge_list(&m).len(), 9);
    }

    #[test]
    fn improve_on_a_coarse_box_refines_to_target() {
        let mut m = crate::remesh::collapse::tests::double_box();
        let params = ImproveParams {
            target_edge_length: Some(0.3),
            ..ImproveParams::default()
        };
        let r = improve(&mut m, &params, &mut VertexAttributes::none(), &mut NoGuard);
        assert!(r.split.done > 0);
        assert!(r.edges_in_range > 0.8, "{r:?}");
        let regions = m.regions();
        assert!(regions.shells.iter().all(|s| s.closed && s.consistent));
    }

    /// A sphere whose vertices are jittered along it (so collapses, flips and smoothing all
    /// have work) keeps its volume to rounding through a whole `improve` with midpoint
    /// splits (butterfly splits move towards the smooth surface on purpose), and loses
    /// volume visibly without `conserve_volume`: every flip across the curved surface, every
    /// midpoint collapse and every tangential smoothing move cuts a sliver off it.
    #[test]
    fn improvement_conserves_volume_where_the_surface_is_smooth() {
        use crate::ids::Label;
        use glam::DVec3;
        let mut m =
            crate::generators::icosphere(3, DVec3::ZERO, 1.0, [Label::new(0), Label::new(1)])
                .expect("sphere");
        let mut state = 11u64;
        for v in m.vertices().collect::<Vec<_>>() {
            let mut next = || ((lcg(&mut state) >> 33) % 1000) as f64 / 500.0 - 1.0;
            let jitter = 0.04 * DVec3::new(next(), next(), next());
            m.set_position(v, (m.position(v) + jitter).normalize());
        }
        let volume = |m: &LabeledMesh| crate::geometry::label_volumes(m)[&Label::new(1)];
        let v0 = volume(&m);
        let drift = |conserve_volume: ConserveVolume| {
            let mut m = m.clone();
            let params = ImproveParams {
                target_edge_length: Some(1.2 * mean_edge_length(&m)),
                butterfly: false,
                conserve_volume,
                ..ImproveParams::default()
            };
            let r = improve(&mut m, &params, &mut VertexAttributes::none(), &mut NoGuard);
            assert!(
                r.collapse.done > 0 && r.flip.done > 0 && r.smooth.done > 0,
                "{r:?}"
            );
            (volume(&m) - v0) / v0
        };
        let (kept, lost) = (drift(ConserveVolume::ALL), drift(ConserveVolume::OFF));
        assert!(kept.abs() < 1e-12, "relative volume change {kept:e}");
        assert!(lost < -1e-4, "without conservation: {lost:e}");
    }

    /// A jittered sphere refined below its edge length needs several sweeps; only the
    /// first smooths every vertex, so the moves stay near one per vertex (re-smoothing the
    /// whole mesh each sweep made them sweeps × vertices), the result is intersection-free
    /// and its edges are in range.
    #[test]
    fn later_sweeps_smooth_only_where_the_mesh_changed() {
        use crate::remesh::guard::StaticIntersectionGuard;
        use crate::validate::{ValidateOptions, validate};
        use glam::DVec3;
        let mut m = crate::generators::icosphere(
            3,
            DVec3::ZERO,
            1.0,
            [crate::ids::Label::new(0), crate::ids::Label::new(1)],
        )
        .expect("sphere");
        let mut state = 7u64;
        for v in m.vertices().collect::<Vec<_>>() {
            let r = 1.0 + 0.02 * (((lcg(&mut state) >> 33) % 1000) as f64 / 500.0 - 1.0);
            m.set_position(v, m.position(v).normalize() * r);
        }
        let params = ImproveParams {
            target_edge_length: Some(0.7 * mean_edge_length(&m)),
            ..ImproveParams::default()
        };
        let r = improve(
            &mut m,
            &params,
            &mut VertexAttributes::none(),
            &mut StaticIntersectionGuard::new(),
        );
        let vertices = m.num_vertices();
        assert!(r.sweeps > 1 && r.split.done > 0, "{r:?}");
        assert!(
            r.smooth.done > vertices / 2,
            "the first sweep smooths: {r:?}"
        );
        assert!(
            r.smooth.done < 2 * vertices,
            "{} moves for {vertices} vertices over {} sweeps",
            r.smooth.done,
            r.sweeps
        );
        assert!(r.edges_in_range > 0.95, "{r:?}");
        assert!(validate(&m, &ValidateOptions::with_intersections()).is_valid());
    }

    /// `Corners` hands the next smoothing pass exactly the noted vertices (live, each
    /// once); `Neighbourhood` adds every neighbour of theirs.
    #[test]
    fn resmooth_reach_is_the_noted_vertices_or_their_neighbourhood() {
        use crate::remesh::guard::NoGuard;
        use glam::DVec3;
        let m = crate::generators::icosphere(
            2,
            DVec3::ZERO,
            1.0,
            [crate::ids::Label::new(0), crate::ids::Label::new(1)],
        )
        .expect("sphere");
        let v = VertexId::new(5);
        let mut ring: Vec<VertexId> = m.vertex_triangles(v).flat_map(|t| m.tri(t)).collect();
        ring.sort_unstable();
        ring.dedup();
        assert!(ring.len() > 5, "a vertex and its neighbours");
        let mut guard = NoGuard;
        let mut recorder = Recorder::new(&mut guard);
        recorder.log.extend([v, v, VertexId::new(9), v]);
        assert_eq!(
            recorder.take_smoothing(&m, Resmooth::Corners),
            vec![v, VertexId::new(9)]
        );
        assert!(
            recorder.take_smoothing(&m, Resmooth::Corners).is_empty(),
            "each note is handed over once"
        );
        recorder.log.push(v);
        assert_eq!(recorder.take_smoothing(&m, Resmooth::Neighbourhood), ring);
    }
}
