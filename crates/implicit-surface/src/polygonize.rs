//! Meshing from scratch: plain single-material marching tetrahedra.
//!
//! The paper builds its initial mechanical mesh by marching cubes (§2) and compares its
//! dynamic mesh against re-polygonizing every frame (§1.1). This module does both jobs:
//! [`polygonize`] returns index/vertex buffers (what a renderer needs each frame; the
//! baseline of the comparison), [`polygonize_mesh`] the same as a [`LabeledMesh`]
//! (labels `[outside 0, inside 1]`) to start a follower from.
//!
//! Scheme: the box is sampled on a grid; every cube is cut into the six Kuhn tetrahedra
//! around its main diagonal, the same way in every cube, so neighbouring cubes split
//! their shared faces along the same diagonal and the surface is watertight. Surface
//! vertices sit on the sign-changing edges (linear interpolation, parameter clamped to
//! `[δ, 1 − δ]` with `δ =` [`EDGE_MARGIN`], so no vertex sits on a grid point and no
//! triangle degenerates) and are shared through a per-grid-point table of the seven edge
//! directions a Kuhn tetrahedron uses (+x, +y, +z, the three face diagonals, the body
//! diagonal) — no hashing. Each triangle is oriented so its normal points from the
//! inside corner of a crossed edge to the outside one. Grid points on the box boundary
//! count as outside, so a surface leaving the box is capped inside it. Sampling, vertex
//! placement and triangle emission run in parallel over z-slabs.

use glam::DVec3;
use mesh_core::{Label, LabeledMesh};
use rayon::prelude::*;

use crate::error::{ImplicitError, invalid};
use crate::field::ImplicitField;

/// Smallest distance of a surface vertex from a grid point, as a fraction of its edge.
pub const EDGE_MARGIN: f64 = 1e-3;

/// Largest number of cells per axis.
pub const MAX_CELLS_PER_AXIS: usize = 1024;

/// The six Kuhn tetrahedra as cube corners (bit 0 = x, 1 = y, 2 = z): the paths
/// `0 → e_a → e_a + e_b → 7` over the six axis orders. Every edge joins two corners one of
/// which is a bit-subset of the other.
const KUHN: [[u8; 4]; 6] = [
    [0, 1, 3, 7],
    [0, 1, 5, 7],
    [0, 2, 3, 7],
    [0, 2, 6, 7],
    [0, 4, 5, 7],
    [0, 4, 6, 7],
];

/// Index/vertex buffers of a polygonized surface; triangles wind counter-clockwise seen
/// from outside (normals point out of `F > 0`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Polygonization {
    /// Vertex positions.
    pub positions: Vec<DVec3>,
    /// Triangles as indices into `positions`.
    pub triangles: Vec<[u32; 3]>,
}

impl Polygonization {
    /// Connected components (union–find over triangle edges): the topology of the
    /// surface at this grid's resolution, the reference the follower's is compared to.
    pub fn components(&self) -> usize {
        use mesh_core::union_find::{find, union};
        let mut parent: Vec<u32> = (0..self.positions.len() as u32).collect();
        for t in &self.triangles {
            union(&mut parent, t[0], t[1]);
            union(&mut parent, t[1], t[2]);
        }
        let mut roots: Vec<u32> = self
            .triangles
            .iter()
            .map(|t| find(&mut parent, t[0]))
            .collect();
        roots.sort_unstable();
        roots.dedup();
        roots.len()
    }
}

/// The sampled grid: `n[a] + 1` points per axis.
struct Samples {
    origin: DVec3,
    cell: f64,
    points: [usize; 3],
    values: Vec<f64>,
}

impl Samples {
    fn index(&self, i: usize, j: usize, k: usize) -> usize {
        i + self.points[0] * (j + self.points[1] * k)
    }

    fn position(&self, i: usize, j: usize, k: usize) -> DVec3 {
        self.origin + DVec3::new(i as f64, j as f64, k as f64) * self.cell
    }
}

/// Marching tetrahedra of `F(·, t) = 0` over `bounds` (grown by one cell so the surface
/// closes) with cubic cells of size `cell`. Fails on a bad box or cell size, more than
/// [`MAX_CELLS_PER_AXIS`] cells along an axis, or a non-finite field value.
pub fn polygonize(
    field: &(impl ImplicitField + ?Sized),
    t: f64,
    bounds: [DVec3; 2],
    cell: f64,
) -> Result<Polygonization, ImplicitError> {
    let s = sample(field, t, bounds, cell)?;
    let [px, py, pz] = s.points;
    let slab = px * py;
    // Phase 1: one vertex per crossed edge, numbered slab by slab.
    let mut edge_ids = vec![u32::MAX; 7 * s.values.len()];
    let slab_positions: Vec<Vec<DVec3>> = edge_ids
        .par_chunks_mut(7 * slab)
        .enumerate()
        .map(|(k, ids)| {
            let mut out = Vec::new();
            for j in 0..py {
                for i in 0..px {
                    let a = s.index(i, j, k);
                    let va = s.values[a];
                    for dir in 1u8..8 {
                        let (di, dj, dk) = bits(dir);
                        if i + di >= px || j + dj >= py || k + dk >= pz {
                            continue;
                        }
                        let b = s.index(i + di, j + dj, k + dk);
                        let vb = s.values[b];
                        if (va > 0.0) == (vb > 0.0) {
                            continue;
                        }
                        // Interpolate from the outside end: independent of the order.
                        let (po, pi, fo, fi) = if va > 0.0 {
                            (
                                s.position(i + di, j + dj, k + dk),
                                s.position(i, j, k),
                                vb,
                                va,
                            )
                        } else {
                            (
                                s.position(i, j, k),
                                s.position(i + di, j + dj, k + dk),
                                va,
                                vb,
                            )
                        };
                        let u = (fo / (fo - fi)).clamp(EDGE_MARGIN, 1.0 - EDGE_MARGIN);
                        ids[7 * (i + px * j) + (dir as usize - 1)] = out.len() as u32;
                        out.push(po + (pi - po) * u);
                    }
                }
            }
            out
        })
        .collect();
    let mut offsets = Vec::with_capacity(slab_positions.len());
    let mut total = 0usize;
    for v in &slab_positions {
        offsets.push(total as u32);
        total += v.len();
    }
    if total > u32::MAX as usize {
        return Err(invalid(
            "polygonize",
            "cell",
            cell,
            "a grid with < 2^32 surface vertices",
        ));
    }
    edge_ids
        .par_chunks_mut(7 * slab)
        .zip(offsets.par_iter())
        .for_each(|(ids, &off)| {
            for id in ids.iter_mut().filter(|id| **id != u32::MAX) {
                *id += off;
            }
        });
    let positions: Vec<DVec3> = slab_positions.into_iter().flatten().collect();
    // Phase 2: triangles, cube by cube.
    let corner_offset: [usize; 8] = std::array::from_fn(|c| {
        let (di, dj, dk) = bits(c as u8);
        di + px * (dj + py * dk)
    });
    let slab_tris: Vec<Vec<[u32; 3]>> = (0..pz - 1)
        .into_par_iter()
        .map(|k| {
            let mut out = Vec::new();
            for j in 0..py - 1 {
                for i in 0..px - 1 {
                    let base = s.index(i, j, k);
                    let inside: [bool; 8] =
                        std::array::from_fn(|c| s.values[base + corner_offset[c]] > 0.0);
                    if inside.iter().all(|&x| x == inside[0]) {
                        continue;
                    }
                    let edge = |lo: u8, hi: u8| -> (u32, DVec3) {
                        let (lo, hi) = if lo & hi == lo { (lo, hi) } else { (hi, lo) };
                        let p = base + corner_offset[lo as usize];
                        let id = edge_ids[7 * p + ((hi ^ lo) as usize - 1)];
                        // Direction from the inside end to the outside end.
                        let d = corner_vec(hi) - corner_vec(lo);
                        (id, if inside[lo as usize] { d } else { -d })
                    };
                    for tet in KUHN {
                        emit_tet(tet, &inside, &edge, &positions, &mut out);
                    }
                }
            }
            out
        })
        .collect();
    let triangles = slab_tris.into_iter().flatten().collect();
    Ok(Polygonization {
        positions,
        triangles,
    })
}

/// [`polygonize`] as a [`LabeledMesh`] with labels `[front, back] = [0, 1]` (outside,
/// inside). Fails with [`ImplicitError::EmptySurface`] when there is no surface.
pub fn polygonize_mesh(
    field: &(impl ImplicitField + ?Sized),
    t: f64,
    bounds: [DVec3; 2],
    cell: f64,
) -> Result<LabeledMesh, ImplicitError> {
    let p = polygonize(field, t, bounds, cell)?;
    if p.triangles.is_empty() {
        return Err(ImplicitError::EmptySurface {
            stage: "polygonize",
            t,
        });
    }
    let labels = vec![[Label::OUTSIDE.raw(), 1]; p.triangles.len()];
    LabeledMesh::from_raw(p.positions, &p.triangles, &labels).map_err(|source| {
        ImplicitError::Mesh {
            stage: "polygonize",
            source,
        }
    })
}

fn bits(c: u8) -> (usize, usize, usize) {
    (
        (c & 1) as usize,
        ((c >> 1) & 1) as usize,
        ((c >> 2) & 1) as usize,
    )
}

fn corner_vec(c: u8) -> DVec3 {
    let (a, b, d) = bits(c);
    DVec3::new(a as f64, b as f64, d as f64)
}

/// Emits the zero, one or two triangles of one tetrahedron.
fn emit_tet(
    tet: [u8; 4],
    inside: &[bool; 8],
    edge: &impl Fn(u8, u8) -> (u32, DVec3),
    positions: &[DVec3],
    out: &mut Vec<[u32; 3]>,
) {
    let ins: [bool; 4] = tet.map(|c| inside[c as usize]);
    let count = ins.iter().filter(|&&x| x).count();
    let mut push = |a: (u32, DVec3), b: (u32, DVec3), c: (u32, DVec3)| {
        let (pa, pb, pc) = (
            positions[a.0 as usize],
            positions[b.0 as usize],
            positions[c.0 as usize],
        );
        let n = (pb - pa).cross(pc - pa);
        // The outward direction of any crossed edge of the tetrahedron agrees with the
        // triangle's outward normal (the triangle separates inside from outside corners).
        out.push(if n.dot(a.1) >= 0.0 {
            [a.0, b.0, c.0]
        } else {
            [a.0, c.0, b.0]
        });
    };
    match count {
        1 | 3 => {
            let odd = count == 1;
            let Some(i) = (0..4).find(|&i| ins[i] == odd) else {
                return;
            };
            let others: Vec<u8> = (0..4).filter(|&j| j != i).map(|j| tet[j]).collect();
            let a = tet[i];
            push(edge(a, others[0]), edge(a, others[1]), edge(a, others[2]));
        }
        2 => {
            let mut inn = (0..4).filter(|&j| ins[j]).map(|j| tet[j]);
            let mut outs = (0..4).filter(|&j| !ins[j]).map(|j| tet[j]);
            let (Some(a), Some(b), Some(c), Some(d)) =
                (inn.next(), inn.next(), outs.next(), outs.next())
            else {
                return;
            };
            // The quad ac–ad–bd–bc, cut along ac–bd.
            let (ac, ad, bd, bc) = (edge(a, c), edge(a, d), edge(b, d), edge(b, c));
            push(ac, ad, bd);
            push(ac, bd, bc);
        }
        _ => {}
    }
}

fn sample(
    field: &(impl ImplicitField + ?Sized),
    t: f64,
    bounds: [DVec3; 2],
    cell: f64,
) -> Result<Samples, ImplicitError> {
    let [lo, hi] = bounds;
    if !(lo.is_finite() && hi.is_finite() && lo.cmple(hi).all()) {
        return Err(invalid(
            "polygonize",
            "bounds",
            format!("{lo}..{hi}"),
            "a finite, non-empty box",
        ));
    }
    if !(cell.is_finite() && cell > 0.0) {
        return Err(invalid("polygonize", "cell", cell, "finite and > 0"));
    }
    let origin = lo - DVec3::splat(cell);
    let cells = ((hi - lo) / cell + 2.0).ceil();
    if cells.max_element() > MAX_CELLS_PER_AXIS as f64 {
        return Err(invalid(
            "polygonize",
            "cell",
            cell,
            "coarse enough for at most 1024 cells per axis",
        ));
    }
    let points = [cells.x, cells.y, cells.z].map(|c| (c as usize).max(1) + 1);
    let mut s = Samples {
        origin,
        cell,
        points,
        values: vec![0.0; points[0] * points[1] * points[2]],
    };
    let [px, py, pz] = points;
    let bad = s
        .values
        .par_chunks_mut(px * py)
        .enumerate()
        .map(|(k, slab)| {
            for j in 0..py {
                for i in 0..px {
                    let p = origin + DVec3::new(i as f64, j as f64, k as f64) * cell;
                    let v = field.value(p, t);
                    if !v.is_finite() {
                        return Some(p);
                    }
                    let boundary =
                        i == 0 || j == 0 || k == 0 || i + 1 == px || j + 1 == py || k + 1 == pz;
                    slab[i + px * j] = if boundary { -v.abs() } else { v };
                }
            }
            None
        })
        .find_any(|x| x.is_some())
        .flatten();
    if let Some(p) = bad {
        return Err(ImplicitError::NonFiniteField {
            stage: "polygonize",
            at: p.to_array(),
            t,
        });
    }
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::SphereField;
    use mesh_core::geometry::label_volumes;
    use mesh_core::validate::{ValidateOptions, validate};

    #[test]
    fn a_sphere_polygonizes_valid_closed_outward_and_with_the_right_volume() {
        let s = SphereField::new(DVec3::new(0.013, -0.021, 0.007), 0.5);
        let mesh = polygonize_mesh(&s, 0.0, s.bounds(0.0).unwrap(), 0.05).unwrap();
        let report = validate(&mesh, &ValidateOptions::with_intersections());
        assert!(report.is_valid(), "{report}");
        let vol = label_volumes(&mesh)[&Label::new(1)];
        let exact = 4.0 / 3.0 * std::f64::consts::PI * 0.125;
        assert!((vol - exact).abs() < 0.02 * exact, "{vol} vs {exact}");
        for v in mesh.vertices() {
            assert!((s.value(mesh.position(v), 0.0)).abs() < 0.01);
        }
    }

    #[test]
    fn no_surface_is_an_empty_result_and_bad_input_an_error() {
        let s = SphereField::new(DVec3::ZERO, 0.5);
        let far = [DVec3::splat(3.0), DVec3::splat(4.0)];
        assert!(polygonize(&s, 0.0, far, 0.1).unwrap().triangles.is_empty());
        assert!(matches!(
            polygonize_mesh(&s, 0.0, far, 0.1),
            Err(ImplicitError::EmptySurface { .. })
        ));
        assert!(polygonize(&s, 0.0, far, 0.0).is_err());
        assert!(polygonize(&s, 0.0, [DVec3::ONE, DVec3::ZERO], 0.1).is_err());
        assert!(polygonize(&s, 0.0, [DVec3::ZERO, DVec3::splat(100.0)], 0.01).is_err());
    }
}
