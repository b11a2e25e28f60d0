//! The ablation report: one table row per variant, per-stage times, and bar charts.

use std::fmt::Write;

use crate::ablate::AblateRecord;

use super::ReportFile;
use super::svg::bar_chart;

/// `x` with `digits` decimals, or `–`.
fn num(x: Option<f64>, digits: usize) -> String {
    match x {
        Some(v) if v.is_finite() => format!("{v:.digits$}"),
        _ => "–".to_string(),
    }
}

/// The main table: success, time, triangles, untouched fraction, feature distance,
/// volume drift (largest |mean drift| over labels) and events, per variant.
pub fn ablate_table(record: &AblateRecord) -> String {
    let mut md = String::new();
    md.push_str(
        "| variant | runs | success | s/step | triangles | untouched | feature dist | max |vol drift| | merges | splits | T1 | T2 | remesh edits |\n",
    );
    md.push_str("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    for v in &record.variants {
        let drift = v
            .volume_drift
            .iter()
            .map(|d| d.mean_relative_drift.abs())
            .fold(None, |m: Option<f64>, d| Some(m.map_or(d, |m| m.max(d))));
        let e = &v.events;
        let _ = writeln!(
            md,
            "| {} | {} | {:.0} % | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            v.variant.name,
            v.runs,
            100.0 * v.success_rate,
            num(v.seconds_per_step, 3),
            num(v.final_triangles, 0),
            v.untouched_fraction
                .map_or("–".to_string(), |f| format!("{:.1} %", 100.0 * f)),
            num(v.feature_distance, 5),
            drift.map_or("–".to_string(), |d| format!("{:.2} %", 100.0 * d)),
            e.merges,
            e.splits,
            e.t1,
            e.t2,
            e.remeshing_edits
        );
    }
    md
}

/// The full markdown report: what ran, the table, stage times, drift per label, runs.
pub fn ablate_markdown(record: &AblateRecord) -> String {
    let mut md = String::new();
    let _ = writeln!(
        md,
        "# Ablation: {}\n",
        record.preset.as_deref().unwrap_or("custom")
    );
    let _ = writeln!(
        md,
        "Scene `{}`, seeds {:?}, steps {}. Each run in its own child process; metrics are \
         means over successful runs. *untouched*: fraction of final triangles that are an \
         initial triangle carried by the scene's rigid motion (or not moved), never \
         resampled; *feature dist*: mean distance of final vertices outside the contact \
         zone to the rigidly moved original (rolling only).\n",
        record.scene,
        record.seeds,
        record
            .steps
            .map_or("scene default".to_string(), |s| s.to_string())
    );
    md.push_str(&ablate_table(record));
    md.push_str("\n## Seconds per step by stage\n\n");
    let mut stages: Vec<String> = Vec::new();
    for v in &record.variants {
        for s in &v.stage_seconds_per_step {
            if !stages.contains(&s.stage) {
                stages.push(s.stage.clone());
            }
        }
    }
    let _ = writeln!(md, "| variant | {} |", stages.join(" | "));
    let _ = writeln!(md, "|---|{}", "---:|".repeat(stages.len()));
    for v in &record.variants {
        let cells: Vec<String> = stages
            .iter()
            .map(|st| {
                num(
                    v.stage_seconds_per_step
                        .iter()
                        .find(|s| &s.stage == st)
                        .map(|s| s.seconds),
                    4,
                )
            })
            .collect();
        let _ = writeln!(md, "| {} | {} |", v.variant.name, cells.join(" | "));
    }
    md.push_str("\n## Volume drift per label (mean relative)\n\n");
    for v in &record.variants {
        let list: Vec<String> = v
            .volume_drift
            .iter()
            .map(|d| format!("{}: {:+.3} %", d.label, 100.0 * d.mean_relative_drift))
            .collect();
        let _ = writeln!(md, "- {}: {}", v.variant.name, list.join(", "));
    }
    md.push_str("\n## Variants\n\n");
    for v in &record.variants {
        let _ = writeln!(
            md,
            "- {} ({}): `{}`",
            v.variant.name,
            v.variant.tracker,
            v.variant.sets.join("` `")
        );
    }
    md.push_str("\n## Runs\n\n| variant | seed | success | failure | seconds | dir |\n|---|---:|---|---|---:|---|\n");
    for r in &record.runs {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {:.2} | {} |",
            r.variant,
            r.run.seed,
            r.run.success,
            r.run
                .failure
                .as_ref()
                .map_or("–".to_string(), |f| f.reason.to_string()),
            r.run.wall_seconds,
            r.dir
        );
    }
    md
}

/// Bar charts per variant: success rate, seconds per step, untouched fraction, final
/// triangles, largest volume drift.
pub fn ablate_plots(record: &AblateRecord) -> Vec<ReportFile> {
    let bars = |f: &dyn Fn(&crate::ablate::VariantSummary) -> Option<f64>| -> Vec<(String, f64)> {
        record
            .variants
            .iter()
            .map(|v| (v.variant.name.clone(), f(v).unwrap_or(0.0)))
            .collect()
    };
    vec![
        (
            "success_rate.svg".into(),
            bar_chart(
                "Success rate",
                "%",
                &bars(&|v| Some(100.0 * v.success_rate)),
                Some(100.0),
            ),
        ),
        (
            "seconds_per_step.svg".into(),
            bar_chart(
                "Time per step",
                "seconds",
                &bars(&|v| v.seconds_per_step),
                None,
            ),
        ),
        (
            "untouched_fraction.svg".into(),
            bar_chart(
                "Triangles never resampled",
                "%",
                &bars(&|v| v.untouched_fraction.map(|f| 100.0 * f)),
                Some(100.0),
            ),
        ),
        (
            "triangles.svg".into(),
            bar_chart(
                "Final triangles",
                "triangles",
                &bars(&|v| v.final_triangles),
                None,
            ),
        ),
        (
            "volume_drift.svg".into(),
            bar_chart(
                "Largest volume drift",
                "%",
                &bars(&|v| {
                    v.volume_drift
                        .iter()
                        .map(|d| 100.0 * d.mean_relative_drift.abs())
                        .reduce(f64::max)
                }),
                None,
            ),
        ),
    ]
}
