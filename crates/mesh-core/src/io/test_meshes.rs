//! Small meshes for the I/O tests.

use glam::DVec3;

use crate::LabeledMesh;
use crate::ids::{TriId, VertexId};

/// Two tetrahedra sharing the face `abc` (labels 1 above, 2 below, outside 0): every edge
/// of `abc` is non-manifold. Coordinates are not short decimals (1/3, 1/7, 0.1), an
/// isolated vertex holds extreme values (1e300, the smallest subnormal, −0.0), and a
/// deleted vertex and triangle leave holes in the id space, so writers must renumber.
pub(crate) fn two_tets() -> LabeledMesh {
    let positions = vec![
        DVec3::new(0.0, 0.0, 0.0),              // a
        DVec3::new(1.0, 0.0, 0.0),              // b
        DVec3::new(0.0, 1.0, 0.0),              // c
        DVec3::new(0.1, 0.2, 0.7),              // d, above
        DVec3::new(1.0 / 3.0, 1.0 / 7.0, -0.9), // e, below
        DVec3::new(9.0, 9.0, 9.0),              // junk, deleted below
        DVec3::new(1e300, -5e-324, -0.0),       // isolated
    ];
    let (a, b, c, d, e) = (0, 1, 2, 3, 4);
    let tris = [
        [a, b, c], // shared: normal +z points into tet 1
        [a, b, d],
        [b, c, d],
        [a, b, 5], // junk, deleted below
        [c, a, d],
        [a, e, b],
        [b, e, c],
        [c, e, a],
    ];
    let labels = [
        [1, 2],
        [0, 1],
        [0, 1],
        [3, 4],
        [0, 1],
        [0, 2],
        [0, 2],
        [0, 2],
    ];
    let mut mesh = LabeledMesh::from_raw(positions, &tris, &labels).unwrap();
    mesh.remove_triangle(TriId::new(3)).unwrap();
    mesh.remove_vertex(VertexId::new(5)).unwrap();
    mesh
}

/// Asserts that two meshes have identical live arrays, positions bit for bit.
pub(crate) fn assert_same_raw(expected: &LabeledMesh, got: &LabeledMesh) {
    let (p1, t1, l1) = expected.to_raw();
    let (p2, t2, l2) = got.to_raw();
    let bits = |p: &[DVec3]| {
        p.iter()
            .map(|v| v.to_array().map(f64::to_bits))
            .collect::<Vec<_>>()
    };
    assert_eq!(bits(&p1), bits(&p2), "positions differ");
    assert_eq!(t1, t2, "triangles differ");
    assert_eq!(l1, l2, "labels differ");
}

#[test]
fn two_tets_is_what_it_claims() {
    let mesh = two_tets();
    assert_eq!(mesh.num_vertices(), 6);
    assert_eq!(mesh.num_triangles(), 7);
    let volumes = crate::geometry::label_volumes(&mesh);
    let tet = |p: [DVec3; 4]| (p[1] - p[0]).dot((p[2] - p[0]).cross(p[3] - p[0])).abs() / 6.0;
    let raw = mesh.to_raw().0;
    let v1 = tet([raw[0], raw[1], raw[2], raw[3]]);
    let v2 = tet([raw[0], raw[1], raw[2], raw[4]]);
    approx::assert_relative_eq!(volumes[&crate::Label::new(1)], v1, max_relative = 1e-12);
    approx::assert_relative_eq!(volumes[&crate::Label::new(2)], v2, max_relative = 1e-12);
}
