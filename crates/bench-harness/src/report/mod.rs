//! Human reports: markdown tables and SVG plots of run, robustness and compare records.
//!
//! Everything here is a pure function of a record, so a merged benchmark prints the very
//! table the unsharded one would, and the tests can compare strings.

pub mod ablate;
pub mod picture;
pub mod scaling;
pub mod svg;

use std::fmt::Write;
use std::path::{Path, PathBuf};

use crate::record::{CompareRecord, RobustnessRecord, RunRecord, RunSummary};
pub use ablate::{ablate_markdown, ablate_plots, ablate_table};
use svg::{Series, bar_chart, line_chart};

/// A file of a report: name inside the output directory, and contents.
pub type ReportFile = (String, String);

/// `x` with three significant decimals, or `–` when absent.
fn seconds(x: Option<f64>) -> String {
    match x {
        Some(v) if v.is_finite() => format!("{v:.3}"),
        _ => "–".to_string(),
    }
}

/// A MiB figure, or a dash where unknown.
fn mib(v: Option<f64>) -> String {
    v.map_or_else(|| "–".to_string(), |m| format!("{m:.0}"))
}

/// The per-backend table of the robustness benchmark (what the paper reports), with the
/// memory figures of the runs.
pub fn robustness_table(record: &RobustnessRecord) -> String {
    let mut md = String::new();
    md.push_str(
        "| tracker | runs | successes | success rate | mean s | median s | max s | peak triangles | peak MiB | MiB per M triangles | failures |\n",
    );
    md.push_str("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|\n");
    for s in &record.summary {
        let failures = if s.failures.is_empty() {
            "–".to_string()
        } else {
            s.failures
                .iter()
                .map(|(reason, n)| format!("{reason} {n}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let _ = writeln!(
            md,
            "| {} | {} | {} | {:.1} % | {} | {} | {} | {} | {} | {} | {} |",
            s.tracker,
            s.runs,
            s.successes,
            100.0 * s.success_rate,
            seconds(s.mean_seconds),
            seconds(s.median_seconds),
            seconds(s.max_seconds),
            s.peak_triangles,
            mib(s.max_peak_rss_mib),
            mib(s.max_mib_per_million_triangles),
            failures
        );
    }
    md
}

/// The full robustness report: parameters, the table, mean stage times, every run.
pub fn robustness_markdown(record: &RobustnessRecord) -> String {
    let c = &record.config;
    let mut md = String::new();
    let _ = writeln!(md, "# Robustness benchmark\n");
    let _ = writeln!(
        md,
        "{} random non-overlapping spheres expanding under naive normal flow for {} steps, seeds {}; \
         time limit {} s, triangle cap {}, memory cap {} MiB per run{}. \
         A run succeeds if it finishes without panic, error, time-out or memory blow-up and every \
         frame passes `validate()` (Heiss-Synak et al. 2024, §9.6). Times are wall seconds of \
         successful runs.\n",
        c.spheres,
        c.steps,
        seed_list(&c.seeds),
        c.timeout_seconds,
        c.max_triangles,
        c.max_memory_mib,
        match c.shard {
            Some([i, n]) => format!(", shard {i}/{n}"),
            None => String::new(),
        }
    );
    md.push_str(&robustness_table(record));
    let stages: Vec<_> = record
        .summary
        .iter()
        .filter(|s| !s.mean_stage_seconds.is_empty())
        .collect();
    if !stages.is_empty() {
        md.push_str("\n## Mean seconds per stage (successful runs)\n\n| tracker | stage | seconds | share |\n|---|---|---:|---:|\n");
        for s in stages {
            let total: f64 = s.mean_stage_seconds.iter().map(|t| t.seconds).sum();
            for t in &s.mean_stage_seconds {
                let share = if total > 0.0 {
                    100.0 * t.seconds / total
                } else {
                    0.0
                };
                let _ = writeln!(
                    md,
                    "| {} | {} | {:.3} | {share:.0} % |",
                    s.tracker, t.stage, t.seconds
                );
            }
        }
    }
    md.push_str("\n## Runs\n\n");
    md.push_str(&runs_table(record.runs.iter().map(|r| (None, r))));
    md
}

/// "1–10" for a contiguous list, else the list.
fn seed_list(seeds: &[u64]) -> String {
    match (seeds.first(), seeds.last()) {
        (Some(a), Some(b)) if seeds.windows(2).all(|w| w[1] == w[0] + 1) && seeds.len() > 2 => {
            format!("{a}–{b}")
        }
        _ => seeds
            .iter()
            .map(u64::to_string)
            .collect::<Vec<_>>()
            .join(", "),
    }
}

/// One row per run; with a scene column when the runs carry one.
fn runs_table<'a>(runs: impl Iterator<Item = (Option<&'a str>, &'a RunSummary)>) -> String {
    let runs: Vec<_> = runs.collect();
    let with_scene = runs.iter().any(|r| r.0.is_some());
    let mut md = String::new();
    if with_scene {
        md.push_str("| scene ");
    }
    md.push_str("| tracker | seed | result | steps | wall s | s/step | triangles (initial → final, peak) | merges | splits | T1 | T2 | edits |\n");
    if with_scene {
        md.push_str("|---");
    }
    md.push_str("|---|---:|---|---:|---:|---:|---|---:|---:|---:|---:|---:|\n");
    for (scene, r) in runs {
        if let Some(scene) = scene {
            let _ = write!(md, "| {scene} ");
        }
        let result = match &r.failure {
            None => "ok".to_string(),
            Some(f) => match f.step {
                Some(step) => format!("**{}** at step {step}", f.reason),
                None => format!("**{}**", f.reason),
            },
        };
        let per_step = if r.step_seconds.is_empty() {
            None
        } else {
            Some(r.step_seconds.iter().sum::<f64>() / r.step_seconds.len() as f64)
        };
        let e = &r.events;
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {:.3} | {} | {} → {}, {} | {} | {} | {} | {} | {} |",
            r.tracker,
            r.seed,
            result,
            r.steps_completed,
            r.wall_seconds,
            seconds(per_step),
            r.initial_triangles,
            r.final_triangles(),
            r.peak_triangles,
            e.merges,
            e.splits,
            e.t1,
            e.t2,
            e.remeshing_edits
        );
    }
    md
}

/// Mean of `value(run)[step]` over the runs that reached each step: one point per step.
fn mean_per_step(runs: &[&RunSummary], value: impl Fn(&RunSummary) -> Vec<f64>) -> Vec<(f64, f64)> {
    let columns: Vec<Vec<f64>> = runs.iter().map(|r| value(r)).collect();
    let longest = columns.iter().map(Vec::len).max().unwrap_or(0);
    (0..longest)
        .filter_map(|i| {
            let values: Vec<f64> = columns.iter().filter_map(|c| c.get(i).copied()).collect();
            (!values.is_empty()).then(|| {
                (
                    (i + 1) as f64,
                    values.iter().sum::<f64>() / values.len() as f64,
                )
            })
        })
        .collect()
}

/// The robustness plots: mean time and triangles per step per backend, success rate per
/// backend.
pub fn robustness_plots(record: &RobustnessRecord) -> Vec<ReportFile> {
    let per_backend = |value: fn(&RunSummary) -> Vec<f64>| -> Vec<Series> {
        record
            .config
            .trackers
            .iter()
            .map(|t| {
                let runs: Vec<&RunSummary> =
                    record.runs.iter().filter(|r| &r.tracker == t).collect();
                Series {
                    name: t.clone(),
                    points: mean_per_step(&runs, value),
                }
            })
            .collect()
    };
    let times = per_backend(|r| r.step_seconds.clone());
    let triangles = per_backend(|r| r.step_triangles.iter().map(|&n| n as f64).collect());
    let rates: Vec<(String, f64)> = record
        .summary
        .iter()
        .map(|s| (s.tracker.clone(), s.success_rate))
        .collect();
    vec![
        (
            "time_per_step.svg".into(),
            line_chart("Mean wall time per step", "step", "seconds", &times),
        ),
        (
            "triangles_per_step.svg".into(),
            line_chart(
                "Mean triangle count per step",
                "step",
                "triangles",
                &triangles,
            ),
        ),
        (
            "success_rate.svg".into(),
            bar_chart(
                "Success rate per backend",
                "success rate",
                &rates,
                Some(1.0),
            ),
        ),
    ]
}

/// The compare table and failure details.
pub fn compare_markdown(record: &CompareRecord) -> String {
    let mut md = String::new();
    let _ = writeln!(md, "# Backends side by side (seed {})\n", record.seed);
    md.push_str(&runs_table(
        record.rows.iter().map(|r| (Some(r.scene.as_str()), &r.run)),
    ));
    let failures: Vec<_> = record
        .rows
        .iter()
        .filter_map(|r| r.run.failure.as_ref().map(|f| (r, f)))
        .collect();
    if !failures.is_empty() {
        md.push_str("\n## Failures\n\n");
        for (row, f) in failures {
            let _ = writeln!(
                md,
                "- {} / {}: {} — {}",
                row.scene,
                row.run.tracker,
                f.reason,
                f.message.lines().next().unwrap_or("")
            );
        }
    }
    md
}

/// The report of one run: what ran, how it ended, a link to its page (`view`, relative
/// to the report) and its plots; the caller appends the pictures.
pub fn run_markdown(record: &RunRecord, view: Option<&str>) -> String {
    let mut md = String::new();
    let _ = writeln!(
        md,
        "# {} with {} (seed {})\n",
        record.scene, record.tracker, record.seed
    );
    let outcome = match &record.failure {
        None => "succeeded, every frame valid".to_string(),
        Some(f) => format!(
            "**failed** ({}) at step {}: {}",
            f.reason,
            f.step.map_or("–".to_string(), |s| s.to_string()),
            f.message.lines().next().unwrap_or("")
        ),
    };
    let last = record
        .per_step
        .last()
        .map_or(record.initial.triangles, |s| s.triangles);
    let _ = writeln!(
        md,
        "{} of {} steps in {:.2} s; {outcome}. Triangles {} → {} (peak {}); {} merges, {} splits, {} T1, {} T2.\n",
        record.steps_completed,
        record.steps,
        record.wall_seconds,
        record.initial.triangles,
        last,
        record.peak_triangles,
        record.events.merges,
        record.events.splits,
        record.events.t1,
        record.events.t2,
    );
    if let Some(view) = view {
        let _ = writeln!(
            md,
            "Every frame in a browser (no network needed): [{view}]({view}) (`surftrack view`).\n"
        );
    }
    if !record.per_step.is_empty() {
        md.push_str(
            "![time per step](time_per_step.svg) ![triangles per step](triangles_per_step.svg)\n",
        );
    }
    md
}

/// The plots of one run: time and triangles per step.
pub fn run_plots(record: &RunRecord) -> Vec<ReportFile> {
    let series = |name: &str, f: fn(&crate::record::StepRecord) -> f64| {
        vec![Series {
            name: name.to_string(),
            points: record
                .per_step
                .iter()
                .map(|s| (s.step as f64, f(s)))
                .collect(),
        }]
    };
    let title = format!("{} with {}", record.scene, record.tracker);
    vec![
        (
            "time_per_step.svg".into(),
            line_chart(
                &format!("{title}: wall time per step"),
                "step",
                "seconds",
                &series(&record.tracker, |s| s.seconds),
            ),
        ),
        (
            "triangles_per_step.svg".into(),
            line_chart(
                &format!("{title}: triangles"),
                "step",
                "triangles",
                &series(&record.tracker, |s| s.triangles as f64),
            ),
        ),
    ]
}

/// Writes report files into `dir` (created if missing); returns their paths.
pub fn write_files(dir: &Path, files: &[ReportFile]) -> std::io::Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir)?;
    files
        .iter()
        .map(|(name, contents)| {
            let path = dir.join(name);
            std::fs::write(&path, contents)?;
            Ok(path)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::record::merge_records;
    use crate::record::tests::{synthetic_config, synthetic_run};

    fn record() -> RobustnessRecord {
        let runs = (1..=7)
            .flat_map(|s| [synthetic_run("grid", s), synthetic_run("collision", s)])
            .collect();
        RobustnessRecord::new(synthetic_config(None), runs)
    }

    #[test]
    fn the_table_shows_rates_times_and_failures() {
        let table = robustness_table(&record());
        let grid = table.lines().find(|l| l.starts_with("| grid")).unwrap();
        assert!(grid.contains("| 7 | 5 | 71.4 % |"), "{grid}");
        assert!(grid.contains("error 1, timeout 1"), "{grid}");
        assert!(grid.contains("| 2.000 |"), "median: {grid}");
        let md = robustness_markdown(&record());
        assert!(md.contains("seeds 1–7"));
        assert!(md.contains("**timeout** at step 2"));
        assert!(md.contains("| grid | improve |"));
    }

    #[test]
    fn merged_shards_print_the_same_report() {
        let whole = record();
        let shards: Vec<_> = (0..2)
            .map(|i| {
                let runs = whole
                    .runs
                    .iter()
                    .filter(|r| r.seed as usize % 2 == i)
                    .cloned()
                    .collect();
                RobustnessRecord::new(synthetic_config(Some([i, 2])), runs)
            })
            .collect();
        let merged = merge_records(&shards).unwrap();
        assert_eq!(robustness_markdown(&merged), robustness_markdown(&whole));
        assert_eq!(robustness_plots(&merged), robustness_plots(&whole));
    }

    #[test]
    fn plots_average_over_the_runs_that_reached_each_step() {
        let a = synthetic_run("grid", 1);
        let mut b = synthetic_run("grid", 2);
        b.step_seconds = vec![0.3];
        let points = mean_per_step(&[&a, &b], |r| r.step_seconds.clone());
        assert_eq!(points.len(), 3);
        assert!((points[0].1 - 0.2).abs() < 1e-12);
        assert!((points[2].1 - 0.3).abs() < 1e-12);
        let files = robustness_plots(&record());
        assert_eq!(files.len(), 3);
        assert!(
            files
                .iter()
                .all(|(name, svg)| name.ends_with(".svg") && svg.contains("</svg>"))
        );
    }
}
