//! The double bubble: two equal soap bubbles merged along a shared wall.
//!
//! Geometry (Plateau's laws for equal bubbles of radius r): the shared wall is a flat disk
//! and each outer film a spherical cap of radius r. Three films meeting along a curve must
//! make equal 120° angles, so their unit tangents there (pointing away from the curve)
//! sum to zero. With cap centres at `(∓d/2, 0, 0)` the triple circle lies in the plane
//! `x = 0` at radius `ρ = √(r² − d²/4)`; at the triple point `(0, ρ, 0)` the tangents
//! are `(−ρ, d/2)/r`, `(ρ, d/2)/r` (the caps) and `(0, −1)` (the wall), which sum to zero
//! exactly when `d = r`. So the centres are `r` apart, `ρ = r·√3/2`, and each cap spans
//! polar angles `0..120°` from its pole. Each bubble encloses the ball minus a cap of
//! height `r/2`: `9πr³/8`.
//!
//! Meshing: each of the three surfaces is a stack of rings (the wall around its centre,
//! each cap around its pole) ending on the same `N` triple-circle vertices, so all three
//! share exactly those vertices and edges. Ring spacing and ring sizes follow the
//! triple-circle edge length `h = 2πρ/N`, giving near-uniform triangles. Consecutive rings
//! are joined by a zipper that always advances on the ring whose next vertex comes first
//! in angle.
//!
//! Labels: outside 0, left bubble (x < 0) 1, right bubble 2.

use std::f64::consts::{PI, TAU};

use glam::DVec3;

use super::error::{GeneratorError, check_positive, invalid};
use crate::mesh::LabeledMesh;

/// Angular extent of each cap, from its pole to the triple circle.
const CAP_ANGLE: f64 = 2.0 * PI / 3.0;

/// One ring of a surface: vertex ids and their angles about the x axis, increasing in
/// `[0, 2π)`.
struct Ring {
    ids: Vec<u32>,
    angles: Vec<f64>,
}

impl Ring {
    /// Unwrapped angle of the `i`-th vertex, `i ≤ len` (index `len` is vertex 0 plus 2π).
    fn angle(&self, i: usize) -> f64 {
        let n = self.ids.len();
        self.angles[i % n] + TAU * (i / n) as f64
    }

    fn id(&self, i: usize) -> u32 {
        self.ids[i % self.ids.len()]
    }
}

/// Triangles between an inner ring and the next outer one. Every triangle is
/// counter-clockwise in the `(angle, ring)` parameter plane, so all triangles of one
/// surface share an orientation.
fn zip(inner: &Ring, outer: &Ring, tris: &mut Vec<[u32; 3]>) {
    let (na, nb) = (inner.ids.len(), outer.ids.len());
    if na == 1 {
        for j in 0..nb {
            tris.push([inner.ids[0], outer.id(j + 1), outer.id(j)]);
        }
        return;
    }
    let (mut i, mut j) = (0, 0);
    while i < na || j < nb {
        let advance_inner = j == nb || (i < na && inner.angle(i + 1) < outer.angle(j + 1));
        if advance_inner {
            tris.push([inner.id(i), inner.id(i + 1), outer.id(j)]);
            i += 1;
        } else {
            tris.push([inner.id(i), outer.id(j + 1), outer.id(j)]);
            j += 1;
        }
    }
}

/// Builds one surface of revolution about the x axis from its profile: `profile(s)`
/// gives `(x, ring radius)` for `s ∈ [0, 1]`, with ring radius 0 at `s = 0` (a pole).
/// The last ring is `rim`, shared with the other surfaces. `rings` is the number of rings
/// after the pole and `count(s)` the vertex count of an inner ring.
fn surface_of_revolution(
    profile: impl Fn(f64) -> (f64, f64),
    rings: usize,
    count: impl Fn(f64) -> usize,
    rim: &Ring,
    positions: &mut Vec<DVec3>,
    tris: &mut Vec<[u32; 3]>,
) {
    let (x0, _) = profile(0.0);
    positions.push(DVec3::new(x0, 0.0, 0.0));
    let mut prev = Ring {
        ids: vec![(positions.len() - 1) as u32],
        angles: vec![0.0],
    };
    for k in 1..rings {
        let s = k as f64 / rings as f64;
        let (x, rho) = profile(s);
        let n = count(s).max(3);
        // Alternate half-step offsets so consecutive rings interleave.
        let offset = 0.5 * (k % 2) as f64;
        let angles: Vec<f64> = (0..n)
            .map(|j| TAU * (j as f64 + offset) / n as f64)
            .collect();
        let ids = angles
            .iter()
            .map(|&a| {
                positions.push(DVec3::new(x, rho * a.cos(), rho * a.sin()));
                (positions.len() - 1) as u32
            })
            .collect();
        let ring = Ring { ids, angles };
        zip(&prev, &ring, tris);
        prev = ring;
    }
    zip(&prev, rim, tris);
}

/// Labels `[front, back]` for a surface whose triangles share one orientation: `front`
/// is the material on the side `outward(centroid)` points to if the normals agree with it.
fn oriented_labels(
    tris: &[[u32; 3]],
    positions: &[DVec3],
    outward: impl Fn(DVec3) -> DVec3,
    [towards, away]: [u32; 2],
) -> [u32; 2] {
    let agreement: f64 = tris
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| positions[v as usize]);
            (b - a).cross(c - a).dot(outward((a + b + c) / 3.0))
        })
        .sum();
    if agreement > 0.0 {
        [towards, away]
    } else {
        [away, towards]
    }
}

/// Two equal bubbles of the given `radius` around the origin, merged along a flat wall in
/// the plane `x = 0` (see the module doc for the 120° geometry). `resolution` is the
/// number of segments around the triple circle (at least 3); the other edges have about
/// the same length. Labels: 0 outside, 1 the bubble at `x < 0`, 2 the bubble at `x > 0`.
pub fn double_bubble(radius: f64, resolution: usize) -> Result<LabeledMesh, GeneratorError> {
    const NAME: &str = "double_bubble";
    check_positive(NAME, "radius", radius)?;
    if !(3..=1 << 20).contains(&resolution) {
        return Err(invalid(
            NAME,
            "resolution",
            resolution,
            "between 3 and 2^20",
        ));
    }
    let r = radius;
    let n = resolution;
    let rho = r * 3f64.sqrt() / 2.0;
    let h = TAU * rho / n as f64;
    let ring_count = |length: f64| ((length / h).round() as usize).max(1);

    let mut positions = Vec::new();
    let rim_angles: Vec<f64> = (0..n).map(|i| TAU * i as f64 / n as f64).collect();
    for &a in &rim_angles {
        positions.push(DVec3::new(0.0, rho * a.cos(), rho * a.sin()));
    }
    let rim = Ring {
        ids: (0..n as u32).collect(),
        angles: rim_angles,
    };

    let mut surfaces: [Vec<[u32; 3]>; 3] = Default::default();
    // The wall: a disk of radius ρ, ring radius proportional to s.
    surface_of_revolution(
        |s| (0.0, rho * s),
        ring_count(rho),
        |s| (n as f64 * s).round() as usize,
        &rim,
        &mut positions,
        &mut surfaces[0],
    );
    // The caps: polar angle θ = s·120° from the pole at x = ∓3r/2.
    let cap_rings = ring_count(r * CAP_ANGLE);
    let cap_count = |s: f64| (n as f64 * (s * CAP_ANGLE).sin() / CAP_ANGLE.sin()).round() as usize;
    for (side, surface) in [(-1.0, 1), (1.0, 2)] {
        let profile = |s: f64| {
            let theta = s * CAP_ANGLE;
            (side * (r / 2.0 + r * theta.cos()), r * theta.sin())
        };
        surface_of_revolution(
            profile,
            cap_rings,
            cap_count,
            &rim,
            &mut positions,
            &mut surfaces[surface],
        );
    }

    let left_centre = DVec3::new(-r / 2.0, 0.0, 0.0);
    let right_centre = DVec3::new(r / 2.0, 0.0, 0.0);
    let pairs = [
        oriented_labels(&surfaces[0], &positions, |_| DVec3::X, [2, 1]),
        oriented_labels(&surfaces[1], &positions, |p| p - left_centre, [0, 1]),
        oriented_labels(&surfaces[2], &positions, |p| p - right_centre, [0, 2]),
    ];
    let mut tris = Vec::new();
    let mut labels = Vec::new();
    for (surface, pair) in surfaces.iter().zip(pairs) {
        tris.extend_from_slice(surface);
        labels.extend(std::iter::repeat_n(pair, surface.len()));
    }
    Ok(LabeledMesh::from_raw(positions, &tris, &labels)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::connectivity::EdgeTable;
    use crate::generators::checks::{assert_well_formed, volume_per_label};
    use crate::ids::Label;

    #[test]
    fn is_well_formed_at_several_resolutions() {
        for n in [3, 4, 7, 12, 24] {
            let m = double_bubble(1.0, n).unwrap();
            assert_well_formed(&m);
            assert_eq!(m.label_set(), [0, 1, 2].map(Label::new), "resolution {n}");
        }
    }

    #[test]
    fn triple_curve_is_a_circle_of_n_edges() {
        let r = 2.0;
        let n = 20;
        let m = double_bubble(r, n).unwrap();
        let table = EdgeTable::build(m.tris(), m.tri_alive_flags(), m.vertex_capacity());
        let mut degree = vec![0; m.vertex_capacity()];
        let mut triple = 0;
        for g in table.groups() {
            assert!(
                g.len() == 2 || g.len() == 3,
                "edge with {} triangles",
                g.len()
            );
            if g.len() == 3 {
                triple += 1;
                let mut pairs: Vec<[u32; 2]> = g
                    .iter()
                    .map(|e| {
                        let mut p = m.labels(e.tri).map(|l| l.raw());
                        p.sort_unstable();
                        p
                    })
                    .collect();
                pairs.sort_unstable();
                assert_eq!(pairs, [[0, 1], [0, 2], [1, 2]]);
                for v in [g[0].lo, g[0].hi] {
                    degree[v.idx()] += 1;
                    let p = m.position(v);
                    assert!(p.x.abs() < 1e-15);
                    assert!((p.length() - r * 3f64.sqrt() / 2.0).abs() < 1e-12);
                }
            }
        }
        assert_eq!(triple, n);
        assert!(degree.iter().all(|&d| d == 0 || d == 2));
    }

    #[test]
    fn films_meet_at_120_degrees() {
        // Away from the discretisation, the exact surfaces meet at 120°: check it on the
        // triangles at a triple edge, whose dihedral angles approach 120° as n grows.
        let m = double_bubble(1.0, 128).unwrap();
        let table = EdgeTable::build(m.tris(), m.tri_alive_flags(), m.vertex_capacity());
        let g = table.groups().find(|g| g.len() == 3).unwrap();
        let (a, b) = (m.position(g[0].lo), m.position(g[0].hi));
        let axis = (b - a).normalize();
        let dirs: Vec<DVec3> = g
            .iter()
            .map(|e| {
                let w = m.position(m.tri(e.tri)[e.slot as usize]) - a;
                (w - axis * axis.dot(w)).normalize()
            })
            .collect();
        for i in 0..3 {
            for j in 0..i {
                let angle = dirs[i].dot(dirs[j]).clamp(-1.0, 1.0).acos().to_degrees();
                assert!((angle - 120.0).abs() < 3.0, "angle {angle}");
            }
        }
    }

    #[test]
    fn bubbles_have_equal_volume_converging_to_9_pi_r3_over_8() {
        let r = 0.8;
        let exact = 9.0 * PI * r * r * r / 8.0;
        let mut last = f64::INFINITY;
        for n in [8, 16, 32, 64] {
            let vols = volume_per_label(&double_bubble(r, n).unwrap());
            assert_eq!(vols.len(), 2);
            let (v1, v2) = (vols[&Label::new(1)], vols[&Label::new(2)]);
            assert!(v1 > 0.0 && ((v1 - v2) / v1).abs() < 1e-12, "{v1} vs {v2}");
            let err = (exact - v1) / exact;
            assert!(err > 0.0 && err < last, "n = {n}: error {err} after {last}");
            last = err;
        }
        assert!(last < 0.01, "error {last} at n = 64");
    }

    #[test]
    fn bad_parameters_are_refused() {
        assert!(double_bubble(0.0, 10).is_err());
        assert!(double_bubble(f64::NAN, 10).is_err());
        assert!(double_bubble(-1.0, 10).is_err());
        assert!(double_bubble(1.0, 2).is_err());
    }
}
