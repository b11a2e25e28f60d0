//! `surftrack fix IN OUT [--cell L] [--json]`: one-shot repair / multi-material union with
//! the grid backend (`grid_tracker::fix_with`).
//!
//! The input may overlap itself anywhere, by any amount (rotated copies of a mesh, a
//! tangled simulation frame); the output is watertight, consistently labelled and free of
//! intersections, and every triangle away from the flawed cells is the input's own.

use std::process::ExitCode;

use grid_tracker::{FixOptions, fix_with};
use serde::Serialize;

use super::{FixArgs, write_mesh_file};

/// The record printed by `fix --json` (schema `surftrack.fix/1`).
#[derive(Serialize)]
struct FixRecord<'a> {
    schema: &'static str,
    input: String,
    output: String,
    valid: bool,
    /// Peak resident memory of the process, MiB (Linux `VmHWM`), reading and writing the
    /// files included.
    peak_rss_mib: Option<f64>,
    report: &'a grid_tracker::FixReport,
}

pub(super) fn run(args: &FixArgs) -> anyhow::Result<ExitCode> {
    let mesh = match super::read_work_mesh(&args.input) {
        Ok(mesh) => mesh,
        Err(err) => {
            report_error(args, &err.to_string());
            return Ok(ExitCode::from(2));
        }
    };
    let mut options = FixOptions::default();
    options.params.cell_size = args.cell;
    options.validate_intersections = !args.no_intersection_check;
    options.allow_loss = args.allow_loss;
    options.volume_tolerance = args.volume_tolerance;
    let outcome = match fix_with(&mesh, &options) {
        Ok(outcome) => outcome,
        Err(err) => {
            report_error(args, &err.to_string());
            return Ok(ExitCode::from(1));
        }
    };
    write_mesh_file(&outcome.mesh, &args.output, args.binary)?;
    let report = &outcome.report;
    let valid = report.validation.is_valid();
    for w in &report.warnings {
        eprintln!("warning: {w}");
    }
    if args.json {
        let record = FixRecord {
            schema: "surftrack.fix/1",
            input: args.input.display().to_string(),
            output: args.output.display().to_string(),
            valid,
            peak_rss_mib: crate::isolate::own_peak_resident_bytes()
                .map(crate::record::bytes_to_mib),
            report,
        };
        println!("{}", serde_json::to_string_pretty(&record)?);
    } else {
        let total = report.seconds;
        let c = &report.volume_check;
        for r in &report.relabelled {
            println!("nested part: {r}");
        }
        println!("{}", report.cell_size_choice.reason);
        for v in &report.volumes {
            println!(
                "material {}: volume {:.6} -> {:.6}",
                v.label.raw(),
                v.before,
                v.after
            );
        }
        println!(
            "total volume {:.6}, union of the input {:.6} ({:.2} % off, tolerance {:.2} %)",
            c.output,
            c.reference,
            100.0 * c.relative_change,
            100.0 * c.tolerance
        );
        println!(
            "fixed {} -> {}: {} -> {} triangles, {:.1}% of the input untouched, {} flawed cells (ℓ = {:.4}), {:.2} s",
            args.input.display(),
            args.output.display(),
            report.triangles_in,
            report.triangles_out,
            100.0 * report.untouched_fraction,
            report.flawed_cells,
            report.cell_size,
            total,
        );
        println!("{}", report.validation);
    }
    Ok(if valid {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}

fn report_error(args: &FixArgs, message: &str) {
    if args.json {
        let record = serde_json::json!({
            "schema": "surftrack.fix/1",
            "input": args.input.display().to_string(),
            "error": message,
            "valid": false,
        });
        println!("{record}");
    } else {
        eprintln!("error: {message}");
    }
}
