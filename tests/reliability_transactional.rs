//! Transactional steps (issue 7, item 2): every `advance` either returns `Ok` with a valid
//! mesh or `Err` with the previous mesh bit-identical — positions compared bitwise,
//! triangles, labels, slot capacities and liveness exactly. Failures are forced on both
//! backends through the trait object a simulator holds: NaN and wrong-length proposals, a
//! zero time budget (grid), bounds of zero (no safety-net or sub-ℓ rounds for the grid
//! backend, no step halvings for the collision backend), and steps that cannot succeed
//! (coordinates beyond the grid's range, a teleport beyond the collision backend's
//! displacement bound). After each failure the tracker must still take a good step.

use std::time::Duration;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use surftrack::collision_tracker::{CollisionParams, CollisionTracker};
use surftrack::grid_tracker::{GridParams, GridTracker};
use surftrack::mesh_core::generators::icosphere;
use surftrack::mesh_core::validate::{ValidateOptions, validate};
use surftrack::mesh_core::{DVec3, Label, LabeledMesh};
use surftrack::{Backend, SurfaceTracker, TrackError, TrackerOptions, make_tracker_with};

/// Everything observable about a mesh, bitwise.
#[derive(Debug, PartialEq, Eq)]
struct Snapshot {
    positions: Vec<[u64; 3]>,
    tris: Vec<[u32; 3]>,
    labels: Vec<[u32; 2]>,
    tri_alive: Vec<bool>,
    vertex_capacity: usize,
}

fn snapshot(mesh: &LabeledMesh) -> Snapshot {
    Snapshot {
        positions: mesh
            .positions()
            .iter()
            .map(|p| p.to_array().map(f64::to_bits))
            .collect(),
        tris: mesh.tris().iter().map(|t| t.map(|v| v.raw())).collect(),
        labels: mesh
            .label_pairs()
            .iter()
            .map(|l| l.map(|l| l.raw()))
            .collect(),
        tri_alive: mesh.tri_alive_flags().to_vec(),
        vertex_capacity: mesh.vertex_capacity(),
    }
}

/// Two spheres of labels 1 and 2, radius 0.5, centres `distance` apart on x.
fn two_spheres(distance: f64) -> LabeledMesh {
    let a = icosphere(2, DVec3::ZERO, 0.5, [Label::OUTSIDE, Label::new(1)]).unwrap();
    let b = icosphere(2, DVec3::X * distance, 0.5, [Label::OUTSIDE, Label::new(2)]).unwrap();
    let (mut p, mut t, mut l) = a.to_raw();
    let (pb, tb, lb) = b.to_raw();
    let base = p.len() as u32;
    p.extend(pb);
    t.extend(tb.iter().map(|f| f.map(|i| i + base)));
    l.extend(lb);
    LabeledMesh::from_raw(p, &t, &l).unwrap()
}

/// Runs `advance` and checks the contract; returns whether the step succeeded.
fn step(tracker: &mut dyn SurfaceTracker, proposed: &[DVec3]) -> Result<(), TrackError> {
    let before = snapshot(tracker.mesh());
    match tracker.advance(proposed) {
        Ok(report) => {
            let v = validate(tracker.mesh(), &ValidateOptions::default());
            assert!(
                v.is_valid(),
                "{}: Ok with an invalid mesh: {v}",
                tracker.name()
            );
            assert_eq!(report.triangles, tracker.mesh().num_triangles());
            Ok(())
        }
        Err(e) => {
            assert_eq!(
                snapshot(tracker.mesh()),
                before,
                "{}: failed step ({e}) changed the mesh",
                tracker.name()
            );
            Err(e)
        }
    }
}

/// The first sphere moved `dx` towards the second.
fn approach(mesh: &LabeledMesh, dx: f64) -> Vec<DVec3> {
    mesh.positions()
        .iter()
        .map(|&p| if p.x < 0.75 { p + DVec3::X * dx } else { p })
        .collect()
}

/// Both backends through the facade, with default options.
fn trackers(mesh: &LabeledMesh) -> Vec<Box<dyn SurfaceTracker>> {
    Backend::ALL
        .iter()
        .map(|&b| make_tracker_with(b, mesh.clone(), &TrackerOptions::default()).unwrap())
        .collect()
}

#[test]
fn malformed_proposals_fail_and_the_tracker_goes_on() {
    let mesh = two_spheres(1.5);
    for mut t in trackers(&mesh) {
        let good = approach(t.mesh(), 0.05);
        let mut nan = good.clone();
        nan[7].z = f64::NAN;
        assert!(matches!(
            step(t.as_mut(), &nan),
            Err(TrackError::NonFiniteProposal { .. })
        ));
        assert!(matches!(
            step(t.as_mut(), &good[1..]),
            Err(TrackError::ProposalLength { .. })
        ));
        step(t.as_mut(), &good).unwrap_or_else(|e| panic!("{}: {e}", t.name()));
    }
}

#[test]
fn grid_zero_time_budget_fails_every_step_untouched() {
    let mesh = two_spheres(1.5);
    for budget in [Duration::ZERO, Duration::from_nanos(1)] {
        let params = GridParams {
            time_budget: Some(budget),
            ..GridParams::default()
        };
        let mut t: Box<dyn SurfaceTracker> =
            Box::new(GridTracker::new(mesh.clone(), params).unwrap());
        // Motion that makes the spheres overlap: the step would have work to do.
        let proposed = approach(t.mesh(), 0.3);
        match step(t.as_mut(), &proposed) {
            Err(TrackError::TimeBudgetExceeded { budget: b, .. }) => assert_eq!(b, budget),
            other => panic!("budget {budget:?}: expected TimeBudgetExceeded, got {other:?}"),
        }
    }
    // A generous budget changes nothing.
    let params = GridParams {
        time_budget: Some(Duration::from_secs(600)),
        ..GridParams::default()
    };
    let mut t = GridTracker::new(mesh.clone(), params).unwrap();
    let proposed = approach(t.mesh(), 0.3);
    step(&mut t, &proposed).unwrap();
}

#[test]
fn grid_step_beyond_the_grid_range_fails_untouched() {
    let mesh = two_spheres(1.5);
    let mut t = make_tracker_with(Backend::Grid, mesh, &TrackerOptions::default()).unwrap();
    // One vertex thrown 1e12 away: ℓ is far too fine for that extent.
    let mut proposed = t.mesh().positions().to_vec();
    proposed[0] += DVec3::splat(1e12);
    match step(t.as_mut(), &proposed) {
        Err(TrackError::StageFailed { stage: "grid", .. }) => {}
        other => panic!("expected a grid-stage failure, got {other:?}"),
    }
    let good = approach(t.mesh(), 0.05);
    step(t.as_mut(), &good).unwrap();
}

#[test]
fn grid_without_repair_rounds_is_transactional() {
    // Zero safety-net and sub-ℓ rounds: a deep overlap may now fail; whatever happens,
    // the contract holds.
    let mesh = two_spheres(1.5);
    let params = GridParams {
        max_safety_rounds: 0,
        max_subcell_rounds: 0,
        ..GridParams::default()
    };
    let mut t = GridTracker::new(mesh, params).unwrap();
    for dx in [0.4, 0.2, -0.3] {
        let proposed = approach(t.mesh(), dx);
        let _ = step(&mut t, &proposed);
    }
}

#[test]
fn collision_teleport_and_zero_halvings_fail_untouched() {
    let mesh = two_spheres(1.5);
    let mut t: Box<dyn SurfaceTracker> =
        Box::new(CollisionTracker::new(mesh.clone(), CollisionParams::default()).unwrap());
    // A teleport of the first sphere into the second: refused by the displacement bound.
    let proposed = approach(t.mesh(), 1.5);
    assert!(step(t.as_mut(), &proposed).is_err());
    let small = approach(t.mesh(), 0.02);
    step(t.as_mut(), &small).unwrap();

    // No halvings allowed: a step whose motion collides cannot shrink itself.
    let params = CollisionParams {
        max_halvings: 0,
        ..CollisionParams::default()
    };
    let mut t: Box<dyn SurfaceTracker> = Box::new(CollisionTracker::new(mesh, params).unwrap());
    let mut failures = 0;
    for _ in 0..3 {
        let proposed = approach(t.mesh(), 0.3);
        if step(t.as_mut(), &proposed).is_err() {
            failures += 1;
        }
    }
    println!("collision with max_halvings = 0: {failures} of 3 colliding steps failed");
}

#[test]
fn random_good_and_bad_steps_keep_the_contract() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let mesh = two_spheres(1.3);
    for mut t in trackers(&mesh) {
        let (mut ok, mut err) = (0, 0);
        for _ in 0..6 {
            let n = t.mesh().vertex_capacity();
            let mut proposed: Vec<DVec3> = t
                .mesh()
                .positions()
                .iter()
                .map(|&p| {
                    p + DVec3::new(
                        rng.random_range(-0.02..0.02),
                        rng.random_range(-0.02..0.02),
                        rng.random_range(-0.02..0.02),
                    )
                })
                .collect();
            match rng.random_range(0..4) {
                0 => proposed[rng.random_range(0..n)].y = f64::INFINITY,
                1 => proposed.truncate(n / 2),
                _ => {}
            }
            match step(t.as_mut(), &proposed) {
                Ok(()) => ok += 1,
                Err(_) => err += 1,
            }
        }
        assert!(ok > 0 && err > 0, "{}: {ok} ok, {err} failed", t.name());
    }
}

#[test]
fn fix_with_a_zero_time_budget_is_a_typed_error() {
    use surftrack::grid_tracker::{FixError, FixOptions, PipelineError, fix_with};
    // Overlapping spheres: a repair with real work to do.
    let mesh = two_spheres(0.7);
    let mut options = FixOptions::default();
    options.params.time_budget = Some(Duration::ZERO);
    match fix_with(&mesh, &options) {
        Err(FixError::Pipeline(PipelineError::TimeBudget { budget, .. })) => {
            assert_eq!(budget, Duration::ZERO)
        }
        other => panic!(
            "expected a time-budget error, got {:?}",
            other.map(|o| o.report)
        ),
    }
    options.params.time_budget = Some(Duration::from_secs(600));
    let out = fix_with(&mesh, &options).unwrap();
    assert!(
        out.report.validation.is_valid(),
        "{}",
        out.report.validation
    );
}
