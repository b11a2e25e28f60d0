//! The cotangent Laplacian and lumped mass of a labelled mesh, assembled once per step and
//! shared by both time discretisations of mean curvature flow: the forward Euler velocity
//! `−γ M⁻¹ L x` and the backward Euler solve `(M + γ dt L) x' = M x`.
//!
//! **Operator.** Over the *union* of all live triangles, each triangle once whatever its
//! labels (the multi-material surface is one non-manifold surface, and its mean curvature
//! flow is the gradient descent of its total area; Los Topos §8.2):
//! `(L x)ᵢ = Σ_t∋i Σ_{j ∈ t} ½ cot γ_t(i, j) (xᵢ − xⱼ)` with `γ_t(i, j)` the angle of `t`
//! opposite edge `ij`. That is exactly the gradient of the total area with respect to
//! `xᵢ` (Meyer et al. 2003, eq. 8), summed over every sheet at a non-manifold vertex, so
//! a triple curve whose sheets meet at 120° feels no force. `L` is symmetric positive
//! semi-definite for *any* non-degenerate triangles (it is the Hessian of the piecewise
//! linear Dirichlet energy `½ Σ_t area_t |∇u|²`, a sum of one semi-definite term per
//! triangle), obtuse ones included; its constant vectors are the null space.
//!
//! **Mass.** `M = diag(A_mixed(i))`, Meyer's mixed Voronoi area (Fig. 4 of the paper): the
//! Voronoi area `⅛(|xᵢ − xⱼ|² cot γₖ + |xᵢ − xₖ|² cot γⱼ)` of a non-obtuse triangle, half
//! the triangle's area if the angle at `i` is obtuse, a quarter if another angle is. The
//! mixed areas tile the surface, so `M` is a lumped mass; `M⁻¹ L x` is Meyer's
//! mean-curvature normal `K(xᵢ)` with `|K| = κ₁ + κ₂`.
//!
//! **Degenerate triangles** (zero or non-finite area) contribute neither weight nor mass:
//! their cotangents are undefined and their area gradient is zero.
//!
//! **Storage.** Struct of arrays over vertex slots: row `i` holds two entries
//! `(j, ½ cot)` per live incident triangle (an edge shared by several triangles appears
//! once per triangle; summing duplicates in a product is the same as merging them first,
//! and needs no sort). Rows are filled in triangle order, so every product sums in one
//! fixed order: results are identical for any thread count.

use glam::DVec3;
use mesh_core::LabeledMesh;
use rayon::prelude::*;

/// Rows per rayon task in the products.
const ROWS_PER_TASK: usize = 512;

/// Cotangent Laplacian `L` and lumped mass `M` of a mesh (see the module doc).
#[derive(Clone, Debug, Default)]
pub struct CotanLaplacian {
    /// Entries of row `i` are `row_start[i]..row_start[i + 1]` (one more than slots).
    row_start: Vec<u32>,
    /// Neighbour vertex slot of every entry.
    col: Vec<u32>,
    /// `½ cot` of the angle opposite the entry's edge in one triangle.
    weight: Vec<f64>,
    /// Mixed area per vertex slot (0 for dead, isolated or fully degenerate vertices).
    mass: Vec<f64>,
}

/// Half cotangents `½ cot` of the angles at corners 0, 1, 2 (the weight of the opposite
/// edge) and Meyer's mixed area at each corner, of a triangle with corners `p`; `None`
/// when its area is zero or not finite.
fn triangle_weights(p: [DVec3; 3]) -> Option<([f64; 3], [f64; 3])> {
    let cross = (p[1] - p[0]).cross(p[2] - p[0]);
    let double_area = cross.length();
    if !(double_area > 0.0 && double_area.is_finite()) {
        return None;
    }
    let mut half_cot = [0.0; 3];
    for (k, c) in half_cot.iter_mut().enumerate() {
        let (a, b) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
        *c = 0.5 * a.dot(b) / double_area;
    }
    let area = 0.5 * double_area;
    let mut mixed = [0.0; 3];
    let obtuse = half_cot.iter().position(|&c| c < 0.0);
    for (i, m) in mixed.iter_mut().enumerate() {
        let (j, k) = ((i + 1) % 3, (i + 2) % 3);
        *m = match obtuse {
            Some(o) if o == i => area / 2.0,
            Some(_) => area / 4.0,
            // ⅛(|xᵢ − xⱼ|² cot γₖ + |xᵢ − xₖ|² cot γⱼ), with the half cotangents.
            None => {
                ((p[i] - p[j]).length_squared() * half_cot[k]
                    + (p[i] - p[k]).length_squared() * half_cot[j])
                    / 4.0
            }
        };
    }
    Some((half_cot, mixed))
}

impl CotanLaplacian {
    /// Assembles `L` and `M` of the live triangles of `mesh` at its current positions.
    pub fn of(mesh: &LabeledMesh) -> Self {
        Self::at(mesh, mesh.positions())
    }

    /// Assembles `L` and `M` of the live triangles of `mesh` at positions `x` (one per
    /// vertex slot).
    pub fn at(mesh: &LabeledMesh, x: &[DVec3]) -> Self {
        let (tris, alive) = (mesh.tris(), mesh.tri_alive_flags());
        let n = mesh.vertex_capacity();
        let per_tri: Vec<Option<([f64; 3], [f64; 3])>> = (0..tris.len())
            .into_par_iter()
            .with_min_len(ROWS_PER_TASK)
            .map(|t| {
                if alive[t] {
                    triangle_weights(tris[t].map(|v| x[v.idx()]))
                } else {
                    None
                }
            })
            .collect();
        let mut row_start = vec![0u32; n + 1];
        for (t, w) in per_tri.iter().enumerate() {
            if w.is_some() {
                for v in tris[t] {
                    row_start[v.idx() + 1] += 2;
                }
            }
        }
        for i in 0..n {
            row_start[i + 1] += row_start[i];
        }
        let entries = row_start[n] as usize;
        let (mut col, mut weight) = (vec![0u32; entries], vec![0.0; entries]);
        let mut fill: Vec<u32> = row_start[..n].to_vec();
        let mut mass = vec![0.0; n];
        for (t, w) in per_tri.iter().enumerate() {
            let Some((half_cot, mixed)) = w else {
                continue;
            };
            let v = tris[t].map(|v| v.idx());
            for i in 0..3 {
                let (j, k) = ((i + 1) % 3, (i + 2) % 3);
                let at = fill[v[i]] as usize;
                // Edge ij is opposite corner k, edge ik opposite corner j.
                col[at] = v[j] as u32;
                weight[at] = half_cot[k];
                col[at + 1] = v[k] as u32;
                weight[at + 1] = half_cot[j];
                fill[v[i]] += 2;
                mass[v[i]] += mixed[i];
            }
        }
        CotanLaplacian {
            row_start,
            col,
            weight,
            mass,
        }
    }

    /// Number of vertex slots.
    pub fn len(&self) -> usize {
        self.mass.len()
    }

    /// Whether the operator has no vertex slot.
    pub fn is_empty(&self) -> bool {
        self.mass.is_empty()
    }

    /// Mixed area of every vertex slot (the diagonal of `M`).
    pub fn mass(&self) -> &[f64] {
        &self.mass
    }

    fn row(&self, i: usize) -> std::ops::Range<usize> {
        self.row_start[i] as usize..self.row_start[i + 1] as usize
    }

    /// `Σⱼ wᵢⱼ` of row `i`: the diagonal of `L`, positive whenever the row has an entry
    /// (per triangle `½(cot β + cot γ) = sin α / (2 sin β sin γ) > 0`).
    pub fn diagonal(&self, i: usize) -> f64 {
        self.weight[self.row(i)].iter().sum()
    }

    /// `(L x)ᵢ` of one row, `x` interleaved (`3i + axis`).
    #[inline]
    fn apply_row(&self, i: usize, x: &[f64]) -> [f64; 3] {
        let r = self.row(i);
        let xi = [x[3 * i], x[3 * i + 1], x[3 * i + 2]];
        let mut y = [0.0; 3];
        for (&j, &w) in self.col[r.clone()].iter().zip(&self.weight[r]) {
            let j = 3 * j as usize;
            for a in 0..3 {
                y[a] += w * (xi[a] - x[j + a]);
            }
        }
        y
    }

    /// `y = (α M + β L) x` with `x`, `y` interleaved per vertex slot (`3i + axis`), in
    /// parallel (each row sums in a fixed order, so any thread count gives the same `y`).
    pub fn combine(&self, alpha: f64, beta: f64, x: &[f64], y: &mut [f64]) {
        y.par_chunks_mut(3)
            .with_min_len(ROWS_PER_TASK)
            .enumerate()
            .for_each(|(i, y)| {
                let l = self.apply_row(i, x);
                let m = alpha * self.mass[i];
                for a in 0..3 {
                    y[a] = m * x[3 * i + a] + beta * l[a];
                }
            });
    }

    /// `L x` per vertex slot: the gradient of the total area when `x` are the positions
    /// the operator was assembled at.
    pub fn apply(&self, x: &[DVec3]) -> Vec<DVec3> {
        let flat = flatten(x);
        let mut y = vec![0.0; flat.len()];
        self.combine(0.0, 1.0, &flat, &mut y);
        unflatten(&y)
    }

    /// Meyer's mean-curvature normal `K = M⁻¹ L x` per slot (zero where the mass is 0 or
    /// the result not finite).
    pub fn mean_curvature_normals(&self, x: &[DVec3]) -> Vec<DVec3> {
        let mut k = self.apply(x);
        for (k, &m) in k.iter_mut().zip(&self.mass) {
            let v = *k / m;
            *k = if m > 0.0 && v.is_finite() {
                v
            } else {
                DVec3::ZERO
            };
        }
        k
    }

    /// `maxᵢ Σⱼ |wᵢⱼ| / Mᵢ`: with it, Gershgorin bounds the spectrum of `M⁻¹ L` by twice
    /// this, so forward Euler with speed `γ` is stable for `dt ≤ 1 / (γ ·` this `)`; 0 for
    /// an operator without entries.
    pub fn gershgorin_rate(&self) -> f64 {
        (0..self.len())
            .into_par_iter()
            .with_min_len(ROWS_PER_TASK)
            .map(|i| {
                let m = self.mass[i];
                if m > 0.0 {
                    self.weight[self.row(i)]
                        .iter()
                        .map(|w| w.abs())
                        .sum::<f64>()
                        / m
                } else {
                    0.0
                }
            })
            .reduce(|| 0.0, f64::max)
    }
}

/// Conjugate-gradient iterations of one backward Euler solve, at most.
pub const SOLVE_ITERATIONS: usize = 1000;
/// The solve stops when its residual is below this fraction of the right-hand side.
pub const SOLVE_TOLERANCE: f64 = 1e-10;

/// One backward Euler step of mean curvature flow ([`CotanLaplacian::backward_euler`]).
#[derive(Clone, Debug)]
pub struct BackwardEulerStep {
    /// New position of every vertex slot (unchanged where nothing could move).
    pub positions: Vec<DVec3>,
    /// `‖A d − b‖ / ‖b‖` over the free coordinates after the solve (0 when there was
    /// nothing to solve): how well the linear system was solved.
    pub relative_residual: f64,
}

impl CotanLaplacian {
    /// One linearly implicit (backward Euler) step of mean curvature flow with
    /// `c = γ dt` from positions `x` (the positions this operator was assembled at):
    /// `(M + c L) x' = M x`, i.e. `x' = x + d` with `(M + c L) d = −c L x`.
    ///
    /// `held[i]` bit `a` set keeps coordinate `a` of slot `i` at `xᵢ` (Dirichlet: the
    /// unknown is removed, which leaves a principal submatrix of an SPD matrix, still
    /// SPD); slots without mass (dead, isolated) stay put. Solved by mesh-core's
    /// Jacobi-preconditioned conjugate gradients on the interleaved `3n` unknowns (the
    /// matrix is `M + c L` once per axis, so the three coordinates decouple and one CG
    /// solves them together), at most [`SOLVE_ITERATIONS`] to [`SOLVE_TOLERANCE`].
    ///
    /// Why it is stable for every `dt`: `M + c L` is SPD and `x'` minimises
    /// `½‖x' − x‖²_M + ½ c x'ᵀ L x'` (the linearised area), so no mode grows; a sphere
    /// shrinks to `r / (1 + 2c/r²)` instead of exploding. Large steps over-damp but
    /// never blow up, which is what lets the foam take steps set by the tracker.
    pub fn backward_euler(&self, x: &[DVec3], c: f64, held: Option<&[u8]>) -> BackwardEulerStep {
        let n = self.len();
        let flat = flatten(&x[..n]);
        let inverse_diagonal: Vec<f64> = (0..3 * n)
            .map(|k| {
                let (i, a) = (k / 3, k % 3);
                let fixed = held.is_some_and(|h| h.get(i).is_some_and(|m| m & (1 << a) != 0));
                let d = self.mass[i] + c * self.diagonal(i);
                if fixed || self.mass[i] <= 0.0 || !(d > 0.0 && d.is_finite()) {
                    0.0
                } else {
                    1.0 / d
                }
            })
            .collect();
        let mut rhs = vec![0.0; 3 * n];
        self.combine(0.0, -c, &flat, &mut rhs);
        let keep_free = |r: &mut [f64]| {
            for (r, &inv) in r.iter_mut().zip(&inverse_diagonal) {
                if inv == 0.0 {
                    *r = 0.0;
                }
            }
        };
        keep_free(&mut rhs);
        let d = mesh_core::solve::conjugate_gradients(
            &rhs,
            &inverse_diagonal,
            SOLVE_TOLERANCE,
            SOLVE_ITERATIONS,
            |p, ap| self.combine(1.0, c, p, ap),
            keep_free,
        );
        let mut ad = vec![0.0; 3 * n];
        self.combine(1.0, c, &d, &mut ad);
        keep_free(&mut ad);
        let norm = |v: &mut dyn Iterator<Item = f64>| v.map(|e| e * e).sum::<f64>().sqrt();
        let b = norm(&mut rhs.iter().copied());
        let relative_residual = if b > 0.0 {
            norm(&mut ad.iter().zip(&rhs).map(|(a, b)| a - b)) / b
        } else {
            0.0
        };
        let mut positions = x.to_vec();
        for (i, p) in positions.iter_mut().enumerate().take(n) {
            let step = DVec3::from_slice(&d[3 * i..3 * i + 3]);
            if step.is_finite() {
                *p += step;
            }
        }
        BackwardEulerStep {
            positions,
            relative_residual,
        }
    }
}

/// `[x0, y0, z0, x1, …]` of a slice of vectors.
pub(crate) fn flatten(x: &[DVec3]) -> Vec<f64> {
    x.iter().flat_map(|v| v.to_array()).collect()
}

/// The vectors of an interleaved slice.
pub(crate) fn unflatten(x: &[f64]) -> Vec<DVec3> {
    x.chunks_exact(3).map(DVec3::from_slice).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flows::test_meshes::{icosphere, outside_inside, triple_fan};
    use mesh_core::Label;

    #[test]
    fn laplacian_of_the_positions_is_the_area_gradient() {
        let [a, b, c] = [
            DVec3::new(0.1, -0.2, 0.3),
            DVec3::new(1.3, 0.1, -0.2),
            DVec3::new(0.4, 0.9, 0.5),
        ];
        let mesh = LabeledMesh::from_raw(vec![a, b, c], &[[0, 1, 2]], &[[0, 1]]).unwrap();
        let lap = CotanLaplacian::of(&mesh);
        let grad = lap.apply(mesh.positions());
        let area = |a: DVec3| 0.5 * (b - a).cross(c - a).length();
        let h = 1e-6;
        let fd = DVec3::new(
            area(a + h * DVec3::X) - area(a - h * DVec3::X),
            area(a + h * DVec3::Y) - area(a - h * DVec3::Y),
            area(a + h * DVec3::Z) - area(a - h * DVec3::Z),
        ) / (2.0 * h);
        assert!((grad[0] - fd).length() < 1e-8, "{} vs {fd}", grad[0]);
        // The gradient of a triangle's area is perpendicular to the opposite edge, in its
        // plane, of length half that edge: ½ n̂ × (c − b).
        let n = (b - a).cross(c - a).normalize();
        assert!((grad[0] - 0.5 * n.cross(c - b)).length() < 1e-14);
    }

    #[test]
    fn symmetric_and_positive_semi_definite_on_a_non_manifold_mesh() {
        // A triple fan (three sheets on one curve) has an obtuse-free but non-manifold
        // stencil; check xᵀ L y = yᵀ L x and xᵀ L x ≥ 0 for some arbitrary fields.
        let mesh = triple_fan(Label::new(1), Label::new(2), Label::new(0));
        let lap = CotanLaplacian::of(&mesh);
        let n = lap.len();
        let field = |s: f64| -> Vec<DVec3> {
            (0..n)
                .map(|i| {
                    let t = i as f64 * s;
                    DVec3::new(t.sin(), (2.0 * t).cos(), (0.5 + t).sin())
                })
                .collect()
        };
        let (x, y) = (field(0.7), field(1.9));
        let (lx, ly) = (lap.apply(&x), lap.apply(&y));
        let dot = |a: &[DVec3], b: &[DVec3]| a.iter().zip(b).map(|(p, q)| p.dot(*q)).sum::<f64>();
        let (xly, ylx) = (dot(&x, &ly), dot(&y, &lx));
        assert!(
            (xly - ylx).abs() < 1e-12 * xly.abs().max(1.0),
            "{xly} vs {ylx}"
        );
        assert!(dot(&x, &lx) > 0.0 && dot(&y, &ly) > 0.0);
        // Constants are the null space.
        let l1 = lap.apply(&vec![DVec3::ONE; n]);
        assert!(l1.iter().all(|v| v.length() < 1e-12));
    }

    #[test]
    fn mixed_areas_tile_the_surface_and_the_sphere_has_curvature_two_over_r() {
        let r = 1.3;
        let mesh = icosphere(3, r, outside_inside());
        let lap = CotanLaplacian::of(&mesh);
        let total: f64 = lap.mass().iter().sum();
        let exact: f64 = mesh
            .triangles()
            .map(|t| mesh_core::geometry::triangle_area(&mesh.tri_positions(t)))
            .sum();
        assert!((total - exact).abs() < 1e-12 * exact, "{total} vs {exact}");
        let k = lap.mean_curvature_normals(mesh.positions());
        for v in mesh.vertices() {
            let radial = k[v.idx()].dot(mesh.position(v).normalize());
            assert!((radial - 2.0 / r).abs() < 1e-9, "{v:?}: {radial}");
        }
    }

    #[test]
    fn degenerate_triangles_carry_nothing() {
        let p = [DVec3::ZERO, DVec3::X, 2.0 * DVec3::X];
        assert!(triangle_weights(p).is_none());
        assert!(triangle_weights([DVec3::ZERO, DVec3::X, DVec3::NAN]).is_none());
        let (_, mixed) = triangle_weights([DVec3::ZERO, DVec3::X, DVec3::Y]).unwrap();
        // Right angle at corner 0: non-obtuse, Voronoi areas; they sum to the area ½.
        assert!((mixed.iter().sum::<f64>() - 0.5).abs() < 1e-15);
        let (_, mixed) =
            triangle_weights([DVec3::ZERO, DVec3::X, DVec3::new(-1.0, 0.1, 0.0)]).unwrap();
        // Obtuse at corner 0: half there, a quarter at the others.
        assert!((mixed[0] - 2.0 * mixed[1]).abs() < 1e-15 && mixed[1] == mixed[2]);
    }
}
