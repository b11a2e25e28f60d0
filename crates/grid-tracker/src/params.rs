//! The parameters of the grid tracker and of [`crate::fix`], in one documented struct.
//!
//! The paper has a single parameter, the topological resolution ℓ (§9.1); everything
//! else here either reproduces its choices (random grid offset per step, improvement to
//! edge lengths in 0.5–1.5 ℓ) or bounds the loops that make a step always terminate
//! (safety net §9.2, the sub-ℓ intersection pass that goes beyond the paper).

use mesh_core::remesh::{BlockParams, ImproveParams};
use serde::{Deserialize, Serialize};

use crate::stages::flaws::{FlawOptions, Resampling};
use crate::stages::labels::LabelCorrection;
use crate::stages::rebuild::RebuildOptions;

/// Which triangles mesh improvement (§8.5) may change.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ImproveScope {
    /// The whole mesh, every sweep's first pass over every vertex: the reference the local
    /// default is measured against.
    Whole,
    /// The newly changed surface (§8.5: cut pieces and rebuilt triangles) plus whatever the
    /// motion took out of range or shape (an edge outside the length range, an angle below
    /// `ImproveParams::seed_min_angle_deg`), grown by a work list as edits touch their
    /// neighbours (`mesh_core::remesh::ImproveRegion::Around`). A tracker under large
    /// deformation needs edge lengths kept in range wherever the motion stretched the
    /// mesh, but not a sweep over the surface nothing degraded.
    #[default]
    Local,
    /// Only the triangles this step created (cut pieces and rebuilt triangles) and the
    /// triangles improvement creates from them; every other triangle is kept exactly, as
    /// in the paper's "local mesh improvement". What [`crate::fix`] uses.
    Changed,
}

/// What to do about intersections finer than ℓ, which the axis rays cannot see (the
/// paper's §10 names this as future work).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
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
///
/// Serialisable (serde, every field optional on input thanks to `#[serde(default)]`), so a
/// run record or a scenario file can carry the exact options of a run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
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
    #[serde(with = "improve_serde")]
    pub improve: Option<ImproveParams>,
    /// Which triangles improvement works on. Default [`ImproveScope::Local`].
    pub improve_scope: ImproveScope,
    /// Improvement on every core, by blocks of space, when its work list is large
    /// (`mesh_core::remesh::blocks`). Default [`BlockParams::default`]; `passes = 0`
    /// keeps it serial.
    pub improve_blocks: BlockParams,
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
    /// own check after each rebuild already covers the changed region, and every
    /// improvement edit is checked structurally before it commits.
    pub validate_each_step: bool,
    /// Local (the paper) or global resampling (Fig. 17b ablation). Default
    /// [`Resampling::Local`].
    pub resampling: Resampling,
    /// How non-physical grid nodes get their label (§8.1). Default
    /// [`LabelCorrection::FastMarching`], the paper's.
    pub label_correction: LabelCorrection,
    /// Rebuild options (§8.2–8.3), among them the non-manifold curve smoothing steps.
    /// Default [`RebuildOptions::default`].
    pub rebuild: RebuildOptions,
    /// Wall-time budget of one step (or one `fix`). Default `None`: unbounded — every loop
    /// of a step is bounded by the counters above, so a step always terminates, but on
    /// adversarial input it may take long. With `Some(b)`, the budget is checked at stage
    /// boundaries (after each stage and each safety-net or sub-ℓ round) and an exceeded
    /// budget fails the step with `TrackError::TimeBudgetExceeded` (for `fix`,
    /// `PipelineError::TimeBudget`), the previous mesh kept: a step overshoots `b` by at
    /// most the duration of one stage. `Some(Duration::ZERO)` fails every step.
    #[serde(with = "mesh_core::tracker::optional_seconds")]
    pub time_budget: Option<std::time::Duration>,
}

impl Default for GridParams {
    fn default() -> Self {
        Self {
            cell_size: None,
            perturbation: 0.1,
            seed: 0,
            flaws: FlawOptions::default(),
            improve: Some(ImproveParams::default()),
            improve_scope: ImproveScope::Local,
            improve_blocks: BlockParams::default(),
            max_safety_rounds: 8,
            subcell: SubcellPass::Require,
            max_subcell_rounds: 6,
            validate_each_step: cfg!(debug_assertions),
            resampling: Resampling::Local,
            label_correction: LabelCorrection::FastMarching,
            rebuild: RebuildOptions::default(),
            time_budget: None,
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

/// Serde for `Option<ImproveParams>` through a mirror struct: mesh-core's
/// [`ImproveParams`] is not deserialisable, and the grid tracker's options must be, so
/// that a record can reproduce a run. Every field of the mirror is optional on input
/// (missing fields take [`ImproveParams::default`]'s values); `null` means improvement off.
mod improve_serde {
    use mesh_core::remesh::{
        ConserveVolume, FeatureParams, FlipCriterion, ImproveParams, Resmooth, SeparationParams,
    };
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    /// [`FlipCriterion`] by name.
    #[derive(Clone, Copy, Serialize, Deserialize)]
    #[serde(rename_all = "snake_case")]
    enum Flip {
        Delaunay,
        ShorterEdge,
    }

    /// The fields of [`ImproveParams`], flattened one level (features and separation are
    /// nested tables of two numbers each).
    #[derive(Clone, Serialize, Deserialize)]
    #[serde(default, deny_unknown_fields)]
    struct Mirror {
        target_edge_length: Option<f64>,
        min_edge_factor: f64,
        max_edge_factor: f64,
        collapse_max_edge_factor: f64,
        min_feature_factor: f64,
        max_volume_change: Option<f64>,
        max_material_share: f64,
        max_sweeps: usize,
        split: bool,
        butterfly: bool,
        collapse: bool,
        flip: bool,
        smooth: bool,
        remove_degenerate: bool,
        separate: bool,
        pinch: bool,
        smooth_step: f64,
        smooth_passes: usize,
        resmooth: Resmooth,
        flip_criterion: Flip,
        flip_min_improvement: f64,
        min_normal_cos: f64,
        conserve_volume: ConserveVolume,
        feature_rank_ratio: f64,
        feature_curve_corner_angle_deg: f64,
        separation_fraction: f64,
        separation_max_iterations: usize,
        seed_min_angle_deg: f64,
    }

    impl Default for Mirror {
        fn default() -> Self {
            Mirror::from(&ImproveParams::default())
        }
    }

    impl From<&ImproveParams> for Mirror {
        fn from(p: &ImproveParams) -> Self {
            Mirror {
                target_edge_length: p.target_edge_length,
                min_edge_factor: p.min_edge_factor,
                max_edge_factor: p.max_edge_factor,
                collapse_max_edge_factor: p.collapse_max_edge_factor,
                min_feature_factor: p.min_feature_factor,
                max_volume_change: p.max_volume_change,
                max_material_share: p.max_material_share,
                max_sweeps: p.max_sweeps,
                split: p.split,
                butterfly: p.butterfly,
                collapse: p.collapse,
                flip: p.flip,
                smooth: p.smooth,
                remove_degenerate: p.remove_degenerate,
                separate: p.separate,
                pinch: p.pinch,
                smooth_step: p.smooth_step,
                smooth_passes: p.smooth_passes,
                resmooth: p.resmooth,
                flip_criterion: match p.flip_criterion {
                    FlipCriterion::Delaunay => Flip::Delaunay,
                    FlipCriterion::ShorterEdge => Flip::ShorterEdge,
                },
                flip_min_improvement: p.flip_min_improvement,
                min_normal_cos: p.min_normal_cos,
                conserve_volume: p.conserve_volume,
                feature_rank_ratio: p.features.rank_ratio,
                feature_curve_corner_angle_deg: p.features.curve_corner_angle_deg,
                separation_fraction: p.separation.separation_fraction,
                separation_max_iterations: p.separation.max_iterations,
                seed_min_angle_deg: p.seed_min_angle_deg,
            }
        }
    }

    impl From<Mirror> for ImproveParams {
        fn from(m: Mirror) -> Self {
            ImproveParams {
                target_edge_length: m.target_edge_length,
                min_edge_factor: m.min_edge_factor,
                max_edge_factor: m.max_edge_factor,
                collapse_max_edge_factor: m.collapse_max_edge_factor,
                min_feature_factor: m.min_feature_factor,
                max_volume_change: m.max_volume_change,
                max_material_share: m.max_material_share,
                max_sweeps: m.max_sweeps,
                split: m.split,
                butterfly: m.butterfly,
                collapse: m.collapse,
                flip: m.flip,
                smooth: m.smooth,
                remove_degenerate: m.remove_degenerate,
                separate: m.separate,
                pinch: m.pinch,
                smooth_step: m.smooth_step,
                smooth_passes: m.smooth_passes,
                resmooth: m.resmooth,
                flip_criterion: match m.flip_criterion {
                    Flip::Delaunay => FlipCriterion::Delaunay,
                    Flip::ShorterEdge => FlipCriterion::ShorterEdge,
                },
                flip_min_improvement: m.flip_min_improvement,
                min_normal_cos: m.min_normal_cos,
                conserve_volume: m.conserve_volume,
                features: FeatureParams {
                    rank_ratio: m.feature_rank_ratio,
                    curve_corner_angle_deg: m.feature_curve_corner_angle_deg,
                },
                separation: SeparationParams {
                    separation_fraction: m.separation_fraction,
                    max_iterations: m.separation_max_iterations,
                },
                seed_min_angle_deg: m.seed_min_angle_deg,
            }
        }
    }

    pub(super) fn serialize<S: Serializer>(
        value: &Option<ImproveParams>,
        s: S,
    ) -> Result<S::Ok, S::Error> {
        value.as_ref().map(Mirror::from).serialize(s)
    }

    pub(super) fn deserialize<'de, D: Deserializer<'de>>(
        d: D,
    ) -> Result<Option<ImproveParams>, D::Error> {
        Ok(Option::<Mirror>::deserialize(d)?.map(ImproveParams::from))
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec3;
    use mesh_core::validate::{ValidateOptions, validate};
    use mesh_core::{LabeledMesh, SurfaceTracker};

    use super::*;
    use crate::GridTracker;
    use crate::test_util::{sphere, union};

    /// A sphere with six bumps of 15 % of the radius: surface detail above ℓ that crosses
    /// grid edges twice (complex edges) but is shallow.
    fn bumpy_sphere() -> LabeledMesh {
        let mut mesh = sphere(4, DVec3::ZERO, 1.0, 0, 1);
        let bumps = [
            DVec3::X,
            DVec3::NEG_X,
            DVec3::Y,
            DVec3::NEG_Y,
            DVec3::Z,
            DVec3::NEG_Z,
        ]
        .map(|d| (d + DVec3::new(0.2, 0.3, 0.1)).normalize());
        let vs: Vec<_> = mesh.vertices().collect();
        for v in vs {
            let u = mesh.position(v).normalize();
            let h: f64 = bumps
                .iter()
                .map(|d| {
                    let a = u.dot(*d).clamp(-1.0, 1.0).acos();
                    0.15 * (-a * a / (2.0 * 0.12 * 0.12)).exp()
                })
                .sum();
            mesh.set_position(v, u * (1.0 + h));
        }
        mesh
    }

    fn still_step(params: GridParams, mesh: LabeledMesh) -> (GridTracker, usize) {
        let mut tracker = GridTracker::new(mesh, params).unwrap();
        let proposed = tracker.mesh().positions().to_vec();
        tracker.advance(&proposed).unwrap();
        let cells = tracker.last_pass().map_or(0, |p| p.flawed_cells);
        (tracker, cells)
    }

    #[test]
    fn global_resampling_and_no_deep_test_remesh_what_local_keeps() {
        let local = GridParams {
            improve_scope: ImproveScope::Changed,
            ..GridParams::default()
        };
        let mesh = bumpy_sphere();
        let (kept, cells) = still_step(local.clone(), mesh.clone());
        assert_eq!(cells, 0, "shallow bumps are kept by the paper's method");
        assert_eq!(kept.mesh().positions(), mesh.positions());

        let no_deep = GridParams {
            flaws: FlawOptions {
                deep_cell_test: false,
                ..FlawOptions::default()
            },
            ..local.clone()
        };
        let (t, cells) = still_step(no_deep, mesh.clone());
        assert!(
            cells > 0,
            "without the deep test the bumps' complex cells are remeshed"
        );
        assert!(validate(t.mesh(), &ValidateOptions::default()).is_valid());

        let global = GridParams {
            resampling: Resampling::Global,
            ..local
        };
        let (t, cells) = still_step(global, mesh.clone());
        assert!(cells > 100, "{cells}");
        assert!(validate(t.mesh(), &ValidateOptions::default()).is_valid());
        // No triangle of the input survives a global rebuild.
        let before: std::collections::HashSet<[u64; 9]> = mesh
            .triangles()
            .map(|f| {
                let p = mesh.tri(f).map(|v| mesh.position(v));
                std::array::from_fn(|k| p[k / 3].to_array()[k % 3].to_bits())
            })
            .collect();
        let m = t.mesh();
        let kept = m
            .triangles()
            .filter(|&f| {
                let p = m.tri(f).map(|v| m.position(v));
                before.contains(&std::array::from_fn(|k| {
                    p[k / 3].to_array()[k % 3].to_bits()
                }))
            })
            .count();
        assert_eq!(kept, 0);
    }

    #[test]
    fn nearest_vertex_labels_give_a_valid_different_merge() {
        let a = sphere(3, DVec3::new(-0.55, 0.0, 0.0), 0.5, 0, 1);
        let b = sphere(3, DVec3::new(0.55, 0.0, 0.0), 0.5, 0, 2);
        let mesh = union(&[a, b]);
        let run = |label_correction| {
            let params = GridParams {
                label_correction,
                ..GridParams::default()
            };
            let mut tracker = GridTracker::new(mesh.clone(), params).unwrap();
            // Push both spheres 0.15 into each other.
            let proposed: Vec<DVec3> = tracker
                .mesh()
                .positions()
                .iter()
                .map(|p| *p - DVec3::new(0.15 * p.x.signum(), 0.0, 0.0))
                .collect();
            tracker.advance(&proposed).unwrap();
            assert!(validate(tracker.mesh(), &ValidateOptions::default()).is_valid());
            tracker.mesh().positions().to_vec()
        };
        let fast = run(LabelCorrection::FastMarching);
        let nearest = run(LabelCorrection::NearestVertex);
        assert_ne!(fast, nearest, "the label correction made no difference");
    }
}
