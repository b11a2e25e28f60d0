//! Midpoint subdivision: every triangle split into four through its edge midpoints.
//!
//! One step ([`split_in_four`]) serves both the icosphere, which projects each midpoint
//! onto the sphere, and [`subdivide`], which keeps it on its edge so the surface is
//! exactly the same, only finer. Why the latter: a benchmark that grows a real scanned
//! mesh's resolution (`bench scaling --mesh`) must not change its shape, or it would
//! measure a different problem at every size.

use std::collections::HashMap;

use glam::DVec3;

use super::error::{GeneratorError, invalid};
use crate::ids::MAX_INDEX;
use crate::mesh::LabeledMesh;

/// Splits every triangle of `tris` into four, appending one vertex per edge (placed by
/// `place(a, b)` from its end positions) to `positions`. The corner triangles come in
/// the parent's orientation, then the middle one; children of triangle `t` are
/// `4t..4t+4`. Edges are keyed by their vertex pair, so triangles sharing an edge —
/// two, or more at a non-manifold edge — share its midpoint.
///
/// The caller makes sure the counts fit in `u32`.
pub(crate) fn split_in_four(
    positions: &mut Vec<DVec3>,
    tris: &[[u32; 3]],
    place: impl Fn(DVec3, DVec3) -> DVec3,
) -> Vec<[u32; 3]> {
    let mut next = Vec::with_capacity(tris.len() * 4);
    // A closed manifold surface has 3/2 edges per triangle.
    let mut midpoints: HashMap<u64, u32> = HashMap::with_capacity(tris.len() * 3 / 2);
    let mut midpoint = |a: u32, b: u32, positions: &mut Vec<DVec3>| -> u32 {
        let key = (u64::from(a.min(b)) << 32) | u64::from(a.max(b));
        *midpoints.entry(key).or_insert_with(|| {
            positions.push(place(positions[a as usize], positions[b as usize]));
            (positions.len() - 1) as u32
        })
    };
    for &[a, b, c] in tris {
        let ab = midpoint(a, b, positions);
        let bc = midpoint(b, c, positions);
        let ca = midpoint(c, a, positions);
        next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
    }
    next
}

/// `mesh` with every triangle split into four `levels` times, midpoints on their edges:
/// the same surface with `4^levels` times the triangles, each child carrying its parent's
/// labels and orientation. Non-manifold edges stay non-manifold (their triangles share
/// the midpoint).
///
/// Fails when the result would exceed `u32` indices.
pub fn subdivide(mesh: &LabeledMesh, levels: u32) -> Result<LabeledMesh, GeneratorError> {
    let (mut positions, mut tris, mut labels) = mesh.to_raw();
    let factor = 4u64.checked_pow(levels).unwrap_or(u64::MAX);
    // Vertices grow by at most 3 per triangle per level: bounded by 4^levels times the
    // triangles plus the original vertices.
    let worst = (tris.len() as u64)
        .saturating_mul(factor)
        .saturating_add(positions.len() as u64);
    if worst > u64::from(MAX_INDEX) {
        return Err(invalid(
            "subdivide",
            "levels",
            levels,
            "few enough that the triangles fit in u32 indices",
        ));
    }
    for _ in 0..levels {
        tris = split_in_four(&mut positions, &tris, |a, b| 0.5 * (a + b));
        labels = labels.iter().flat_map(|&l| [l; 4]).collect();
    }
    Ok(LabeledMesh::from_raw(positions, &tris, &labels)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generators::checks::assert_well_formed;
    use crate::generators::{copies, double_bubble, zalesak};
    use crate::geometry::label_volumes;
    use crate::validate::{ValidateOptions, validate};

    /// Counts grow by 4 per level, the enclosed volume of every label is unchanged (the
    /// surface is the same), and a non-manifold input (the double bubble's triple curve,
    /// where three triangles share each edge) stays valid.
    #[test]
    fn subdivision_keeps_the_surface_and_its_labels() {
        let base = zalesak(8).unwrap();
        let fine = subdivide(&base, 2).unwrap();
        assert_eq!(fine.num_triangles(), 16 * base.num_triangles());
        let (v0, v1) = (label_volumes(&base), label_volumes(&fine));
        assert_eq!(v0.len(), v1.len());
        for ((l0, a), (l1, b)) in v0.iter().zip(&v1) {
            assert_eq!(l0, l1);
            assert!(
                (a - b).abs() <= 1e-12 * a.abs().max(1.0),
                "{l0}: {a} vs {b}"
            );
        }
        assert_well_formed(&fine);
        let bubble = double_bubble(1.0, 12).unwrap();
        let finer = subdivide(&bubble, 1).unwrap();
        assert_well_formed(&finer);
        let report = validate(&finer, &ValidateOptions::with_intersections());
        assert!(report.is_valid(), "{report:?}");
        assert_eq!(finer.label_set(), bubble.label_set());
        let overlapping = copies(&base, 2, 3).unwrap();
        assert_eq!(
            subdivide(&overlapping, 1).unwrap().num_triangles(),
            4 * overlapping.num_triangles()
        );
        assert_eq!(
            subdivide(&base, 0).unwrap().num_triangles(),
            base.num_triangles()
        );
    }

    #[test]
    fn too_many_levels_are_an_error() {
        let base = zalesak(8).unwrap();
        assert!(matches!(
            subdivide(&base, 20),
            Err(GeneratorError::InvalidParameter { .. })
        ));
    }
}
