//! Mesh improvement on a noisy scene: `cargo run --release --example remesh [-- no-guard]`.
//!
//! Builds 40 random spheres (~205k triangles), jitters every vertex radially by up to 20 %
//! of an edge length, runs the shared `improve` driver with the static exact-intersection
//! guard (or none, with `no-guard`, to see what the guard costs), validates the result
//! (exact self-intersection check included) and prints the report with the quality figures
//! the driver is meant to reach: the fraction of edges in `[0.5, 1.5] × ℓ` and the
//! smallest angle.

use std::time::Instant;

use bench_harness::scenes::noisy_spheres;
use surftrack::mesh_core::geometry::quality;
use surftrack::mesh_core::remesh::{
    EditGuard, ImproveParams, NoGuard, StaticIntersectionGuard, VertexAttributes, improve,
};
use surftrack::mesh_core::validate::{ValidateOptions, validate};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let guarded = !std::env::args().any(|a| a == "no-guard");
    let mut mesh = noisy_spheres()?;
    let exact = ValidateOptions {
        intersections: true,
        ..ValidateOptions::default()
    };
    let before = validate(&mesh, &exact);
    println!("input: {before}");
    let q0 = quality(&mesh);
    let triangles = mesh.num_triangles();
    let mut static_guard = StaticIntersectionGuard::new();
    let mut no_guard = NoGuard;
    let guard: &mut dyn EditGuard = if guarded {
        &mut static_guard
    } else {
        &mut no_guard
    };
    let start = Instant::now();
    let report = improve(
        &mut mesh,
        &ImproveParams::default(),
        &mut VertexAttributes::none(),
        guard,
    );
    let seconds = start.elapsed().as_secs_f64();
    let check = validate(&mesh, &exact);
    let q1 = quality(&mesh);
    println!("{}", serde_json::to_string_pretty(&report)?);
    println!("output: {check}");
    println!(
        "min angle {:.2}° -> {:.2}°, edges in [0.5, 1.5]ℓ: {:.4}",
        q0.min_angle_deg, q1.min_angle_deg, report.edges_in_range
    );
    println!(
        "{triangles} -> {} triangles in {seconds:.2} s ({:.0} input triangles/s, {}); valid: {}",
        mesh.num_triangles(),
        triangles as f64 / seconds,
        if guarded {
            "StaticIntersectionGuard"
        } else {
            "no guard"
        },
        check.is_valid()
    );
    Ok(())
}
