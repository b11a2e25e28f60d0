//! Stage "relax": clean interface walls (issue 15 item 3; Los Topos §8.2, where the wall
//! two merged bodies share "remains smooth").
//!
//! ```text
//! relax(mesh):
//!     repeat passes times:
//!         wall vertex    (all triangles one label pair, neither the ambient label)
//!                        → step/2 · (L(v) − mean of L over its ring), L the area-weighted
//!                          Laplacian (normal part included; 0 off the wall)
//!         curve vertex   (exactly two non-manifold edges, three labels around it)
//!                        → step/2 · (L(v) − mean of L at its two curve neighbours),
//!                          L(w) = midpoint of w's curve neighbours − w
//!         refused when a triangle would turn by more than 60° or invert, or a label's
//!         volume change exceed Ω
//!     the moves of a pass computed from one snapshot (in parallel) and committed by
//!     mesh-core's batched smoothing commit: independent sets of moves, each set one
//!     guarded pseudo-motion, offenders retried alone; on large walls the commit runs on
//!     blocks of space on every core (mesh-core's `run_in_blocks`, each block with its
//!     own collision guard), the moves a border held back committed serially after
//! ```
//!
//! **Why.** Improvement's null-space smoothing keeps sharp features, so the creases of a
//! wall crumpled while being zipped together (each snap lands at the average of two
//! sheets a few hundredths of ℓ apart, and the next step's collision response pushes
//! the unsnapped rest around) read as features and stay; fins and spikes then grow with
//! every step. A wall between two bodies has no features of its own: its shape is set
//! by its boundary, the triple curve, so relaxing it (and the curve along itself, which
//! keeps the curve's vertices from zig-zagging) gives the membrane the geometry implies.
//!
//! **Why a bi-Laplacian** (a vertex's Laplacian minus its neighbours'). A crumple or a
//! zig-zag is the highest frequency the mesh carries, and half a step of the difference
//! cancels it in one pass; a uniformly curved wall or rim has equal Laplacians
//! everywhere, so it is left as the flow shaped it. The plain Laplacian was curvature
//! flow: it pulled every wall flat against the flow and the rim of a young wall inwards,
//! so the 2-sphere wall of seed 4 ended 20 % smaller than the contact circle (now 11 %),
//! and on a foam, where everything is wall, it added a curvature flow the caller had not
//! asked for.
//! The ambient label's surfaces (label 0: free surfaces, the Enright and Zalesak
//! shapes) are never touched, and every move is bounded by Ω, so volumes and sharp
//! free-surface features keep what improvement gives them.

use glam::DVec3;
use mesh_core::remesh::smooth::laplacian_displacement;
use mesh_core::remesh::{
    BlockJob, BlockParams, Proposal, SmoothOutcome, SmoothParams, VertexAttributes, commit_moves,
    run_in_blocks,
};
use mesh_core::{Label, LabeledMesh, VertexId};
use rayon::prelude::*;

use crate::guard::CollisionGuard;

/// Options of [`relax_walls`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct RelaxOptions {
    /// Passes per step. 0 turns the stage off.
    pub passes: usize,
    /// Side of the blocks the commit runs on (`block_edges · ℓ` of the blocks passed to
    /// [`relax_walls`]).
    pub block_side: f64,
    /// Fraction of the Laplacian applied per pass (0.5: monotone on regular patches).
    pub step: f64,
    /// Ω: the largest change of any label's volume one move may cause.
    pub max_volume_change: f64,
    /// Moves shorter than this are skipped as converged.
    pub min_move: f64,
}

/// What the stage did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct RelaxReport {
    pub moved: usize,
    pub refused: usize,
}

/// Runs the stage (see the module doc). `guard` checks the serial commits; on `blocks`
/// (the improvement stage's, with its margin) each block gets a guard of its own with its
/// options, and `guard` is reset after them (it no longer knows the mesh).
pub(crate) fn relax_walls(
    mesh: &mut LabeledMesh,
    attrs: &mut VertexAttributes,
    guard: &mut CollisionGuard,
    options: &RelaxOptions,
    blocks: &BlockParams,
) -> RelaxReport {
    let mut report = RelaxReport::default();
    let checks = SmoothParams {
        max_volume_change: options.max_volume_change,
        min_normal_cos: 0.5,
        conserve_volume: false,
        ..SmoothParams::default()
    };
    for _ in 0..options.passes {
        let snapshot: &LabeledMesh = mesh;
        let proposals: Vec<Proposal> = (0..snapshot.vertex_capacity() as u32)
            .into_par_iter()
            .with_min_len(256)
            .filter_map(|i| {
                let v = VertexId::new(i);
                if !snapshot.is_vertex_alive(v) {
                    return None;
                }
                let target = relaxed_position(snapshot, v, options.step)?;
                let displacement = target - snapshot.position(v);
                (displacement.length() >= options.min_move).then_some(Proposal {
                    vertex: v,
                    displacement,
                    normal: None,
                })
            })
            .collect();
        let out = commit(
            mesh,
            attrs,
            guard,
            &checks,
            &proposals,
            options.block_side,
            blocks,
        );
        report.moved += out.moved;
        report.refused += out.refused + out.vetoed;
        if out.moved == 0 {
            break;
        }
    }
    report
}

/// Commits one pass's proposals (increasing vertex order): by blocks where there are
/// enough of them, then serially what the blocks' borders held back.
fn commit(
    mesh: &mut LabeledMesh,
    attrs: &mut VertexAttributes,
    guard: &mut CollisionGuard,
    checks: &SmoothParams,
    proposals: &[Proposal],
    side: f64,
    blocks: &BlockParams,
) -> SmoothOutcome {
    let of = |v: VertexId| {
        proposals
            .binary_search_by_key(&v, |p| p.vertex)
            .ok()
            .map(|i| proposals[i])
    };
    let stage = |job: BlockJob<'_>| {
        let local: Vec<Proposal> = job
            .work
            .iter()
            .filter_map(|&v| of(job.globals[v.idx()]).map(|p| Proposal { vertex: v, ..p }))
            .collect();
        let out = commit_moves(job.mesh, job.attrs, job.guard, checks, &local);
        let moved = out.moved;
        (out, moved)
    };
    let work: Vec<VertexId> = proposals.iter().map(|p| p.vertex).collect();
    let (outs, left) = run_in_blocks(
        mesh,
        attrs,
        &mut None,
        work,
        side,
        blocks,
        &guard.maker(),
        &stage,
    );
    let mut total = SmoothOutcome::default();
    if !outs.is_empty() {
        guard.reset();
    }
    let rest: Vec<Proposal> = left.into_iter().filter_map(of).collect();
    let last = commit_moves(mesh, attrs, guard, checks, &rest);
    for out in outs.iter().chain([&last]) {
        total.moved += out.moved;
        total.refused += out.refused;
        total.vetoed += out.vetoed;
        total.volume_change += out.volume_change;
    }
    total
}

/// Where relaxation moves `v`, or `None` when `v` is neither a wall nor a curve vertex.
fn relaxed_position(mesh: &LabeledMesh, v: VertexId, step: f64) -> Option<DVec3> {
    let p = mesh.position(v);
    let mut pair: Option<[Label; 2]> = None;
    let mut one_pair = true;
    let mut labels: [Option<Label>; 4] = [None; 4];
    let mut n_labels = 0usize;
    for t in mesh.vertex_triangles(v) {
        let [a, b] = mesh.labels(t);
        let key = if a < b { [a, b] } else { [b, a] };
        match pair {
            None => pair = Some(key),
            Some(k) if k != key => one_pair = false,
            _ => {}
        }
        for l in [a, b] {
            if !labels[..n_labels].contains(&Some(l)) {
                if n_labels == labels.len() {
                    return None;
                }
                labels[n_labels] = Some(l);
                n_labels += 1;
            }
        }
    }
    let pair = pair?;
    if one_pair {
        if pair.contains(&Label::OUTSIDE) {
            return None;
        }
        let (own, _) = laplacian_displacement(mesh, v)?;
        let (mut ring, mut n) = (DVec3::ZERO, 0usize);
        for t in mesh.vertex_triangles(v) {
            for w in mesh.tri(t) {
                if w != v {
                    // Each ring vertex is seen from its two triangles at v: counted twice
                    // alike, so the mean is unchanged.
                    ring += wall_laplacian(mesh, w, pair).unwrap_or(DVec3::ZERO);
                    n += 1;
                }
            }
        }
        return Some(p + 0.5 * step * (own - ring / n.max(1) as f64));
    }
    if n_labels != 3 {
        return None;
    }
    // A triple-curve vertex: its non-manifold edges are the curve. Its curve Laplacian
    // minus the mean of its two neighbours' (a bi-Laplacian, at half the step: exactly
    // what cancels a zig-zag of one vertex) evens the curve out without shrinking it. The
    // Laplacian alone is curve-shortening flow: it pulled the rim of a young wall inwards
    // by a few thousandths of ℓ per pass, and the wall lagged the contact circle by a
    // fifth of its area.
    let [a, b] = curve_ends(mesh, v)?;
    let lap = |w: VertexId| {
        curve_ends(mesh, w).map_or(DVec3::ZERO, |[x, y]| {
            0.5 * (mesh.position(x) + mesh.position(y)) - mesh.position(w)
        })
    };
    let own = 0.5 * (mesh.position(a) + mesh.position(b)) - p;
    Some(p + 0.5 * step * (own - 0.5 * (lap(a) + lap(b))))
}

/// The area-weighted Laplacian of `w` when `w` is a vertex inside a wall between `pair`.
fn wall_laplacian(mesh: &LabeledMesh, w: VertexId, pair: [Label; 2]) -> Option<DVec3> {
    let inside = mesh.vertex_triangles(w).all(|t| {
        let [a, b] = mesh.labels(t);
        (if a < b { [a, b] } else { [b, a] }) == pair
    });
    if !inside {
        return None;
    }
    laplacian_displacement(mesh, w).map(|(d, _)| d)
}

/// The two curve neighbours of `v`: the other ends of its non-manifold edges, if it has
/// exactly two.
fn curve_ends(mesh: &LabeledMesh, v: VertexId) -> Option<[VertexId; 2]> {
    let mut ends: [Option<VertexId>; 2] = [None; 2];
    let mut count = 0usize;
    for t in mesh.vertex_triangles(v) {
        for w in mesh.tri(t) {
            if w == v || ends[..count.min(2)].contains(&Some(w)) {
                continue;
            }
            if mesh.edge_triangles(v, w).nth(2).is_some() {
                if count == 2 {
                    return None;
                }
                ends[count] = Some(w);
                count += 1;
            }
        }
    }
    match ends {
        [Some(a), Some(b)] if count == 2 => Some([a, b]),
        _ => None,
    }
}
