//! `surftrack validate FILE [--intersections] [--json]`.

use std::collections::BTreeMap;
use std::path::Path;
use std::process::ExitCode;

use mesh_core::geometry::label_volumes;
use mesh_core::io::{ReadOptions, ReadReport, read_mesh_reported};
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
    out_of_range: usize,
    corner_table_errors: usize,
    non_manifold_edges: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    self_intersecting_pairs: Option<usize>,
    volumes: BTreeMap<String, f64>,
    /// Vertices `fix` and `run --mesh` would stitch (repeated positions on open edges).
    stitchable_vertices: usize,
    /// Vertices they would insert into open edges that run past them (T-junctions).
    t_junction_vertices: usize,
    valid: bool,
    report: mesh_core::validate::ValidationReport,
}

/// What the working commands' stitching would change in `path` (nothing if the file
/// does not read even so): validation reports the file as written, this says whether a
/// broken-looking file is only a triangle soup or has T-junctions.
fn stitchable(path: &Path) -> ReadReport {
    let stitch = ReadOptions {
        stitch: true,
        ..ReadOptions::default()
    };
    read_mesh_reported(path, &stitch).map_or(ReadReport::default(), |(_, report)| report)
}

/// The hint shown under an invalid or unreadable file that stitching would change.
fn stitch_hint(stitchable: &ReadReport) -> Option<String> {
    let mut found = Vec::new();
    if stitchable.stitched_vertices > 0 {
        found.push(format!(
            "{} vertices repeat another one's position on an open edge (per-face vertices, \
             as STL-style exporters write them)",
            stitchable.stitched_vertices
        ));
    }
    if stitchable.t_junction_vertices > 0 {
        found.push(format!(
            "{} vertices lie on an open edge that runs past them (T-junctions, as CAD \
             exporters leave them)",
            stitchable.t_junction_vertices
        ));
    }
    (!found.is_empty()).then(|| {
        format!(
            "hint: {}; `surftrack fix` and `run --mesh` stitch them",
            found.join("; ")
        )
    })
}

pub(super) fn run(args: &ValidateArgs) -> anyhow::Result<ExitCode> {
    let read = mesh_core::io::read_mesh(&args.file).map_err(|e| e.to_string());
    let read = read.and_then(|mesh| match super::no_triangles(&args.file, &mesh) {
        Some(refusal) => Err(refusal),
        None => Ok(mesh),
    });
    let mesh = match read {
        Ok(mesh) => mesh,
        Err(err) => {
            let stitchable = stitchable(&args.file);
            if args.json {
                let record = serde_json::json!({
                    "file": args.file.display().to_string(),
                    "error": err,
                    "stitchable_vertices": stitchable.stitched_vertices,
                    "t_junction_vertices": stitchable.t_junction_vertices,
                    "valid": false,
                });
                println!("{record}");
            } else {
                eprintln!("error: {err}");
                if let Some(hint) = stitch_hint(&stitchable) {
                    eprintln!("{hint}");
                }
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
    let stitchable = if report.boundary_edges.count > 0 {
        stitchable(&args.file)
    } else {
        ReadReport::default()
    };
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
            out_of_range: report.out_of_range.count,
            corner_table_errors: report.corner_table.count,
            non_manifold_edges: report.non_manifold_edges,
            self_intersecting_pairs: report.self_intersecting_pairs.as_ref().map(|l| l.count),
            volumes,
            stitchable_vertices: stitchable.stitched_vertices,
            t_junction_vertices: stitchable.t_junction_vertices,
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
        if let Some(hint) = stitch_hint(&stitchable) {
            println!("{hint}");
        }
    }
    Ok(if valid {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}
