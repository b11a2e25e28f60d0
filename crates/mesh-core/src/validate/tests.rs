//! Each invariant broken by hand on a small mesh, and the clean cases that must pass.

use glam::DVec3;
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::testmesh::{build, concat, icosphere, tetra};
use super::*;
use crate::ids::{Label, TriId, VertexId};

fn t(i: u32) -> TriId {
    TriId::new(i)
}
fn v(i: u32) -> VertexId {
    VertexId::new(i)
}
fn full() -> ValidateOptions {
    ValidateOptions::with_intersections()
}

/// Tetrahedron A = (O, X, Y, Z) with label 1 and tetrahedron B = (X, Y, Z, W), W = (1,1,1),
/// with label 2, sharing face XYZ (vertices 1, 2, 3; W is vertex 4).
fn double_tetra() -> LabeledMesh {
    let p = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z, DVec3::ONE];
    let tris = [
        [0, 2, 1],
        [0, 1, 3],
        [0, 3, 2],
        [1, 2, 3],
        [1, 2, 4],
        [2, 3, 4],
        [3, 1, 4],
    ];
    let labels = [[0, 1], [0, 1], [0, 1], [2, 1], [0, 2], [0, 2], [0, 2]];
    LabeledMesh::from_raw(p, &tris, &labels).unwrap()
}

#[test]
fn closed_tetrahedron_is_valid() {
    let mesh = build(tetra(DVec3::ZERO, 1));
    let r = validate(&mesh, &full());
    assert!(r.is_valid(), "{r}");
    assert_eq!(
        (r.vertices, r.triangles, r.edges, r.non_manifold_edges),
        (4, 4, 6, 0)
    );
    assert_eq!(r.self_intersecting_pairs.as_ref().map(|p| p.count), Some(0));
    assert!(r.to_string().starts_with("mesh valid"));
    let r = validate(&mesh, &ValidateOptions::default());
    assert!(r.is_valid() && r.self_intersecting_pairs.is_none());
    assert!(r.to_string().contains("not checked"));
}

#[test]
fn removed_triangle_leaves_boundary_edges() {
    let mut mesh = build(tetra(DVec3::ZERO, 1));
    mesh.remove_triangle(t(3)).unwrap(); // [1, 2, 3]
    let r = validate(&mesh, &full());
    assert!(!r.is_valid());
    let edges: Vec<[VertexId; 2]> = r.boundary_edges.items.iter().map(|e| e.edge).collect();
    assert_eq!(edges, vec![[v(1), v(2)], [v(1), v(3)], [v(2), v(3)]]);
    // Each boundary edge names the remaining triangle along it.
    let tris: Vec<TriId> = r.boundary_edges.items.iter().map(|e| e.tri).collect();
    assert_eq!(tris, vec![t(0), t(1), t(2)]);
    assert_eq!(r.corner_table.count, 0, "{r}");
    assert_eq!(r.inconsistent_edges.count, 0);
    assert!(
        r.to_string().contains("3 boundary edges: v1–v2 (t0)"),
        "{r}"
    );
}

#[test]
fn swapped_labels_make_its_edges_inconsistent() {
    let mut mesh = build(tetra(DVec3::ZERO, 1));
    mesh.set_labels(t(3), [Label::new(1), Label::new(0)]);
    let r = validate(&mesh, &ValidateOptions::default());
    assert_eq!(r.inconsistent_edges.count, 3, "{r}");
    for e in &r.inconsistent_edges.items {
        assert!(e.tris.contains(&t(3)) && e.wedge.contains(&t(3)));
        assert_ne!(e.labels[0], e.labels[1]);
        assert_eq!(e.tris.len(), 2);
    }
    let edges: Vec<_> = r.inconsistent_edges.items.iter().map(|e| e.edge).collect();
    assert_eq!(edges, vec![[v(1), v(2)], [v(1), v(3)], [v(2), v(3)]]);
    assert_eq!(r.same_label_triangles.count, 0);
    // Flipping the orientation *and* the labels (what flip_orientation does) is consistent.
    let mut mesh = build(tetra(DVec3::ZERO, 1));
    mesh.flip_orientation(t(3)).unwrap();
    assert!(validate(&mesh, &full()).is_valid());
}

#[test]
fn same_label_on_both_sides_is_reported() {
    let mut mesh = build(tetra(DVec3::ZERO, 1));
    mesh.set_labels(t(2), [Label::new(1), Label::new(1)]);
    let r = validate(&mesh, &ValidateOptions::default());
    assert_eq!(
        r.same_label_triangles.items,
        vec![SameLabel {
            tri: t(2),
            label: Label::new(1)
        }]
    );
    assert!(!r.is_valid());
}

#[test]
fn repeated_vertex_is_degenerate_not_zero_area() {
    let (p, mut tris, mut labels) = tetra(DVec3::ZERO, 1);
    tris.push([0, 0, 1]);
    labels.push([0, 1]);
    let mesh = build((p, tris, labels));
    let r = validate(&mesh, &full());
    assert_eq!(r.degenerate.items, vec![t(4)]);
    assert_eq!(r.zero_area.count, 0);
    assert_eq!(r.corner_table.count, 0, "{r}");
    assert!(!r.is_valid());
}

/// A "book": `pages` triangles on the spine v0–v1, page `i` ending at vertex `2 + i % 7`
/// (so pages repeat every 7), with every page's id listed against the lowest id of its
/// vertex set. Above the pairwise degree the sort path must list exactly the pairs, in
/// the order, that comparing every pair lists.
#[test]
fn duplicates_on_one_edge_of_high_degree_are_each_paired_with_the_lowest() {
    for pages in [5u32, 40, 2000] {
        let mut p = vec![DVec3::ZERO, DVec3::X];
        for k in 0..7 {
            let a = std::f64::consts::TAU * k as f64 / 7.0;
            p.push(DVec3::new(0.5, a.cos(), a.sin()));
        }
        let tris: Vec<[u32; 3]> = (0..pages).map(|i| [0, 1, 2 + i % 7]).collect();
        let labels = vec![[0, 1]; tris.len()];
        let mesh = build((p, tris, labels));
        let r = validate(&mesh, &ValidateOptions::default());
        let expected: Vec<[TriId; 2]> = (7..pages).map(|i| [t(i % 7), t(i)]).collect();
        assert_eq!(r.duplicates.count, expected.len(), "{pages} pages");
        let listed = r.duplicates.items.len();
        assert_eq!(r.duplicates.items, expected[..listed], "{pages} pages");
    }
}

#[test]
fn duplicate_triangles_in_any_orientation() {
    let (p, mut tris, mut labels) = tetra(DVec3::ZERO, 1);
    tris.push([1, 0, 2]); // same set as t0 = [0, 2, 1], rotated
    labels.push([0, 1]);
    tris.push([3, 2, 1]); // same set as t3 = [1, 2, 3], reversed
    labels.push([1, 0]);
    let mesh = build((p, tris, labels));
    let r = validate(&mesh, &full());
    assert_eq!(r.duplicates.items, vec![[t(0), t(4)], [t(3), t(5)]]);
    // Duplicates are not double-reported as intersecting pairs.
    let pairs = r.self_intersecting_pairs.unwrap();
    assert!(!pairs.items.contains(&[t(0), t(4)]) && !pairs.items.contains(&[t(3), t(5)]));
}

#[test]
fn non_finite_positions_are_reported_without_panicking() {
    let (mut p, tris, labels) = tetra(DVec3::ZERO, 1);
    p[3] = DVec3::new(0.0, f64::NAN, 1.0);
    p[2] = DVec3::new(f64::INFINITY, 1.0, 0.0);
    let mesh = build((p, tris, labels));
    let r = validate(&mesh, &full());
    assert_eq!(r.non_finite.items, vec![v(2), v(3)]);
    assert_eq!(r.zero_area.count, 0);
    assert!(!r.is_valid());
}

#[test]
fn coordinates_outside_the_predicates_range_are_named_not_taken_for_other_defects() {
    // Near 1e300 the products overflow: before the range check this tetrahedron was
    // "valid" with NaN volumes, and the trackers refused it for an infinite cell size.
    let (mut p, tris, labels) = tetra(DVec3::ZERO, 1);
    p[1] = DVec3::new(1e300, 0.0, 0.0);
    p[2] = DVec3::new(0.0, 2e30, 0.0);
    let r = validate(&build((p, tris.clone(), labels.clone())), &full());
    assert_eq!(r.out_of_range.items, vec![v(1), v(2)]);
    assert!(r.non_finite.is_empty() && r.zero_area.is_empty());
    assert_eq!(r.self_intersecting_pairs.as_ref().map(|l| l.count), Some(0));
    assert!(!r.is_valid());
    assert!(r.to_string().contains("2 vertices out of range"), "{r}");

    // Near 1e-300 they underflow: the same tetrahedron scaled down had four "zero-area"
    // triangles. The whole mesh is too small, so every vertex is named.
    let (p, tris, labels) = tetra(DVec3::ZERO, 1);
    let tiny: Vec<DVec3> = p.iter().map(|&q| q * 1e-300).collect();
    let r = validate(&build((tiny, tris.clone(), labels.clone())), &full());
    assert_eq!(r.out_of_range.items, vec![v(0), v(1), v(2), v(3)]);
    assert!(r.zero_area.is_empty());
    assert!(!r.is_valid());

    // At the bounds, and with float32 export noise near zero in a mesh of unit size: valid.
    for scale in [
        crate::predicates::MAX_COORDINATE,
        1.5 * crate::predicates::MIN_EXTENT,
    ] {
        let q: Vec<DVec3> = p.iter().map(|&x| x * scale).collect();
        let r = validate(&build((q, tris.clone(), labels.clone())), &full());
        assert!(r.is_valid(), "scale {scale:e}: {r}");
    }
    let mut q = p.clone();
    q[0] = DVec3::new(1e-45, -1e-45, 0.0);
    assert!(validate(&build((q, tris, labels)), &full()).is_valid());
}

#[test]
fn exactly_collinear_triangle_is_zero_area() {
    let (mut p, mut tris, mut labels) = tetra(DVec3::ZERO, 1);
    p.push(DVec3::new(0.5, 0.0, 0.0)); // v4 on edge v0–v1
    p.push(DVec3::new(0.5, 0.0, 1e-300)); // v5 off it by a hair
    tris.extend([[0, 4, 1], [0, 5, 1]]);
    labels.extend([[0, 1], [0, 1]]);
    let mesh = build((p, tris, labels));
    let r = validate(&mesh, &ValidateOptions::default());
    assert_eq!(r.zero_area.items, vec![t(4)]);
    assert_eq!(r.degenerate.count, 0);
}

#[test]
fn interpenetrating_tetrahedra_intersect() {
    let mesh = build(concat(&[
        tetra(DVec3::ZERO, 1),
        tetra(DVec3::splat(0.2), 2),
    ]));
    // Each tetrahedron alone is fine: only layer 4 sees the problem.
    assert!(validate(&mesh, &ValidateOptions::default()).is_valid());
    let r = validate(&mesh, &full());
    let pairs = r.self_intersecting_pairs.clone().unwrap();
    assert!(pairs.count > 0 && !r.is_valid());
    for [a, b] in &pairs.items {
        assert!(
            a.raw() < 4 && b.raw() >= 4,
            "pair {a} {b} is within one tetrahedron"
        );
    }
    // The big slanted face of A (t3) is crossed by B.
    assert!(pairs.items.iter().any(|p| p[0] == t(3)));
    assert!(r.to_string().contains("self-intersecting triangle pairs"));
    // Far apart: no pairs.
    let apart = build(concat(&[
        tetra(DVec3::ZERO, 1),
        tetra(DVec3::splat(3.0), 2),
    ]));
    assert!(validate(&apart, &full()).is_valid());
}

#[test]
fn tetrahedra_sharing_a_face_are_valid_and_non_manifold() {
    let mesh = double_tetra();
    let r = validate(&mesh, &full());
    assert!(r.is_valid(), "{r}");
    assert_eq!((r.edges, r.non_manifold_edges), (9, 3));
    let vols = crate::geometry::label_volumes(&mesh);
    assert!((vols[&Label::new(1)] - 1.0 / 6.0).abs() < 1e-12);
    assert!((vols[&Label::new(2)] - 1.0 / 3.0).abs() < 1e-12);
    assert!((vols[&Label::new(0)] + 0.5).abs() < 1e-12);
    // The shared face with its labels the wrong way round breaks all three junctions.
    let mut bad = double_tetra();
    bad.set_labels(t(3), [Label::new(1), Label::new(2)]);
    let r = validate(&bad, &ValidateOptions::default());
    assert_eq!(r.inconsistent_edges.count, 3, "{r}");
    assert!(r.inconsistent_edges.items.iter().all(|e| e.tris.len() == 3));
}

#[test]
fn moving_a_vertex_across_a_junction_breaks_the_stored_pairing() {
    let mut mesh = double_tetra();
    // W into tetrahedron A: around edge X–Y the radial order of O, Z and W changes, but the
    // stored pairing still reflects the old order.
    mesh.set_position(v(4), DVec3::new(0.2, 0.2, 0.1));
    let r = validate(&mesh, &ValidateOptions::default());
    assert!(
        r.corner_table
            .items
            .iter()
            .any(|e| matches!(e, CornerTableError::PairingMismatch { .. })),
        "{r}"
    );
    // Relinking the edges brings the table in line with the geometry again.
    for (a, b) in [(1, 2), (2, 3), (3, 1)] {
        mesh.relink_edge(v(a), v(b));
    }
    assert_eq!(
        check_topology(&mesh, &ValidateOptions::default())
            .corner_table
            .count,
        0
    );
}

#[test]
fn folded_coplanar_neighbours_are_reported() {
    // Two triangles sharing edge v0–v1, in the plane z = 0.
    let fold = |apex: DVec3| {
        let p = vec![DVec3::ZERO, DVec3::X, DVec3::Y, apex];
        let mesh = LabeledMesh::from_raw(p, &[[0, 1, 2], [1, 0, 3]], &[[0, 1], [0, 1]]).unwrap();
        validate(&mesh, &full()).self_intersecting_pairs.unwrap()
    };
    assert_eq!(fold(DVec3::new(0.3, 0.3, 0.0)).items, vec![[t(0), t(1)]]);
    assert_eq!(fold(DVec3::new(0.3, -0.5, 0.0)).count, 0); // unfolded, coplanar
    assert_eq!(fold(DVec3::new(0.3, 0.3, 1e-300)).count, 0); // folded but not coplanar
    // Sharing only v0, coplanar and overlapping.
    let p = vec![
        DVec3::ZERO,
        DVec3::X,
        DVec3::Y,
        DVec3::new(1.0, 0.5, 0.0),
        DVec3::new(0.5, 1.0, 0.0),
    ];
    let mesh = LabeledMesh::from_raw(p, &[[0, 1, 2], [0, 3, 4]], &[[0, 1], [0, 1]]).unwrap();
    let pairs = validate(&mesh, &full()).self_intersecting_pairs.unwrap();
    assert_eq!(pairs.items, vec![[t(0), t(1)]]);
}

#[test]
fn corner_table_stays_intact_through_edits() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let opts = ValidateOptions::default();
    for raw in [icosphere(DVec3::ZERO, 1.0, 1, 1), double_tetra().to_raw()] {
        let mut mesh = build(raw);
        assert!(validate(&mesh, &full()).is_valid());
        let mut removed = Vec::new();
        for _ in 0..40 {
            let live: Vec<TriId> = mesh.triangles().collect();
            if !live.is_empty() && (removed.is_empty() || rng.random_bool(0.5)) {
                let t = live[rng.random_range(0..live.len())];
                removed.push((mesh.tri(t), mesh.labels(t)));
                mesh.remove_triangle(t).unwrap();
            } else {
                removed.shuffle(&mut rng);
                if let Some((verts, labels)) = removed.pop() {
                    mesh.add_triangle(verts, labels).unwrap();
                }
            }
            let r = check_topology(&mesh, &opts);
            assert_eq!(r.corner_table.count, 0, "{r}");
            if removed.is_empty() {
                assert_eq!(r.boundary_edges.count, 0, "{r}");
            }
        }
        while let Some((verts, labels)) = removed.pop() {
            mesh.add_triangle(verts, labels).unwrap();
        }
        let r = validate(&mesh, &full());
        assert!(r.is_valid(), "{r}");
        mesh.compact();
        assert!(validate(&mesh, &full()).is_valid());
    }
}

#[test]
fn lists_are_capped_counts_exact_and_sorted() {
    let mut mesh = build(icosphere(DVec3::ZERO, 1.0, 2, 1));
    let n = mesh.num_triangles() as u32;
    for i in (0..n).step_by(3) {
        mesh.set_labels(t(i), [Label::new(2), Label::new(2)]);
    }
    let opts = ValidateOptions {
        intersections: false,
        max_listed: 5,
        ..ValidateOptions::default()
    };
    let r = validate(&mesh, &opts);
    assert_eq!(r.same_label_triangles.count, n.div_ceil(3) as usize);
    let listed: Vec<TriId> = r.same_label_triangles.items.iter().map(|s| s.tri).collect();
    assert_eq!(listed, vec![t(0), t(3), t(6), t(9), t(12)]);
    assert!(r.inconsistent_edges.count > 5 && r.inconsistent_edges.items.len() == 5);
    assert!(r.to_string().contains("…"));
}

#[test]
fn clean_sphere_passes_and_a_dented_one_fails() {
    let raw = icosphere(DVec3::new(0.3, -0.2, 0.1), 2.0, 3, 1);
    let mesh = build(raw.clone());
    let r = validate(&mesh, &full());
    assert!(r.is_valid(), "{r}");
    assert_eq!((r.triangles, r.edges), (1280, 1920));
    // Push one vertex through the far side of the sphere.
    let (mut p, tris, labels) = raw;
    p[0] = DVec3::new(0.3, -0.2, 0.1) - (p[0] - DVec3::new(0.3, -0.2, 0.1)) * 1.5;
    let r = validate(&build((p, tris, labels)), &full());
    assert!(r.self_intersecting_pairs.unwrap().count > 0);
}

/// The yes/no form of layer 4 agrees with the full count: no on a clean sphere, yes on a
/// dented one and on two overlapping spheres, for any thread count; and it skips what
/// layers 1–3 reject (a dead triangle, a repeated vertex) instead of panicking.
#[test]
fn any_intersection_answers_as_the_count_does() {
    let c = DVec3::new(0.3, -0.2, 0.1);
    let raw = icosphere(c, 2.0, 3, 1);
    let dented = {
        let (mut p, tris, labels) = raw.clone();
        p[0] = c - (p[0] - c) * 1.5;
        build((p, tris, labels))
    };
    let overlapping = build(concat(&[
        icosphere(DVec3::ZERO, 1.0, 2, 1),
        icosphere(DVec3::new(0.9, 0.3, 0.1), 0.8, 2, 2),
    ]));
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        pool.install(|| {
            assert!(!intersections::any_intersection(&build(raw.clone())));
            assert!(intersections::any_intersection(&dented));
            assert!(intersections::any_intersection(&overlapping));
        });
    }
    let mut broken = dented.clone();
    let [a, b, _] = broken.tri(t(0));
    broken.remove_triangle(t(1)).expect("a live triangle");
    let degenerate = broken.add_triangle([a, a, b], [Label::new(0), Label::new(1)]);
    assert!(degenerate.is_ok(), "{degenerate:?}");
    assert!(intersections::any_intersection(&broken));
}

#[test]
fn broad_phase_misses_no_intersecting_pair() {
    // Two overlapping spheres: compare with the all-pairs narrow phase.
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let (mut p, tris, labels) = concat(&[
        icosphere(DVec3::ZERO, 1.0, 2, 1),
        icosphere(DVec3::new(0.9, 0.3, 0.1), 0.8, 2, 2),
    ]);
    for q in &mut p {
        *q += DVec3::new(rng.random(), rng.random(), rng.random()) * 0.02;
    }
    let mesh = build((p, tris, labels));
    let opts = ValidateOptions {
        intersections: true,
        max_listed: usize::MAX,
        ..ValidateOptions::default()
    };
    let got = validate(&mesh, &opts).self_intersecting_pairs.unwrap();
    let mut want = Vec::new();
    let n = mesh.num_triangles() as u32;
    for a in 0..n {
        for b in a + 1..n {
            let shared = mesh
                .tri(t(a))
                .iter()
                .filter(|x| mesh.tri(t(b)).contains(x))
                .count();
            if shared < 3 && intersections::triangles_intersect(&mesh, t(a), t(b)) {
                want.push([t(a), t(b)]);
            }
        }
    }
    assert!(want.len() > 10);
    assert_eq!(got.count, want.len());
    assert_eq!(got.items, want);
}

#[test]
fn report_serializes() {
    fn is_serialize<T: serde::Serialize>(_: &T) {}
    is_serialize(&validate(&double_tetra(), &full()));
}

#[test]
fn empty_mesh_is_valid() {
    let r = validate(&LabeledMesh::new(), &full());
    assert!(r.is_valid());
    assert_eq!(r.edges, 0);
}

#[cfg(debug_assertions)]
#[test]
#[should_panic(expected = "mesh invalid after stage after cut")]
fn debug_validate_panics_on_invalid_mesh() {
    let mut mesh = build(tetra(DVec3::ZERO, 1));
    crate::debug_validate!(mesh, "after loading");
    mesh.remove_triangle(t(0)).unwrap();
    crate::debug_validate!(&mesh, "after cut");
}

/// Process CPU time (user + system, all threads) in seconds, from `/proc/self/stat`
/// (0 where unavailable): a throughput figure that a loaded machine does not distort as
/// much as wall time.
fn process_cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let fields: Vec<&str> = stat
        .rsplit(')')
        .next()
        .unwrap_or("")
        .split_whitespace()
        .collect();
    let ticks = |i: usize| {
        fields
            .get(i)
            .and_then(|x| x.parse::<f64>().ok())
            .unwrap_or(0.0)
    };
    (ticks(11) + ticks(12)) / 100.0
}

/// Throughput on a ~1.3M-triangle icosphere. Run with
/// `cargo test --release -p mesh-core validate::tests::throughput -- --ignored --nocapture`.
#[test]
#[ignore]
fn throughput_million_triangle_sphere() {
    let t0 = std::time::Instant::now();
    let labels = [Label::new(0), Label::new(1)];
    let mesh = match crate::generators::icosphere(8, DVec3::ZERO, 1.0, labels) {
        Ok(m) => m,
        Err(e) => panic!("{e}"),
    };
    let n = mesh.num_triangles() as f64;
    eprintln!(
        "built {} triangles in {:.2?}",
        mesh.num_triangles(),
        t0.elapsed()
    );
    for opts in [ValidateOptions::default(), full()] {
        for _ in 0..3 {
            let (t0, c0) = (std::time::Instant::now(), process_cpu_seconds());
            let r = validate(&mesh, &opts);
            let (dt, cpu) = (t0.elapsed(), process_cpu_seconds() - c0);
            assert!(r.is_valid(), "{r}");
            eprintln!(
                "validate (intersections: {}): wall {:.3?} = {:.2} M triangles/s; cpu {:.2} s = {:.2} M triangles per cpu-second",
                opts.intersections,
                dt,
                n / dt.as_secs_f64() / 1e6,
                cpu,
                n / cpu / 1e6
            );
        }
    }
}
