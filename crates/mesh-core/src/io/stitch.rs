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
//!
//! After stitching, [`split_t_junctions`] closes what exporters of CAD models leave open
//! in another way: an edge running past vertices of its neighbours (see there).

use glam::DVec3;

use crate::broadphase::{Aabb, Bvh};
use crate::predicates::collinear;

/// Stitches `tris` over `positions` in place (see the module docs) and returns the
/// number of vertices merged into another, or `None` when no edge is open (then neither
/// this nor [`split_t_junctions`] has anything to do: a closed mesh costs one sort).
pub(crate) fn stitch_open_vertices(
    positions: &mut Vec<DVec3>,
    tris: &mut [[u32; 3]],
) -> Option<usize> {
    let n = positions.len();
    if tris.iter().flatten().any(|&v| v as usize >= n) {
        return None; // the mesh builder names the bad index, with the file's numbering
    }
    let open_keys = open_edge_keys(tris);
    if open_keys.is_empty() {
        return None;
    }
    let mut open = vec![false; n];
    for &key in &open_keys {
        let [a, b] = key_ends(key);
        open[a as usize] = true;
        open[b as usize] = true;
    }
    drop(open_keys);

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
        return Some(0);
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
    Some(merged)
}

/// Splits open edges at the open vertices that lie exactly on them (T-junctions) and
/// returns how many vertices were inserted into edges.
///
/// Why: CAD exporters mesh each face on its own, so where a coarse face meets a finely
/// split neighbour along a shared boundary curve, the coarse face's edge runs past the
/// neighbour's vertices. The surface is closed, but as written the long edge and the
/// short ones are each used once, and nothing downstream can tell inside from outside.
///
/// What is split, and why only that: an **open** edge (used by one triangle), at a
/// vertex that is itself on an open edge and lies on the segment, strictly between its
/// ends: exactly ([`crate::predicates::collinear`]), or off it by no more than the
/// rounding of written coordinates ([`t_vertex_slack`]), which is how T-vertices on
/// slanted edges arrive (a midpoint computed in floating point, then printed or stored
/// as `f32`, is almost never exactly on the segment). The triangle
/// `(a, b, c)` becomes the fan `(a, v₁, c), (v₁, v₂, c), …, (v_k, b, c)` with its labels:
/// the same surface, the same orientation. A closed mesh is never changed, and neither
/// is an exactly flat triangle. A triangle with T-vertices on several of its edges is
/// split one edge per pass; three passes reach every edge of every triangle.
pub(crate) fn split_t_junctions(
    positions: &[DVec3],
    tris: &mut Vec<[u32; 3]>,
    labels: Option<&mut Vec<[u32; 2]>>,
) -> usize {
    split_t_junctions_counted(positions, tris, labels).0
}

/// [`split_t_junctions`], also returning the number of exact tests made.
fn split_t_junctions_counted(
    positions: &[DVec3],
    tris: &mut Vec<[u32; 3]>,
    labels: Option<&mut Vec<[u32; 2]>>,
) -> (usize, usize) {
    let n = positions.len();
    let labels_fit = labels.as_ref().is_none_or(|l| l.len() == tris.len());
    if !labels_fit || tris.iter().flatten().any(|&v| v as usize >= n) {
        return (0, 0); // the mesh builder names the bad index or the count mismatch
    }
    let mut labels = labels;
    let mut inserted = 0;
    let mut tests = 0usize;
    for _pass in 0..3 {
        let open = open_edges(tris);
        if open.is_empty() {
            break;
        }
        let mut on_open: Vec<u32> = open.iter().flat_map(|e| [e.0, e.1]).collect();
        on_open.sort_unstable();
        on_open.dedup();
        let boxes: Vec<Aabb> = on_open
            .iter()
            .map(|&v| Aabb::new(positions[v as usize], positions[v as usize]))
            .collect();
        let Ok(bvh) = Bvh::build(&boxes) else {
            break;
        };
        // Per triangle, the first of its open edges that has T-vertices, with them in
        // order from the edge's first corner (in the triangle's orientation).
        let mut splits: Vec<(usize, usize, Vec<u32>)> = Vec::new();
        let mut done = vec![false; tris.len()];
        // A file of unrelated triangles (every edge open, long edges whose boxes hold
        // most vertices) would make this quadratic; past this many exact tests the pass
        // is dropped and the mesh stays as it is, for validation to report.
        let budget = tests + TESTS_PER_ELEMENT * (open.len() + on_open.len());
        for &(lo, hi, t) in &open {
            if tests > budget {
                return (inserted, tests);
            }
            if done[t] {
                continue;
            }
            let tri = tris[t];
            let Some(k) = (0..3).find(|&k| {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                (a.min(b), a.max(b)) == (lo, hi)
            }) else {
                continue;
            };
            let (a, b, c) = (tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]);
            let [pa, pb, pc] = [a, b, c].map(|v| positions[v as usize]);
            if collinear(pa, pb, pc) {
                continue;
            }
            // The axis along which the segment is longest orders points on it.
            let axis = (pb - pa).abs().max_position();
            let slack = t_vertex_slack(pa, pb);
            let mut on: Vec<(f64, u32)> = Vec::new();
            bvh.query(&Aabb::from_points(&[pa, pb]), slack, |i| {
                tests += 1;
                let v = on_open[i as usize];
                let p = positions[v as usize];
                let (x, lo, hi) = (p[axis], pa[axis].min(pb[axis]), pa[axis].max(pb[axis]));
                if v == a || v == b || x <= lo || x >= hi {
                    return;
                }
                // Strictly between the ends; by more than the slack when only near the
                // segment (an exactly collinear vertex splits at any distance, as before).
                let exact = collinear(pa, pb, p);
                let inside = x > lo + slack && x < hi - slack;
                if exact || (inside && near_line(pa, pb, p, slack)) {
                    on.push(((x - pa[axis]).abs(), v));
                }
            });
            if on.is_empty() {
                continue;
            }
            on.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
            on.dedup_by_key(|x| x.1);
            done[t] = true;
            splits.push((t, k, on.into_iter().map(|x| x.1).collect()));
        }
        if splits.is_empty() {
            break;
        }
        for (t, k, on) in splits {
            let tri = tris[t];
            let (a, b, c) = (tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]);
            inserted += on.len();
            let chain: Vec<u32> = std::iter::once(a).chain(on).chain([b]).collect();
            let label = labels.as_ref().map(|l| l[t]);
            tris[t] = [chain[0], chain[1], c];
            for w in chain[1..].windows(2) {
                tris.push([w[0], w[1], c]);
                if let (Some(l), Some(label)) = (labels.as_deref_mut(), label) {
                    l.push(label);
                }
            }
        }
    }
    (inserted, tests)
}

/// How far off the open edge `pa`–`pb` a vertex may lie and still be taken as a T-vertex
/// of it: the rounding of coordinates as files store them, not a modelling tolerance.
/// 2⁻¹⁷ ≈ 7.6·10⁻⁶ of the largest coordinate magnitude covers coordinates stored as `f32`
/// (6·10⁻⁸ relative) and printed with six significant digits (5·10⁻⁶); capped at 10⁻³ of
/// the edge's length, so that on a fine mesh far from the origin no vertex a visible
/// distance away is ever pulled onto the edge (its T-junction then stays open, for
/// validation to report).
fn t_vertex_slack(pa: DVec3, pb: DVec3) -> f64 {
    let magnitude = pa.abs().max(pb.abs()).max_element();
    (magnitude * T_SLACK_OF_MAGNITUDE).min(pa.distance(pb) * T_SLACK_OF_LENGTH)
}

/// See [`t_vertex_slack`]: 2⁻¹⁷.
const T_SLACK_OF_MAGNITUDE: f64 = 1.0 / (1u32 << 17) as f64;

/// See [`t_vertex_slack`].
const T_SLACK_OF_LENGTH: f64 = 1e-3;

/// Whether `p` lies within `slack` of the line through `pa` and `pb`.
fn near_line(pa: DVec3, pb: DVec3, p: DVec3, slack: f64) -> bool {
    let d = pb - pa;
    let t = (p - pa).dot(d) / d.length_squared();
    (pa + d * t).distance(p) <= slack
}

/// Exact on-segment tests per open edge and open vertex that [`split_t_junctions`] may
/// spend in one pass (a T-junction curve's edge box holds a few of its vertices).
const TESTS_PER_ELEMENT: usize = 16;

/// The key of the unordered edge `{a, b}`: the lower end in the high 32 bits.
fn edge_key(a: u32, b: u32) -> u64 {
    (u64::from(a.min(b)) << 32) | u64::from(a.max(b))
}

/// The ends of an [`edge_key`], lower first.
fn key_ends(key: u64) -> [u32; 2] {
    [(key >> 32) as u32, (key & 0xffff_ffff) as u32]
}

/// The edges used by exactly one triangle, as sorted [`edge_key`]s: one sort of 8-byte
/// keys, which is all a closed mesh costs the stitch.
fn open_edge_keys(tris: &[[u32; 3]]) -> Vec<u64> {
    let mut edges: Vec<u64> = tris
        .iter()
        .flat_map(|t| {
            [
                edge_key(t[0], t[1]),
                edge_key(t[1], t[2]),
                edge_key(t[2], t[0]),
            ]
        })
        .collect();
    edges.sort_unstable();
    edges
        .chunk_by(|a, b| a == b)
        .filter(|run| run.len() == 1)
        .map(|run| run[0])
        .collect()
}

/// Edges used by exactly one triangle: `(lower vertex, higher vertex, triangle)`, sorted.
fn open_edges(tris: &[[u32; 3]]) -> Vec<(u32, u32, usize)> {
    let keys = open_edge_keys(tris);
    let mut open: Vec<(u32, u32, usize)> = Vec::with_capacity(keys.len());
    if keys.is_empty() {
        return open;
    }
    for (t, tri) in tris.iter().enumerate() {
        for k in 0..3 {
            let key = edge_key(tri[k], tri[(k + 1) % 3]);
            if keys.binary_search(&key).is_ok() {
                let [a, b] = key_ends(key);
                open.push((a, b, t));
            }
        }
    }
    open.sort_unstable();
    open
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
        assert_eq!(
            stitch_open_vertices(&mut positions, &mut tris),
            Some(36 - 8)
        );
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
        assert_eq!(stitch_open_vertices(&mut positions, &mut tris), None);
        assert_eq!((positions, tris), before);

        // A soup with one corner moved by one ulp keeps that corner's copy apart.
        let (mut positions, mut tris) = soup();
        positions[0].x = f64::from_bits(positions[0].x.to_bits() + 1);
        assert_eq!(
            stitch_open_vertices(&mut positions, &mut tris),
            Some(36 - 8 - 1)
        );
        assert_eq!(positions.len(), 9);
    }

    /// The unit cube with its front face (y = 0) meshed as a fan through the midpoint
    /// of its top edge, which the top face's triangle runs past: a T-junction.
    fn cube_with_t_junction() -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let (mut p, t) = cube();
        let m = p.len() as u32;
        p.push(DVec3::new(0.5, 0.0, 1.0));
        let corner =
            |x: f64, z: f64| p.iter().position(|&q| q == DVec3::new(x, 0.0, z)).unwrap() as u32;
        let [c00, c10, c11, c01] = [
            corner(0., 0.),
            corner(1., 0.),
            corner(1., 1.),
            corner(0., 1.),
        ];
        let mut tris: Vec<[u32; 3]> = t
            .into_iter()
            .filter(|tri| !tri.iter().all(|&v| p[v as usize].y == 0.0))
            .collect();
        // Outward is −y: counter-clockwise seen from −y.
        for tri in [[c00, c10, m], [c10, c11, m], [m, c01, c00]] {
            let [a, b, c] = tri.map(|v| p[v as usize]);
            let outward = (b - a).cross(c - a).y < 0.0;
            tris.push(if outward {
                tri
            } else {
                [tri[0], tri[2], tri[1]]
            });
        }
        (p, tris)
    }

    #[test]
    fn a_t_junction_is_closed_by_splitting_the_edge_that_runs_past_it() {
        let (p, mut tris) = cube_with_t_junction();
        let mut labels = vec![[0, 1]; tris.len()];
        let open = |tris: &[[u32; 3]]| open_edges(tris).len();
        assert_eq!(open(&tris), 3, "the long top edge and its two halves");
        assert_eq!(split_t_junctions(&p, &mut tris, Some(&mut labels)), 1);
        assert_eq!((open(&tris), tris.len(), labels.len()), (0, 14, 14));
        let mesh = crate::LabeledMesh::from_raw(p.clone(), &tris, &labels).unwrap();
        let report = crate::validate::validate(&mesh, &crate::validate::ValidateOptions::default());
        assert!(report.is_valid(), "{report}");
        let volumes = crate::geometry::label_volumes(&mesh);
        assert!((volumes[&Label::new(1)] - 1.0).abs() < 1e-12);
        // Closed: nothing to do, twice.
        let before = tris.clone();
        assert_eq!(split_t_junctions(&p, &mut tris, None), 0);
        assert_eq!(tris, before);
    }

    #[test]
    fn a_t_vertex_off_its_edge_by_rounding_is_split_but_not_one_visibly_off() {
        // The midpoint moved off the edge by one ulp, and by what printing with six
        // digits leaves: T-junctions, split.
        for off in [f64::EPSILON / 2.0, 4e-7] {
            let (mut p, mut tris) = cube_with_t_junction();
            let m = p.len() - 1;
            p[m].z -= off;
            assert_eq!(split_t_junctions(&p, &mut tris, None), 1, "{off}");
            assert!(open_edges(&tris).is_empty());
        }
        // Exactly on the edge a ten-millionth from its end: split, as by the exact test
        // alone (the slack's margin from the ends is only for vertices near the edge).
        let (mut p, mut tris) = cube_with_t_junction();
        let m = p.len() - 1;
        p[m].x = 1e-7;
        assert_eq!(split_t_junctions(&p, &mut tris, None), 1);
        assert!(open_edges(&tris).is_empty());
        // A thousandth of the edge off it: a gap in the surface, not a rounding; left
        // open for validation to report.
        let (mut p, mut tris) = cube_with_t_junction();
        let m = p.len() - 1;
        p[m].z -= 1e-3;
        let before = tris.clone();
        assert_eq!(split_t_junctions(&p, &mut tris, None), 0);
        assert_eq!(tris, before);
    }

    /// A prism over the triangle (0,0)–(1,0)–(0,1) whose slanted side face is split at
    /// the slanted top edge's midpoint, computed in f64 and stored as f32, as a CAD
    /// exporter writing floats leaves it: not exactly on the edge, and closed by the split
    /// into a valid solid of the prism's volume.
    #[test]
    fn a_t_junction_on_a_slanted_edge_written_as_f32_is_closed() {
        let r = |x: f64| f64::from(x as f32);
        let v = |x: f64, y: f64, z: f64| DVec3::new(r(x), r(y), r(z));
        // Scaled and moved so that coordinates are not round numbers.
        let (s, o) = (0.37, DVec3::new(1.3, -2.1, 0.7));
        let corners = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)];
        let mut p: Vec<DVec3> = Vec::new();
        for z in [0.0, 1.0] {
            for &(x, y) in &corners {
                p.push(v(o.x + s * x, o.y + s * y, o.z + s * z));
            }
        }
        // Bottom 0 1 2, top 3 4 5; the slanted edge on top runs 4–5, its midpoint is 6.
        p.push(v(o.x + s * 0.5, o.y + s * 0.5, o.z + s));
        assert!(!collinear(p[4], p[5], p[6]), "not exactly on the edge");
        let mut tris: Vec<[u32; 3]> = vec![
            [0, 2, 1],
            [3, 4, 5],
            [0, 1, 4],
            [0, 4, 3],
            [0, 3, 5],
            [0, 5, 2],
            // The slanted side (1, 2, 5, 4), fanned through the top edge's midpoint.
            [1, 2, 6],
            [1, 6, 4],
            [2, 5, 6],
        ];
        let mut labels = vec![[0, 1]; tris.len()];
        assert_eq!(open_edges(&tris).len(), 3);
        assert_eq!(split_t_junctions(&p, &mut tris, Some(&mut labels)), 1);
        assert!(open_edges(&tris).is_empty());
        let mesh = crate::LabeledMesh::from_raw(p.clone(), &tris, &labels).unwrap();
        let report = crate::validate::validate(&mesh, &crate::validate::ValidateOptions::default());
        assert!(report.is_valid(), "{report}");
        let volume = crate::geometry::label_volumes(&mesh)[&Label::new(1)];
        assert!((volume - s * s * s / 2.0).abs() < 1e-6, "{volume}");
    }

    #[test]
    fn unrelated_open_triangles_cost_a_bounded_number_of_tests() {
        // Long thin triangles fanned around one axis: every edge is open, and every
        // edge's box holds nearly every vertex. Nothing lies on another edge; the pass
        // gives up after its budget instead of testing every pair.
        let n = 2000u32;
        let mut p = Vec::new();
        let mut tris = Vec::new();
        for i in 0..n {
            let a = f64::from(i) * 0.001;
            p.push(DVec3::new(-1.0, a.cos(), a.sin()));
            p.push(DVec3::new(1.0, -a.cos(), -a.sin()));
            p.push(DVec3::new(0.0, 0.5 * a.sin(), 0.01 + f64::from(i) * 1e-4));
            tris.push([3 * i, 3 * i + 1, 3 * i + 2]);
        }
        let before = tris.clone();
        let (inserted, tests) = split_t_junctions_counted(&p, &mut tris, None);
        assert_eq!((inserted, &tris), (0, &before));
        // Without the budget: 6.0M exact tests (measured), 500 per element.
        assert!(tests <= 16 * 12_000 + 6_000, "{tests} tests");
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
        assert_eq!(stitch_open_vertices(&mut positions, &mut tris), Some(2));
        assert_eq!(tris, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(positions.len(), 5);
        assert_eq!(positions[4], DVec3::splat(5.0));
    }
}
