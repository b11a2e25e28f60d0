//! The run records: what `surftrack run` writes to `run.json` and what the robustness
//! benchmark keeps per seed. Stable, documented schemas, versioned by their `schema` field,
//! so scripts can read records written by older builds.
//!
//! # `run.json` (schema `surftrack.run/1`)
//!
//! | field | type | meaning |
//! |---|---|---|
//! | `schema` | string | always `"surftrack.run/1"` |
//! | `scene` | string | scene name (`surftrack scenes`) |
//! | `tracker` | string | backend name (`grid`, `collision`) |
//! | `seed` | integer | random seed of the scene |
//! | `count` | integer or null | spheres / cells / copies, when the scene has such a count |
//! | `dt` | number | the scene's time step (a flow may take smaller stable steps) |
//! | `steps` | integer | steps requested |
//! | `steps_completed` | integer | steps the tracker finished |
//! | `success` | bool | finished every step, every frame valid, no limit hit |
//! | `failure` | object or null | `{"reason": R, "message": "…", "step": k or null}`, `R` one of [`FailureReason`] in snake case |
//! | `wall_seconds` | number | wall time of the whole run (scene building excluded) |
//! | `peak_triangles` | integer | most live triangles seen, initial mesh included |
//! | `events` | object | topology events summed over steps ([`EventCounts`]) |
//! | `stage_seconds` | array | `[{"stage": name, "seconds": s}]` summed over steps, pipeline order |
//! | `initial` | object | `{"vertices", "triangles", "valid"}` of the mesh handed to the tracker |
//! | `frames` | array | `[{"step": k, "file": "frame_0000.ply"}]` written frames, relative to the record |
//! | `per_step` | array | one [`StepRecord`] per finished step |
//! | `options` | object | effective options ([`RunOptions`]: `grid`, `collision`, `flow`) |
//! | `scene_params` | object | `count`, `resolution`, `radius`, `mesh` as given (null: default) |
//! | `threads` | integer | rayon threads of the run |
//! | `volumes` | array | `[{"label", "initial", "last", "relative_drift"}]` per material |
//! | `preservation` | object | untouched triangles and feature distance ([`Preservation`]) |
//! | `final_digest` | string | digest of the final mesh (equal digests: the same mesh) |
//! | `peak_rss_mib` | number or null | peak resident memory of the process (Linux `VmHWM`), MiB |
//! | `mib_per_million_triangles` | number or null | `peak_rss_mib` per million `peak_triangles` |
//!
//! A [`StepRecord`] holds `step` (1-based), `t` (time at the start of the step), `dt`,
//! `seconds` (wall time of proposal + advance), `stages`, `triangles`, `vertices`,
//! `events`, `substeps` and `valid` (the step's mesh passed `validate()`).
//!
//! # `robustness.json` (schema `surftrack.robustness/1`)
//!
//! `config` ([`BenchConfig`]), `runs` (one [`RunSummary`] per tracker × seed, sorted by
//! tracker then seed) and `summary` (one [`BackendSummary`] per tracker). Shards of the
//! same benchmark differ only in `config.shard` and their runs; [`merge_records`] joins
//! them into the record an unsharded run would have written.
//!
//! # `compare.json` (schema `surftrack.compare/1`)
//!
//! `seed` and `rows`: one [`CompareRow`] (`scene`, `steps`, `run`: a
//! [`RunSummary`]) per scene × backend.

use std::collections::BTreeMap;

use mesh_core::{StepReport, TopologyEvents};
use serde::{Deserialize, Serialize};

use crate::options::RunOptions;
use crate::preservation::Preservation;

/// Version tag of `run.json`.
pub const RUN_SCHEMA: &str = "surftrack.run/1";
/// Version tag of `robustness.json`.
pub const ROBUSTNESS_SCHEMA: &str = "surftrack.robustness/1";
/// Version tag of `compare.json`.
pub const COMPARE_SCHEMA: &str = "surftrack.compare/1";

/// Why a run did not succeed, in the categories of the 2024 paper's robustness benchmark
/// (§9.6: no crash, error, time-out or memory blow-up, every frame valid) plus the ones a
/// harness needs to tell apart from a tracker failure.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FailureReason {
    /// The backend is not available in this build: not a tracker failure, but no success.
    Unavailable,
    /// `advance` returned an error.
    Error,
    /// The tracker panicked (caught in the run, or the child exited as a panic).
    Panic,
    /// A frame failed `validate()`.
    Invalid,
    /// The watchdog killed the run at its time limit.
    Timeout,
    /// Triangle count or resident memory above the cap.
    Memory,
    /// The child process died without a record (signal, unexpected exit).
    Crash,
}

impl FailureReason {
    /// Every reason, in table order.
    pub const ALL: [FailureReason; 7] = [
        FailureReason::Unavailable,
        FailureReason::Error,
        FailureReason::Panic,
        FailureReason::Invalid,
        FailureReason::Timeout,
        FailureReason::Memory,
        FailureReason::Crash,
    ];

    /// The snake-case name used in records and tables.
    pub fn name(self) -> &'static str {
        match self {
            FailureReason::Unavailable => "unavailable",
            FailureReason::Error => "error",
            FailureReason::Panic => "panic",
            FailureReason::Invalid => "invalid",
            FailureReason::Timeout => "timeout",
            FailureReason::Memory => "memory",
            FailureReason::Crash => "crash",
        }
    }
}

impl std::fmt::Display for FailureReason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Why a run failed, with the message a user needs to find the cause.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Failure {
    /// The category.
    pub reason: FailureReason,
    /// Human-readable details (the tracker's error, the validation summary, …).
    pub message: String,
    /// The step that failed (1-based), when known.
    pub step: Option<usize>,
}

/// Topology events, summable, with the field names of [`TopologyEvents`]; our own type so
/// records can be read back (mesh-core's type is serialise-only).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct EventCounts {
    /// Regions joined.
    pub merges: u64,
    /// Regions pulled apart.
    pub splits: u64,
    /// T1 vertex separations.
    pub t1: u64,
    /// T2 degenerate-tetrahedron removals.
    pub t2: u64,
    /// Splits, flips, collapses and smoothing moves of mesh improvement.
    pub remeshing_edits: u64,
}

impl EventCounts {
    /// Adds another count in place.
    pub fn add(&mut self, other: &EventCounts) {
        self.merges += other.merges;
        self.splits += other.splits;
        self.t1 += other.t1;
        self.t2 += other.t2;
        self.remeshing_edits += other.remeshing_edits;
    }

    /// Merges + splits + T1 + T2: the topology changes, remeshing excluded.
    pub fn topology_changes(&self) -> u64 {
        self.merges + self.splits + self.t1 + self.t2
    }
}

impl From<&TopologyEvents> for EventCounts {
    fn from(e: &TopologyEvents) -> Self {
        EventCounts {
            merges: e.merges,
            splits: e.splits,
            t1: e.t1,
            t2: e.t2,
            remeshing_edits: e.remeshing_edits,
        }
    }
}

/// Seconds spent in one pipeline stage.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StageSeconds {
    /// Stage name as the backend reports it.
    pub stage: String,
    /// Seconds.
    pub seconds: f64,
}

/// Adds `(stage, seconds)` to a list kept in first-seen (pipeline) order; stage lists
/// are a handful long, so a linear search beats a map and keeps the order.
pub fn add_stage_seconds(totals: &mut Vec<StageSeconds>, stage: &str, seconds: f64) {
    match totals.iter_mut().find(|s| s.stage == stage) {
        Some(s) => s.seconds += seconds,
        None => totals.push(StageSeconds {
            stage: stage.to_string(),
            seconds,
        }),
    }
}

/// One finished step of a run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StepRecord {
    /// Step number, from 1.
    pub step: usize,
    /// Time at the start of the step.
    pub t: f64,
    /// Time step taken.
    pub dt: f64,
    /// Wall time of proposing and advancing.
    pub seconds: f64,
    /// Per-stage times reported by the tracker.
    pub stages: Vec<StageSeconds>,
    /// Live triangles after the step.
    pub triangles: usize,
    /// Live vertices after the step.
    pub vertices: usize,
    /// Events of this step.
    pub events: EventCounts,
    /// Sub-steps the tracker took.
    pub substeps: u32,
    /// The mesh after the step passed `validate()`.
    pub valid: bool,
    /// Materials that vanished in this step ([`TopologyEvents::vanished`]); absent from
    /// the JSON when none did.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub vanished: Vec<u32>,
}

impl StepRecord {
    /// The record of a successful `advance`.
    pub fn from_report(step: usize, t: f64, dt: f64, seconds: f64, report: &StepReport) -> Self {
        StepRecord {
            step,
            t,
            dt,
            seconds,
            stages: report
                .stages
                .iter()
                .map(|s| StageSeconds {
                    stage: s.stage.to_string(),
                    seconds: s.seconds,
                })
                .collect(),
            triangles: report.triangles,
            vertices: report.vertices,
            events: EventCounts::from(&report.events),
            substeps: report.substeps,
            valid: true,
            vanished: report.events.vanished.iter().map(|l| l.raw()).collect(),
        }
    }
}

/// Size and validity of the initial mesh.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MeshSummary {
    /// Live vertices.
    pub vertices: usize,
    /// Live triangles.
    pub triangles: usize,
    /// Passed `validate()`.
    pub valid: bool,
}

/// A written frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrameRecord {
    /// Step after which it was written (0 = initial mesh).
    pub step: usize,
    /// File name, relative to the directory of the record.
    pub file: String,
}

/// The record of one run: `run.json` (see the module doc for the schema).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunRecord {
    /// [`RUN_SCHEMA`].
    pub schema: String,
    /// Scene name.
    pub scene: String,
    /// Backend name.
    pub tracker: String,
    /// Scene seed.
    pub seed: u64,
    /// Spheres, cells or copies, when the scene has a count.
    pub count: Option<usize>,
    /// The scene's time step.
    pub dt: f64,
    /// Steps requested.
    pub steps: usize,
    /// Steps finished.
    pub steps_completed: usize,
    /// Whether the run succeeded (see [`FailureReason`] for the ways it cannot).
    pub success: bool,
    /// Why not, if not.
    pub failure: Option<Failure>,
    /// Wall time of the run, scene building excluded.
    pub wall_seconds: f64,
    /// Most live triangles seen.
    pub peak_triangles: usize,
    /// Events summed over steps.
    pub events: EventCounts,
    /// Stage times summed over steps.
    pub stage_seconds: Vec<StageSeconds>,
    /// The initial mesh.
    pub initial: MeshSummary,
    /// Frames written.
    pub frames: Vec<FrameRecord>,
    /// Every finished step.
    pub per_step: Vec<StepRecord>,
    /// The effective options of the run (both backends and the flows), so that the record
    /// alone reproduces it (`surftrack run --from-record`). Absent in records of older
    /// builds.
    #[serde(default)]
    pub options: Option<RunOptions>,
    /// The scene parameters given on the command line (absent: the scene's defaults).
    #[serde(default)]
    pub scene_params: Option<SceneParams>,
    /// Rayon worker threads of the run (results are bit-identical for the same seed,
    /// options and thread count).
    #[serde(default)]
    pub threads: usize,
    /// Volume per material label, initial and final (label 0, the unbounded outside,
    /// excluded).
    #[serde(default)]
    pub volumes: Vec<LabelVolume>,
    /// How much of the original surface the run kept ([`crate::preservation`]).
    #[serde(default)]
    pub preservation: Option<Preservation>,
    /// FNV-1a digest (hex) of the final mesh's vertex position bits, triangles and labels:
    /// two runs with equal digests produced the same mesh.
    #[serde(default)]
    pub final_digest: Option<String>,
    /// Peak resident memory of the process that ran it, MiB (Linux `VmHWM`; `None`
    /// elsewhere). Scene building included: it is the figure a cluster's memory limit
    /// sees.
    #[serde(default)]
    pub peak_rss_mib: Option<f64>,
    /// `peak_rss_mib` per million `peak_triangles`: comparable across sizes.
    #[serde(default)]
    pub mib_per_million_triangles: Option<f64>,
}

impl RunRecord {
    /// Fills the memory fields from this process's peak resident set.
    pub fn record_memory(&mut self) {
        self.peak_rss_mib = crate::isolate::own_peak_resident_bytes().map(bytes_to_mib);
        self.mib_per_million_triangles =
            per_million_triangles(self.peak_rss_mib, self.peak_triangles);
    }
}

/// Bytes as MiB.
pub fn bytes_to_mib(bytes: u64) -> f64 {
    bytes as f64 / (1u64 << 20) as f64
}

/// MiB per million triangles, when both are known and the mesh is not empty.
pub fn per_million_triangles(mib: Option<f64>, triangles: usize) -> Option<f64> {
    mib.filter(|_| triangles > 0)
        .map(|m| m / (triangles as f64 / 1e6))
}

/// Scene parameters as given (`None`: the scene's default), for replays.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SceneParams {
    /// `--count`.
    pub count: Option<usize>,
    /// `--resolution`.
    pub resolution: Option<u32>,
    /// `--radius`.
    pub radius: Option<f64>,
    /// `--mesh` (path as given).
    pub mesh: Option<String>,
}

/// One material's volume at the start and the end of a run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LabelVolume {
    /// The label.
    pub label: u32,
    /// Volume of the initial mesh.
    pub initial: f64,
    /// Volume of the final mesh.
    pub last: f64,
    /// `(last − initial) / initial` (0 when the initial volume is 0).
    pub relative_drift: f64,
}

/// The parameters of a robustness benchmark, identical across its shards.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BenchConfig {
    /// The scene (`spheres`).
    pub scene: String,
    /// Spheres per run.
    pub spheres: usize,
    /// All seeds of the benchmark (every shard lists them all).
    pub seeds: Vec<u64>,
    /// Steps per run.
    pub steps: usize,
    /// Backends, in table order.
    pub trackers: Vec<String>,
    /// Watchdog limit per run, seconds.
    pub timeout_seconds: f64,
    /// Triangle cap per run (the memory guard inside the child).
    pub max_triangles: usize,
    /// Resident-memory cap per child, MiB (checked by the watchdog on Linux).
    pub max_memory_mib: u64,
    /// `[index, count]` of this shard, `None` for a whole (or merged) benchmark.
    pub shard: Option<[usize; 2]>,
}

/// One tracker × seed of the robustness benchmark.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunSummary {
    /// Backend name.
    pub tracker: String,
    /// Seed.
    pub seed: u64,
    /// Success as in the 2024 paper §9.6.
    pub success: bool,
    /// Why not.
    pub failure: Option<Failure>,
    /// Wall time of the child process (start to exit), seconds.
    pub wall_seconds: f64,
    /// Steps finished.
    pub steps_completed: usize,
    /// Triangles of the initial mesh (0 when the run left no record).
    pub initial_triangles: usize,
    /// Most live triangles seen.
    pub peak_triangles: usize,
    /// Events summed over steps.
    pub events: EventCounts,
    /// Stage times summed over steps.
    pub stage_seconds: Vec<StageSeconds>,
    /// Wall seconds of every finished step (for the plots).
    pub step_seconds: Vec<f64>,
    /// Triangles after every finished step (for the plots).
    pub step_triangles: Vec<usize>,
    /// Peak resident memory, MiB: the child's own `VmHWM`, or for a run killed before it
    /// wrote a record the largest resident set the watchdog saw.
    #[serde(default)]
    pub peak_rss_mib: Option<f64>,
    /// `peak_rss_mib` per million `peak_triangles`.
    #[serde(default)]
    pub mib_per_million_triangles: Option<f64>,
}

impl RunSummary {
    /// Triangles at the end: after the last finished step, or initially.
    pub fn final_triangles(&self) -> usize {
        self.step_triangles
            .last()
            .copied()
            .unwrap_or(self.initial_triangles)
    }

    /// The summary of a run record, with the wall time measured by whoever ran it.
    pub fn from_record(record: &RunRecord, wall_seconds: f64) -> Self {
        RunSummary {
            tracker: record.tracker.clone(),
            seed: record.seed,
            success: record.success,
            failure: record.failure.clone(),
            wall_seconds,
            steps_completed: record.steps_completed,
            initial_triangles: record.initial.triangles,
            peak_triangles: record.peak_triangles,
            events: record.events,
            stage_seconds: record.stage_seconds.clone(),
            step_seconds: record.per_step.iter().map(|s| s.seconds).collect(),
            step_triangles: record.per_step.iter().map(|s| s.triangles).collect(),
            peak_rss_mib: record.peak_rss_mib,
            mib_per_million_triangles: record.mib_per_million_triangles,
        }
    }

    /// A run that left no record (killed, crashed, not started).
    pub fn failed(tracker: &str, seed: u64, failure: Failure, wall_seconds: f64) -> Self {
        RunSummary {
            tracker: tracker.to_string(),
            seed,
            success: false,
            failure: Some(failure),
            wall_seconds,
            steps_completed: 0,
            initial_triangles: 0,
            peak_triangles: 0,
            events: EventCounts::default(),
            stage_seconds: Vec::new(),
            step_seconds: Vec::new(),
            step_triangles: Vec::new(),
            peak_rss_mib: None,
            mib_per_million_triangles: None,
        }
    }
}

/// Per-backend statistics of the robustness benchmark (what `--json` prints).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BackendSummary {
    /// Backend name.
    pub tracker: String,
    /// Runs recorded.
    pub runs: usize,
    /// Successful runs.
    pub successes: usize,
    /// `successes / runs` (0 when there are no runs).
    pub success_rate: f64,
    /// Mean wall seconds of the successful runs (`null` if none succeeded).
    pub mean_seconds: Option<f64>,
    /// Median wall seconds of the successful runs.
    pub median_seconds: Option<f64>,
    /// Longest successful run.
    pub max_seconds: Option<f64>,
    /// Failures by reason (snake-case names).
    pub failures: BTreeMap<String, usize>,
    /// Mean seconds per stage over the successful runs, pipeline order.
    pub mean_stage_seconds: Vec<StageSeconds>,
    /// Mean topology changes (merges + splits + T1 + T2) per successful run.
    pub mean_topology_changes: Option<f64>,
    /// Largest peak triangle count over all runs.
    pub peak_triangles: usize,
    /// Largest peak resident memory over all runs, MiB.
    #[serde(default)]
    pub max_peak_rss_mib: Option<f64>,
    /// Largest MiB per million triangles over all runs.
    #[serde(default)]
    pub max_mib_per_million_triangles: Option<f64>,
}

impl BackendSummary {
    /// Statistics over `runs` (all of one tracker).
    pub fn of_runs<'a>(tracker: &str, runs: impl IntoIterator<Item = &'a RunSummary>) -> Self {
        let mut summary = BackendSummary {
            tracker: tracker.to_string(),
            runs: 0,
            successes: 0,
            success_rate: 0.0,
            mean_seconds: None,
            median_seconds: None,
            max_seconds: None,
            failures: BTreeMap::new(),
            mean_stage_seconds: Vec::new(),
            mean_topology_changes: None,
            peak_triangles: 0,
            max_peak_rss_mib: None,
            max_mib_per_million_triangles: None,
        };
        let max = |a: Option<f64>, b: Option<f64>| match (a, b) {
            (Some(x), Some(y)) => Some(x.max(y)),
            (x, y) => x.or(y),
        };
        let mut times = Vec::new();
        let mut changes = 0u64;
        for run in runs {
            summary.runs += 1;
            summary.peak_triangles = summary.peak_triangles.max(run.peak_triangles);
            summary.max_peak_rss_mib = max(summary.max_peak_rss_mib, run.peak_rss_mib);
            summary.max_mib_per_million_triangles = max(
                summary.max_mib_per_million_triangles,
                run.mib_per_million_triangles,
            );
            if run.success {
                summary.successes += 1;
                times.push(run.wall_seconds);
                changes += run.events.topology_changes();
                for s in &run.stage_seconds {
                    add_stage_seconds(&mut summary.mean_stage_seconds, &s.stage, s.seconds);
                }
            } else if let Some(f) = &run.failure {
                *summary
                    .failures
                    .entry(f.reason.name().to_string())
                    .or_default() += 1;
            }
        }
        if summary.runs > 0 {
            summary.success_rate = summary.successes as f64 / summary.runs as f64;
        }
        if !times.is_empty() {
            let n = times.len() as f64;
            summary.mean_seconds = Some(times.iter().sum::<f64>() / n);
            summary.median_seconds = Some(median(&mut times));
            summary.max_seconds = times.iter().copied().reduce(f64::max);
            summary.mean_topology_changes = Some(changes as f64 / n);
            for s in &mut summary.mean_stage_seconds {
                s.seconds /= n;
            }
        }
        summary
    }
}

/// Median by sorting (`total_cmp`: NaN-safe); the mean of the middle two for even counts.
fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    let n = values.len();
    if n == 0 {
        f64::NAN
    } else if n % 2 == 1 {
        values[n / 2]
    } else {
        0.5 * (values[n / 2 - 1] + values[n / 2])
    }
}

/// `robustness.json` (see the module doc).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RobustnessRecord {
    /// [`ROBUSTNESS_SCHEMA`].
    pub schema: String,
    /// Parameters.
    pub config: BenchConfig,
    /// Runs, sorted by tracker (config order) then seed.
    pub runs: Vec<RunSummary>,
    /// Per-backend statistics, config order.
    pub summary: Vec<BackendSummary>,
}

impl RobustnessRecord {
    /// A record from its runs: sorts them and computes the summary, so the same runs
    /// always give the same record however they were produced (sharded or not).
    pub fn new(config: BenchConfig, mut runs: Vec<RunSummary>) -> Self {
        let order = |name: &str| {
            config
                .trackers
                .iter()
                .position(|t| t == name)
                .unwrap_or(usize::MAX)
        };
        runs.sort_by_key(|r| (order(&r.tracker), r.seed));
        let summary = config
            .trackers
            .iter()
            .map(|t| BackendSummary::of_runs(t, runs.iter().filter(|r| &r.tracker == t)))
            .collect();
        RobustnessRecord {
            schema: ROBUSTNESS_SCHEMA.to_string(),
            config,
            runs,
            summary,
        }
    }
}

/// Why shard records cannot be merged.
#[derive(Debug, thiserror::Error)]
pub enum MergeError {
    /// Nothing to merge.
    #[error("no records to merge")]
    Empty,
    /// A record of another schema version.
    #[error("record {index} has schema `{found}`, expected `{ROBUSTNESS_SCHEMA}`")]
    Schema {
        /// Position among the inputs.
        index: usize,
        /// Its schema.
        found: String,
    },
    /// The shards are not of one benchmark.
    #[error(
        "record {index} was run with other parameters ({what} differs) and cannot be merged with record 0"
    )]
    Mismatch {
        /// Position among the inputs.
        index: usize,
        /// Which parameter.
        what: &'static str,
    },
    /// The same run appears twice.
    #[error("tracker `{tracker}` seed {seed} appears in more than one record")]
    Duplicate {
        /// Backend.
        tracker: String,
        /// Seed.
        seed: u64,
    },
}

/// Joins shard records of one benchmark into the record an unsharded run writes: same
/// config (shard cleared), the union of the runs, the summary recomputed. Missing seeds
/// (a shard not yet run) are allowed — the table then counts the runs present.
pub fn merge_records(records: &[RobustnessRecord]) -> Result<RobustnessRecord, MergeError> {
    let first = records.first().ok_or(MergeError::Empty)?;
    let mut seen = std::collections::HashSet::new();
    let mut runs = Vec::new();
    for (index, r) in records.iter().enumerate() {
        if r.schema != ROBUSTNESS_SCHEMA {
            return Err(MergeError::Schema {
                index,
                found: r.schema.clone(),
            });
        }
        let (a, b) = (&first.config, &r.config);
        let mismatch = [
            (a.scene != b.scene, "scene"),
            (a.spheres != b.spheres, "spheres"),
            (a.seeds != b.seeds, "seeds"),
            (a.steps != b.steps, "steps"),
            (a.trackers != b.trackers, "trackers"),
            (a.max_triangles != b.max_triangles, "max_triangles"),
            (a.timeout_seconds != b.timeout_seconds, "timeout"),
        ];
        if let Some((_, what)) = mismatch.iter().find(|m| m.0) {
            return Err(MergeError::Mismatch { index, what });
        }
        for run in &r.runs {
            if !seen.insert((run.tracker.clone(), run.seed)) {
                return Err(MergeError::Duplicate {
                    tracker: run.tracker.clone(),
                    seed: run.seed,
                });
            }
            runs.push(run.clone());
        }
    }
    let config = BenchConfig {
        shard: None,
        ..first.config.clone()
    };
    Ok(RobustnessRecord::new(config, runs))
}

/// One scene × backend of `bench compare`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CompareRow {
    /// Scene name.
    pub scene: String,
    /// Steps the scene was run for.
    pub steps: usize,
    /// The run.
    pub run: RunSummary,
}

/// `compare.json` (schema `surftrack.compare/1`): every scene with every backend, rows in
/// scene order then backend order.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CompareRecord {
    /// [`COMPARE_SCHEMA`].
    pub schema: String,
    /// Seed of every scene.
    pub seed: u64,
    /// The rows.
    pub rows: Vec<CompareRow>,
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    pub(crate) fn synthetic_run(tracker: &str, seed: u64) -> RunSummary {
        let success = !seed.is_multiple_of(3);
        let failure = (!success).then(|| Failure {
            reason: if seed.is_multiple_of(2) {
                FailureReason::Timeout
            } else {
                FailureReason::Error
            },
            message: format!("seed {seed}"),
            step: Some(2),
        });
        RunSummary {
            tracker: tracker.to_string(),
            seed,
            success,
            failure,
            wall_seconds: 1.0 + seed as f64 * 0.25,
            steps_completed: 3,
            initial_triangles: 90,
            peak_triangles: 100 + seed as usize,
            peak_rss_mib: Some(50.0 + seed as f64),
            // Exactly representable: the round-trip test compares bit for bit.
            mib_per_million_triangles: Some(500.0 + seed as f64),
            events: EventCounts {
                merges: seed,
                ..EventCounts::default()
            },
            stage_seconds: vec![
                StageSeconds {
                    stage: "cut".into(),
                    seconds: 0.5,
                },
                StageSeconds {
                    stage: "improve".into(),
                    seconds: 0.25 * seed as f64,
                },
            ],
            step_seconds: vec![0.1, 0.2, 0.3],
            step_triangles: vec![100, 110, 120],
        }
    }

    pub(crate) fn synthetic_config(shard: Option<[usize; 2]>) -> BenchConfig {
        BenchConfig {
            scene: "spheres".into(),
            spheres: 5,
            seeds: (1..=7).collect(),
            steps: 3,
            trackers: vec!["grid".into(), "collision".into()],
            timeout_seconds: 10.0,
            max_triangles: 1000,
            max_memory_mib: 100,
            shard,
        }
    }

    #[test]
    fn summary_statistics_are_over_successful_runs() {
        let runs: Vec<_> = (1..=7).map(|s| synthetic_run("grid", s)).collect();
        let s = BackendSummary::of_runs("grid", &runs);
        // Seeds 3 and 6 fail: 3 (odd) by error, 6 (even) by time-out.
        assert_eq!((s.runs, s.successes), (7, 5));
        assert_eq!(s.failures.get("error"), Some(&1));
        assert_eq!(s.failures.get("timeout"), Some(&1));
        let times: Vec<f64> = [1, 2, 4, 5, 7]
            .iter()
            .map(|&k| 1.0 + k as f64 * 0.25)
            .collect();
        assert_eq!(s.mean_seconds, Some(times.iter().sum::<f64>() / 5.0));
        assert_eq!(s.median_seconds, Some(2.0));
        assert_eq!(s.max_seconds, Some(2.75));
        assert_eq!(s.mean_stage_seconds[0].stage, "cut");
        assert_eq!(s.mean_stage_seconds[0].seconds, 0.5);
        assert_eq!(s.peak_triangles, 107);
        assert_eq!(s.max_peak_rss_mib, Some(57.0));
        assert_eq!(s.max_mib_per_million_triangles, Some(507.0));
        assert_eq!(per_million_triangles(Some(3.0), 2_000_000), Some(1.5));
        assert_eq!(per_million_triangles(Some(3.0), 0), None);
        let none = BackendSummary::of_runs("grid", &[]);
        assert_eq!(
            (none.runs, none.success_rate, none.mean_seconds),
            (0, 0.0, None)
        );
    }

    #[test]
    fn records_round_trip_through_json() {
        let runs: Vec<_> = (1..=7)
            .flat_map(|s| [synthetic_run("grid", s), synthetic_run("collision", s)])
            .collect();
        let record = RobustnessRecord::new(synthetic_config(None), runs);
        let text = serde_json::to_string_pretty(&record).unwrap();
        let back: RobustnessRecord = serde_json::from_str(&text).unwrap();
        assert_eq!(back, record);
        // Reasons are snake-case strings, the documented schema.
        assert!(text.contains("\"reason\": \"timeout\""));
        assert!(text.contains("\"success_rate\""));
    }

    #[test]
    fn sharded_runs_merge_to_the_unsharded_record() {
        let runs: Vec<_> = (1..=7)
            .flat_map(|s| [synthetic_run("collision", s), synthetic_run("grid", s)])
            .collect();
        let whole = RobustnessRecord::new(synthetic_config(None), runs.clone());
        let shards: Vec<_> = (0..3)
            .map(|i| {
                let mine = runs
                    .iter()
                    .filter(|r| (r.seed as usize - 1) % 3 == i)
                    .cloned()
                    .collect();
                RobustnessRecord::new(synthetic_config(Some([i, 3])), mine)
            })
            .collect();
        // Any order of shards.
        let merged =
            merge_records(&[shards[2].clone(), shards[0].clone(), shards[1].clone()]).unwrap();
        assert_eq!(merged, whole);
        assert!(matches!(
            merge_records(&[shards[0].clone(), shards[0].clone()]),
            Err(MergeError::Duplicate { .. })
        ));
        let mut other = shards[1].clone();
        other.config.steps = 4;
        assert!(matches!(
            merge_records(&[shards[0].clone(), other]),
            Err(MergeError::Mismatch { what: "steps", .. })
        ));
        assert!(matches!(merge_records(&[]), Err(MergeError::Empty)));
    }
}
