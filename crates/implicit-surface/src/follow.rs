//! Stage 2 — following the animated surface (paper §2 and §4), with a tracker backend
//! resolving the topology.
//!
//! One frame, from the mesh on `F(·, t₀) = 0` to `F(·, t₁) = 0` ([`Follower::advance_to`]):
//!
//! ```text
//! relax (tangential)  →  project (Newton, eq. 2)  →  hint quasi-critical points
//!   →  tracker.advance(proposal)  (grid backend: overlaps merge, sub-ℓ necks split,
//!                                  remeshing keeps edges in 0.5–1.5 ℓ)
//!   →  re-project the tracker's mesh onto F(·, t₁)
//! ```
//!
//! **Keeping the mesh well shaped.** The paper's FEM "skin" (§2.3–2.4: one rest
//! triangle, quasi-static solve, split/collapse by edge length) is replaced by two
//! things we already have: a light *tangential relaxation* before projection (each
//! vertex moves a fraction of the way to the mean of its neighbours, within the tangent
//! plane of `F`, so it does not fight the projection), and the shared remeshing
//! `mesh_core::remesh::improve` that the grid tracker runs after every step (split
//! above 1.5 ℓ, collapse below 0.5 ℓ, Delaunay flips, null-space smoothing, every edit
//! checked). Why: `improve` is the paper's ALTERMESH and FEM together, already tested on
//! both backends, and it keeps sampling uniform without a linear solve per frame; the
//! relaxation only stops vertices from bunching where the surface shrinks between two
//! improvements.
//!
//! **Topology.** The paper detects blending by collisions between the two meshes and
//! splitting by quasi-critical points, then erases, welds and collapses triangles by
//! hand, one pair at a time. Here the grid tracker (Heiss-Synak et al. 2024) does it,
//! for any number of places at once, including three surfaces meeting in one spot:
//! - the tracker runs with [`FollowParams::deep_radius`] = 0 (default), i.e. every
//!   complex grid edge — one crossed by the mesh more than once — whose labels are not
//!   those of its end nodes is rebuilt from the node labels. A gap between two sheets,
//!   or a neck, thinner than the cell size ℓ is exactly such an edge, so two surfaces
//!   that the field brings within ℓ merge and a neck the projection thins below ℓ is cut:
//!   topology is resolved at the scale ℓ, the tracker's topological resolution;
//! - overlaps (two meshes pushed into each other) are non-physical cells and merge;
//! - quasi-critical points (§2.2) are the hint for changes faster than one frame: a
//!   vertex whose projection fails *inside* (`F > 0`: it sits at an interior saddle
//!   between two sheets that the field just joined) is pushed outward along its normal
//!   by [`FollowParams::hint_push`]·ℓ, into the other sheet, and one failing *outside*
//!   (`F < 0`: left on a neck that the field just cut) inward, across the neck; the
//!   resulting overlap or inverted tube is a flaw the tracker rebuilds from the grid.
//!
//! **Deep, fast overlaps.** Every vertex is projected onto its *own* sheet
//! ([`project_point_oriented`]): where `F > 0` at a vertex the surface grew over it and
//! the vertex moves out along its own normal, never back through the inside to the
//! nearest point of another element's surface. Plain Newton did the latter when one
//! element moved into another by more than about ℓ per frame: the sheet folded onto the
//! union's surface with its orientation reversed, the two windings cancelled, and the
//! tracker's exact ray casting found *outside* material vectors in the middle of the
//! overlap (physical ones, so the labelling of non-physical regions was never involved);
//! the material vanished (crossing at ℓ = 0.1 or 0.15 in 10 frames, ℓ = 0.08 in 12–15).
//! Now a vertex that finds no surface on its ray within `max_travel` stays inside the other
//! element; that overlap is non-physical and the tracker merges it.
//!
//! **Limits, measured** (`examples/metaballs.rs`): topology follows the field's to
//! within a frame or two when a vertex moves less than about ½ ℓ per frame; at 1–3 ℓ per
//! frame (the crossing at ℓ = 0.08–0.15 in 8–15 frames) nothing vanishes any more, but
//! the split after the crossing can lag the field's by a frame or two and leave a small
//! extra piece for a frame. Surfaces born away from the mesh (a new blob appearing from
//! nothing) are never seen — as in the paper.
//!
//! The follower's own mesh ([`Follower::mesh`]) is the tracker's mesh re-projected onto
//! `F(·, t₁)`: the tracker's repairs and smoothing move vertices slightly off the
//! surface, and the next frame's proposal starts from these projected positions anyway.
//! The re-projection is guarded ([`reproject`]), so every frame handed out is valid with
//! the exact intersection check; around a merge or a cut some vertices wait off the
//! surface (counted in [`FrameReport::unprojected`]) while the tracker, which starts the
//! next frame from the unguarded projection, resolves the change.

use std::collections::HashSet;
use std::time::Instant;

use glam::DVec3;
use grid_tracker::{GridParams, GridTracker, ImproveScope};
use mesh_core::remesh::{self, SmoothParams, StaticIntersectionGuard, VertexAttributes};
use mesh_core::{Label, LabeledMesh, RegionCensus, StepReport, SurfaceTracker, VertexId};
use rayon::prelude::*;

use crate::error::{ImplicitError, invalid};
use crate::field::ImplicitField;
use crate::polygonize::polygonize_mesh;
use crate::project::{
    ProjectParams, Projection, ProjectionOutcome, project_point, project_point_oriented,
};

/// Parameters of the follower; lengths are fractions of the target edge length ℓ.
#[derive(Clone, Debug, PartialEq)]
pub struct FollowParams {
    /// Target edge length ℓ; also the grid tracker's cell size (its topological
    /// resolution). Required, > 0.
    pub edge_length: f64,
    /// Newton steps per projection. Default 8.
    pub max_iterations: usize,
    /// Largest Newton step, × ℓ. Default 0.5.
    pub step_fraction: f64,
    /// Largest distance a vertex walks in one frame, × ℓ. Default 2. A surface moving
    /// faster is followed over several frames (the vertices report not converged).
    pub travel_fraction: f64,
    /// Tangential relaxation passes before projection. Default 1.
    pub relax_passes: usize,
    /// Fraction of the way to the neighbours' mean each pass moves. Default 0.3.
    pub relax_weight: f64,
    /// How far a quasi-critical vertex is pushed across the gap or neck, × ℓ (0: never).
    /// Default 1.
    pub hint_push: f64,
    /// The tracker's deep-edge radius (see the module doc). Default 0.
    pub deep_radius: i32,
    /// Surface components enclosing less than `debris_volume · ℓ³` are removed after the
    /// tracker step (0: never). Default 0.25. Why: when blobs separate fast, the
    /// tracker's rebuild can leave closed slivers of a few triangles and no volume at
    /// the cut; the field has no surface there (projection fails on them), and a
    /// feature smaller than ℓ³ is below the resolution anyway.
    pub debris_volume: f64,
    /// The grid tracker's parameters; `cell_size` and `flaws.deep_radius` are
    /// overwritten from the fields above.
    pub tracker: GridParams,
}

impl FollowParams {
    /// Defaults for edge length `edge_length`.
    pub fn new(edge_length: f64) -> Self {
        Self {
            edge_length,
            max_iterations: 8,
            step_fraction: 0.5,
            travel_fraction: 2.0,
            relax_passes: 1,
            relax_weight: 0.3,
            hint_push: 1.0,
            deep_radius: 0,
            debris_volume: 0.25,
            // Projection moves every vertex every frame: the whole surface is changed
            // surface, so improvement keeps its whole-mesh scope here (the grid backend's
            // local default seeds only from rebuilt and degraded triangles).
            tracker: GridParams {
                improve_scope: ImproveScope::Whole,
                ..GridParams::default()
            },
        }
    }

    /// Checks the fields, naming the bad one.
    pub fn check(&self) -> Result<(), ImplicitError> {
        const W: &str = "FollowParams";
        if !(self.edge_length.is_finite() && self.edge_length > 0.0) {
            return Err(invalid(
                W,
                "edge_length",
                self.edge_length,
                "finite and > 0",
            ));
        }
        for (name, v, lo, hi) in [
            ("step_fraction", self.step_fraction, 1e-6, 100.0),
            ("travel_fraction", self.travel_fraction, 1e-6, 1e3),
            ("relax_weight", self.relax_weight, 0.0, 1.0),
            ("hint_push", self.hint_push, 0.0, 10.0),
            ("debris_volume", self.debris_volume, 0.0, 1e3),
        ] {
            if !(v.is_finite() && (lo..=hi).contains(&v)) {
                return Err(invalid(W, name, v, "within its documented range"));
            }
        }
        if self.relax_passes > 100 {
            return Err(invalid(W, "relax_passes", self.relax_passes, "at most 100"));
        }
        if !(0..=8).contains(&self.deep_radius) {
            return Err(invalid(W, "deep_radius", self.deep_radius, "in 0..=8"));
        }
        self.projection().check()
    }

    /// The Newton parameters these imply.
    pub fn projection(&self) -> ProjectParams {
        ProjectParams {
            max_iterations: self.max_iterations,
            ..ProjectParams::for_edge_length(
                self.edge_length,
                self.step_fraction,
                self.travel_fraction,
            )
        }
    }

    /// The grid tracker's parameters these imply.
    pub fn grid_params(&self) -> GridParams {
        let mut p = self.tracker.clone();
        p.cell_size = Some(self.edge_length);
        p.flaws.deep_radius = self.deep_radius;
        p
    }
}

/// Which way a quasi-critical point failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum QuasiCriticalKind {
    /// `F > 0` where the walk stopped: an interior saddle, two sheets the field joined.
    Blend,
    /// `F < 0`: an exterior saddle, a neck the field cut (or no surface within reach).
    Split,
}

/// A vertex whose projection failed (paper §2.2, "quasi-critical" point).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuasiCritical {
    /// The vertex (id in the mesh the proposal was made for).
    pub vertex: VertexId,
    /// Where its Newton walk stopped.
    pub position: DVec3,
    /// `F` there.
    pub value: f64,
    /// Why it stopped.
    pub outcome: ProjectionOutcome,
    /// Blend or split side.
    pub kind: QuasiCriticalKind,
}

/// The positions to hand to a tracker, and the quasi-critical points met on the way.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Proposal {
    /// One position per vertex slot (dead slots copied).
    pub positions: Vec<DVec3>,
    /// The vertices whose projection failed, with how.
    pub quasi_critical: Vec<QuasiCritical>,
}

/// Outward unit normal of every vertex slot: area-weighted face normals, each turned to
/// face the outside label 0 (triangles between two inside labels do not count).
pub fn outward_vertex_normals(mesh: &LabeledMesh) -> Vec<DVec3> {
    let face: Vec<DVec3> = (0..mesh.triangle_capacity())
        .into_par_iter()
        .with_min_len(1024)
        .map(|t| {
            let t = mesh_core::TriId::new(t as u32);
            if !mesh.is_triangle_alive(t) {
                return DVec3::ZERO;
            }
            let [a, b, c] = mesh.tri_positions(t);
            let n = (b - a).cross(c - a);
            let [front, back] = mesh.labels(t);
            if front == Label::OUTSIDE {
                n
            } else if back == Label::OUTSIDE {
                -n
            } else {
                DVec3::ZERO
            }
        })
        .collect();
    (0..mesh.vertex_capacity())
        .into_par_iter()
        .with_min_len(1024)
        .map(|v| {
            let v = VertexId::new(v as u32);
            if !mesh.is_vertex_alive(v) {
                return DVec3::ZERO;
            }
            mesh.vertex_triangles(v)
                .map(|t| face[t.idx()])
                .sum::<DVec3>()
                .normalize_or_zero()
        })
        .collect()
}

/// One pass of tangential relaxation: each live vertex moves `weight` of the way to the
/// mean of its neighbours (over incident triangles), with the component along `∇F`
/// removed so the move stays in the surface's tangent plane.
fn relax(
    mesh: &LabeledMesh,
    field: &(impl ImplicitField + ?Sized),
    positions: &[DVec3],
    t: f64,
    weight: f64,
) -> Vec<DVec3> {
    (0..mesh.vertex_capacity())
        .into_par_iter()
        .with_min_len(256)
        .map(|v| {
            let vid = VertexId::new(v as u32);
            let p = positions[v];
            if !mesh.is_vertex_alive(vid) {
                return p;
            }
            let (mut sum, mut n) = (DVec3::ZERO, 0.0);
            for tri in mesh.vertex_triangles(vid) {
                for w in mesh.tri(tri) {
                    if w != vid {
                        sum += positions[w.idx()];
                        n += 1.0;
                    }
                }
            }
            if n == 0.0 {
                return p;
            }
            let lap = sum / n - p;
            let g = field.gradient(p, t);
            let normal = if g.is_finite() {
                g.normalize_or_zero()
            } else {
                DVec3::ZERO
            };
            p + (lap - normal * lap.dot(normal)) * weight
        })
        .collect()
}

/// The proposal for moving `mesh` onto `F(·, t) = 0`: tangential relaxation, Newton
/// projection of every vertex (in parallel), and the push of quasi-critical vertices
/// across their gap or neck (module doc). Pure: reads the mesh, returns positions, so a
/// harness flow can call it for any backend.
pub fn propose(
    mesh: &LabeledMesh,
    field: &(impl ImplicitField + ?Sized),
    t: f64,
    params: &FollowParams,
) -> Result<Proposal, ImplicitError> {
    params.check()?;
    let mut positions = mesh.positions().to_vec();
    for _ in 0..params.relax_passes {
        if params.relax_weight > 0.0 {
            positions = relax(mesh, field, &positions, t, params.relax_weight);
        }
    }
    let pp = params.projection();
    // Each vertex keeps to its own sheet ([`project_point_oriented`]): without the
    // orientation, deep overlaps fold sheets onto each other and their material vanishes.
    let normals = outward_vertex_normals(mesh);
    let projections: Vec<Option<Projection>> = (0..mesh.vertex_capacity())
        .into_par_iter()
        .with_min_len(256)
        .map(|v| {
            mesh.is_vertex_alive(VertexId::new(v as u32))
                .then(|| project_point_oriented(field, positions[v], normals[v], t, &pp))
        })
        .collect();
    let push = params.hint_push * params.edge_length;
    let mut quasi_critical = Vec::new();
    for (v, pr) in projections.iter().enumerate() {
        let Some(pr) = pr else { continue };
        let vid = VertexId::new(v as u32);
        if !pr.position.is_finite() {
            return Err(ImplicitError::NonFiniteField {
                stage: "project",
                at: positions[v].to_array(),
                t,
            });
        }
        positions[v] = pr.position;
        if pr.is_quasi_critical() {
            let kind = if pr.value > 0.0 {
                QuasiCriticalKind::Blend
            } else {
                QuasiCriticalKind::Split
            };
            if push > 0.0 && pr.outcome == ProjectionOutcome::FlatGradient {
                let n = normals[v];
                positions[v] += match kind {
                    QuasiCriticalKind::Blend => n * push,
                    QuasiCriticalKind::Split => -n * push,
                };
            }
            quasi_critical.push(QuasiCritical {
                vertex: vid,
                position: pr.position,
                value: pr.value,
                outcome: pr.outcome,
                kind,
            });
        }
    }
    Ok(Proposal {
        positions,
        quasi_critical,
    })
}

/// Projects every live vertex of `mesh` onto `F(·, t) = 0` in place (no relaxation, no
/// hints), as far as the mesh stays valid: [`projection_targets`], committed as guarded
/// moves ([`commit_moves`] under a [`StaticIntersectionGuard`]). A move that would turn
/// a triangle over or make two triangles intersect is held back and the vertex keeps its
/// position.
///
/// Why guarded: around a merge or a cut the tracker has not caught up with the field
/// yet, and its mesh projected freely folds there. Measured on the three blobs of
/// `scenes::triple` (ℓ = 0.12, 30 frames): the frames where they merge and separate had
/// 73–173 intersecting triangle pairs, and as they separated the tracker left a closed
/// piece of 76 triangles at the centre, every vertex at `F < 0`, which the projection
/// spread over the surrounding blobs inside out. Guarded, every frame validates; up to
/// 8 % of the vertices (nearly all of them for turning a triangle over) wait off the
/// surface, for at most three frames in a row, while the tracker resolves the change
/// ([`Follower`] starts each frame from the unguarded projection, so the tracker's
/// course is unchanged).
///
/// Returns the number of live vertices left off the surface (walk failed or move held
/// back) and the largest first-order distance `|F|/‖∇F‖` on the others.
///
/// [`commit_moves`]: mesh_core::remesh::commit_moves
pub fn reproject(
    mesh: &mut LabeledMesh,
    field: &(impl ImplicitField + ?Sized),
    t: f64,
    params: &ProjectParams,
) -> (usize, f64) {
    let targets = projection_targets(mesh, field, t, params);
    commit_targets(mesh, field, t, &targets)
}

/// Where [`reproject`] would take every vertex slot: `None` for dead slots and for live
/// vertices whose walk fails. A walk that fails (the vertex sits at a critical point of
/// `F`, where the gradient gives no direction) is retried from the position nudged by
/// `¼·max_travel`, then `½·max_travel`, along its outward mesh normal (outward when
/// `F > 0`, inward when `F < 0`: towards the surface), which breaks the symmetry that
/// stalled it.
fn projection_targets(
    mesh: &LabeledMesh,
    field: &(impl ImplicitField + ?Sized),
    t: f64,
    params: &ProjectParams,
) -> Vec<Option<DVec3>> {
    // Oriented, as in [`propose`]: a tracker mesh still overlapping itself must not be
    // folded onto the other sheet's surface by the re-projection either. Where the own
    // sheet's ray finds no surface within reach (a rebuilt vertex whose normal runs
    // along the surface), plain Newton as before.
    let normals = outward_vertex_normals(mesh);
    let attempt = |p: DVec3, n: DVec3| -> Option<DVec3> {
        let pr = project_point_oriented(field, p, n, t, params);
        let pr = if pr.is_quasi_critical() {
            project_point(field, p, t, params)
        } else {
            pr
        };
        (!pr.is_quasi_critical() && pr.position.is_finite()).then_some(pr.position)
    };
    (0..mesh.vertex_capacity())
        .into_par_iter()
        .with_min_len(256)
        .map(|v| {
            if !mesh.is_vertex_alive(VertexId::new(v as u32)) {
                return None;
            }
            let (p, n) = (mesh.positions()[v], normals[v]);
            attempt(p, n).or_else(|| {
                let toward = if field.value(p, t) > 0.0 { 1.0 } else { -1.0 };
                [0.25, 0.5]
                    .iter()
                    .find_map(|&s| attempt(p + n * (toward * s * params.max_travel), n))
            })
        })
        .collect()
}

/// Moves every vertex to its target as far as the mesh stays valid ([`reproject`]);
/// returns the live vertices left off the surface and the largest `|F|/‖∇F‖` on the
/// others.
fn commit_targets(
    mesh: &mut LabeledMesh,
    field: &(impl ImplicitField + ?Sized),
    t: f64,
    targets: &[Option<DVec3>],
) -> (usize, f64) {
    let before = mesh.positions().to_vec();
    let moves: Vec<remesh::Proposal> = targets
        .iter()
        .enumerate()
        .filter_map(|(v, q)| {
            let displacement = (*q)? - before[v];
            (displacement != DVec3::ZERO).then_some(remesh::Proposal {
                vertex: VertexId::new(v as u32),
                displacement,
                normal: None,
            })
        })
        .collect();
    // No rotation limit and no volume limit: the projection decides where the surface
    // is; only a triangle turned over (the local check) or an intersection (the guard)
    // holds a vertex back.
    let checks = SmoothParams {
        min_normal_cos: -1.0,
        ..SmoothParams::default()
    };
    remesh::commit_moves(
        mesh,
        &mut VertexAttributes::none(),
        &mut StaticIntersectionGuard::new(),
        &checks,
        &moves,
    );
    let mut off = 0;
    let mut worst: f64 = 0.0;
    for v in mesh.vertices() {
        // Moved (to its target, up to the rounding of `p + (q − p)`), or already there.
        let p = mesh.position(v);
        match targets[v.idx()] {
            Some(q) if p != before[v.idx()] || q == p => {
                let (f, g) = field.value_and_gradient(p, t);
                worst = worst.max(f.abs() / g.length().max(f64::MIN_POSITIVE));
            }
            _ => off += 1,
        }
    }
    (off, worst)
}

/// The triangles of the surface components (triangles joined through shared vertices)
/// whose enclosed volume is below `min_volume`, and how many such components there are.
fn debris(mesh: &LabeledMesh, min_volume: f64) -> (Vec<mesh_core::TriId>, usize) {
    use mesh_core::union_find::{find, union};
    let mut parent: Vec<u32> = (0..mesh.vertex_capacity() as u32).collect();
    for t in mesh.triangles() {
        let [a, b, c] = mesh.tri(t).map(|v| v.raw());
        union(&mut parent, a, b);
        union(&mut parent, b, c);
    }
    let mut volume = vec![0.0f64; mesh.vertex_capacity()];
    let mut root_of = Vec::with_capacity(mesh.num_triangles());
    for t in mesh.triangles() {
        let r = find(&mut parent, mesh.tri(t)[0].raw());
        let [a, b, c] = mesh.tri_positions(t);
        let [front, back] = mesh.labels(t);
        let sign = if front == Label::OUTSIDE {
            1.0
        } else if back == Label::OUTSIDE {
            -1.0
        } else {
            0.0
        };
        volume[r as usize] += sign * mesh_core::geometry::signed_cone_volume(a, b, c);
        root_of.push((t, r));
    }
    let mut doomed = Vec::new();
    let mut roots = Vec::new();
    for (t, r) in root_of {
        if volume[r as usize].abs() < min_volume {
            doomed.push(t);
            roots.push(r);
        }
    }
    roots.sort_unstable();
    roots.dedup();
    (doomed, roots.len())
}

/// A good starting mesh of `F(·, t0) = 0` inside `bounds`: marching tetrahedra at cells
/// of size ℓ (the paper's initial mesh, §2), then the shared remeshing
/// (`mesh_core::remesh::improve`, edges to 0.5–1.5 ℓ; marching tetrahedra leaves
/// slivers) and a projection back onto the surface. Falls back to the raw
/// polygonization if the improved mesh does not validate.
pub fn initial_mesh(
    field: &(impl ImplicitField + ?Sized),
    t0: f64,
    bounds: [DVec3; 2],
    edge_length: f64,
) -> Result<LabeledMesh, ImplicitError> {
    use mesh_core::remesh::{ImproveParams, NoGuard, improve};
    use mesh_core::validate::{ValidateOptions, validate};
    let raw = polygonize_mesh(field, t0, bounds, edge_length)?;
    let mut mesh = raw.clone();
    let params = ImproveParams {
        target_edge_length: Some(edge_length),
        ..ImproveParams::default()
    };
    let mut attrs = VertexAttributes::none();
    improve(&mut mesh, &params, &mut attrs, &mut NoGuard);
    mesh.compact();
    let pp = ProjectParams::for_edge_length(edge_length, 0.5, 1.0);
    reproject(&mut mesh, field, t0, &pp);
    if mesh.num_triangles() > 0 && validate(&mesh, &ValidateOptions::default()).is_valid() {
        Ok(mesh)
    } else {
        Ok(raw)
    }
}

/// What one frame did.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameReport {
    /// The time reached.
    pub t: f64,
    /// Live vertices and triangles of the output mesh.
    pub vertices: usize,
    /// Live triangles.
    pub triangles: usize,
    /// Surface components (connected pieces of the mesh).
    pub components: usize,
    /// Quasi-critical points of the proposal (before the tracker).
    pub quasi_critical: Vec<QuasiCritical>,
    /// Vertices left off the surface by the final re-projection: its walk failed, or the
    /// move would have turned a triangle over or made two intersect ([`reproject`]).
    pub unprojected: usize,
    /// Largest `|F|/‖∇F‖` over the projected output vertices.
    pub max_residual: f64,
    /// Output vertices that are the same particle as in the previous frame (carried by
    /// the tracker, not created or rebuilt by it): the temporal-coherence count.
    pub persisted: usize,
    /// Debris components removed after the tracker step.
    pub debris_removed: usize,
    /// The tracker's report.
    pub tracker: StepReport,
    /// Wall seconds of the whole frame (proposal, tracker step, re-projection).
    pub seconds: f64,
}

/// A mesh following an animated implicit surface, with the grid tracker resolving its
/// topology (module doc).
pub struct Follower<F: ImplicitField> {
    field: F,
    params: FollowParams,
    tracker: GridTracker,
    /// The valid mesh handed out: the tracker's, re-projected as far as it stays valid.
    mesh: LabeledMesh,
    /// The tracker's mesh with every vertex on its projection, valid or not: where the
    /// next proposal starts. Why not [`Self::mesh`]: a vertex held back there would
    /// lag a frame behind the field at every merge and cut, and the tracker, fed its
    /// stale position, resolves the change differently (the three blobs' merge came
    /// apart into two and three components for four frames); the tracker checks its own
    /// step, so its input need not be valid.
    basis: LabeledMesh,
    time: f64,
    next_tag: u64,
}

/// A tag for vertex identity: a pseudo-random double in [1, 2). Blends of tags (what
/// edits and the PIC transfer give new vertices) are, with overwhelming probability, not
/// tags themselves, so a tag found again means the same vertex.
fn tag(counter: u64) -> f64 {
    let mut z = counter.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    f64::from_bits(0x3FF0_0000_0000_0000 | (z >> 12))
}

impl<F: ImplicitField> Follower<F> {
    /// Meshes `F(·, t0) = 0` inside `field.bounds(t0)` (or `bounds` if given) with
    /// [`initial_mesh`] and starts the tracker.
    pub fn new(
        field: F,
        t0: f64,
        bounds: Option<[DVec3; 2]>,
        params: FollowParams,
    ) -> Result<Self, ImplicitError> {
        params.check()?;
        let bounds = bounds.or_else(|| field.bounds(t0)).ok_or_else(|| {
            invalid(
                "Follower::new",
                "bounds",
                "None",
                "a box (the field reports none)",
            )
        })?;
        let mesh = initial_mesh(&field, t0, bounds, params.edge_length)?;
        Self::from_mesh(field, mesh, t0, params)
    }

    /// Starts from a given valid mesh near `F(·, t0) = 0` (labels `[0, inside]`).
    pub fn from_mesh(
        field: F,
        mesh: LabeledMesh,
        t0: f64,
        params: FollowParams,
    ) -> Result<Self, ImplicitError> {
        params.check()?;
        let mut tracker = GridTracker::new(mesh, params.grid_params())
            .map_err(|source| ImplicitError::Track { t: t0, source })?;
        let mut attrs = VertexAttributes::zeros(tracker.mesh(), 1);
        let mut next_tag = 0;
        for v in tracker.mesh().vertices() {
            attrs.get_mut(v)[0] = tag(next_tag);
            next_tag += 1;
        }
        tracker.set_attributes(attrs);
        let mesh = tracker.mesh().clone();
        Ok(Self {
            field,
            params,
            tracker,
            basis: mesh.clone(),
            mesh,
            time: t0,
            next_tag,
        })
    }

    /// The mesh on `F(·, time) = 0`.
    pub fn mesh(&self) -> &LabeledMesh {
        &self.mesh
    }

    /// The time of [`Self::mesh`].
    pub fn time(&self) -> f64 {
        self.time
    }

    /// The field.
    pub fn field(&self) -> &F {
        &self.field
    }

    /// The parameters.
    pub fn params(&self) -> &FollowParams {
        &self.params
    }

    /// The tracker (its mesh is [`Self::mesh`] before the final re-projection).
    pub fn tracker(&self) -> &GridTracker {
        &self.tracker
    }

    /// Removes surface components enclosing less than `debris_volume · ℓ³` from the
    /// tracker's mesh (never all of them), restarting the tracker on the cleaned mesh
    /// with the identity tags carried over. Returns the number removed.
    fn remove_debris(&mut self, t: f64) -> Result<usize, ImplicitError> {
        let min_volume = self.params.debris_volume * self.params.edge_length.powi(3);
        if min_volume <= 0.0 {
            return Ok(0);
        }
        let (doomed, count) = debris(self.tracker.mesh(), min_volume);
        if count == 0 || doomed.len() == self.tracker.mesh().num_triangles() {
            return Ok(0);
        }
        let mut mesh = self.tracker.mesh().clone();
        let mut orphans = Vec::new();
        for &tri in &doomed {
            orphans.extend(mesh.tri(tri));
            mesh.remove_triangle(tri)
                .map_err(|source| ImplicitError::Mesh {
                    stage: "debris",
                    source,
                })?;
        }
        orphans.sort_unstable();
        orphans.dedup();
        for v in orphans {
            if mesh.vertex_triangles(v).next().is_none() {
                mesh.remove_vertex(v)
                    .map_err(|source| ImplicitError::Mesh {
                        stage: "debris",
                        source,
                    })?;
            }
        }
        let map = mesh.compact();
        let old = self.tracker.attributes();
        let mut attrs = VertexAttributes::zeros(&mesh, 1);
        for (o, n) in map.vertex_map.iter().enumerate() {
            if let Some(n) = n {
                attrs.get_mut(*n)[0] = old.get(VertexId::new(o as u32))[0];
            }
        }
        // A fresh tracker restarts its step count: shift the seed so its grid shifts do
        // not repeat the first steps'.
        let mut gp = self.params.grid_params();
        gp.seed = gp
            .seed
            .wrapping_add(self.tracker.steps().wrapping_mul(0x9E37_79B9));
        let mut tracker =
            GridTracker::new(mesh, gp).map_err(|source| ImplicitError::Track { t, source })?;
        tracker.set_attributes(attrs);
        self.tracker = tracker;
        Ok(count)
    }

    /// One frame to time `t` (module doc). On error the follower keeps its previous mesh
    /// and time.
    pub fn advance_to(&mut self, t: f64) -> Result<FrameReport, ImplicitError> {
        if !t.is_finite() {
            return Err(invalid("Follower::advance_to", "t", t, "finite"));
        }
        let start = Instant::now();
        let proposal = propose(&self.basis, &self.field, t, &self.params)?;
        let before: HashSet<u64> = self
            .tracker
            .mesh()
            .vertices()
            .map(|v| self.tracker.attributes().get(v)[0].to_bits())
            .collect();
        let step = self
            .tracker
            .advance(&proposal.positions)
            .map_err(|source| ImplicitError::Track { t, source })?;
        // Identity: keep the tags that survived, give fresh ones to new vertices.
        let live: Vec<VertexId> = self.tracker.mesh().vertices().collect();
        let mut persisted = 0;
        let mut next_tag = self.next_tag;
        let attrs = self.tracker.attributes_mut();
        for v in live {
            let slot = &mut attrs.get_mut(v)[0];
            if before.contains(&slot.to_bits()) {
                persisted += 1;
            } else {
                *slot = tag(next_tag);
                next_tag += 1;
            }
        }
        self.next_tag = next_tag;
        let debris_removed = self.remove_debris(t)?;
        let mut mesh = self.tracker.mesh().clone();
        // The tracker may have rebuilt vertices a few ℓ from the surface (e.g. on the
        // cap of a neck it just cut, where the field is flat): the final projection may
        // walk twice as far and twice as long as the proposal's.
        let pp = self.params.projection();
        let far = ProjectParams {
            max_iterations: 2 * pp.max_iterations,
            max_travel: 2.0 * pp.max_travel,
            ..pp
        };
        let targets = projection_targets(&mesh, &self.field, t, &far);
        let mut basis = mesh.clone();
        for (p, q) in basis.positions_mut().iter_mut().zip(&targets) {
            *p = q.unwrap_or(*p);
        }
        let (unprojected, max_residual) = commit_targets(&mut mesh, &self.field, t, &targets);
        let components = RegionCensus::of(&mesh).components;
        self.mesh = mesh;
        self.basis = basis;
        self.time = t;
        Ok(FrameReport {
            t,
            vertices: self.mesh.num_vertices(),
            triangles: self.mesh.num_triangles(),
            components,
            quasi_critical: proposal.quasi_critical,
            unprojected,
            max_residual,
            persisted,
            debris_removed,
            tracker: step,
            seconds: start.elapsed().as_secs_f64(),
        })
    }
}
