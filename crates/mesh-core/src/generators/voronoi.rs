//! A Voronoi foam: the Voronoi cells of random sites, clipped to a cube, one material each.
//!
//! **Cells.** Each cell starts as the cube and is clipped, as a convex polyhedron, by the
//! bisector half-spaces of the other sites in order of distance. A site `j` at distance
//! `D` can only cut the cell if `D < 2R`, `R` being the distance of the cell's farthest
//! vertex from its own site; sorted by distance, the clipping stops at the first site
//! beyond that. Cells are independent and built in parallel; sorting the candidates makes
//! the whole O(N² log N) in the worst case, fine for thousands of cells.
//!
//! **Welding (why shared faces match).** Every polyhedron vertex is identified
//! combinatorially by the planes through it: a bisector `(i, j)` is named by the site `j`,
//! a cube face by its own id. A Voronoi vertex of cell `i` with planes `{a, b, c}` is
//! the point equidistant from the four "sites" `{i, a, b, c}` (a cube face acting as a
//! mirror site), so that sorted quadruple is the same key in every cell that has it.
//! Faces are welded on that key; each face polygon is fanned from a centre vertex and
//! emitted once (by the lower-numbered of its two cells), labelled `[other, own]` with
//! its normal pointing out of its own cell.
//!
//! **Degeneracy.** Random sites are in general position with probability one, but near
//! ties (a bisector passing within `1e-9` of the cube size of a vertex, an edge shorter
//! than that, a face seen differently by its two cells) would make the keys ambiguous or
//! the triangles degenerate. Such a configuration is rejected and all sites are redrawn
//! from the same seeded stream, up to [`MAX_SITE_ATTEMPTS`] times; with random sites the
//! first draw is rejected with probability of order `N·1e-9`.

use std::collections::HashMap;

use glam::DVec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use super::error::{GeneratorError, check_box, invalid};
use crate::ids::MAX_INDEX;
use crate::mesh::LabeledMesh;

/// How many site configurations [`voronoi_foam`] draws before giving up.
pub const MAX_SITE_ATTEMPTS: usize = 16;

/// Largest accepted number of cells.
pub const MAX_CELLS: usize = 1 << 20;

/// Relative tolerance (of the largest cube extent) below which a configuration counts as
/// degenerate.
const RELATIVE_TOLERANCE: f64 = 1e-9;

/// The configuration is too close to degenerate; draw new sites.
#[derive(Debug)]
struct Degenerate;

/// A convex polyhedron with combinatorially named vertices. Plane ids: site `j` (a
/// bisector with it) is `j`, cube face `f` (−x, +x, −y, +y, −z, +z) is `n + f`.
#[derive(Clone, Debug, Default)]
struct Cell {
    pos: Vec<DVec3>,
    /// The three plane ids through each vertex, sorted.
    planes: Vec<[u32; 3]>,
    face_plane: Vec<u32>,
    /// Face `f`'s loop is `loops[face_start[f]..face_start[f + 1]]`, counter-clockwise
    /// seen from outside.
    face_start: Vec<usize>,
    loops: Vec<u32>,
}

/// Buffers reused across clips of one cell.
#[derive(Default)]
struct Scratch {
    dist: Vec<f64>,
    remap: Vec<u32>,
    /// `(lo, hi, new vertex)` for every cut edge.
    cut_edges: Vec<(u32, u32, u32)>,
    /// `(entry, exit)` cut vertices of each clipped face: the new face runs entry → exit.
    links: Vec<(u32, u32)>,
}

const NONE: u32 = u32::MAX;

impl Cell {
    fn cube(min: DVec3, max: DVec3, n: u32) -> Cell {
        let pos = (0..8u32)
            .map(|c| {
                DVec3::new(
                    if c & 1 == 0 { min.x } else { max.x },
                    if c & 2 == 0 { min.y } else { max.y },
                    if c & 4 == 0 { min.z } else { max.z },
                )
            })
            .collect();
        let planes = (0..8u32)
            .map(|c| [n + (c & 1), n + 2 + ((c >> 1) & 1), n + 4 + ((c >> 2) & 1)])
            .collect();
        let loops: [[u32; 4]; 6] = [
            [0, 4, 6, 2],
            [1, 3, 7, 5],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 2, 3, 1],
            [4, 5, 7, 6],
        ];
        Cell {
            pos,
            planes,
            face_plane: (0..6).map(|f| n + f).collect(),
            face_start: (0..=6).map(|f| 4 * f).collect(),
            loops: loops.concat(),
        }
    }

    fn faces(&self) -> usize {
        self.face_plane.len()
    }

    fn face(&self, f: usize) -> &[u32] {
        &self.loops[self.face_start[f]..self.face_start[f + 1]]
    }

    fn clear(&mut self) {
        self.pos.clear();
        self.planes.clear();
        self.face_plane.clear();
        self.face_start.clear();
        self.face_start.push(0);
        self.loops.clear();
    }

    fn push_face(&mut self, plane: u32) {
        self.face_plane.push(plane);
        self.face_start.push(self.loops.len());
    }

    /// Clips to the half-space `normal·p ≤ offset` (`normal` a unit vector) into `out`.
    /// Returns false (and leaves `out` untouched) when nothing is cut off.
    fn clip(
        &self,
        plane: u32,
        normal: DVec3,
        offset: f64,
        tol: f64,
        out: &mut Cell,
        s: &mut Scratch,
    ) -> Result<bool, Degenerate> {
        s.dist.clear();
        s.dist
            .extend(self.pos.iter().map(|p| normal.dot(*p) - offset));
        if s.dist.iter().any(|d| d.abs() <= tol || !d.is_finite()) {
            return Err(Degenerate);
        }
        if s.dist.iter().all(|&d| d < 0.0) {
            return Ok(false);
        }
        out.clear();
        s.remap.clear();
        for (v, &d) in s.dist.iter().enumerate() {
            if d < 0.0 {
                s.remap.push(out.pos.len() as u32);
                out.pos.push(self.pos[v]);
                out.planes.push(self.planes[v]);
            } else {
                s.remap.push(NONE);
            }
        }
        if out.pos.is_empty() {
            return Err(Degenerate);
        }
        s.cut_edges.clear();
        s.links.clear();
        for f in 0..self.faces() {
            let face = self.face(f);
            let start = out.loops.len();
            let (mut entry, mut exit) = (NONE, NONE);
            for (k, &u) in face.iter().enumerate() {
                let v = face[(k + 1) % face.len()];
                let (ku, kv) = (s.remap[u as usize] != NONE, s.remap[v as usize] != NONE);
                if ku {
                    out.loops.push(s.remap[u as usize]);
                }
                if ku != kv {
                    let x = self.cut_vertex(u, v, plane, out, s)?;
                    out.loops.push(x);
                    if ku { exit = x } else { entry = x }
                }
            }
            if out.loops.len() - start >= 3 {
                out.push_face(self.face_plane[f]);
            } else {
                out.loops.truncate(start);
            }
            if (entry == NONE) != (exit == NONE) {
                return Err(Degenerate);
            }
            if entry != NONE {
                s.links.push((entry, exit));
            }
        }
        // The new face runs against the clipped faces' cut edges: entry → exit each.
        let m = s.cut_edges.len();
        if m < 3 || s.links.len() != m {
            return Err(Degenerate);
        }
        let first = s.links[0].0;
        let mut at = first;
        for _ in 0..m {
            out.loops.push(at);
            at = s.links.iter().find(|l| l.0 == at).ok_or(Degenerate)?.1;
            if at == first {
                break;
            }
        }
        if at != first || out.loops.len() - out.face_start[out.faces()] != m {
            return Err(Degenerate);
        }
        out.push_face(plane);
        Ok(true)
    }

    /// The vertex where the clipping plane cuts edge `u–v`, created on first use. Its
    /// planes are the two the edge lies on plus the clipping plane.
    fn cut_vertex(
        &self,
        u: u32,
        v: u32,
        plane: u32,
        out: &mut Cell,
        s: &mut Scratch,
    ) -> Result<u32, Degenerate> {
        let (lo, hi) = (u.min(v), u.max(v));
        if let Some(&(_, _, x)) = s.cut_edges.iter().find(|e| e.0 == lo && e.1 == hi) {
            return Ok(x);
        }
        let (pu, pv) = (self.planes[u as usize], self.planes[v as usize]);
        let mut common = pu.iter().filter(|p| pv.contains(p));
        let (Some(&a), Some(&b), None) = (common.next(), common.next(), common.next()) else {
            return Err(Degenerate);
        };
        let mut key = [a, b, plane];
        key.sort_unstable();
        let (du, dv) = (s.dist[u as usize], s.dist[v as usize]);
        let (xu, xv) = (self.pos[u as usize], self.pos[v as usize]);
        let x = out.pos.len() as u32;
        out.pos.push(xu + (xv - xu) * (du / (du - dv)));
        out.planes.push(key);
        s.cut_edges.push((lo, hi, x));
        Ok(x)
    }
}

/// Builds the cell of site `i` and checks its edges are not tiny.
fn build_cell(i: usize, sites: &[DVec3], cube: [DVec3; 2], tol: f64) -> Result<Cell, Degenerate> {
    let n = sites.len() as u32;
    let me = sites[i];
    let mut order: Vec<(f64, u32)> = sites
        .iter()
        .enumerate()
        .filter(|&(j, _)| j != i)
        .map(|(j, s)| (s.distance(me), j as u32))
        .collect();
    order.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let mut cell = Cell::cube(cube[0], cube[1], n);
    let mut next = Cell::default();
    let mut scratch = Scratch::default();
    let mut reach = cell.pos.iter().map(|p| p.distance(me)).fold(0.0, f64::max);
    for (d, j) in order {
        if d >= 2.0 * reach {
            break;
        }
        if d <= tol {
            return Err(Degenerate);
        }
        let other = sites[j as usize];
        let normal = (other - me) / d;
        if cell.clip(
            j,
            normal,
            normal.dot((me + other) / 2.0),
            tol,
            &mut next,
            &mut scratch,
        )? {
            std::mem::swap(&mut cell, &mut next);
            reach = cell.pos.iter().map(|p| p.distance(me)).fold(0.0, f64::max);
        }
    }
    for f in 0..cell.faces() {
        let face = cell.face(f);
        for (k, &u) in face.iter().enumerate() {
            let v = face[(k + 1) % face.len()];
            if cell.pos[u as usize].distance(cell.pos[v as usize]) <= tol {
                return Err(Degenerate);
            }
        }
    }
    Ok(cell)
}

/// The global key of vertex `v` of the cell of site `i`: its four defining "sites".
fn vertex_key(cell: &Cell, i: u32, v: u32) -> [u32; 4] {
    let [a, b, c] = cell.planes[v as usize];
    let mut key = [i, a, b, c];
    key.sort_unstable();
    key
}

/// True when cell `j` sees its face with cell `i` as the reverse of cell `i`'s face with
/// `j` (the same keys in opposite cyclic order).
fn faces_match(cells: &[Cell], i: usize, fi: usize, j: usize) -> bool {
    let (ci, cj) = (&cells[i], &cells[j]);
    let Some(fj) = cj.face_plane.iter().position(|&p| p as usize == i) else {
        return false;
    };
    let (a, b) = (ci.face(fi), cj.face(fj));
    if a.len() != b.len() {
        return false;
    }
    let key_a = |k: usize| vertex_key(ci, i as u32, a[k]);
    let key_b = |k: usize| vertex_key(cj, j as u32, b[k]);
    let m = a.len();
    let Some(start) = (0..m).find(|&k| key_b(k) == key_a(0)) else {
        return false;
    };
    (0..m).all(|t| key_a(t) == key_b((start + m - t) % m))
}

/// Builds and cross-checks all cells for one set of sites.
fn build_cells(sites: &[DVec3], cube: [DVec3; 2], tol: f64) -> Result<Vec<Cell>, Degenerate> {
    let cells: Vec<Cell> = (0..sites.len())
        .into_par_iter()
        .map(|i| build_cell(i, sites, cube, tol))
        .collect::<Result<_, _>>()?;
    let n = sites.len();
    let consistent = (0..n).into_par_iter().all(|i| {
        (0..cells[i].faces()).all(|f| {
            let p = cells[i].face_plane[f] as usize;
            p >= n || faces_match(&cells, i, f, p)
        })
    });
    if consistent {
        Ok(cells)
    } else {
        Err(Degenerate)
    }
}

/// Welds the cells on vertex keys and fans every face once.
fn assemble(cells: &[Cell]) -> Result<LabeledMesh, GeneratorError> {
    let n = cells.len();
    let mut index: HashMap<[u32; 4], u32> = HashMap::new();
    let mut positions = Vec::new();
    let mut tris = Vec::new();
    let mut labels = Vec::new();
    for (i, cell) in cells.iter().enumerate() {
        for f in 0..cell.faces() {
            let other = cell.face_plane[f] as usize;
            if other < i {
                continue; // emitted by the lower-numbered cell
            }
            // Labels fit: n ≤ MAX_CELLS.
            let pair = [if other >= n { 0 } else { other as u32 + 1 }, i as u32 + 1];
            let face = cell.face(f);
            let centre_id = positions.len() as u32;
            positions.push(
                face.iter().map(|&v| cell.pos[v as usize]).sum::<DVec3>() / face.len() as f64,
            );
            let ids_start = tris.len();
            for (k, &u) in face.iter().enumerate() {
                let v = face[(k + 1) % face.len()];
                let [gu, gv] = [u, v].map(|w| {
                    *index
                        .entry(vertex_key(cell, i as u32, w))
                        .or_insert_with(|| {
                            positions.push(cell.pos[w as usize]);
                            (positions.len() - 1) as u32
                        })
                });
                tris.push([centre_id, gu, gv]);
            }
            labels.extend(std::iter::repeat_n(pair, tris.len() - ids_start));
        }
    }
    if positions.len() > MAX_INDEX as usize {
        return Err(crate::error::MeshError::TooLarge {
            what: "vertices",
            count: positions.len(),
        }
        .into());
    }
    Ok(LabeledMesh::from_raw(positions, &tris, &labels)?)
}

/// The Voronoi cells of `n_cells` sites drawn uniformly in the cube `[cube_min,
/// cube_max]` (a `ChaCha8Rng` seeded with `seed`), clipped to the cube: site `i` gives
/// label `i + 1`, the outside of the cube is 0. Shared faces are meshed once, fanned from
/// their centre, so the mesh is watertight and the cells partition the cube exactly.
///
/// Fails on `n_cells = 0` or above [`MAX_CELLS`], a non-finite or empty box, or when
/// [`MAX_SITE_ATTEMPTS`] draws of sites were all near-degenerate (see the module doc).
pub fn voronoi_foam(
    n_cells: usize,
    seed: u64,
    cube_min: DVec3,
    cube_max: DVec3,
) -> Result<LabeledMesh, GeneratorError> {
    const NAME: &str = "voronoi_foam";
    if !(1..=MAX_CELLS).contains(&n_cells) {
        return Err(invalid(NAME, "n_cells", n_cells, "between 1 and 2^20"));
    }
    check_box(NAME, cube_min, cube_max)?;
    let tol = RELATIVE_TOLERANCE * (cube_max - cube_min).max_element();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut sites = Vec::with_capacity(n_cells);
    for _ in 0..MAX_SITE_ATTEMPTS {
        sites.clear();
        for _ in 0..n_cells {
            let u = DVec3::new(rng.random(), rng.random(), rng.random());
            sites.push(cube_min + (cube_max - cube_min) * u);
        }
        if let Ok(cells) = build_cells(&sites, [cube_min, cube_max], tol) {
            return assemble(&cells);
        }
    }
    Err(GeneratorError::Degenerate {
        generator: NAME,
        attempts: MAX_SITE_ATTEMPTS,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generators::checks::{assert_well_formed, volume_per_label};
    use crate::ids::Label;

    #[test]
    fn cells_partition_the_cube() {
        let (lo, hi) = (DVec3::new(-1.0, 0.0, 2.0), DVec3::new(1.0, 0.5, 3.0));
        let cube_volume = (hi - lo).element_product();
        for (n, seed) in [(1, 0), (2, 1), (5, 2), (40, 3), (150, 4)] {
            let m = voronoi_foam(n, seed, lo, hi).unwrap();
            assert_well_formed(&m);
            let vols = volume_per_label(&m);
            let labels: Vec<Label> = vols.keys().copied().collect();
            assert_eq!(
                labels,
                (1..=n as u32).map(Label::new).collect::<Vec<_>>(),
                "n = {n}"
            );
            assert!(vols.values().all(|&v| v > 0.0));
            let total: f64 = vols.values().sum();
            assert!(
                ((total - cube_volume) / cube_volume).abs() < 1e-9,
                "n = {n}: {total}"
            );
            for v in m.vertices() {
                let p = m.position(v);
                assert!(p.cmpge(lo - 1e-12).all() && p.cmple(hi + 1e-12).all());
            }
        }
    }

    #[test]
    fn interior_edges_join_three_cells() {
        let m = voronoi_foam(30, 11, DVec3::ZERO, DVec3::ONE).unwrap();
        let table = crate::connectivity::EdgeTable::build(
            m.tris(),
            m.tri_alive_flags(),
            m.vertex_capacity(),
        );
        let mut by_degree = [0usize; 5];
        for g in table.groups() {
            assert!((2..=3).contains(&g.len()), "edge of degree {}", g.len());
            by_degree[g.len()] += 1;
        }
        assert!(by_degree[3] > 0, "no Voronoi edges");
    }

    #[test]
    fn cell_vertices_are_nearest_to_their_own_site() {
        let mut rng = ChaCha8Rng::seed_from_u64(8);
        let sites: Vec<DVec3> = (0..60)
            .map(|_| DVec3::new(rng.random(), rng.random(), rng.random()))
            .collect();
        let cells = build_cells(&sites, [DVec3::ZERO, DVec3::ONE], 1e-9).unwrap();
        for (i, cell) in cells.iter().enumerate() {
            for p in &cell.pos {
                let own = p.distance(sites[i]);
                assert!(
                    sites.iter().all(|s| own <= p.distance(*s) + 1e-12),
                    "cell {i}"
                );
            }
            // Every vertex lies on the three planes it is named after.
            for (p, planes) in cell.pos.iter().zip(&cell.planes) {
                for &q in planes {
                    let d = if (q as usize) < sites.len() {
                        p.distance(sites[i]) - p.distance(sites[q as usize])
                    } else {
                        let f = q as usize - sites.len();
                        p[f / 2] - (f % 2) as f64
                    };
                    assert!(d.abs() < 1e-12, "cell {i}: vertex off plane {q} by {d}");
                }
            }
        }
    }

    #[test]
    fn cospherical_sites_are_rejected_as_degenerate() {
        // Sites at the centres of the eight octants: all eight cells meet at the centre,
        // so bisectors pass exactly through existing vertices.
        let sites: Vec<DVec3> = (0..8)
            .map(|c| {
                DVec3::new(
                    0.25 + 0.5 * (c & 1) as f64,
                    0.25 + 0.5 * ((c >> 1) & 1) as f64,
                    0.25 + 0.5 * (c >> 2) as f64,
                )
            })
            .collect();
        assert!(build_cells(&sites, [DVec3::ZERO, DVec3::ONE], 1e-9).is_err());
        // Coincident sites as well.
        let twins = [DVec3::splat(0.3), DVec3::splat(0.3), DVec3::splat(0.7)];
        assert!(build_cells(&twins, [DVec3::ZERO, DVec3::ONE], 1e-9).is_err());
    }

    #[test]
    fn deterministic_per_seed() {
        let a = voronoi_foam(25, 5, DVec3::ZERO, DVec3::ONE).unwrap();
        let b = voronoi_foam(25, 5, DVec3::ZERO, DVec3::ONE).unwrap();
        let c = voronoi_foam(25, 6, DVec3::ZERO, DVec3::ONE).unwrap();
        assert_eq!(a.to_raw(), b.to_raw());
        assert_ne!(a.to_raw().0, c.to_raw().0);
    }

    #[test]
    fn clipping_a_cube_in_half() {
        let mut cell = Cell::cube(DVec3::ZERO, DVec3::ONE, 2);
        let mut out = Cell::default();
        let mut s = Scratch::default();
        // Cut by x ≤ 0.25 (the bisector of sites 0.0 and 0.5 on x, say site 1).
        assert!(
            cell.clip(1, DVec3::X, 0.25, 1e-12, &mut out, &mut s)
                .unwrap()
        );
        std::mem::swap(&mut cell, &mut out);
        assert_eq!(cell.faces(), 6);
        assert_eq!(cell.pos.len(), 8);
        let new_face = cell.face_plane.iter().position(|&p| p == 1).unwrap();
        for &v in cell.face(new_face) {
            assert!((cell.pos[v as usize].x - 0.25).abs() < 1e-15);
            assert!(cell.planes[v as usize].contains(&1));
        }
        // A plane through a vertex is degenerate.
        assert!(
            cell.clip(
                0,
                DVec3::new(1.0, 1.0, 0.0).normalize(),
                0.0,
                1e-12,
                &mut out,
                &mut s
            )
            .is_err()
        );
    }

    #[test]
    fn bad_parameters_are_refused() {
        assert!(voronoi_foam(0, 1, DVec3::ZERO, DVec3::ONE).is_err());
        assert!(voronoi_foam(3, 1, DVec3::ONE, DVec3::ZERO).is_err());
        assert!(voronoi_foam(3, 1, DVec3::ZERO, DVec3::new(1.0, f64::NAN, 1.0)).is_err());
    }
}
