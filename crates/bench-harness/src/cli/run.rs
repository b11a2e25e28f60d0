//! `surftrack run SCENE` (or `run --mesh FILE --flow NAME[:key=value,…]`, a built-in flow
//! on the user's mesh): one scene through one backend, frames and a record on disk.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;

use anyhow::Context;
use surftrack::Backend;

use crate::bench::Simulate;
use crate::driver::{RunConfig, run_scene};
use crate::isolate::{EXIT_RUN_FAILED, EXIT_UNAVAILABLE};
use crate::options::{OptionsBuilder, RunOptions, option_lines};
use crate::record::{FailureReason, RunRecord, SceneParams};
use crate::report::picture::{PicturedRun, pictures_section};
use crate::report::{run_markdown, run_plots, write_files};
use crate::scenes::{SceneOptions, user};
use crate::view::ViewSource;

use super::{OptionArgs, RunArgs, SceneArgs, output};

/// Longest a simulated hang sleeps: long past any test's watchdog, short enough that a
/// forgotten child goes away by itself.
const HANG_LIMIT: Duration = Duration::from_secs(600);

/// Scene options from the command line (reading `--mesh` if given).
pub(super) fn scene_options(args: &SceneArgs, seed: u64) -> anyhow::Result<SceneOptions> {
    let mesh = match &args.mesh {
        Some(path) => Some(
            super::read_work_mesh(path)
                .with_context(|| format!("reading --mesh {}", path.display()))?,
        ),
        None => None,
    };
    Ok(SceneOptions {
        seed,
        count: args.count,
        resolution: args.resolution,
        radius: args.radius,
        mesh,
    })
}

/// Writes `run.json` into `dir`.
pub(super) fn write_record(dir: &Path, record: &RunRecord) -> anyhow::Result<PathBuf> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let path = dir.join("run.json");
    let text = serde_json::to_string_pretty(record)?;
    std::fs::write(&path, text).with_context(|| format!("writing {}", path.display()))?;
    Ok(path)
}

fn simulate(what: Simulate) {
    match what {
        Simulate::Hang => {
            let start = std::time::Instant::now();
            while start.elapsed() < HANG_LIMIT {
                std::thread::sleep(Duration::from_millis(100));
            }
        }
        Simulate::Panic => panic!("simulated panic (--simulate panic)"),
    }
}

/// The options of a run: `base` (defaults, or a record's), then the scenario file, then
/// every `--set`.
pub(super) fn build_options(
    base: &RunOptions,
    args: &OptionArgs,
) -> anyhow::Result<OptionsBuilder> {
    let mut builder = OptionsBuilder::new(base);
    if let Some(path) = &args.config {
        builder.config_file(path)?;
    }
    for assignment in &args.set {
        builder.set(assignment)?;
    }
    Ok(builder)
}

/// Reads a `run.json` to replay.
fn read_replay(path: &Path) -> anyhow::Result<RunRecord> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    serde_json::from_str(&text).with_context(|| format!("{} is not a run record", path.display()))
}

/// What a run is, from the command line or from a record.
struct Plan {
    scene: String,
    backend: Backend,
    seed: u64,
    steps: Option<usize>,
    dt: Option<f64>,
    scene_args: SceneArgs,
    base: RunOptions,
    replay: bool,
}

fn plan(args: &RunArgs) -> anyhow::Result<Plan> {
    let Some(path) = &args.from_record else {
        let scene = match &args.flow {
            Some(flow) => {
                if !args.scene.is_empty() {
                    anyhow::bail!(
                        "give a scene or --flow on --mesh, not both (scene `{}`)",
                        args.scene
                    );
                }
                if args.scene_args.mesh.is_none() {
                    anyhow::bail!("--flow runs on your own mesh: give it with --mesh FILE");
                }
                user::scene_name(flow)
            }
            None if args.scene.is_empty() => {
                anyhow::bail!(
                    "a scene is required (or --from-record run.json, or --mesh with --flow)"
                )
            }
            None => args.scene.clone(),
        };
        return Ok(Plan {
            scene,
            backend: args.tracker,
            seed: args.seed,
            steps: args.steps,
            dt: args.dt,
            scene_args: args.scene_args.clone(),
            base: RunOptions::default(),
            replay: false,
        });
    };
    let record = read_replay(path)?;
    let backend: Backend = record
        .tracker
        .parse()
        .with_context(|| format!("record {}", path.display()))?;
    let params = record.scene_params.clone().unwrap_or_default();
    Ok(Plan {
        scene: record.scene.clone(),
        backend,
        seed: record.seed,
        steps: args.steps.or(Some(record.steps)),
        dt: args.dt.or(Some(record.dt)),
        scene_args: SceneArgs {
            count: params.count,
            resolution: params.resolution,
            radius: params.radius,
            mesh: params.mesh.map(PathBuf::from),
        },
        base: record.options.clone().unwrap_or_default(),
        replay: true,
    })
}

pub(super) fn run(args: &RunArgs) -> anyhow::Result<ExitCode> {
    if let Some(what) = args.simulate {
        simulate(what);
    }
    let plan = plan(args)?;
    let builder = build_options(&plan.base, &args.option_args)?;
    let mut run_options = builder.build()?;
    // The grid's per-step shifts follow the run's seed unless an option file, a --set or
    // the replayed record fixes them.
    if !plan.replay && !builder.was_set("grid.seed") {
        run_options.grid.seed = plan.seed;
    }
    if args.print_options {
        for line in option_lines(&run_options) {
            println!("{line}");
        }
        return Ok(ExitCode::SUCCESS);
    }
    let out = args.out.clone().unwrap_or_else(|| {
        let name = if plan.scene.starts_with(user::PREFIX) {
            "mesh"
        } else {
            &plan.scene
        };
        PathBuf::from("out").join(format!("{name}-{}", plan.backend.name()))
    });
    let config = RunConfig {
        scene: plan.scene.clone(),
        options: scene_options(&plan.scene_args, plan.seed)?,
        backend: plan.backend,
        steps: plan.steps,
        dt: plan.dt,
        every: args.every,
        out: Some(out.clone()),
        ascii: args.ascii,
        max_triangles: args.max_triangles,
        check_intersections: args.check_intersections,
        run_options,
        scene_params: SceneParams {
            count: plan.scene_args.count,
            resolution: plan.scene_args.resolution,
            radius: plan.scene_args.radius,
            mesh: plan
                .scene_args
                .mesh
                .as_ref()
                .map(|p| p.display().to_string()),
        },
    };
    let progress = output::progress_bar(args.quiet || args.json, 0, &plan.scene);
    let mut record = run_scene(&config, &progress)?;
    record.record_memory();
    progress.finish_and_clear();
    let record_path = write_record(&out, &record)?;
    if !record.per_step.is_empty() {
        write_files(&out, &run_plots(&record))
            .with_context(|| format!("writing plots to {}", out.display()))?;
    }

    let page = if args.no_view || record.frames.is_empty() {
        None
    } else {
        Some(write_view_and_report(&record, &out)?)
    };
    if args.json {
        println!("{}", serde_json::to_string_pretty(&record)?);
    } else if !args.quiet {
        print_summary(&record, &out, &record_path);
        if let Some(page) = page {
            println!(
                "report: {}\nview: {}",
                out.join("report.md").display(),
                page.display()
            );
        }
    }
    let code = match &record.failure {
        None => ExitCode::SUCCESS,
        Some(f) if f.reason == FailureReason::Unavailable => {
            if args.quiet || args.json {
                eprintln!("error: {}", f.message);
            }
            ExitCode::from(EXIT_UNAVAILABLE)
        }
        Some(_) => ExitCode::from(EXIT_RUN_FAILED),
    };
    Ok(code)
}

fn print_summary(record: &RunRecord, out: &Path, record_path: &Path) {
    let per_step = if record.steps_completed > 0 {
        record.per_step.iter().map(|s| s.seconds).sum::<f64>() / record.steps_completed as f64
    } else {
        0.0
    };
    match &record.failure {
        None => println!(
            "{} with {}: {} steps in {:.2} s ({:.3} s/step), {} → {} triangles (peak {}), \
             {} merges, {} splits, every frame valid",
            record.scene,
            record.tracker,
            record.steps_completed,
            record.wall_seconds,
            per_step,
            record.initial.triangles,
            record
                .per_step
                .last()
                .map_or(record.initial.triangles, |s| s.triangles),
            record.peak_triangles,
            record.events.merges,
            record.events.splits,
        ),
        Some(f) => println!(
            "{} with {}: FAILED ({}) after {} of {} steps: {}",
            record.scene,
            record.tracker,
            f.reason,
            record.steps_completed,
            record.steps,
            f.message.lines().next().unwrap_or("")
        ),
    }
    for s in record.per_step.iter().filter(|s| !s.vanished.is_empty()) {
        let labels: Vec<String> = s.vanished.iter().map(u32::to_string).collect();
        println!(
            "step {}: material{} {} vanished",
            s.step,
            if labels.len() > 1 { "s" } else { "" },
            labels.join(", ")
        );
    }
    match (record.frames.first(), record.frames.last()) {
        (Some(first), Some(last)) if record.frames.len() > 1 => println!(
            "frames: {} … {} ({} files)",
            out.join(&first.file).display(),
            out.join(&last.file).display(),
            record.frames.len()
        ),
        (Some(only), _) => println!("frame: {}", out.join(&only.file).display()),
        _ => println!("frames: none written"),
    }
    println!("record: {}", record_path.display());
}

/// Writes `view.html` (every frame of the run) and `report.md` with pictures of the first
/// and last frames; returns the page's path.
fn write_view_and_report(record: &RunRecord, out: &Path) -> anyhow::Result<PathBuf> {
    let page = out.join("view.html");
    let source = ViewSource::open(out)?;
    super::view::write_page_file(&[source], &page)?;
    let pictures = pictures_section(
        &[PicturedRun {
            label: format!("{} · {}", record.scene, record.tracker),
            dir: out.to_path_buf(),
        }],
        out,
    )?;
    let report = format!("{}{pictures}", run_markdown(record, Some("view.html")));
    write_files(out, &[("report.md".into(), report)])
        .with_context(|| format!("writing the report to {}", out.display()))?;
    Ok(page)
}
