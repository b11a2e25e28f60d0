//! The `bench scaling` report: tables of the points, the slopes, and log–log SVG plots.

use std::fmt::Write as _;

use super::svg::{Series, line_chart};
use crate::scaling::ScalingRecord;

fn opt(v: Option<f64>, digits: usize) -> String {
    v.map_or_else(|| "–".to_string(), |x| format!("{x:.digits$}"))
}

/// `report.md`: the `fix` table (one column per stage), the steps table, the slopes.
pub fn scaling_markdown(record: &ScalingRecord) -> String {
    let mut md = String::from("# Scaling\n\n");
    if !record.fix.is_empty() {
        let mut stages: Vec<&str> = Vec::new();
        for p in &record.fix {
            for s in &p.stages {
                if !stages.contains(&s.stage.as_str()) {
                    stages.push(&s.stage);
                }
            }
        }
        let _ = writeln!(
            md,
            "## fix on {} rotated copies of {}\n",
            record.copies,
            record.base_mesh.as_deref().map_or_else(
                || "the notched sphere".to_string(),
                |name| format!("{name}, subdivided to size")
            )
        );
        let runs = record.fix.iter().map(|p| p.runs).max().unwrap_or(1);
        if runs > 1 {
            let _ = writeln!(
                md,
                "Each time is the smallest of up to {runs} runs of the point (`--repeat`); \
                 peak memory the largest.\n"
            );
        }
        let _ = write!(
            md,
            "| input triangles | output triangles | flawed cells | ok | wall s |"
        );
        for s in &stages {
            let _ = write!(md, " {s} s |");
        }
        md.push_str(" peak MiB | MiB per M triangles |\n|---:|---:|---:|---|---:|");
        md.push_str(&"---:|".repeat(stages.len() + 2));
        md.push('\n');
        for p in &record.fix {
            let _ = write!(
                md,
                "| {} | {} | {} | {} | {:.2} |",
                p.triangles_in,
                p.triangles_out,
                opt(p.flawed_cells.map(|n| n as f64), 0),
                if p.success { "yes" } else { "**no**" },
                p.wall_seconds
            );
            for s in &stages {
                let t = p.stages.iter().find(|x| x.stage == *s).map(|x| x.seconds);
                let _ = write!(md, " {} |", opt(t, 3));
            }
            let _ = writeln!(
                md,
                " {} | {} |",
                opt(p.peak_rss_mib, 0),
                opt(p.mib_per_million_triangles, 0)
            );
        }
        for p in record.fix.iter().filter(|p| !p.success) {
            let _ = writeln!(
                md,
                "\n{} triangles failed: {}",
                p.triangles_in,
                p.failure.as_deref().unwrap_or("?")
            );
        }
        md.push('\n');
    }
    if !record.steps.is_empty() {
        md.push_str("## Steps of the `spheres` scene\n\n| tracker | spheres | ok | mean triangles | s per step | peak MiB | MiB per M triangles |\n|---|---:|---|---:|---:|---:|---:|\n");
        for p in &record.steps {
            let _ = writeln!(
                md,
                "| {} | {} | {} | {:.0} | {:.3} | {} | {} |",
                p.tracker,
                p.spheres,
                if p.success { "yes" } else { "**no**" },
                p.mean_triangles,
                p.seconds_per_step,
                opt(p.peak_rss_mib, 0),
                opt(p.mib_per_million_triangles, 0)
            );
        }
        md.push('\n');
    }
    md.push_str("## Log–log slopes (against triangles unless named; 1 = linear)\n\n| what | slope | points |\n|---|---:|---:|\n");
    for s in &record.slopes {
        let _ = writeln!(md, "| {} | {} | {} |", s.what, opt(s.slope, 2), s.points);
    }
    md.push_str("\nPlots: fix_scaling.svg, steps_scaling.svg (log10 axes).\n");
    md
}

/// The plots: `fix_scaling.svg` (log10 seconds per stage against log10 input triangles)
/// and `steps_scaling.svg` (log10 seconds per step against log10 triangles per backend).
pub fn scaling_plots(record: &ScalingRecord) -> Vec<(String, String)> {
    let log = |x: f64| if x > 0.0 { x.log10() } else { f64::NAN };
    let mut names: Vec<&str> = Vec::new();
    for p in &record.fix {
        for s in &p.stages {
            if !names.contains(&s.stage.as_str()) {
                names.push(&s.stage);
            }
        }
    }
    let ok = || record.fix.iter().filter(|p| p.success);
    let mut fix: Vec<Series> = names
        .iter()
        .map(|name| Series {
            name: name.to_string(),
            points: ok()
                .filter_map(|p| {
                    let s = p.stages.iter().find(|s| s.stage == *name)?;
                    Some((log(p.triangles_in as f64), log(s.seconds)))
                })
                .collect(),
        })
        .collect();
    fix.push(Series {
        name: "total".into(),
        points: ok()
            .map(|p| (log(p.triangles_in as f64), log(p.total_seconds())))
            .collect(),
    });
    let mut trackers: Vec<&str> = Vec::new();
    for p in &record.steps {
        if !trackers.contains(&p.tracker.as_str()) {
            trackers.push(&p.tracker);
        }
    }
    let steps: Vec<Series> = trackers
        .iter()
        .map(|t| Series {
            name: t.to_string(),
            points: record
                .steps
                .iter()
                .filter(|p| p.success && p.tracker == *t)
                .map(|p| (log(p.mean_triangles), log(p.seconds_per_step)))
                .collect(),
        })
        .collect();
    vec![
        (
            "fix_scaling.svg".into(),
            line_chart(
                "fix: seconds per stage",
                "log10 input triangles",
                "log10 seconds",
                &fix,
            ),
        ),
        (
            "steps_scaling.svg".into(),
            line_chart(
                "spheres: seconds per step",
                "log10 triangles",
                "log10 seconds",
                &steps,
            ),
        ),
    ]
}
