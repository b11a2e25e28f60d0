//! Timings of the first three stages on large meshes. Ignored by default; run with
//! `cargo test --release -p grid-tracker --test stage_timing -- --ignored --nocapture
//! --test-threads=1`. Prints wall time (best of `REPS`, default 3) and the process CPU
//! time of that run, which is less disturbed by other load on a shared machine.

mod common;

use std::time::Instant;

use common::{mean_edge, sphere, union};
use glam::DVec3;
use grid_tracker::{
    FlawOptions, GridOptions, MaterialOptions, assign_materials, build_grid, detect_flaws,
};
use mesh_core::LabeledMesh;

/// Runs the three stages `reps` times and prints the fastest time of each (the machine
/// may be shared, so the minimum is the least disturbed figure).
fn time_stages(name: &str, mesh: &LabeledMesh, ell: f64) {
    let reps = std::env::var("REPS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(3);
    let mut best = [f64::INFINITY; 3];
    let mut cpu_best = [f64::INFINITY; 3];
    let mut report = String::new();
    for _ in 0..reps {
        let (t0, c0) = (Instant::now(), cpu_ms());
        let grid = build_grid(mesh, ell, &GridOptions::default()).expect("grid");
        let (t1, c1) = (Instant::now(), cpu_ms());
        let mats = assign_materials(mesh, &grid, &MaterialOptions::default()).expect("materials");
        let (t2, c2) = (Instant::now(), cpu_ms());
        let flaws = detect_flaws(mesh, &grid, &mats, &FlawOptions::default()).expect("flaws");
        let (t3, c3) = (Instant::now(), cpu_ms());
        for (b, d) in best.iter_mut().zip([t1 - t0, t2 - t1, t3 - t2]) {
            *b = b.min(d.as_secs_f64() * 1e3);
        }
        for (b, d) in cpu_best.iter_mut().zip([c1 - c0, c2 - c1, c3 - c2]) {
            *b = b.min(d);
        }
        report = format!(
            "  {:?}\n  {:?}\n  {:?}",
            grid.stats(),
            mats.stats(),
            flaws.stats()
        );
    }
    println!(
        "{name}: {} triangles, ℓ = {ell:.5}, {} threads, best of {reps}\n  wall: build_grid {:.0} ms, assign_materials {:.0} ms, detect_flaws {:.0} ms, total {:.0} ms\n  cpu:  build_grid {:.0} ms, assign_materials {:.0} ms, detect_flaws {:.0} ms\n{report}",
        mesh.num_triangles(),
        rayon::current_num_threads(),
        best[0],
        best[1],
        best[2],
        best.iter().sum::<f64>(),
        cpu_best[0],
        cpu_best[1],
        cpu_best[2],
    );
}

/// User + system CPU time of this process in ms (Linux `/proc/self/stat`, 10 ms ticks);
/// NaN elsewhere.
fn cpu_ms() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return f64::NAN;
    };
    // Fields after the parenthesised command name; utime and stime are fields 14 and 15.
    let rest = stat.rsplit(')').next().unwrap_or("");
    let f: Vec<&str> = rest.split_whitespace().collect();
    let tick = |i: usize| {
        f.get(i)
            .and_then(|s| s.parse::<f64>().ok())
            .unwrap_or(f64::NAN)
    };
    (tick(11) + tick(12)) * 10.0
}

#[test]
#[ignore]
fn one_million_triangle_icosphere() {
    let t = Instant::now();
    let s = sphere(8, DVec3::new(0.01, -0.02, 0.03), 1.0, 0, 1);
    println!(
        "icosphere generated in {:.0} ms",
        t.elapsed().as_secs_f64() * 1e3
    );
    time_stages("icosphere s=8", &s, mean_edge(&s));
}

#[test]
#[ignore]
fn two_overlapping_half_million_spheres() {
    let a = sphere(7, DVec3::new(-0.4, 0.0, 0.0), 1.0, 0, 1);
    let b = sphere(7, DVec3::new(0.45, 0.05, 0.02), 0.9, 0, 2);
    let m = union(&[a, b]);
    time_stages("two overlapping spheres s=7", &m, mean_edge(&m));
}
