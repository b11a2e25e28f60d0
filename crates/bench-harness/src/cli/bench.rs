//! `surftrack bench robustness | merge | compare`.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, bail};
use serde::Serialize;
use surftrack::Backend;

use crate::bench::{
    ChildOptions, ComparePlan, RobustnessPlan, compare as run_compare, robustness as run_robustness,
};
use crate::isolate::Limits;
use crate::record::{BackendSummary, BenchConfig, RobustnessRecord, merge_records};
use crate::report::picture::PicturedRun;
use crate::report::{
    compare_markdown, robustness_markdown, robustness_plots, robustness_table, write_files,
};
use crate::scenes::{SCENES, scene_info};

use super::{CompareArgs, MergeArgs, RobustnessArgs, output};

/// The backends named on the command line, or all of them.
fn backends(chosen: &[Backend]) -> Vec<Backend> {
    let mut list = if chosen.is_empty() {
        Backend::ALL.to_vec()
    } else {
        chosen.to_vec()
    };
    let mut seen = Vec::new();
    list.retain(|b| {
        let new = !seen.contains(b);
        seen.push(*b);
        new
    });
    list
}

/// The executable to run children with: this one.
fn current_exe() -> anyhow::Result<PathBuf> {
    std::env::current_exe().context("cannot find the surftrack executable to run children")
}

/// What `--json` prints: the per-backend summary (runs, successes, success_rate,
/// mean/median/max_seconds, failures, …).
#[derive(Serialize)]
struct JsonSummary<'a> {
    schema: &'a str,
    config: &'a BenchConfig,
    summary: &'a [BackendSummary],
}

/// Writes robustness.json, report.md (with `pictures` appended) and the plots; prints the
/// table or the JSON.
fn publish(
    record: &RobustnessRecord,
    out: &Path,
    json: bool,
    pictures: &str,
) -> anyhow::Result<()> {
    let text = serde_json::to_string_pretty(record)?;
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let record_path = out.join("robustness.json");
    std::fs::write(&record_path, text)
        .with_context(|| format!("writing {}", record_path.display()))?;
    let mut files = vec![(
        "report.md".to_string(),
        format!("{}{pictures}", robustness_markdown(record)),
    )];
    files.extend(robustness_plots(record));
    write_files(out, &files).with_context(|| format!("writing the report to {}", out.display()))?;
    if json {
        let summary = JsonSummary {
            schema: &record.schema,
            config: &record.config,
            summary: &record.summary,
        };
        println!("{}", serde_json::to_string_pretty(&summary)?);
    } else {
        print!("{}", robustness_table(record));
        for s in &record.summary {
            if s.runs > 0 && s.failures.get("unavailable") == Some(&s.runs) {
                println!(
                    "note: backend `{}` is unavailable in this build; every run was recorded as `unavailable`",
                    s.tracker
                );
            }
        }
        println!(
            "record: {}\nreport: {} (plots: time_per_step.svg, triangles_per_step.svg, success_rate.svg)",
            record_path.display(),
            out.join("report.md").display()
        );
    }
    Ok(())
}

pub(super) fn robustness(args: &RobustnessArgs) -> anyhow::Result<ExitCode> {
    if args.spheres == 0 || args.seeds == 0 || args.steps == 0 {
        bail!("--spheres, --seeds and --steps must be at least 1");
    }
    if !(args.timeout.is_finite() && args.timeout > 0.0) {
        bail!("--timeout must be a positive number of seconds");
    }
    let backends = backends(&args.tracker);
    if let Some(dir) = &args.slurm {
        return write_slurm(args, dir, &backends);
    }
    let out = args.out.clone().unwrap_or_else(|| match args.shard {
        Some(s) => PathBuf::from(format!("out/robustness/shard-{}", s.index)),
        None => PathBuf::from("out/robustness"),
    });
    let last = args
        .first_seed
        .checked_add(args.seeds as u64 - 1)
        .context("--first-seed + --seeds overflows")?;
    let config = BenchConfig {
        scene: "spheres".into(),
        spheres: args.spheres,
        seeds: (args.first_seed..=last).collect(),
        steps: args.steps,
        trackers: backends.iter().map(|b| b.name().to_string()).collect(),
        timeout_seconds: args.timeout,
        max_triangles: args.max_triangles,
        max_memory_mib: args.max_memory_mib,
        shard: None,
    };
    let plan = RobustnessPlan {
        config,
        backends,
        shard: args.shard,
        jobs: args.jobs,
        out: out.clone(),
        every: match (args.every, args.no_pictures) {
            (0, false) => super::view::ENDS_ONLY,
            (every, _) => every,
        },
        simulate: args.simulate,
    };
    let progress = output::progress_bar(args.quiet || args.json, 0, "robustness");
    let record = run_robustness(&current_exe()?, &plan, &progress);
    progress.finish_and_clear();
    let pictures = if args.no_pictures {
        String::new()
    } else {
        // The first seed of every backend (of this shard), pictured with one camera.
        let runs: Vec<PicturedRun> = record
            .config
            .trackers
            .iter()
            .filter_map(|t| {
                let run = record.runs.iter().find(|r| &r.tracker == t)?;
                Some(PicturedRun {
                    label: format!("{t} (seed {})", run.seed),
                    dir: out.join("runs").join(format!("{t}-seed-{:04}", run.seed)),
                })
            })
            .collect();
        super::view::bench_pictures(&runs, &out)
    };
    publish(&record, &out, args.json, &pictures)?;
    Ok(ExitCode::SUCCESS)
}

/// The `bench robustness` arguments that every array task repeats: everything that
/// defines the sweep, none of `--shard`, `--out`, `--slurm`, `--json`, `--quiet`.
pub(super) fn task_arguments(args: &RobustnessArgs, backends: &[Backend]) -> Vec<String> {
    let mut a: Vec<String> = vec![
        "--spheres".into(),
        args.spheres.to_string(),
        "--seeds".into(),
        args.seeds.to_string(),
        "--first-seed".into(),
        args.first_seed.to_string(),
        "--tracker".into(),
        backends
            .iter()
            .map(|b| b.name())
            .collect::<Vec<_>>()
            .join(","),
        "--steps".into(),
        args.steps.to_string(),
        "--timeout".into(),
        args.timeout.to_string(),
        "--jobs".into(),
        args.jobs.to_string(),
        "--max-triangles".into(),
        args.max_triangles.to_string(),
        "--max-memory-mib".into(),
        args.max_memory_mib.to_string(),
        "--every".into(),
        args.every.to_string(),
    ];
    if args.no_pictures {
        a.push("--no-pictures".into());
    }
    if let Some(sim) = args.simulate {
        a.extend(["--simulate".into(), sim.name().into()]);
    }
    a
}

/// An absolute form of a path that may not exist yet (relative to the working directory).
fn absolute(path: &Path) -> anyhow::Result<PathBuf> {
    std::path::absolute(path).with_context(|| format!("cannot make {} absolute", path.display()))
}

/// `--slurm DIR`: writes the job-array, merge and submit scripts instead of running.
fn write_slurm(
    args: &RobustnessArgs,
    dir: &Path,
    backends: &[Backend],
) -> anyhow::Result<ExitCode> {
    use crate::slurm::{SUBMIT_SCRIPT, SlurmPlan, write_slurm_scripts};
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("out/robustness"));
    let plan = SlurmPlan {
        exe: current_exe()?,
        dir: absolute(dir)?,
        out: absolute(&out)?,
        shards: args.slurm_shards.unwrap_or(args.seeds),
        bench_args: task_arguments(args, backends),
        seeds: args.seeds,
        trackers: backends.len(),
        jobs: args.jobs.max(1),
        run_timeout_seconds: args.timeout,
        child_memory_mib: args.max_memory_mib,
        job_name: format!("surftrack-rb-{}", args.spheres),
    };
    let written = write_slurm_scripts(&plan)?;
    if !args.quiet {
        for path in &written {
            println!("wrote {}", path.display());
        }
        println!(
            "submit with: sh {}
merged table (after the merge job): {}",
            plan.dir.join(SUBMIT_SCRIPT).display(),
            plan.out.join("robustness.json").display()
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// Reads `robustness.json` from a directory or the file itself.
fn read_record(input: &Path) -> anyhow::Result<RobustnessRecord> {
    let path = if input.is_dir() {
        input.join("robustness.json")
    } else {
        input.to_path_buf()
    };
    let text =
        std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
    serde_json::from_str(&text)
        .with_context(|| format!("{} is not a robustness record", path.display()))
}

pub(super) fn merge(args: &MergeArgs) -> anyhow::Result<ExitCode> {
    let records = args
        .inputs
        .iter()
        .map(|p| read_record(p))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let merged = merge_records(&records)?;
    let expected = merged.config.seeds.len() * merged.config.trackers.len();
    if merged.runs.len() < expected {
        eprintln!(
            "warning: {} of {expected} runs present; is a shard missing?",
            merged.runs.len()
        );
    }
    publish(&merged, &args.out, args.json, "")?;
    Ok(ExitCode::SUCCESS)
}

pub(super) fn compare(args: &CompareArgs) -> anyhow::Result<ExitCode> {
    let scenes: Vec<String> = if args.scenes.is_empty() {
        SCENES
            .iter()
            .filter(|s| s.steps > 0)
            .map(|s| s.name.to_string())
            .collect()
    } else {
        args.scenes.clone()
    };
    for scene in &scenes {
        match scene_info(scene) {
            Some(info) if info.steps > 0 => {}
            _ => bail!("`{scene}` is not a tracked scene (see `surftrack scenes`)"),
        }
    }
    if !(args.timeout.is_finite() && args.timeout > 0.0) {
        bail!("--timeout must be a positive number of seconds");
    }
    let plan = ComparePlan {
        scenes,
        backends: backends(&args.tracker),
        seed: args.seed,
        child: ChildOptions {
            steps: args.steps,
            count: args.count,
            every: match (args.every, args.no_pictures) {
                (0, false) => super::view::ENDS_ONLY,
                (every, _) => every,
            },
            max_triangles: args.max_triangles,
            simulate: None,
        },
        limits: Limits {
            timeout: std::time::Duration::from_secs_f64(args.timeout),
            max_rss_bytes: (args.max_memory_mib > 0).then_some(args.max_memory_mib << 20),
        },
        jobs: args.jobs,
        out: args.out.clone(),
    };
    let progress = output::progress_bar(args.quiet || args.json, 0, "compare");
    let record = run_compare(&current_exe()?, &plan, &progress);
    progress.finish_and_clear();
    let mut markdown = compare_markdown(&record);
    if !args.no_pictures {
        let runs: Vec<PicturedRun> = record
            .rows
            .iter()
            .map(|r| PicturedRun {
                label: format!("{} · {}", r.scene, r.run.tracker),
                dir: args.out.join(format!("{}-{}", r.scene, r.run.tracker)),
            })
            .collect();
        markdown.push_str(&super::view::bench_pictures(&runs, &args.out));
    }
    let json = serde_json::to_string_pretty(&record)?;
    write_files(
        &args.out,
        &[
            ("compare.json".into(), json.clone()),
            ("compare.md".into(), markdown.clone()),
        ],
    )
    .with_context(|| format!("writing to {}", args.out.display()))?;
    if args.json {
        println!("{json}");
    } else {
        print!("{markdown}");
        println!("record: {}", args.out.join("compare.json").display());
    }
    Ok(ExitCode::SUCCESS)
}
