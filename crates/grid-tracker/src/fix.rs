//! One-shot repair and multi-material union (§9.5): [`fix`] / [`fix_with`].
//!
//! A tangled mesh — overlapping copies of shapes, an inside-out region, a self-intersecting
//! deformation — goes through one pass of the pipeline with no motion: every region the
//! grid finds flawed is cut out and rebuilt, every exact intersection finer than ℓ is found
//! by one test over the whole mesh and repaired the same way, and everything else is kept
//! as it was. Improvement (§8.5) is restricted to the triangles the pass created
//! ([`crate::ImproveScope::Changed`]).
//!
//! What a user of a repair tool can rely on:
//! - **clean input is returned unchanged** (byte-identical `to_raw()`), at any ℓ: an
//!   input that passes all four layers of [`mesh_core::validate`] needs no repair, so the
//!   pipeline does not run;
//! - **ℓ fits the input** when none is given ([`default_cell_size`]);
//! - **no material is lost silently**: every label's volume before and after is in the
//!   report, and a vanished label, or an output whose total volume differs from the
//!   union of the input's materials ([`union_volume`], measured independently of the
//!   pipeline) by more than [`FixOptions::volume_tolerance`], is a [`FixError::Loss`]
//!   unless [`FixOptions::allow_loss`] turns it into a warning;
//! - **[`crate::GridParams::time_budget`] holds through every stage**, improvement (whose
//!   edits stop at the deadline) and validation included: the call returns within the
//!   budget plus one stage other than improvement.
//!
//! What rebuilt regions cannot keep: the rebuild (§8.1–8.3) is multi-material marching
//! cubes with vertices on grid edges, faces and cell centres, so inside flawed cells a
//! flat face is kept only where it coincides with grid-edge crossings and a crease (an
//! input edge, or the intersection curve of two overlapping flat faces) is cut by a
//! chamfer of size up to ℓ; the curve smoothing of §8.3 rounds it further. Flat faces and
//! creases outside the flawed cells are untouched (the input's own triangles), and a finer
//! ℓ shrinks what is rebuilt.

use std::cell::{OnceCell, RefCell};
use std::time::Instant;

use glam::IVec3;
use mesh_core::broadphase::{Aabb, Bvh};
use mesh_core::placement::{Relabelled, place_nested, surface_components};
use mesh_core::remesh::{ImproveParams, ImproveReport, VertexAttributes};
use mesh_core::validate::{
    Listed, ValidateOptions, ValidationReport, any_intersection, triangles_intersect, validate,
};
use mesh_core::{Label, LabelVolume, LabeledMesh, MaterialCensus, StageTiming, TriId};

use crate::params::{GridParams, ImproveScope};
use crate::pipeline::{PassOutcome, PassStats, PipelineError, Timings, improve_mesh, run_pass};
use crate::scale::{CellSizeChoice, CellSizeRule, default_cell_size};
use crate::stages::grid::{GridError, Lattice};
use crate::union_volume::union_volume;

/// Options of [`fix_with`].
#[derive(Clone, Debug, PartialEq)]
pub struct FixOptions {
    /// The pipeline's parameters. Default: [`GridParams::default`] with improvement
    /// restricted to the rebuilt parts ([`ImproveScope::Changed`]). Without
    /// [`GridParams::cell_size`], ℓ is [`default_cell_size`].
    pub params: GridParams,
    /// Also check the output for exact self-intersections (layer 4 of
    /// [`mesh_core::validate`]) for the report. Default true: a one-shot repair can afford
    /// it, and it is the figure a user of `fix` wants.
    pub validate_intersections: bool,
    /// Accept a loss (a vanished material, or a total volume off the union's by more than
    /// [`Self::volume_tolerance`]): the result is returned with the loss in
    /// [`FixReport::warnings`] (and a `tracing` warning) instead of [`FixError::Loss`].
    /// Default false.
    pub allow_loss: bool,
    /// Largest accepted relative difference between the output's total enclosed volume
    /// and the union reference ([`FixReport::volume_check`]). Default 0.02: the rebuild
    /// chamfers creases by up to ℓ and the reference's quadrature is good to a few 0.1 %
    /// (see [`union_volume`]), far below the loss of a material.
    pub volume_tolerance: f64,
}

impl Default for FixOptions {
    fn default() -> Self {
        let grid = GridParams::default();
        Self {
            params: GridParams {
                improve_scope: ImproveScope::Changed,
                // No edge splits: the rebuilt triangles are already no longer than about
                // ℓ, so a long edge in the output is the input's own (a coarse face, or
                // the part of one the cut kept), and splitting it re-meshes the user's
                // faces at ℓ. A plate 10 × 10 × 0.2 through a box, 24 input triangles,
                // came out as 450k triangles after 125 s of improvement with splits.
                improve: grid.improve.map(|ip| ImproveParams { split: false, ..ip }),
                ..grid
            },
            validate_intersections: true,
            allow_loss: false,
            volume_tolerance: 0.02,
        }
    }
}

/// How the union volume the output is checked against was measured.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ReferenceMethod {
    /// The input was clean: its materials do not overlap, so the sum of their
    /// divergence-theorem volumes is the union's, exactly.
    CleanInput,
    /// Exact line crossings integrated over a lattice of lines ([`union_volume`]).
    LineIntegral,
}

/// The total-volume check of [`fix_with`].
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct VolumeCheck {
    /// Enclosed volume of the union of the input's materials (labels ≠ 0).
    pub reference: f64,
    /// How it was measured.
    pub method: ReferenceMethod,
    /// Line spacing of [`ReferenceMethod::LineIntegral`] (0 otherwise).
    pub spacing: f64,
    /// Sum of the output's per-label volumes (labels ≠ 0).
    pub output: f64,
    /// `|output − reference| / reference` (0 when both are 0).
    pub relative_change: f64,
    /// [`FixOptions::volume_tolerance`].
    pub tolerance: f64,
}

/// What [`fix_with`] did (the CLI's `surftrack fix --json` record).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct FixReport {
    /// Wall time per stage, in pipeline order. `reference` runs beside `improve`, so the
    /// seconds add up to more than [`FixReport::seconds`].
    pub stages: Vec<StageTiming>,
    /// Wall time of the whole call.
    pub seconds: f64,
    /// The cell size ℓ used.
    pub cell_size: f64,
    /// How ℓ was chosen, and why.
    pub cell_size_choice: CellSizeChoice,
    /// The input was clean (every validation layer) and is returned unchanged.
    pub clean_input: bool,
    /// Nested parts whose outside was relabelled with the material they lie in before
    /// anything else ([`place_nested`]): what a part drawn inside another and labelled
    /// against 0 means. When this is not empty, the other counts and ids of the report
    /// refer to the relabelled input.
    pub relabelled: Vec<Relabelled>,
    /// Live triangles of the input.
    pub triangles_in: usize,
    /// Live triangles of the output.
    pub triangles_out: usize,
    /// Fraction of the input triangles that are in the output exactly as they were
    /// (same corner positions and labels): 1 for a clean input.
    pub untouched_fraction: f64,
    /// Cells of the final flawed region.
    pub flawed_cells: usize,
    /// Safety-net restarts (§9.2).
    pub safety_rounds: usize,
    /// Sub-ℓ rounds, and the intersecting pairs they found.
    pub subcell_rounds: usize,
    /// Intersecting pairs found by the sub-ℓ pass over all rounds.
    pub subcell_pairs: usize,
    /// Edits of the local improvement.
    pub improve_edits: usize,
    /// What the improvement did, operation by operation (refusals and the guard's vetoes
    /// per kind included); `None` when it did not run.
    pub improvement: Option<ImproveReport>,
    /// Per material (label ≠ 0): the input's divergence-theorem volume (on an overlapping
    /// input, overlaps count once per material covering them) and the output's volume.
    pub volumes: Vec<LabelVolume>,
    /// Materials of the input with no volume in the output, or carried by no output
    /// triangle (see [`MaterialLoss::vanished`]).
    pub vanished: Vec<Label>,
    /// The output's total volume against the union of the input's materials.
    pub volume_check: VolumeCheck,
    /// Losses accepted with [`FixOptions::allow_loss`] (empty otherwise: a loss is an
    /// error).
    pub warnings: Vec<String>,
    /// Validation of the output (layers 1–3, and 4 with
    /// [`FixOptions::validate_intersections`]).
    pub validation: ValidationReport,
}

/// What [`fix_with`] returns: the repaired mesh (densely numbered), the report, and where
/// the repair acted.
#[derive(Clone, Debug)]
pub struct FixOutcome {
    /// The repaired mesh.
    pub mesh: LabeledMesh,
    /// What happened.
    pub report: FixReport,
    /// Ids (in the input) of the input triangles not kept exactly: removed, cut or
    /// improved. Empty for a clean input.
    pub changed_input: Vec<TriId>,
    /// Lattice coordinates of the final flawed region's cells, on [`Self::lattice`]:
    /// every changed input triangle meets one of them (cut triangles cross its boundary).
    pub flawed_cells: Vec<IVec3>,
    /// The grid lattice of the pass (`None` for a clean input: no pass ran).
    pub lattice: Option<Lattice>,
}

/// What a repair would lose: the materials that vanished and the volumes.
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialLoss {
    /// ℓ of the repair.
    pub cell_size: f64,
    /// The rule that chose ℓ: at a bound ([`CellSizeRule::is_bound`]) a finer ℓ is no
    /// remedy (the grid would exceed its budget), which the message says.
    pub cell_size_rule: CellSizeRule,
    /// Vanished materials with their input volumes: those with a bounded volume in the
    /// input and none in the output, and every label no output triangle carries any more
    /// (label 0 among them when the output is empty).
    pub vanished: Vec<LabelVolume>,
    /// The total-volume check.
    pub volume: VolumeCheck,
}

impl std::fmt::Display for MaterialLoss {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let mut parts: Vec<String> = self
            .vanished
            .iter()
            .map(|v| {
                if v.label == Label::OUTSIDE {
                    return "the output has no triangles left".to_string();
                }
                format!(
                    "material {} vanished (volume {} in the input, {} in the output)",
                    v.label.raw(),
                    shown(v.before),
                    shown(v.after)
                )
            })
            .collect();
        let c = &self.volume;
        if c.relative_change > c.tolerance {
            parts.push(format!(
                "total volume {} against {} for the union of the input's materials \
                 ({:+.2} %, tolerance {:.2} %)",
                shown(c.output),
                shown(c.reference),
                100.0 * (c.output - c.reference) / c.reference.abs().max(f64::MIN_POSITIVE),
                100.0 * c.tolerance
            ));
        }
        let remedy = if self.cell_size_rule.is_bound() {
            "ℓ is as fine as the grid's budget allows for this mesh (a finer --cell would \
             exceed it), so a material too thin for it cannot be kept in one repair; repair a \
             crop around it"
        } else {
            "a finer cell size (--cell) may keep it"
        };
        write!(
            f,
            "{} at ℓ = {}; {remedy}",
            parts.join("; "),
            shown(self.cell_size)
        )
    }
}

/// A volume or length for a message: six decimals, or three significant digits in
/// exponent form where six decimals would show nothing (a 10⁻³ cube has volume 10⁻⁹).
fn shown(x: f64) -> String {
    if x == 0.0 || x.abs() >= 1e-3 {
        format!("{x:.6}")
    } else {
        format!("{x:.3e}")
    }
}

/// Why a repair failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FixError {
    /// The input violates a precondition (open, dangling, degenerate, non-finite, …).
    #[error("invalid input mesh: {0}")]
    InvalidInput(String),
    /// A parameter is out of range.
    #[error("invalid parameter: {0}")]
    BadParams(String),
    /// A stage failed within its bounds.
    #[error("stage `{stage}` failed: {source}", stage = .0.stage(), source = .0)]
    Pipeline(#[from] PipelineError),
    /// The result failed validation (a bug: the safety net should have caught it).
    #[error("the repaired mesh is invalid: {0}")]
    InvalidOutput(String),
    /// The repair would lose a material or volume (see [`FixOptions::allow_loss`]).
    #[error("the repair loses material: {0}")]
    Loss(Box<MaterialLoss>),
}

/// Repairs `mesh` with cell size `cell_size` (`None`: [`default_cell_size`]) and the
/// default options: a clean, consistently labelled mesh whose overlaps became interfaces
/// (different labels) or merged volumes (equal labels).
pub fn fix(mesh: &LabeledMesh, cell_size: Option<f64>) -> Result<LabeledMesh, FixError> {
    let mut options = FixOptions::default();
    options.params.cell_size = cell_size;
    options.validate_intersections = false;
    fix_with(mesh, &options).map(|o| o.mesh)
}

/// Checks what the pipeline needs and cannot repair: topology (closed, no dangling,
/// degenerate or duplicate triangle, a sound corner table), a front ≠ back label on every
/// triangle, finite coordinates within the supported range. Inconsistent wedges and
/// zero-area triangles are defects the pass repairs, so they are allowed here. Returns the
/// report of layers 1–3.
fn check_fix_input(mesh: &LabeledMesh) -> Result<ValidationReport, FixError> {
    let r = validate(mesh, &ValidateOptions::default());
    let fatal = !(r.dangling_references.is_empty()
        && r.degenerate.is_empty()
        && r.duplicates.is_empty()
        && r.boundary_edges.is_empty()
        && r.corner_table.is_empty()
        && r.same_label_triangles.is_empty()
        && r.non_finite.is_empty()
        && r.out_of_range.is_empty());
    if fatal {
        return Err(FixError::InvalidInput(r.to_string()));
    }
    if mesh.num_triangles() == 0 {
        return Err(FixError::InvalidInput("the mesh has no triangles".into()));
    }
    Ok(r)
}

/// Relabels the nested parts of the input ([`place_nested`]) that layer 4 of validation
/// found misplaced, except parts that intersect another surface component: their
/// overlap is the repair's to resolve (a copy overlapping another also measures a wrong
/// outside, but it is not nested). Returns the relabelled mesh (`None`: unchanged).
///
/// Whether a part intersects another is asked only of the parts that could be relabelled,
/// and answered at the first intersecting pair: overlapping copies, the usual input of a
/// union, cost one tree over the triangles and a few queries, not an all-pairs check.
fn place_input(
    mesh: &LabeledMesh,
    report: &ValidationReport,
) -> Result<(Option<LabeledMesh>, Vec<Relabelled>), FixError> {
    if report
        .misplaced_shells
        .as_ref()
        .is_none_or(Listed::is_empty)
    {
        return Ok((None, Vec::new()));
    }
    let (component, count) = surface_components(mesh);
    let component_of = |t: TriId| component[t.idx()] as usize;
    // Built on the first question: the triangles of each component, and a tree over all.
    let index: OnceCell<(Vec<Vec<TriId>>, Option<Bvh>)> = OnceCell::new();
    let overlapping: RefCell<Vec<Option<bool>>> = RefCell::new(vec![None; count]);
    let may_relabel = |t: TriId| {
        let c = component_of(t);
        if let Some(known) = overlapping.borrow()[c] {
            return !known;
        }
        let (members, bvh) = index.get_or_init(|| {
            let mut members = vec![Vec::new(); count];
            for t in mesh.triangles() {
                members[component_of(t)].push(t);
            }
            let alive = mesh.tri_alive_flags();
            let bvh = Bvh::build_from_fn(mesh.triangle_capacity(), |i| {
                if alive[i as usize] {
                    Aabb::from_points(&mesh.tri_positions(TriId::new(i)))
                } else {
                    Aabb::EMPTY
                }
            })
            .ok();
            (members, bvh)
        });
        let hits = bvh.as_ref().is_none_or(|bvh| {
            members[c].iter().any(|&a| {
                let mut hit = false;
                let b = Aabb::from_points(&mesh.tri_positions(a));
                bvh.query(&b, 0.0, |u| {
                    let u = TriId::new(u);
                    hit = hit || (component_of(u) != c && triangles_intersect(mesh, a, u));
                });
                hit
            })
        });
        overlapping.borrow_mut()[c] = Some(hits);
        !hits
    };
    let (placed, relabelled) = place_nested(mesh, may_relabel)
        .map_err(|e| FixError::InvalidInput(format!("relabelling nested parts failed: {e}")))?;
    for r in &relabelled {
        tracing::info!("fix: {r}");
    }
    Ok((placed, relabelled))
}

/// Refuses a consistently labelled input whose unbounded outside is not label 0: a
/// material with a negative enclosed volume (every closed shell of a material facing
/// outward counts positive) means its faces' sides are the other way round. Why here:
/// the repair rebuilds from the grid, whose cells outside every shell are label 0, so
/// such an input would come back as an empty mesh; the user needs to hear that the labels
/// are swapped, not that ℓ was too coarse. An inconsistently labelled input is left to
/// the repair (its volumes mean nothing), and so is a clean one (returned unchanged).
fn check_outside_label(input: &ValidationReport, census: &MaterialCensus) -> Result<(), FixError> {
    if !input.inconsistent_edges.is_empty() {
        return Ok(());
    }
    let scale: f64 = census.volumes.values().map(|v| v.abs()).sum();
    let inverted = census
        .volumes
        .iter()
        .find(|(l, v)| **l != Label::OUTSIDE && **v < -1e-9 * scale);
    match inverted {
        Some((label, volume)) => Err(FixError::InvalidInput(format!(
            "material {} encloses a negative volume ({volume:.6}): its faces put it \
             outside them, but the unbounded outside must be label 0; are the front and \
             back labels swapped? (the front label is the material the normal \
             (v1−v0)×(v2−v0) points into)",
            label.raw()
        ))),
        None => Ok(()),
    }
}

/// Sum of the volumes of the bounded materials (labels ≠ 0).
fn bounded_total(census: &MaterialCensus) -> f64 {
    census
        .volumes
        .iter()
        .filter(|(l, _)| **l != Label::OUTSIDE)
        .map(|(_, v)| *v)
        .sum()
}

/// [`fix`] with every option, returning the report too.
pub fn fix_with(mesh: &LabeledMesh, options: &FixOptions) -> Result<FixOutcome, FixError> {
    let params = &options.params;
    params.check().map_err(FixError::BadParams)?;
    if !(options.volume_tolerance.is_finite() && options.volume_tolerance >= 0.0) {
        return Err(FixError::BadParams(format!(
            "volume_tolerance = {} must be finite and ≥ 0",
            options.volume_tolerance
        )));
    }
    let started = Instant::now();
    let deadline = params.time_budget.map(|b| started + b);
    let mut timings = Timings::default();
    let input_report = timings.time("validate", || check_fix_input(mesh))?;
    let original_triangles = mesh.num_triangles();
    let (placed, relabelled) = timings.time("placement", || place_input(mesh, &input_report))?;
    let (mesh, input_report) = match &placed {
        Some(placed) => (
            placed,
            timings.time("validate", || check_fix_input(placed))?,
        ),
        None => (mesh, input_report),
    };
    let choice = match params.cell_size {
        Some(l) => CellSizeChoice::given(l),
        None => timings.time("scale", || default_cell_size(mesh)),
    };
    let cell_size = choice.cell_size;
    if !(cell_size.is_finite() && cell_size > 0.0) {
        return Err(FixError::BadParams(format!(
            "cell size ℓ = {cell_size} must be finite and > 0 ({})",
            choice.reason
        )));
    }
    let before = timings.time("volumes", || MaterialCensus::of(mesh));
    timings.check_budget(params.time_budget, "volumes")?;

    // A clean input needs no repair: returned as it is, whatever ℓ. Layers 1–3 have run;
    // layer 4 only needs a yes or no, which an input that needs repair answers at its
    // first intersecting pair.
    if input_report.is_valid() {
        let intersects = timings.time("validate", || any_intersection(mesh));
        timings.check_budget(params.time_budget, "validate")?;
        if !intersects {
            let mut full = input_report;
            full.self_intersecting_pairs = Some(Listed::default());
            let touched: usize = relabelled.iter().map(|r| r.relabelled_triangles).sum();
            let mut outcome = clean_outcome(started, mesh, options, choice, before, full, timings);
            if !relabelled.is_empty() {
                let report = &mut outcome.report;
                report.clean_input = false;
                report.triangles_in = original_triangles;
                report.untouched_fraction = 1.0 - touched as f64 / original_triangles.max(1) as f64;
                report.relabelled = relabelled;
            }
            return Ok(outcome);
        }
    }

    check_outside_label(&input_report, &before)?;

    let (pass, choice) = pass_within_grid_budget(mesh, params, choice, &mut timings)?;
    let cell_size = choice.cell_size;
    let stats: PassStats = pass.stats;
    let mut out = pass.mesh;
    timings.check_budget(params.time_budget, "pass")?;
    // The reference reads only the input, and improvement is mostly serial: measured
    // beside it, on the core improvement leaves idle, the loss check costs next to no wall
    // time (0.2 s of about 2 s on the README's six copies when it ran on its own).
    let (reference, improvement) = rayon::join(
        || {
            let start = Instant::now();
            (union_volume(mesh), start.elapsed())
        },
        || {
            improve_repaired(
                &mut out,
                params,
                cell_size,
                &pass.created,
                deadline,
                &mut timings,
            )
        },
    );
    let (reference, reference_time) = reference;
    timings.add_overlapped("reference", reference_time);
    let improvement = improvement?;
    let improve_edits = improvement.as_ref().map_or(0, ImproveReport::edits);
    let changed_input: Vec<TriId> = mesh
        .triangles()
        .filter(|&t| !is_same_triangle(mesh, &out, t))
        .collect();
    let untouched = mesh.num_triangles() - changed_input.len();
    out.compact();
    let validation = timings.time("validate", || {
        validate(
            &out,
            &ValidateOptions {
                intersections: options.validate_intersections,
                ..ValidateOptions::default()
            },
        )
    });
    timings.check_budget(params.time_budget, "validate")?;
    let layers_1_to_3_ok = validation.dangling_references.is_empty()
        && validation.degenerate.is_empty()
        && validation.duplicates.is_empty()
        && validation.boundary_edges.is_empty()
        && validation.corner_table.is_empty()
        && validation.same_label_triangles.is_empty()
        && validation.inconsistent_edges.is_empty()
        && validation.non_finite.is_empty()
        && validation.out_of_range.is_empty()
        && validation.zero_area.is_empty();
    if !layers_1_to_3_ok {
        return Err(FixError::InvalidOutput(validation.to_string()));
    }
    let after = timings.time("volumes", || MaterialCensus::of(&out));
    let output = bounded_total(&after);
    let (reference, method, spacing) = match reference {
        Some(r) => (r.volume, ReferenceMethod::LineIntegral, r.spacing),
        // No extent in two axes: nothing is enclosed.
        None => (0.0, ReferenceMethod::LineIntegral, 0.0),
    };
    let volume_check = VolumeCheck {
        reference,
        method,
        spacing,
        output,
        relative_change: relative_change(output, reference),
        tolerance: options.volume_tolerance,
    };
    let volumes = before.volumes_to(&after);
    // A material of the input with a bounded volume there and none left, or one that no
    // output triangle carries any more whatever its input volume: a material enclosing no
    // volume (a flat shell) or an inconsistently labelled one (whose volume means nothing)
    // is still the user's data, and an output that dropped every triangle lost the outside
    // (label 0) too.
    let gone = before.vanished_in(&after);
    let vanished: Vec<LabelVolume> = volumes
        .iter()
        .filter(|v| (v.before > 0.0 && v.after <= 0.0) || gone.contains(&v.label))
        .copied()
        .chain(gone.contains(&Label::OUTSIDE).then(|| LabelVolume {
            label: Label::OUTSIDE,
            before: before.volumes[&Label::OUTSIDE],
            after: 0.0,
        }))
        .collect();
    let mut warnings = Vec::new();
    if !vanished.is_empty() || volume_check.relative_change > volume_check.tolerance {
        let loss = MaterialLoss {
            cell_size,
            cell_size_rule: choice.rule,
            vanished: vanished.clone(),
            volume: volume_check.clone(),
        };
        if !options.allow_loss {
            return Err(FixError::Loss(Box::new(loss)));
        }
        tracing::warn!("fix: accepted loss: {loss}");
        warnings.push(format!("accepted loss: {loss}"));
    }
    let triangles_in = mesh.num_triangles();
    let report = FixReport {
        stages: timings.into_stages(),
        seconds: started.elapsed().as_secs_f64(),
        cell_size,
        cell_size_choice: choice,
        clean_input: false,
        relabelled,
        triangles_in,
        triangles_out: out.num_triangles(),
        untouched_fraction: untouched as f64 / triangles_in.max(1) as f64,
        flawed_cells: stats.flawed_cells,
        safety_rounds: stats.safety_rounds,
        subcell_rounds: stats.subcell_rounds,
        subcell_pairs: stats.subcell_pairs,
        improve_edits,
        improvement,
        volumes,
        vanished: vanished.iter().map(|v| v.label).collect(),
        volume_check,
        warnings,
        validation,
    };
    Ok(FixOutcome {
        mesh: out,
        report,
        changed_input,
        flawed_cells: pass.region_cells,
        lattice: Some(pass.lattice),
    })
}

/// Coarsenings of a chosen ℓ that [`pass_within_grid_budget`] tries before it gives up.
const MAX_BUDGET_COARSENINGS: usize = 4;

/// The repair pass at `choice`'s ℓ, coarsened while the grid would exceed its incidence
/// budget and ℓ was not given: the default ℓ comes from edge lengths and thicknesses,
/// which do not foresee how many cells the boxes of large slanted triangles cover (a rod
/// through a coarse sphere: 4·10⁹ incidences), and the user asked for a repair, not for a
/// cell size. Each try scales ℓ by the cube root of the excess (box cells scale as ℓ⁻³,
/// surface cells as ℓ⁻²), with 10 % to spare; a material the coarser ℓ cannot hold is
/// then reported as a loss, naming the bound.
fn pass_within_grid_budget(
    mesh: &LabeledMesh,
    params: &GridParams,
    mut choice: CellSizeChoice,
    timings: &mut Timings,
) -> Result<(PassOutcome, CellSizeChoice), FixError> {
    let mut tries = 0;
    loop {
        let pass = run_pass(
            mesh.clone(),
            &VertexAttributes::none(),
            None,
            params,
            choice.cell_size,
            params.step_seed(0),
            timings,
        );
        match pass {
            Err(PipelineError::Grid(GridError::TooManyCells { needed, limit }))
                if choice.rule != CellSizeRule::Given && tries < MAX_BUDGET_COARSENINGS =>
            {
                tries += 1;
                let factor = 1.1 * (needed as f64 / limit.max(1) as f64).cbrt();
                let cell_size = choice.cell_size * factor.max(1.1);
                choice = CellSizeChoice {
                    cell_size,
                    rule: CellSizeRule::GridBudget,
                    thinnest: choice.thinnest,
                    reason: format!(
                        "{}; coarsened to ℓ = {cell_size:.4}: at ℓ = {:.4} the grid needed \
                         {needed} cell–triangle incidences, above its budget of {limit}",
                        choice.reason, choice.cell_size
                    ),
                };
            }
            other => return Ok((other?, choice)),
        }
    }
}

/// Improves the rebuilt mesh `out` of a [`fix_with`] (when [`GridParams::improve`] asks
/// for it).
fn improve_repaired(
    out: &mut LabeledMesh,
    params: &GridParams,
    cell_size: f64,
    created: &[TriId],
    deadline: Option<Instant>,
    timings: &mut Timings,
) -> Result<Option<ImproveReport>, FixError> {
    let Some(ip) = &params.improve else {
        return Ok(None);
    };
    let r = timings.time("improve", || {
        improve_mesh(
            out,
            &mut VertexAttributes::none(),
            params,
            ip,
            cell_size,
            created,
            deadline,
        )
    });
    timings.check_budget(params.time_budget, "improve")?;
    Ok(r)
}

/// `|output − reference| / |reference|`, 0 when both vanish, infinite when only the
/// reference does.
fn relative_change(output: f64, reference: f64) -> f64 {
    let d = (output - reference).abs();
    if d == 0.0 {
        0.0
    } else if reference == 0.0 {
        f64::INFINITY
    } else {
        d / reference.abs()
    }
}

/// The outcome for a clean input: the input itself, every volume unchanged.
fn clean_outcome(
    started: Instant,
    mesh: &LabeledMesh,
    options: &FixOptions,
    choice: CellSizeChoice,
    census: MaterialCensus,
    validation: ValidationReport,
    timings: Timings,
) -> FixOutcome {
    let mut out = mesh.clone();
    out.compact();
    let total = bounded_total(&census);
    let n = mesh.num_triangles();
    let report = FixReport {
        stages: timings.into_stages(),
        seconds: started.elapsed().as_secs_f64(),
        cell_size: choice.cell_size,
        cell_size_choice: choice,
        clean_input: true,
        relabelled: Vec::new(),
        triangles_in: n,
        triangles_out: n,
        untouched_fraction: 1.0,
        flawed_cells: 0,
        safety_rounds: 0,
        subcell_rounds: 0,
        subcell_pairs: 0,
        improve_edits: 0,
        improvement: None,
        volumes: census.volumes_to(&census),
        vanished: Vec::new(),
        volume_check: VolumeCheck {
            reference: total,
            method: ReferenceMethod::CleanInput,
            spacing: 0.0,
            output: total,
            relative_change: 0.0,
            tolerance: options.volume_tolerance,
        },
        warnings: Vec::new(),
        validation,
    };
    FixOutcome {
        mesh: out,
        report,
        changed_input: Vec::new(),
        flawed_cells: Vec::new(),
        lattice: None,
    }
}

/// Whether input triangle `t` is in `out` at the same slot with the same corner positions
/// and labels (the pass keeps the ids of everything it does not touch).
fn is_same_triangle(a: &LabeledMesh, b: &LabeledMesh, t: TriId) -> bool {
    t.idx() < b.triangle_capacity()
        && b.is_triangle_alive(t)
        && a.labels(t) == b.labels(t)
        && a.tri_positions(t) == b.tri_positions(t)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A slanted rod 0.3 × 0.3 × 20 through a box: ℓ from the rod's thickness makes its
    /// twelve long triangles' boxes cover about 10⁹ cells, far above the grid's budget.
    /// The default ℓ is coarsened until the grid fits, and the repair keeps both
    /// materials; a given ℓ is not changed behind the user's back.
    #[test]
    fn a_default_cell_size_over_the_grid_budget_is_coarsened_until_it_fits() {
        use glam::{DQuat, DVec3};
        let l = Label::new;
        let boxed =
            mesh_core::generators::cuboid(DVec3::splat(-1.0), DVec3::splat(1.0), [l(0), l(1)])
                .unwrap();
        let rod = mesh_core::generators::cuboid(
            DVec3::new(-0.15, -0.15, -10.0),
            DVec3::new(0.15, 0.15, 10.0),
            [l(0), l(2)],
        )
        .unwrap();
        let (p, t, labels) = rod.to_raw();
        let turn = DQuat::from_euler(glam::EulerRot::XYZ, 0.7, 0.5, 0.3);
        let p: Vec<DVec3> = p.into_iter().map(|p| turn * p).collect();
        let rod = LabeledMesh::from_raw(p, &t, &labels).unwrap();
        let mesh = LabeledMesh::disjoint_union(&[boxed, rod]).unwrap();

        let out = fix_with(&mesh, &FixOptions::default()).expect("coarsened, repaired");
        let choice = &out.report.cell_size_choice;
        assert_eq!(choice.rule, CellSizeRule::GridBudget, "{}", choice.reason);
        assert!(choice.reason.contains("coarsened"), "{}", choice.reason);
        assert!(
            out.report.validation.is_valid(),
            "{}",
            out.report.validation
        );
        assert!(out.report.vanished.is_empty());
        assert!(out.report.volume_check.relative_change < 0.02);

        let given = FixOptions {
            params: GridParams {
                cell_size: Some(0.02),
                ..FixOptions::default().params
            },
            ..FixOptions::default()
        };
        let refused = fix_with(&mesh, &given).unwrap_err();
        assert!(refused.to_string().contains("incidences"), "{refused}");
    }

    /// A loss message shows a tiny volume in exponent form (not as 0.000000) and, when ℓ
    /// sat at its surface-cell bound, says a finer `--cell` is no remedy.
    #[test]
    fn a_loss_names_tiny_volumes_and_the_remedy_that_applies() {
        let loss = |rule| MaterialLoss {
            cell_size: 0.0012,
            cell_size_rule: rule,
            vanished: vec![LabelVolume {
                label: Label::new(2),
                before: 1e-9,
                after: 0.0,
            }],
            volume: VolumeCheck {
                reference: 1.0,
                method: ReferenceMethod::LineIntegral,
                spacing: 0.01,
                output: 1.0,
                relative_change: 0.0,
                tolerance: 0.02,
            },
        };
        let bound = loss(CellSizeRule::SurfaceCellBound).to_string();
        assert!(
            bound.contains("volume 1.000e-9 in the input, 0.000000 in the output"),
            "{bound}"
        );
        assert!(bound.contains("ℓ = 0.001200"), "{bound}");
        assert!(
            bound.contains("repair a crop") && !bound.contains("--cell)"),
            "{bound}"
        );
        let thin = loss(CellSizeRule::ThinnestMaterial).to_string();
        assert!(
            thin.contains("a finer cell size (--cell) may keep it"),
            "{thin}"
        );
    }
}
