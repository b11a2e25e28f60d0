//! Mesh improvement on a noisy scene: `cargo run --release --example remesh`.
//!
//! Builds 40 random spheres (~205k triangles), jitters every vertex radially by up to 20 %
//! of an edge length, runs the shared `improve` driver with the static exact-intersection guard,
//! validates the result (exact self-intersection check included) and prints the report.

use std::time::Instant;

use glam::DVec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use surftrack::mesh_core::LabeledMesh;
use surftrack::mesh_core::generators::{place_random_spheres, spheres_mesh};
use surftrack::mesh_core::remesh::{
    ImproveParams, StaticIntersectionGuard, VertexAttributes, improve,
};
use surftrack::mesh_core::validate::{ValidateOptions, validate};

/// 40 spheres of 5120 triangles each (~205k triangles) with radii varying threefold, so one
/// target edge length makes the small ones collapse and the large ones split; every vertex
/// is pushed radially from its sphere's centre by up to ±20 % of that sphere's edge length,
/// so flips and smoothing have work too. Still intersection-free: each sphere stays
/// star-shaped about its centre, and the jitter stays below half the smallest gap.
fn noisy_spheres() -> LabeledMesh {
    let spheres = place_random_spheres(40, DVec3::ZERO, DVec3::ONE, [0.03, 0.09], 7)
        .expect("valid parameters");
    let mut mesh = spheres_mesh(&spheres, 4).expect("valid parameters");
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let vertices: Vec<_> = mesh.vertices().collect();
    for v in vertices {
        let p = mesh.position(v);
        let Some(sphere) = spheres.iter().min_by(|a, b| {
            (a.centre.distance(p) - a.radius)
                .abs()
                .total_cmp(&(b.centre.distance(p) - b.radius).abs())
        }) else {
            continue;
        };
        // An icosphere of 4 subdivisions has edges of about 0.066 radius.
        let jitter = rng.random_range(-1.0..1.0) * 0.2 * 0.066 * sphere.radius;
        mesh.set_position(v, p + (p - sphere.centre).normalize_or_zero() * jitter);
    }
    mesh
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut mesh = noisy_spheres();
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
