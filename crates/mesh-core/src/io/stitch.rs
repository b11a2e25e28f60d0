//! Stitching: vertices at the same position on open edges become one vertex.
//!
//! Why: many exporters give every triangle its own three vertices (every STL file, and
//! OBJ or PLY written with per-face normals or colours). Such a file describes a closed
//! surface, but as written every edge is used by one triangle only, so it reads as a
//! soup of open triangles and nothing downstream can tell inside from outside.
//!
//! What is merged, and why only that:
//! - only vertices on an **open edge** (an edge, as an unordered vertex pair, used by one
//!   triangle): a closed mesh is never changed, so two solids that merely touch at a
//!   vertex or along a face (a contact `fix` resolves) stay as the file gives them;
//! - only **exactly equal coordinates** (`-0.0` equals `0.0`): no tolerance can merge two
//!   distinct points of a fine mesh, and text exporters print a shared corner the same
//!   way every time it occurs. A near miss stays open and is reported by validation.
//!
//! Each group of coincident open vertices keeps its first vertex (in file order); the
//! others are removed and the vertices after them renumbered down, so the result has no
//! vertex the stitch orphaned. Cost: two sorts, O(T log T).

use glam::DVec3;

/// Stitches `tris` over `positions` in place (see the module docs) and returns the
/// number of vertices merged into another.
pub(crate) fn stitch_open_vertices(positions: &mut Vec<DVec3>, tris: &mut [[u32; 3]]) -> usize {
    let n = positions.len();
    if tris.iter().flatten().any(|&v| v as usize >= n) {
        return 0; // the mesh builder names the bad index, with the file's numbering
    }
    // Open edges: unordered pairs used by exactly one triangle.
    let mut edges: Vec<u64> = tris
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .map(|(a, b)| (u64::from(a.min(b)) << 32) | u64::from(a.max(b)))
        .collect();
    edges.sort_unstable();
    let mut open = vec![false; n];
    let mut any_open = false;
    for run in edges.chunk_by(|a, b| a == b) {
        if run.len() == 1 {
            open[(run[0] >> 32) as usize] = true;
            open[(run[0] & 0xffff_ffff) as usize] = true;
            any_open = true;
        }
    }
    drop(edges);
    if !any_open {
        return 0;
    }

    // Group open vertices by exact position; the first of each group represents it.
    let key = |v: u32| {
        let p = positions[v as usize] + DVec3::ZERO; // -0.0 + 0.0 = +0.0
        [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()]
    };
    let mut candidates: Vec<u32> = (0..n as u32).filter(|&v| open[v as usize]).collect();
    candidates.sort_unstable_by_key(|&v| (key(v), v));
    let mut target: Vec<u32> = (0..n as u32).collect();
    let mut merged = 0;
    for group in candidates.chunk_by(|&a, &b| key(a) == key(b)) {
        for &v in &group[1..] {
            target[v as usize] = group[0];
            merged += 1;
        }
    }
    if merged == 0 {
        return 0;
    }

    // Renumber: every kept vertex moves down by the number of merged ones before it.
    let mut new_index = vec![0u32; n];
    let mut kept = 0u32;
    for v in 0..n {
        if target[v] == v as u32 {
            new_index[v] = kept;
            positions[kept as usize] = positions[v];
            kept += 1;
        }
    }
    positions.truncate(kept as usize);
    for tri in tris.iter_mut() {
        for v in tri.iter_mut() {
            *v = new_index[target[*v as usize] as usize];
        }
    }
    merged
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generators::cuboid;
    use crate::ids::Label;

    /// The 12 triangles of the unit cube, outward, over its 8 corners.
    fn cube() -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let labels = [Label::OUTSIDE, Label::new(1)];
        let (positions, tris, _) = cuboid(DVec3::ZERO, DVec3::ONE, labels).unwrap().to_raw();
        (positions, tris)
    }

    /// The same cube with every triangle on its own three vertices (as STL writes it).
    fn soup() -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let (p, t) = cube();
        let positions = t
            .iter()
            .flat_map(|tri| tri.map(|v| p[v as usize]))
            .collect();
        let tris = (0..t.len() as u32)
            .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
            .collect();
        (positions, tris)
    }

    #[test]
    fn a_triangle_soup_becomes_the_welded_cube() {
        let (mut positions, mut tris) = soup();
        assert_eq!(stitch_open_vertices(&mut positions, &mut tris), 36 - 8);
        assert_eq!(positions.len(), 8);
        // Same triangles as the welded cube, corner for corner, by position.
        let (p, t) = cube();
        for (a, b) in tris.iter().zip(&t) {
            for k in 0..3 {
                assert_eq!(positions[a[k] as usize], p[b[k] as usize]);
            }
        }
        // Every edge is now used twice.
        let mut edges: Vec<(u32, u32)> = tris
            .iter()
            .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
            .map(|(a, b)| (a.min(b), a.max(b)))
            .collect();
        edges.sort_unstable();
        assert!(edges.chunk_by(|a, b| a == b).all(|r| r.len() == 2));
    }

    #[test]
    fn closed_meshes_and_near_misses_are_left_alone() {
        // Two closed cubes sharing a corner position: no open edge, nothing merged.
        let (mut positions, mut tris) = cube();
        let (p2, t2) = cube();
        positions.extend(p2.iter().map(|&p| p + DVec3::ONE));
        tris.extend(t2.iter().map(|t| t.map(|v| v + 8)));
        let before = (positions.clone(), tris.clone());
        assert_eq!(stitch_open_vertices(&mut positions, &mut tris), 0);
        assert_eq!((positions, tris), before);

        // A soup with one corner moved by one ulp keeps that corner's copy apart.
        let (mut positions, mut tris) = soup();
        positions[0].x = f64::from_bits(positions[0].x.to_bits() + 1);
        assert_eq!(stitch_open_vertices(&mut positions, &mut tris), 36 - 8 - 1);
        assert_eq!(positions.len(), 9);
    }

    #[test]
    fn negative_zero_is_zero_and_isolated_vertices_stay() {
        let mut positions = vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::X,
            DVec3::Y,
            DVec3::new(-0.0, 0.0, -0.0),
            DVec3::Y,
            DVec3::Z,
            DVec3::splat(5.0), // isolated: not on any edge
        ];
        let mut tris = vec![[0, 1, 2], [3, 4, 5]];
        assert_eq!(stitch_open_vertices(&mut positions, &mut tris), 2);
        assert_eq!(tris, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(positions.len(), 5);
        assert_eq!(positions[4], DVec3::splat(5.0));
    }
}
