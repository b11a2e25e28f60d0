//! Every built-in scene through every backend, through the trait object a simulator
//! would hold (`Box<dyn SurfaceTracker>`): a few steps each, every mesh validated.
//!
//! Scenes are built at their smoke-test size (`bench_harness::scenes::smoke_options`). A
//! backend that this build cannot construct (`BackendError::Unavailable`) is skipped
//! with a note on stdout, so the test runs whichever backends exist.

use bench_harness::scenes::{SCENES, build_tracked, smoke_options};
use surftrack::mesh_core::validate::{ValidateOptions, validate};
use surftrack::{Backend, BackendError, SurfaceTracker, make_tracker};

/// Steps per scene: enough to move, merge or repair, few enough to keep the test short.
const STEPS: usize = 3;

/// Scenes that teleport shapes into each other in one step (booleans): the collision
/// backend resolves trajectories, not teleports, and must refuse them at once with an
/// error that says so (`CollisionParams::max_displacement_factor`), not grind or tangle.
const TELEPORTS: &[&str] = &["copies"];

/// Runs one scene with one backend; `Ok(false)` when the backend is unavailable.
fn run_scene(scene: &str, backend: Backend) -> Result<bool, String> {
    let built = build_tracked(scene, &smoke_options(scene)).map_err(|e| e.to_string())?;
    let options = ValidateOptions::default();
    let initial = validate(&built.mesh, &options);
    if !initial.is_valid() {
        return Err(format!("initial mesh invalid: {initial}"));
    }
    let mut tracker: Box<dyn SurfaceTracker> = match make_tracker(backend, built.mesh) {
        Ok(tracker) => tracker,
        Err(BackendError::Unavailable { reason, .. }) => {
            println!("{scene} / {backend}: skipped, backend unavailable ({reason})");
            return Ok(false);
        }
        Err(e) => return Err(e.to_string()),
    };
    let mut t = 0.0;
    for step in 1..=built.steps.min(STEPS) {
        let dt = match built.flow.max_stable_dt(tracker.mesh()) {
            Some(limit) if limit > 0.0 && 0.9 * limit < built.dt => 0.9 * limit,
            _ => built.dt,
        };
        let proposed = built.flow.propose(tracker.mesh(), t, dt);
        let report = tracker
            .advance(&proposed)
            .map_err(|e| format!("step {step}: {e}"))?;
        t += dt;
        let mesh = tracker.mesh();
        let check = validate(mesh, &options);
        if !check.is_valid() {
            return Err(format!("step {step}: invalid mesh: {check}"));
        }
        if report.triangles != mesh.num_triangles() {
            return Err(format!(
                "step {step}: report says {} triangles, mesh has {}",
                report.triangles,
                mesh.num_triangles()
            ));
        }
    }
    println!(
        "{scene} / {backend}: {} steps, {} triangles, valid",
        built.steps.min(STEPS),
        tracker.mesh().num_triangles()
    );
    Ok(true)
}

#[test]
fn every_scene_runs_through_every_available_backend_and_stays_valid() {
    let mut failures = Vec::new();
    let mut ran = 0;
    for scene in SCENES.iter().filter(|s| s.steps > 0) {
        for backend in Backend::ALL {
            let teleport = backend == Backend::Collision && TELEPORTS.contains(&scene.name);
            match run_scene(scene.name, backend) {
                Ok(true) if teleport => failures.push(format!(
                    "{} / {backend}: a teleport was accepted by the collision backend",
                    scene.name
                )),
                Ok(true) => ran += 1,
                Ok(false) => {}
                Err(e) if teleport && e.contains("teleports") => {
                    println!("{} / {backend}: refused as expected ({e})", scene.name);
                }
                Err(e) => failures.push(format!("{} / {backend}: {e}", scene.name)),
            }
        }
    }
    println!("{ran} scene × backend runs");
    assert!(failures.is_empty(), "failures:\n{}", failures.join("\n"));
}
