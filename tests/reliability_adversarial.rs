//! Adversarial geometry (issue 7, item 4): vertices exactly on grid planes and lines,
//! coplanar overlapping triangles, coincident duplicate surfaces of different labels,
//! needle and cap triangles, many materials meeting in a small region, meshes scaled to
//! 1e-6 and 1e6. Every backend — and `fix` — must return a valid mesh or a typed error,
//! within a bounded time; a failed step must leave the mesh as it was.
//!
//! The many-materials case uses 200 materials here (fast in the test profile); the
//! 1000-material version is `#[ignore]`d, for release runs:
//! `cargo test --release --test reliability_adversarial -- --ignored`.

use std::time::{Duration, Instant};

use surftrack::grid_tracker::{GridParams, GridTracker, fix};
use surftrack::mesh_core::generators::{icosphere, voronoi_foam};
use surftrack::mesh_core::validate::{ValidateOptions, validate};
use surftrack::mesh_core::{DVec3, Label, LabeledMesh};
use surftrack::{Backend, BackendError, SurfaceTracker, TrackerOptions, make_tracker_with};

/// Wall-time bound of any single case in the test profile: far above what the cases
/// take (well under a second each), far below "hanging".
const BOUND: Duration = Duration::from_secs(30);

/// How a backend dealt with a mesh and a proposal.
#[derive(Debug, PartialEq)]
enum Outcome {
    /// Refused at construction with a typed error.
    Refused,
    /// Stepped: `Ok` with a valid mesh.
    Stepped,
    /// The step failed with a typed error, the mesh untouched.
    Failed,
}

/// A mesh's live arrays, positions as bits: equal exactly when the meshes are identical.
type Bits = (Vec<[u64; 3]>, Vec<[u32; 3]>, Vec<[u32; 2]>);

fn bits(mesh: &LabeledMesh) -> Bits {
    let (p, t, l) = mesh.to_raw();
    (
        p.iter().map(|p| p.to_array().map(f64::to_bits)).collect(),
        t,
        l,
    )
}

/// Runs one step of `tracker` towards `propose(mesh)` and checks the contract.
fn run_step(
    tracker: &mut dyn SurfaceTracker,
    propose: &dyn Fn(&LabeledMesh) -> Vec<DVec3>,
    what: &str,
) -> Outcome {
    let before = bits(tracker.mesh());
    let proposed = propose(tracker.mesh());
    let start = Instant::now();
    let result = tracker.advance(&proposed);
    let elapsed = start.elapsed();
    assert!(
        elapsed < BOUND,
        "{what}/{}: step took {elapsed:?}",
        tracker.name()
    );
    match result {
        Ok(_) => {
            let v = validate(tracker.mesh(), &ValidateOptions::default());
            assert!(
                v.is_valid(),
                "{what}/{}: Ok but invalid: {v}",
                tracker.name()
            );
            Outcome::Stepped
        }
        Err(e) => {
            assert_eq!(
                bits(tracker.mesh()),
                before,
                "{what}/{}: {e} changed the mesh",
                tracker.name()
            );
            println!("{what}/{}: step failed: {e}", tracker.name());
            Outcome::Failed
        }
    }
}

/// Both backends through the facade on `mesh`, one step each.
fn every_backend(
    mesh: &LabeledMesh,
    options: &TrackerOptions,
    propose: &dyn Fn(&LabeledMesh) -> Vec<DVec3>,
    what: &str,
) -> Vec<(Backend, Outcome)> {
    Backend::ALL
        .iter()
        .map(|&b| {
            let start = Instant::now();
            let made = make_tracker_with(b, mesh.clone(), options);
            assert!(
                start.elapsed() < BOUND,
                "{what}/{b}: construction took too long"
            );
            let outcome = match made {
                Ok(mut t) => run_step(t.as_mut(), propose, what),
                Err(BackendError::InvalidInput { error, .. }) => {
                    println!("{what}/{b}: refused: {error}");
                    Outcome::Refused
                }
                Err(e) => panic!("{what}/{b}: {e}"),
            };
            (b, outcome)
        })
        .collect()
}

/// `fix` on `mesh`: a valid mesh or a typed error, in bounded time.
fn check_fix(mesh: &LabeledMesh, cell: Option<f64>, what: &str) -> bool {
    let start = Instant::now();
    let result = fix(mesh, cell);
    assert!(
        start.elapsed() < BOUND,
        "{what}/fix took {:?}",
        start.elapsed()
    );
    match result {
        Ok(out) => {
            let v = validate(&out, &ValidateOptions::with_intersections());
            assert!(v.is_valid(), "{what}/fix: Ok but invalid: {v}");
            true
        }
        Err(e) => {
            println!("{what}/fix: {e}");
            false
        }
    }
}

fn identity(mesh: &LabeledMesh) -> Vec<DVec3> {
    mesh.positions().to_vec()
}

/// Concatenates meshes (labels kept).
fn union(parts: &[LabeledMesh]) -> LabeledMesh {
    let (mut p, mut t, mut l) = (Vec::new(), Vec::new(), Vec::new());
    for m in parts {
        let (pm, tm, lm) = m.to_raw();
        let base = p.len() as u32;
        p.extend(pm);
        t.extend(tm.iter().map(|f| f.map(|i| i + base)));
        l.extend(lm);
    }
    LabeledMesh::from_raw(p, &t, &l).unwrap()
}

/// An axis-aligned box `[lo, hi]` as 12 outward triangles, labels `[0, inside]`.
fn cube(lo: DVec3, hi: DVec3, inside: u32) -> LabeledMesh {
    let c = |i: usize| {
        DVec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    };
    let p: Vec<DVec3> = (0..8).map(c).collect();
    let f: [[u32; 3]; 12] = [
        [0, 2, 1],
        [1, 2, 3],
        [4, 5, 6],
        [5, 7, 6],
        [0, 1, 4],
        [1, 5, 4],
        [2, 6, 3],
        [3, 6, 7],
        [0, 4, 2],
        [2, 4, 6],
        [1, 3, 5],
        [3, 7, 5],
    ];
    LabeledMesh::from_raw(p, &f, &[[0, inside]; 12]).unwrap()
}

fn sphere(centre: DVec3, radius: f64, label: u32) -> LabeledMesh {
    icosphere(2, centre, radius, [Label::OUTSIDE, Label::new(label)]).unwrap()
}

#[test]
fn the_cube_fixture_is_a_valid_closed_box() {
    let c = cube(DVec3::ZERO, DVec3::ONE, 1);
    assert!(validate(&c, &ValidateOptions::with_intersections()).is_valid());
    let v = surftrack::mesh_core::geometry::label_volumes(&c);
    assert!(
        v.iter()
            .any(|(l, vol)| l.raw() == 1 && (vol - 1.0).abs() < 1e-12),
        "{v:?}"
    );
}

#[test]
fn vertices_exactly_on_grid_planes_and_lines() {
    // Unit cubes on integer coordinates, a grid of ℓ = 0.25 with no random shift: every
    // vertex is a grid node, every edge lies on a grid line, every face on a plane.
    let mesh = union(&[
        cube(DVec3::ZERO, DVec3::ONE, 1),
        cube(DVec3::new(2.0, 0.0, 0.0), DVec3::new(3.0, 1.0, 1.0), 2),
    ]);
    for shift in [0.0, 0.25, 1.0] {
        let params = GridParams {
            cell_size: Some(0.25),
            perturbation: 0.0,
            ..GridParams::default()
        };
        let mut t = GridTracker::new(mesh.clone(), params).unwrap();
        // Move the first cube by whole cells: it lands on planes again (and, by 1.0,
        // exactly face to face with the second cube).
        let propose = move |m: &LabeledMesh| -> Vec<DVec3> {
            m.positions()
                .iter()
                .map(|&p| if p.x < 1.5 { p + DVec3::X * shift } else { p })
                .collect()
        };
        let o = run_step(&mut t, &propose, &format!("grid planes, shift {shift}"));
        if shift < 1.0 {
            assert_eq!(
                o,
                Outcome::Stepped,
                "no contact at shift {shift}: must succeed"
            );
        }
    }
    let options = TrackerOptions {
        length_scale: Some(0.25),
        ..TrackerOptions::default()
    };
    every_backend(&mesh, &options, &identity, "grid planes (facade)");
    // Two cubes overlapping by exactly half a cell, faces on planes.
    let overlapping = union(&[
        cube(DVec3::ZERO, DVec3::ONE, 1),
        cube(
            DVec3::new(0.875, 0.25, 0.25),
            DVec3::new(1.875, 0.75, 0.75),
            2,
        ),
    ]);
    check_fix(&overlapping, Some(0.25), "grid planes overlap");
}

#[test]
fn coplanar_overlapping_triangles() {
    // A box standing on another: the contact faces are coplanar and overlap partly.
    let mesh = union(&[
        cube(DVec3::ZERO, DVec3::ONE, 1),
        cube(DVec3::new(0.3, 0.2, 1.0), DVec3::new(1.4, 0.7, 1.8), 2),
    ]);
    let outcomes = every_backend(&mesh, &TrackerOptions::default(), &identity, "coplanar");
    // The exact intersection test sees the touching faces: the collision backend (which
    // requires an intersection-free input) must refuse, not track an invalid state.
    assert_eq!(outcomes[1], (Backend::Collision, Outcome::Refused));
    assert!(
        check_fix(&mesh, Some(0.2), "coplanar"),
        "fix must repair a coplanar contact"
    );
}

#[test]
fn coincident_duplicate_surfaces_of_different_labels() {
    // The same sphere twice, inside labels 1 and 2: every triangle has a coincident twin.
    let a = sphere(DVec3::ZERO, 1.0, 1);
    let b = sphere(DVec3::ZERO, 1.0, 2);
    let mesh = union(&[a.clone(), b]);
    let outcomes = every_backend(&mesh, &TrackerOptions::default(), &identity, "coincident");
    assert_eq!(outcomes[1], (Backend::Collision, Outcome::Refused));
    check_fix(&mesh, None, "coincident");
    // The same with a cube, whose coincident faces lie on grid planes.
    let cubes = union(&[
        cube(DVec3::ZERO, DVec3::ONE, 1),
        cube(DVec3::ZERO, DVec3::ONE, 2),
    ]);
    check_fix(&cubes, Some(0.25), "coincident cubes");
    every_backend(
        &cubes,
        &TrackerOptions::default(),
        &identity,
        "coincident cubes",
    );
}

#[test]
fn needle_and_cap_triangles() {
    // A needle: a tetrahedron 1e-7 thin; a cap: a sphere with one vertex pushed almost
    // into the plane of its neighbours.
    let needle = LabeledMesh::from_raw(
        vec![
            DVec3::ZERO,
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.5, 1e-7, 0.0),
            DVec3::new(0.5, 0.0, 1e-7),
        ],
        &[[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
        &[[0, 1]; 4],
    )
    .unwrap();
    let outward = |m: &LabeledMesh| -> Vec<DVec3> {
        let c = m.positions().iter().copied().sum::<DVec3>() / m.num_vertices() as f64;
        m.positions().iter().map(|&p| c + (p - c) * 1.01).collect()
    };
    every_backend(&needle, &TrackerOptions::default(), &outward, "needle");
    check_fix(&needle, None, "needle");

    let mut cap = sphere(DVec3::ZERO, 1.0, 1);
    let v = surftrack::mesh_core::VertexId::new(0);
    let ring: Vec<DVec3> = cap
        .vertex_triangles(v)
        .flat_map(|t| cap.tri(t))
        .filter(|&w| w != v)
        .map(|w| cap.position(w))
        .collect();
    let centre = ring.iter().copied().sum::<DVec3>() / ring.len() as f64;
    cap.set_position(v, centre + (cap.position(v) - centre) * 1e-6);
    every_backend(&cap, &TrackerOptions::default(), &outward, "cap");
    check_fix(&cap, None, "cap");
}

/// `n` octahedral cells of labels `1..=n`, all overlapping near the origin.
fn many_materials(n: usize) -> LabeledMesh {
    let cells: Vec<LabeledMesh> = (0..n)
        .map(|i| {
            let a = i as f64 * 2.399_963; // golden angle: spread the centres evenly
            let r = 0.05 * ((i as f64 + 0.5) / n as f64).sqrt();
            let centre = DVec3::new(r * a.cos(), r * a.sin(), 0.02 * (i % 5) as f64);
            icosphere(0, centre, 0.2, [Label::OUTSIDE, Label::new(i as u32 + 1)]).unwrap()
        })
        .collect();
    union(&cells)
}

#[test]
fn two_hundred_materials_in_a_small_region() {
    let mesh = many_materials(200);
    let start = Instant::now();
    check_fix(&mesh, Some(0.05), "200 materials");
    println!("200 overlapping materials: fix in {:?}", start.elapsed());
    // A valid 200-material foam: both backends take a step (grid) or refuse/fail typed.
    let foam = voronoi_foam(200, 3, DVec3::ZERO, DVec3::splat(0.1)).unwrap();
    let squeeze = |m: &LabeledMesh| -> Vec<DVec3> {
        m.positions()
            .iter()
            .map(|&p| p + DVec3::new(0.0, 0.0, 0.002 * (p.x * 60.0).sin()))
            .collect()
    };
    let start = Instant::now();
    let outcomes = every_backend(&foam, &TrackerOptions::default(), &squeeze, "foam 200");
    println!("foam of 200 cells: {outcomes:?} in {:?}", start.elapsed());
}

#[test]
#[ignore = "release-mode scale test: 1000 materials"]
fn a_thousand_materials_in_a_small_region() {
    use surftrack::grid_tracker::{FixError, FixOptions, PipelineError, fix_with};
    // ℓ = 0.05 as for 200 materials. Measured (release, 2 shared cores): an unbounded
    // `fix` takes 47 s and 2.7 GB here. At ℓ = 0.02 it passed 20 GB of resident memory
    // within 5 minutes (killed) in the sub-ℓ pass's cell collection
    // (`grid_tracker::safety::pair_cells` gathers the overlap-box cells of every
    // intersecting pair, duplicates included, before sorting them): reported, not run.
    // With a time budget the call returns a typed error instead, within the budget plus
    // one stage.
    let mesh = many_materials(1000);
    let mut options = FixOptions::default();
    options.params.cell_size = Some(0.05);
    options.params.time_budget = Some(Duration::from_secs(10));
    options.validate_intersections = false;
    let start = Instant::now();
    match fix_with(&mesh, &options) {
        Ok(out) => {
            assert!(out.report.validation.is_valid());
            println!(
                "1000 materials: repaired, {} triangles",
                out.mesh.num_triangles()
            )
        }
        Err(FixError::Pipeline(PipelineError::TimeBudget { stage, .. })) => {
            println!("1000 materials: time budget exceeded after `{stage}`")
        }
        Err(e) => panic!("1000 materials: {e}"),
    }
    let elapsed = start.elapsed();
    println!("1000 materials: fix with a 10 s budget returned in {elapsed:?}");
    assert!(elapsed < Duration::from_secs(60), "{elapsed:?}");
    let foam = voronoi_foam(1000, 3, DVec3::ZERO, DVec3::splat(0.1)).unwrap();
    let start = Instant::now();
    let outcomes = every_backend(&foam, &TrackerOptions::default(), &identity, "foam 1000");
    println!("foam of 1000 cells: {outcomes:?} in {:?}", start.elapsed());
}

#[test]
fn meshes_scaled_to_micro_and_mega() {
    for scale in [1e-6, 1e6] {
        let mesh = union(&[
            sphere(DVec3::ZERO, 0.5 * scale, 1),
            sphere(DVec3::X * 1.2 * scale, 0.5 * scale, 2),
        ]);
        let approach = move |m: &LabeledMesh| -> Vec<DVec3> {
            m.positions()
                .iter()
                .map(|&p| {
                    if p.x < 0.6 * scale {
                        p + DVec3::X * 0.05 * scale
                    } else {
                        p
                    }
                })
                .collect()
        };
        let what = format!("scale {scale:e}");
        let outcomes = every_backend(&mesh, &TrackerOptions::default(), &approach, &what);
        // A uniformly scaled scene is an ordinary scene: both backends must step.
        for (b, o) in outcomes {
            assert_eq!(o, Outcome::Stepped, "{what}/{b}");
        }
        // And overlapping at that scale, for fix.
        let overlap = union(&[
            sphere(DVec3::ZERO, 0.5 * scale, 1),
            sphere(DVec3::X * 0.6 * scale, 0.5 * scale, 2),
        ]);
        assert!(check_fix(&overlap, None, &what), "{what}: fix must succeed");
    }
}
