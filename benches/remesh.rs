//! Criterion bench of the shared mesh improvement (issue 3): `improve` on a ~200k-triangle
//! scene of 40 noisy spheres, triangles processed per second.
//!
//! Run: `cargo bench --bench remesh`.

use std::hint::black_box;
use std::time::Duration;

use criterion::{BatchSize, Criterion, Throughput, criterion_group, criterion_main};
use glam::DVec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use surftrack::mesh_core::LabeledMesh;
use surftrack::mesh_core::generators::{place_random_spheres, spheres_mesh};
use surftrack::mesh_core::remesh::{
    EditGuard, ImproveParams, NoGuard, StaticIntersectionGuard, VertexAttributes, improve,
};

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

/// Makes a fresh guard for each run (guards index the mesh they see).
type MakeGuard = fn() -> Box<dyn EditGuard>;

fn bench_improve(c: &mut Criterion) {
    let mesh = noisy_spheres();
    let mut group = c.benchmark_group("improve");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(20));
    group.throughput(Throughput::Elements(mesh.num_triangles() as u64));
    let params = ImproveParams::default();
    let guards: [(&str, MakeGuard); 2] = [
        ("no_guard", || Box::new(NoGuard)),
        ("static_intersection_guard", || {
            Box::new(StaticIntersectionGuard::new())
        }),
    ];
    for (name, make_guard) in guards {
        group.bench_function(
            format!(
                "{name}_noisy_spheres_{}k_triangles",
                mesh.num_triangles() / 1000
            ),
            |b| {
                b.iter_batched(
                    || (mesh.clone(), make_guard()),
                    |(mut m, mut guard)| {
                        let mut attrs = VertexAttributes::none();
                        black_box(improve(&mut m, &params, &mut attrs, guard.as_mut()))
                    },
                    BatchSize::LargeInput,
                )
            },
        );
    }
    group.finish();
}

criterion_group!(benches, bench_improve);
criterion_main!(benches);
