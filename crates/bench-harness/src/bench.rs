//! The benchmarks: the statistical robustness benchmark of the 2024 paper (§9.6) and
//! the side-by-side comparison of the backends on the built-in scenes.
//!
//! **Robustness.** For each backend and each seed, N random non-overlapping spheres
//! expand under naive normal flow for K steps, each run in its own child process
//! ([`crate::isolate`]). A run succeeds if it finishes without panic, error, time-out or
//! memory blow-up and every frame is valid. Seeds are dealt round-robin to shards
//! (`--shard I/N`: seed number `k` of the list goes to shard `k mod N`), so a cluster job
//! array runs one shard per task and `bench merge` joins them
//! ([`crate::record::merge_records`]).
//!
//! **Compare.** Every scene with every backend, same seed, same steps, also isolated.

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use indicatif::ProgressBar;
use surftrack::Backend;

use crate::isolate::{ChildRun, Limits, run_isolated};
use crate::record::{
    BenchConfig, COMPARE_SCHEMA, CompareRecord, CompareRow, RobustnessRecord, RunSummary,
};
use crate::scenes::scene_info;

/// Test hooks passed to children: make them misbehave on purpose, so the watchdog and the
/// failure bookkeeping can be tested cheaply (hidden from `--help`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Simulate {
    /// Sleep instead of running (until the watchdog kills the child).
    Hang,
    /// Panic outside any `catch_unwind`: the child dies without a record.
    Panic,
}

impl Simulate {
    /// The command-line value.
    pub fn name(self) -> &'static str {
        match self {
            Simulate::Hang => "hang",
            Simulate::Panic => "panic",
        }
    }
}

/// A shard `index` of `count` (0-based), as `--shard I/N` gives it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    /// This shard, `0 ..count`.
    pub index: usize,
    /// Number of shards.
    pub count: usize,
}

impl std::str::FromStr for Shard {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let (i, n) = s
            .split_once('/')
            .ok_or_else(|| format!("`{s}`: expected I/N, e.g. 0/4"))?;
        let index: usize = i
            .trim()
            .parse()
            .map_err(|_| format!("`{i}` is not a shard index"))?;
        let count: usize = n
            .trim()
            .parse()
            .map_err(|_| format!("`{n}` is not a shard count"))?;
        if count == 0 || index >= count {
            return Err(format!(
                "shard {index}/{count}: need 0 <= I < N (shards are numbered from 0)"
            ));
        }
        Ok(Shard { index, count })
    }
}

/// The seeds of one shard: seed number `k` of `seeds` belongs to shard `k mod count`.
pub fn shard_seeds(seeds: &[u64], shard: Option<Shard>) -> Vec<u64> {
    match shard {
        None => seeds.to_vec(),
        Some(s) => seeds
            .iter()
            .enumerate()
            .filter(|(k, _)| k % s.count == s.index)
            .map(|(_, &seed)| seed)
            .collect(),
    }
}

/// What a child run of a scene needs besides scene and backend.
#[derive(Clone, Debug)]
pub struct ChildOptions {
    /// Steps (`None`: the scene's default).
    pub steps: Option<usize>,
    /// Sphere / cell / copy count (`None`: the scene's default).
    pub count: Option<usize>,
    /// Frames every N steps (0: none).
    pub every: usize,
    /// The triangle cap (memory guard inside the child).
    pub max_triangles: usize,
    /// Misbehave on purpose (tests).
    pub simulate: Option<Simulate>,
}

/// The `run` command line of one child.
pub fn child_args(
    scene: &str,
    backend: Backend,
    seed: u64,
    dir: &Path,
    o: &ChildOptions,
) -> Vec<OsString> {
    let mut args: Vec<OsString> = vec![
        "run".into(),
        scene.into(),
        "--tracker".into(),
        backend.name().into(),
        "--seed".into(),
        seed.to_string().into(),
        "--every".into(),
        o.every.to_string().into(),
        "--max-triangles".into(),
        o.max_triangles.to_string().into(),
        "--out".into(),
        dir.as_os_str().to_owned(),
        "--quiet".into(),
        // The benchmark's report pictures its runs; a page per child would only cost.
        "--no-view".into(),
    ];
    if let Some(steps) = o.steps {
        args.extend(["--steps".into(), steps.to_string().into()]);
    }
    if let Some(count) = o.count {
        args.extend(["--count".into(), count.to_string().into()]);
    }
    if let Some(sim) = o.simulate {
        args.extend(["--simulate".into(), sim.name().into()]);
    }
    args
}

/// Runs children `jobs` at a time (at least one), in order of `runs`; returns their
/// summaries in the same order. Each finished run advances `progress`.
pub fn run_all(
    exe: &Path,
    runs: &[ChildRun],
    limits: &Limits,
    jobs: usize,
    progress: &ProgressBar,
) -> Vec<RunSummary> {
    let next = AtomicUsize::new(0);
    let results: Mutex<Vec<Option<RunSummary>>> = Mutex::new(vec![None; runs.len()]);
    let workers = jobs.clamp(1, runs.len().max(1));
    std::thread::scope(|scope| {
        for _ in 0..workers {
            scope.spawn(|| {
                // Each iteration claims a distinct index; at most `runs.len()` of them.
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(run) = runs.get(i) else { break };
                    let summary = run_isolated(exe, run, limits);
                    let status = match &summary.failure {
                        None => "ok".to_string(),
                        Some(f) => f.reason.to_string(),
                    };
                    progress.set_message(format!("{} seed {}: {status}", run.tracker, run.seed));
                    progress.inc(1);
                    // A poisoned lock only means another worker panicked mid-push; the
                    // vector itself is intact.
                    let mut guard = results.lock().unwrap_or_else(|e| e.into_inner());
                    guard[i] = Some(summary);
                }
            });
        }
    });
    results
        .into_inner()
        .unwrap_or_else(|e| e.into_inner())
        .into_iter()
        .zip(runs)
        .map(|(summary, run)| {
            summary.unwrap_or_else(|| {
                let failure = crate::record::Failure {
                    reason: crate::record::FailureReason::Crash,
                    message: "the worker running it panicked".into(),
                    step: None,
                };
                RunSummary::failed(&run.tracker, run.seed, failure, 0.0)
            })
        })
        .collect()
}

/// Everything the robustness benchmark needs.
#[derive(Clone, Debug)]
pub struct RobustnessPlan {
    /// Parameters recorded in `robustness.json`.
    pub config: BenchConfig,
    /// Backends, in `config.trackers` order.
    pub backends: Vec<Backend>,
    /// This shard.
    pub shard: Option<Shard>,
    /// Children at a time.
    pub jobs: usize,
    /// Output directory (`runs/<tracker>-seed-<s>/` per run).
    pub out: PathBuf,
    /// Frames every N steps in each run (0: none).
    pub every: usize,
    /// Test hook.
    pub simulate: Option<Simulate>,
}

/// Runs the seeds of the plan's shard for every backend and returns the record.
pub fn robustness(exe: &Path, plan: &RobustnessPlan, progress: &ProgressBar) -> RobustnessRecord {
    let seeds = shard_seeds(&plan.config.seeds, plan.shard);
    let options = ChildOptions {
        steps: Some(plan.config.steps),
        count: Some(plan.config.spheres),
        every: plan.every,
        max_triangles: plan.config.max_triangles,
        simulate: plan.simulate,
    };
    let runs: Vec<ChildRun> = plan
        .backends
        .iter()
        .flat_map(|&backend| seeds.iter().map(move |&seed| (backend, seed)))
        .map(|(backend, seed)| {
            let dir = plan
                .out
                .join("runs")
                .join(format!("{}-seed-{seed:04}", backend.name()));
            ChildRun {
                tracker: backend.name().to_string(),
                seed,
                args: child_args(&plan.config.scene, backend, seed, &dir, &options),
                dir,
            }
        })
        .collect();
    progress.set_length(runs.len() as u64);
    let summaries = run_all(exe, &runs, &limits_of(&plan.config), plan.jobs, progress);
    let mut config = plan.config.clone();
    config.shard = plan.shard.map(|s| [s.index, s.count]);
    RobustnessRecord::new(config, summaries)
}

/// The watchdog limits of a benchmark configuration.
pub fn limits_of(config: &BenchConfig) -> Limits {
    Limits {
        timeout: std::time::Duration::from_secs_f64(config.timeout_seconds),
        max_rss_bytes: (config.max_memory_mib > 0).then_some(config.max_memory_mib << 20),
    }
}

/// Everything `bench compare` needs.
#[derive(Clone, Debug)]
pub struct ComparePlan {
    /// Scenes, in table order.
    pub scenes: Vec<String>,
    /// Backends, in table order.
    pub backends: Vec<Backend>,
    /// Seed of every scene.
    pub seed: u64,
    /// Child options (steps, frames, caps).
    pub child: ChildOptions,
    /// Watchdog limits.
    pub limits: Limits,
    /// Children at a time.
    pub jobs: usize,
    /// Output directory (`<scene>-<tracker>/` per run).
    pub out: PathBuf,
}

/// Runs every scene with every backend and returns the record.
pub fn compare(exe: &Path, plan: &ComparePlan, progress: &ProgressBar) -> CompareRecord {
    let mut runs = Vec::new();
    let mut rows_of = Vec::new();
    for scene in &plan.scenes {
        let steps = plan
            .child
            .steps
            .or_else(|| scene_info(scene).map(|i| i.steps))
            .unwrap_or(0);
        for &backend in &plan.backends {
            let dir = plan.out.join(format!("{scene}-{}", backend.name()));
            runs.push(ChildRun {
                tracker: backend.name().to_string(),
                seed: plan.seed,
                args: child_args(scene, backend, plan.seed, &dir, &plan.child),
                dir,
            });
            rows_of.push((scene.clone(), steps));
        }
    }
    progress.set_length(runs.len() as u64);
    let summaries = run_all(exe, &runs, &plan.limits, plan.jobs, progress);
    let rows = rows_of
        .into_iter()
        .zip(summaries)
        .map(|((scene, steps), run)| CompareRow { scene, steps, run })
        .collect();
    CompareRecord {
        schema: COMPARE_SCHEMA.to_string(),
        seed: plan.seed,
        rows,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_parse_and_partition_the_seeds() {
        assert_eq!("1/3".parse::<Shard>(), Ok(Shard { index: 1, count: 3 }));
        assert!("3/3".parse::<Shard>().is_err());
        assert!("0/0".parse::<Shard>().is_err());
        assert!("a/2".parse::<Shard>().is_err());
        assert!("2".parse::<Shard>().is_err());
        let seeds: Vec<u64> = (10..20).collect();
        let mut all: Vec<u64> = (0..3)
            .flat_map(|index| shard_seeds(&seeds, Some(Shard { index, count: 3 })))
            .collect();
        all.sort();
        assert_eq!(all, seeds);
        assert_eq!(
            shard_seeds(&seeds, Some(Shard { index: 0, count: 3 })),
            vec![10, 13, 16, 19]
        );
        assert_eq!(shard_seeds(&seeds, None), seeds);
    }

    #[test]
    fn child_arguments_parse_as_a_run_command() {
        use clap::Parser;
        let o = ChildOptions {
            steps: Some(3),
            count: Some(5),
            every: 0,
            max_triangles: 1000,
            simulate: Some(Simulate::Hang),
        };
        let args = child_args("spheres", Backend::Collision, 7, Path::new("out/x"), &o);
        let cli = crate::cli::Cli::try_parse_from(
            std::iter::once(OsString::from("surftrack")).chain(args),
        )
        .unwrap();
        let crate::cli::Command::Run(run) = cli.command else {
            panic!("not a run command")
        };
        assert_eq!(run.scene, "spheres");
        assert_eq!(run.tracker, Backend::Collision);
        assert_eq!(
            (run.seed, run.steps, run.scene_args.count),
            (7, Some(3), Some(5))
        );
        assert_eq!(run.max_triangles, Some(1000));
        assert_eq!(run.simulate, Some(Simulate::Hang));
        assert!(run.quiet);
        assert!(run.no_view, "children write no page");
    }
}
