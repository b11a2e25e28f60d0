//! `surftrack validate FILE [--intersections] [--json]`.

use std::collections::BTreeMap;
use std::process::ExitCode;

use mesh_core::geometry::label_volumes;
use mesh_core::validate::{ValidateOptions, validate};
use serde::Serialize;

use super::ValidateArgs;

/// The stable JSON record printed by `validate --json`.
#[derive(Serialize)]
struct ValidateRecord {
    file: String,
    vertices: usize,
    triangles: usize,
    labels: Vec<u32>,
    boundary_edges: usize,
    inconsistent_edges: usize,
    same_label_triangles: usize,
    degenerate: usize,
    zero_area: usize,
    duplicates: usize,
    non_finite: usize,
    corner_table_errors: usize,
    non_manifold_edges: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    self_intersecting_pairs: Option<usize>,
    volumes: BTreeMap<String, f64>,
    valid: bool,
    report: mesh_core::validate::ValidationReport,
}

pub(super) fn run(args: &ValidateArgs) -> anyhow::Result<ExitCode> {
    let mesh = match mesh_core::io::read_mesh(&args.file) {
        Ok(mesh) => mesh,
        Err(err) => {
            if args.json {
                let record = serde_json::json!({ "file": args.file.display().to_string(), "error": err.to_string(), "valid": false });
                println!("{record}");
            } else {
                eprintln!("error: {err}");
            }
            return Ok(ExitCode::from(2));
        }
    };
    let options = ValidateOptions {
        intersections: args.intersections,
        ..ValidateOptions::default()
    };
    let report = validate(&mesh, &options);
    let valid = report.is_valid();
    let volumes = label_volumes(&mesh)
        .into_iter()
        .map(|(label, volume)| (label.raw().to_string(), volume))
        .collect();
    if args.json {
        let record = ValidateRecord {
            file: args.file.display().to_string(),
            vertices: mesh.num_vertices(),
            triangles: mesh.num_triangles(),
            labels: mesh.label_set().iter().map(|l| l.raw()).collect(),
            boundary_edges: report.boundary_edges.count,
            inconsistent_edges: report.inconsistent_edges.count,
            same_label_triangles: report.same_label_triangles.count,
            degenerate: report.degenerate.count,
            zero_area: report.zero_area.count,
            duplicates: report.duplicates.count,
            non_finite: report.non_finite.count,
            corner_table_errors: report.corner_table.count,
            non_manifold_edges: report.non_manifold_edges,
            self_intersecting_pairs: report.self_intersecting_pairs.as_ref().map(|l| l.count),
            volumes,
            valid,
            report,
        };
        println!("{}", serde_json::to_string_pretty(&record)?);
    } else {
        println!("{}: {}", args.file.display(), report);
        for (label, volume) in &volumes {
            println!("  volume of label {label}: {volume:.9}");
        }
        println!("{}", if valid { "valid" } else { "INVALID" });
    }
    Ok(if valid {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}
