//! An axis-aligned box as 12 triangles: the coarse CAD-like solid that tests of thin and
//! coarse materials need (a plate, a cube far coarser than the grid), written once here
//! instead of in each test.

use glam::DVec3;

use super::error::{GeneratorError, check_box};
use crate::ids::Label;
use crate::mesh::LabeledMesh;

/// The box `[lo, hi]` as 12 triangles with outward normals, `labels = [outside, inside]`
/// (the front label is the side the normal points into).
///
/// Errors: a non-finite corner, or `hi` not above `lo` on every axis.
pub fn cuboid(lo: DVec3, hi: DVec3, labels: [Label; 2]) -> Result<LabeledMesh, GeneratorError> {
    check_box("cuboid", lo, hi)?;
    let corners: Vec<DVec3> = (0..8)
        .map(|i| {
            DVec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            )
        })
        .collect();
    // Quads counter-clockwise seen from outside.
    let quads = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let tris: Vec<[u32; 3]> = quads
        .iter()
        .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
        .collect();
    let pair = labels.map(|l| l.raw());
    Ok(LabeledMesh::from_raw(
        corners,
        &tris,
        &vec![pair; tris.len()],
    )?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::label_volumes;
    use crate::validate::{ValidateOptions, validate};

    #[test]
    fn a_box_is_valid_with_its_volume_inside() {
        let m = cuboid(
            DVec3::ZERO,
            DVec3::new(2.0, 1.0, 0.5),
            [Label::OUTSIDE, Label::new(3)],
        )
        .unwrap();
        assert!(validate(&m, &ValidateOptions::default()).is_valid());
        assert!((label_volumes(&m)[&Label::new(3)] - 1.0).abs() < 1e-12);
        assert!(cuboid(DVec3::ONE, DVec3::ZERO, [Label::OUTSIDE, Label::new(1)]).is_err());
        assert!(
            cuboid(
                DVec3::ZERO,
                DVec3::splat(f64::NAN),
                [Label::OUTSIDE, Label::new(1)]
            )
            .is_err()
        );
    }
}
