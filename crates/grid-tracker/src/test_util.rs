//! Test scenes shared by the unit tests: spheres, boxes, unions of meshes.

use glam::DVec3;
use mesh_core::generators::{cuboid, icosphere};
use mesh_core::{Label, LabeledMesh};

/// An icosphere with `[outside, inside]` labels.
pub fn sphere(sub: u32, centre: DVec3, radius: f64, outside: u32, inside: u32) -> LabeledMesh {
    icosphere(
        sub,
        centre,
        radius,
        [Label::new(outside), Label::new(inside)],
    )
    .expect("valid sphere parameters")
}

/// The disjoint union of several meshes ([`LabeledMesh::disjoint_union`]).
pub fn union(meshes: &[LabeledMesh]) -> LabeledMesh {
    LabeledMesh::disjoint_union(meshes).expect("valid union")
}

/// The same mesh with every triangle's orientation reversed but labels kept: an
/// inside-out surface.
pub fn inverted(m: &LabeledMesh) -> LabeledMesh {
    let (p, t, l) = m.to_raw();
    let t: Vec<[u32; 3]> = t.iter().map(|&[a, b, c]| [a, c, b]).collect();
    LabeledMesh::from_raw(p, &t, &l).expect("valid inverted mesh")
}

/// The axis-aligned box `[lo, hi]` as 12 outward-facing triangles, labels
/// `[outside, inside]`.
pub fn cube(lo: DVec3, hi: DVec3, outside: u32, inside: u32) -> LabeledMesh {
    cuboid(lo, hi, [Label::new(outside), Label::new(inside)]).expect("valid cube")
}
