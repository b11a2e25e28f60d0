//! Small meshes for the flow tests, built here so the tests do not depend on the
//! generators of mesh-core.

use std::collections::HashMap;

use glam::DVec3;
use mesh_core::{Label, LabeledMesh};

/// Outside 0, inside 1: the labels of the one-material test spheres.
pub fn outside_inside() -> [Label; 2] {
    [Label::new(0), Label::new(1)]
}

/// A sphere of radius `r` about the origin: an octahedron subdivided `levels` times by
/// edge midpoints projected to the sphere (`8·4^levels` triangles), normals outward, so
/// `labels = [outside, inside]`.
pub fn icosphere(levels: u32, r: f64, labels: [Label; 2]) -> LabeledMesh {
    let mut pos = vec![
        DVec3::X,
        -DVec3::X,
        DVec3::Y,
        -DVec3::Y,
        DVec3::Z,
        -DVec3::Z,
    ];
    let mut tris: Vec<[u32; 3]> = vec![
        [0, 2, 4],
        [2, 1, 4],
        [1, 3, 4],
        [3, 0, 4],
        [2, 0, 5],
        [1, 2, 5],
        [3, 1, 5],
        [0, 3, 5],
    ];
    for _ in 0..levels {
        let mut cache: HashMap<(u32, u32), u32> = HashMap::new();
        let mut mid = |a: u32, b: u32, pos: &mut Vec<DVec3>| {
            *cache.entry((a.min(b), a.max(b))).or_insert_with(|| {
                pos.push((pos[a as usize] + pos[b as usize]).normalize());
                (pos.len() - 1) as u32
            })
        };
        let mut next = Vec::with_capacity(tris.len() * 4);
        for &[a, b, c] in &tris {
            let (ab, bc, ca) = (
                mid(a, b, &mut pos),
                mid(b, c, &mut pos),
                mid(c, a, &mut pos),
            );
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        tris = next;
    }
    let pos = pos.into_iter().map(|p| p * r).collect();
    let lab = vec![labels.map(|l| l.raw()); tris.len()];
    LabeledMesh::from_raw(pos, &tris, &lab).unwrap()
}

/// The cube `[-1, 1]³`, 12 triangles, normals outward, `labels = [outside, inside]`.
pub fn cube(labels: [Label; 2]) -> LabeledMesh {
    let pos: Vec<DVec3> = (0..8)
        .map(|i| DVec3::new(sign(i & 1), sign(i & 2), sign(i & 4)))
        .collect();
    // Quads counter-clockwise seen from outside.
    let quads = [
        [0, 4, 6, 2],
        [1, 3, 7, 5],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 2, 3, 1],
        [4, 5, 7, 6],
    ];
    let tris: Vec<[u32; 3]> = quads
        .iter()
        .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
        .collect();
    let lab = vec![labels.map(|l| l.raw()); tris.len()];
    LabeledMesh::from_raw(pos, &tris, &lab).unwrap()
}

fn sign(bit: i32) -> f64 {
    if bit == 0 { -1.0 } else { 1.0 }
}

/// Three half-plane sheets meeting at 120° along the z axis (an open piece of a triple
/// curve). Vertex 0 is the origin, on the curve; vertices 1, 2 are `±z`; vertex `3 + k`
/// is the unit vector at angle `90° + 120°·k` in the xy plane, on sheet `k`.
///
/// Wedges: `a` around 30°, `b` around 150°, `c` around 270°. Sheet 0 (90°) separates
/// `a | b`, sheet 1 (210°) `b | c`, sheet 2 (330°) `c | a`. Triangles are oriented with
/// the normal pointing counter-clockwise about z, i.e. into the wedge after the sheet.
pub fn triple_fan(a: Label, b: Label, c: Label) -> LabeledMesh {
    triple_fan_at(a, b, c, [90.0, 210.0, 330.0])
}

/// [`triple_fan`] with its three sheets (a|b, b|c, c|a) at the given angles in degrees,
/// counter-clockwise in that order: `a` fills the angle from the c|a sheet to the a|b
/// sheet, and so on.
pub fn triple_fan_at(a: Label, b: Label, c: Label, degrees: [f64; 3]) -> LabeledMesh {
    let mut pos = vec![DVec3::ZERO, DVec3::Z, -DVec3::Z];
    for angle in degrees {
        let angle = angle.to_radians();
        pos.push(DVec3::new(angle.cos(), angle.sin(), 0.0));
    }
    // (sheet vertex, wedge in front = counter-clockwise side, wedge behind)
    let sheets = [(3, b, a), (4, c, b), (5, a, c)];
    let mut tris = Vec::new();
    let mut lab = Vec::new();
    for (p, front, back) in sheets {
        // Normal of (0, p, 1) is d × z, clockwise; (0, 1, p) is z × d, counter-clockwise.
        tris.push([0, 1, p]);
        tris.push([0, p, 2]);
        lab.push([front.raw(), back.raw()]);
        lab.push([front.raw(), back.raw()]);
    }
    LabeledMesh::from_raw(pos, &tris, &lab).unwrap()
}

/// Mean distance of the live vertices from the origin, and the spread (max − min).
pub fn radius_stats(positions: &[DVec3], mesh: &LabeledMesh) -> (f64, f64) {
    let radii: Vec<f64> = mesh
        .vertices()
        .map(|v| positions[v.idx()].length())
        .collect();
    let mean = radii.iter().sum::<f64>() / radii.len() as f64;
    let max = radii.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    let min = radii.iter().cloned().fold(f64::INFINITY, f64::min);
    (mean, max - min)
}
