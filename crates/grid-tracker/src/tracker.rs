//! [`GridTracker`]: the 2024 algorithm behind the [`SurfaceTracker`] trait.
//!
//! A step, as in the paper's experiments (§9: "one step of mesh deformation for one step
//! of our topological change algorithm"):
//!
//! ```text
//! check_proposal → move a copy of the mesh (relink non-manifold edges)
//!   → pipeline (grid → materials → flaws → cut → labels → rebuild → transfer,
//!               safety net and sub-ℓ pass, see `pipeline`)
//!   → improve (§8.5) → validate → commit, compact
//! ```
//!
//! The tracker works on a copy: any error leaves the previous mesh and attributes exactly
//! as they were. Proposals may be arbitrarily large (teleporting shapes into each other
//! is a boolean union): nothing in the step assumes small motion.
//!
//! # Resource bounds
//!
//! For `n` live triangles and a flawed region of `r` cells, one step holds at most a few
//! copies of the mesh (`O(n)`: the working copy and the compacted result) plus the sparse grid, whose cell–triangle incidences are counted before it is
//! allocated and capped at `GridOptions::max_cell_entries` (2²⁶ by default; a tiny ℓ or
//! a huge triangle is a typed `GridError::TooManyCells` / `TooFine`, not an out-of-memory
//! abort). Time: the grid, material and flaw stages are linear in those incidences; the
//! cut → rebuild loop runs at most `max_safety_rounds + max_subcell_rounds + 1` times,
//! each roughly linear in `r` and the triangles it touches, plus a linear validation; mesh
//! improvement is bounded by its sweep count. So every step terminates, and with
//! [`GridParams::time_budget`] it also returns within the budget plus one stage
//! ([`TrackError::TimeBudgetExceeded`]).

use std::time::Instant;

use glam::DVec3;
use mesh_core::remesh::VertexAttributes;
use mesh_core::validate::{ValidateOptions, validate};
use mesh_core::{
    LabeledMesh, MaterialCensus, RegionCensus, StepReport, SurfaceTracker, TopologyEvents,
    TrackError, TriId, check_proposal,
};

use crate::params::GridParams;
use crate::pipeline::{PassStats, PipelineError, Timings, improve_mesh, run_pass};
use crate::scale::{CellSizeChoice, tracker_cell_size};

/// The grid tracker (Heiss-Synak et al. 2024): lets the mesh tangle, then repairs the
/// flawed regions from a multi-material implicit surface on a sparse background grid,
/// leaving the rest of the mesh untouched.
///
/// The mesh is compacted after every step that removed anything, so vertex ids change
/// with topology: propose positions for [`SurfaceTracker::mesh`] as it is after the last
/// step. [`StepReport::events`] counts merges and splits with
/// [`RegionCensus::events_since`], as the collision backend does: regions of one label
/// joining, or separate surface components coming into contact, are merges. This backend
/// has no T1 or T2 operation — neighbour swaps and vanishing cells happen implicitly when
/// a tangled region is rebuilt from the grid labels — so it counts them on the result:
/// `t1` is the number of material pairs that gained or lost a shared interface
/// ([`MaterialCensus::contact_changes`], each an elementary 3D T1 event) and `t2` the
/// number of materials that vanished ([`TopologyEvents::vanished`]: a region shrunk to
/// nothing, Los Topos' T2).
#[derive(Clone, Debug)]
pub struct GridTracker {
    mesh: LabeledMesh,
    attrs: VertexAttributes,
    params: GridParams,
    cell_size: f64,
    /// How ℓ was chosen.
    choice: CellSizeChoice,
    step: u64,
    /// Regions of the current mesh, to count merges and splits.
    census: RegionCensus,
    /// Volume per material of the current mesh, for [`StepReport::volumes`] and
    /// [`TopologyEvents::vanished`].
    materials: MaterialCensus,
    last: Option<PassStats>,
}

/// Checks the preconditions of a tracker's or `fix`'s input: layers 1–3 of validation.
pub(crate) fn check_input(mesh: &LabeledMesh) -> Result<(), String> {
    let report = validate(mesh, &ValidateOptions::default());
    if report.is_valid() {
        Ok(())
    } else {
        Err(report.to_string())
    }
}

/// Moves every vertex whose proposed position differs and re-pairs the non-manifold
/// edges around it from the new geometry. Returns the triangles with a moved vertex.
fn move_vertices(mesh: &mut LabeledMesh, proposed: &[DVec3]) -> Vec<TriId> {
    let moved: Vec<_> = mesh
        .vertices()
        .filter(|&v| mesh.position(v) != proposed[v.idx()])
        .collect();
    for &v in &moved {
        mesh.set_position(v, proposed[v.idx()]);
    }
    let mut tris = vec![false; mesh.triangle_capacity()];
    for &v in &moved {
        mesh.relink_around(v);
        for t in mesh.vertex_triangles(v) {
            tris[t.idx()] = true;
        }
    }
    mesh.triangles().filter(|t| tris[t.idx()]).collect()
}

impl GridTracker {
    /// A tracker for `mesh`, which must be valid (layers 1–3 of
    /// [`mesh_core::validate`]: closed, consistently labelled, finite, no zero-area
    /// triangle) and non-empty. ℓ is [`GridParams::cell_size`] or, without one, the mean
    /// edge length ([`crate::tracker_cell_size`], see [`Self::cell_size_choice`]).
    pub fn new(mesh: LabeledMesh, params: GridParams) -> Result<Self, TrackError> {
        params.check().map_err(TrackError::InvalidInput)?;
        if mesh.num_triangles() == 0 {
            return Err(TrackError::InvalidInput("the mesh has no triangles".into()));
        }
        check_input(&mesh).map_err(TrackError::InvalidInput)?;
        let choice = match params.cell_size {
            Some(l) => CellSizeChoice::given(l),
            None => tracker_cell_size(&mesh),
        };
        let cell_size = choice.cell_size;
        if !(cell_size.is_finite() && cell_size > 0.0) {
            return Err(TrackError::InvalidInput(format!(
                "cell size ℓ = {cell_size} must be finite and > 0 ({})",
                choice.reason
            )));
        }
        let census = RegionCensus::of(&mesh);
        let materials = MaterialCensus::of(&mesh);
        Ok(Self {
            mesh,
            attrs: VertexAttributes::none(),
            params,
            cell_size,
            choice,
            step: 0,
            census,
            materials,
            last: None,
        })
    }

    /// Per-vertex attributes (e.g. velocities) carried through steps: kept on surviving
    /// vertices, interpolated by edits, and transferred to rebuilt vertices by PIC (§8.4).
    /// Empty (`dim() == 0`) unless set with [`Self::set_attributes`].
    pub fn attributes(&self) -> &VertexAttributes {
        &self.attrs
    }

    /// Mutable attributes, indexed by the current vertex ids.
    pub fn attributes_mut(&mut self) -> &mut VertexAttributes {
        &mut self.attrs
    }

    /// Replaces the attributes, e.g. `VertexAttributes::zeros(tracker.mesh(), 3)`.
    pub fn set_attributes(&mut self, attrs: VertexAttributes) {
        self.attrs = attrs;
    }

    /// The parameters.
    pub fn params(&self) -> &GridParams {
        &self.params
    }

    /// The cell size ℓ in use.
    pub fn cell_size(&self) -> f64 {
        self.cell_size
    }

    /// ℓ and why it was chosen (given, the mean edge length, or the thinnest material).
    pub fn cell_size_choice(&self) -> &CellSizeChoice {
        &self.choice
    }

    /// Steps completed.
    pub fn steps(&self) -> u64 {
        self.step
    }

    /// What the last successful step's pipeline pass did (flawed cells, safety-net and
    /// sub-ℓ rounds, triangles replaced).
    pub fn last_pass(&self) -> Option<&PassStats> {
        self.last.as_ref()
    }

    /// The step on a copy; `Ok` carries everything to commit.
    fn step_on_copy(
        &self,
        proposed: &[DVec3],
        timings: &mut Timings,
    ) -> Result<(LabeledMesh, VertexAttributes, PassStats, u64), TrackError> {
        let mut moved = self.mesh.clone();
        let changed = timings.time("move", || move_vertices(&mut moved, proposed));
        let budget = self.params.time_budget;
        timings.check_budget(budget, "move").map_err(stage_failed)?;
        let seed = self.params.step_seed(self.step);
        let pass = run_pass(
            moved,
            &self.attrs,
            Some(&changed),
            &self.params,
            self.cell_size,
            seed,
            timings,
        )
        .map_err(stage_failed)?;
        let (mut mesh, mut attrs) = (pass.mesh, pass.attrs);
        let mut edits = 0u64;
        if let Some(ip) = &self.params.improve {
            // Every improvement edit passes the structural check of `apply_edit` (labels
            // and radial order around each edge it touches included), so the pass's valid
            // output stays valid: no copy, no whole-mesh re-validation, no fallback.
            let report = timings.time("improve", || {
                improve_mesh(
                    &mut mesh,
                    &mut attrs,
                    &self.params,
                    ip,
                    self.cell_size,
                    &pass.created,
                    None,
                )
            });
            if let Some(r) = report {
                edits = r.edits() as u64;
            }
        }
        if self.params.validate_each_step {
            let report = timings.time("validate", || validate(&mesh, &ValidateOptions::default()));
            if !report.is_valid() {
                return Err(TrackError::StageFailed {
                    stage: "validate",
                    reason: report.to_string(),
                });
            }
        }
        timings
            .check_budget(budget, "improve")
            .map_err(stage_failed)?;
        Ok((mesh, attrs, pass.stats, edits))
    }
}

/// A pipeline error as the trait's error: an exceeded budget keeps its own variant.
fn stage_failed(e: PipelineError) -> TrackError {
    match e {
        PipelineError::TimeBudget { stage, budget } => {
            TrackError::TimeBudgetExceeded { stage, budget }
        }
        e => TrackError::StageFailed {
            stage: e.stage(),
            reason: e.to_string(),
        },
    }
}

/// Drops dead slots (if any), carrying the attributes along.
fn compact(mesh: &mut LabeledMesh, attrs: &mut VertexAttributes) {
    if mesh.num_vertices() == mesh.vertex_capacity()
        && mesh.num_triangles() == mesh.triangle_capacity()
    {
        return;
    }
    let map = mesh.compact();
    if attrs.dim() > 0 {
        let mut out = VertexAttributes::zeros(mesh, attrs.dim());
        for (old, new) in map.vertex_map.iter().enumerate() {
            if let Some(new) = new {
                out.get_mut(*new)
                    .copy_from_slice(attrs.get(mesh_core::VertexId::new(old as u32)));
            }
        }
        *attrs = out;
    }
}

impl SurfaceTracker for GridTracker {
    fn name(&self) -> &str {
        "grid"
    }

    fn mesh(&self) -> &LabeledMesh {
        &self.mesh
    }

    fn advance(&mut self, proposed: &[DVec3]) -> Result<StepReport, TrackError> {
        check_proposal(&self.mesh, proposed)?;
        let mut timings = Timings::default();
        let (mut mesh, mut attrs, stats, edits) = self.step_on_copy(proposed, &mut timings)?;
        let start = Instant::now();
        compact(&mut mesh, &mut attrs);
        let census = RegionCensus::of(&mesh);
        let materials = MaterialCensus::of(&mesh);
        timings.add("commit", start.elapsed());
        let (merges, splits) = census.events_since(&self.census);
        let vanished = self.materials.vanished_in(&materials);
        if !vanished.is_empty() {
            tracing::warn!("step {}: materials {vanished:?} vanished", self.step + 1);
        }
        let contacts = self.materials.contact_changes(&materials);
        let events = TopologyEvents {
            merges,
            splits,
            t1: contacts.gained + contacts.lost,
            t2: vanished.len() as u64,
            remeshing_edits: edits,
            vanished,
        };
        let volumes = self.materials.volumes_to(&materials);
        self.mesh = mesh;
        self.attrs = attrs;
        self.census = census;
        self.materials = materials;
        self.step += 1;
        self.last = Some(stats);
        Ok(StepReport {
            stages: timings.into_stages(),
            events,
            vertices: self.mesh.num_vertices(),
            triangles: self.mesh.num_triangles(),
            substeps: 1,
            volumes,
        })
    }

    fn attributes(&self) -> Option<&VertexAttributes> {
        Some(&self.attrs)
    }

    fn set_attributes(&mut self, attrs: VertexAttributes) -> Result<(), VertexAttributes> {
        self.attrs = attrs;
        Ok(())
    }
}
