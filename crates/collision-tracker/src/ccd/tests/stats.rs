//! Release-mode timings and large-sample statistics (both `#[ignore]`d):
//! `cargo test --release -p collision-tracker -- --ignored --nocapture`.

use glam::DVec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::*;

/// Timings in release: `cargo test --release -p collision-tracker -- --ignored --nocapture`.
#[test]
#[ignore = "timing; run in release"]
fn ccd_timings() {
    use std::hint::black_box;
    use std::time::Instant;

    fn time(label: &str, cfgs: &[Config], kind: Kind) {
        let reps = 2_000_000 / cfgs.len();
        let start = Instant::now();
        let mut hits = 0usize;
        for _ in 0..reps {
            for &(x0, x1) in cfgs {
                let r = match kind {
                    Kind::VertexTriangle => ccd_vertex_triangle(black_box(x0), black_box(x1)),
                    Kind::EdgeEdge => ccd_edge_edge(black_box(x0), black_box(x1)),
                };
                hits += usize::from(r.is_some());
            }
        }
        let ns = start.elapsed().as_nanos() as f64 / (reps * cfgs.len()) as f64;
        let iterations: u32 = cfgs
            .iter()
            .map(|&(x0, x1)| match kind {
                Kind::VertexTriangle => ccd_vertex_triangle_traced(x0, x1).1,
                Kind::EdgeEdge => ccd_edge_edge_traced(x0, x1).1,
            })
            .sum();
        let mean = f64::from(iterations) / cfgs.len() as f64;
        println!(
            "{label:<48} {ns:8.1} ns/query {mean:5.1} iterations ({} hits of {})",
            hits / reps,
            cfgs.len()
        );
    }

    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let mut small = |c: DVec3, r: f64| {
        c + DVec3::new(
            rng.random_range(-r..r),
            rng.random_range(-r..r),
            rng.random_range(-r..r),
        )
    };
    // Rejected by the swept box: elements of size ~0.2 about 0.5 apart.
    let mut far = |first: usize| -> Vec<Config> {
        (0..1000)
            .map(|_| {
                let c: [DVec3; 4] = std::array::from_fn(|i| {
                    if i < first {
                        DVec3::ZERO
                    } else {
                        DVec3::splat(0.5)
                    }
                });
                let a = c.map(|c| small(c, 0.1));
                (a, a.map(|x| x + DVec3::splat(0.01)))
            })
            .collect()
    };
    let (far_vt, far_ee) = (far(1), far(2));
    // Sliding at a small distance (1e-4) over a tilted triangle: rejected by the cubic.
    let tilt = glam::DMat3::from_euler(glam::EulerRot::XYZ, 0.3, -0.4, 0.5);
    let flat = |c: DVec3, r: f64, rng: &mut ChaCha8Rng| {
        c + DVec3::new(rng.random_range(-r..r), rng.random_range(-r..r), 0.0)
    };
    let slide_vt: Vec<Config> = {
        let mut r = ChaCha8Rng::seed_from_u64(6);
        (0..1000)
            .map(|_| {
                let tri = [DVec3::ZERO, DVec3::X, DVec3::Y].map(|c| flat(c, 0.05, &mut r));
                let p = DVec3::new(0.3, 0.3, 1e-4);
                let v = DVec3::new(0.2, -0.1, 0.0);
                (
                    [p, tri[0], tri[1], tri[2]].map(|x| tilt * x),
                    [p + v, tri[0], tri[1], tri[2]].map(|x| tilt * x),
                )
            })
            .collect()
    };
    // True collisions through the exact path.
    let hit_vt: Vec<Config> = (0..1000)
        .map(|_| {
            let tri = [DVec3::ZERO, DVec3::X, DVec3::Y].map(|c| small(c, 0.05));
            let p = small(DVec3::new(0.3, 0.3, 0.0), 0.1);
            (
                [p + DVec3::Z * 0.5, tri[0], tri[1], tri[2]].map(|x| tilt * x),
                [p - DVec3::Z * 0.5, tri[0], tri[1], tri[2]].map(|x| tilt * x),
            )
        })
        .collect();
    let hit_ee: Vec<Config> = (0..1000)
        .map(|_| {
            let p = [DVec3::new(-1.0, 0.0, 0.5), DVec3::new(1.0, 0.0, 0.5)].map(|c| small(c, 0.1));
            let qq = [DVec3::new(0.0, -1.0, 0.0), DVec3::new(0.0, 1.0, 0.0)].map(|c| small(c, 0.1));
            let x0 = [p[0], p[1], qq[0], qq[1]].map(|x| tilt * x);
            let x1 = [p[0] - DVec3::Z, p[1] - DVec3::Z, qq[0], qq[1]].map(|x| tilt * x);
            (x0, x1)
        })
        .collect();
    // Near misses: the vertex crosses the plane 1e-3 outside an edge.
    let miss_vt: Vec<Config> = (0..1000)
        .map(|_| {
            let p = DVec3::new(0.5005, 0.5005, 0.5);
            let tri = [DVec3::ZERO, DVec3::X, DVec3::Y];
            (
                [p, tri[0], tri[1], tri[2]].map(|x| tilt * x),
                [p - DVec3::Z, tri[0], tri[1], tri[2]].map(|x| tilt * x),
            )
        })
        .collect();
    let random: Vec<Config> = {
        let mut r = ChaCha8Rng::seed_from_u64(9);
        (0..1000).map(|_| random_config(&mut r)).collect()
    };
    time(
        "vertex-triangle, far (swept box rejects)",
        &far_vt,
        Kind::VertexTriangle,
    );
    time(
        "edge-edge, far (swept box rejects)",
        &far_ee,
        Kind::EdgeEdge,
    );
    time(
        "vertex-triangle, sliding at 1e-4 (cubic rejects)",
        &slide_vt,
        Kind::VertexTriangle,
    );
    time(
        "vertex-triangle, near miss 1e-3 outside an edge",
        &miss_vt,
        Kind::VertexTriangle,
    );
    time(
        "vertex-triangle, true collision",
        &hit_vt,
        Kind::VertexTriangle,
    );
    time("edge-edge, true collision", &hit_ee, Kind::EdgeEdge);
    time(
        "vertex-triangle, random in [-1,1]^3",
        &random,
        Kind::VertexTriangle,
    );
    time("edge-edge, random in [-1,1]^3", &random, Kind::EdgeEdge);
}

/// A configuration generator.
type Gen<'a> = &'a dyn Fn(&mut ChaCha8Rng) -> Config;

/// Large-sample statistics: `cargo test --release -p collision-tracker soak -- --ignored --nocapture`.
#[test]
#[ignore = "soak; minutes in the test profile"]
fn soak_statistics() {
    let n = 20_000;
    let touching_vt = |rng: &mut ChaCha8Rng| {
        let (mut x0, mut x1) = grid_config_rng(rng);
        let (i, j) = (rng.random_range(0..=4u8), rng.random_range(0..=4u8));
        let (i, j) = if i + j > 4 { (4 - i, 4 - j) } else { (i, j) };
        let x = if rng.random_bool(0.5) {
            &mut x1
        } else {
            &mut x0
        };
        x[0] = x[1] + (x[2] - x[1]) * (f64::from(i) / 4.0) + (x[3] - x[1]) * (f64::from(j) / 4.0);
        (x0, x1)
    };
    let touching_ee = |rng: &mut ChaCha8Rng| {
        let (mut x0, mut x1) = grid_config_rng(rng);
        let k = rng.random_range(0..=4u8);
        let idx = rng.random_range(0..2usize);
        let x = if rng.random_bool(0.5) {
            &mut x1
        } else {
            &mut x0
        };
        x[idx] = quarter(x[2], x[3], k);
        (x0, x1)
    };
    let parallel_ee = |rng: &mut ChaCha8Rng| {
        let (mut x0, mut x1) = grid_config_rng(rng);
        let s = [1.0, -1.0, 2.0, 0.5, -0.5][rng.random_range(0..5usize)];
        x0[3] = x0[2] + (x0[1] - x0[0]) * s;
        x1[3] = x1[2] + (x1[1] - x1[0]) * s;
        (x0, x1)
    };
    let planar_rng = |rng: &mut ChaCha8Rng| planar(grid_config_rng(rng));
    let planar_touching_vt = |rng: &mut ChaCha8Rng| planar(touching_vt(rng));
    let planar_touching_ee = |rng: &mut ChaCha8Rng| planar(touching_ee(rng));
    let planar_parallel_ee = |rng: &mut ChaCha8Rng| planar(parallel_ee(rng));
    let near = |rng: &mut ChaCha8Rng| {
        let cfg = grid_config_rng(rng);
        perturbed(cfg, rng, 1e-12)
    };
    let vt: [(&str, Gen); 5] = [
        ("random", &random_config),
        ("grid", &grid_config_rng),
        ("planar grid", &planar_rng),
        ("touching", &touching_vt),
        ("planar touching", &planar_touching_vt),
    ];
    for (name, g) in vt {
        println!("VT {name:<18} {:?}", tally(Kind::VertexTriangle, n, g, 1));
    }
    let vt_near = tally(Kind::VertexTriangle, n, near, 2);
    println!("VT {:<18} {vt_near:?}", "grid ± 1e-12");
    let ee: [(&str, Gen); 7] = [
        ("random", &random_config),
        ("grid", &grid_config_rng),
        ("planar grid", &planar_rng),
        ("touching", &touching_ee),
        ("planar touching", &planar_touching_ee),
        ("parallel", &parallel_ee),
        ("planar parallel", &planar_parallel_ee),
    ];
    for (name, g) in ee {
        println!("EE {name:<18} {:?}", tally(Kind::EdgeEdge, n, g, 3));
    }
    println!(
        "EE {:<18} {:?}",
        "grid ± 1e-12",
        tally(Kind::EdgeEdge, n, near, 4)
    );
}
