//! Small meshes for the tests of this crate, built by hand so these tests do not depend
//! on the generators module.

use std::collections::HashMap;

use glam::DVec3;

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
pub(crate) fn icosphere(center: DVec3, r: f64, levels: u32, inside: u32) -> Raw {
    let g = (1.0 + 5f64.sqrt()) / 2.0;
    let mut p: Vec<DVec3> = [
        (-1.0, g, 0.0),
        (1.0, g, 0.0),
        (-1.0, -g, 0.0),
        (1.0, -g, 0.0),
        (0.0, -1.0, g),
        (0.0, 1.0, g),
        (0.0, -1.0, -g),
        (0.0, 1.0, -g),
        (g, 0.0, -1.0),
        (g, 0.0, 1.0),
        (-g, 0.0, -1.0),
        (-g, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| DVec3::new(x, y, z).normalize())
    .collect();
    let mut t: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..levels {
        let mut mid: HashMap<(u32, u32), u32> = HashMap::with_capacity(t.len() * 2);
        let mut next = Vec::with_capacity(t.len() * 4);
        for &[a, b, c] in &t {
            let mut m = |x: u32, y: u32| {
                *mid.entry((x.min(y), x.max(y))).or_insert_with(|| {
                    p.push(((p[x as usize] + p[y as usize]) * 0.5).normalize());
                    p.len() as u32 - 1
                })
            };
            let (ab, bc, ca) = (m(a, b), m(b, c), m(c, a));
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        t = next;
    }
    let p = p.into_iter().map(|q| center + q * r).collect();
    let l = vec![[0, inside]; t.len()];
    (p, t, l)
}
