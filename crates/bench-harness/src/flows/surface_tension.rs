//! Volume-preserving surface tension in a box with fixed walls: the flow of the
//! `foam-tension` scene (2024 paper Fig. 21–22; Los Topos' foam under mean curvature flow
//! with a volume constraint per bubble).
//!
//! **Discretisation.** One step from positions `x` with step `dt` (`γ` the tension):
//!
//! 1. *Walls*: a vertex of a triangle that touches the outside (label 0) is a wall vertex.
//!    Its coordinate along an axis whose box plane it lies on (within [`WALL_TOLERANCE`] ×
//!    box size; at least the nearest plane) is *held* on that plane, so wall vertices slide
//!    within the walls, along box edges, or stay put at corners. The walls neither move
//!    nor pull: the foam keeps filling the box.
//! 2. *Tension*: one step of [`MeanCurvatureFlow`] on the union of all interface
//!    triangles, each once whatever its labels ([`CotanLaplacian`]: Meyer et al. 2003
//!    cotangent operator, lumped mixed-area mass; at a triple curve every sheet counts, so
//!    the flow is the gradient descent of the total film area and triple curves relax
//!    towards Plateau's 120°). With [`super::McfScheme::BackwardEuler`] (the scene's) that is
//!    the linearly implicit solve `(M + γ dt L) x̃ = M x` with the held coordinates as
//!    Dirichlet constraints (principal submatrix of an SPD matrix: still SPD, solved by
//!    Jacobi-preconditioned CG), stable for any `dt`; with forward Euler
//!    `x̃ = x − γ dt M⁻¹ L x` and the held coordinates reset onto their planes. Every
//!    coordinate is then clamped into the box.
//! 3. *Volumes*: Newton steps on the bubbles' pressures, projecting `x̃` back onto the
//!    constraint set `{V_l = V_l⁰}` in the mass metric. With `N_t = (b−a)×(c−a)/6` for
//!    triangle `t = (a,b,c)` (front label `f`, back `k`), `∂V_k/∂x_i = Σ_t∋i N_t` and
//!    `∂V_f/∂x_i = −Σ_t∋i N_t` (mesh-core's convention: the normal points into the
//!    front). Every vertex moves by `dᵢ = Pᵢ Mᵢ⁻¹ Σ_l π_l ∂V_l/∂xᵢ` (`Pᵢ` removes the
//!    held components of step 1; `π_l` a pressure per bubble, `π_0 = 0` for the
//!    outside): the displacement of least `dᵀ M d` that changes the volumes by `G d`, and
//!    since `Σ_t∋i N_t ≈ Mᵢ n̂ᵢ` on an interface, `π` jumps across an interface offset it
//!    uniformly along its normal (a pressure jump, independent of the local edge
//!    length). The linearised volume change is `A π` with `A = G P M⁻¹ Gᵀ`, symmetric
//!    positive semi-definite, definite on the bubbles' pressures up to their common
//!    part (below), so the projection is well posed. Solving
//!    `A π = V_target − V(x̃)` by Jacobi-preconditioned conjugate gradients
//!    (matrix-free: two passes over the triangles per product, [`CG_ITERATIONS`] at most)
//!    and applying `d` is one Newton step; steps repeat until every bubble is within
//!    [`VOLUME_TOLERANCE`] of its target, [`NEWTON_STEPS`] at most. The targets are the
//!    bubbles' volumes when the flow was made (their sum is the box volume, which the
//!    walls fix: the common part of the error cannot be corrected and is spread evenly
//!    over the bubbles), so the tracker's own volume errors (remeshing, the grid
//!    backend's rebuilt regions) are corrected at the next step instead of accumulating.
//!
//! This is a splitting of the volume-constrained backward Euler step
//! `min ½‖x' − x‖²_M + γ dt · area(x')` s.t. `V(x') = V⁰` (whose exact KKT system would
//! couple the pressures to the Laplacian solve, one solve per bubble): tension first,
//! then the projection in the mass metric. The correction moves vertices along
//! area-weighted normals, the discrete analogue of a pressure jump across each
//! interface, so it adds no tangential motion.
//!
//! The volume passes are serial over triangles (a scatter to vertices) and the Laplacian
//! products are per row: deterministic for any thread count.

use glam::DVec3;
use mesh_core::{Label, LabeledMesh};

use super::laplacian::CotanLaplacian;
use super::{Flow, MeanCurvatureFlow};

/// Relative distance (of the box size) within which a wall vertex counts as lying on a
/// box plane.
pub const WALL_TOLERANCE: f64 = 1e-3;
/// Newton steps on the pressures per proposal, at most.
pub const NEWTON_STEPS: usize = 8;
/// Newton stops when every bubble's volume is within this fraction of its target (after
/// the common part, which the walls make unreachable, is set aside).
pub const VOLUME_TOLERANCE: f64 = 1e-12;
/// Conjugate-gradient iterations per Newton step, at most.
pub const CG_ITERATIONS: usize = 300;
/// CG stops when the residual is below this fraction of the right-hand side.
const CG_TOLERANCE: f64 = 1e-10;

/// Mean curvature flow with fixed box walls and one volume constraint per bubble (see
/// the module doc).
#[derive(Clone, Debug)]
pub struct VolumePreservingTension {
    mcf: MeanCurvatureFlow,
    lo: DVec3,
    hi: DVec3,
    /// Target volume per label index (`None`: unconstrained, e.g. the outside).
    targets: Vec<Option<f64>>,
}

impl VolumePreservingTension {
    /// Tension `mcf` (its scheme and surface tension) on the box `[lo, hi]`, keeping every
    /// bubble (label ≥ 1) of `mesh` at its current volume.
    pub fn new(mesh: &LabeledMesh, mcf: MeanCurvatureFlow, lo: DVec3, hi: DVec3) -> Self {
        let volumes = mesh_core::geometry::label_volumes(mesh);
        let len = volumes.keys().map(|l| l.idx() + 1).max().unwrap_or(0);
        let mut targets = vec![None; len];
        for (label, v) in volumes {
            if label != Label::OUTSIDE {
                targets[label.idx()] = Some(v);
            }
        }
        VolumePreservingTension {
            mcf,
            lo,
            hi,
            targets,
        }
    }

    /// The target volume of a bubble.
    pub fn target(&self, label: Label) -> Option<f64> {
        self.targets.get(label.idx()).copied().flatten()
    }

    /// Per vertex slot: bit `2a` set when the vertex is held on the low plane of axis `a`,
    /// bit `2a + 1` on the high plane (0 for interior and dead vertices).
    fn wall_masks(&self, mesh: &LabeledMesh) -> Vec<u8> {
        let mut on_wall = vec![false; mesh.vertex_capacity()];
        let (tris, labels, alive) = (mesh.tris(), mesh.label_pairs(), mesh.tri_alive_flags());
        for t in 0..tris.len() {
            if alive[t] && labels[t].contains(&Label::OUTSIDE) {
                for v in tris[t] {
                    on_wall[v.idx()] = true;
                }
            }
        }
        let tol = WALL_TOLERANCE * (self.hi - self.lo).max_element();
        let positions = mesh.positions();
        on_wall
            .iter()
            .zip(positions)
            .map(|(&wall, p)| {
                if !wall {
                    return 0;
                }
                let mut mask = 0u8;
                let mut nearest = (f64::INFINITY, 0u8);
                for a in 0..3 {
                    for (side, plane) in [(0, self.lo[a]), (1, self.hi[a])] {
                        let d = (p[a] - plane).abs();
                        let bit = 1u8 << (2 * a + side);
                        if d <= tol {
                            mask |= bit;
                        }
                        if d < nearest.0 {
                            nearest = (d, bit);
                        }
                    }
                }
                mask | nearest.1
            })
            .collect()
    }

    /// Resets held coordinates onto their planes and clamps into the box.
    fn hold(&self, p: &mut DVec3, mask: u8) {
        for a in 0..3 {
            if mask & (1 << (2 * a)) != 0 {
                p[a] = self.lo[a];
            } else if mask & (1 << (2 * a + 1)) != 0 {
                p[a] = self.hi[a];
            }
        }
        *p = p.clamp(self.lo, self.hi);
    }

    /// Volume per label index of the mesh's triangles at positions `p`.
    fn volumes(&self, mesh: &LabeledMesh, p: &[DVec3], out: &mut [f64]) {
        out.fill(0.0);
        let (tris, labels, alive) = (mesh.tris(), mesh.label_pairs(), mesh.tri_alive_flags());
        // Cones from the box centre: small numbers, no cancellation across the box.
        let o = 0.5 * (self.lo + self.hi);
        for t in 0..tris.len() {
            if !alive[t] {
                continue;
            }
            let [a, b, c] = tris[t].map(|v| p[v.idx()] - o);
            let v = mesh_core::geometry::signed_cone_volume(a, b, c);
            let [front, back] = labels[t];
            add(out, back, v);
            add(out, front, -v);
        }
    }
}

fn add(out: &mut [f64], label: Label, v: f64) {
    if let Some(x) = out.get_mut(label.idx()) {
        *x += v;
    }
}

/// `N_t = (b−a)×(c−a)/6` of every live triangle at positions `p` (zero for dead ones).
fn triangle_gradients(mesh: &LabeledMesh, p: &[DVec3], out: &mut [DVec3]) {
    let (tris, alive) = (mesh.tris(), mesh.tri_alive_flags());
    for t in 0..tris.len() {
        out[t] = if alive[t] {
            let [a, b, c] = tris[t].map(|v| p[v.idx()]);
            (b - a).cross(c - a) / 6.0
        } else {
            DVec3::ZERO
        };
    }
}

/// The pressure system `A = G P M⁻¹ Gᵀ` of one Newton step, applied matrix-free.
struct PressureSystem<'a> {
    mesh: &'a LabeledMesh,
    grads: &'a [DVec3],
    masks: &'a [u8],
    /// `1 / Mᵢ` per vertex slot (0 where the mass is 0: such a vertex does not move).
    inverse_mass: &'a [f64],
    /// Whether a label index is an unknown (a constrained bubble present in the mesh).
    active: &'a [bool],
}

impl PressureSystem<'_> {
    /// `d = P M⁻¹ Gᵀ π` into `disp` (per vertex slot).
    fn displacements(&self, pi: &[f64], disp: &mut [DVec3]) {
        disp.fill(DVec3::ZERO);
        let (tris, labels, alive) = (
            self.mesh.tris(),
            self.mesh.label_pairs(),
            self.mesh.tri_alive_flags(),
        );
        let pressure = |l: Label| {
            let i = l.idx();
            if self.active.get(i).copied().unwrap_or(false) {
                pi[i]
            } else {
                0.0
            }
        };
        for t in 0..tris.len() {
            if !alive[t] {
                continue;
            }
            let [front, back] = labels[t];
            let jump = pressure(back) - pressure(front);
            if jump != 0.0 {
                for v in tris[t] {
                    disp[v.idx()] += jump * self.grads[t];
                }
            }
        }
        for ((d, &mask), &w) in disp.iter_mut().zip(self.masks).zip(self.inverse_mass) {
            *d *= w;
            for a in 0..3 {
                if mask & (0b11 << (2 * a)) != 0 {
                    d[a] = 0.0;
                }
            }
        }
    }

    /// `G d` (linearised volume change per label) into `out`.
    fn volume_change(&self, disp: &[DVec3], out: &mut [f64]) {
        out.fill(0.0);
        let (tris, labels, alive) = (
            self.mesh.tris(),
            self.mesh.label_pairs(),
            self.mesh.tri_alive_flags(),
        );
        for t in 0..tris.len() {
            if !alive[t] {
                continue;
            }
            let moved: DVec3 = tris[t].iter().map(|v| disp[v.idx()]).sum();
            let dv = self.grads[t].dot(moved);
            let [front, back] = labels[t];
            add(out, back, dv);
            add(out, front, -dv);
        }
        for (x, &on) in out.iter_mut().zip(self.active) {
            if !on {
                *x = 0.0;
            }
        }
    }

    /// Jacobi diagonal estimate `Σ_{t on ∂l} Σ_{i ∈ t} |N_t|² / Mᵢ` (the diagonal without
    /// the cross terms between a vertex's triangles and the walls; any positive diagonal
    /// preconditions).
    fn diagonal(&self, out: &mut [f64]) {
        out.fill(0.0);
        let (tris, labels, alive) = (
            self.mesh.tris(),
            self.mesh.label_pairs(),
            self.mesh.tri_alive_flags(),
        );
        for t in 0..labels.len() {
            if alive[t] {
                let w: f64 = tris[t]
                    .iter()
                    .map(|v| self.inverse_mass[v.idx()])
                    .sum::<f64>()
                    * self.grads[t].length_squared();
                let [front, back] = labels[t];
                add(out, back, w);
                add(out, front, w);
            }
        }
    }
}

/// Removes the mean of the active entries. With fixed walls the bubbles fill the box, so
/// their total volume cannot change: a pressure common to every bubble moves nothing
/// (only wall vertices border the outside, and they may not move across the walls), `A`
/// is singular along the all-ones vector, and the right-hand side's common part (the
/// tracker's error of the total) is unreachable. CG works in the complement.
fn remove_common_part(r: &mut [f64], active: &[bool]) {
    let count = active.iter().filter(|&&a| a).count();
    if count == 0 {
        return;
    }
    let mean = r
        .iter()
        .zip(active)
        .filter(|(_, a)| **a)
        .map(|(x, _)| x)
        .sum::<f64>()
        / count as f64;
    for (x, &a) in r.iter_mut().zip(active) {
        if a {
            *x -= mean;
        }
    }
}

/// Preconditioned conjugate gradients (mesh-core's) on the active unknowns, with the
/// common part of the pressures projected out; at most [`CG_ITERATIONS`].
fn solve_pressures(sys: &PressureSystem<'_>, rhs: &[f64], disp: &mut [DVec3]) -> Vec<f64> {
    let n = rhs.len();
    let mut diag = vec![0.0; n];
    sys.diagonal(&mut diag);
    let inv: Vec<f64> = diag
        .iter()
        .zip(sys.active)
        .map(|(&d, &on)| if on && d > 0.0 { 1.0 / d } else { 0.0 })
        .collect();
    let b: Vec<f64> = rhs
        .iter()
        .zip(sys.active)
        .map(|(&b, &on)| if on { b } else { 0.0 })
        .collect();
    mesh_core::solve::conjugate_gradients(
        &b,
        &inv,
        CG_TOLERANCE,
        CG_ITERATIONS,
        |p, ap| {
            sys.displacements(p, disp);
            sys.volume_change(disp, ap);
        },
        |r| remove_common_part(r, sys.active),
    )
}

impl Flow for VolumePreservingTension {
    fn name(&self) -> &str {
        "volume-preserving-tension"
    }

    fn propose(&self, mesh: &LabeledMesh, _t: f64, dt: f64) -> Vec<DVec3> {
        let masks = self.wall_masks(mesh);
        let lap = CotanLaplacian::of(mesh);
        let held: Vec<u8> = masks.iter().map(|&m| held_axes(m)).collect();
        let mut p = self.mcf.step_with(&lap, mesh.positions(), dt, Some(&held));
        for (v, &mask) in p.iter_mut().zip(&masks) {
            if mask != 0 {
                self.hold(v, mask);
            } else {
                *v = v.clamp(self.lo, self.hi);
            }
        }
        let inverse_mass: Vec<f64> = lap
            .mass()
            .iter()
            .map(|&m| if m > 0.0 { 1.0 / m } else { 0.0 })
            .collect();
        self.correct_volumes(mesh, &masks, &inverse_mass, &mut p);
        p
    }

    fn max_stable_dt(&self, mesh: &LabeledMesh) -> Option<f64> {
        self.mcf.max_stable_dt(mesh)
    }
}

/// The axes a wall mask holds: bit `a` for either plane of axis `a`.
fn held_axes(mask: u8) -> u8 {
    (0..3).fold(0, |h, a| {
        if mask & (0b11 << (2 * a)) != 0 {
            h | (1 << a)
        } else {
            h
        }
    })
}

impl VolumePreservingTension {
    /// Step 3 of the module doc: Newton steps on the pressures, moving `p` until every
    /// bubble is back at its target volume.
    fn correct_volumes(
        &self,
        mesh: &LabeledMesh,
        masks: &[u8],
        inverse_mass: &[f64],
        p: &mut [DVec3],
    ) {
        let n = self.targets.len();
        let mut present = vec![false; n];
        for (t, pair) in mesh.label_pairs().iter().enumerate() {
            if mesh.tri_alive_flags()[t] {
                for l in pair {
                    if let Some(x) = present.get_mut(l.idx()) {
                        *x = true;
                    }
                }
            }
        }
        let active: Vec<bool> = (0..n)
            .map(|i| present[i] && self.targets[i].is_some())
            .collect();
        let mut grads = vec![DVec3::ZERO; mesh.tris().len()];
        let mut disp = vec![DVec3::ZERO; p.len()];
        let mut volumes = vec![0.0; n];
        for _ in 0..NEWTON_STEPS {
            self.volumes(mesh, p, &mut volumes);
            let rhs: Vec<f64> = (0..n)
                .map(|i| match (active[i], self.targets[i]) {
                    (true, Some(target)) => target - volumes[i],
                    _ => 0.0,
                })
                .collect();
            let mut reachable = rhs.clone();
            remove_common_part(&mut reachable, &active);
            let converged = (0..n).all(|i| match (active[i], self.targets[i]) {
                (true, Some(target)) => reachable[i].abs() <= VOLUME_TOLERANCE * target.abs(),
                _ => true,
            });
            if converged {
                break;
            }
            triangle_gradients(mesh, p, &mut grads);
            let sys = PressureSystem {
                mesh,
                grads: &grads,
                masks,
                inverse_mass,
                active: &active,
            };
            let pi = solve_pressures(&sys, &rhs, &mut disp);
            sys.displacements(&pi, &mut disp);
            for (v, d) in mesh.vertices().map(|v| v.idx()).map(|i| (i, disp[i])) {
                if d.is_finite() {
                    p[v] = (p[v] + d).clamp(self.lo, self.hi);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flows::McfScheme;
    use mesh_core::generators::voronoi_foam;

    fn foam() -> LabeledMesh {
        voronoi_foam(8, 5, DVec3::ZERO, DVec3::ONE).unwrap()
    }

    /// One step of `scheme` at `dt` (the forward Euler bound times `factor`): the volume
    /// correction brings every bubble back, the walls hold.
    fn one_step_keeps_every_bubble_volume_and_the_walls(scheme: McfScheme, factor: f64) {
        let mut mesh = foam();
        let mcf = MeanCurvatureFlow::default().with_scheme(scheme);
        let flow = VolumePreservingTension::new(&mesh, mcf, DVec3::ZERO, DVec3::ONE);
        let dt = factor * MeanCurvatureFlow::default().stable_dt(&mesh).min(1e-3);
        let before = mesh_core::geometry::label_volumes(&mesh);
        let plain = mcf.propose(&mesh, 0.0, dt);
        let proposed = flow.propose(&mesh, 0.0, dt);
        // Plain mean curvature flow changes the volumes measurably …
        let mut moved = mesh.clone();
        moved.positions_mut().copy_from_slice(&plain);
        let plain_after = mesh_core::geometry::label_volumes(&moved);
        mesh.positions_mut().copy_from_slice(&proposed);
        let after = mesh_core::geometry::label_volumes(&mesh);
        let mut plain_drift: f64 = 0.0;
        for (label, v0) in &before {
            if *label == Label::OUTSIDE {
                continue;
            }
            plain_drift = plain_drift.max((plain_after[label] - v0).abs() / v0);
            let drift = (after[label] - v0).abs() / v0;
            assert!(drift < 1e-9, "{label:?}: {v0} -> {}", after[label]);
        }
        assert!(
            plain_drift > 1e-6,
            "mean curvature flow alone moved nothing: {plain_drift}"
        );
        // … the walls stay put: every outside-facing triangle lies on a box face.
        for t in mesh.triangles() {
            if mesh.labels(t).contains(&Label::OUTSIDE) {
                let p = mesh.tri_positions(t);
                let on_face =
                    (0..3).any(|a| p.iter().all(|q| q[a] == 0.0) || p.iter().all(|q| q[a] == 1.0));
                assert!(on_face, "{t:?} left the walls: {p:?}");
            }
        }
        assert!(
            proposed
                .iter()
                .all(|p| p.cmpge(DVec3::ZERO).all() && p.cmple(DVec3::ONE).all())
        );
    }

    #[test]
    fn forward_euler_step_keeps_every_bubble_volume_and_the_walls() {
        one_step_keeps_every_bubble_volume_and_the_walls(McfScheme::ForwardEuler, 0.5);
    }

    #[test]
    fn backward_euler_step_far_beyond_the_explicit_bound_keeps_volumes_and_walls() {
        one_step_keeps_every_bubble_volume_and_the_walls(McfScheme::BackwardEuler, 200.0);
    }
}
