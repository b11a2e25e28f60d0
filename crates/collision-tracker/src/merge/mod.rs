//! Snap merging (Los Topos §7.1, "generalized snapping"): surfaces that come within the
//! merge distance of each other are joined by snapping vertex pairs together.
//!
//! ```text
//! for round in 0..max_rounds:
//!     proximate_pairs     vertex–triangle and edge–edge pairs closer than merge_distance,
//!                         non-adjacent, nearest first
//!     for each pair:      re-check it against the current mesh (still proximate,
//!                         brought together by the flow if a displacement is given, and
//!                         not joined to its partner by a short path of edges), then
//!         counterparts    give each side a vertex: an existing vertex if the closest
//!                         point is within merge_distance of one, else split the edge at
//!                         the closest point (also when a triangle's closest point lies
//!                         that close to one of its edges), else trisect the triangle there
//!         snap            coalesce the two vertices at their average (refused when they
//!                         share an edge, or would fold triangles meeting at ≥ 90°)
//!     remove_degenerate   coincident triangle pairs: equal outer labels → both deleted
//!                         (the regions merge), different → one kept with the two outer
//!                         labels (a new interface)
//!     pinch (optional)    duplicate singular vertices
//!     stop when a round snaps nothing
//! remove_thin_regions     pockets the snaps trapped between the joined sheets absorbed
//!                         into their main neighbour (optional)
//! ```
//!
//! **Why pockets are closed here.** Snapping joins two sheets pair by pair, and what lies
//! between joined pairs is a closed pocket of the surrounding material a few thousandths of
//! ℓ thick. Its two sides are neighbours along the mesh, so later rounds take them for one
//! sheet (the surface-reach test), and its tiny edges block every collapse: left alone,
//! pockets pile up in the wall (≈ 100 after 40 steps of two spheres pressed together) as
//! crumples that remeshing cannot smooth. Closing a pocket is the T2 rule for a region of
//! (almost) zero volume, bounded by Ω like every remeshing edit.
//!
//! Every split, snap and removal is one atomic edit through the caller's guard (pass a
//! [`crate::CollisionGuard`] to keep the mesh intersection-free), so a refused or vetoed
//! step leaves the mesh as it was and the merge simply goes on with the next pair. The
//! mesh stays valid throughout: splits and snaps preserve every invariant except that
//! snaps may leave coincident triangle pairs, which the degenerate removal of the same
//! round resolves.

mod pairs;
#[cfg(test)]
mod tests;

use std::collections::{BTreeMap, BTreeSet};

use glam::DVec3;
use mesh_core::remesh::{
    DegenerateReport, EditError, EditGuard, SnapError, SnapParams, SplitRecord, ThinRegionParams,
    ThinRegionReport, VertexAttributes, pinch_singular_vertices, remove_degenerate,
    remove_thin_regions, snap_vertices, split_edge_at, split_triangle_at, undo_split,
};
use mesh_core::{Label, LabeledMesh, MeshError, TriId, VertexId};

use crate::proximity::{Proximity, proximity_edge_edge, proximity_vertex_triangle};
use pairs::{Candidate, Pair, SurfaceReach, proximate_pairs};

/// Options of [`snap_merge`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MergeOptions {
    /// Elements closer than this are merged. Use [`MergeOptions::for_length`] for the
    /// default, 0.02 × the mean edge length (the 2024 paper's comparison setting).
    pub merge_distance: f64,
    /// Bound on the find–split–snap–clean rounds. Default 4: a round snaps every pair that
    /// is still proximate; later rounds catch the pairs the first round's splits created.
    pub max_rounds: usize,
    /// The snap's fold rule. Default [`SnapParams::default`] (90°).
    pub snap: SnapParams,
    /// Pinch singular vertices after each round. Default false: a vertex where two
    /// surfaces touch after a partial merge is valid, and the next merge steps usually
    /// complete it; pinching would pull it apart again.
    pub pinch: bool,
    /// A pair whose elements are joined by a path of mesh edges shorter than
    /// `surface_reach_factor × merge_distance` is not merged: its elements are neighbours
    /// on one sheet that only look proximate because the edges between them are tiny
    /// (slivers, marching-cubes output), not two surfaces that came together. Default 2
    /// (every pair is closer than the merge distance, and a path along a sheet between
    /// two points is rarely longer than twice their distance).
    pub surface_reach_factor: f64,
    /// When `Some(a)`: the vertex attributes passed to [`snap_merge_with`] hold each
    /// vertex's displacement over the step (the flow's proposal) in their first three
    /// values, and only pairs that the displacement brings together faster than `a` along
    /// their normal are merged. Los Topos merges surfaces *as they come within* the merge
    /// distance; surfaces that are merely close — neighbours across a sliver, a notch
    /// moving rigidly — are left alone. Default `None`: every proximate pair merges.
    pub min_approach: Option<f64>,
    /// Pockets closed after the rounds (see the module doc): thin regions with a corner at
    /// a vertex snapped in this call or listed in its `snapped` on entry, so regions that
    /// thin out elsewhere (a shrinking foam cell) are left to T2. `None` leaves them. Default
    /// `None` here; the collision tracker closes regions thinner than a tenth of ℓ
    /// (the thickness below which it does not count a region) of at most Ω.
    pub thin_regions: Option<ThinRegionParams>,
}

impl MergeOptions {
    /// The defaults for a mesh of mean edge length `l`: merge distance `0.02 · l`.
    pub fn for_length(l: f64) -> Self {
        Self {
            merge_distance: 0.02 * l,
            max_rounds: 4,
            snap: SnapParams::default(),
            pinch: false,
            surface_reach_factor: 2.0,
            min_approach: None,
            thin_regions: None,
        }
    }

    /// The defaults for `mesh`, from its mean edge length.
    pub fn for_mesh(mesh: &LabeledMesh) -> Self {
        Self::for_length(mesh_core::remesh::improve::mean_edge_length(mesh))
    }
}

/// What [`snap_merge`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MergeReport {
    /// Vertex pairs snapped together.
    pub snaps: usize,
    /// Edges split at a closest point.
    pub edge_splits: usize,
    /// Triangles trisected at a closest point.
    pub face_splits: usize,
    /// Splits undone because the snap they prepared was refused or vetoed (counted in
    /// `edge_splits` / `face_splits` too).
    pub undone_splits: usize,
    /// Regions joined: over all labels, the decrease of the number of bounded region
    /// shells of that label (a label whose count grows — e.g. a sliver of the outside
    /// trapped between two merged sheets — adds nothing).
    pub merges: usize,
    /// Pairs of labels that share an interface after the merge and did not before.
    pub new_interfaces: usize,
    /// Proximate pairs found (over all rounds).
    pub pairs: usize,
    /// Splits and snaps the operations refused (adjacent vertices, fold angle, stale pair).
    pub refused: usize,
    /// Splits and snaps the guard vetoed.
    pub vetoed: usize,
    /// Pairs skipped as neighbours along the surface (see
    /// [`MergeOptions::surface_reach_factor`]).
    pub same_sheet: usize,
    /// Pairs skipped because the flow does not bring them together (see
    /// [`MergeOptions::min_approach`]).
    pub not_approaching: usize,
    /// Rounds run.
    pub rounds: usize,
    /// Degenerate removal, summed over rounds.
    pub degenerate: DegenerateReport,
    /// Singular vertices pinched.
    pub pinched: usize,
    /// Pockets closed (see [`MergeOptions::thin_regions`]).
    pub thin: ThinRegionReport,
}

impl MergeReport {
    /// True when the merge changed the mesh (a split, snap, or degenerate removal), so
    /// callers know whether indices and region counts must be refreshed.
    pub fn changed(&self) -> bool {
        self.snaps + self.edge_splits + self.face_splits > 0
            || self.degenerate.collapsed_removed
                + self.degenerate.pairs_relabelled
                + self.degenerate.pairs_removed
                > 0
            || self.pinched > 0
            || self.thin.absorbed > 0
    }
}

/// Why [`snap_merge`] stopped. Edits already committed stay (each was atomic and the mesh
/// is valid between them).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MergeError {
    /// An option is out of range.
    #[error("merge option {what} = {value} is invalid: expected {expected}")]
    InvalidOption {
        /// Which option.
        what: &'static str,
        /// Its value.
        value: f64,
        /// What it should be.
        expected: &'static str,
    },
    /// The mesh ran out of ids while splitting.
    #[error("mesh capacity exceeded during snap merging: {0}")]
    Mesh(#[from] MeshError),
    /// A split made for a snap that did not happen could not be undone (a bug: the undo
    /// restores the state just before the split).
    #[error("could not undo a split after a refused snap: {0}")]
    Undo(#[from] EditError),
}

/// Snap merging (see the [module doc](self)) without vertex attributes.
pub fn snap_merge(
    mesh: &mut LabeledMesh,
    options: &MergeOptions,
    guard: &mut impl EditGuard,
) -> Result<MergeReport, MergeError> {
    snap_merge_with(mesh, &mut VertexAttributes::none(), options, guard)
}

/// Snap merging carrying per-vertex attributes through every split and snap.
pub fn snap_merge_with(
    mesh: &mut LabeledMesh,
    attrs: &mut VertexAttributes,
    options: &MergeOptions,
    guard: &mut dyn EditGuard,
) -> Result<MergeReport, MergeError> {
    snap_merge_from(mesh, attrs, options, guard, &mut Vec::new())
}

/// Snap merging that proceeds outward from the contacts already made (Los Topos §7.1:
/// a contact zone joins into one wall within a few steps, instead of one pair at a time).
///
/// `snapped` holds, on entry, the vertices snapped in the previous step (the caller
/// carries them over), and on return those plus every vertex snapped now. A pair one of
/// whose vertices is, or neighbours, a *contact vertex* — one of those, or an end of a
/// non-manifold edge (an existing wall or triple curve) — is merged without the
/// [`MergeOptions::min_approach`] test: the flow brought the surfaces into contact
/// there, and collision response has stopped their approach (the proposal near a fresh
/// wall is the average of two sheets' normals and often points along it), so waiting
/// for the flow to bring each pair together again leaves slivers between the sheets
/// that the next steps' remeshing crumples.
pub fn snap_merge_from(
    mesh: &mut LabeledMesh,
    attrs: &mut VertexAttributes,
    options: &MergeOptions,
    guard: &mut dyn EditGuard,
    snapped: &mut Vec<VertexId>,
) -> Result<MergeReport, MergeError> {
    if !has_work(mesh, options)? {
        return Ok(MergeReport::default());
    }
    let shells_before = bounded_shells(mesh);
    let interfaces_before = interfaces(mesh);
    let mut report = snap_merge_uncounted(mesh, attrs, options, guard, snapped)?;
    let shells_after = bounded_shells(mesh);
    report.merges = shells_before
        .iter()
        .map(|(l, &n)| n.saturating_sub(shells_after.get(l).copied().unwrap_or(0)))
        .sum();
    report.new_interfaces = interfaces(mesh).difference(&interfaces_before).count();
    Ok(report)
}

/// Checks the options; false when there is nothing to merge (distance 0, empty mesh).
fn has_work(mesh: &LabeledMesh, options: &MergeOptions) -> Result<bool, MergeError> {
    let d = options.merge_distance;
    if !(d.is_finite() && d >= 0.0) {
        return Err(MergeError::InvalidOption {
            what: "merge_distance",
            value: d,
            expected: "a finite, non-negative distance",
        });
    }
    let f = options.surface_reach_factor;
    if !(f.is_finite() && f >= 0.0) {
        return Err(MergeError::InvalidOption {
            what: "surface_reach_factor",
            value: f,
            expected: "a finite, non-negative factor",
        });
    }
    if let Some(a) = options.min_approach
        && !(a.is_finite() && a >= 0.0)
    {
        return Err(MergeError::InvalidOption {
            what: "min_approach",
            value: a,
            expected: "a finite, non-negative speed",
        });
    }
    Ok(d > 0.0 && mesh.num_triangles() > 0)
}

/// [`snap_merge_from`] without its event counts ([`MergeReport::merges`] and
/// [`MergeReport::new_interfaces`] stay 0), for the backend's step. Why: those counts
/// take the mesh's regions before and after, two whole-mesh passes that were a sixth of
/// the stage on 20 meeting spheres, and the step counts its events on its own region
/// census anyway.
pub(crate) fn snap_merge_uncounted(
    mesh: &mut LabeledMesh,
    attrs: &mut VertexAttributes,
    options: &MergeOptions,
    guard: &mut dyn EditGuard,
    snapped: &mut Vec<VertexId>,
) -> Result<MergeReport, MergeError> {
    if !has_work(mesh, options)? {
        return Ok(MergeReport::default());
    }
    let d = options.merge_distance;
    let mut report = MergeReport::default();
    let mut reach = SurfaceReach::default();
    let mut contact = contact_vertices(mesh, snapped);
    for _ in 0..options.max_rounds {
        report.rounds += 1;
        let candidates = proximate_pairs(mesh, d);
        if candidates.is_empty() {
            break;
        }
        report.pairs += candidates.len();
        let snaps_before = report.snaps;
        for c in &candidates {
            let state = PairState {
                reach: &mut reach,
                contact: &mut contact,
                snapped: &mut *snapped,
            };
            merge_pair(mesh, attrs, guard, c, options, state, &mut report)?;
        }
        let r = remove_degenerate(mesh, attrs, guard);
        add_degenerate(&mut report.degenerate, &r);
        if options.pinch {
            report.pinched += pinch_singular_vertices(mesh, attrs, guard);
        }
        if report.snaps == snaps_before {
            break;
        }
    }
    if let Some(thin) = &options.thin_regions {
        report.thin = remove_thin_regions(mesh, attrs, guard, thin, Some(snapped));
    }
    Ok(report)
}

/// Per-vertex flags of [`snap_merge_from`]'s contact vertices: the given snapped vertices
/// and the ends of every non-manifold edge.
fn contact_vertices(mesh: &LabeledMesh, snapped: &[VertexId]) -> Vec<bool> {
    let mut flags = vec![false; mesh.vertex_capacity()];
    for t in mesh.triangles() {
        let tri = mesh.tri(t);
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            if a < b && mesh.edge_triangles(a, b).nth(2).is_some() {
                flags[a.idx()] = true;
                flags[b.idx()] = true;
            }
        }
    }
    for &v in snapped {
        if mesh.is_vertex_alive(v) && v.idx() < flags.len() {
            flags[v.idx()] = true;
        }
    }
    flags
}

/// True when `v` or one of its neighbours is a contact vertex.
fn near_contact(mesh: &LabeledMesh, contact: &[bool], v: VertexId) -> bool {
    let flagged = |w: VertexId| contact.get(w.idx()).copied().unwrap_or(false);
    flagged(v)
        || mesh
            .vertex_triangles(v)
            .any(|t| mesh.tri(t).into_iter().any(flagged))
}

/// The merge's working state across pairs.
struct PairState<'a> {
    reach: &'a mut SurfaceReach,
    /// Contact flags by vertex index (see [`snap_merge_from`]).
    contact: &'a mut Vec<bool>,
    /// Vertices snapped (see [`snap_merge_from`]).
    snapped: &'a mut Vec<VertexId>,
}

/// Splits and snaps one proximate pair, if it is still proximate in the current mesh.
fn merge_pair(
    mesh: &mut LabeledMesh,
    attrs: &mut VertexAttributes,
    guard: &mut dyn EditGuard,
    c: &Candidate,
    options: &MergeOptions,
    state: PairState<'_>,
    report: &mut MergeReport,
) -> Result<(), MergeError> {
    let d = options.merge_distance;
    let PairState {
        reach,
        contact,
        snapped,
    } = state;
    // Whether the pair is one to leave alone: not brought together by the flow (unless
    // it borders a contact), or neighbours along one sheet.
    let mut skip = |mesh: &LabeledMesh,
                    attrs: &VertexAttributes,
                    prox: &Proximity,
                    quad: [VertexId; 4],
                    report: &mut MergeReport| {
        let at_contact = || quad.iter().any(|&v| near_contact(mesh, contact, v));
        if let Some(a) = options.min_approach
            && !at_contact()
        {
            if attrs.dim() < 3 {
                return false;
            }
            let relative: DVec3 = (0..4)
                .map(|i| DVec3::from_slice(attrs.get(quad[i])) * prox.weights[i])
                .sum();
            // Negative: approaching. NaN is not approaching.
            let rate = prox.normal.dot(relative);
            if rate.is_nan() || rate >= -a {
                report.not_approaching += 1;
                return true;
            }
        }
        let near = reach.near_along_surface(mesh, &c.pair, options.surface_reach_factor * d);
        report.same_sheet += usize::from(near);
        near
    };
    // Splits made for this pair, to undo if its snap does not happen.
    let mut splits: Vec<(VertexId, SplitRecord)> = Vec::new();
    let sides = match c.pair {
        Pair::VertexTriangle(v, t) => {
            if !mesh.is_vertex_alive(v) || !mesh.is_triangle_alive(t) || mesh.tri(t).contains(&v) {
                report.refused += 1;
                return Ok(());
            }
            let prox = proximity_vertex_triangle(mesh.position(v), mesh.tri_positions(t));
            let [a, b, e] = mesh.tri(t);
            if prox.distance >= d || skip(mesh, attrs, &prox, [v, a, b, e], report) {
                return Ok(());
            }
            let bary = [-prox.weights[1], -prox.weights[2], -prox.weights[3]];
            let plan = plan_on_triangle(mesh, t, bary, d);
            if would_share_an_edge(mesh, Counterpart::Existing(v), plan) {
                report.refused += 1;
                return Ok(());
            }
            make(mesh, attrs, guard, plan, &mut splits, report)?.map(|w| (v, w))
        }
        Pair::EdgeEdge([a, b], [p, q]) => {
            let live = [a, b, p, q].iter().all(|&v| mesh.is_vertex_alive(v))
                && mesh.edge_triangles(a, b).next().is_some()
                && mesh.edge_triangles(p, q).next().is_some();
            if !live {
                report.refused += 1;
                return Ok(());
            }
            let x = [a, b, p, q].map(|v| mesh.position(v));
            let prox = proximity_edge_edge(x[0], x[1], x[2], x[3]);
            if prox.distance >= d || skip(mesh, attrs, &prox, [a, b, p, q], report) {
                return Ok(());
            }
            let (s, u) = (prox.weights[1], -prox.weights[3]);
            let plans = [
                plan_on_edge(mesh, a, b, s, d),
                plan_on_edge(mesh, p, q, u, d),
            ];
            if would_share_an_edge(mesh, plans[0], plans[1]) {
                report.refused += 1;
                return Ok(());
            }
            let first = make(mesh, attrs, guard, plans[0], &mut splits, report)?;
            let second = match first {
                Some(_) => make(mesh, attrs, guard, plans[1], &mut splits, report)?,
                None => None,
            };
            first.zip(second)
        }
    };
    let snapped = match sides {
        Some((keep, other)) => {
            match snap_vertices(mesh, attrs, guard, keep, other, &options.snap) {
                Ok(v) => {
                    report.snaps += 1;
                    if contact.len() <= v.idx() {
                        contact.resize(v.idx() + 1, false);
                    }
                    contact[v.idx()] = true;
                    snapped.push(v);
                    true
                }
                Err(e) => {
                    count_failure(e, report)?;
                    false
                }
            }
        }
        None => false,
    };
    if !snapped {
        // The splits only prepared this snap: without it they would leave a vertex on one
        // surface within the merge distance of the other — possibly a rounding error away
        // from the vertex it was meant to join — for the next step's collision handling
        // to start from. Undo them, latest first.
        for (w, record) in splits.iter().rev() {
            undo_split(mesh, attrs, guard, *w, record)?;
            report.undone_splits += 1;
        }
    }
    Ok(())
}

/// Where one side of a pair gets its vertex to snap: an existing vertex, or one made by
/// splitting an edge or a triangle at the closest point.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Counterpart {
    Existing(VertexId),
    /// Edge `{a, b}` split at parameter `s` from `a`.
    OnEdge(VertexId, VertexId, f64),
    /// Triangle trisected at barycentric coordinates.
    OnTriangle(TriId, [f64; 3]),
}

/// The counterpart at the closest point of triangle `t` (barycentric `bary`): a corner
/// within `d`, else a split of an edge within `d`, else a trisection.
fn plan_on_triangle(mesh: &LabeledMesh, t: TriId, bary: [f64; 3], d: f64) -> Counterpart {
    let verts = mesh.tri(t);
    let x = mesh.tri_positions(t);
    let point = x[0] * bary[0] + x[1] * bary[1] + x[2] * bary[2];
    // Nearest corner within d.
    if let Some(k) = (0..3)
        .filter(|&k| (x[k] - point).length() <= d)
        .min_by(|&i, &j| (x[i] - point).length().total_cmp(&(x[j] - point).length()))
    {
        return Counterpart::Existing(verts[k]);
    }
    // Nearest edge within d: split it at the projection of the point.
    let on_edge = |i: usize, j: usize| {
        let e = x[j] - x[i];
        let s = ((point - x[i]).dot(e) / e.length_squared()).clamp(0.0, 1.0);
        (s, (x[i] + e * s - point).length())
    };
    if let Some((i, j, s, _)) = [(0, 1), (1, 2), (2, 0)]
        .into_iter()
        .map(|(i, j)| {
            let (s, dist) = on_edge(i, j);
            (i, j, s, dist)
        })
        .filter(|e| e.3 <= d)
        .min_by(|a, b| a.3.total_cmp(&b.3))
    {
        return Counterpart::OnEdge(verts[i], verts[j], s);
    }
    Counterpart::OnTriangle(t, bary)
}

/// The counterpart at parameter `s` of edge `{a, b}`: an end within `d`, else a split.
fn plan_on_edge(mesh: &LabeledMesh, a: VertexId, b: VertexId, s: f64, d: f64) -> Counterpart {
    let len = (mesh.position(b) - mesh.position(a)).length();
    if s * len <= d {
        Counterpart::Existing(a)
    } else if (1.0 - s) * len <= d {
        Counterpart::Existing(b)
    } else {
        Counterpart::OnEdge(a, b, s)
    }
}

/// True when the two counterparts would be one vertex or the ends of one edge, so the
/// snap would be refused ([`mesh_core::remesh::SnapRefusal::Adjacent`]: that is an edge
/// collapse). Asked before any split is made: a split vertex is joined to the ends of its
/// edge and to the third vertex of every triangle on it, a trisection's to the corners.
/// Most such pairs are a sliver's own edge against its apex — one sheet, not two — and
/// splitting, refusing and undoing each of them (three guarded edits) was most of the
/// merge's work on crowded contacts.
fn would_share_an_edge(mesh: &LabeledMesh, x: Counterpart, y: Counterpart) -> bool {
    use Counterpart::*;
    let joined = |u: VertexId, w: VertexId| {
        u == w || mesh.vertex_triangles(u).any(|t| mesh.tri(t).contains(&w))
    };
    let on_edge_triangles = |u: VertexId, a: VertexId, b: VertexId| {
        u == a || u == b || mesh.edge_triangles(a, b).any(|t| mesh.tri(t).contains(&u))
    };
    match (x, y) {
        (Existing(u), Existing(w)) => joined(u, w),
        (Existing(u), OnEdge(a, b, _)) | (OnEdge(a, b, _), Existing(u)) => {
            on_edge_triangles(u, a, b)
        }
        (Existing(u), OnTriangle(t, _)) | (OnTriangle(t, _), Existing(u)) => {
            mesh.tri(t).contains(&u)
        }
        // Two new vertices are joined only if they split one edge.
        (OnEdge(a, b, _), OnEdge(p, q, _)) => [a, b] == [p, q] || [a, b] == [q, p],
        (OnEdge(..) | OnTriangle(..), OnEdge(..) | OnTriangle(..)) => false,
    }
}

/// Makes the planned counterpart: the vertex itself, or the split (recorded in `splits`).
/// `None` when a split was refused or vetoed.
fn make(
    mesh: &mut LabeledMesh,
    attrs: &mut VertexAttributes,
    guard: &mut dyn EditGuard,
    plan: Counterpart,
    splits: &mut Vec<(VertexId, SplitRecord)>,
    report: &mut MergeReport,
) -> Result<Option<VertexId>, MergeError> {
    match plan {
        Counterpart::Existing(v) => Ok(Some(v)),
        Counterpart::OnEdge(a, b, s) => split_edge(mesh, attrs, guard, a, b, s, splits, report),
        Counterpart::OnTriangle(t, bary) => {
            let record = SplitRecord::triangle(mesh, t);
            let split = split_triangle_at(mesh, attrs, guard, t, bary);
            keep_split(split, record, |r| &mut r.face_splits, splits, report)
        }
    }
}

/// Splits edge `{a, b}` at `s`, recording the split in `splits`.
#[allow(clippy::too_many_arguments)]
fn split_edge(
    mesh: &mut LabeledMesh,
    attrs: &mut VertexAttributes,
    guard: &mut dyn EditGuard,
    a: VertexId,
    b: VertexId,
    s: f64,
    splits: &mut Vec<(VertexId, SplitRecord)>,
    report: &mut MergeReport,
) -> Result<Option<VertexId>, MergeError> {
    let record = SplitRecord::edge(mesh, a, b);
    let split = split_edge_at(mesh, attrs, guard, a, b, s);
    keep_split(split, record, |r| &mut r.edge_splits, splits, report)
}

/// A split's outcome: on success it is counted and recorded in `splits` (for the undo if
/// its snap does not happen) and its vertex returned; a refusal or veto is counted and
/// gives `None`.
fn keep_split(
    split: Result<VertexId, EditError>,
    record: SplitRecord,
    counter: fn(&mut MergeReport) -> &mut usize,
    splits: &mut Vec<(VertexId, SplitRecord)>,
    report: &mut MergeReport,
) -> Result<Option<VertexId>, MergeError> {
    match split {
        Ok(v) => {
            *counter(report) += 1;
            splits.push((v, record));
            Ok(Some(v))
        }
        Err(e) => {
            count_failure(SnapError::Edit(e), report)?;
            Ok(None)
        }
    }
}

/// Counts a refused or vetoed step; a capacity error stops the merge.
fn count_failure(e: SnapError, report: &mut MergeReport) -> Result<(), MergeError> {
    match e {
        SnapError::Edit(EditError::Vetoed(_)) => report.vetoed += 1,
        SnapError::Edit(EditError::Mesh(m)) => return Err(m.into()),
        SnapError::Edit(EditError::Malformed(_) | EditError::Structure(_))
        | SnapError::Refused(_) => report.refused += 1,
    }
    Ok(())
}

fn add_degenerate(sum: &mut DegenerateReport, r: &DegenerateReport) {
    sum.collapsed_removed += r.collapsed_removed;
    sum.pairs_relabelled += r.pairs_relabelled;
    sum.pairs_removed += r.pairs_removed;
    sum.vertices_removed += r.vertices_removed;
    sum.vetoed += r.vetoed;
    sum.unresolved = r.unresolved;
}

/// Number of bounded region shells per label.
fn bounded_shells(mesh: &LabeledMesh) -> BTreeMap<Label, usize> {
    let mut count = BTreeMap::new();
    for s in mesh.regions().bounded() {
        *count.entry(s.label).or_insert(0) += 1;
    }
    count
}

/// The unordered label pairs of the mesh's triangles.
fn interfaces(mesh: &LabeledMesh) -> BTreeSet<[Label; 2]> {
    mesh.triangles()
        .map(|t| {
            let [a, b] = mesh.labels(t);
            if a < b { [a, b] } else { [b, a] }
        })
        .collect()
}
