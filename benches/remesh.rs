//! Criterion bench of the shared mesh improvement (issue 3): `improve` on a ~200k-triangle
//! scene of 40 noisy spheres, triangles processed per second.
//!
//! Run: `cargo bench --bench remesh`.

use std::hint::black_box;
use std::time::Duration;

use bench_harness::scenes::noisy_spheres;
use criterion::{BatchSize, Criterion, Throughput, criterion_group, criterion_main};
use surftrack::mesh_core::remesh::{
    EditGuard, ImproveParams, NoGuard, StaticIntersectionGuard, VertexAttributes, improve,
};

/// Makes a fresh guard for each run (guards index the mesh they see).
type MakeGuard = fn() -> Box<dyn EditGuard>;

fn bench_improve(c: &mut Criterion) {
    let mesh = noisy_spheres().expect("fixed, valid scene parameters");
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
