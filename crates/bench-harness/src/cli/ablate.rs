//! `surftrack bench ablate SCENE [--preset NAME] [--vary path=v1,v2 ...] --seeds M`.

use std::ffi::OsString;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{Context, bail};
use surftrack::Backend;

use crate::ablate::{AblateError, AblatePlan, PRESETS, ablate, parse_vary, preset, variants};
use crate::bench::ChildOptions;
use crate::isolate::Limits;
use crate::report::picture::PicturedRun;
use crate::report::{ablate_markdown, ablate_plots, ablate_table, write_files};
use crate::scenes::scene_info;

use super::{AblateArgs, output};

pub(super) fn run(args: &AblateArgs) -> anyhow::Result<ExitCode> {
    match scene_info(&args.scene) {
        Some(info) if info.steps > 0 => {}
        _ => bail!(
            "`{}` is not a tracked scene (see `surftrack scenes`)",
            args.scene
        ),
    }
    if args.seeds == 0 || args.steps == Some(0) {
        bail!("--seeds and --steps must be at least 1");
    }
    if !(args.timeout.is_finite() && args.timeout > 0.0) {
        bail!("--timeout must be a positive number of seconds");
    }
    let chosen = match &args.preset {
        Some(name) => Some(preset(name).ok_or_else(|| {
            AblateError::UnknownPreset {
                name: name.clone(),
                known: PRESETS
                    .iter()
                    .map(|p| p.name)
                    .collect::<Vec<_>>()
                    .join(", "),
            }
        })?),
        None => None,
    };
    let mut axes = Vec::new();
    let mut fixed: Vec<String> = args.option_args.set.clone();
    if let Some(p) = chosen {
        axes.push(p.axis());
        fixed.splice(0..0, p.fixed.iter().map(|s| s.to_string()));
    }
    for v in &args.vary {
        axes.push(parse_vary(v)?);
    }
    if axes.is_empty() {
        return Err(AblateError::Empty.into());
    }
    let backends: Vec<Backend> = if !args.tracker.is_empty() {
        let mut b = args.tracker.clone();
        b.dedup();
        b
    } else {
        chosen.map_or(vec![Backend::Grid], |p| p.backends.to_vec())
    };
    // Check every assignment here, so a typo fails before any child starts.
    let variants = variants(&backends, &axes, &fixed);
    for v in &variants {
        let mut b =
            super::run::build_options(&crate::options::RunOptions::default(), &args.option_args)?;
        for s in &v.sets {
            b.set(s).with_context(|| format!("variant `{}`", v.name))?;
        }
    }
    let last = args
        .first_seed
        .checked_add(args.seeds as u64 - 1)
        .context("--first-seed + --seeds overflows")?;
    let mut extra: Vec<OsString> = Vec::new();
    if let Some(r) = args.scene_args.resolution {
        extra.extend(["--resolution".into(), r.to_string().into()]);
    }
    if let Some(r) = args.scene_args.radius {
        extra.extend(["--radius".into(), r.to_string().into()]);
    }
    if let Some(m) = &args.scene_args.mesh {
        extra.extend(["--mesh".into(), m.as_os_str().to_owned()]);
    }
    if let Some(c) = &args.option_args.config {
        extra.extend(["--config".into(), c.as_os_str().to_owned()]);
    }
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from(format!("out/ablate-{}", args.scene)));
    let plan = AblatePlan {
        scene: args.scene.clone(),
        preset: args.preset.clone(),
        variants,
        seeds: (args.first_seed..=last).collect(),
        child: ChildOptions {
            steps: args.steps,
            count: args.scene_args.count,
            every: if args.no_pictures {
                0
            } else {
                super::view::ENDS_ONLY
            },
            max_triangles: args.max_triangles,
            simulate: None,
        },
        extra_args: extra,
        limits: Limits {
            timeout: std::time::Duration::from_secs_f64(args.timeout),
            max_rss_bytes: (args.max_memory_mib > 0).then_some(args.max_memory_mib << 20),
        },
        jobs: args.jobs,
        out: out.clone(),
    };
    let exe = std::env::current_exe().context("cannot find the surftrack executable")?;
    let progress = output::progress_bar(args.quiet || args.json, 0, "ablate");
    let record = ablate(&exe, &plan, &progress);
    progress.finish_and_clear();
    let json = serde_json::to_string_pretty(&record)?;
    let mut report = ablate_markdown(&record);
    if !args.no_pictures {
        // The first seed of every variant, pictured with one camera.
        let runs: Vec<PicturedRun> = record
            .variants
            .iter()
            .filter_map(|v| {
                let run = record.runs.iter().find(|r| r.variant == v.variant.name)?;
                Some(PicturedRun {
                    label: format!("{} (seed {})", v.variant.name, run.run.seed),
                    dir: out.join(&run.dir),
                })
            })
            .collect();
        report.push_str(&super::view::bench_pictures(&runs, &out));
    }
    let mut files = vec![
        ("ablate.json".to_string(), json.clone()),
        ("report.md".to_string(), report),
    ];
    files.extend(ablate_plots(&record));
    write_files(&out, &files).with_context(|| format!("writing to {}", out.display()))?;
    if args.json {
        println!("{json}");
    } else {
        print!("{}", ablate_table(&record));
        println!(
            "record: {}\nreport: {}",
            out.join("ablate.json").display(),
            out.join("report.md").display()
        );
    }
    Ok(ExitCode::SUCCESS)
}
