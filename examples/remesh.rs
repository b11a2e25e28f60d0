//! Mesh improvement on a noisy scene: `cargo run --release --example remesh`.
//!
//! Builds 40 random spheres (~205k triangles), jitters every vertex radially by up to 20 %
//! of an edge length, runs the shared `improve` driver with the static exact-intersection guard,
//! validates the result (exact self-intersection check included) and prints the report.

use std::time::Instant;

use bench_harness::scenes::noisy_spheres;
use surftrack::mesh_core::remesh::{
    ImproveParams, StaticIntersectionGuard, VertexAttributes, improve,
};
use surftrack::mesh_core::validate::{ValidateOptions, validate};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut mesh = noisy_spheres()?;
    let before = validate(
        &mesh,
        &ValidateOptions {
            intersections: true,
            ..ValidateOptions::default()
        },
    );
    println!("input: {before}");
    let triangles = mesh.num_triangles();
    let start = Instant::now();
    let report = improve(
        &mut mesh,
        &ImproveParams::default(),
        &mut VertexAttributes::none(),
        &mut StaticIntersectionGuard::new(),
    );
    let seconds = start.elapsed().as_secs_f64();
    let check = validate(
        &mesh,
        &ValidateOptions {
            intersections: true,
            ..ValidateOptions::default()
        },
    );
    println!("{}", serde_json::to_string_pretty(&report)?);
    println!("output: {check}");
    println!(
        "{triangles} -> {} triangles in {seconds:.2} s ({:.0} input triangles/s); valid: {}",
        mesh.num_triangles(),
        triangles as f64 / seconds,
        check.is_valid()
    );
    Ok(())
}
