//! `surftrack bench scaling`: time and peak memory against size ([`crate::scaling`]).

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, bail};
use clap::Args;
use surftrack::Backend;

use crate::isolate::Limits;
use crate::report::scaling::{scaling_markdown, scaling_plots};
use crate::report::write_files;
use crate::scaling::{ScalingPlan, scaling};

const EXAMPLES: &str = "\
Examples:
  surftrack bench scaling                                   # fix 100k..2M, spheres 20..200
  surftrack bench scaling --fix-triangles 100000,300000,1000000 --spheres 0 --repeat 3
  surftrack bench scaling --fix-triangles 5000000 --max-memory-mib 20000 --spheres 0
  surftrack bench scaling --mesh bunny.obj --fix-triangles 337000,1350000,5400000 --spheres 0

Output (in --out, default out/scaling): scaling.json (schema surftrack.scaling/1: fix
points with stages, triangles in/out, peak_rss_mib, mib_per_million_triangles; step
points; slopes), report.md, fix_scaling.svg, steps_scaling.svg, and one directory per
point (input.ply/output.ply/fix.json/child.log, or the run's run.json/child.log).

Every point runs in its own child process under the watchdog (--timeout, --max-memory-mib),
so its peak memory is its own. Slopes are least-squares slopes of log time (or memory)
against log triangles over the successful points.";

/// Arguments of `surftrack bench scaling`.
#[derive(Debug, Args)]
#[command(after_long_help = EXAMPLES)]
pub struct ScalingArgs {
    /// Input triangle counts of the `fix` series (comma-separated; 0 alone: skip it).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "100000,200000,500000,1000000,2000000"
    )]
    pub fix_triangles: Vec<usize>,
    /// Copy this mesh (.ply or .obj; e.g. a real scan) instead of the notched sphere; it
    /// is split in four (same surface) as many times as comes nearest each triangle count,
    /// so counts below its own copies' are measured at its own resolution, once.
    #[arg(long)]
    pub mesh: Option<PathBuf>,
    /// Rotated copies per `fix` input (2024 paper Fig. 16: 6).
    #[arg(long, default_value_t = 6)]
    pub copies: usize,
    /// Sphere counts of the step series (comma-separated; 0 alone: skip it).
    #[arg(long, value_delimiter = ',', default_value = "20,50,100,200")]
    pub spheres: Vec<usize>,
    /// Steps per sphere run.
    #[arg(long, default_value_t = 5)]
    pub steps: usize,
    /// Backends of the step series (default: all).
    #[arg(long, short = 't', value_delimiter = ',')]
    pub tracker: Vec<Backend>,
    /// Time limit per point, seconds.
    #[arg(long, default_value_t = 3600.0)]
    pub timeout: f64,
    /// Resident memory cap per point, MiB (Linux); 0 = off.
    #[arg(long, default_value_t = 16384)]
    pub max_memory_mib: u64,
    /// Runs of each `fix` point: each stage's time is its minimum over the runs (noise on
    /// a shared machine only adds time, and a single run at 2M triangles varies by a
    /// third), peak memory the largest.
    #[arg(long, default_value_t = 1)]
    pub repeat: usize,
    /// Seed (rotations of the copies, sphere placement).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output directory.
    #[arg(long, default_value = "out/scaling")]
    pub out: PathBuf,
    /// Print scaling.json instead of the report.
    #[arg(long)]
    pub json: bool,
    /// No progress lines on stderr.
    #[arg(long, short = 'q')]
    pub quiet: bool,
}

pub(super) fn run(args: &ScalingArgs) -> anyhow::Result<ExitCode> {
    if !(args.timeout.is_finite() && args.timeout > 0.0) {
        bail!("--timeout must be a positive number of seconds");
    }
    if args.copies == 0 || args.steps == 0 || args.repeat == 0 {
        bail!("--copies, --steps and --repeat must be at least 1");
    }
    let base_mesh = match &args.mesh {
        Some(path) => {
            let mesh = super::read_work_mesh(path)
                .with_context(|| format!("reading --mesh {}", path.display()))?;
            let name = path.file_name().map_or_else(
                || path.display().to_string(),
                |n| n.to_string_lossy().into_owned(),
            );
            Some((name, mesh))
        }
        None => None,
    };
    let nonzero = |v: &[usize]| v.iter().copied().filter(|&n| n > 0).collect::<Vec<_>>();
    let plan = ScalingPlan {
        fix_triangles: nonzero(&args.fix_triangles),
        copies: args.copies,
        base_mesh,
        spheres: nonzero(&args.spheres),
        steps: args.steps,
        backends: if args.tracker.is_empty() {
            Backend::ALL.to_vec()
        } else {
            args.tracker.clone()
        },
        limits: Limits {
            timeout: std::time::Duration::from_secs_f64(args.timeout),
            max_rss_bytes: (args.max_memory_mib > 0).then_some(args.max_memory_mib << 20),
        },
        out: args.out.clone(),
        seed: args.seed,
        repeat: args.repeat,
    };
    let exe = std::env::current_exe().context("cannot find the surftrack executable")?;
    let quiet = args.quiet || args.json;
    let record = scaling(&exe, &plan, |line| {
        if !quiet {
            eprintln!("{line}");
        }
    })?;
    let json = serde_json::to_string_pretty(&record)?;
    let markdown = scaling_markdown(&record);
    let mut files = vec![
        ("scaling.json".to_string(), json.clone()),
        ("report.md".to_string(), markdown.clone()),
    ];
    files.extend(scaling_plots(&record));
    write_files(&args.out, &files).with_context(|| format!("writing to {}", args.out.display()))?;
    if args.json {
        println!("{json}");
    } else {
        print!("{markdown}");
        println!("record: {}", args.out.join("scaling.json").display());
    }
    Ok(ExitCode::SUCCESS)
}
