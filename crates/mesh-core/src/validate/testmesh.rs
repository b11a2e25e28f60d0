//! Small meshes for the tests of this crate: tetrahedra built by hand, and the icosphere
//! taken from the generators module.

use glam::DVec3;

use crate::ids::Label;
use crate::mesh::LabeledMesh;

/// Raw arrays of a mesh: positions, triangles, `[front, back]` labels.
pub(crate) type Raw = (Vec<DVec3>, Vec<[u32; 3]>, Vec<[u32; 2]>);

/// The unit right tetrahedron at `offset`, right-hand normals pointing outwards, outside
/// label 0 in front and `inside` behind.
pub(crate) fn tetra(offset: DVec3, inside: u32) -> Raw {
    let p = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z]
        .map(|q| q + offset)
        .to_vec();
    let t = vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
    (p, t, vec![[0, inside]; 4])
}

/// Concatenates raw meshes, renumbering vertices.
pub(crate) fn concat(parts: &[Raw]) -> Raw {
    let mut out: Raw = (Vec::new(), Vec::new(), Vec::new());
    for (p, t, l) in parts {
        let base = out.0.len() as u32;
        out.0.extend_from_slice(p);
        out.1.extend(t.iter().map(|tri| tri.map(|v| v + base)));
        out.2.extend_from_slice(l);
    }
    out
}

/// Builds a mesh from raw arrays known to be in range.
pub(crate) fn build((p, t, l): Raw) -> LabeledMesh {
    match LabeledMesh::from_raw(p, &t, &l) {
        Ok(m) => m,
        Err(e) => panic!("test mesh is malformed: {e}"),
    }
}

/// An icosphere of radius `r` about `center` after `levels` subdivisions
/// (20·4^levels triangles), outward normals, outside 0 in front and `inside` behind.
///
/// The raw arrays of [`crate::generators::icosphere`], so these tests and the generator
/// share one construction. Callers pass a level of at most
/// [`crate::generators::MAX_SUBDIVISIONS`], a positive radius and `inside != 0`.
pub(crate) fn icosphere(center: DVec3, r: f64, levels: u32, inside: u32) -> Raw {
    match crate::generators::icosphere(levels, center, r, [Label::new(0), Label::new(inside)]) {
        Ok(m) => m.to_raw(),
        Err(e) => panic!("test icosphere is malformed: {e}"),
    }
}
