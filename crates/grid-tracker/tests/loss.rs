//! Issue 16: `fix` and the grid tracker never lose a material silently.
//!
//! Coarse meshes of the kind CAD tools write (a cube of 12 triangles, boxes, a thin plate,
//! a long thin cylinder), through `fix` with no cell size: clean ones come back
//! byte-identical; overlapping ones keep every label with the volumes of the exact
//! union's split, computed here from the boxes (by symmetry each pairwise overlap is
//! shared half and half). A loss is an error, or with the opt-in a warning with numbers.

mod common;

use common::{cube, inverted, sphere, union};
use glam::DVec3;
use grid_tracker::{
    CellSizeRule, FixError, FixOptions, FixOutcome, GridParams, GridTracker, ReferenceMethod,
    fix_with,
};
use mesh_core::geometry::label_volumes;
use mesh_core::validate::{ValidateOptions, validate};
use mesh_core::{Label, LabeledMesh, SurfaceTracker};

fn fix_default(m: &LabeledMesh) -> FixOutcome {
    fix_with(m, &FixOptions::default()).unwrap_or_else(|e| panic!("fix: {e}"))
}

fn assert_untouched(m: &LabeledMesh, what: &str) {
    let out = fix_default(m);
    assert!(out.report.clean_input, "{what}: {:?}", out.report);
    assert_eq!(out.mesh.to_raw(), m.to_raw(), "{what}: changed");
    assert_eq!(out.report.untouched_fraction, 1.0);
    assert_eq!(out.report.volume_check.method, ReferenceMethod::CleanInput);
    assert!(out.report.vanished.is_empty());
    // Also at a cell size far larger than the whole mesh.
    let mut options = FixOptions::default();
    options.params.cell_size = Some(10.0);
    let out = fix_with(m, &options).expect("fix at ℓ = 10");
    assert_eq!(out.mesh.to_raw(), m.to_raw(), "{what}: changed at ℓ = 10");
}

/// A closed cylinder along x, radius `r`, from 0 to `len`, `n` sides, 4n triangles.
fn cylinder(r: f64, len: f64, n: u32, label: u32) -> LabeledMesh {
    let mut p = Vec::new();
    for end in [0.0, len] {
        for k in 0..n {
            let a = std::f64::consts::TAU * f64::from(k) / f64::from(n);
            p.push(DVec3::new(end, r * a.cos(), r * a.sin()));
        }
    }
    p.push(DVec3::ZERO);
    p.push(DVec3::new(len, 0.0, 0.0));
    let (c0, c1) = (2 * n, 2 * n + 1);
    let mut t = Vec::new();
    for k in 0..n {
        let k1 = (k + 1) % n;
        // Sides (outward normals), then the two caps.
        t.push([k, k1, n + k1]);
        t.push([k, n + k1, n + k]);
        t.push([c0, k1, k]);
        t.push([c1, n + k, n + k1]);
    }
    let labels = vec![[0, label]; t.len()];
    LabeledMesh::from_raw(p, &t, &labels).expect("cylinder")
}

#[test]
fn coarse_clean_inputs_come_back_byte_identical() {
    let c = cube(DVec3::ZERO, DVec3::ONE, 0, 1);
    assert_eq!(c.num_triangles(), 12);
    assert_untouched(&c, "12-triangle cube");
    let plate = cube(DVec3::ZERO, DVec3::new(1.0, 1.0, 0.02), 0, 1);
    assert_untouched(&plate, "thin plate");
    let rod = cylinder(0.02, 3.0, 8, 1);
    assert!(validate(&rod, &ValidateOptions::with_intersections()).is_valid());
    assert_untouched(&rod, "long thin cylinder");
    let pair = union(&[
        sphere(3, DVec3::ZERO, 1.0, 0, 1),
        sphere(1, DVec3::new(1.1, 0.0, 0.0), 0.05, 0, 2),
    ]);
    assert_untouched(&pair, "small sphere next to a large one");
}

#[test]
fn the_default_cell_size_follows_the_thinnest_material() {
    let plate = cube(DVec3::ZERO, DVec3::new(1.0, 1.0, 0.02), 0, 1);
    let r = fix_default(&plate).report;
    assert_eq!(r.cell_size_choice.rule, CellSizeRule::ThinnestMaterial);
    // 3V/A of the plate ≈ 1.5 × 0.02 (the rim adds a little area), over 8.
    assert!(
        r.cell_size < 0.005 && r.cell_size > 0.003,
        "{:?}",
        r.cell_size_choice
    );
    assert!(r.cell_size_choice.reason.contains("thinnest material"));
}

/// Fixes `m` with no cell size and checks every label's volume against `expected`
/// (within 1 %) and the total against the union.
fn check_split(m: &LabeledMesh, expected: &[(u32, f64)], what: &str) {
    let out = fix_default(m);
    let r = &out.report;
    assert!(!r.clean_input);
    assert!(r.validation.is_valid(), "{what}: {}", r.validation);
    assert!(r.vanished.is_empty(), "{what}: {:?}", r.vanished);
    let vol = label_volumes(&out.mesh);
    let union: f64 = expected.iter().map(|e| e.1).sum();
    for &(l, v) in expected {
        let got = vol.get(&Label::new(l)).copied().unwrap_or(0.0);
        assert!(
            (got - v).abs() < 0.01 * v,
            "{what}: label {l} has {got}, expected {v} (ℓ = {})",
            r.cell_size
        );
        let rec = r
            .volumes
            .iter()
            .find(|x| x.label.raw() == l)
            .expect("label");
        assert_eq!(rec.after, got);
    }
    let c = &r.volume_check;
    assert!((c.reference - union).abs() < 0.005 * union, "{what}: {c:?}");
    assert!(c.relative_change < 0.01, "{what}: {c:?}");
}

#[test]
fn two_overlapping_coarse_boxes_keep_both_labels_and_split_the_overlap() {
    // A = [0,1]³, B = A + (s,s,s): the overlap [s,1]³ is symmetric under the point
    // reflection swapping A and B, so each keeps 1 − (1−s)³/2.
    let s: f64 = 0.4;
    let a = cube(DVec3::ZERO, DVec3::ONE, 0, 1);
    let b = cube(DVec3::splat(s), DVec3::splat(1.0 + s), 0, 2);
    let half = 1.0 - (1.0 - s).powi(3) / 2.0;
    check_split(&union(&[a, b]), &[(1, half), (2, half)], "two boxes");
}

#[test]
fn three_overlapping_coarse_boxes_keep_every_label() {
    // A, B, C along the diagonal, 0.55 apart: A∩B and B∩C are cubes of side 0.45, A∩C is
    // empty; each overlap is shared half and half.
    let s: f64 = 0.55;
    let o = (1.0 - s).powi(3);
    let boxes: Vec<LabeledMesh> = (0..3)
        .map(|i| {
            let lo = DVec3::splat(s * f64::from(i));
            cube(lo, lo + DVec3::ONE, 0, i + 1)
        })
        .collect();
    check_split(
        &union(&boxes),
        &[(1, 1.0 - o / 2.0), (2, 1.0 - o), (3, 1.0 - o / 2.0)],
        "three boxes",
    );
}

/// Two overlapping boxes and a small box of label 3 poking into one of them: at ℓ = 0.5
/// no grid node is inside label 3 (its y and z ranges hold no multiple of 0.5 even with
/// the grid's random shift of up to 0.1 ℓ), so the rebuild cannot keep it.
fn forced_loss_scene() -> LabeledMesh {
    union(&[
        cube(DVec3::ZERO, DVec3::ONE, 0, 1),
        cube(DVec3::splat(0.4), DVec3::splat(1.4), 0, 2),
        cube(
            DVec3::new(-0.12, 0.13, 0.17),
            DVec3::new(0.08, 0.29, 0.33),
            0,
            3,
        ),
    ])
}

#[test]
fn a_material_far_below_the_cell_size_is_an_error_naming_it() {
    let m = forced_loss_scene();
    let mut options = FixOptions::default();
    options.params.cell_size = Some(0.5);
    match fix_with(&m, &options) {
        Err(FixError::Loss(loss)) => {
            assert_eq!(loss.vanished.len(), 1, "{loss}");
            assert_eq!(loss.vanished[0].label, Label::new(3));
            let v3 = 0.2 * 0.16 * 0.16;
            assert!((loss.vanished[0].before - v3).abs() < 1e-9, "{loss}");
            let msg = FixError::Loss(loss).to_string();
            assert!(msg.contains("material 3 vanished"), "{msg}");
            assert!(msg.contains("0.005120"), "{msg}");
        }
        other => panic!(
            "expected a loss error, got {:?}",
            other.map(|o| o.report.vanished)
        ),
    }
    // Opted in: the mesh, with the loss as a warning carrying the numbers.
    options.allow_loss = true;
    let out = fix_with(&m, &options).expect("allowed loss");
    let r = &out.report;
    assert_eq!(r.vanished, vec![Label::new(3)]);
    assert_eq!(r.warnings.len(), 1);
    assert!(
        r.warnings[0].contains("material 3 vanished (volume 0.005120"),
        "{r:?}"
    );
    let v3 = r
        .volumes
        .iter()
        .find(|v| v.label == Label::new(3))
        .expect("3");
    assert_eq!(v3.after, 0.0);
    assert!(r.validation.is_valid());
    // At a cell size that puts grid nodes inside label 3, nothing is lost.
    options.allow_loss = false;
    options.params.cell_size = Some(0.04);
    let out = fix_with(&m, &options).expect("no loss at ℓ = 0.04");
    assert!(out.report.vanished.is_empty(), "{:?}", out.report);
}

#[test]
fn a_total_volume_change_beyond_the_tolerance_is_an_error() {
    let a = cube(DVec3::ZERO, DVec3::ONE, 0, 1);
    let b = cube(DVec3::splat(0.4), DVec3::splat(1.4), 0, 2);
    let m = union(&[a, b]);
    let mut options = FixOptions {
        volume_tolerance: 0.0,
        ..FixOptions::default()
    };
    options.params.cell_size = Some(0.3);
    match fix_with(&m, &options) {
        Err(FixError::Loss(loss)) => {
            assert!(loss.vanished.is_empty());
            assert!(loss.to_string().contains("total volume"), "{loss}");
        }
        other => panic!("expected a loss error, got {:?}", other.map(|o| o.report)),
    }
}

#[test]
fn the_grid_tracker_keeps_a_clean_cube_coarser_than_the_cells() {
    // ℓ = 1.5 > the cube: before the deep-test change every cell around it was deep and
    // the first step deleted it.
    let c = cube(DVec3::ZERO, DVec3::ONE, 0, 1);
    for seed in 0..4 {
        let params = GridParams {
            cell_size: Some(1.5),
            seed,
            ..GridParams::default()
        };
        let mut tracker = GridTracker::new(c.clone(), params).expect("tracker");
        let proposed: Vec<DVec3> = c
            .vertices()
            .map(|v| c.position(v) + DVec3::new(0.01, 0.0, 0.0))
            .collect();
        let report = tracker.advance(&proposed).expect("step");
        assert!(report.events.vanished.is_empty(), "seed {seed}");
        let v = report.volumes.iter().find(|v| v.label == Label::new(1));
        let v = v.expect("label 1 reported");
        assert!(
            (v.before - 1.0).abs() < 1e-12 && (v.after - 1.0).abs() < 1e-3,
            "{v:?}"
        );
        assert_eq!(tracker.mesh().num_triangles(), 12, "seed {seed}");
    }
}

#[test]
fn a_material_vanishing_in_a_step_is_reported() {
    // A small sphere turned inside out inside a big one: non-physical, rebuilt as
    // material 1, so material 2 vanishes.
    let m = union(&[
        sphere(3, DVec3::ZERO, 1.0, 0, 1),
        sphere(1, DVec3::ZERO, 0.2, 1, 2),
    ]);
    let params = GridParams {
        cell_size: Some(0.1),
        ..GridParams::default()
    };
    let mut tracker = GridTracker::new(m.clone(), params).expect("tracker");
    let proposed: Vec<DVec3> = m
        .vertices()
        .map(|v| {
            let p = m.position(v);
            if p.length() < 0.5 { -0.5 * p } else { p }
        })
        .collect();
    let report = tracker.advance(&proposed).expect("step");
    assert_eq!(report.events.vanished, vec![Label::new(2)], "{report:?}");
    let v2 = report
        .volumes
        .iter()
        .find(|v| v.label == Label::new(2))
        .expect("2");
    assert!(v2.before > 0.02 && v2.after == 0.0, "{v2:?}");
}

/// A closed shell enclosing no volume (four coplanar points: overlapping faces, so the
/// input needs repair) is still a material of the input: a repair that drops it is a
/// loss naming it, though its volume was 0 before and after. And a repair left with no
/// triangles at all says so.
#[test]
fn a_material_with_no_volume_that_vanishes_is_an_error_too() {
    let flat = |dx: f64| {
        let p = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(0.3, 0.3, 0.0),
        ]
        .map(|q| q + DVec3::new(dx, 0.0, 0.0))
        .to_vec();
        let t = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        LabeledMesh::from_raw(p, &t, &[[0, 1]; 4]).expect("flat shell")
    };
    let m = union(&[flat(3.0), cube(DVec3::ZERO, DVec3::ONE, 0, 2)]);
    assert!(label_volumes(&m)[&Label::new(1)].abs() < 1e-12);
    let options = FixOptions::default();
    match fix_with(&m, &options) {
        Err(FixError::Loss(loss)) => {
            let labels: Vec<Label> = loss.vanished.iter().map(|v| v.label).collect();
            assert_eq!(labels, vec![Label::new(1)], "{loss}");
            assert!(loss.to_string().contains("material 1 vanished"), "{loss}");
        }
        other => panic!(
            "expected a loss error, got {:?}",
            other.map(|o| o.report.vanished)
        ),
    }
    match fix_with(&flat(0.0), &options) {
        Err(FixError::Loss(loss)) => {
            assert!(
                loss.vanished.iter().any(|v| v.label == Label::OUTSIDE),
                "{loss}"
            );
            assert!(loss.to_string().contains("no triangles left"), "{loss}");
        }
        other => panic!(
            "expected a loss error, got {:?}",
            other.map(|o| o.report.vanished)
        ),
    }
    // Opted in: the cube comes back, the loss as a warning.
    let out = fix_with(
        &m,
        &FixOptions {
            allow_loss: true,
            ..FixOptions::default()
        },
    )
    .expect("allowed loss");
    assert_eq!(out.report.vanished, vec![Label::new(1)]);
    assert!(out.report.validation.is_valid());
}

/// Overlapping cubes whose faces carry front and back the other way round (each label
/// outside its own faces): an error that says so, not an empty mesh or a loss blamed on
/// the cell size. The same cubes the right way round are repaired.
#[test]
fn swapped_front_and_back_labels_are_named_in_the_error() {
    let right = union(&[
        cube(DVec3::ZERO, DVec3::ONE, 0, 1),
        cube(DVec3::new(0.5, 0.3, 0.2), DVec3::new(1.5, 1.3, 1.2), 0, 2),
    ]);
    let swapped = inverted(&right);
    assert!(label_volumes(&swapped)[&Label::new(1)] < 0.0);
    match fix_with(&swapped, &FixOptions::default()) {
        Err(FixError::InvalidInput(msg)) => {
            assert!(
                msg.contains("material 1 encloses a negative volume"),
                "{msg}"
            );
            assert!(msg.contains("swapped"), "{msg}");
        }
        other => panic!(
            "expected an input error, got {:?}",
            other.map(|o| o.report.vanished)
        ),
    }
    let out = fix_default(&right);
    assert!(out.report.vanished.is_empty());
}

/// The volume of each label of `m`.
fn volume_of(m: &LabeledMesh, label: u32) -> f64 {
    label_volumes(m)
        .get(&Label::new(label))
        .copied()
        .unwrap_or(0.0)
}

/// A part drawn inside another and labelled against the outside 0, as separately
/// exported parts of an assembly arrive: `validate` now says where, the grid tracker
/// refuses it instead of resolving the inner part away as an overlap, and `fix` relabels
/// its outside with the material around it, keeping both materials and every triangle.
#[test]
fn a_nested_part_keeps_its_material() {
    let outer = sphere(2, DVec3::ZERO, 1.0, 0, 1);
    let inner = sphere(2, DVec3::new(0.1, -0.05, 0.0), 0.4, 0, 2);
    let (v_outer, v_inner) = (volume_of(&outer, 1), volume_of(&inner, 2));
    let nested = union(&[outer, inner]);

    let report = validate(&nested, &ValidateOptions::default());
    assert_eq!(
        report.misplaced_shells.as_ref().map(|m| m.count),
        Some(1),
        "{report}"
    );
    match GridTracker::new(nested.clone(), GridParams::default()) {
        Err(e) => assert!(e.to_string().contains("misplaced"), "{e}"),
        Ok(_) => panic!("the grid tracker took a misplaced part"),
    }

    let out = fix_default(&nested);
    assert_eq!(out.report.relabelled.len(), 1);
    let r = &out.report.relabelled[0];
    assert_eq!((r.from, r.to), (Label::new(0), Label::new(1)));
    assert!(!out.report.clean_input);
    assert!(out.report.vanished.is_empty());
    let check = validate(&out.mesh, &ValidateOptions::with_intersections());
    assert!(check.is_valid(), "{check}");
    assert_eq!(out.mesh.num_triangles(), nested.num_triangles());
    assert!((volume_of(&out.mesh, 2) - v_inner).abs() < 1e-12);
    assert!((volume_of(&out.mesh, 1) - (v_outer - v_inner)).abs() < 1e-12);
}

/// Next to an overlap (two crossing boxes, which the repair resolves into an interface),
/// a nested part that touches nothing is still relabelled, and the overlapping boxes are
/// not: each keeps its material.
#[test]
fn a_nested_part_beside_an_overlap_is_relabelled_and_the_overlap_repaired() {
    let a = cube(DVec3::ZERO, DVec3::new(2.0, 1.0, 1.0), 0, 1);
    let b = cube(
        DVec3::new(1.5, 0.25, 0.25),
        DVec3::new(2.5, 0.75, 0.75),
        0,
        2,
    );
    let part = sphere(1, DVec3::new(0.5, 0.5, 0.5), 0.2, 0, 3);
    let v_part = volume_of(&part, 3);
    let mesh = union(&[a, b, part]);
    let out = fix_default(&mesh);
    assert_eq!(
        out.report.relabelled.len(),
        1,
        "{:?}",
        out.report.relabelled
    );
    assert_eq!(out.report.relabelled[0].to, Label::new(1));
    assert!(
        out.report.flawed_cells > 0,
        "the overlap went through the repair"
    );
    let check = validate(&out.mesh, &ValidateOptions::with_intersections());
    assert!(check.is_valid(), "{check}");
    for label in 1..=3 {
        assert!(volume_of(&out.mesh, label) > 0.0, "material {label} kept");
    }
    assert!((volume_of(&out.mesh, 3) - v_part).abs() < 1e-3 * v_part);
}
