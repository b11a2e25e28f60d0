//! Research ablations (`surftrack bench ablate`): what does each algorithmic choice buy?
//!
//! An ablation is a list of **axes**; each axis is a list of **settings**, a setting a
//! name and the option assignments (`path=value`, as `--set` takes them) that make it.
//! The cross product of the axes' settings, times the backends, gives the **variants**;
//! every variant runs on the same seeds, each run a child process under the watchdog
//! ([`crate::isolate`], through [`crate::bench::run_all`]), and the records are summarised
//! per variant ([`VariantSummary`]). `--vary path=v1,v2` adds an axis; a [`Preset`] is a
//! named list of axes plus fixed assignments, reproducing one of the papers' ablations.

use std::ffi::OsString;
use std::path::{Path, PathBuf};

use indicatif::ProgressBar;
use serde::{Deserialize, Serialize};
use surftrack::Backend;

use crate::bench::{ChildOptions, child_args, run_all};
use crate::isolate::{ChildRun, Limits, read_run_record};
use crate::record::{EventCounts, RunRecord, RunSummary, StageSeconds, add_stage_seconds};

/// Version tag of `ablate.json`.
pub const ABLATE_SCHEMA: &str = "surftrack.ablate/1";

/// One setting of an axis: its name in tables, and the assignments that make it.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Setting {
    /// Short name (`global`, `off`, `grid.resampling=global`).
    pub name: String,
    /// `path=value` assignments.
    pub sets: Vec<String>,
}

/// A named ablation from the papers.
#[derive(Clone, Copy, Debug)]
pub struct Preset {
    /// Name on the command line.
    pub name: &'static str,
    /// What it asks, and where the paper asks it.
    pub summary: &'static str,
    /// Backends it applies to.
    pub backends: &'static [Backend],
    /// The varied axis: `(setting name, assignments)`.
    pub settings: &'static [(&'static str, &'static [&'static str])],
    /// Assignments every variant gets.
    pub fixed: &'static [&'static str],
}

const GRID: &[Backend] = &[Backend::Grid];
const COLLISION: &[Backend] = &[Backend::Collision];
const BOTH: &[Backend] = &[Backend::Grid, Backend::Collision];

/// The papers' ablations (see `surftrack bench ablate --help`).
pub const PRESETS: &[Preset] = &[
    Preset {
        name: "resampling",
        summary: "grid: local vs global resampling (2024 paper Fig. 17b); improvement restricted to changed triangles",
        backends: GRID,
        settings: &[
            ("local", &["grid.resampling=local"]),
            ("global", &["grid.resampling=global"]),
        ],
        fixed: &["grid.improve_scope=changed"],
    },
    Preset {
        name: "deep-cells",
        summary: "grid: deep-cell test on/off (2024 paper §6.3, Fig. 9); improvement restricted to changed triangles",
        backends: GRID,
        settings: &[
            ("on", &["grid.flaws.deep_cell_test=true"]),
            ("off", &["grid.flaws.deep_cell_test=false"]),
        ],
        fixed: &["grid.improve_scope=changed"],
    },
    Preset {
        name: "curve-smoothing",
        summary: "grid: non-manifold curve smoothing, 10 steps vs off (2024 paper §8.3)",
        backends: GRID,
        settings: &[
            ("on", &["grid.rebuild.curve_smoothing_steps=10"]),
            ("off", &["grid.rebuild.curve_smoothing_steps=0"]),
        ],
        fixed: &[],
    },
    Preset {
        name: "label-correction",
        summary: "grid: nearest breaking point (the paper finds it by fast marching) vs nearest physical grid vertex (2024 paper §8.1)",
        backends: GRID,
        settings: &[
            ("fast-marching", &["grid.label_correction=fast_marching"]),
            ("nearest-vertex", &["grid.label_correction=nearest_vertex"]),
        ],
        fixed: &[],
    },
    Preset {
        name: "merging",
        summary: "collision: snap merging vs no merging (Los Topos §7)",
        backends: COLLISION,
        settings: &[
            ("snap", &["collision.merge=true"]),
            ("none", &["collision.merge=false"]),
        ],
        fixed: &[],
    },
    Preset {
        name: "volume",
        summary: "collision: which remeshing edits conserve volume: flips and collapses (the default), all (smoothing too), none (El Topo's Ω bound alone)",
        backends: COLLISION,
        settings: &[
            (
                "flips-collapses",
                &["collision.conserve_volume.smoothing=false"],
            ),
            ("all", &["collision.conserve_volume.smoothing=true"]),
            (
                "none",
                &[
                    "collision.conserve_volume.flips=false",
                    "collision.conserve_volume.collapses=false",
                    "collision.conserve_volume.smoothing=false",
                ],
            ),
        ],
        fixed: &[],
    },
    Preset {
        name: "t1",
        summary: "collision: T1 vertex separation on/off (Los Topos §5)",
        backends: COLLISION,
        settings: &[
            ("on", &["collision.t1=true"]),
            ("off", &["collision.t1=false"]),
        ],
        fixed: &[],
    },
    Preset {
        name: "impact-zones",
        summary: "collision: impact zones, the fail-safe, on/off (El Topo §3.8); the flag is recorded but takes effect only once the collision tracker's stage configuration reads it (CollisionParams::impact_zones)",
        backends: COLLISION,
        settings: &[
            ("on", &["collision.impact_zones=true"]),
            ("off", &["collision.impact_zones=false"]),
        ],
        fixed: &[],
    },
    Preset {
        name: "collision-safety",
        summary: "collision: El Topo's collision_safety toggle on/off; recorded, in effect once the collision tracker's stage configuration reads it (CollisionParams::collision_safety)",
        backends: COLLISION,
        settings: &[
            ("on", &["collision.collision_safety=true"]),
            ("off", &["collision.collision_safety=false"]),
        ],
        fixed: &[],
    },
    Preset {
        name: "normal-flow",
        summary: "both backends: vertex-normal vs face-offsetting normal flow (Los Topos §8.3, 2024 paper §9.6)",
        backends: BOTH,
        settings: &[
            ("vertex-normals", &["flow.normal_scheme=vertex_normals"]),
            ("face-offsetting", &["flow.normal_scheme=face_offsetting"]),
        ],
        fixed: &[],
    },
    Preset {
        name: "remeshing",
        summary: "both backends: mesh improvement on/off (El Topo Figs. 4.5-4.6)",
        backends: BOTH,
        settings: &[
            ("on", &[]),
            ("off", &["grid.improve=none", "collision.improve=false"]),
        ],
        fixed: &[],
    },
];

/// The preset named `name`.
pub fn preset(name: &str) -> Option<&'static Preset> {
    PRESETS.iter().find(|p| p.name == name)
}

impl Preset {
    /// Its varied axis as [`Setting`]s.
    pub fn axis(&self) -> Vec<Setting> {
        self.settings
            .iter()
            .map(|(name, sets)| Setting {
                name: name.to_string(),
                sets: sets.iter().map(|s| s.to_string()).collect(),
            })
            .collect()
    }
}

/// Why an ablation could not be set up.
#[derive(Debug, thiserror::Error)]
pub enum AblateError {
    /// `--vary` is not `path=v1,v2,...`.
    #[error("`--vary {0}`: expected path=v1,v2,... (e.g. grid.resampling=local,global)")]
    Vary(String),
    /// No preset of this name.
    #[error("unknown preset `{name}`; presets: {known}")]
    UnknownPreset {
        /// The name given.
        name: String,
        /// The known names.
        known: String,
    },
    /// Nothing to vary.
    #[error("nothing to vary: give --preset NAME or --vary path=v1,v2")]
    Empty,
}

/// Parses `--vary path=v1,v2,...` into an axis (values split at commas, so a value cannot
/// itself contain one).
pub fn parse_vary(text: &str) -> Result<Vec<Setting>, AblateError> {
    let (path, values) = text
        .split_once('=')
        .ok_or_else(|| AblateError::Vary(text.to_string()))?;
    let path = path.trim();
    let values: Vec<&str> = values
        .split(',')
        .map(str::trim)
        .filter(|v| !v.is_empty())
        .collect();
    if path.is_empty() || values.is_empty() {
        return Err(AblateError::Vary(text.to_string()));
    }
    Ok(values
        .into_iter()
        .map(|v| Setting {
            name: format!("{path}={v}"),
            sets: vec![format!("{path}={v}")],
        })
        .collect())
}

/// One variant: a backend and one setting per axis.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Variant {
    /// Setting names joined by spaces, prefixed by the backend when several run.
    pub name: String,
    /// Backend name.
    pub tracker: String,
    /// Every assignment (fixed ones first).
    pub sets: Vec<String>,
}

/// The cross product of `axes` times `backends`, with `fixed` assignments first.
pub fn variants(backends: &[Backend], axes: &[Vec<Setting>], fixed: &[String]) -> Vec<Variant> {
    let mut combos: Vec<(Vec<String>, Vec<String>)> = vec![(Vec::new(), fixed.to_vec())];
    for axis in axes {
        let mut next = Vec::with_capacity(combos.len() * axis.len());
        for (names, sets) in &combos {
            for s in axis {
                let mut n = names.clone();
                n.push(s.name.clone());
                let mut a = sets.clone();
                a.extend(s.sets.iter().cloned());
                next.push((n, a));
            }
        }
        combos = next;
    }
    let several = backends.len() > 1;
    backends
        .iter()
        .flat_map(|b| {
            combos.iter().map(move |(names, sets)| {
                let mut name = names.join(" ");
                if several {
                    name = format!("{} {name}", b.name());
                }
                Variant {
                    name,
                    tracker: b.name().to_string(),
                    sets: sets.clone(),
                }
            })
        })
        .collect()
}

/// A directory name for a variant: its name with everything but `[A-Za-z0-9._-]` as `_`.
pub fn variant_dir(variant: &Variant) -> String {
    variant
        .name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || "._-".contains(c) {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// Mean relative volume drift of one label over a variant's successful runs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LabelDrift {
    /// The label.
    pub label: u32,
    /// Mean of `(final − initial) / initial`.
    pub mean_relative_drift: f64,
}

/// A variant's results over its seeds. Everything but `runs`, `successes` and
/// `success_rate` is averaged over the successful runs (`None` without any).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct VariantSummary {
    /// The variant.
    pub variant: Variant,
    /// Runs.
    pub runs: usize,
    /// Successful runs (2024 paper §9.6).
    pub successes: usize,
    /// `successes / runs`.
    pub success_rate: f64,
    /// Mean wall seconds per step.
    pub seconds_per_step: Option<f64>,
    /// Mean seconds per step of every stage, pipeline order.
    pub stage_seconds_per_step: Vec<StageSeconds>,
    /// Mean triangles of the final mesh.
    pub final_triangles: Option<f64>,
    /// Mean relative volume drift per label.
    pub volume_drift: Vec<LabelDrift>,
    /// Mean fraction of untouched triangles ([`crate::preservation`]).
    pub untouched_fraction: Option<f64>,
    /// Mean feature distance (rigid-reference scenes only).
    pub feature_distance: Option<f64>,
    /// Topology events summed over the successful runs.
    pub events: EventCounts,
}

/// One run of an ablation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AblateRun {
    /// Variant name.
    pub variant: String,
    /// The child's summary.
    pub run: RunSummary,
    /// Its record directory, relative to the output directory.
    pub dir: String,
}

/// `ablate.json` (schema `surftrack.ablate/1`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct AblateRecord {
    /// [`ABLATE_SCHEMA`].
    pub schema: String,
    /// Scene.
    pub scene: String,
    /// Preset, if one was used.
    pub preset: Option<String>,
    /// Seeds, the same for every variant.
    pub seeds: Vec<u64>,
    /// Steps (`None`: the scene's).
    pub steps: Option<usize>,
    /// Summary per variant, in run order.
    pub variants: Vec<VariantSummary>,
    /// Every run.
    pub runs: Vec<AblateRun>,
}

/// Summarises a variant's runs (`records[i]` is the record of `runs[i]`, when the child
/// left one).
pub fn summarize(
    variant: &Variant,
    runs: &[RunSummary],
    records: &[Option<RunRecord>],
) -> VariantSummary {
    let ok: Vec<&RunRecord> = runs
        .iter()
        .zip(records)
        .filter(|(s, _)| s.success)
        .filter_map(|(_, r)| r.as_ref())
        .collect();
    let n = ok.len() as f64;
    let mean = |f: &dyn Fn(&RunRecord) -> Option<f64>| -> Option<f64> {
        let vals: Vec<f64> = ok.iter().filter_map(|r| f(r)).collect();
        (!vals.is_empty()).then(|| vals.iter().sum::<f64>() / vals.len() as f64)
    };
    let per_step = |r: &RunRecord| {
        (r.steps_completed > 0)
            .then(|| r.per_step.iter().map(|s| s.seconds).sum::<f64>() / r.steps_completed as f64)
    };
    let mut stages: Vec<StageSeconds> = Vec::new();
    for r in &ok {
        let steps = r.steps_completed.max(1) as f64;
        for s in &r.stage_seconds {
            add_stage_seconds(&mut stages, &s.stage, s.seconds / steps / n);
        }
    }
    let mut drift: Vec<(u32, f64, usize)> = Vec::new();
    for r in &ok {
        for v in &r.volumes {
            match drift.iter_mut().find(|d| d.0 == v.label) {
                Some(d) => {
                    d.1 += v.relative_drift;
                    d.2 += 1;
                }
                None => drift.push((v.label, v.relative_drift, 1)),
            }
        }
    }
    drift.sort_by_key(|d| d.0);
    let mut events = EventCounts::default();
    for r in &ok {
        events.add(&r.events);
    }
    let successes = runs.iter().filter(|s| s.success).count();
    VariantSummary {
        variant: variant.clone(),
        runs: runs.len(),
        successes,
        success_rate: if runs.is_empty() {
            0.0
        } else {
            successes as f64 / runs.len() as f64
        },
        seconds_per_step: mean(&per_step),
        stage_seconds_per_step: stages,
        final_triangles: mean(&|r: &RunRecord| r.per_step.last().map(|s| s.triangles as f64)),
        volume_drift: drift
            .into_iter()
            .map(|(label, sum, k)| LabelDrift {
                label,
                mean_relative_drift: sum / k as f64,
            })
            .collect(),
        untouched_fraction: mean(&|r: &RunRecord| {
            r.preservation.as_ref().map(|p| p.untouched_fraction)
        }),
        feature_distance: mean(&|r: &RunRecord| {
            r.preservation
                .as_ref()
                .and_then(|p| p.feature_distance_mean)
        }),
        events,
    }
}

/// Everything an ablation needs.
#[derive(Clone, Debug)]
pub struct AblatePlan {
    /// Scene.
    pub scene: String,
    /// Preset name, for the record.
    pub preset: Option<String>,
    /// The variants.
    pub variants: Vec<Variant>,
    /// Seeds.
    pub seeds: Vec<u64>,
    /// Child options (steps, count, triangle cap).
    pub child: ChildOptions,
    /// Extra child arguments every run gets (scene parameters, `--config`).
    pub extra_args: Vec<OsString>,
    /// Watchdog limits.
    pub limits: Limits,
    /// Children at once.
    pub jobs: usize,
    /// Output directory.
    pub out: PathBuf,
}

/// Runs every variant on every seed (isolated) and summarises.
pub fn ablate(exe: &Path, plan: &AblatePlan, progress: &ProgressBar) -> AblateRecord {
    let mut runs: Vec<ChildRun> = Vec::new();
    let mut owners: Vec<(usize, String)> = Vec::new();
    for (k, variant) in plan.variants.iter().enumerate() {
        let backend: Backend = variant.tracker.parse().unwrap_or(Backend::Grid);
        for &seed in &plan.seeds {
            let rel = format!("runs/{}/seed-{seed}", variant_dir(variant));
            let dir = plan.out.join(&rel);
            let mut args = child_args(&plan.scene, backend, seed, &dir, &plan.child);
            args.extend(plan.extra_args.iter().cloned());
            for s in &variant.sets {
                args.push("--set".into());
                args.push(s.into());
            }
            runs.push(ChildRun {
                tracker: variant.tracker.clone(),
                seed,
                args,
                dir,
            });
            owners.push((k, rel));
        }
    }
    progress.set_length(runs.len() as u64);
    let summaries = run_all(exe, &runs, &plan.limits, plan.jobs, progress);
    let records: Vec<Option<RunRecord>> = runs.iter().map(|r| read_run_record(&r.dir)).collect();
    let variants = plan
        .variants
        .iter()
        .enumerate()
        .map(|(k, v)| {
            let (s, r): (Vec<RunSummary>, Vec<Option<RunRecord>>) = owners
                .iter()
                .zip(summaries.iter().zip(&records))
                .filter(|((owner, _), _)| *owner == k)
                .map(|(_, (s, r))| (s.clone(), r.clone()))
                .unzip();
            summarize(v, &s, &r)
        })
        .collect();
    let runs = owners
        .into_iter()
        .zip(summaries)
        .map(|((k, dir), run)| AblateRun {
            variant: plan.variants[k].name.clone(),
            run,
            dir,
        })
        .collect();
    AblateRecord {
        schema: ABLATE_SCHEMA.to_string(),
        scene: plan.scene.clone(),
        preset: plan.preset.clone(),
        seeds: plan.seeds.clone(),
        steps: plan.child.steps,
        variants,
        runs,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn variants_are_the_cross_product_times_backends() {
        let a = parse_vary("grid.resampling=local,global").unwrap();
        let b = parse_vary("collision.t1=true, false").unwrap();
        let v = variants(
            &[Backend::Grid, Backend::Collision],
            &[a, b],
            &["x=1".into()],
        );
        assert_eq!(v.len(), 8);
        assert_eq!(v[0].name, "grid grid.resampling=local collision.t1=true");
        assert_eq!(
            v[0].sets,
            vec!["x=1", "grid.resampling=local", "collision.t1=true"]
        );
        assert_eq!(v[7].tracker, "collision");
        assert!(variant_dir(&v[0]).chars().all(|c| c != ' ' && c != '='));
        assert!(parse_vary("nothing").is_err() && parse_vary("a=").is_err());
    }

    #[test]
    fn every_preset_sets_known_options() {
        for p in PRESETS {
            assert!(p.settings.len() >= 2, "{}", p.name);
            let mut b = crate::options::OptionsBuilder::default();
            for s in p
                .fixed
                .iter()
                .chain(p.settings.iter().flat_map(|s| s.1.iter()))
            {
                b.set(s).unwrap_or_else(|e| panic!("{}: {e}", p.name));
            }
        }
        assert!(preset("resampling").is_some() && preset("nope").is_none());
    }
}
