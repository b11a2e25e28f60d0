//! One-shot repair and multi-material union (§9.5): [`fix`] / [`fix_with`].
//!
//! A tangled mesh — overlapping copies of shapes, an inside-out region, a self-intersecting
//! deformation — goes through one pass of the pipeline with no motion: every region the
//! grid finds flawed is cut out and rebuilt, every exact intersection finer than ℓ is found
//! by one test over the whole mesh and repaired the same way, and everything else is kept
//! as it was. Improvement (§8.5) is restricted to the triangles the pass created
//! ([`crate::ImproveScope::Changed`]), so a clean input comes out with every triangle
//! untouched.

use glam::IVec3;
use mesh_core::remesh::{VertexAttributes, improve::mean_edge_length};
use mesh_core::validate::{ValidateOptions, ValidationReport, validate};
use mesh_core::{LabeledMesh, StageTiming, TriId};

use crate::params::{GridParams, ImproveScope};
use crate::pipeline::{PassStats, PipelineError, Timings, improve_mesh, run_pass};
use crate::stages::grid::Lattice;

/// Options of [`fix_with`].
#[derive(Clone, Debug, PartialEq)]
pub struct FixOptions {
    /// The pipeline's parameters. Default: [`GridParams::default`] with improvement
    /// restricted to the rebuilt parts ([`ImproveScope::Changed`]).
    pub params: GridParams,
    /// Also check the output for exact self-intersections (layer 4 of
    /// [`mesh_core::validate`]) for the report. Default true: a one-shot repair can afford
    /// it, and it is the figure a user of `fix` wants.
    pub validate_intersections: bool,
}

impl Default for FixOptions {
    fn default() -> Self {
        Self {
            params: GridParams {
                improve_scope: ImproveScope::Changed,
                ..GridParams::default()
            },
            validate_intersections: true,
        }
    }
}

/// What [`fix_with`] did (the CLI's `surftrack fix --json` record).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct FixReport {
    /// Wall time per stage, in pipeline order.
    pub stages: Vec<StageTiming>,
    /// The cell size ℓ used.
    pub cell_size: f64,
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
    /// The grid lattice of the pass.
    pub lattice: Lattice,
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
}

/// Repairs `mesh` with cell size `cell_size` (`None`: the mean edge length) and the
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
/// triangle, finite coordinates. Inconsistent wedges and zero-area triangles are defects
/// the pass repairs, so they are allowed here.
fn check_fix_input(mesh: &LabeledMesh) -> Result<(), FixError> {
    let r = validate(mesh, &ValidateOptions::default());
    let fatal = !(r.dangling_references.is_empty()
        && r.degenerate.is_empty()
        && r.duplicates.is_empty()
        && r.boundary_edges.is_empty()
        && r.corner_table.is_empty()
        && r.same_label_triangles.is_empty()
        && r.non_finite.is_empty());
    if fatal {
        return Err(FixError::InvalidInput(r.to_string()));
    }
    if mesh.num_triangles() == 0 {
        return Err(FixError::InvalidInput("the mesh has no triangles".into()));
    }
    Ok(())
}

/// [`fix`] with every option, returning the report too.
pub fn fix_with(mesh: &LabeledMesh, options: &FixOptions) -> Result<FixOutcome, FixError> {
    let params = &options.params;
    params.check().map_err(FixError::BadParams)?;
    check_fix_input(mesh)?;
    let cell_size = match params.cell_size {
        Some(l) => l,
        None => mean_edge_length(mesh),
    };
    if !(cell_size.is_finite() && cell_size > 0.0) {
        return Err(FixError::BadParams(format!(
            "cell size ℓ = {cell_size} must be finite and > 0"
        )));
    }
    let mut timings = Timings::default();
    let pass = run_pass(
        mesh.clone(),
        &VertexAttributes::none(),
        None,
        params,
        cell_size,
        params.step_seed(0),
        &mut timings,
    )?;
    let stats: PassStats = pass.stats;
    let mut out = pass.mesh;
    timings.check_budget(params.time_budget, "pass")?;
    let mut improve_edits = 0;
    if let Some(ip) = &params.improve {
        let r = timings.time("improve", || {
            improve_mesh(
                &mut out,
                &mut VertexAttributes::none(),
                params,
                ip,
                cell_size,
                &pass.created,
            )
        });
        if let Some(r) = r {
            improve_edits = r.split.done
                + r.collapse.done
                + r.flip.done
                + r.smooth.done
                + r.separations
                + r.pinched;
        }
    }
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
    let layers_1_to_3_ok = validation.dangling_references.is_empty()
        && validation.degenerate.is_empty()
        && validation.duplicates.is_empty()
        && validation.boundary_edges.is_empty()
        && validation.corner_table.is_empty()
        && validation.same_label_triangles.is_empty()
        && validation.inconsistent_edges.is_empty()
        && validation.non_finite.is_empty()
        && validation.zero_area.is_empty();
    if !layers_1_to_3_ok {
        return Err(FixError::InvalidOutput(validation.to_string()));
    }
    let triangles_in = mesh.num_triangles();
    let report = FixReport {
        stages: timings.into_stages(),
        cell_size,
        triangles_in,
        triangles_out: out.num_triangles(),
        untouched_fraction: untouched as f64 / triangles_in.max(1) as f64,
        flawed_cells: stats.flawed_cells,
        safety_rounds: stats.safety_rounds,
        subcell_rounds: stats.subcell_rounds,
        subcell_pairs: stats.subcell_pairs,
        improve_edits,
        validation,
    };
    Ok(FixOutcome {
        mesh: out,
        report,
        changed_input,
        flawed_cells: pass.region_cells,
        lattice: pass.lattice,
    })
}

/// Whether input triangle `t` is in `out` at the same slot with the same corner positions
/// and labels (the pass keeps the ids of everything it does not touch).
fn is_same_triangle(a: &LabeledMesh, b: &LabeledMesh, t: TriId) -> bool {
    t.idx() < b.triangle_capacity()
        && b.is_triangle_alive(t)
        && a.labels(t) == b.labels(t)
        && a.tri_positions(t) == b.tri_positions(t)
}
