//! Null-space smoothing (El Topo §3.6.1, after Jiao 2007).
//!
//! Each vertex is pulled towards the area-weighted centroid of its incident triangles'
//! centroids (an area-weighted Laplacian), but only within the null space of its quadric
//! tensor ([`VertexKind::project`]): tangentially on a smooth patch, along the ridge on a
//! ridge, and not at all at corners or on feature curves. Edge lengths even out without
//! shrinking the surface or rounding its features.
//!
//! Displacements are computed for all vertices in parallel from one snapshot (Jacobi
//! style), then committed in *batches*: independent sets of vertices (no two share a
//! triangle), each move checked locally for inverted triangles, excessive normal rotation
//! and volume change (in parallel: a move's triangles are its own), and the batch offered
//! to the guard as one edit ([`EditGuard::offending_moves`]: one index query, or one CCD
//! pseudo-motion, per batch instead of per move). The guard blames the offending moves;
//! they are left out, the rest is asked about again and committed, and the blamed ones are
//! retried one at a time, so one blocked vertex never freezes a batch.

use glam::DVec3;
use nalgebra::Matrix3;
use rayon::prelude::*;

use crate::geometry;
use crate::ids::{Label, VertexId};
use crate::mesh::LabeledMesh;

use super::attributes::VertexAttributes;
use super::edit::{
    Edit, EditError, VertexMove, apply_edit, check_batch_structure, commit_guarded, with_moves_only,
};
use super::features::{self, FeatureParams, VertexKind};
use super::guard::EditGuard;
use super::structure::blame_moves;

/// Parameters of [`smooth_vertices`].
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct SmoothParams {
    /// Fraction of the projected Laplacian displacement applied per pass. Default 0.5: the
    /// Jacobi update of neighbours at full step can overshoot; half a step converges
    /// monotonically on regular patches.
    pub step: f64,
    /// Classification thresholds.
    pub features: FeatureParams,
    /// Largest allowed change of any label's volume per move (Ω). Default: no limit.
    pub max_volume_change: f64,
    /// Smallest allowed cosine between an incident triangle's normal before and after the
    /// move. Default 0.5 (60°).
    pub min_normal_cos: f64,
    /// Moves shorter than this fraction of the vertex's local scale (√ of its mean incident
    /// triangle area) are skipped as converged. Default 1e-3.
    pub min_relative_move: f64,
    /// On a smooth patch between two materials, shift each move along the vertex normal
    /// by what cancels its volume change (exactly: a label volume is affine in one
    /// vertex's position). A tangential move over a curved patch still cuts or adds a
    /// sliver of volume, and over a long run those add up (measured in the collision
    /// backend's Enright test: small next to flips, +0.04 %). The shift is computed when
    /// the move is committed,
    /// against its neighbours' positions then (moves of one batch share no triangle, so
    /// their changes add up exactly). Ridges and curves are left as they are: a normal
    /// shift would round them. Default false (see [`super::ImproveParams::conserve_volume`]).
    pub conserve_volume: bool,
}

impl Default for SmoothParams {
    fn default() -> Self {
        Self {
            step: 0.5,
            features: FeatureParams::default(),
            max_volume_change: f64::INFINITY,
            min_normal_cos: 0.5,
            min_relative_move: 1e-3,
            conserve_volume: false,
        }
    }
}

/// What a smoothing pass did.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct SmoothOutcome {
    /// Vertices moved.
    pub moved: usize,
    /// Moves refused by the local checks (inversion, rotation, volume).
    pub refused: usize,
    /// Moves vetoed by the guard.
    pub vetoed: usize,
    /// Sum over committed moves of the largest label volume change of each.
    pub volume_change: f64,
}

/// One proposed smoothing move: the vertex, its displacement, and the normal to conserve
/// the volume along (`None` off smooth patches or with `conserve_volume` off). Other
/// smoothing rules (the collision tracker's wall relaxation) propose their own and commit
/// them with [`commit_moves`].
#[derive(Clone, Copy, Debug)]
pub struct Proposal {
    /// The vertex to move.
    pub vertex: VertexId,
    /// Where to, relative to its position.
    pub displacement: DVec3,
    /// The normal to shift the move along so that it keeps every label's volume.
    pub normal: Option<DVec3>,
}

/// The unprojected area-weighted Laplacian of `v`: `Σ areaᵢ (centroidᵢ − v) / Σ areaᵢ`,
/// with the local scale `√(Σ areaᵢ / n)`. `None` for isolated or zero-area vertices.
pub fn laplacian_displacement(mesh: &LabeledMesh, v: VertexId) -> Option<(DVec3, f64)> {
    let p = mesh.position(v);
    let (mut sum, mut area, mut n) = (DVec3::ZERO, 0.0, 0usize);
    for t in mesh.vertex_triangles(v) {
        let q = mesh.tri_positions(t);
        let w = geometry::triangle_area(&q);
        sum += w * ((q[0] + q[1] + q[2]) / 3.0 - p);
        area += w;
        n += 1;
    }
    (area > 0.0 && area.is_finite()).then(|| (sum / area, (area / n as f64).sqrt()))
}

/// The null-space smoothing displacement of `v` for the given kind (zero when it must stay).
pub fn smoothing_displacement(mesh: &LabeledMesh, v: VertexId, kind: &VertexKind) -> DVec3 {
    match laplacian_displacement(mesh, v) {
        Some((d, _)) => kind.project(d),
        None => DVec3::ZERO,
    }
}

/// One smoothing pass over all vertices (see the module doc), in increasing vertex order.
pub fn smooth_vertices(
    mesh: &mut LabeledMesh,
    attrs: &mut VertexAttributes,
    guard: &mut dyn EditGuard,
    params: &SmoothParams,
) -> SmoothOutcome {
    let proposals = propose_moves(mesh, params, None, None);
    commit_moves(mesh, attrs, guard, params, &proposals)
}

/// Moves per batch at most. A guard that finds offenders by bisection (a CCD guard: the
/// sweep of a batch is one pseudo-motion, and a collision somewhere in it says nothing of
/// where) pays about `log₂(batch)` checks per offender, each of up to half the batch, so
/// large batches would cost more than they save; 256 moves still keep both cores busy.
const MAX_BATCH: usize = 256;

/// Times the guard is asked about one batch, each time without the moves it blamed,
/// before the rest of that batch is committed one move at a time.
const MAX_GUARD_ROUNDS: usize = 4;

/// Commits proposed moves in batches (see the module doc): each round takes every pending
/// move that no earlier pending move shares a triangle with (an independent set that keeps
/// the commit order of one move at a time for every pair of neighbouring moves), makes
/// the local checks of every move in parallel, and asks the guard about the batch once ([`EditGuard::offending_moves`]). Blamed moves, and whatever a batch could
/// not clear, are committed one at a time afterwards, each as its own guarded edit, so
/// the outcome is what per-move checking would allow, at the price of one index query
/// per batch instead of one per move. Of `params`, the local checks read
/// `min_normal_cos` and `max_volume_change`.
pub fn commit_moves(
    mesh: &mut LabeledMesh,
    attrs: &mut VertexAttributes,
    guard: &mut dyn EditGuard,
    params: &SmoothParams,
    proposals: &[Proposal],
) -> SmoothOutcome {
    with_moves_only(mesh, |mesh| {
        commit_moves_in(mesh, attrs, guard, params, proposals)
    })
}

fn commit_moves_in(
    mesh: &mut LabeledMesh,
    attrs: &mut VertexAttributes,
    guard: &mut dyn EditGuard,
    params: &SmoothParams,
    proposals: &[Proposal],
) -> SmoothOutcome {
    let mut out = SmoothOutcome::default();
    let mut alone: Vec<Proposal> = Vec::new();
    let mut edit = Edit::default();
    // Batches: the moves grouped by level, each level cut into runs of MAX_BATCH, in
    // proposal order. A move's level is one more than the highest level among the earlier
    // moves it shares a triangle with, so no two moves of a level are neighbours, and of
    // any two neighbouring moves the one proposed first is committed first, as one at a
    // time would (that order decides which of them sees the other's result); moves that
    // touch nothing in common commute. One linear pass: a triangle remembers the highest
    // level of the moves seen at it (a rescan of the queue per batch made smoothing
    // quadratic in the number of moves).
    let mut at_triangle: Vec<u32> = vec![0; mesh.triangle_capacity()];
    let mut levels: Vec<u32> = Vec::with_capacity(proposals.len());
    for &Proposal { vertex: v, .. } in proposals {
        if !mesh.is_vertex_alive(v) {
            levels.push(u32::MAX);
            continue;
        }
        let level = mesh
            .vertex_triangles(v)
            .map(|t| at_triangle[t.idx()])
            .max()
            .unwrap_or(0);
        mesh.vertex_triangles(v)
            .for_each(|t| at_triangle[t.idx()] = level + 1);
        levels.push(level);
    }
    drop(at_triangle);
    let mut order: Vec<u32> = (0..proposals.len() as u32)
        .filter(|&i| levels[i as usize] != u32::MAX)
        .collect();
    out.refused += proposals.len() - order.len();
    // Stable: proposal order within a level.
    order.sort_by_key(|&i| levels[i as usize]);
    let batches = order
        .chunk_by(|&a, &b| levels[a as usize] == levels[b as usize])
        .flat_map(|level| level.chunks(MAX_BATCH));
    let mut batch: Vec<Proposal> = Vec::with_capacity(MAX_BATCH);
    for members in batches {
        batch.clear();
        batch.extend(members.iter().map(|&i| proposals[i as usize]));
        // Local checks, in parallel: each move's triangles are its own.
        let snapshot: &LabeledMesh = mesh;
        let checked: Vec<Option<(VertexMove, f64)>> = batch
            .par_iter()
            .with_min_len(64)
            .map_init(
                || (Edit::default(), Vec::new()),
                |(scratch, volumes), p| local_move_check(snapshot, p, params, scratch, volumes),
            )
            .collect();
        edit.clear();
        // Per committed move: its volume change and the proposal it came from (a blamed
        // move is retried from its proposal, its volume shift recomputed then).
        let mut changes: Vec<(f64, Proposal)> = Vec::with_capacity(checked.len());
        for (c, p) in checked.into_iter().zip(&batch) {
            match c {
                // A move the guard refuses whatever else happens: a batch would blame it
                // and its retry alone would be vetoed, so it is vetoed here (the levels,
                // computed with it, keep every other move's order).
                Some(_) if guard.check_vertex(mesh, p.vertex).is_err() => out.vetoed += 1,
                Some((m, dv)) => {
                    edit.moves.push(m);
                    changes.push((dv, *p));
                }
                None => out.refused += 1,
            }
        }
        let mut cleared = false;
        for _ in 0..MAX_GUARD_ROUNDS {
            if edit.moves.is_empty() {
                break;
            }
            // The structure first (cheap, and it keeps labels consistent around the
            // non-manifold edges the batch reorders), then the guard.
            let verdict = match check_batch_structure(mesh, &edit) {
                Ok(()) => guard.offending_moves(mesh, &edit),
                Err(fault) => match blame_moves(mesh, &edit, &fault) {
                    blamed if blamed.is_empty() => Some((0..edit.moves.len()).collect()),
                    blamed => Some(blamed),
                },
            };
            match verdict {
                None => {
                    cleared = true;
                    break;
                }
                Some(blamed) => {
                    let mut keep = 0;
                    for i in 0..edit.moves.len() {
                        let m = edit.moves[i];
                        if blamed.binary_search(&i).is_ok() {
                            alone.push(changes[i].1);
                        } else {
                            edit.moves[keep] = m;
                            changes[keep] = changes[i];
                            keep += 1;
                        }
                    }
                    edit.moves.truncate(keep);
                    changes.truncate(keep);
                }
            }
        }
        if cleared {
            if commit_guarded(mesh, attrs, guard, &edit).is_ok() {
                out.moved += edit.moves.len();
                out.volume_change += changes.iter().map(|c| c.0).sum::<f64>();
            } else {
                out.refused += edit.moves.len();
            }
        } else {
            alone.extend(changes.iter().map(|c| c.1));
        }
    }
    let mut volumes = Vec::new();
    for p in &alone {
        match smooth_vertex_in(&mut edit, &mut volumes, mesh, attrs, guard, p, params) {
            Ok(dv) => {
                out.moved += 1;
                out.volume_change += dv;
            }
            Err(SmoothError::Refused) => out.refused += 1,
            Err(SmoothError::Edit(EditError::Vetoed(_))) => out.vetoed += 1,
            Err(SmoothError::Edit(_)) => out.refused += 1,
        }
    }
    out
}

/// Displacements `(v, step · projected Laplacian)` worth applying, in increasing vertex
/// order, computed in parallel. `feature_edges[v]`, when given, is the number of feature
/// edges at `v` (computed once per sweep by the caller); only vertices with none can move,
/// so the per-vertex edge walk of [`features::classify_vertex`] is skipped. `only`, when
/// given, restricts the pass to those vertices (in increasing order, each once): the
/// driver's later sweeps smooth only where the mesh changed.
pub(crate) fn propose_moves(
    mesh: &LabeledMesh,
    params: &SmoothParams,
    feature_edges: Option<&[u32]>,
    only: Option<&[VertexId]>,
) -> Vec<Proposal> {
    let propose = |v: VertexId| {
        if !mesh.is_vertex_alive(v) {
            return None;
        }
        let on_curve = match feature_edges {
            Some(counts) => counts.get(v.idx()).is_none_or(|&c| c > 0),
            None => features::classify_vertex(mesh, v, &params.features).on_curve(),
        };
        if on_curve {
            return None;
        }
        let (kind, d, scale) = vertex_frame(mesh, v, &params.features)?;
        let d = kind.project(d) * params.step;
        let normal = match (params.conserve_volume, kind) {
            (true, VertexKind::Smooth { normal }) => Some(normal),
            _ => None,
        };
        (d.length() > params.min_relative_move * scale && d.is_finite()).then_some(Proposal {
            vertex: v,
            displacement: d,
            normal,
        })
    };
    match only {
        Some(vertices) => vertices
            .par_iter()
            .with_min_len(256)
            .filter_map(|&v| propose(v))
            .collect(),
        None => (0..mesh.vertex_capacity() as u32)
            .into_par_iter()
            .with_min_len(256)
            .filter_map(|i| propose(VertexId::new(i)))
            .collect(),
    }
}

/// The quadric classification, the unprojected area-weighted Laplacian and the local scale
/// of `v` in one walk over its triangles (see [`features::classify_vertex`] and
/// [`laplacian_displacement`]); the caller has ruled out feature edges at `v`.
fn vertex_frame(
    mesh: &LabeledMesh,
    v: VertexId,
    params: &FeatureParams,
) -> Option<(VertexKind, DVec3, f64)> {
    let p = mesh.position(v);
    let (mut tensor, mut normals, mut sum, mut area, mut n) =
        (Matrix3::zeros(), DVec3::ZERO, DVec3::ZERO, 0.0, 0usize);
    for t in mesh.vertex_triangles(v) {
        let q = mesh.tri_positions(t);
        let an = geometry::area_normal(&q);
        let w = an.length();
        features::add_to_quadric(&mut tensor, an);
        normals += an;
        sum += w * ((q[0] + q[1] + q[2]) / 3.0 - p);
        area += w;
        n += 1;
    }
    let kind = features::classify_with_hint(tensor, normals, params);
    (area > 0.0 && area.is_finite()).then(|| (kind, sum / area, (area / n as f64).sqrt()))
}

/// Why one smoothing move was not made.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
enum SmoothError {
    #[error("refused by the local checks")]
    Refused,
    #[error(transparent)]
    Edit(#[from] EditError),
}

/// The local checks of a proposed move, after shifting it along its normal (when it has
/// one) by what keeps every label's volume: no incident triangle inverts or rotates too
/// far and no label volume changes by more than Ω. Returns the move and the largest label
/// volume change it causes.
fn local_move_check(
    mesh: &LabeledMesh,
    p: &Proposal,
    params: &SmoothParams,
    scratch: &mut Edit,
    volumes: &mut Vec<(Label, f64)>,
) -> Option<(VertexMove, f64)> {
    let v = p.vertex;
    scratch.clear();
    scratch.moves.push(VertexMove {
        vertex: v,
        end: mesh.position(v) + p.displacement,
        blend: None,
    });
    if let Some(normal) = p.normal {
        // The sliver a tangential move cuts is second order in the move, so a shift as
        // long as the move itself is already generous.
        let reach = p.displacement.length();
        features::conserve_volume_along(mesh, scratch, normal, reach, volumes);
    }
    let end = scratch.moves[0].end;
    for t in mesh.vertex_triangles(v) {
        let old = mesh.tri_positions(t);
        let new = mesh
            .tri(t)
            .map(|w| if w == v { end } else { mesh.position(w) });
        if !features::normals_agree(&old, &new)
            || features::normal_cos(&old, &new).is_none_or(|c| c < params.min_normal_cos)
        {
            return None;
        }
    }
    let dv = features::max_label_volume_change(mesh, scratch, volumes);
    (dv <= params.max_volume_change).then_some((scratch.moves[0], dv))
}

/// Makes one proposed move alone, if it passes [`local_move_check`] and the guard; returns
/// the largest label volume change.
fn smooth_vertex_in(
    edit: &mut Edit,
    volumes: &mut Vec<(Label, f64)>,
    mesh: &mut LabeledMesh,
    attrs: &mut VertexAttributes,
    guard: &mut dyn EditGuard,
    p: &Proposal,
    params: &SmoothParams,
) -> Result<f64, SmoothError> {
    if !mesh.is_vertex_alive(p.vertex) {
        return Err(SmoothError::Refused);
    }
    let (m, dv) = local_move_check(mesh, p, params, edit, volumes).ok_or(SmoothError::Refused)?;
    edit.clear();
    edit.moves.push(m);
    apply_edit(mesh, attrs, guard, edit)?;
    Ok(dv)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::remesh::collapse::tests::double_box;
    use crate::remesh::guard::NoGuard;

    /// A closed "pillow": a flat square grid on top (z = 0, n × n cells) over an apex.
    fn pillow(n: usize, jitter: f64) -> LabeledMesh {
        let mut p = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                let interior = i > 0 && i < n && j > 0 && j < n;
                let (dx, dy) = if interior {
                    // Deterministic jitter, enough to make the grid uneven.
                    (
                        jitter * (((i * 7 + j * 3) % 5) as f64 - 2.0),
                        jitter * (((i * 2 + j * 5) % 5) as f64 - 2.0),
                    )
                } else {
                    (0.0, 0.0)
                };
                p.push(DVec3::new(i as f64 + dx, j as f64 + dy, 0.0));
            }
        }
        let apex = p.len() as u32;
        p.push(DVec3::new(n as f64 / 2.0, n as f64 / 2.0, -(n as f64)));
        let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        let mut tris = Vec::new();
        for j in 0..n {
            for i in 0..n {
                tris.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                tris.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
            }
        }
        // Boundary ring, counter-clockwise seen from above, fanned to the apex below.
        let mut ring = Vec::new();
        ring.extend((0..n).map(|i| id(i, 0)));
        ring.extend((0..n).map(|j| id(n, j)));
        ring.extend((0..n).map(|i| id(n - i, n)));
        ring.extend((0..n).map(|j| id(0, n - j)));
        for k in 0..ring.len() {
            tris.push([ring[(k + 1) % ring.len()], ring[k], apex]);
        }
        let labels = vec![[0, 1]; tris.len()];
        LabeledMesh::from_raw(p, &tris, &labels).expect("valid arrays")
    }

    #[test]
    fn smoothing_stays_in_the_plane_and_keeps_volume() {
        let mut m = pillow(6, 0.08);
        let vol_before = geometry::label_volumes(&m);
        let params = SmoothParams::default();
        let mut total = 0;
        for _ in 0..5 {
            total +=
                smooth_vertices(&mut m, &mut VertexAttributes::none(), &mut NoGuard, &params).moved;
        }
        assert!(total > 0);
        // The top grid (vertices 0..49) is planar: tangential and ridge motion keep it so.
        for v in m.vertices().filter(|v| v.idx() < 49) {
            assert!(
                m.position(v).z.abs() < 1e-12,
                "top vertex {v} left the plane"
            );
        }
        let vol_after = geometry::label_volumes(&m);
        for (l, v) in &vol_before {
            assert!((vol_after[l] - v).abs() < 1e-9);
        }
    }

    /// Relative standard deviation of the triangle edge lengths.
    fn edge_spread(m: &LabeledMesh) -> f64 {
        let lens: Vec<f64> = m
            .triangles()
            .flat_map(|t| {
                let p = m.tri_positions(t);
                [
                    p[0].distance(p[1]),
                    p[1].distance(p[2]),
                    p[2].distance(p[0]),
                ]
            })
            .collect();
        let mean = lens.iter().sum::<f64>() / lens.len() as f64;
        (lens.iter().map(|l| (l - mean).powi(2)).sum::<f64>() / lens.len() as f64).sqrt() / mean
    }

    #[test]
    fn smoothing_evens_a_jittered_sphere_without_leaving_it() {
        use rand::{Rng, SeedableRng};
        let mut m =
            crate::generators::icosphere(3, DVec3::ZERO, 1.0, [Label::new(0), Label::new(1)])
                .expect("sphere");
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for v in m.vertices().collect::<Vec<_>>() {
            let p = m.position(v);
            let jitter = DVec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            );
            m.set_position(v, (p + 0.04 * jitter).normalize());
        }
        let before = edge_spread(&m);
        for _ in 0..6 {
            smooth_vertices(
                &mut m,
                &mut VertexAttributes::none(),
                &mut NoGuard,
                &SmoothParams::default(),
            );
        }
        let after = edge_spread(&m);
        assert!(
            after < 0.8 * before,
            "edge length spread {before} -> {after}"
        );
        let off = m
            .vertices()
            .map(|v| (m.position(v).length() - 1.0).abs())
            .fold(0.0, f64::max);
        assert!(off < 5e-3, "left the sphere by {off}");
    }

    #[test]
    fn curve_and_corner_vertices_stay() {
        let mut m = double_box();
        // Jitter a smooth (face-interior) vertex? The boxes have none: every vertex is a
        // corner or on the triple square, so nothing may move.
        let before = m.to_raw();
        let out = smooth_vertices(
            &mut m,
            &mut VertexAttributes::none(),
            &mut NoGuard,
            &SmoothParams::default(),
        );
        assert_eq!(out.moved, 0);
        assert_eq!(m.to_raw(), before);
    }
}
