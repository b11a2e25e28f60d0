//! The Rust side of the Python-overhead figure: `cargo run --release --example overhead
//! [-- STEPS]`, against `python examples/python/overhead.py [STEPS]`.
//!
//! Both run the same loop on the same mesh — the `spheres` scene's 20 random spheres
//! (seed 1) growing along their area-weighted vertex normals at the scene's speed, 40
//! steps of the grid backend by default, through `surftrack::Tracker` — and print the
//! wall time of the loop, proposal included, and how much of it was spent outside
//! `advance` (the part Python can make slower).

use std::time::Instant;

use bench_harness::scenes::{SceneOptions, build_scene};
use surftrack::mesh_core::DVec3;
use surftrack::mesh_core::geometry::vertex_normals;
use surftrack::{Backend, BackendOptions, Tracker};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let steps: usize = std::env::args().nth(1).map_or(Ok(40), |s| s.parse())?;
    let n = 20;
    let options = SceneOptions {
        seed: 1,
        count: Some(n),
        ..SceneOptions::default()
    };
    let mesh = build_scene("spheres", &options)?;
    let speed = 0.5 * (n as f64).powf(-1.0 / 3.0);
    let dt = 1.0 / 40.0;
    let mut tracker = Tracker::new(Backend::Grid, mesh, &BackendOptions::default())?;
    let start = Instant::now();
    let mut merges = 0;
    let mut in_advance = 0.0;
    for _ in 0..steps {
        let mesh = tracker.mesh();
        let normals = vertex_normals(mesh);
        let proposed: Vec<DVec3> = mesh
            .positions()
            .iter()
            .zip(normals.as_slice())
            .map(|(p, n)| *p + dt * speed * *n)
            .collect();
        let clock = Instant::now();
        merges += tracker.advance(&proposed)?.events.merges;
        in_advance += clock.elapsed().as_secs_f64();
    }
    println!(
        "rust: {steps} steps, {} triangles, {merges} merges, {:.3} s ({in_advance:.3} s in advance, {:.3} s outside)",
        tracker.mesh().num_triangles(),
        start.elapsed().as_secs_f64(),
        start.elapsed().as_secs_f64() - in_advance,
    );
    Ok(())
}
