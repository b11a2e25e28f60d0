//! How much of the original surface a run kept: the feature-preservation measures of the
//! 2024 paper's Fig. 17 and of `bench ablate`.
//!
//! **Untouched fraction.** A triangle of the final mesh is *untouched* when it is an
//! initial triangle carried along by the scene's rigid motion and never resampled: its
//! three vertices lie within `tolerance` of the expected positions of the three vertices
//! of one initial triangle, with the same label pair. (Bit identity is out of reach even
//! for an untouched triangle: a rigid motion applied step by step rounds differently from
//! the same motion applied at once; `tolerance` is 10⁻⁹ of the scene size, a million
//! times below any resampling change, which moves vertices by a fraction of ℓ.) The
//! fraction is over the final triangles. For scenes without a rigid reference the
//! expected positions are the initial ones: there it counts triangles the run never moved.
//!
//! **Feature distance.** For every final vertex, the distance to the nearest triangle of
//! the rigidly moved original surface (searched within `search`, so larger distances are
//! capped at it), skipping vertices whose nearest original triangle is in the contact
//! zone (where the scene changes topology and the surface must change). Mean and maximum
//! are reported.

use std::collections::{HashMap, HashSet};

use glam::DVec3;
use mesh_core::broadphase::{Aabb, Bvh};
use mesh_core::{LabeledMesh, TriId};
use serde::{Deserialize, Serialize};

/// What [`measure`] found.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Preservation {
    /// Triangles of the final mesh.
    pub final_triangles: usize,
    /// Of those, the untouched ones (see the module doc).
    pub untouched_triangles: usize,
    /// `untouched_triangles / final_triangles` (0 for an empty mesh).
    pub untouched_fraction: f64,
    /// Mean distance of final vertices outside the contact zone to the moved original;
    /// `None` without a rigid reference.
    pub feature_distance_mean: Option<f64>,
    /// Largest such distance (capped at the search radius).
    pub feature_distance_max: Option<f64>,
    /// Final vertices the distance was measured on.
    pub feature_vertices: usize,
}

/// The reference a final mesh is compared with: the initial mesh, where each of its
/// vertices is expected now, and which initial vertices lie in the contact zone.
pub struct Reference<'a> {
    /// The initial mesh (connectivity and labels).
    pub initial: &'a LabeledMesh,
    /// Expected position of every initial vertex slot now.
    pub expected: Vec<DVec3>,
    /// Contact-zone flag per initial vertex slot; `None`: no rigid reference, no
    /// distance measure.
    pub contact: Option<Vec<bool>>,
}

/// Integer key of a point on a grid of spacing `h`.
fn key(p: DVec3, h: f64) -> [i64; 3] {
    let q = (p / h).floor();
    [q.x as i64, q.y as i64, q.z as i64]
}

/// Distance from `p` to triangle `abc` (Ericson's closest-point regions).
fn distance_point_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return p.distance(a);
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return p.distance(b);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return p.distance(a + ab * v);
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return p.distance(c);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return p.distance(a + ac * w);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return p.distance(b + (c - b) * w);
    }
    let denom = 1.0 / (va + vb + vc);
    let (v, w) = (vb * denom, vc * denom);
    p.distance(a + ab * v + ac * w)
}

/// Compares `last` with the reference (see the module doc). `tolerance`: vertex match
/// distance; `search`: cap of the feature distance.
pub fn measure(
    reference: &Reference<'_>,
    last: &LabeledMesh,
    tolerance: f64,
    search: f64,
) -> Preservation {
    let initial = reference.initial;
    let expected = &reference.expected;
    // Expected initial vertices, hashed on a grid of spacing `tolerance`, each position
    // once (the lowest id at it, the one the nearest-first search below picks among
    // equals). Why once: a file with 200 000 vertices at one point (unused, or pinched
    // parts touching there) put them all in one bucket, every lookup scanned it, and
    // `run` on a 1280-triangle sphere with them took minutes.
    let h = tolerance.max(f64::MIN_POSITIVE);
    let mut buckets: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
    let mut positions: HashSet<[u64; 3]> = HashSet::new();
    for v in initial.vertices() {
        if !positions.insert(expected[v.idx()].to_array().map(f64::to_bits)) {
            continue;
        }
        buckets
            .entry(key(expected[v.idx()], h))
            .or_default()
            .push(v.idx() as u32);
    }
    let find = |p: DVec3| -> Option<u32> {
        let k = key(p, h);
        let mut best: Option<(f64, u32)> = None;
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let Some(list) = buckets.get(&[k[0] + dx, k[1] + dy, k[2] + dz]) else {
                        continue;
                    };
                    for &v in list {
                        let d = expected[v as usize].distance(p);
                        if d <= tolerance && best.is_none_or(|b| d < b.0) {
                            best = Some((d, v));
                        }
                    }
                }
            }
        }
        best.map(|b| b.1)
    };
    // Initial triangles by sorted vertex triple, with their oriented triple and labels.
    let mut triangles: HashMap<[u32; 3], ([u32; 3], [u32; 2])> = HashMap::new();
    for t in initial.triangles() {
        let tri = initial.tri(t).map(|v| v.idx() as u32);
        let labels = initial.labels(t).map(|l| l.raw());
        let mut sorted = tri;
        sorted.sort_unstable();
        triangles.insert(sorted, (tri, labels));
    }
    let mut matched: Vec<Option<u32>> = vec![None; last.vertex_capacity()];
    for v in last.vertices() {
        matched[v.idx()] = find(last.position(v));
    }
    let mut untouched = 0usize;
    for t in last.triangles() {
        let tri = last.tri(t);
        let Some(m) = tri
            .iter()
            .map(|v| matched[v.idx()])
            .collect::<Option<Vec<u32>>>()
        else {
            continue;
        };
        let mut sorted = [m[0], m[1], m[2]];
        sorted.sort_unstable();
        let labels = last.labels(t).map(|l| l.raw());
        if let Some((orig, orig_labels)) = triangles.get(&sorted) {
            // Same orientation (a cyclic shift) and labels, or reversed with swapped labels.
            let cyc = (0..3).any(|s| (0..3).all(|k| orig[k] == m[(k + s) % 3]));
            let same = cyc && *orig_labels == labels;
            let flipped = !cyc && *orig_labels == [labels[1], labels[0]];
            if same || flipped {
                untouched += 1;
            }
        }
    }
    let final_triangles = last.num_triangles();
    let mut out = Preservation {
        final_triangles,
        untouched_triangles: untouched,
        untouched_fraction: if final_triangles == 0 {
            0.0
        } else {
            untouched as f64 / final_triangles as f64
        },
        ..Preservation::default()
    };
    let Some(contact) = &reference.contact else {
        return out;
    };
    // Feature distance through a BVH over the moved original triangles.
    let ids: Vec<TriId> = initial.triangles().collect();
    let boxes: Vec<Aabb> = ids
        .iter()
        .map(|&t| Aabb::from_points(&initial.tri(t).map(|v| expected[v.idx()])))
        .collect();
    let Ok(bvh) = Bvh::build(&boxes) else {
        return out;
    };
    let (mut sum, mut max, mut n) = (0.0f64, 0.0f64, 0usize);
    for v in last.vertices() {
        let p = last.position(v);
        let query = Aabb::new(p, p);
        let mut best: Option<(f64, usize)> = None;
        bvh.query(&query, search, |i| {
            let t = ids[i as usize];
            let [a, b, c] = initial.tri(t).map(|v| expected[v.idx()]);
            let d = distance_point_triangle(p, a, b, c);
            if best.is_none_or(|x| d < x.0) {
                best = Some((d, i as usize));
            }
        });
        let d = match best {
            Some((d, i)) => {
                if initial.tri(ids[i]).iter().any(|v| contact[v.idx()]) {
                    continue;
                }
                d.min(search)
            }
            None => search,
        };
        sum += d;
        max = max.max(d);
        n += 1;
    }
    if n > 0 {
        out.feature_distance_mean = Some(sum / n as f64);
        out.feature_distance_max = Some(max);
    }
    out.feature_vertices = n;
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use mesh_core::Label;
    use mesh_core::generators::icosphere;

    #[test]
    fn a_rigidly_moved_mesh_is_untouched_and_a_moved_vertex_touches_its_ring() {
        let mesh = icosphere(2, DVec3::ZERO, 1.0, [Label::OUTSIDE, Label::new(1)]).unwrap();
        let shift = DVec3::new(0.3, -0.1, 0.2);
        let mut moved = mesh.clone();
        for v in mesh.vertices() {
            moved.set_position(v, mesh.position(v) + shift);
        }
        let expected: Vec<DVec3> = mesh.positions().iter().map(|p| *p + shift).collect();
        let reference = Reference {
            initial: &mesh,
            expected,
            contact: Some(vec![false; mesh.vertex_capacity()]),
        };
        let p = measure(&reference, &moved, 1e-9, 0.5);
        assert_eq!(p.untouched_triangles, mesh.num_triangles());
        assert!(p.feature_distance_max.unwrap() < 1e-12);
        // Push one vertex out: its 5 or 6 triangles are touched, its distance shows.
        let v = mesh_core::VertexId::new(0);
        moved.set_position(v, moved.position(v) * 1.0 + DVec3::splat(0.01));
        let p = measure(&reference, &moved, 1e-9, 0.5);
        let ring = mesh.vertex_triangles(v).count();
        assert_eq!(p.untouched_triangles, mesh.num_triangles() - ring);
        assert!(p.feature_distance_max.unwrap() > 1e-3);
    }

    /// Vertices at one point (unused ones here, as a hostile file had 200 000 of) are
    /// looked up once per position: the sphere's triangles still all match, and an
    /// unused vertex at a sphere vertex's position does not take its place.
    #[test]
    fn coincident_vertices_do_not_change_the_match() {
        let mut mesh = icosphere(1, DVec3::ZERO, 1.0, [Label::OUTSIDE, Label::new(1)]).unwrap();
        let at_vertex = mesh.position(mesh_core::VertexId::new(3));
        for i in 0..2000 {
            let p = if i % 2 == 0 { DVec3::ZERO } else { at_vertex };
            mesh.add_vertex(p).unwrap();
        }
        let reference = Reference {
            initial: &mesh,
            expected: mesh.positions().to_vec(),
            contact: None,
        };
        let p = measure(&reference, &mesh, 1e-9, 0.5);
        assert_eq!(p.untouched_triangles, mesh.num_triangles());
    }

    #[test]
    fn point_triangle_distance_regions() {
        let (a, b, c) = (DVec3::ZERO, DVec3::X, DVec3::Y);
        assert!((distance_point_triangle(DVec3::new(0.2, 0.2, 1.0), a, b, c) - 1.0).abs() < 1e-15);
        assert!((distance_point_triangle(DVec3::new(-1.0, 0.0, 0.0), a, b, c) - 1.0).abs() < 1e-15);
        let d = distance_point_triangle(DVec3::new(1.0, 1.0, 0.0), a, b, c);
        assert!((d - 0.5f64.sqrt()).abs() < 1e-15);
    }
}
