//! Determinism: the same scene gives the bit-identical final mesh for any number of
//! threads and from run to run, on both backends.
//!
//! The scene is `surftrack run spheres --spheres 2 --seed 5 --steps 12`: two spheres
//! expanding under normal flow touch at step 6 and merge, so the run covers motion,
//! remeshing and topology changes (merges, and on the collision backend T1/T2 and
//! pinches). It is run through the harness's own driver with 1, 2 and 4 threads (each in
//! its own rayon pool), twice each, and every run must end in one `final_digest` (the
//! harness's digest of vertex and triangle slots, position bits and labels) per backend.
//!
//! Why this catches thread-order dependence: before the float sums that reach decisions
//! were made order-independent (`mesh_core::geometry::ordered_sum`), the mean edge length
//! both trackers derive their length targets from differed in its last bits between 1 and
//! 4 threads, and both backends ended this scene in different meshes.

use bench_harness::driver::{RunConfig, run_scene};
use bench_harness::options::RunOptions;
use bench_harness::record::SceneParams;
use bench_harness::scenes::SceneOptions;
use indicatif::ProgressBar;
use surftrack::Backend;

const SEED: u64 = 5;
const SPHERES: usize = 2;
const STEPS: usize = 12;
const THREADS: [usize; 3] = [1, 2, 4];
const REPEATS: usize = 2;

/// One run of the scene on `backend` inside `pool`: its final digest, after checking that
/// the run completed (a failed run's digest would compare a truncated mesh).
fn final_digest(backend: Backend, pool: &rayon::ThreadPool) -> String {
    let mut run_options = RunOptions::default();
    // As `surftrack run` does: the grid's per-step shifts follow the run's seed.
    run_options.grid.seed = SEED;
    let config = RunConfig {
        scene: "spheres".into(),
        options: SceneOptions {
            seed: SEED,
            count: Some(SPHERES),
            ..SceneOptions::default()
        },
        backend,
        steps: Some(STEPS),
        dt: None,
        every: 0,
        out: None,
        ascii: false,
        max_triangles: None,
        check_intersections: false,
        run_options,
        scene_params: SceneParams {
            count: Some(SPHERES),
            ..SceneParams::default()
        },
    };
    let record = pool
        .install(|| run_scene(&config, &ProgressBar::hidden()))
        .unwrap_or_else(|e| panic!("{backend}: the run could not start: {e}"));
    assert!(
        record.success,
        "{backend} with {} threads failed: {:?}",
        pool.current_num_threads(),
        record.failure
    );
    assert!(
        record.events.merges > 0,
        "{backend}: the scene must change topology to test it: {:?}",
        record.events
    );
    record.final_digest.expect("a finished run has a digest")
}

/// Every (threads, repeat) run of `backend` and their digests; one digest expected.
fn check(backend: Backend) {
    let mut digests = Vec::new();
    for threads in THREADS {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a thread pool");
        for repeat in 0..REPEATS {
            digests.push((threads, repeat, final_digest(backend, &pool)));
        }
    }
    let first = &digests[0].2;
    assert!(
        digests.iter().all(|d| &d.2 == first),
        "{backend}: final meshes differ across thread counts or runs \
         (threads, repeat, digest): {digests:?}"
    );
}

#[test]
fn grid_backend_is_deterministic_across_threads_and_runs() {
    check(Backend::Grid);
}

#[test]
fn collision_backend_is_deterministic_across_threads_and_runs() {
    check(Backend::Collision);
}
