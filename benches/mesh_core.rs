//! Criterion benches of the mesh foundation on a ~1.3M-triangle icosphere:
//! building the corner table (target ≥ 2M triangles/s on one core) and the full validation
//! with the exact self-intersection check (target ≥ 1M triangles/s on 2 cores).
//!
//! Run: `cargo bench --bench mesh_core`.

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::DVec3;
use surftrack::mesh_core::generators::icosphere;
use surftrack::mesh_core::validate::{ValidateOptions, validate};
use surftrack::mesh_core::{Label, LabeledMesh};

fn big_sphere() -> LabeledMesh {
    icosphere(8, DVec3::ZERO, 1.0, [Label::new(0), Label::new(1)]).expect("valid parameters")
}

fn bench_connectivity(c: &mut Criterion) {
    let (positions, tris, labels) = big_sphere().to_raw();
    let mut group = c.benchmark_group("corner_table");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(10));
    group.throughput(Throughput::Elements(tris.len() as u64));
    // One thread: the target is per core.
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("thread pool");
    group.bench_function("build_1.3M_triangles_1_thread", |b| {
        b.iter(|| {
            pool.install(|| black_box(LabeledMesh::from_raw(positions.clone(), &tris, &labels)))
        })
    });
    group.finish();
}

fn bench_validate(c: &mut Criterion) {
    let mesh = big_sphere();
    let mut group = c.benchmark_group("validate");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(15));
    group.throughput(Throughput::Elements(mesh.num_triangles() as u64));
    let plain = ValidateOptions::default();
    let exact = ValidateOptions {
        intersections: true,
        ..ValidateOptions::default()
    };
    group.bench_function("invariants_1.3M_triangles", |b| {
        b.iter(|| black_box(validate(&mesh, &plain)))
    });
    group.bench_function("with_intersections_1.3M_triangles", |b| {
        b.iter(|| black_box(validate(&mesh, &exact)))
    });
    group.finish();
}

criterion_group!(benches, bench_connectivity, bench_validate);
criterion_main!(benches);
