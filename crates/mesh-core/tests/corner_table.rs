//! The corner table on hand-built meshes: pairing, radial order, edits, compaction, regions.

use glam::DVec3;
use mesh_core::{CornerId, Label, LabeledMesh, Side, TriId, VertexId};

/// A tetrahedron with outward normals: front = 0 (outside), back = `inside`.
fn tetrahedron(inside: u32) -> LabeledMesh {
    let p = vec![
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(0.0, 1.0, 0.0),
        DVec3::new(0.0, 0.0, 1.0),
    ];
    let t = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
    LabeledMesh::from_raw(p, &t, &[[0, inside]; 4]).unwrap()
}

/// Two tetrahedra sharing the face (0,1,2): label 1 above (z > 0), label 2 below.
fn two_tets() -> LabeledMesh {
    let p = vec![
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(0.0, 1.0, 0.0),
        DVec3::new(0.2, 0.2, 1.0),
        DVec3::new(0.2, 0.2, -1.0),
    ];
    // Shared face (0,1,2): normal +z points into label 1, back is label 2.
    let tris = [
        [0, 1, 2],
        // upper tet, outward normals: front 0, back 1
        [0, 1, 3],
        [1, 2, 3],
        [2, 0, 3],
        // lower tet, outward normals: front 0, back 2
        [1, 0, 4],
        [2, 1, 4],
        [0, 2, 4],
    ];
    let labels = [[1, 2], [0, 1], [0, 1], [0, 1], [0, 2], [0, 2], [0, 2]];
    LabeledMesh::from_raw(p, &tris, &labels).unwrap()
}

/// Every corner's opposite is symmetric, faces the same label, and traverses the edge the
/// other way.
fn check_corner_table(mesh: &LabeledMesh) {
    for t in mesh.triangles() {
        for side in [Side::Front, Side::Back] {
            for slot in 0..3 {
                let c = CornerId::of(t, side, slot);
                let o = mesh
                    .opposite(c)
                    .expect("closed mesh: every corner has an opposite");
                assert_eq!(mesh.opposite(o), Some(c), "opposite not symmetric at {c}");
                assert_eq!(
                    mesh.corner_label(o),
                    mesh.corner_label(c),
                    "labels differ across {c}"
                );
                let [a, b] = mesh.corner_edge(c);
                assert_eq!(mesh.corner_edge(o), [b, a], "edge not reversed across {c}");
            }
        }
    }
}

#[test]
fn tetrahedron_pairs_every_side() {
    let mesh = tetrahedron(1);
    check_corner_table(&mesh);
    let regions = mesh.regions();
    assert_eq!(regions.shells.len(), 2);
    let inside = regions
        .shells
        .iter()
        .find(|s| s.label == Label::new(1))
        .unwrap();
    assert!(inside.closed && inside.consistent);
    assert!((inside.volume - 1.0 / 6.0).abs() < 1e-12);
    let outside = regions
        .shells
        .iter()
        .find(|s| s.label == Label::OUTSIDE)
        .unwrap();
    assert!((outside.volume + 1.0 / 6.0).abs() < 1e-12);
}

#[test]
fn non_manifold_edges_pair_by_wedge() {
    let mesh = two_tets();
    check_corner_table(&mesh);
    // Edge {0,1} has three triangles; walking radially visits all three.
    let t0 = TriId::new(0);
    let c = CornerId::of(t0, Side::Front, 2); // opposite edge (0,1)
    assert_eq!(mesh.corner_edge(c), [VertexId::new(0), VertexId::new(1)]);
    let around: Vec<TriId> = mesh.radial_corners(c).map(|c| c.tri()).collect();
    assert_eq!(around.len(), 3, "{around:?}");
    let regions = mesh.regions();
    assert_eq!(regions.shells.len(), 3);
    let mut vols: Vec<(u32, f64)> = regions
        .shells
        .iter()
        .map(|s| (s.label.raw(), s.volume))
        .collect();
    vols.sort_by_key(|v| v.0);
    assert_eq!(vols[1].0, 1);
    assert!((vols[1].1 - 1.0 / 6.0).abs() < 1e-12, "{vols:?}");
    assert!((vols[2].1 - 1.0 / 6.0).abs() < 1e-12, "{vols:?}");
    assert!((vols[0].1 + 2.0 / 6.0).abs() < 1e-12, "{vols:?}");
    assert!(regions.shells.iter().all(|s| s.closed && s.consistent));
}

#[test]
fn remove_then_add_restores_the_table() {
    let mut mesh = two_tets();
    let t = TriId::new(2);
    let (verts, labels) = (mesh.tri(t), mesh.labels(t));
    mesh.remove_triangle(t).unwrap();
    assert_eq!(mesh.num_triangles(), 6);
    let open = mesh.regions();
    assert!(open.shells.iter().any(|s| !s.closed));
    let back = mesh.add_triangle(verts, labels).unwrap();
    assert_eq!(back, t, "free slot reused");
    check_corner_table(&mesh);
    assert!(mesh.remove_triangle(TriId::new(99)).is_err());
}

#[test]
fn compact_renumbers_and_keeps_pairing() {
    let mut mesh = two_tets();
    // Replace the shared face by three triangles through a new centre vertex.
    let centre = mesh.add_vertex(DVec3::new(0.3, 0.3, 0.0)).unwrap();
    let shared = TriId::new(0);
    let [a, b, c] = mesh.tri(shared);
    let labels = mesh.labels(shared);
    mesh.remove_triangle(shared).unwrap();
    for [p, q] in [[a, b], [b, c], [c, a]] {
        mesh.add_triangle([p, q, centre], labels).unwrap();
    }
    check_corner_table(&mesh);
    let before = mesh.regions();
    let map = mesh.compact();
    assert_eq!(mesh.triangle_capacity(), mesh.num_triangles());
    assert_eq!(map.tri_map.iter().flatten().count(), mesh.num_triangles());
    assert_eq!(map.vertex_map.iter().flatten().count(), 6);
    check_corner_table(&mesh);
    let after = mesh.regions();
    let vol = |r: &mesh_core::Regions| {
        let mut v: Vec<f64> = r.shells.iter().map(|s| s.volume).collect();
        v.sort_by(f64::total_cmp);
        v
    };
    for (x, y) in vol(&before).iter().zip(vol(&after).iter()) {
        assert!((x - y).abs() < 1e-12);
    }
}

#[test]
fn vertex_removal_is_refused_while_in_use() {
    let mut mesh = tetrahedron(1);
    assert!(mesh.remove_vertex(VertexId::new(0)).is_err());
    let v = mesh.add_vertex(DVec3::ONE).unwrap();
    mesh.remove_vertex(v).unwrap();
    assert_eq!(mesh.num_vertices(), 4);
}

#[test]
fn from_raw_rejects_bad_indices() {
    let err = LabeledMesh::from_raw(vec![DVec3::ZERO; 3], &[[0, 1, 3]], &[[0, 1]]).unwrap_err();
    assert!(err.to_string().contains("vertex 3"), "{err}");
    assert!(LabeledMesh::from_raw(vec![DVec3::ZERO; 3], &[[0, 1, 2]], &[]).is_err());
    let err =
        LabeledMesh::from_raw(vec![DVec3::ZERO; 3], &[[0, 1, 2]], &[[0, u32::MAX]]).unwrap_err();
    assert!(
        matches!(err, mesh_core::MeshError::LabelOutOfRange { tri: 0, .. }),
        "{err}"
    );
}

#[test]
fn degenerate_and_nan_input_builds_without_panic() {
    let p = vec![DVec3::ZERO, DVec3::X, DVec3::splat(f64::NAN)];
    let mesh = LabeledMesh::from_raw(
        p,
        &[[0, 0, 1], [0, 1, 2], [1, 0, 2], [2, 1, 0]],
        &[[0, 1]; 4],
    )
    .unwrap();
    let _ = mesh.regions();
}
