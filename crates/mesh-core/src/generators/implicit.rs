//! Meshing the zero set of an implicit function by marching tetrahedra.
//!
//! The box is cut into cubes and every cube into the six Kuhn tetrahedra along its main
//! diagonal (`000 → 111`, one per order of the three axes). All cubes are cut the same way,
//! so every cube face is split along the same diagonal from both sides and the surface is
//! watertight by construction. In each tetrahedron the sign pattern of the four corner
//! values gives no triangle, one (one corner differs) or two (a 2–2 split); surface
//! vertices sit on the sign-changing grid edges by linear interpolation, and are welded by
//! the grid edge they lie on, so neighbours share them exactly.
//!
//! Robustness (why no triangle is degenerate): a corner counts as inside iff `f < 0`, so
//! `f = 0` is outside, and the interpolation parameter is clamped to `[δ, 1 − δ]` with
//! `δ =` [`EDGE_MARGIN`]. Every surface vertex is then strictly inside its grid edge, and
//! three points strictly inside three distinct edges of a tetrahedron are never collinear
//! (two of the edges span a face, and the third edge leaves that face's plane except at a
//! corner). Distinct grid edges meet only at grid points, so no two vertices coincide.
//!
//! Orientation: with the tetrahedron's corners `(a, b, c, d)` positively oriented, the
//! triangle through the edges `ab, ac, ad` has its normal pointing away from `a`, and for a
//! 2–2 split `{a, b} | {c, d}` the triangles `(ac, ad, bd)` and `(ac, bd, bc)` point away
//! from `a` and `b` (both follow from the sign of `orient3d` in a limit where the
//! triangle degenerates onto tetrahedron corners; the orientation cannot flip in between
//! since the triangle never degenerates). Corners are permuted to an even permutation of
//! the positively oriented tetrahedron before applying these rules.

use std::collections::HashMap;

use glam::DVec3;
use rayon::prelude::*;

use super::error::{GeneratorError, check_box, invalid};
use crate::ids::Label;
use crate::mesh::LabeledMesh;

/// Smallest distance of a surface vertex from a grid point, as a fraction of its edge.
pub const EDGE_MARGIN: f64 = 1e-3;

/// Largest accepted number of cells per axis (the grid of values then takes ~1 GB).
pub const MAX_CELLS_PER_AXIS: usize = 512;

/// The six Kuhn tetrahedra of a cube, as cube corners (bit 0 = x, bit 1 = y, bit 2 = z),
/// each listed in positive orientation (`orient3d > 0` for an axis-aligned cube).
/// Path `0 → e_σ0 → e_σ0 + e_σ1 → 7`; odd permutations σ have their last two corners
/// swapped to make the orientation positive.
const KUHN_TETS: [[u8; 4]; 6] = [
    [0, 1, 3, 7], // x, y, z (even)
    [0, 1, 7, 5], // x, z, y (odd, swapped)
    [0, 2, 7, 3], // y, x, z (odd, swapped)
    [0, 2, 6, 7], // y, z, x (even)
    [0, 4, 5, 7], // z, x, y (even)
    [0, 4, 7, 6], // z, y, x (odd, swapped)
];

/// Parity of a permutation of `0..4` (true if odd), by counting inversions.
fn is_odd(p: [usize; 4]) -> bool {
    let mut inversions = 0;
    for i in 0..4 {
        for j in i + 1..4 {
            inversions += usize::from(p[i] > p[j]);
        }
    }
    inversions % 2 == 1
}

/// The sampled grid: `n + 1` points per axis over `[min, max]`.
struct Grid {
    min: DVec3,
    step: DVec3,
    n: usize,
    values: Vec<f64>,
}

impl Grid {
    fn points(&self) -> usize {
        self.n + 1
    }

    fn index(&self, i: usize, j: usize, k: usize) -> usize {
        let g = self.points();
        i + g * (j + g * k)
    }

    fn position_of(&self, index: usize) -> DVec3 {
        let g = self.points();
        let (i, j, k) = (index % g, (index / g) % g, index / (g * g));
        self.min + self.step * DVec3::new(i as f64, j as f64, k as f64)
    }

    /// Samples `f` at every grid point in parallel. Points on the box boundary are forced
    /// outside (`|f|`), so the surface is closed even where `f` is negative at the box.
    fn sample(
        f: &(impl Fn(DVec3) -> f64 + Sync),
        min: DVec3,
        max: DVec3,
        n: usize,
    ) -> Result<Grid, GeneratorError> {
        let g = n + 1;
        let mut grid = Grid {
            min,
            step: (max - min) / n as f64,
            n,
            values: vec![0.0; g * g * g],
        };
        let step = grid.step;
        grid.values
            .par_chunks_mut(g * g)
            .enumerate()
            .try_for_each(|(k, slab)| {
                for j in 0..g {
                    for i in 0..g {
                        let p = min + step * DVec3::new(i as f64, j as f64, k as f64);
                        let v = f(p);
                        if !v.is_finite() {
                            return Err(GeneratorError::NonFiniteField { at: p });
                        }
                        let boundary = [i, j, k].iter().any(|&c| c == 0 || c == n);
                        slab[i + g * j] = if boundary { v.abs() } else { v };
                    }
                }
                Ok(())
            })?;
        Ok(grid)
    }
}

/// Builds the triangles, welding vertices by grid edge.
struct Builder<'a> {
    grid: &'a Grid,
    edge_vertex: HashMap<u64, u32>,
    positions: Vec<DVec3>,
    tris: Vec<[u32; 3]>,
}

impl Builder<'_> {
    /// The surface vertex on the grid edge between points `a` and `b` (one inside, one
    /// outside), created on first use. The edge runs between comparable corners of a cube,
    /// so `(lower point, axis bits of the step)` names it.
    fn vertex(&mut self, a: usize, b: usize) -> u32 {
        let (lo, hi) = (a.min(b), a.max(b));
        let g = self.grid.points();
        let d = hi - lo;
        // d = dx + dy·g + dz·g² with each step 0 or 1.
        let bits = (d % g) as u64 | u64::from(d % (g * g) >= g) << 1 | u64::from(d >= g * g) << 2;
        let key = (lo as u64) << 3 | bits;
        let (grid, positions) = (self.grid, &mut self.positions);
        *self.edge_vertex.entry(key).or_insert_with(|| {
            // Interpolate from the outside end so the result does not depend on the order.
            let (out, inn) = if grid.values[lo] >= 0.0 {
                (lo, hi)
            } else {
                (hi, lo)
            };
            let (fo, fi) = (grid.values[out], grid.values[inn]);
            let t = (fo / (fo - fi)).clamp(EDGE_MARGIN, 1.0 - EDGE_MARGIN);
            let (po, pi) = (grid.position_of(out), grid.position_of(inn));
            positions.push(po + (pi - po) * t);
            (positions.len() - 1) as u32
        })
    }

    /// Emits the triangles of one tetrahedron, corners positively oriented.
    fn tetrahedron(&mut self, corners: [usize; 4]) {
        let inside = corners.map(|c| self.grid.values[c] < 0.0);
        let count = inside.iter().filter(|&&x| x).count();
        match count {
            1 | 3 => {
                let minority = count == 1;
                let Some(i) = (0..4).find(|&i| inside[i] == minority) else {
                    return;
                };
                let mut p = [i, (i + 1) % 4, (i + 2) % 4, (i + 3) % 4];
                p[1..].sort_unstable();
                if is_odd(p) {
                    p.swap(2, 3);
                }
                let [a, b, c, d] = p.map(|k| corners[k]);
                let (ab, ac, ad) = (self.vertex(a, b), self.vertex(a, c), self.vertex(a, d));
                // The normal points away from `a`: outward when `a` is the inside corner.
                self.tris.push(if inside[i] {
                    [ab, ac, ad]
                } else {
                    [ab, ad, ac]
                });
            }
            2 => {
                let mut ins = (0..4).filter(|&k| inside[k]);
                let mut outs = (0..4).filter(|&k| !inside[k]);
                let (Some(i), Some(j), Some(k), Some(l)) =
                    (ins.next(), ins.next(), outs.next(), outs.next())
                else {
                    return;
                };
                let mut p = [i, j, k, l];
                if is_odd(p) {
                    p.swap(2, 3);
                }
                let [a, b, c, d] = p.map(|k| corners[k]);
                let (ac, ad) = (self.vertex(a, c), self.vertex(a, d));
                let (bc, bd) = (self.vertex(b, c), self.vertex(b, d));
                self.tris.push([ac, ad, bd]);
                self.tris.push([ac, bd, bc]);
            }
            _ => {}
        }
    }
}

/// Meshes the surface `f = 0` inside the box `bounds = [min, max]`, sampled on a grid of
/// `cells_per_axis` cells along each axis, by marching tetrahedra (see the module doc).
/// `f < 0` is inside; `labels = [outside, inside]` become every triangle's
/// `[front, back]`, with normals pointing out of the inside.
///
/// The result is closed and consistently oriented whatever `f` is: grid points on the box
/// boundary count as outside, so a surface leaving the box is capped just inside it. It
/// has no degenerate triangle and no duplicate vertex, and does not self-intersect (each
/// tetrahedron holds a disjoint piece). Sharp features of `f` are chamfered at the grid
/// scale, and an empty zero set gives an empty mesh.
///
/// Fails on a non-finite or empty box, `cells_per_axis` outside `1..=512`, equal labels,
/// or a non-finite value of `f` at a grid point.
pub fn mesh_implicit(
    f: impl Fn(DVec3) -> f64 + Sync,
    bounds: [DVec3; 2],
    cells_per_axis: usize,
    labels: [Label; 2],
) -> Result<LabeledMesh, GeneratorError> {
    const NAME: &str = "mesh_implicit";
    let [min, max] = bounds;
    check_box(NAME, min, max)?;
    if !(1..=MAX_CELLS_PER_AXIS).contains(&cells_per_axis) {
        return Err(invalid(
            NAME,
            "cells_per_axis",
            cells_per_axis,
            "between 1 and 512",
        ));
    }
    if labels[0] == labels[1] {
        return Err(invalid(
            NAME,
            "labels",
            format!("{labels:?}"),
            "two different labels",
        ));
    }
    let grid = Grid::sample(&f, min, max, cells_per_axis)?;
    let n = cells_per_axis;
    let mut b = Builder {
        grid: &grid,
        edge_vertex: HashMap::new(),
        positions: Vec::new(),
        tris: Vec::new(),
    };
    let offsets = [0usize, 1, 2, 3, 4, 5, 6, 7].map(|c| grid.index(c & 1, (c >> 1) & 1, c >> 2));
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let base = grid.index(i, j, k);
                let corners = offsets.map(|o| base + o);
                let first = grid.values[base] < 0.0;
                if corners.iter().all(|&c| (grid.values[c] < 0.0) == first) {
                    continue;
                }
                for tet in KUHN_TETS {
                    b.tetrahedron(tet.map(|c| corners[c as usize]));
                }
            }
        }
    }
    let pair = labels.map(|l| l.raw());
    let tri_labels = vec![pair; b.tris.len()];
    Ok(LabeledMesh::from_raw(b.positions, &b.tris, &tri_labels)?)
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI;

    use super::*;
    use crate::generators::checks::{assert_well_formed, bounded_volumes};

    const LABELS: [Label; 2] = [Label::new(0), Label::new(1)];

    fn corner(c: u8) -> DVec3 {
        DVec3::new((c & 1) as f64, ((c >> 1) & 1) as f64, (c >> 2) as f64)
    }

    #[test]
    fn kuhn_tetrahedra_are_positive_and_tile_the_cube() {
        let mut total = 0.0;
        for t in KUHN_TETS {
            let [a, b, c, d] = t.map(corner);
            let vol = (b - a).dot((c - a).cross(d - a)) / 6.0;
            assert!(vol > 0.0, "{t:?} is negatively oriented");
            total += vol;
        }
        assert!((total - 1.0).abs() < 1e-15);
    }

    #[test]
    fn parity() {
        assert!(!is_odd([0, 1, 2, 3]));
        assert!(is_odd([1, 0, 2, 3]));
        assert!(!is_odd([1, 2, 0, 3]));
        assert!(is_odd([0, 1, 3, 2]));
        assert!(!is_odd([3, 2, 1, 0]));
    }

    fn ball(c: DVec3, r: f64) -> impl Fn(DVec3) -> f64 + Sync {
        move |p| p.distance(c) - r
    }

    #[test]
    fn ball_volume_converges() {
        let (c, r) = (DVec3::new(0.1, -0.2, 0.3), 0.8f64);
        let exact = 4.0 / 3.0 * PI * r.powi(3);
        let bounds = [c - 1.0, c + 1.0];
        let mut last = f64::INFINITY;
        for n in [8, 16, 32] {
            let m = mesh_implicit(ball(c, r), bounds, n, LABELS).unwrap();
            assert_well_formed(&m);
            let vols = bounded_volumes(&m);
            assert_eq!(vols.len(), 1);
            assert_eq!(vols[0].0, Label::new(1));
            let err = ((vols[0].1 - exact) / exact).abs();
            assert!(err < last, "n = {n}: error {err} after {last}");
            last = err;
        }
        assert!(last < 0.01, "{last}");
        // Normals point outward from the ball.
        let m = mesh_implicit(ball(c, r), bounds, 12, LABELS).unwrap();
        for t in m.triangles() {
            let [a, b, d] = m.tri_positions(t);
            assert!((b - a).cross(d - a).dot((a + b + d) / 3.0 - c) > 0.0);
        }
    }

    #[test]
    fn two_blobs_give_two_shells() {
        let f = |p: DVec3| {
            (p.distance(DVec3::new(-0.5, 0.0, 0.0)) - 0.3)
                .min(p.distance(DVec3::new(0.5, 0.0, 0.0)) - 0.3)
        };
        let m = mesh_implicit(f, [DVec3::splat(-1.0), DVec3::splat(1.0)], 20, LABELS).unwrap();
        assert_well_formed(&m);
        assert_eq!(bounded_volumes(&m).len(), 2);
    }

    #[test]
    fn zeros_on_grid_points_give_no_degenerate_triangles() {
        // The plane x = 0.5 and the box faces of the inside region pass through grid
        // points exactly; a slanted plane through many grid points as well.
        for f in [
            (|p: DVec3| p.x - 0.5) as fn(DVec3) -> f64,
            |p: DVec3| p.x + p.y - 1.0,
            |p: DVec3| (p - DVec3::splat(0.5)).abs().max_element() - 0.25,
        ] {
            let m = mesh_implicit(f, [DVec3::ZERO, DVec3::ONE], 8, LABELS).unwrap();
            assert_well_formed(&m);
        }
    }

    #[test]
    fn surface_leaving_the_box_is_capped() {
        // Everything inside: the mesh is a closed skin just inside the box.
        let m = mesh_implicit(|_| -1.0, [DVec3::ZERO, DVec3::ONE], 4, LABELS).unwrap();
        assert_well_formed(&m);
        let vols = bounded_volumes(&m);
        assert_eq!(vols.len(), 1);
        // Boundary values are |f|, so the cap passes through the midpoints of the first
        // cell layer: every vertex lies on the skin of the cube [1/8, 7/8]³ (with those
        // cube edges whose Kuhn diagonals run across them chamfered).
        for v in m.vertices() {
            let p = m.position(v);
            assert!(
                p.cmpge(DVec3::splat(0.125 - 1e-15)).all()
                    && p.cmple(DVec3::splat(0.875 + 1e-15)).all()
            );
            let on_skin = p
                .to_array()
                .iter()
                .any(|&c| (c - 0.125).abs() < 1e-15 || (c - 0.875).abs() < 1e-15);
            assert!(on_skin, "{p}");
        }
        assert!(
            vols[0].1 > 0.35 && vols[0].1 < 0.75f64.powi(3),
            "{}",
            vols[0].1
        );
    }

    #[test]
    fn empty_zero_set_gives_empty_mesh() {
        let m = mesh_implicit(|_| 1.0, [DVec3::ZERO, DVec3::ONE], 4, LABELS).unwrap();
        assert_eq!(m.num_triangles(), 0);
    }

    #[test]
    fn bad_parameters_are_refused() {
        let b = [DVec3::ZERO, DVec3::ONE];
        assert!(matches!(
            mesh_implicit(|p| if p.x > 0.5 { f64::NAN } else { 1.0 }, b, 4, LABELS),
            Err(GeneratorError::NonFiniteField { .. })
        ));
        assert!(mesh_implicit(|_| 1.0, b, 0, LABELS).is_err());
        assert!(mesh_implicit(|_| 1.0, b, 513, LABELS).is_err());
        assert!(mesh_implicit(|_| 1.0, [DVec3::ONE, DVec3::ZERO], 4, LABELS).is_err());
        assert!(mesh_implicit(|_| 1.0, b, 4, [Label::new(1); 2]).is_err());
    }
}
