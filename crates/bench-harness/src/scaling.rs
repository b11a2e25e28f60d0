//! `bench scaling`: how time and memory grow with the mesh (2024 paper Fig. 16: a
//! 5.3M-triangle union of 6 rotated copies resolved in 8 minutes).
//!
//! Two series, every point in its own child process under the watchdog (time-out and
//! resident-memory cap, [`crate::isolate`]), so each point's peak memory is its own:
//!
//! - **fix**: `k` rotated copies of Zalesak's notched sphere ([`generators::copies`]) at
//!   the resolution that gives about the requested input triangle count — or, with a
//!   base mesh (`--mesh`, e.g. a real scan), of that mesh split in four
//!   ([`generators::subdivide`]) as many times as comes nearest the count, so its shape
//!   stays the same at every size — repaired by `surftrack fix` (one shot, grid backend);
//!   per point the wall time of every stage of its report, the triangles in and out and
//!   the child's peak resident memory;
//! - **steps**: the `spheres` scene at increasing sphere counts through each backend
//!   (`surftrack run`), per point the mean seconds per step, the mean triangles per step
//!   and the peak memory.
//!
//! The **slope** of a quantity is the least-squares slope of `log y` against `log n` (`n`
//! the triangles) over the points that succeeded: 1 is linear scaling, 2 quadratic.

use std::ffi::OsString;
use std::path::{Path, PathBuf};

use mesh_core::generators;
use serde::{Deserialize, Serialize};
use surftrack::Backend;

use crate::bench::{ChildOptions, child_args};
use crate::isolate::{ChildRun, Limits, WatchedEnding, run_isolated, run_watched};
use crate::record::{StageSeconds, bytes_to_mib, per_million_triangles};

/// Version tag of `scaling.json`.
pub const SCALING_SCHEMA: &str = "surftrack.scaling/1";

/// One `fix` point.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FixPoint {
    /// Triangles asked for.
    pub target_triangles: usize,
    /// Notched-sphere resolution used; with a base mesh, the subdivision levels applied
    /// to it.
    pub resolution: u32,
    /// Triangles of the input (all copies).
    pub triangles_in: usize,
    /// Triangles of the output (0 when it failed).
    pub triangles_out: usize,
    /// Whether `fix` succeeded with a valid output.
    pub success: bool,
    /// Why not.
    pub failure: Option<String>,
    /// Wall time of the child, seconds (file reading and writing included).
    pub wall_seconds: f64,
    /// The stages of `fix`'s report.
    pub stages: Vec<StageSeconds>,
    /// `fix`'s own wall time (its report's `seconds`; file I/O excluded; absent from
    /// records written before it was reported).
    #[serde(default)]
    pub fix_seconds: Option<f64>,
    /// Peak resident memory of the child, MiB.
    pub peak_rss_mib: Option<f64>,
    /// `peak_rss_mib` per million input triangles.
    pub mib_per_million_triangles: Option<f64>,
    /// Cells of the flawed region `fix` rebuilt (its report's `flawed_cells`; absent from
    /// records written before it was kept). Why: where the copies overlap in volume, the
    /// region fills that volume, so it grows as the input triangles to the power 3/2, and
    /// a stage that labels every node of it (labels) grows with it, not with the surface.
    #[serde(default)]
    pub flawed_cells: Option<usize>,
    /// Runs of `fix` the times are the minimum of (`bench scaling --repeat`; 1 in records
    /// written before it existed).
    #[serde(default = "one_run")]
    pub runs: usize,
}

fn one_run() -> usize {
    1
}

impl FixPoint {
    /// This point and `other`, a run of `fix` on the same input, as one: each time the
    /// smaller (noise on a shared machine only ever adds time), peak memory the larger,
    /// and a failure of either run the point's failure.
    pub fn merge(self, other: FixPoint) -> FixPoint {
        if !self.success {
            return self;
        }
        if !other.success {
            return other;
        }
        // Either figure when only one run has it.
        let both = |a: Option<f64>, b: Option<f64>, pick: fn(f64, f64) -> f64| match (a, b) {
            (Some(a), Some(b)) => Some(pick(a, b)),
            (a, b) => a.or(b),
        };
        let mut stages = self.stages;
        for s in other.stages {
            match stages.iter_mut().find(|t| t.stage == s.stage) {
                Some(t) => t.seconds = t.seconds.min(s.seconds),
                None => stages.push(s),
            }
        }
        let peak_rss_mib = both(self.peak_rss_mib, other.peak_rss_mib, f64::max);
        FixPoint {
            wall_seconds: self.wall_seconds.min(other.wall_seconds),
            stages,
            fix_seconds: both(self.fix_seconds, other.fix_seconds, f64::min),
            peak_rss_mib,
            mib_per_million_triangles: per_million_triangles(peak_rss_mib, self.triangles_in),
            runs: self.runs + other.runs,
            ..self
        }
    }
}

/// One `steps` point.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StepPoint {
    /// Backend.
    pub tracker: String,
    /// Spheres.
    pub spheres: usize,
    /// Whether every step finished valid.
    pub success: bool,
    /// Why not.
    pub failure: Option<String>,
    /// Mean triangles after a step.
    pub mean_triangles: f64,
    /// Mean wall seconds per step.
    pub seconds_per_step: f64,
    /// Peak resident memory of the child, MiB.
    pub peak_rss_mib: Option<f64>,
    /// `peak_rss_mib` per million peak triangles.
    pub mib_per_million_triangles: Option<f64>,
}

/// A log–log slope.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Slope {
    /// What was fitted (`fix: <stage>`, `fix: total`, `grid: step`, …).
    pub what: String,
    /// The slope of `log y` against `log triangles`; `None` with fewer than two points.
    pub slope: Option<f64>,
    /// Points used.
    pub points: usize,
}

/// `scaling.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ScalingRecord {
    /// [`SCALING_SCHEMA`].
    pub schema: String,
    /// Copies per `fix` input.
    pub copies: usize,
    /// What was copied: the base mesh's file name, or `None` for the notched sphere.
    #[serde(default)]
    pub base_mesh: Option<String>,
    /// The `fix` points, by size.
    pub fix: Vec<FixPoint>,
    /// The step points, by backend then size.
    pub steps: Vec<StepPoint>,
    /// Slopes: per `fix` stage, `fix` total and memory, per backend step time and memory.
    pub slopes: Vec<Slope>,
}

impl FixPoint {
    /// `fix`'s wall time: its own figure, or (from a record without one) the sum of its
    /// stages. The stages overlap (the union reference runs beside improvement), so the
    /// sum is larger.
    pub fn total_seconds(&self) -> f64 {
        self.fix_seconds
            .unwrap_or_else(|| self.stages.iter().map(|s| s.seconds).sum())
    }
}

/// Least-squares slope of `ln y` on `ln x` over the positive, finite points.
pub fn log_log_slope(points: &[(f64, f64)]) -> Option<f64> {
    let logs: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0 && x.is_finite() && y.is_finite())
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    if logs.len() < 2 {
        return None;
    }
    let n = logs.len() as f64;
    let (mx, my) = logs
        .iter()
        .fold((0.0, 0.0), |(a, b), (x, y)| (a + x / n, b + y / n));
    let sxx: f64 = logs.iter().map(|(x, _)| (x - mx).powi(2)).sum();
    let sxy: f64 = logs.iter().map(|(x, y)| (x - mx) * (y - my)).sum();
    (sxx > 0.0).then(|| sxy / sxx)
}

/// The notched-sphere resolution whose `copies` copies have about `target` triangles
/// (triangles grow with the square of the resolution; calibrated on resolution 16).
pub fn resolution_for(target: usize, copies: usize) -> Result<u32, generators::GeneratorError> {
    const CALIBRATION: u32 = 16;
    let per_copy = generators::zalesak(CALIBRATION as usize)?.num_triangles() as f64;
    let scale = (target as f64 / (per_copy * copies.max(1) as f64)).sqrt();
    Ok(((f64::from(CALIBRATION) * scale).round() as u32).max(4))
}

/// The subdivision levels of a base mesh of `base` triangles whose `copies` copies come
/// nearest `target` triangles (nearest on a log scale; each level multiplies by 4).
pub fn levels_for(target: usize, copies: usize, base: usize) -> u32 {
    let ratio = target as f64 / (base.max(1) as f64 * copies.max(1) as f64);
    ratio.log(4.0).round().max(0.0) as u32
}

/// Everything `bench scaling` needs.
#[derive(Clone, Debug)]
pub struct ScalingPlan {
    /// Input triangle counts of the `fix` series (empty: none).
    pub fix_triangles: Vec<usize>,
    /// Copies per input.
    pub copies: usize,
    /// The mesh to copy instead of the notched sphere, and its name for the report.
    pub base_mesh: Option<(String, mesh_core::LabeledMesh)>,
    /// Sphere counts of the step series (empty: none).
    pub spheres: Vec<usize>,
    /// Steps per sphere run.
    pub steps: usize,
    /// Backends of the step series.
    pub backends: Vec<Backend>,
    /// Watchdog limits of every child.
    pub limits: Limits,
    /// Output directory.
    pub out: PathBuf,
    /// Seed (copies' rotations, sphere placement).
    pub seed: u64,
    /// Runs of each `fix` point ([`FixPoint::merge`]).
    pub repeat: usize,
}

/// One `fix` point: writes the input, runs `surftrack fix` on it in a child.
fn fix_point(exe: &Path, plan: &ScalingPlan, target: usize) -> anyhow::Result<FixPoint> {
    let dir = plan.out.join(format!("fix-{target}"));
    std::fs::create_dir_all(&dir)?;
    let (resolution, base) = match &plan.base_mesh {
        Some((_, mesh)) => {
            let levels = levels_for(target, plan.copies, mesh.num_triangles());
            (levels, generators::subdivide(mesh, levels)?)
        }
        None => {
            let resolution = resolution_for(target, plan.copies)?;
            (resolution, generators::zalesak(resolution as usize)?)
        }
    };
    let input = generators::copies(&base, plan.copies, plan.seed)?;
    let triangles_in = input.num_triangles();
    let input_path = dir.join("input.ply");
    mesh_core::io::write_mesh(&input, &input_path)?;
    // The parent holds no copy of a 5M-triangle input while the child runs.
    drop((input, base));
    let run = || {
        fix_run(
            exe,
            plan,
            &dir,
            &input_path,
            target,
            resolution,
            triangles_in,
        )
    };
    let point = (1..plan.repeat).fold(run(), |point, _| point.merge(run()));
    Ok(point)
}

/// One run of `surftrack fix` on the point's input, in a watched child.
fn fix_run(
    exe: &Path,
    plan: &ScalingPlan,
    dir: &Path,
    input_path: &Path,
    target: usize,
    resolution: u32,
    triangles_in: usize,
) -> FixPoint {
    let args: Vec<OsString> = vec![
        "fix".into(),
        input_path.into(),
        dir.join("output.ply").into(),
        "--json".into(),
        "--binary".into(),
        "--no-intersection-check".into(),
    ];
    let watched = run_watched(
        exe,
        &args,
        &dir.join("fix.json"),
        &dir.join("child.log"),
        &plan.limits,
    );
    let mut point = FixPoint {
        target_triangles: target,
        resolution,
        triangles_in,
        triangles_out: 0,
        success: false,
        failure: None,
        wall_seconds: watched.wall_seconds,
        stages: Vec::new(),
        fix_seconds: None,
        peak_rss_mib: (watched.sampled_peak_rss_bytes > 0)
            .then(|| bytes_to_mib(watched.sampled_peak_rss_bytes)),
        mib_per_million_triangles: None,
        flawed_cells: None,
        runs: 1,
    };
    match watched.ending {
        WatchedEnding::Exited(code) => {
            let text = std::fs::read_to_string(dir.join("fix.json")).unwrap_or_default();
            match serde_json::from_str::<serde_json::Value>(&text) {
                Ok(record) => {
                    let report = &record["report"];
                    point.success = code == Some(0) && record["valid"] == true;
                    if !point.success {
                        point.failure = Some(format!("fix exited with {code:?}: {}", record));
                    }
                    point.triangles_out = report["triangles_out"].as_u64().unwrap_or(0) as usize;
                    if let Some(stages) = report["stages"].as_array() {
                        point.stages = stages
                            .iter()
                            .filter_map(|s| {
                                Some(StageSeconds {
                                    stage: s["stage"].as_str()?.to_string(),
                                    seconds: s["seconds"].as_f64()?,
                                })
                            })
                            .collect();
                    }
                    point.fix_seconds = report["seconds"].as_f64();
                    point.flawed_cells = report["flawed_cells"].as_u64().map(|n| n as usize);
                    if let Some(mib) = record["peak_rss_mib"].as_f64() {
                        point.peak_rss_mib = Some(mib);
                    }
                }
                Err(_) => {
                    point.failure = Some(format!(
                        "fix exited with {code:?} without a record; see {}",
                        dir.join("child.log").display()
                    ));
                }
            }
        }
        WatchedEnding::Killed(reason, message) => {
            point.failure = Some(format!("{}: {message}", reason.name()));
        }
        WatchedEnding::Failed(message) => point.failure = Some(message),
    }
    point.mib_per_million_triangles = per_million_triangles(point.peak_rss_mib, triangles_in);
    point
}

/// One step point: the `spheres` scene in a child `run`.
fn step_point(exe: &Path, plan: &ScalingPlan, backend: Backend, spheres: usize) -> StepPoint {
    let dir = plan.out.join(format!("steps-{}-{spheres}", backend.name()));
    let options = ChildOptions {
        steps: Some(plan.steps),
        count: Some(spheres),
        every: 0,
        max_triangles: usize::MAX,
        simulate: None,
    };
    let run = ChildRun {
        tracker: backend.name().to_string(),
        seed: plan.seed,
        args: child_args("spheres", backend, plan.seed, &dir, &options),
        dir,
    };
    let s = run_isolated(exe, &run, &plan.limits);
    let n = s.step_seconds.len().max(1) as f64;
    StepPoint {
        tracker: s.tracker.clone(),
        spheres,
        success: s.success,
        failure: s
            .failure
            .as_ref()
            .map(|f| format!("{}: {}", f.reason.name(), f.message)),
        mean_triangles: s.step_triangles.iter().sum::<usize>() as f64 / n,
        seconds_per_step: s.step_seconds.iter().sum::<f64>() / n,
        peak_rss_mib: s.peak_rss_mib,
        mib_per_million_triangles: s.mib_per_million_triangles,
    }
}

/// The slopes of a record's points (see the module doc).
pub fn slopes(fix: &[FixPoint], steps: &[StepPoint], backends: &[Backend]) -> Vec<Slope> {
    let mut out = Vec::new();
    let ok: Vec<&FixPoint> = fix.iter().filter(|p| p.success).collect();
    let mut stage_names: Vec<&str> = Vec::new();
    for p in &ok {
        for s in &p.stages {
            if !stage_names.contains(&s.stage.as_str()) {
                stage_names.push(&s.stage);
            }
        }
    }
    let mut fit = |what: String, points: Vec<(f64, f64)>| {
        out.push(Slope {
            what,
            slope: log_log_slope(&points),
            points: points.len(),
        });
    };
    for stage in stage_names {
        let points = ok
            .iter()
            .filter_map(|p| {
                let s = p.stages.iter().find(|s| s.stage == stage)?;
                Some((p.triangles_in as f64, s.seconds))
            })
            .collect();
        fit(format!("fix: {stage}"), points);
    }
    fit(
        "fix: total".into(),
        ok.iter()
            .map(|p| (p.triangles_in as f64, p.total_seconds()))
            .collect(),
    );
    fit(
        "fix: peak memory".into(),
        ok.iter()
            .filter_map(|p| Some((p.triangles_in as f64, p.peak_rss_mib?)))
            .collect(),
    );
    // The region's own growth, and the labels stage against it rather than against the
    // surface: together they tell a stage that is slow per node from a region that grows
    // faster than the surface (see [`FixPoint::flawed_cells`]).
    fit(
        "fix: flawed cells".into(),
        ok.iter()
            .filter_map(|p| Some((p.triangles_in as f64, p.flawed_cells? as f64)))
            .collect(),
    );
    fit(
        "fix: labels against flawed cells".into(),
        ok.iter()
            .filter_map(|p| {
                let s = p.stages.iter().find(|s| s.stage == "labels")?;
                Some((p.flawed_cells? as f64, s.seconds))
            })
            .collect(),
    );
    for b in backends {
        let ok: Vec<&StepPoint> = steps
            .iter()
            .filter(|p| p.success && p.tracker == b.name())
            .collect();
        fit(
            format!("{}: seconds per step", b.name()),
            ok.iter()
                .map(|p| (p.mean_triangles, p.seconds_per_step))
                .collect(),
        );
        fit(
            format!("{}: peak memory", b.name()),
            ok.iter()
                .filter_map(|p| Some((p.mean_triangles, p.peak_rss_mib?)))
                .collect(),
        );
    }
    out
}

/// Runs every point of the plan, smallest first, calling `progress` after each.
pub fn scaling(
    exe: &Path,
    plan: &ScalingPlan,
    mut progress: impl FnMut(&str),
) -> anyhow::Result<ScalingRecord> {
    std::fs::create_dir_all(&plan.out)?;
    let mut fix = Vec::new();
    let mut sizes = plan.fix_triangles.clone();
    sizes.sort_unstable();
    if let Some((_, mesh)) = &plan.base_mesh {
        // Targets that round to the same subdivision level would repeat one input.
        sizes.dedup_by_key(|&mut t| levels_for(t, plan.copies, mesh.num_triangles()));
    }
    for target in sizes {
        let point = fix_point(exe, plan, target)?;
        progress(&format!(
            "fix {} triangles: {}",
            point.triangles_in,
            if point.success { "ok" } else { "failed" }
        ));
        fix.push(point);
    }
    let mut steps = Vec::new();
    let mut counts = plan.spheres.clone();
    counts.sort_unstable();
    for &backend in &plan.backends {
        for &n in &counts {
            let point = step_point(exe, plan, backend, n);
            progress(&format!(
                "{} {n} spheres: {}",
                backend.name(),
                if point.success { "ok" } else { "failed" }
            ));
            steps.push(point);
        }
    }
    let slopes = slopes(&fix, &steps, &plan.backends);
    Ok(ScalingRecord {
        schema: SCALING_SCHEMA.to_string(),
        copies: plan.copies,
        base_mesh: plan.base_mesh.as_ref().map(|(name, _)| name.clone()),
        fix,
        steps,
        slopes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slopes_of_power_laws_are_their_exponents() {
        let linear: Vec<(f64, f64)> = [1e5, 2e5, 4e5].iter().map(|&n| (n, 3e-6 * n)).collect();
        assert!((log_log_slope(&linear).unwrap() - 1.0).abs() < 1e-12);
        let square: Vec<(f64, f64)> = [1e5, 1e6].iter().map(|&n| (n, n * n)).collect();
        assert!((log_log_slope(&square).unwrap() - 2.0).abs() < 1e-12);
        assert_eq!(log_log_slope(&[(1.0, 1.0)]), None);
        assert_eq!(
            log_log_slope(&[(1.0, 1.0), (1.0, 2.0)]),
            None,
            "one size only"
        );
    }

    #[test]
    fn subdivision_levels_come_nearest_the_target() {
        // 6 copies of 56k triangles: 337k, 1.35M, 5.4M at levels 0, 1, 2.
        assert_eq!(levels_for(100_000, 6, 56_172), 0);
        assert_eq!(levels_for(337_000, 6, 56_172), 0);
        assert_eq!(levels_for(1_000_000, 6, 56_172), 1);
        assert_eq!(levels_for(1_350_000, 6, 56_172), 1);
        assert_eq!(levels_for(3_000_000, 6, 56_172), 2);
        assert_eq!(levels_for(5_400_000, 6, 56_172), 2);
    }

    #[test]
    fn resolutions_grow_with_the_square_root_of_the_triangles() {
        let r1 = resolution_for(100_000, 6).unwrap();
        let r4 = resolution_for(400_000, 6).unwrap();
        assert!(
            (f64::from(r4) / f64::from(r1) - 2.0).abs() < 0.1,
            "{r1} {r4}"
        );
        let tris = 6 * generators::zalesak(r1 as usize).unwrap().num_triangles();
        assert!((tris as f64 / 1e5 - 1.0).abs() < 0.15, "{tris}");
    }

    #[test]
    fn slopes_skip_failed_points() {
        let point = |n: usize, s: f64, success| FixPoint {
            target_triangles: n,
            resolution: 8,
            triangles_in: n,
            triangles_out: n,
            success,
            failure: None,
            wall_seconds: s,
            stages: vec![StageSeconds {
                stage: "labels".into(),
                seconds: s,
            }],
            fix_seconds: Some(s),
            peak_rss_mib: Some(n as f64 / 1000.0),
            mib_per_million_triangles: Some(1000.0),
            // A region growing as n^1.5 while labels time grows as n: slope 2/3 against it.
            flawed_cells: Some((n as f64).powf(1.5) as usize),
            runs: 1,
        };
        // Runs merge stage by stage to the smaller time, memory to the larger; a failed
        // run fails the point.
        let mut slow = point(1000, 3.0, true);
        slow.stages.push(StageSeconds {
            stage: "cut".into(),
            seconds: 0.5,
        });
        slow.peak_rss_mib = Some(7.0);
        let merged = point(1000, 1.0, true).merge(slow);
        assert_eq!(
            (merged.runs, merged.wall_seconds, merged.peak_rss_mib),
            (2, 1.0, Some(7.0))
        );
        let seconds: Vec<(&str, f64)> = merged
            .stages
            .iter()
            .map(|s| (s.stage.as_str(), s.seconds))
            .collect();
        assert_eq!(seconds, [("labels", 1.0), ("cut", 0.5)]);
        assert!(
            !point(1000, 1.0, true)
                .merge(point(1000, 0.5, false))
                .success
        );
        let fix = [
            point(1000, 1.0, true),
            point(2000, 2.0, true),
            point(4000, 100.0, false),
        ];
        let s = slopes(&fix, &[], &[]);
        let labels = s.iter().find(|s| s.what == "fix: labels").unwrap();
        assert_eq!(labels.points, 2);
        assert!((labels.slope.unwrap() - 1.0).abs() < 1e-12);
        let memory = s.iter().find(|s| s.what == "fix: peak memory").unwrap();
        assert!((memory.slope.unwrap() - 1.0).abs() < 1e-12);
        let cells = s.iter().find(|s| s.what == "fix: flawed cells").unwrap();
        assert!((cells.slope.unwrap() - 1.5).abs() < 1e-4, "{cells:?}");
        let per_cell = s
            .iter()
            .find(|s| s.what == "fix: labels against flawed cells")
            .unwrap();
        assert!(
            (per_cell.slope.unwrap() - 2.0 / 3.0).abs() < 1e-4,
            "{per_cell:?}"
        );
    }
}
