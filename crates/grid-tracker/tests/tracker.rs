//! The grid tracker through the `SurfaceTracker` trait (issue 4, "Done when"): normal
//! flow merges two bubbles into a double bubble, reversed flow separates them and makes
//! them vanish, every frame valid with no exact self-intersection; a failed step leaves
//! the mesh unchanged; attributes follow the mesh.

mod common;

use common::sphere;
use glam::DVec3;
use grid_tracker::{GridParams, GridTracker};
use mesh_core::validate::{ValidateOptions, validate};
use mesh_core::{Label, LabeledMesh, SurfaceTracker, TrackError};

/// Outward normal flow of the bubbles: each vertex moves along the sum of the area
/// normals of its triangles that face the outside (label 0), oriented towards it.
/// Interior walls (no outside label) do not push their vertices; on the triple curve the
/// two outer films do.
fn outward_normals(mesh: &LabeledMesh) -> Vec<DVec3> {
    let mut n = vec![DVec3::ZERO; mesh.vertex_capacity()];
    for t in mesh.triangles() {
        let [front, back] = mesh.labels(t);
        let p = mesh.tri_positions(t);
        let area_normal = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]);
        let dir = if front == Label::OUTSIDE {
            area_normal
        } else if back == Label::OUTSIDE {
            -area_normal
        } else {
            continue;
        };
        for v in mesh.tri(t) {
            n[v.idx()] += dir;
        }
    }
    n.iter().map(|d| d.normalize_or_zero()).collect()
}

fn normal_flow(mesh: &LabeledMesh, speed: f64) -> Vec<DVec3> {
    let normals = outward_normals(mesh);
    mesh.positions()
        .iter()
        .zip(&normals)
        .map(|(p, n)| *p + speed * *n)
        .collect()
}

fn interface_triangles(mesh: &LabeledMesh) -> usize {
    mesh.triangles()
        .filter(|&t| !mesh.labels(t).contains(&Label::OUTSIDE))
        .count()
}

fn assert_clean(mesh: &LabeledMesh, frame: usize) {
    let report = validate(mesh, &ValidateOptions::with_intersections());
    assert!(report.is_valid(), "frame {frame}: {report}");
}

fn two_bubbles() -> LabeledMesh {
    common::union(&[
        sphere(2, DVec3::new(-0.62, 0.0, 0.0), 0.5, 0, 1),
        sphere(2, DVec3::new(0.62, 0.01, -0.01), 0.5, 0, 2),
    ])
}

#[test]
fn normal_flow_merges_then_reversed_flow_separates_and_vanishes() {
    let mesh = two_bubbles();
    let mut tracker = GridTracker::new(mesh, GridParams::default()).expect("tracker");
    assert_eq!(tracker.name(), "grid");
    let ell = tracker.cell_size();
    let speed = 0.6 * ell;
    let mut merged_at = None;
    let (mut merges, mut splits) = (0, 0);
    for frame in 0..6 {
        let proposal = normal_flow(tracker.mesh(), speed);
        let report = tracker.advance(&proposal).expect("outward step");
        merges += report.events.merges;
        assert_eq!(report.substeps, 1);
        assert_clean(tracker.mesh(), frame);
        if merged_at.is_none() && interface_triangles(tracker.mesh()) > 0 {
            merged_at = Some(frame);
        }
    }
    let merged_at = merged_at.expect("the bubbles never formed a shared wall");
    assert!(interface_triangles(tracker.mesh()) > 5);
    assert!(merged_at <= 3, "merged late, at frame {merged_at}");
    assert_eq!(merges, 1, "contact of the two bubbles is one merge event");

    let mut separated = false;
    let mut vanished = None;
    for frame in 6..60 {
        let proposal = normal_flow(tracker.mesh(), -speed);
        let report = tracker.advance(&proposal).expect("inward step");
        splits += report.events.splits;
        assert_clean(tracker.mesh(), frame);
        let m = tracker.mesh();
        if interface_triangles(m) == 0 && m.num_triangles() > 0 {
            separated = true;
        }
        if m.num_triangles() == 0 {
            vanished = Some(frame);
            break;
        }
    }
    assert!(separated, "the bubbles never separated");
    assert!(splits >= 1, "the separation was not counted as a split");
    assert!(vanished.is_some(), "the bubbles never vanished");
    // An empty mesh stays a valid state to step from.
    tracker.advance(&[]).expect("empty step");
}

#[test]
fn a_large_displacement_is_a_union() {
    let mesh = two_bubbles();
    let mut tracker = GridTracker::new(mesh, GridParams::default()).expect("tracker");
    // Teleport the right bubble halfway into the left one in a single step.
    let proposal: Vec<DVec3> = tracker
        .mesh()
        .positions()
        .iter()
        .map(|p| {
            if p.x > 0.0 {
                *p - DVec3::new(0.6, 0.0, 0.0)
            } else {
                *p
            }
        })
        .collect();
    let report = tracker.advance(&proposal).expect("teleport");
    assert_clean(tracker.mesh(), 0);
    assert!(interface_triangles(tracker.mesh()) > 0);
    let names: Vec<&str> = report.stages.iter().map(|s| s.stage).collect();
    for stage in [
        "grid",
        "materials",
        "flaws",
        "cut",
        "labels",
        "rebuild",
        "improve",
    ] {
        assert!(names.contains(&stage), "no timing for {stage}: {names:?}");
    }
    let pass = tracker.last_pass().expect("pass stats");
    assert!(pass.flawed_cells > 0 && pass.new_triangles > 0, "{pass:?}");
}

#[test]
fn a_failed_step_leaves_the_mesh_unchanged() {
    let mesh = two_bubbles();
    let mut tracker = GridTracker::new(mesh, GridParams::default()).expect("tracker");
    let before = tracker.mesh().to_raw();
    let n = tracker.mesh().vertex_capacity();
    let short = vec![DVec3::ZERO; n - 1];
    assert!(matches!(
        tracker.advance(&short),
        Err(TrackError::ProposalLength { .. })
    ));
    let mut nan = tracker.mesh().positions().to_vec();
    nan[3].y = f64::NAN;
    assert!(matches!(
        tracker.advance(&nan),
        Err(TrackError::NonFiniteProposal { .. })
    ));
    // A stage failure: one vertex thrown 10¹² away needs a grid far beyond any bound.
    let mut far = tracker.mesh().positions().to_vec();
    far[5] = DVec3::new(1e12, 0.0, 0.0);
    match tracker.advance(&far) {
        Err(TrackError::StageFailed { stage, .. }) => assert_eq!(stage, "grid"),
        other => panic!("expected a grid failure, got {other:?}"),
    }
    assert_eq!(tracker.mesh().to_raw(), before);
    assert_eq!(tracker.steps(), 0);
}

#[test]
fn invalid_input_is_rejected() {
    let m = sphere(1, DVec3::ZERO, 1.0, 0, 1);
    let (p, mut t, mut l) = m.to_raw();
    t.pop();
    l.pop();
    let open = LabeledMesh::from_raw(p, &t, &l).expect("open mesh");
    let err = GridTracker::new(open, GridParams::default()).expect_err("open mesh");
    assert!(matches!(err, TrackError::InvalidInput(_)), "{err}");
    let bad = GridParams {
        cell_size: Some(f64::NAN),
        ..GridParams::default()
    };
    assert!(GridTracker::new(m, bad).is_err());
}

#[test]
fn attributes_follow_the_mesh() {
    let mut tracker = GridTracker::new(two_bubbles(), GridParams::default()).expect("tracker");
    let mut attrs = mesh_core::remesh::VertexAttributes::zeros(tracker.mesh(), 1);
    for v in tracker.mesh().vertices() {
        attrs.get_mut(v)[0] = tracker.mesh().position(v).x + 10.0;
    }
    tracker.set_attributes(attrs);
    let ell = tracker.cell_size();
    for frame in 0..4 {
        let proposal = normal_flow(tracker.mesh(), 0.5 * ell);
        tracker.advance(&proposal).expect("step");
        assert_clean(tracker.mesh(), frame);
    }
    // The attribute is 10 + the x coordinate at the start; vertices moved by at most 2ℓ
    // and rebuilt ones take values from their neighbourhood (PIC), so it stays close to
    // 10 + x (a vertex left at zero would be 10 off).
    let m = tracker.mesh();
    assert_eq!(tracker.attributes().dim(), 1);
    for v in m.vertices() {
        let a = tracker.attributes().get(v)[0] - 10.0;
        assert!(a.is_finite());
        assert!(
            (a - m.position(v).x).abs() < 4.0 * ell,
            "vertex {v}: {a} vs {}",
            m.position(v).x
        );
    }
}
