//! Geometric measures of a [`LabeledMesh`]: per-material volumes, areas, normals and
//! quality figures.
//!
//! Everything here reads positions and never connectivity beyond vertex rings, so it is
//! cheap enough to call every time step (the harness records volumes to measure volume
//! loss; flows need vertex normals). Work over triangles or vertices runs on rayon.
//!
//! **Volumes** come from the divergence theorem over *labelled sides*: the signed volume
//! of the cone from a reference point `r` to triangle `(a, b, c)`,
//! `V = (a−r)·((b−r)×(c−r)) / 6`, is positive when the triangle's right-hand normal points
//! away from `r`. A closed region bounded by triangles that all have it on their *back*
//! (normals pointing out of it) therefore sums to its volume: each triangle adds `+V` to
//! its back label and `−V` to its front label. The outside material (label 0 by
//! convention) surrounds everything and so receives minus the total enclosed volume; the
//! volumes of all labels always sum to zero. The result does not depend on `r` for closed,
//! consistently labelled meshes; `r` is a mesh vertex to keep the products small.

use std::collections::BTreeMap;

use glam::DVec3;
use rayon::prelude::*;
use serde::Serialize;

use crate::ids::{IdVec, Label, TriId, VertexId};
use crate::mesh::LabeledMesh;

/// Triangles per rayon task for per-triangle reductions: large enough that the per-task
/// accumulator is amortised, small enough to balance two to dozens of cores.
const CHUNK: usize = 16 * 1024;

/// Signed volume of the cone from the origin to the triangle `a, b, c`: positive when the
/// right-hand normal `(b−a)×(c−a)` points away from the origin.
#[inline]
pub fn signed_cone_volume(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    a.dot(b.cross(c)) / 6.0
}

/// Area-weighted normal of a triangle: `(b−a)×(c−a) / 2`, whose length is the area.
#[inline]
pub fn area_normal(p: &[DVec3; 3]) -> DVec3 {
    (p[1] - p[0]).cross(p[2] - p[0]) * 0.5
}

/// Area of a triangle.
#[inline]
pub fn triangle_area(p: &[DVec3; 3]) -> f64 {
    area_normal(p).length()
}

/// Unit right-hand normal of a triangle, or zero for a degenerate (or non-finite) one,
/// so callers can sum normals without a NaN poisoning the sum.
#[inline]
pub fn unit_normal(p: &[DVec3; 3]) -> DVec3 {
    let n = area_normal(p).normalize_or_zero();
    if n.is_finite() { n } else { DVec3::ZERO }
}

/// Enclosed volume per label (see the module doc for the sign convention): each live
/// triangle adds its cone volume to its back label and subtracts it from its front label.
///
/// For a closed, consistently labelled mesh every bounded material gets its volume, and
/// the outside label gets minus their sum (the labels always sum to zero). On an open or
/// inconsistent mesh the figures still follow the formula but are not volumes.
pub fn label_volumes(mesh: &LabeledMesh) -> BTreeMap<Label, f64> {
    let tris = mesh.tris();
    let alive = mesh.tri_alive_flags();
    let labels = mesh.label_pairs();
    let positions = mesh.positions();
    let origin = mesh
        .triangles()
        .next()
        .map(|t| positions[tris[t.idx()][0].idx()])
        .unwrap_or(DVec3::ZERO);
    let per_chunk: Vec<Vec<(Label, f64)>> = (0..tris.len())
        .into_par_iter()
        .chunks(CHUNK)
        .map(|range| {
            // A tiny sorted map: there are few labels, and it is allocated once per chunk.
            let mut acc: Vec<(Label, f64)> = Vec::new();
            for t in range {
                if !alive[t] {
                    continue;
                }
                let [a, b, c] = tris[t].map(|v| positions[v.idx()] - origin);
                let v = signed_cone_volume(a, b, c);
                let [front, back] = labels[t];
                add_to(&mut acc, back, v);
                add_to(&mut acc, front, -v);
            }
            acc
        })
        .collect();
    let mut out = BTreeMap::new();
    for acc in per_chunk {
        for (label, v) in acc {
            *out.entry(label).or_insert(0.0) += v;
        }
    }
    out
}

#[inline]
fn add_to(acc: &mut Vec<(Label, f64)>, label: Label, v: f64) {
    match acc.binary_search_by_key(&label, |e| e.0) {
        Ok(i) => acc[i].1 += v,
        Err(i) => acc.insert(i, (label, v)),
    }
}

/// Area of every triangle slot (0 for dead slots).
pub fn triangle_areas(mesh: &LabeledMesh) -> IdVec<TriId, f64> {
    per_triangle(mesh, 0.0, |p| triangle_area(&p))
}

/// Total area of the live triangles, bit-identical for any thread count ([`ordered_sum`]).
pub fn total_area(mesh: &LabeledMesh) -> f64 {
    let alive = mesh.tri_alive_flags();
    ordered_sum(mesh.triangle_capacity(), |t| {
        if alive[t] {
            triangle_area(&mesh.tri_positions(TriId::new(t as u32)))
        } else {
            0.0
        }
    })
}

/// `f(0) + f(1) + … + f(n − 1)` on rayon, bit-identical for any thread count and from run
/// to run: fixed runs of `CHUNK` indices are summed in index order, then the run sums in
/// run order.
///
/// Why not `par_iter().sum()`: rayon associates a float sum along its work-stealing
/// splits, which depend on the number of threads and on timing, so the last bits of the
/// result vary. A mean edge length that differs in its last bit moves the split and
/// collapse thresholds, and a whole run of a tracker then takes different edits. Use this
/// for every float sum that can reach a decision.
pub fn ordered_sum(n: usize, f: impl Fn(usize) -> f64 + Sync) -> f64 {
    let runs: Vec<f64> = (0..n.div_ceil(CHUNK))
        .into_par_iter()
        .map(|r| (r * CHUNK..n.min((r + 1) * CHUNK)).map(&f).sum())
        .collect();
    runs.into_iter().sum()
}

/// Unit right-hand normal of every triangle slot (zero for dead or degenerate ones).
pub fn face_normals(mesh: &LabeledMesh) -> IdVec<TriId, DVec3> {
    per_triangle(mesh, DVec3::ZERO, |p| unit_normal(&p))
}

/// Area-weighted right-hand normal `(b−a)×(c−a)/2` of every triangle slot (zero for dead
/// slots).
pub fn area_weighted_face_normals(mesh: &LabeledMesh) -> IdVec<TriId, DVec3> {
    per_triangle(mesh, DVec3::ZERO, |p| area_normal(&p))
}

/// Unit vertex normals: the normalised sum of the area-weighted normals of the incident
/// triangles, *as oriented* (right-hand rule). Orient the mesh consistently (e.g. every
/// triangle with the outside label in front) for these to mean "outward"; at a
/// non-manifold vertex the sum mixes sheets and may cancel. Zero for dead, isolated or
/// cancelling vertices.
pub fn vertex_normals(mesh: &LabeledMesh) -> IdVec<VertexId, DVec3> {
    let face = area_weighted_face_normals(mesh);
    let face = face.as_slice();
    let normals = (0..mesh.vertex_capacity())
        .into_par_iter()
        .with_min_len(1024)
        .map(|v| {
            let v = VertexId::new(v as u32);
            if !mesh.is_vertex_alive(v) {
                return DVec3::ZERO;
            }
            let sum: DVec3 = mesh.vertex_corners(v).map(|c| face[c.tri().idx()]).sum();
            let n = sum.normalize_or_zero();
            if n.is_finite() { n } else { DVec3::ZERO }
        })
        .collect();
    IdVec::from_vec(normals)
}

fn per_triangle<T: Send + Sync + Copy>(
    mesh: &LabeledMesh,
    dead: T,
    f: impl Fn([DVec3; 3]) -> T + Sync,
) -> IdVec<TriId, T> {
    let alive = mesh.tri_alive_flags();
    let values = (0..mesh.triangle_capacity())
        .into_par_iter()
        .with_min_len(1024)
        .map(|t| {
            if alive[t] {
                f(mesh.tri_positions(TriId::new(t as u32)))
            } else {
                dead
            }
        })
        .collect();
    IdVec::from_vec(values)
}

/// The smallest interior angle of a triangle, in radians (0 for a degenerate one).
#[inline]
pub fn triangle_min_angle(p: &[DVec3; 3]) -> f64 {
    (0..3)
        .map(|k| {
            let (u, w) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
            // atan2(|u×w|, u·w) is accurate at every angle, unlike acos of a cosine.
            u.cross(w).length().atan2(u.dot(w))
        })
        .fold(f64::INFINITY, f64::min)
}

/// Mesh quality figures, for reports and for choosing remeshing thresholds.
///
/// Angles are in degrees. Edge lengths are taken per triangle edge, so an edge shared by
/// `k` triangles counts `k` times in the mean (for a closed manifold mesh every edge counts
/// twice and the mean equals the mean over distinct edges). Triangles with a non-finite
/// coordinate are skipped and counted. With no measurable triangle every figure is 0.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct QualityStats {
    /// Live triangles measured (finite coordinates).
    pub triangles: usize,
    /// Live triangles skipped because a coordinate is NaN or infinite.
    pub skipped_non_finite: usize,
    /// Smallest interior angle over all measured triangles, in degrees.
    pub min_angle_deg: f64,
    /// Largest interior angle over all measured triangles, in degrees.
    pub max_angle_deg: f64,
    /// Shortest triangle edge.
    pub min_edge: f64,
    /// Longest triangle edge.
    pub max_edge: f64,
    /// Mean triangle edge length (per triangle edge, see the type doc).
    pub mean_edge: f64,
    /// Smallest triangle area.
    pub min_area: f64,
    /// Largest triangle area.
    pub max_area: f64,
}

#[derive(Clone, Copy)]
struct QualityAcc {
    triangles: usize,
    skipped: usize,
    min_angle: f64,
    max_angle: f64,
    min_edge: f64,
    max_edge: f64,
    min_area: f64,
    max_area: f64,
}

impl QualityAcc {
    const EMPTY: QualityAcc = QualityAcc {
        triangles: 0,
        skipped: 0,
        min_angle: f64::INFINITY,
        max_angle: f64::NEG_INFINITY,
        min_edge: f64::INFINITY,
        max_edge: f64::NEG_INFINITY,
        min_area: f64::INFINITY,
        max_area: f64::NEG_INFINITY,
    };

    fn add(mut self, p: &[DVec3; 3]) -> Self {
        if !p.iter().all(|q| q.is_finite()) {
            self.skipped += 1;
            return self;
        }
        self.triangles += 1;
        for k in 0..3 {
            let (a, b, c) = (p[k], p[(k + 1) % 3], p[(k + 2) % 3]);
            let (u, w) = (b - a, c - a);
            // atan2(|u×w|, u·w) is accurate at every angle, unlike acos of a cosine.
            let angle = u.cross(w).length().atan2(u.dot(w));
            self.min_angle = self.min_angle.min(angle);
            self.max_angle = self.max_angle.max(angle);
            let len = u.length();
            self.min_edge = self.min_edge.min(len);
            self.max_edge = self.max_edge.max(len);
        }
        let area = triangle_area(p);
        self.min_area = self.min_area.min(area);
        self.max_area = self.max_area.max(area);
        self
    }

    fn merge(self, o: Self) -> Self {
        QualityAcc {
            triangles: self.triangles + o.triangles,
            skipped: self.skipped + o.skipped,
            min_angle: self.min_angle.min(o.min_angle),
            max_angle: self.max_angle.max(o.max_angle),
            min_edge: self.min_edge.min(o.min_edge),
            max_edge: self.max_edge.max(o.max_edge),
            min_area: self.min_area.min(o.min_area),
            max_area: self.max_area.max(o.max_area),
        }
    }

    /// The figures, with `edge_sum` the sum of the counted triangles' edge lengths.
    fn finish(self, edge_sum: f64) -> QualityStats {
        if self.triangles == 0 {
            return QualityStats {
                triangles: 0,
                skipped_non_finite: self.skipped,
                min_angle_deg: 0.0,
                max_angle_deg: 0.0,
                min_edge: 0.0,
                max_edge: 0.0,
                mean_edge: 0.0,
                min_area: 0.0,
                max_area: 0.0,
            };
        }
        QualityStats {
            triangles: self.triangles,
            skipped_non_finite: self.skipped,
            min_angle_deg: self.min_angle.to_degrees(),
            max_angle_deg: self.max_angle.to_degrees(),
            min_edge: self.min_edge,
            max_edge: self.max_edge,
            mean_edge: edge_sum / (3 * self.triangles) as f64,
            min_area: self.min_area,
            max_area: self.max_area,
        }
    }
}

/// Quality figures over the live triangles (see [`QualityStats`]).
///
/// The extremes and counts are folded in parallel in any order; the edge-length sum
/// behind the mean goes through [`ordered_sum`], so the figures do not depend on the
/// thread count.
pub fn quality(mesh: &LabeledMesh) -> QualityStats {
    let alive = mesh.tri_alive_flags();
    let acc = (0..mesh.triangle_capacity())
        .into_par_iter()
        .with_min_len(1024)
        .filter(|&t| alive[t])
        .fold(
            || QualityAcc::EMPTY,
            |acc, t| acc.add(&mesh.tri_positions(TriId::new(t as u32))),
        )
        .reduce(|| QualityAcc::EMPTY, QualityAcc::merge);
    let edge_sum = ordered_sum(mesh.triangle_capacity(), |t| {
        if !alive[t] {
            return 0.0;
        }
        let p = mesh.tri_positions(TriId::new(t as u32));
        if p.iter().all(|q| q.is_finite()) {
            (0..3).map(|k| p[k].distance(p[(k + 1) % 3])).sum()
        } else {
            0.0
        }
    });
    acc.finish(edge_sum)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    fn l(i: u32) -> Label {
        Label::new(i)
    }

    #[test]
    fn ordered_sum_is_bit_identical_for_any_thread_count() {
        // Terms of very different magnitudes, so that any change of association changes
        // the last bits; a plain rayon sum fails the reference comparison below.
        let f = |i: usize| {
            ((i * 7919) % 1000) as f64 * 1e-3 + if i.is_multiple_of(97) { 1e9 } else { 0.0 }
        };
        let n = 5 * CHUNK + 7;
        let reference: f64 = (0..n)
            .collect::<Vec<_>>()
            .chunks(CHUNK)
            .map(|c| c.iter().map(|&i| f(i)).sum::<f64>())
            .sum();
        for threads in [1, 2, 3, 4] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            for _ in 0..3 {
                let got = pool.install(|| ordered_sum(n, f));
                assert_eq!(got.to_bits(), reference.to_bits(), "{threads} threads");
            }
        }
        assert_eq!(ordered_sum(0, f), 0.0);
    }

    /// Unit right tetrahedron, every right-hand normal pointing outwards; front = 0
    /// (outside), back = `inside`.
    fn tetra(offset: DVec3, inside: u32) -> (Vec<DVec3>, Vec<[u32; 3]>, Vec<[u32; 2]>) {
        let p = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z]
            .into_iter()
            .map(|q| q + offset)
            .collect();
        let t = vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        (p, t, vec![[0, inside]; 4])
    }

    #[test]
    fn cone_volume_sign_matches_outward_normals() {
        // The face opposite the origin of the unit tetrahedron, normal (1,1,1) outwards.
        assert_relative_eq!(signed_cone_volume(DVec3::X, DVec3::Y, DVec3::Z), 1.0 / 6.0);
        let (p, t, _) = tetra(DVec3::ZERO, 1);
        for tri in &t {
            let [a, b, c] = tri.map(|i| p[i as usize]);
            let centroid = (p[0] + p[1] + p[2] + p[3]) / 4.0;
            // Outward: the normal points away from the centroid.
            assert!((b - a).cross(c - a).dot(a - centroid) > 0.0);
        }
    }

    #[test]
    fn tetrahedron_volume_per_label_independent_of_position() {
        for offset in [DVec3::ZERO, DVec3::new(10.0, -3.0, 7.5)] {
            let (p, t, lab) = tetra(offset, 1);
            let mesh = LabeledMesh::from_raw(p, &t, &lab).unwrap();
            let vols = label_volumes(&mesh);
            assert_eq!(vols.len(), 2);
            assert_relative_eq!(vols[&l(1)], 1.0 / 6.0, epsilon = 1e-12);
            assert_relative_eq!(vols[&l(0)], -1.0 / 6.0, epsilon = 1e-12);
        }
    }

    /// Unit cube `[0,1]³` split by the plane x = 0.5 into label 1 (x < 0.5) and label 2;
    /// outside 0. Built from quads, each split into two triangles with the given normal.
    fn split_cube() -> LabeledMesh {
        let mut pos = Vec::new();
        let mut tris = Vec::new();
        let mut labels = Vec::new();
        let mut quad = |q: [DVec3; 4], lab: [u32; 2]| {
            let base = pos.len() as u32;
            pos.extend_from_slice(&q);
            tris.push([base, base + 1, base + 2]);
            tris.push([base, base + 2, base + 3]);
            labels.push(lab);
            labels.push(lab);
        };
        let v = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
        // Quads given counter-clockwise seen from where the normal points.
        for (x0, x1, inside) in [(0.0, 0.5, 1), (0.5, 1.0, 2)] {
            // y = 0 (normal −y), y = 1 (+y), z = 0 (−z), z = 1 (+z).
            quad(
                [v(x0, 0., 0.), v(x1, 0., 0.), v(x1, 0., 1.), v(x0, 0., 1.)],
                [0, inside],
            );
            quad(
                [v(x0, 1., 0.), v(x0, 1., 1.), v(x1, 1., 1.), v(x1, 1., 0.)],
                [0, inside],
            );
            quad(
                [v(x0, 0., 0.), v(x0, 1., 0.), v(x1, 1., 0.), v(x1, 0., 0.)],
                [0, inside],
            );
            quad(
                [v(x0, 0., 1.), v(x1, 0., 1.), v(x1, 1., 1.), v(x0, 1., 1.)],
                [0, inside],
            );
        }
        // x = 0 (normal −x, label 1 behind), x = 1 (+x, label 2 behind).
        quad(
            [v(0., 0., 0.), v(0., 0., 1.), v(0., 1., 1.), v(0., 1., 0.)],
            [0, 1],
        );
        quad(
            [v(1., 0., 0.), v(1., 1., 0.), v(1., 1., 1.), v(1., 0., 1.)],
            [0, 2],
        );
        // x = 0.5, normal +x: label 2 in front, label 1 behind.
        quad(
            [
                v(0.5, 0., 0.),
                v(0.5, 1., 0.),
                v(0.5, 1., 1.),
                v(0.5, 0., 1.),
            ],
            [2, 1],
        );
        LabeledMesh::from_raw(pos, &tris, &labels).unwrap()
    }

    #[test]
    fn split_cube_volumes_and_area() {
        let mesh = split_cube();
        let vols = label_volumes(&mesh);
        assert_relative_eq!(vols[&l(1)], 0.5, epsilon = 1e-12);
        assert_relative_eq!(vols[&l(2)], 0.5, epsilon = 1e-12);
        assert_relative_eq!(vols[&l(0)], -1.0, epsilon = 1e-12);
        // Six unit faces plus the internal wall.
        assert_relative_eq!(total_area(&mesh), 7.0, epsilon = 1e-12);
        let areas = triangle_areas(&mesh);
        assert!(
            areas
                .as_slice()
                .iter()
                .all(|&a| (a - 0.25).abs() < 1e-12 || (a - 0.5).abs() < 1e-12)
        );
    }

    #[test]
    fn dead_triangles_do_not_count() {
        let (p, t, lab) = tetra(DVec3::ZERO, 1);
        let mut mesh = LabeledMesh::from_raw(p, &t, &lab).unwrap();
        mesh.remove_triangle(TriId::new(3)).unwrap();
        // Only the three faces through the origin remain: zero cone volume about vertex 0.
        let vols = label_volumes(&mesh);
        assert_relative_eq!(vols[&l(1)], 0.0, epsilon = 1e-15);
        assert_eq!(triangle_areas(&mesh)[TriId::new(3)], 0.0);
        assert_relative_eq!(total_area(&mesh), 1.5, epsilon = 1e-12);
    }

    #[test]
    fn normals_point_outwards_on_tetrahedron() {
        let (p, t, lab) = tetra(DVec3::ZERO, 1);
        let mesh = LabeledMesh::from_raw(p, &t, &lab).unwrap();
        let n = face_normals(&mesh);
        assert_relative_eq!(n[TriId::new(0)].z, -1.0, epsilon = 1e-15);
        let s = 1.0 / 3f64.sqrt();
        let n3 = n[TriId::new(3)];
        assert_relative_eq!(n3.x, s, epsilon = 1e-15);
        assert_relative_eq!(n3.y, s, epsilon = 1e-15);
        let aw = area_weighted_face_normals(&mesh);
        assert_relative_eq!(
            aw[TriId::new(3)].length(),
            3f64.sqrt() / 2.0,
            epsilon = 1e-15
        );
        let vn = vertex_normals(&mesh);
        // At the origin the three unit-area-½ faces have normals −x, −y, −z.
        let v0 = vn[VertexId::new(0)];
        assert_relative_eq!(v0.x, -s, epsilon = 1e-15);
        assert_relative_eq!(v0.y, -s, epsilon = 1e-15);
        assert_relative_eq!(v0.z, -s, epsilon = 1e-15);
        // At (1,0,0): faces with normals −y (area ½), −z (½), and (1,1,1)/√3 (√3/2).
        let v1 = vn[VertexId::new(1)];
        let expect = (DVec3::new(0.0, -0.5, 0.0) + DVec3::new(0.0, 0.0, -0.5) + DVec3::splat(0.5))
            .normalize();
        assert_relative_eq!(v1.distance(expect), 0.0, epsilon = 1e-15);
    }

    #[test]
    fn quality_of_tetrahedron() {
        let (p, t, lab) = tetra(DVec3::ZERO, 1);
        let mesh = LabeledMesh::from_raw(p, &t, &lab).unwrap();
        let q = quality(&mesh);
        assert_eq!(q.triangles, 4);
        assert_relative_eq!(q.min_angle_deg, 45.0, epsilon = 1e-12);
        assert_relative_eq!(q.max_angle_deg, 90.0, epsilon = 1e-12);
        assert_relative_eq!(q.min_edge, 1.0, epsilon = 1e-15);
        assert_relative_eq!(q.max_edge, 2f64.sqrt(), epsilon = 1e-15);
        // Three unit edges and three √2 edges, each counted twice.
        assert_relative_eq!(
            q.mean_edge,
            (3.0 + 3.0 * 2f64.sqrt()) / 6.0,
            epsilon = 1e-15
        );
        assert_relative_eq!(q.min_area, 0.5, epsilon = 1e-15);
        assert_relative_eq!(q.max_area, 3f64.sqrt() / 2.0, epsilon = 1e-15);
    }

    #[test]
    fn quality_skips_non_finite_and_handles_empty() {
        let (mut p, t, lab) = tetra(DVec3::ZERO, 1);
        p[3].z = f64::NAN;
        let mesh = LabeledMesh::from_raw(p, &t, &lab).unwrap();
        let q = quality(&mesh);
        assert_eq!((q.triangles, q.skipped_non_finite), (1, 3));
        assert_relative_eq!(q.min_angle_deg, 45.0, epsilon = 1e-12);
        let empty = quality(&LabeledMesh::new());
        assert_eq!(empty.triangles, 0);
        assert_eq!(empty.min_edge, 0.0);
        assert!(label_volumes(&LabeledMesh::new()).is_empty());
    }
}
