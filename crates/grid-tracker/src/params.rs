//! The parameters of the grid tracker and of [`crate::fix`], in one documented struct.
//!
//! The paper has a single parameter, the topological resolution ℓ (§9.1); everything
//! else here either reproduces its choices (random grid offset per step, improvement to
//! edge lengths in 0.5–1.5 ℓ) or bounds the loops that make a step always terminate
//! (safety net §9.2, the sub-ℓ intersection pass that goes beyond the paper).

use mesh_core::remesh::ImproveParams;

use crate::stages::flaws::FlawOptions;

/// Which triangles mesh improvement (§8.5) may change.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ImproveScope {
    /// The whole mesh: a tracker under large deformation (normal flow, stretching) needs
    /// edge lengths kept in range everywhere, not only where topology changed.
    #[default]
    Whole,
    /// Only the triangles this step created (cut pieces and rebuilt triangles) and the
    /// triangles improvement creates from them; every other triangle is kept exactly, as
    /// in the paper's "local mesh improvement". What [`crate::fix`] uses.
    Changed,
}

/// What to do about intersections finer than ℓ, which the axis rays cannot see (the
/// paper's §10 names this as future work).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SubcellPass {
    /// No exact intersection test: clean above ℓ only, as in the paper.
    Off,
    /// Test the changed triangles exactly; the cells of every intersecting pair join the
    /// flawed region and the cut → rebuild pass repeats, up to
    /// [`GridParams::max_subcell_rounds`] times. Pairs left after the last round are
    /// reported, not an error.
    Repair,
    /// As [`SubcellPass::Repair`], but pairs left after the last round fail the step (the
    /// tracker keeps its previous mesh), so every output is free of intersections.
    #[default]
    Require,
}

/// Parameters of [`crate::GridTracker`] (and, through [`crate::FixOptions`], of
/// [`crate::fix_with`]). Every field has a documented default.
#[derive(Clone, Debug, PartialEq)]
pub struct GridParams {
    /// Cell size ℓ, the topological resolution (§4, §9.1). Default `None`: the mean edge
    /// length of the initial mesh, the paper's choice; fixed for the tracker's lifetime so
    /// that the resolution does not drift as the mesh is remeshed.
    pub cell_size: Option<f64>,
    /// Largest random shift of the grid origin per axis, as a fraction of ℓ (see
    /// [`crate::GridOptions::perturbation`]). Default 0.1. Each step draws a fresh shift,
    /// so vertices that one step placed on grid faces and cell centres are not on the next
    /// step's planes. Zero puts the planes on multiples of ℓ (tests of degenerate input).
    pub perturbation: f64,
    /// Seed of the per-step grid shifts. Default 0. Step `k` uses a seed mixed from this
    /// and `k`, so a run is deterministic and steps differ.
    pub seed: u64,
    /// Flaw detection options (§6). Default [`FlawOptions::default`].
    pub flaws: FlawOptions,
    /// Mesh improvement (§8.5). Default `Some` with edge lengths in 0.5–1.5 ℓ (the
    /// target edge length is forced to ℓ); `None` switches improvement off.
    pub improve: Option<ImproveParams>,
    /// Which triangles improvement may change. Default [`ImproveScope::Whole`].
    pub improve_scope: ImproveScope,
    /// Bound on safety-net restarts (§9.2) per step: each one grows the flawed region
    /// where a stage found an inconsistency and redoes cut → rebuild. Default 8.
    pub max_safety_rounds: usize,
    /// The sub-ℓ exact intersection pass. Default [`SubcellPass::Require`].
    pub subcell: SubcellPass,
    /// Bound on sub-ℓ rounds per step. Default 6.
    pub max_subcell_rounds: usize,
    /// Validate the mesh (topology, labels, geometry: layers 1–3 of
    /// [`mesh_core::validate`]) at the end of every step, failing the step if it is not
    /// valid. Default: on in debug builds, off in release builds, where the safety net's
    /// own check after each rebuild already covers the changed region. With improvement
    /// on, its result is always checked (and discarded for the step's unimproved mesh if
    /// invalid), whatever this flag says.
    pub validate_each_step: bool,
}

impl Default for GridParams {
    fn default() -> Self {
        Self {
            cell_size: None,
            perturbation: 0.1,
            seed: 0,
            flaws: FlawOptions::default(),
            improve: Some(ImproveParams::default()),
            improve_scope: ImproveScope::Whole,
            max_safety_rounds: 8,
            subcell: SubcellPass::Require,
            max_subcell_rounds: 6,
            validate_each_step: cfg!(debug_assertions),
        }
    }
}

impl GridParams {
    /// The seed of step `step`'s grid shift: SplitMix64 of the base seed and the step, so
    /// consecutive steps get unrelated shifts.
    pub fn step_seed(&self, step: u64) -> u64 {
        let mut z = self
            .seed
            .wrapping_add(step.wrapping_mul(0x9E37_79B9_7F4A_7C15))
            .wrapping_add(0x9E37_79B9_7F4A_7C15);
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Checks the values that the stages would otherwise reject later, with the name of
    /// the offending field.
    pub(crate) fn check(&self) -> Result<(), String> {
        if let Some(l) = self.cell_size
            && !(l.is_finite() && l > 0.0)
        {
            return Err(format!("cell_size = {l} must be finite and > 0"));
        }
        if !(0.0..=0.5).contains(&self.perturbation) {
            return Err(format!(
                "perturbation = {} must lie in [0, 0.5]",
                self.perturbation
            ));
        }
        Ok(())
    }
}
