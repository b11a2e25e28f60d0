//! The icosphere: a regular icosahedron refined by edge midpoints and projected onto the
//! sphere.
//!
//! Each level splits every triangle into four through its edge midpoints. A midpoint is
//! created once per edge (a cache keyed by the edge's vertex pair), so neighbouring
//! triangles share it and the result has no duplicate vertices: `10·4^s + 2` vertices,
//! `20·4^s` triangles, every vertex of valence 5 or 6. Midpoints are projected at every
//! level (not only at the end), which keeps triangle sizes within a factor of about 1.3.

use glam::DVec3;

use super::error::{GeneratorError, check_finite, check_positive, invalid};
use super::subdivide::split_in_four;
use crate::ids::Label;
use crate::mesh::LabeledMesh;

/// Largest accepted subdivision level: level 9 already has 5.2 million triangles.
pub const MAX_SUBDIVISIONS: u32 = 9;

/// The twelve icosahedron vertices `(0, ±1, ±φ)` and cyclic permutations, unnormalised.
fn icosahedron_vertices() -> [DVec3; 12] {
    let t = (1.0 + 5f64.sqrt()) / 2.0;
    [
        DVec3::new(-1.0, t, 0.0),
        DVec3::new(1.0, t, 0.0),
        DVec3::new(-1.0, -t, 0.0),
        DVec3::new(1.0, -t, 0.0),
        DVec3::new(0.0, -1.0, t),
        DVec3::new(0.0, 1.0, t),
        DVec3::new(0.0, -1.0, -t),
        DVec3::new(0.0, 1.0, -t),
        DVec3::new(t, 0.0, -1.0),
        DVec3::new(t, 0.0, 1.0),
        DVec3::new(-t, 0.0, -1.0),
        DVec3::new(-t, 0.0, 1.0),
    ]
}

/// The twenty faces, counter-clockwise seen from outside.
const ICOSAHEDRON_FACES: [[u32; 3]; 20] = [
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

/// The unit icosphere around the origin: unit-length positions and triangles whose
/// right-hand normals point outward. `subdivisions` must be at most [`MAX_SUBDIVISIONS`]
/// (callers check), so every count fits in `u32`.
pub(crate) fn unit_icosphere(subdivisions: u32) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let mut positions: Vec<DVec3> = icosahedron_vertices()
        .iter()
        .map(|p| p.normalize())
        .collect();
    let mut tris = ICOSAHEDRON_FACES.to_vec();
    for _ in 0..subdivisions {
        tris = split_in_four(&mut positions, &tris, |a, b| (a + b).normalize());
    }
    (positions, tris)
}

/// Checks an icosphere subdivision level.
pub(crate) fn check_subdivisions(
    generator: &'static str,
    subdivisions: u32,
) -> Result<(), GeneratorError> {
    if subdivisions <= MAX_SUBDIVISIONS {
        Ok(())
    } else {
        Err(invalid(
            generator,
            "subdivisions",
            subdivisions,
            "at most 9",
        ))
    }
}

/// An icosphere of `20·4^subdivisions` triangles inscribed in the sphere `(centre,
/// radius)`, normals pointing outward, so `labels = [outside, inside]` are its
/// `[front, back]` labels.
///
/// Fails on a non-finite centre, a radius that is not finite and positive, equal labels,
/// or more than [`MAX_SUBDIVISIONS`] subdivisions.
pub fn icosphere(
    subdivisions: u32,
    centre: DVec3,
    radius: f64,
    labels: [Label; 2],
) -> Result<LabeledMesh, GeneratorError> {
    const NAME: &str = "icosphere";
    check_subdivisions(NAME, subdivisions)?;
    check_finite(NAME, "centre", centre)?;
    check_positive(NAME, "radius", radius)?;
    if labels[0] == labels[1] {
        return Err(invalid(
            NAME,
            "labels",
            format!("{labels:?}"),
            "two different labels",
        ));
    }
    let (unit, tris) = unit_icosphere(subdivisions);
    let positions = unit.iter().map(|&u| centre + radius * u).collect();
    let pair = labels.map(|l| l.raw());
    Ok(LabeledMesh::from_raw(
        positions,
        &tris,
        &vec![pair; tris.len()],
    )?)
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI;

    use super::*;
    use crate::generators::checks::{assert_well_formed, bounded_volumes};

    fn labels() -> [Label; 2] {
        [Label::new(0), Label::new(1)]
    }

    #[test]
    fn counts_follow_the_subdivision_formula() {
        for s in 0..4 {
            let m = icosphere(s, DVec3::ZERO, 1.0, labels()).unwrap();
            assert_eq!(m.num_triangles(), 20 * 4usize.pow(s));
            assert_eq!(m.num_vertices(), 10 * 4usize.pow(s) + 2);
        }
    }

    #[test]
    fn vertices_lie_on_the_sphere_and_normals_point_out() {
        let centre = DVec3::new(1.0, -2.0, 0.5);
        let m = icosphere(3, centre, 2.5, labels()).unwrap();
        for v in m.vertices() {
            assert!(((m.position(v) - centre).length() - 2.5).abs() < 1e-12);
        }
        for t in m.triangles() {
            let [a, b, c] = m.tri_positions(t);
            let n = (b - a).cross(c - a);
            assert!(
                n.dot((a + b + c) / 3.0 - centre) > 0.0,
                "triangle {t} faces inward"
            );
        }
    }

    #[test]
    fn is_well_formed() {
        for s in 0..4 {
            let m = icosphere(s, DVec3::new(0.3, 0.2, 0.1), 0.7, labels()).unwrap();
            assert_well_formed(&m);
        }
    }

    #[test]
    fn volume_converges_to_the_ball() {
        let r = 1.3;
        let exact = 4.0 / 3.0 * PI * r * r * r;
        let mut last = f64::INFINITY;
        for s in 0..6 {
            let m = icosphere(s, DVec3::new(0.5, 0.0, -1.0), r, labels()).unwrap();
            let vols = bounded_volumes(&m);
            assert_eq!(vols.len(), 1);
            assert_eq!(
                vols[0].0,
                Label::new(1),
                "the bounded shell faces the inside label"
            );
            let err = (exact - vols[0].1) / exact;
            // Inscribed: always an underestimate, shrinking with every level.
            assert!(
                err > 0.0 && err < last,
                "s = {s}: relative error {err} after {last}"
            );
            if s >= 4 {
                assert!(err < 0.01, "s = {s}: relative error {err}");
            }
            last = err;
        }
    }

    #[test]
    fn bad_parameters_are_refused() {
        let c = DVec3::ZERO;
        assert!(icosphere(10, c, 1.0, labels()).is_err());
        assert!(icosphere(1, c, 0.0, labels()).is_err());
        assert!(icosphere(1, c, -1.0, labels()).is_err());
        assert!(icosphere(1, c, f64::NAN, labels()).is_err());
        assert!(icosphere(1, DVec3::new(f64::INFINITY, 0.0, 0.0), 1.0, labels()).is_err());
        assert!(icosphere(1, c, 1.0, [Label::new(3), Label::new(3)]).is_err());
    }
}
