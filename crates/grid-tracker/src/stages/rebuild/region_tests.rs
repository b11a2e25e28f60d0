//! Tests of the rebuild stage (§8.2–§8.3) through the real pipeline: grid, materials,
//! flaws, labels, and either a region holding everything (no boundary: the whole surface
//! is rebuilt from the labels) or the cut stage's output.

use std::collections::BTreeSet;

use glam::DVec3;
use mesh_core::geometry::label_volumes;
use mesh_core::validate::{ValidateOptions, validate};
use mesh_core::{Label, LabeledMesh, VertexId};

use super::*;
use crate::stages::cut::{CutOptions, cut_mesh};
use crate::stages::flaws::{FlawOptions, FlawedRegion, detect_flaws};
use crate::stages::grid::{Grid, GridOptions, build_grid};
use crate::stages::labels::{NodeLabels, correct_labels};
use crate::stages::materials::{MaterialOptions, Materials, assign_materials};
use crate::test_util::{sphere, union};

struct Run {
    grid: Grid,
    mats: Materials,
    region: FlawedRegion,
    labels: NodeLabels,
}

/// The pipeline up to §8.1; with `everything`, the region is grown to a box of cells one
/// layer beyond the band, so the cut removes the whole mesh.
fn run(mesh: &LabeledMesh, ell: f64, everything: bool) -> Run {
    let crate::stages::labels::tests::Run { grid, mats, region } =
        crate::stages::labels::tests::run(mesh, ell, everything);
    let labels = correct_labels(mesh, &grid, &mats, &region).unwrap();
    Run {
        grid,
        mats,
        region,
        labels,
    }
}

/// Rebuilds everything into an empty mesh (the cut of a region holding the whole mesh).
fn rebuild_all(r: &Run, options: &RebuildOptions) -> (LabeledMesh, RebuildReport) {
    let mut out = LabeledMesh::new();
    let report = rebuild_region(
        &mut out,
        std::iter::empty(),
        &[],
        &r.grid,
        &r.mats,
        &r.region,
        &r.labels,
        options,
    )
    .unwrap();
    (out, report)
}

fn assert_valid(mesh: &LabeledMesh, what: &str) -> mesh_core::validate::ValidationReport {
    let report = validate(mesh, &ValidateOptions::with_intersections());
    assert!(report.is_valid(), "{what}: {report:#?}");
    assert_eq!(
        report.self_intersecting_pairs.as_ref().map(|l| l.count),
        Some(0),
        "{what}"
    );
    report
}

fn labels_of(mesh: &LabeledMesh) -> BTreeSet<u32> {
    mesh.label_set().iter().map(|l| l.raw()).collect()
}

/// Bounded region shells per label.
fn bounded_shells(mesh: &LabeledMesh, label: u32) -> usize {
    mesh.regions()
        .bounded()
        .filter(|s| s.label == Label::new(label))
        .count()
}

#[test]
fn a_whole_sphere_is_rebuilt_from_its_labels() {
    let c = DVec3::new(0.03, -0.02, 0.01);
    let mesh = sphere(3, c, 1.0, 0, 1);
    let r = run(&mesh, 0.25, true);
    let (out, report) = rebuild_all(&r, &RebuildOptions::default());
    assert_valid(&out, "rebuilt sphere");
    assert_eq!(labels_of(&out), BTreeSet::from([0, 1]));
    assert_eq!(bounded_shells(&out, 1), 1);
    let s = report.stats;
    assert_eq!(s.fan_triangles, 0);
    assert_eq!(s.octant_triangles, out.num_triangles());
    assert_eq!(report.new_vertices.len(), out.num_vertices());
    assert_eq!(report.new_triangles.len(), out.num_triangles());
    // Edge vertices sit on the mesh's own crossings (both ends physical), so the volume
    // is close to the input's, not to the blocky dual-cell volume.
    let (want, got) = (
        label_volumes(&mesh)[&Label::new(1)],
        label_volumes(&out)[&Label::new(1)],
    );
    assert!(
        (got - want).abs() < 0.03 * want,
        "volume {got}, input {want}"
    );
}

#[test]
fn edge_vertices_lie_on_their_grid_edges_at_the_crossings() {
    let c = DVec3::new(0.03, -0.02, 0.01);
    let mesh = sphere(3, c, 1.0, 0, 1);
    let r = run(&mesh, 0.25, true);
    let options = RebuildOptions {
        curve_smoothing_steps: 0,
        ..RebuildOptions::default()
    };
    let (out, _) = rebuild_all(&r, &options);
    let lattice = r.grid.lattice();
    let on_plane = |p: DVec3, a: usize| lattice.plane(a, lattice.locate(a, p[a])) == p[a];
    let mut edge_vertices = 0;
    for v in out.vertices() {
        let p = out.position(v);
        let fixed: Vec<usize> = (0..3).filter(|&a| on_plane(p, a)).collect();
        // Edge vertices have two coordinates on grid planes, face vertices one, centres
        // none; the free coordinates stay `margin·ℓ` inside.
        assert!(fixed.len() <= 2, "vertex {v} at {p} sits on a node");
        for a in (0..3).filter(|a| !fixed.contains(a)) {
            let i = lattice.locate(a, p[a]);
            let (lo, hi) = (lattice.plane(a, i), lattice.plane(a, i + 1));
            let m = 0.999 * options.margin * lattice.cell_size;
            assert!(p[a] >= lo + m && p[a] <= hi - m, "vertex {v} at {p}");
        }
        if fixed.len() == 2 {
            edge_vertices += 1;
            // On the icosphere: between its inscribed radius and 1.
            let d = p.distance(c);
            assert!(
                (0.97..=1.0 + 1e-9).contains(&d),
                "edge vertex {v} at distance {d}"
            );
        }
    }
    assert!(edge_vertices > 100);
}

#[test]
fn overlapping_same_label_spheres_become_one_region() {
    let (c0, c1) = (DVec3::new(-0.45, 0.02, 0.01), DVec3::new(0.45, 0.02, 0.01));
    let mesh = union(&[sphere(3, c0, 1.0, 0, 1), sphere(3, c1, 1.0, 0, 1)]);
    let r = run(&mesh, 0.2, true);
    assert!(r.labels.stats().physical_nodes < r.labels.stats().nodes);
    let (out, _) = rebuild_all(&r, &RebuildOptions::default());
    let report = assert_valid(&out, "union");
    assert_eq!(report.non_manifold_edges, 0);
    assert_eq!(labels_of(&out), BTreeSet::from([0, 1]));
    assert_eq!(bounded_shells(&out, 1), 1, "one merged region");
    // The union of two unit balls at distance d = 0.9: 2·(4π/3) − lens, lens volume
    // π(4 + d)(2 − d)²/12.
    let d = c0.distance(c1);
    let union_volume = 2.0 * 4.0 * std::f64::consts::PI / 3.0
        - std::f64::consts::PI * (4.0 + d) * (2.0 - d).powi(2) / 12.0;
    let got = label_volumes(&out)[&Label::new(1)];
    assert!(
        (got - union_volume).abs() < 0.04 * union_volume,
        "volume {got}, union {union_volume}"
    );
}

#[test]
fn overlapping_different_labels_get_an_interface_and_a_triple_curve() {
    let (c0, c1) = (DVec3::new(-0.45, 0.02, 0.01), DVec3::new(0.45, 0.02, 0.01));
    let mesh = union(&[sphere(3, c0, 1.0, 0, 1), sphere(3, c1, 1.0, 0, 2)]);
    let r = run(&mesh, 0.2, true);
    let (out, report) = rebuild_all(&r, &RebuildOptions::default());
    let v = assert_valid(&out, "two materials");
    assert!(
        v.non_manifold_edges > 10,
        "{} non-manifold edges",
        v.non_manifold_edges
    );
    assert_eq!(labels_of(&out), BTreeSet::from([0, 1, 2]));
    assert_eq!(bounded_shells(&out, 1), 1);
    assert_eq!(bounded_shells(&out, 2), 1);
    assert!(report.stats.smoothed_vertices > 0);
    // The interface between 1 and 2 is the lens' mid-plane x = 0 (the configuration is
    // symmetric): well inside the rim, its vertices stay within ℓ/3 of it.
    let mut interface = 0;
    for t in out.triangles() {
        let [f, b] = out.labels(t);
        if f.raw() + b.raw() == 3 {
            for p in out.tri_positions(t) {
                if p.y.hypot(p.z) < 0.6 {
                    assert!(p.x.abs() < 0.2 / 3.0, "interface vertex at {p}");
                    interface += 1;
                }
            }
        }
    }
    assert!(interface > 50);
    // Each sphere keeps itself minus half the lens. The grid resolves the triple curve
    // (the lens' rim) only to a cell, which shifts a cell-wide ring between materials
    // depending on where the planes fall (measured 6% here), so the bound per material
    // is loose and the bound on the sum tight.
    let d = c0.distance(c1);
    let ball = 4.0 * std::f64::consts::PI / 3.0;
    let lens = std::f64::consts::PI * (4.0 + d) * (2.0 - d).powi(2) / 12.0;
    let vol = label_volumes(&out);
    let (v1, v2) = (vol[&Label::new(1)], vol[&Label::new(2)]);
    for v in [v1, v2] {
        assert!(
            (v - (ball - 0.5 * lens)).abs() < 0.08 * ball,
            "volumes {v1} and {v2}"
        );
    }
    assert!(
        (v1 + v2 - (2.0 * ball - lens)).abs() < 0.04 * (2.0 * ball - lens),
        "volumes {v1} and {v2}"
    );
}

/// The real thing: only the lens is flawed; the cut leaves the rest of both spheres,
/// the rebuild fills the hole and welds to it. Old vertices never move; curve smoothing
/// moves new ones.
#[test]
fn the_cut_hole_is_filled_and_only_new_vertices_move() {
    let (c0, c1) = (DVec3::new(-0.45, 0.02, 0.01), DVec3::new(0.45, 0.02, 0.01));
    let mesh = union(&[sphere(3, c0, 1.0, 0, 1), sphere(3, c1, 1.0, 0, 2)]);
    let r = run(&mesh, 0.2, false);
    assert!(!r.region.is_empty());
    let cut = cut_mesh(&mesh, &r.grid, &r.mats, &r.region, &CutOptions::default()).unwrap();
    let rebuild = |steps: usize| {
        let mut m = cut.mesh.clone();
        let report = rebuild_region(
            &mut m,
            cut.boundary(),
            &cut.edge_points,
            &r.grid,
            &r.mats,
            &r.region,
            &r.labels,
            &RebuildOptions {
                curve_smoothing_steps: steps,
                ..RebuildOptions::default()
            },
        )
        .unwrap();
        (m, report)
    };
    let (plain, plain_report) = rebuild(0);
    let (smooth, smooth_report) = rebuild(10);
    assert!(smooth_report.stats.fan_triangles > 0);
    assert!(smooth_report.stats.cut_vertices > 0);
    for (m, what) in [(&plain, "unsmoothed"), (&smooth, "smoothed")] {
        let v = assert_valid(m, what);
        assert!(v.non_manifold_edges > 0);
        assert_eq!(labels_of(m), BTreeSet::from([0, 1, 2]));
        assert_eq!(bounded_shells(m, 1), 1);
        assert_eq!(bounded_shells(m, 2), 1);
    }
    // Old vertices keep their positions; some new ones moved.
    for v in cut.mesh.vertices() {
        assert_eq!(
            smooth.position(v),
            cut.mesh.position(v),
            "old vertex {v} moved"
        );
    }
    assert_eq!(plain_report.new_vertices, smooth_report.new_vertices);
    let moved: Vec<VertexId> = smooth_report
        .new_vertices
        .iter()
        .copied()
        .filter(|&v| smooth.position(v) != plain.position(v))
        .collect();
    assert!(!moved.is_empty());
    assert!(moved.len() <= smooth_report.stats.smoothed_vertices);
}

#[test]
fn inconsistent_inputs_are_errors_with_cells() {
    let (c0, c1) = (DVec3::new(-0.45, 0.02, 0.01), DVec3::new(0.45, 0.02, 0.01));
    let mesh = union(&[sphere(2, c0, 1.0, 0, 1), sphere(2, c1, 1.0, 0, 2)]);
    let r = run(&mesh, 0.25, false);
    let cut = cut_mesh(&mesh, &r.grid, &r.mats, &r.region, &CutOptions::default()).unwrap();
    let attempt = |edge_points: &[(crate::GridEdge, VertexId)], options: &RebuildOptions| {
        let mut m = cut.mesh.clone();
        let before = m.num_triangles();
        let res = rebuild_region(
            &mut m,
            cut.boundary(),
            edge_points,
            &r.grid,
            &r.mats,
            &r.region,
            &r.labels,
            options,
        );
        if res.is_err() {
            assert_eq!(
                m.num_triangles(),
                before,
                "an error leaves the mesh unchanged"
            );
        }
        res
    };
    // Dropping a cut vertex on a grid edge breaks the weld at that edge.
    let mut missing = cut.edge_points.clone();
    let (edge, _) = missing.pop().expect("the cut meets grid edges");
    let err = attempt(&missing, &RebuildOptions::default()).unwrap_err();
    assert!(
        matches!(err, RebuildError::BoundaryMismatch { edge: e, .. } if e == edge),
        "{err}"
    );
    assert!(!err.cells().is_empty());
    assert!(err.cells().iter().all(|&c| r.region.is_flawed(c)));
    assert!(edge.cells().iter().any(|c| err.cells().contains(c)));
    // A bad option is refused before anything else.
    let bad = RebuildOptions {
        margin: 0.0,
        ..RebuildOptions::default()
    };
    let err = attempt(&cut.edge_points, &bad).unwrap_err();
    assert!(matches!(err, RebuildError::BadOption { .. }) && err.cells().is_empty());
    // Labels for another region: missing corners, reported where.
    let mut m = cut.mesh.clone();
    let err = rebuild_region(
        &mut m,
        cut.boundary(),
        &cut.edge_points,
        &r.grid,
        &r.mats,
        &r.region,
        &NodeLabels::default(),
        &RebuildOptions::default(),
    )
    .unwrap_err();
    assert!(matches!(err, RebuildError::MissingLabel { .. }), "{err}");
    assert!(!err.cells().is_empty(), "{err}");
}

/// Random scenes of 2–5 overlapping spheres of up to three labels, some inside out, at
/// random ℓ: cut and rebuild give a valid mesh free of intersections (checked exactly).
#[test]
fn random_overlaps_rebuild_valid_and_intersection_free() {
    use rand::{Rng, SeedableRng};
    for seed in 0..12u64 {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let k = rng.random_range(2..6);
        let spheres: Vec<LabeledMesh> = (0..k)
            .map(|i| {
                let c = DVec3::new(
                    rng.random_range(-0.6..0.6),
                    rng.random_range(-0.6..0.6),
                    rng.random_range(-0.6..0.6),
                );
                let s = sphere(3, c, rng.random_range(0.3..0.8), 0, 1 + i % 3);
                if rng.random_bool(0.3) {
                    crate::test_util::inverted(&s)
                } else {
                    s
                }
            })
            .collect();
        let mesh = union(&spheres);
        let ell = rng.random_range(0.05..0.15);
        let grid = build_grid(
            &mesh,
            ell,
            &GridOptions {
                seed,
                ..GridOptions::default()
            },
        )
        .unwrap();
        let mats = assign_materials(&mesh, &grid, &MaterialOptions::default()).unwrap();
        let region = detect_flaws(&mesh, &grid, &mats, &FlawOptions::default()).unwrap();
        let cut = cut_mesh(&mesh, &grid, &mats, &region, &CutOptions::default()).unwrap();
        let labels = correct_labels(&mesh, &grid, &mats, &region).unwrap();
        let mut m = cut.mesh.clone();
        rebuild_region(
            &mut m,
            cut.boundary(),
            &cut.edge_points,
            &grid,
            &mats,
            &region,
            &labels,
            &RebuildOptions::default(),
        )
        .unwrap_or_else(|e| panic!("seed {seed}: {e}"));
        assert_valid(&m, &format!("seed {seed}"));
    }
}
