//! Volume-preserving surface tension in a box with fixed walls: the flow of the
//! `foam-tension` scene (2024 paper Fig. 21–22; Los Topos' foam under mean curvature flow
//! with a volume constraint per bubble).
//!
//! **Discretisation.** One step from positions `x` with step `dt`:
//!
//! 1. *Tension*: a forward Euler step of [`MeanCurvatureFlow`] (Meyer et al. 2003
//!    cotangent operator over every incident triangle, so triple curves relax towards
//!    Plateau's 120°): `p = x − γ dt K(x)`.
//! 2. *Walls*: a vertex of a triangle that touches the outside (label 0) is a wall vertex.
//!    Its coordinate along an axis whose box plane it lies on (within [`WALL_TOLERANCE`] ×
//!    box size; at least the nearest plane) is reset to that plane, so wall vertices slide
//!    within the walls, along box edges, or stay put at corners; every vertex is clamped
//!    into the box. The walls neither move nor pull: the foam keeps filling the box.
//! 3. *Volumes*: Newton steps on the bubbles' pressures. With `N_t = (b−a)×(c−a)/6` for
//!    triangle `t = (a,b,c)` (front label `f`, back `k`), `∂V_k/∂x_i = Σ_t∋i N_t` and
//!    `∂V_f/∂x_i = −Σ_t∋i N_t` (mesh-core's convention: the normal points into the
//!    front). Every vertex moves by `dᵢ = Pᵢ Σ_l π_l ∂V_l/∂xᵢ` (`Pᵢ` removes the wall
//!    components of step 2; `π_l` a pressure per bubble, `π_0 = 0` for the outside), so
//!    the linearised volume change is `A π` with `A = G P Gᵀ`, symmetric positive
//!    definite on the bubbles that have a movable vertex. Solving `A π = V_target − V(p)`
//!    by Jacobi-preconditioned conjugate gradients (matrix-free: two passes over the
//!    triangles per product, [`CG_ITERATIONS`] at most) and applying `d` is one Newton
//!    step; [`NEWTON_STEPS`] are taken. The targets are the bubbles' volumes when the flow
//!    was made (their sum is the box volume, which the walls fix: the common part of
//!    the error cannot be corrected and is spread evenly over the bubbles), so
//!    the tracker's own volume errors (remeshing, the grid backend's rebuilt
//!    regions) are corrected at the next step instead of accumulating.
//!
//! The correction moves vertices along area-weighted normals, the discrete analogue of
//! a pressure jump across each interface, so it adds no tangential motion.
//!
//! Every pass is serial over triangles (a scatter to vertices): deterministic for any
//! thread count; the mean curvature step itself runs on rayon.

use glam::DVec3;
use mesh_core::{Label, LabeledMesh};

use super::{Flow, FlowError, MeanCurvatureFlow};

/// Relative distance (of the box size) within which a wall vertex counts as lying on a
/// box plane.
pub const WALL_TOLERANCE: f64 = 1e-3;
/// Newton steps on the pressures per proposal.
pub const NEWTON_STEPS: usize = 3;
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
    /// The flow on the box `[lo, hi]`, keeping every bubble (label ≥ 1) of `mesh` at its
    /// current volume.
    pub fn new(mesh: &LabeledMesh, tension: f64, lo: DVec3, hi: DVec3) -> Result<Self, FlowError> {
        let mcf = MeanCurvatureFlow::new(tension)?;
        let volumes = mesh_core::geometry::label_volumes(mesh);
        let len = volumes.keys().map(|l| l.idx() + 1).max().unwrap_or(0);
        let mut targets = vec![None; len];
        for (label, v) in volumes {
            if label != Label::OUTSIDE {
                targets[label.idx()] = Some(v);
            }
        }
        Ok(VolumePreservingTension {
            mcf,
            lo,
            hi,
            targets,
        })
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

/// The pressure system `A = G P Gᵀ` of one Newton step, applied matrix-free.
struct PressureSystem<'a> {
    mesh: &'a LabeledMesh,
    grads: &'a [DVec3],
    masks: &'a [u8],
    /// Whether a label index is an unknown (a constrained bubble present in the mesh).
    active: &'a [bool],
}

impl PressureSystem<'_> {
    /// `d = P Gᵀ π` into `disp` (per vertex slot).
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
        for (d, &mask) in disp.iter_mut().zip(self.masks) {
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

    /// Jacobi diagonal estimate `Σ_{t on ∂l} 3 |N_t|²` (the diagonal without the
    /// cross terms between a vertex's triangles; any positive diagonal preconditions).
    fn diagonal(&self, out: &mut [f64]) {
        out.fill(0.0);
        let (labels, alive) = (self.mesh.label_pairs(), self.mesh.tri_alive_flags());
        for t in 0..labels.len() {
            if alive[t] {
                let w = 3.0 * self.grads[t].length_squared();
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

    fn propose(&self, mesh: &LabeledMesh, t: f64, dt: f64) -> Vec<DVec3> {
        let mut p = self.mcf.propose(mesh, t, dt);
        let masks = self.wall_masks(mesh);
        for (v, &mask) in p.iter_mut().zip(&masks) {
            if mask != 0 {
                self.hold(v, mask);
            } else {
                *v = v.clamp(self.lo, self.hi);
            }
        }
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
            self.volumes(mesh, &p, &mut volumes);
            let rhs: Vec<f64> = (0..n)
                .map(|i| match (active[i], self.targets[i]) {
                    (true, Some(target)) => target - volumes[i],
                    _ => 0.0,
                })
                .collect();
            triangle_gradients(mesh, &p, &mut grads);
            let sys = PressureSystem {
                mesh,
                grads: &grads,
                masks: &masks,
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
        p
    }

    fn max_stable_dt(&self, mesh: &LabeledMesh) -> Option<f64> {
        self.mcf.max_stable_dt(mesh)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mesh_core::generators::voronoi_foam;

    fn foam() -> LabeledMesh {
        voronoi_foam(8, 5, DVec3::ZERO, DVec3::ONE).unwrap()
    }

    #[test]
    fn one_step_keeps_every_bubble_volume_and_the_walls() {
        let mut mesh = foam();
        let flow = VolumePreservingTension::new(&mesh, 1.0, DVec3::ZERO, DVec3::ONE).unwrap();
        let dt = 0.5 * flow.max_stable_dt(&mesh).unwrap().min(1e-3);
        let before = mesh_core::geometry::label_volumes(&mesh);
        let plain = MeanCurvatureFlow::new(1.0).unwrap().propose(&mesh, 0.0, dt);
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
}
