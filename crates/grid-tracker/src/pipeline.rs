//! One pass of the algorithm of Heiss-Synak et al. 2024 (§3, Fig. 2) on a mesh that has
//! already been moved, plus local mesh improvement (§8.5):
//!
//! ```text
//! grid → materials → flaws                      §4–§6, once per pass
//! subcell: exact pairs among the moved triangles → their cells join the region
//! loop (bounded):
//!     cut → labels → rebuild                    §7, §8.1–8.3, from the moved mesh
//!     safety: a stage's inconsistency, or layers 1–3 of validate() failing
//!             → cells join the region, redo                   (§9.2)
//!     subcell: exact pairs between the new triangles and all near them
//!             → cells join the region, redo                   (beyond the paper)
//! transfer                                      §8.4, PIC, once the region is final
//! ```
//!
//! Every retry starts again from the moved mesh, so a failed attempt leaves nothing
//! behind; the two counters bound the loop, so a pass always terminates.

use std::time::{Duration, Instant};

use glam::IVec3;
use mesh_core::remesh::{
    Applied, Edit, EditGuard, ImproveParams, ImproveRegion, ImproveReport, NoGuard,
    StaticIntersectionGuard, VertexAttributes, Veto, improve_in_blocks,
};
use mesh_core::validate::{ValidateOptions, validate};
use mesh_core::{LabeledMesh, StageTiming, TriId, VertexId};

use crate::params::{GridParams, ImproveScope, SubcellPass};
use crate::safety::{add_cells, inconsistency_cells, intersecting_pairs, pair_cells};
use crate::stages::cut::{CutOptions, cut_mesh};
use crate::stages::flaws::{FlawError, FlawedRegion, Resampling, detect_flaws};
use crate::stages::grid::{Grid, GridError, GridOptions, Lattice, build_grid};
use crate::stages::labels::correct_labels_with;
use crate::stages::materials::{MaterialError, MaterialOptions, Materials, assign_materials};
use crate::stages::rebuild::rebuild_region;
use crate::stages::transfer::{OldVertices, transfer_pic};

/// Offenders listed per category when the safety net validates a rebuilt mesh: enough to
/// locate every defect of a realistic step (the counts stay exact either way).
const SAFETY_LISTED: usize = 1 << 14;

/// Wall time per stage, summed over retries, in order of first appearance.
#[derive(Clone, Debug, Default)]
pub(crate) struct Timings {
    stages: Vec<StageTiming>,
    /// Seconds of the stages that ran beside others ([`Timings::add_overlapped`]): part
    /// of `stages`, but not of the time the budget counts.
    overlapped: f64,
}

impl Timings {
    /// Adds `elapsed` to `stage`.
    pub(crate) fn add(&mut self, stage: &'static str, elapsed: Duration) {
        let s = elapsed.as_secs_f64();
        match self.stages.iter_mut().find(|t| t.stage == stage) {
            Some(t) => t.seconds += s,
            None => self.stages.push(StageTiming { stage, seconds: s }),
        }
    }

    /// Adds `elapsed` to `stage`, a stage that ran beside the others (on another core):
    /// listed with them, but its seconds did not add to the wall time, so the budget
    /// does not count them.
    pub(crate) fn add_overlapped(&mut self, stage: &'static str, elapsed: Duration) {
        self.overlapped += elapsed.as_secs_f64();
        self.add(stage, elapsed);
    }

    /// Runs `f`, timing it as `stage`.
    pub(crate) fn time<T>(&mut self, stage: &'static str, f: impl FnOnce() -> T) -> T {
        let start = Instant::now();
        let out = f();
        self.add(stage, start.elapsed());
        out
    }

    /// Fails once the seconds timed so far reach `budget` ([`GridParams::time_budget`]);
    /// called at stage boundaries, so a step overshoots by at most one stage.
    pub(crate) fn check_budget(
        &self,
        budget: Option<Duration>,
        stage: &'static str,
    ) -> Result<(), PipelineError> {
        match budget {
            Some(budget)
                if self.stages.iter().map(|s| s.seconds).sum::<f64>() - self.overlapped
                    >= budget.as_secs_f64() =>
            {
                Err(PipelineError::TimeBudget { stage, budget })
            }
            _ => Ok(()),
        }
    }

    /// The timings.
    pub(crate) fn into_stages(self) -> Vec<StageTiming> {
        self.stages
    }
}

/// What one pass did, for reports.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PassStats {
    /// ℓ used.
    pub cell_size: f64,
    /// Cells of the final flawed region (allocated or not).
    pub flawed_cells: usize,
    /// Faces of its boundary.
    pub boundary_faces: usize,
    /// Safety-net restarts (§9.2).
    pub safety_rounds: usize,
    /// Sub-ℓ rounds that found intersections and grew the region.
    pub subcell_rounds: usize,
    /// Intersecting pairs the sub-ℓ pass found, over all rounds.
    pub subcell_pairs: usize,
    /// Intersecting pairs left after the last round (only with [`SubcellPass::Repair`]).
    pub remaining_intersections: usize,
    /// Triangles of the moved mesh removed by cutting.
    pub removed_triangles: usize,
    /// Triangles created by cutting and rebuilding.
    pub new_triangles: usize,
}

/// Why a pass failed. The input mesh is untouched in every case.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PipelineError {
    /// §4: the grid could not be built.
    #[error(transparent)]
    Grid(#[from] GridError),
    /// §5: materials could not be assigned.
    #[error(transparent)]
    Materials(#[from] MaterialError),
    /// §6: flaws could not be detected.
    #[error(transparent)]
    Flaws(#[from] FlawError),
    /// A stage stayed inconsistent through every safety-net round (§9.2), or reported an
    /// inconsistency without cells to grow the region by.
    #[error("stage `{stage}` stayed inconsistent after {rounds} safety-net rounds: {reason}")]
    Inconsistent {
        /// The last stage that failed.
        stage: &'static str,
        /// Rounds run.
        rounds: usize,
        /// Its last error.
        reason: String,
    },
    /// Intersections finer than ℓ remained after every sub-ℓ round.
    #[error("{pairs} intersecting triangle pairs remain after {rounds} sub-ℓ rounds")]
    Intersections {
        /// Pairs left.
        pairs: usize,
        /// Rounds run.
        rounds: usize,
    },
    /// §8.4: attributes could not be transferred.
    #[error("attribute transfer failed: {0}")]
    Transfer(String),
    /// [`GridParams::time_budget`] ran out; `stage` is the last stage that completed.
    #[error("time budget of {budget:?} exceeded after stage `{stage}`")]
    TimeBudget {
        /// The stage.
        stage: &'static str,
        /// The budget.
        budget: Duration,
    },
}

impl PipelineError {
    /// The stage name to report (matches the timing names).
    pub fn stage(&self) -> &'static str {
        match self {
            PipelineError::Grid(_) => "grid",
            PipelineError::Materials(_) => "materials",
            PipelineError::Flaws(_) => "flaws",
            PipelineError::Inconsistent { stage, .. } => stage,
            PipelineError::Intersections { .. } => "subcell",
            PipelineError::Transfer(_) => "transfer",
            PipelineError::TimeBudget { stage, .. } => stage,
        }
    }
}

/// The result of a pass.
pub(crate) struct PassOutcome {
    /// The repaired mesh (the moved mesh itself when nothing was flawed).
    pub mesh: LabeledMesh,
    /// Attributes following it (new vertices by PIC transfer).
    pub attrs: VertexAttributes,
    /// Live triangles this pass created (cut pieces and rebuilt triangles).
    pub created: Vec<TriId>,
    /// The final flawed region's cells.
    pub region_cells: Vec<IVec3>,
    /// The grid lattice of the pass.
    pub lattice: Lattice,
    /// Counts.
    pub stats: PassStats,
}

/// A local inconsistency: where, found by which stage, and why.
struct Inconsistency {
    stage: &'static str,
    cells: Vec<IVec3>,
    reason: String,
}

/// One cut → labels → rebuild attempt.
struct Attempt {
    mesh: LabeledMesh,
    created: Vec<TriId>,
    new_vertices: Vec<VertexId>,
    removed: usize,
}

/// Runs one pass on `moved` (see the module doc). `changed`: the triangles whose geometry
/// changed since the last clean state (`None`: all of them), the ones the sub-ℓ pass tests
/// before cutting.
pub(crate) fn run_pass(
    moved: LabeledMesh,
    attrs: &VertexAttributes,
    changed: Option<&[TriId]>,
    params: &GridParams,
    cell_size: f64,
    seed: u64,
    timings: &mut Timings,
) -> Result<PassOutcome, PipelineError> {
    let grid_options = GridOptions {
        perturbation: params.perturbation,
        seed,
        ..GridOptions::default()
    };
    let grid = timings.time("grid", || build_grid(&moved, cell_size, &grid_options))?;
    let materials = timings.time("materials", || {
        assign_materials(&moved, &grid, &MaterialOptions::default())
    })?;
    let mut region = timings.time("flaws", || {
        detect_flaws(&moved, &grid, &materials, &params.flaws)
    })?;
    timings.check_budget(params.time_budget, "flaws")?;
    let mut stats = PassStats {
        cell_size,
        ..PassStats::default()
    };
    let lattice = *grid.lattice();

    // Ablation (Fig. 17b): global resampling rebuilds every cell the surface touches.
    if params.resampling == Resampling::Global {
        let cells: Vec<IVec3> = grid
            .cells()
            .filter(|&c| !grid.cell_triangles(c).is_empty())
            .map(|c| grid.cell_coord(c))
            .collect();
        timings.time("flaws", || {
            add_cells(&mut region, &moved, &grid, &materials, &cells)
        });
    }

    // Beyond the paper: overlaps thinner than ℓ among the moved triangles.
    if params.subcell != SubcellPass::Off {
        let pairs = timings.time("subcell", || intersecting_pairs(&moved, changed));
        if !pairs.is_empty() {
            stats.subcell_pairs += pairs.len();
            let cells = pair_cells(&moved, &lattice, &pairs);
            timings.time("subcell", || {
                add_cells(&mut region, &moved, &grid, &materials, &cells)
            });
        }
    }

    // Each iteration either returns or spends one round of one of the two budgets.
    let rounds = params.max_safety_rounds + params.max_subcell_rounds + 1;
    for _ in 0..rounds {
        timings.check_budget(params.time_budget, "safety")?;
        let attempt = if region.is_empty() {
            // Nothing flawed: the moved mesh is the result if it passes the safety check
            // (a zero-area triangle or a tangled junction finer than the rays can be
            // there even so; it makes the region non-empty and the loop goes on).
            match check_mesh(&moved, &lattice, timings) {
                Ok(()) => {
                    return Ok(PassOutcome {
                        mesh: moved,
                        attrs: attrs.clone(),
                        created: Vec::new(),
                        region_cells: Vec::new(),
                        lattice,
                        stats,
                    });
                }
                Err(inc) => Err(inc),
            }
        } else {
            replace_region(&moved, &grid, &materials, &region, params, timings)
                .and_then(|a| check_mesh(&a.mesh, &lattice, timings).map(|()| a))
        };
        let attempt = match attempt {
            Ok(a) => a,
            Err(inc) => {
                stats.safety_rounds += 1;
                let grown = if stats.safety_rounds > params.max_safety_rounds {
                    0
                } else {
                    timings.time("safety", || {
                        add_cells(&mut region, &moved, &grid, &materials, &inc.cells)
                    })
                };
                if grown == 0 {
                    return Err(PipelineError::Inconsistent {
                        stage: inc.stage,
                        rounds: stats.safety_rounds,
                        reason: inc.reason,
                    });
                }
                continue;
            }
        };
        if params.subcell != SubcellPass::Off {
            let pairs = timings.time("subcell", || {
                intersecting_pairs(&attempt.mesh, Some(&attempt.created))
            });
            if !pairs.is_empty() {
                stats.subcell_pairs += pairs.len();
                let grown = if stats.subcell_rounds >= params.max_subcell_rounds {
                    0
                } else {
                    stats.subcell_rounds += 1;
                    let cells = pair_cells(&attempt.mesh, &lattice, &pairs);
                    timings.time("subcell", || {
                        add_cells(&mut region, &moved, &grid, &materials, &cells)
                    })
                };
                if grown > 0 {
                    continue;
                }
                if params.subcell == SubcellPass::Require {
                    return Err(PipelineError::Intersections {
                        pairs: pairs.len(),
                        rounds: stats.subcell_rounds,
                    });
                }
                stats.remaining_intersections = pairs.len();
            }
        }
        stats.flawed_cells = region.len();
        stats.boundary_faces = region.boundary_faces().len();
        stats.removed_triangles = attempt.removed;
        stats.new_triangles = attempt.created.len();
        let attrs = timings.time("transfer", || {
            transfer(&moved, attrs, &grid, &region, &attempt)
        })?;
        return Ok(PassOutcome {
            mesh: attempt.mesh,
            attrs,
            created: attempt.created,
            region_cells: region.cells().collect(),
            lattice,
            stats,
        });
    }
    Err(PipelineError::Inconsistent {
        stage: "safety",
        rounds: stats.safety_rounds,
        reason: format!(
            "no clean result within {rounds} rounds ({} sub-ℓ)",
            stats.subcell_rounds
        ),
    })
}

/// §7–§8.3: cuts the flawed region out of `moved`, labels the grid, rebuilds the region.
fn replace_region(
    moved: &LabeledMesh,
    grid: &Grid,
    materials: &Materials,
    region: &FlawedRegion,
    params: &GridParams,
    timings: &mut Timings,
) -> Result<Attempt, Inconsistency> {
    let mut cut = timings
        .time("cut", || {
            cut_mesh(moved, grid, materials, region, &CutOptions::default())
        })
        .map_err(|e| Inconsistency {
            stage: "cut",
            cells: e.cells().to_vec(),
            reason: e.to_string(),
        })?;
    let labels = timings
        .time("labels", || {
            correct_labels_with(moved, grid, materials, region, params.label_correction)
        })
        .map_err(|e| Inconsistency {
            // Not local (mismatched inputs, size limits): no cells, so no retry.
            stage: "labels",
            cells: Vec::new(),
            reason: e.to_string(),
        })?;
    let mut mesh = std::mem::take(&mut cut.mesh);
    let rebuilt = timings
        .time("rebuild", || {
            rebuild_region(
                &mut mesh,
                cut.boundary(),
                &cut.edge_points,
                grid,
                materials,
                region,
                &labels,
                &params.rebuild,
            )
        })
        .map_err(|e| Inconsistency {
            stage: "rebuild",
            cells: e.cells().to_vec(),
            reason: e.to_string(),
        })?;
    let mut created: Vec<TriId> = cut
        .new_triangles
        .iter()
        .chain(&rebuilt.new_triangles)
        .copied()
        .filter(|&t| mesh.is_triangle_alive(t))
        .collect();
    created.sort_unstable();
    created.dedup();
    let mut new_vertices: Vec<VertexId> = cut
        .new_vertices
        .iter()
        .chain(&rebuilt.new_vertices)
        .copied()
        .filter(|&v| mesh.is_vertex_alive(v))
        .collect();
    new_vertices.sort_unstable();
    new_vertices.dedup();
    let removed = moved
        .triangles()
        .filter(|&t| !mesh.is_triangle_alive(t) || created.binary_search(&t).is_ok())
        .count();
    Ok(Attempt {
        mesh,
        created,
        new_vertices,
        removed,
    })
}

/// The safety net's own check (§9.2): layers 1–4 of validation; any defect becomes an
/// inconsistency at the cells of its triangles. Placement (layer 4) included: a closed
/// component smaller than a cell crosses no grid edge, so the grid keeps it as it is
/// (§6.3, small features persist) whatever its labels, and motion can carry it out of
/// the material its outside names; its cells rebuilt from the grid's labels drop it.
fn check_mesh(
    mesh: &LabeledMesh,
    lattice: &Lattice,
    timings: &mut Timings,
) -> Result<(), Inconsistency> {
    let options = ValidateOptions {
        intersections: false,
        max_listed: SAFETY_LISTED,
        ..ValidateOptions::default()
    };
    let report = timings.time("safety", || validate(mesh, &options));
    if report.is_valid() {
        return Ok(());
    }
    Err(Inconsistency {
        stage: "validate",
        cells: inconsistency_cells(mesh, lattice, &report),
        reason: report.to_string(),
    })
}

/// §8.4: vertices kept from the moved mesh keep their values; new vertices get theirs by
/// PIC transfer from the moved vertices inside the flawed region.
fn transfer(
    moved: &LabeledMesh,
    attrs: &VertexAttributes,
    grid: &Grid,
    region: &FlawedRegion,
    attempt: &Attempt,
) -> Result<VertexAttributes, PipelineError> {
    if attrs.dim() == 0 {
        return Ok(VertexAttributes::none());
    }
    let mut out = VertexAttributes::zeros(&attempt.mesh, attrs.dim());
    for v in attempt.mesh.vertices() {
        if v.idx() < moved.vertex_capacity()
            && moved.is_vertex_alive(v)
            && attempt.new_vertices.binary_search(&v).is_err()
        {
            out.get_mut(v).copy_from_slice(attrs.get(v));
        }
    }
    let lattice = grid.lattice();
    let mut sources: Vec<VertexId> = moved
        .vertices()
        .filter(|&v| {
            let p = moved.position(v);
            let c = IVec3::new(
                lattice.locate(0, p.x),
                lattice.locate(1, p.y),
                lattice.locate(2, p.z),
            );
            region.is_flawed(c)
        })
        .collect();
    if sources.is_empty() {
        // No old vertex inside the region (triangles larger than ℓ spanning it): the
        // corners of the removed triangles are the nearest data.
        sources = moved
            .triangles()
            .filter(|&t| !attempt.mesh.is_triangle_alive(t))
            .flat_map(|t| moved.tri(t))
            .collect();
        sources.sort_unstable();
        sources.dedup();
    }
    let old = OldVertices {
        positions: moved.positions(),
        attrs,
        vertices: &sources,
    };
    transfer_pic(
        &old,
        grid,
        region,
        &attempt.mesh,
        &attempt.new_vertices,
        &mut out,
    )
    .map_err(|e| PipelineError::Transfer(e.to_string()))?;
    Ok(out)
}

/// Vetoes every edit once `deadline` has passed: improvement's sweeps are bounded in
/// number but not in time, and its edits are the only place it can be stopped from
/// outside without leaving a half-done edit.
struct DeadlineGuard {
    inner: Box<dyn EditGuard>,
    deadline: Instant,
}

impl EditGuard for DeadlineGuard {
    fn check_vertex(&mut self, mesh: &LabeledMesh, v: VertexId) -> Result<(), Veto> {
        self.inner.check_vertex(mesh, v)
    }

    fn precheck(&mut self, mesh: &LabeledMesh, edit: &Edit) -> Result<(), Veto> {
        self.inner.precheck(mesh, edit)
    }

    fn check(&mut self, mesh: &LabeledMesh, edit: &Edit) -> Result<(), Veto> {
        if Instant::now() >= self.deadline {
            return Err(Veto::TimeBudget);
        }
        self.inner.check(mesh, edit)
    }

    fn offending_moves(&mut self, mesh: &LabeledMesh, edit: &Edit) -> Option<Vec<usize>> {
        if Instant::now() >= self.deadline {
            return Some((0..edit.moves.len()).collect());
        }
        self.inner.offending_moves(mesh, edit)
    }

    fn committed(&mut self, mesh: &LabeledMesh, edit: &Edit, applied: &Applied) {
        self.inner.committed(mesh, edit, applied);
    }
}

/// §8.5: mesh improvement with edge lengths in `[min, max] × ℓ` (the target is forced to
/// ℓ), over the whole mesh or only the `created` triangles. When the sub-ℓ pass is on,
/// every edit is checked exactly against the rest of the mesh
/// ([`StaticIntersectionGuard`]), so improvement keeps an intersection-free mesh so.
/// Returns `None` when there was nothing to improve (local scope, nothing created).
/// With a `deadline`, every edit after it is vetoed ([`DeadlineGuard`]), so improvement
/// ends within one edit check of a time budget. Large work lists are improved by blocks
/// on every core ([`improve_in_blocks`], [`GridParams::improve_blocks`]); each block and
/// the final serial pass get their own guard.
pub(crate) fn improve_mesh(
    mesh: &mut LabeledMesh,
    attrs: &mut VertexAttributes,
    params: &GridParams,
    improve_params: &ImproveParams,
    cell_size: f64,
    created: &[TriId],
    deadline: Option<Instant>,
) -> Option<ImproveReport> {
    let improve_params = ImproveParams {
        target_edge_length: Some(cell_size),
        ..improve_params.clone()
    };
    let exact = params.subcell != SubcellPass::Off;
    let make_guard = move || -> Box<dyn EditGuard> {
        let inner: Box<dyn EditGuard> = if exact {
            Box::new(StaticIntersectionGuard::new())
        } else {
            Box::new(NoGuard)
        };
        match deadline {
            Some(deadline) => Box::new(DeadlineGuard { inner, deadline }),
            None => inner,
        }
    };
    let (region, editable) = match params.improve_scope {
        ImproveScope::Whole => (ImproveRegion::Whole, None),
        ImproveScope::Local => (
            ImproveRegion::Around {
                seeds: created,
                degraded: true,
            },
            None,
        ),
        ImproveScope::Changed => {
            if created.is_empty() {
                return None;
            }
            // The paper's local improvement (§8.5): only the triangles this step created,
            // and those the edits create from them, may change.
            let mut editable = vec![false; mesh.triangle_capacity()];
            for &t in created {
                if let Some(e) = editable.get_mut(t.idx()) {
                    *e = true;
                }
            }
            (
                ImproveRegion::Around {
                    seeds: created,
                    degraded: false,
                },
                Some(editable),
            )
        }
    };
    Some(improve_in_blocks(
        mesh,
        &improve_params,
        region,
        editable,
        attrs,
        &params.improve_blocks,
        &make_guard,
    ))
}
