//! Rotated copies of a mesh, overlapping on purpose.
//!
//! The copies share a centre of rotation (the mesh's vertex centroid), so they
//! interpenetrate: a stress test for the intersection handling of a tracker. Each copy
//! keeps the outside material 0 and gets its own range of the other labels (copy `i` maps
//! label `l ≠ 0` to `l + i·max_label`), so no two copies share a material.

use glam::{DQuat, DVec3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::error::{GeneratorError, invalid};
use crate::error::MeshError;
use crate::ids::MAX_INDEX;
use crate::mesh::LabeledMesh;

/// One copy of `mesh` per rotation, each rotated about the vertex centroid of `mesh`, with
/// copy `i`'s non-zero labels offset by `i·max_label` (0 stays 0). Rotations need not be
/// normalised but must be finite and non-zero.
///
/// Fails on an empty mesh or rotation list, a degenerate rotation, or when labels or
/// element counts would overflow `u32`.
pub fn copies_with_rotations(
    mesh: &LabeledMesh,
    rotations: &[DQuat],
) -> Result<LabeledMesh, GeneratorError> {
    const NAME: &str = "copies";
    if rotations.is_empty() {
        return Err(invalid(NAME, "number of copies", 0, "at least 1"));
    }
    let (positions, tris, labels) = mesh.to_raw();
    if tris.is_empty() {
        return Err(invalid(NAME, "mesh triangles", 0, "at least 1"));
    }
    let max_label = labels.iter().flatten().copied().max().unwrap_or(0);
    let copies = rotations.len() as u64;
    if u64::from(max_label) * copies >= u64::from(u32::MAX) {
        return Err(GeneratorError::LabelOverflow { generator: NAME });
    }
    let total = positions.len().saturating_mul(rotations.len());
    if total > MAX_INDEX as usize {
        return Err(MeshError::TooLarge {
            what: "vertices",
            count: total,
        }
        .into());
    }
    let centroid = positions.iter().sum::<DVec3>() / positions.len() as f64;

    let mut out_positions = Vec::with_capacity(total);
    let mut out_tris = Vec::with_capacity(tris.len() * rotations.len());
    let mut out_labels = Vec::with_capacity(tris.len() * rotations.len());
    for (i, q) in rotations.iter().enumerate() {
        if !q.is_finite() || q.length_squared() == 0.0 {
            return Err(invalid(NAME, "rotation", q, "finite and non-zero"));
        }
        let q = q.normalize();
        // Both fit in u32: total ≤ MAX_INDEX and max_label · copies < u32::MAX (checked).
        let base = out_positions.len() as u32;
        let offset = i as u32 * max_label;
        out_positions.extend(positions.iter().map(|&p| centroid + q * (p - centroid)));
        out_tris.extend(tris.iter().map(|t| t.map(|v| v + base)));
        out_labels.extend(
            labels
                .iter()
                .map(|l| l.map(|l| if l == 0 { 0 } else { l + offset })),
        );
    }
    Ok(LabeledMesh::from_raw(
        out_positions,
        &out_tris,
        &out_labels,
    )?)
}

/// `k` copies of `mesh` about its vertex centroid: copy 0 as given, the others under
/// rotations drawn uniformly from SO(3) (Shoemake's method) by a `ChaCha8Rng` seeded with
/// `seed`. Labels as in [`copies_with_rotations`]. Fails on `k = 0` and as that function.
pub fn copies(mesh: &LabeledMesh, k: usize, seed: u64) -> Result<LabeledMesh, GeneratorError> {
    if k == 0 {
        return Err(invalid("copies", "k", k, "at least 1"));
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut rotations = Vec::with_capacity(k);
    rotations.push(DQuat::IDENTITY);
    for _ in 1..k {
        let (u1, u2, u3): (f64, f64, f64) = (rng.random(), rng.random(), rng.random());
        let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
        let (t2, t3) = (std::f64::consts::TAU * u2, std::f64::consts::TAU * u3);
        rotations.push(DQuat::from_xyzw(
            a * t2.sin(),
            a * t2.cos(),
            b * t3.sin(),
            b * t3.cos(),
        ));
    }
    copies_with_rotations(mesh, &rotations)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generators::checks::{assert_well_formed, volume_per_label};
    use crate::generators::{double_bubble, icosphere};
    use crate::ids::Label;

    #[test]
    fn copies_are_rotated_and_relabelled() {
        let bubble = double_bubble(1.0, 8).unwrap();
        let m = copies(&bubble, 3, 5).unwrap();
        assert_eq!(m.num_triangles(), 3 * bubble.num_triangles());
        assert_eq!(m.label_set(), [0, 1, 2, 3, 4, 5, 6].map(Label::new));
        // Each copy is closed and consistent with the same volumes (rotation is rigid).
        assert_well_formed(&m);
        let original = volume_per_label(&bubble);
        let vols = volume_per_label(&m);
        for (l, v) in vols {
            let base = Label::new((l.raw() - 1) % 2 + 1);
            assert!((v - original[&base]).abs() < 1e-12 * v, "label {l}: {v}");
        }
        // The copies really are rotated (not all on top of each other).
        let n = bubble.num_vertices();
        let (p, _, _) = m.to_raw();
        assert!(p[0] == bubble.position(crate::ids::VertexId::new(0)));
        assert!(p[n].distance(p[0]) > 1e-3 && p[2 * n].distance(p[n]) > 1e-3);
    }

    #[test]
    fn rotation_is_about_the_centroid() {
        let c = DVec3::new(3.0, -1.0, 2.0);
        let sphere = icosphere(1, c, 1.0, [Label::new(0), Label::new(1)]).unwrap();
        let m = copies(&sphere, 4, 9).unwrap();
        for v in m.vertices() {
            assert!((m.position(v).distance(c) - 1.0).abs() < 1e-12);
        }
        assert_eq!(
            copies(&sphere, 4, 9).unwrap().to_raw(),
            m.to_raw(),
            "deterministic"
        );
    }

    #[test]
    fn bad_parameters_are_refused() {
        let sphere = icosphere(0, DVec3::ZERO, 1.0, [Label::new(0), Label::new(1)]).unwrap();
        assert!(copies(&sphere, 0, 1).is_err());
        assert!(copies(&LabeledMesh::new(), 2, 1).is_err());
        assert!(copies_with_rotations(&sphere, &[DQuat::from_xyzw(0.0, 0.0, 0.0, 0.0)]).is_err());
        let big = icosphere(
            0,
            DVec3::ZERO,
            1.0,
            [Label::new(0), Label::new(u32::MAX / 2)],
        )
        .unwrap();
        assert!(matches!(
            copies(&big, 3, 1),
            Err(GeneratorError::LabelOverflow { .. })
        ));
    }
}
