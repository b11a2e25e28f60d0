//! Scenes of separate spheres: random non-overlapping spheres in a box, each its own
//! material.
//!
//! Placement is rejection sampling, seeded by [`ChaCha8Rng`] (portable across platforms,
//! so a seed names the same scene everywhere). Each sphere gets a bounded number of
//! candidates ([`ATTEMPTS_PER_SPHERE`]); a candidate is kept when it lies inside the box
//! and keeps a gap of at least [`MIN_GAP_FRACTION`] of the smaller radius to every sphere
//! already placed. The check against placed spheres is linear, so placement is O(n²) —
//! fine for the hundreds of spheres a test scene has.
//!
//! Because icosphere vertices lie *on* their sphere and the rest of the mesh inside it,
//! non-overlapping spheres give non-intersecting meshes.

use glam::DVec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::error::{GeneratorError, check_box, check_positive, invalid};
use super::icosphere::{check_subdivisions, unit_icosphere};
use crate::error::MeshError;
use crate::ids::{Label, MAX_INDEX};
use crate::mesh::LabeledMesh;

/// Candidates tried per sphere before [`random_spheres`] gives up.
pub const ATTEMPTS_PER_SPHERE: usize = 10_000;

/// Required clearance between two spheres, as a fraction of the smaller radius.
pub const MIN_GAP_FRACTION: f64 = 0.1;

/// One placed sphere.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlacedSphere {
    /// Centre.
    pub centre: DVec3,
    /// Radius.
    pub radius: f64,
    /// The material inside it (the outside is label 0).
    pub label: Label,
}

/// Places `n` spheres with radii uniform in `radius_range = [min, max]` and centres
/// uniform over the positions that keep each sphere inside `[box_min, box_max]`, no two
/// closer than `r₁ + r₂ + MIN_GAP_FRACTION·min(r₁, r₂)`. Sphere `i` gets label `i + 1`.
///
/// Fails on `n = 0`, a non-finite or empty box, a radius range that is not
/// `0 < min ≤ max`, a box narrower than `2·max` on some axis, or when some sphere cannot
/// be placed within [`ATTEMPTS_PER_SPHERE`] candidates.
pub fn place_random_spheres(
    n: usize,
    box_min: DVec3,
    box_max: DVec3,
    radius_range: [f64; 2],
    seed: u64,
) -> Result<Vec<PlacedSphere>, GeneratorError> {
    const NAME: &str = "random_spheres";
    if n == 0 {
        return Err(invalid(NAME, "n", n, "at least 1"));
    }
    if n > MAX_INDEX as usize - 1 {
        return Err(GeneratorError::LabelOverflow { generator: NAME });
    }
    check_box(NAME, box_min, box_max)?;
    let [r_min, r_max] = radius_range;
    check_positive(NAME, "minimum radius", r_min)?;
    check_positive(NAME, "maximum radius", r_max)?;
    if r_min > r_max {
        return Err(invalid(
            NAME,
            "radius_range",
            format!("{radius_range:?}"),
            "min ≤ max",
        ));
    }
    if (box_max - box_min).min_element() <= 2.0 * r_max {
        return Err(invalid(
            NAME,
            "box",
            format!("[{box_min}, {box_max}]"),
            "wider than 2·(maximum radius) on every axis",
        ));
    }

    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut placed: Vec<PlacedSphere> = Vec::with_capacity(n);
    let mut attempts = 0;
    while placed.len() < n {
        let mut found = None;
        for _ in 0..ATTEMPTS_PER_SPHERE {
            attempts += 1;
            let radius = r_min + (r_max - r_min) * rng.random::<f64>();
            let u = DVec3::new(rng.random(), rng.random(), rng.random());
            let lo = box_min + DVec3::splat(radius);
            let centre = lo + (box_max - DVec3::splat(radius) - lo) * u;
            let clear = placed.iter().all(|s| {
                let gap = MIN_GAP_FRACTION * s.radius.min(radius);
                s.centre.distance(centre) > s.radius + radius + gap
            });
            if clear {
                found = Some((centre, radius));
                break;
            }
        }
        let Some((centre, radius)) = found else {
            return Err(GeneratorError::CannotPlace {
                generator: NAME,
                placed: placed.len(),
                requested: n,
                attempts,
            });
        };
        // n ≤ MAX_INDEX − 1 was checked, so the label index is below u32::MAX.
        let label = Label::new(placed.len() as u32 + 1);
        placed.push(PlacedSphere {
            centre,
            radius,
            label,
        });
    }
    Ok(placed)
}

/// Meshes each sphere as an icosphere of the given subdivision level, labels
/// `[0, sphere.label]` (outside is 0). Labels must be non-zero for a valid scene.
pub fn spheres_mesh(
    spheres: &[PlacedSphere],
    subdivisions: u32,
) -> Result<LabeledMesh, GeneratorError> {
    const NAME: &str = "spheres_mesh";
    check_subdivisions(NAME, subdivisions)?;
    let (unit, unit_tris) = unit_icosphere(subdivisions);
    let total = unit.len().saturating_mul(spheres.len());
    if total > MAX_INDEX as usize {
        return Err(MeshError::TooLarge {
            what: "vertices",
            count: total,
        }
        .into());
    }
    let mut positions = Vec::with_capacity(total);
    let mut tris = Vec::with_capacity(unit_tris.len() * spheres.len());
    let mut labels = Vec::with_capacity(unit_tris.len() * spheres.len());
    for s in spheres {
        if s.label == Label::new(0) {
            return Err(invalid(
                NAME,
                "sphere label",
                0,
                "non-zero (0 is the outside)",
            ));
        }
        check_positive(NAME, "sphere radius", s.radius)?;
        if !s.centre.is_finite() {
            return Err(invalid(NAME, "sphere centre", s.centre, "finite"));
        }
        // total ≤ MAX_INDEX was checked above, so every offset fits in u32.
        let base = positions.len() as u32;
        positions.extend(unit.iter().map(|&u| s.centre + s.radius * u));
        tris.extend(unit_tris.iter().map(|t| t.map(|v| v + base)));
        labels.extend(std::iter::repeat_n([0, s.label.raw()], unit_tris.len()));
    }
    Ok(LabeledMesh::from_raw(positions, &tris, &labels)?)
}

/// `n` random non-overlapping spheres in a box ([`place_random_spheres`]), meshed as
/// icospheres ([`spheres_mesh`]): labels `1..=n` inside, 0 outside. Deterministic in
/// `seed`.
pub fn random_spheres(
    n: usize,
    box_min: DVec3,
    box_max: DVec3,
    radius_range: [f64; 2],
    subdivisions: u32,
    seed: u64,
) -> Result<LabeledMesh, GeneratorError> {
    check_subdivisions("random_spheres", subdivisions)?;
    let spheres = place_random_spheres(n, box_min, box_max, radius_range, seed)?;
    spheres_mesh(&spheres, subdivisions)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generators::checks::{assert_well_formed, volume_per_label};

    const LO: DVec3 = DVec3::ZERO;
    const HI: DVec3 = DVec3::ONE;

    #[test]
    fn spheres_are_separated_and_inside_the_box() {
        let s = place_random_spheres(40, LO, HI, [0.04, 0.1], 7).unwrap();
        assert_eq!(s.len(), 40);
        for (i, a) in s.iter().enumerate() {
            assert_eq!(a.label, Label::new(i as u32 + 1));
            assert!((0.04..=0.1).contains(&a.radius));
            assert!((a.centre - a.radius).cmpge(LO).all() && (a.centre + a.radius).cmple(HI).all());
            for b in &s[..i] {
                let gap = MIN_GAP_FRACTION * a.radius.min(b.radius);
                assert!(a.centre.distance(b.centre) > a.radius + b.radius + gap);
            }
        }
    }

    #[test]
    fn mesh_is_well_formed_with_one_region_per_sphere() {
        let s = place_random_spheres(12, LO, HI, [0.05, 0.15], 3).unwrap();
        let m = spheres_mesh(&s, 2).unwrap();
        assert_well_formed(&m);
        assert_eq!(m.num_triangles(), 12 * 320);
        let vols = volume_per_label(&m);
        assert_eq!(vols.len(), 12);
        for sphere in &s {
            let exact = 4.0 / 3.0 * std::f64::consts::PI * sphere.radius.powi(3);
            let v = vols[&sphere.label];
            assert!(
                v > 0.9 * exact && v < exact,
                "label {}: {v} vs {exact}",
                sphere.label
            );
        }
        // The mesh of each label stays within its sphere.
        for t in m.triangles() {
            let sphere = &s[m.labels(t)[1].idx() - 1];
            for p in m.tri_positions(t) {
                assert!(p.distance(sphere.centre) <= sphere.radius * (1.0 + 1e-12));
            }
        }
    }

    #[test]
    fn deterministic_per_seed() {
        let a = random_spheres(10, LO, HI, [0.05, 0.1], 1, 42).unwrap();
        let b = random_spheres(10, LO, HI, [0.05, 0.1], 1, 42).unwrap();
        let c = random_spheres(10, LO, HI, [0.05, 0.1], 1, 43).unwrap();
        assert_eq!(a.to_raw(), b.to_raw());
        assert_ne!(a.to_raw().0, c.to_raw().0);
    }

    #[test]
    fn impossible_packing_is_a_typed_error() {
        // 200 spheres of radius 0.2 cannot fit in a unit box.
        let err = place_random_spheres(200, LO, HI, [0.2, 0.2], 1).unwrap_err();
        assert!(
            matches!(err, GeneratorError::CannotPlace { requested: 200, .. }),
            "{err}"
        );
    }

    #[test]
    fn bad_parameters_are_refused() {
        assert!(place_random_spheres(0, LO, HI, [0.1, 0.1], 1).is_err());
        assert!(place_random_spheres(3, LO, HI, [0.0, 0.1], 1).is_err());
        assert!(place_random_spheres(3, LO, HI, [0.2, 0.1], 1).is_err());
        assert!(place_random_spheres(3, LO, HI, [0.1, f64::NAN], 1).is_err());
        assert!(place_random_spheres(3, LO, HI, [0.1, 0.5], 1).is_err());
        assert!(place_random_spheres(3, HI, LO, [0.1, 0.1], 1).is_err());
        assert!(random_spheres(3, LO, HI, [0.1, 0.1], 12, 1).is_err());
    }
}
