//! Edit guards: who may veto an edit before it is committed.
//!
//! The shared remeshing operations never decide on their own whether an edit is safe; they
//! ask the guard the backend passes in. The grid tracker passes a cheap guard (its output is
//! checked per region anyway); the collision tracker passes one that sweeps the
//! pseudo-motion with exact CCD. [`StaticIntersectionGuard`] ships here: it rejects edits
//! whose end state would make a new or moved triangle intersect the rest of the mesh.

use glam::DVec3;
use rayon::prelude::*;

use crate::broadphase::Aabb;
use crate::ids::{TriId, VertexId};
use crate::mesh::LabeledMesh;
use crate::predicates;
use crate::stamps::Stamps;
use crate::triangle_index::TriangleIndex;

use super::edit::{Applied, Edit, VertexRef};

/// Why a guard refused an edit: which check failed and, where the check can name them, the
/// elements involved. [`Veto::kind`] is a short fixed name, for counting vetoes per kind
/// ([`super::ImproveReport::vetoes`]) without formatting a message for each.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum Veto {
    /// A triangle the edit adds or moves would intersect triangle `other` of the mesh.
    #[error("end state intersects triangle {other}")]
    EndStateIntersects {
        /// The mesh's triangle that would be hit.
        other: TriId,
    },
    /// Two triangles of the edit's own end state would intersect.
    #[error("end state intersects itself")]
    EndStateSelfIntersects,
    /// The pseudo-motion (El Topo §3.5) collides: a vertex hits a triangle.
    #[error("pseudo-motion collides: a vertex hits a triangle")]
    SweepVertexTriangle,
    /// The pseudo-motion collides: two edges hit.
    #[error("pseudo-motion collides: two edges hit")]
    SweepEdgeEdge,
    /// A vertex lies in the volume a moving triangle sweeps (a small component tunnelling).
    #[error("a vertex lies in the volume a triangle sweeps")]
    SweptVolume,
    /// A vertex lies in the tetrahedron a flip sweeps.
    #[error("a vertex lies in the tetrahedron a flip sweeps")]
    FlipVolume,
    /// The edit brings non-adjacent elements closer than the guard's minimum distance.
    #[error("edit brings elements closer than the minimum distance")]
    TooClose,
    /// The edit removes or deforms triangle `tri`, outside the region the guard lets change
    /// (the grid tracker's local improvement).
    #[error("edit changes triangle {tri}, outside the region that may change")]
    OutsideRegion {
        /// The first such triangle.
        tri: TriId,
    },
    /// The time budget is spent.
    #[error("the time budget is spent")]
    TimeBudget,
    /// A guard's own reason (guards written outside this workspace, tests).
    #[error("{0}")]
    Other(&'static str),
}

impl Veto {
    /// A short fixed name of the check that failed.
    pub fn kind(&self) -> &'static str {
        match self {
            Veto::EndStateIntersects { .. } => "end state intersects the mesh",
            Veto::EndStateSelfIntersects => "end state intersects itself",
            Veto::SweepVertexTriangle => "sweep: vertex-triangle",
            Veto::SweepEdgeEdge => "sweep: edge-edge",
            Veto::SweptVolume => "swept volume",
            Veto::FlipVolume => "flip volume",
            Veto::TooClose => "too close",
            Veto::OutsideRegion { .. } => "outside the region",
            Veto::TimeBudget => "time budget",
            Veto::Other(why) => why,
        }
    }
}

/// Consulted before each edit; `Err(veto)` refuses it.
///
/// A guard follows the mesh through [`super::apply_edit`], which calls
/// [`EditGuard::committed`] after every edit it commits, so guards that index the mesh can
/// stay current cheaply.
pub trait EditGuard {
    /// Decides on `edit`, seen against the mesh *before* it is applied.
    fn check(&mut self, mesh: &LabeledMesh, edit: &Edit) -> Result<(), Veto>;

    /// Told after `edit` was committed (`mesh` is the mesh after it).
    fn committed(&mut self, _mesh: &LabeledMesh, _edit: &Edit, _applied: &Applied) {}

    /// A cheap necessary condition of [`EditGuard::check`] for every edit that moves or
    /// removes vertex `v`: `Err` means each such edit would be vetoed, for this reason.
    /// Default: no objection.
    ///
    /// Why: the operations ask it before they build and measure a candidate edit, so a
    /// guard that fences part of the mesh off (the grid tracker's local improvement, whose
    /// border vertices are in every work list) costs a few lookups per fenced candidate
    /// instead of a whole evaluation. Measured on `fix` of six bunnies: 34k of the guard's
    /// 34.3k vetoes were of that kind.
    fn check_vertex(&mut self, _mesh: &LabeledMesh, _v: VertexId) -> Result<(), Veto> {
        Ok(())
    }

    /// A cheap necessary condition of [`EditGuard::check`] for `edit` itself: `Err` means
    /// `check` would veto it, for this reason. [`super::apply_edit`] asks it before the
    /// edit's structural check and `check` after it. Default: no objection.
    ///
    /// Why: the structural check costs a few radial sorts and a small-component flood per
    /// edit, and a fence refuses its edits with a few lookups. On `fix` of six notched
    /// spheres (1.08M triangles), 434k of 1.1M collapse attempts were refused by a block's
    /// fence, each after a full structural check; asking first made the run 1.2 % faster.
    fn precheck(&mut self, _mesh: &LabeledMesh, _edit: &Edit) -> Result<(), Veto> {
        Ok(())
    }

    /// Decides on a *batch*: an edit that only moves vertices, no two of which share a
    /// triangle (batched smoothing). `None`: the whole batch may be committed, exactly as
    /// if [`EditGuard::check`] had passed it. `Some(blamed)`: the indices into
    /// `edit.moves` (increasing, at least one) to leave out; the caller asks again about
    /// the rest before committing anything, and retries the blamed moves one at a time.
    ///
    /// Why: one check per batch instead of one per move is what makes guarded smoothing
    /// cheap, and blaming only the offenders keeps one blocked vertex from freezing the
    /// pass. The default bisects with `check` (El Topo's batch pseudo-motion for a CCD
    /// guard); guards that can see every offender in one pass override it.
    fn offending_moves(&mut self, mesh: &LabeledMesh, edit: &Edit) -> Option<Vec<usize>> {
        if self.check(mesh, edit).is_ok() {
            return None;
        }
        let mut blamed = Vec::new();
        bisect_moves(self, mesh, edit, 0, edit.moves.len(), &mut blamed);
        Some(blamed)
    }
}

/// Blames moves of the failing range `lo..hi` of `edit.moves` by asking `guard.check`
/// about halves: a failing single move, or recursively the failing halves; when both
/// halves pass alone (only their combination fails), the upper half, so that the caller
/// always makes progress. The default of [`EditGuard::offending_moves`], for guards that
/// override it only in part.
pub fn bisect_moves<G: EditGuard + ?Sized>(
    guard: &mut G,
    mesh: &LabeledMesh,
    edit: &Edit,
    lo: usize,
    hi: usize,
    blamed: &mut Vec<usize>,
) {
    if hi - lo <= 1 {
        blamed.extend(lo..hi);
        return;
    }
    let mid = lo + (hi - lo) / 2;
    let mut failed = false;
    for (a, b) in [(lo, mid), (mid, hi)] {
        let part = Edit {
            moves: edit.moves[a..b].to_vec(),
            ..Edit::default()
        };
        if guard.check(mesh, &part).is_err() {
            failed = true;
            bisect_moves(guard, mesh, edit, a, b, blamed);
        }
    }
    if !failed {
        blamed.extend(mid..hi);
    }
}

/// True when `edit` is a batch in the sense of [`EditGuard::offending_moves`]: moves only,
/// no triangle with two moved vertices.
///
/// `claimed` must be all false on entry (it grows to the mesh as needed); on return it is
/// true at every triangle of a moved vertex, whatever the answer, until [`release`] clears
/// exactly those entries. Why not clear it here: a smoothing pass asks once per batch of a
/// few hundred moves, and clearing a flag per triangle slot each time made every batch
/// cost as much as the whole mesh.
pub(crate) fn is_batch(mesh: &LabeledMesh, edit: &Edit, claimed: &mut Vec<bool>) -> bool {
    if !edit.only_moves() {
        return false;
    }
    if claimed.len() < mesh.triangle_capacity() {
        claimed.resize(mesh.triangle_capacity(), false);
    }
    let mut batch = true;
    for m in &edit.moves {
        for t in mesh.vertex_triangles(m.vertex) {
            batch &= !std::mem::replace(&mut claimed[t.idx()], true);
        }
    }
    batch
}

/// Clears the entries [`is_batch`] set for `edit` (the mesh unchanged since).
pub(crate) fn release(mesh: &LabeledMesh, edit: &Edit, claimed: &mut [bool]) {
    for m in &edit.moves {
        for t in mesh.vertex_triangles(m.vertex) {
            if let Some(c) = claimed.get_mut(t.idx()) {
                *c = false;
            }
        }
    }
}

/// Allows everything.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoGuard;

impl EditGuard for NoGuard {
    fn check(&mut self, _mesh: &LabeledMesh, _edit: &Edit) -> Result<(), Veto> {
        Ok(())
    }
}

/// A triangle of an edit's end state (or a candidate): vertex keys to recognise shared
/// vertices (new vertices get keys past the mesh's ids), positions and their box.
#[derive(Clone, Copy, Debug)]
struct Keyed {
    keys: [u32; 3],
    points: [DVec3; 3],
    bounds: Aabb,
}

impl Keyed {
    #[inline]
    fn new(keys: [u32; 3], points: [DVec3; 3]) -> Keyed {
        Keyed {
            keys,
            points,
            bounds: Aabb::from_points(&points),
        }
    }
}

/// Rejects an edit if, in its end state, a triangle it adds or moves intersects (exactly)
/// any other triangle, except at shared vertices and edges. It checks the end state, not
/// the sweep: on an intersection-free mesh with small edits (the remeshing case) that keeps
/// the mesh intersection-free; the collision backend adds the sweep test.
///
/// Candidates come from a [`TriangleIndex`] (a BVH over slack-grown boxes plus a grid of
/// the triangles that escaped them), which the guard keeps current.
///
/// One check gathers the candidates of the whole edit at once (one query with the box
/// around its changed triangles), each candidate once, and tests a candidate exactly only
/// against the changed triangles whose boxes it overlaps. So a check costs O(log n) plus
/// the edit's neighbourhood. The guard learns of changes through [`EditGuard::committed`]:
/// if the mesh is changed any other way, call [`StaticIntersectionGuard::reset`].
#[derive(Debug, Default)]
pub struct StaticIntersectionGuard {
    /// The mesh's triangles, kept current through [`EditGuard::committed`].
    index: TriangleIndex,
    /// Per triangle slot: seen in this check (as a candidate, or as a triangle the edit
    /// removes or moves), so each is looked at once per check.
    seen: Stamps,
    /// Scratch buffers, kept to avoid allocation per check.
    moved: Vec<TriId>,
    changed: Vec<Keyed>,
    candidates: Vec<TriId>,
    /// Per triangle slot: moved by the batch being checked ([`is_batch`]).
    claimed: Vec<bool>,
}

/// Edits with more changed triangles than this query the index once per triangle instead
/// of once for the box around them all (which, for a large or spread-out edit, could hold
/// far more triangles than the separate boxes).
const MAX_UNION_QUERY: usize = 32;

impl StaticIntersectionGuard {
    /// A guard with no index yet (built on first use).
    pub fn new() -> Self {
        Self::default()
    }

    /// Forgets the index, e.g. after the mesh was changed outside `apply_edit`.
    pub fn reset(&mut self) {
        self.index.reset();
    }

    /// Brings the triangle index up to date, as a check does first: for a caller that
    /// skips the check but queries the index.
    pub fn refresh_index(&mut self, mesh: &LabeledMesh) {
        self.index.refresh(mesh);
    }

    /// The guard's triangle index, current after the last check and every commit since:
    /// the collision guard sweeps against it instead of keeping an index of its own.
    pub fn index(&self) -> &TriangleIndex {
        &self.index
    }

    /// Starts a check: every triangle unseen.
    fn start_check(&mut self, mesh: &LabeledMesh) {
        self.seen.next_pass(mesh.triangle_capacity());
    }

    /// Marks `t` seen in this check; false if it already was.
    #[inline]
    fn first_sight(&mut self, t: TriId) -> bool {
        self.seen.first_sight(t.idx())
    }

    /// Collects, once each, the live triangles (other than those the edit removes or
    /// moves, which are already marked seen) whose indexed or escaped box meets `b`.
    fn gather(&mut self, mesh: &LabeledMesh, b: &Aabb) {
        let Self {
            index,
            seen,
            candidates,
            ..
        } = self;
        let take = |t: TriId| {
            if seen.first_sight(t.idx()) && mesh.is_triangle_alive(t) {
                candidates.push(t);
            }
        };
        index.query(b, take);
    }
}

/// Whether `edit` leaves a subset of the current geometry: it moves and creates no
/// vertex, and every triangle it adds has the corners of one it removes (degenerate
/// removal: a coincident pair kept as one triangle with the two outer labels). Every
/// pair of triangles of its end state is then a pair of the current state at the same
/// positions, so on a mesh this guard has kept intersection-free it creates no
/// intersection, and the exact tests are skipped. Measured on the collision backend's
/// merge (300 spheres packing), about 2000 such edits per round, each testing its
/// triangle against a dense wall neighbourhood.
fn reuses_existing_triangles(mesh: &LabeledMesh, edit: &Edit) -> bool {
    let sorted = |mut c: [VertexId; 3]| {
        c.sort_unstable();
        c
    };
    edit.moves.is_empty()
        && edit.new_vertices.is_empty()
        && edit.add_tris.iter().all(|(verts, _)| {
            let [VertexRef::Old(a), VertexRef::Old(b), VertexRef::Old(c)] = *verts else {
                return false;
            };
            let corners = sorted([a, b, c]);
            edit.remove_tris
                .iter()
                .any(|&t| sorted(mesh.tri(t)) == corners)
        })
}

impl EditGuard for StaticIntersectionGuard {
    fn check(&mut self, mesh: &LabeledMesh, edit: &Edit) -> Result<(), Veto> {
        // The index first even when the answer is known: the collision guard sweeps
        // against it after this check.
        self.index.refresh(mesh);
        if reuses_existing_triangles(mesh, edit) {
            return Ok(());
        }
        self.start_check(mesh);
        // The edit's own removed and moved triangles are never candidates.
        for &t in &edit.remove_tris {
            self.first_sight(t);
        }
        self.moved.clear();
        for m in &edit.moves {
            for t in mesh.vertex_triangles(m.vertex) {
                if self.first_sight(t) {
                    self.moved.push(t);
                }
            }
        }
        let base = mesh.vertex_capacity() as u32;
        let key = |r: VertexRef| match r {
            VertexRef::Old(v) => v.raw(),
            VertexRef::New(i) => base.saturating_add(i),
        };
        self.changed.clear();
        for (verts, _) in &edit.add_tris {
            self.changed.push(Keyed::new(
                verts.map(key),
                verts.map(|r| edit.end_position(mesh, r)),
            ));
        }
        for &t in &self.moved {
            let tri = mesh.tri(t);
            self.changed.push(Keyed::new(
                tri.map(|v| v.raw()),
                tri.map(|v| edit.end_position(mesh, VertexRef::Old(v))),
            ));
        }
        let all = self
            .changed
            .iter()
            .fold(Aabb::EMPTY, |u, a| u.union(a.bounds));
        self.candidates.clear();
        if self.changed.len() <= MAX_UNION_QUERY {
            self.gather(mesh, &all);
        } else {
            for i in 0..self.changed.len() {
                let b = self.changed[i].bounds;
                self.gather(mesh, &b);
            }
        }
        for &t in &self.candidates {
            let tri = mesh.tri(t);
            let c = Keyed::new(tri.map(|v| v.raw()), tri.map(|v| mesh.position(v)));
            if !c.bounds.overlaps(&all) {
                continue;
            }
            for a in &self.changed {
                if a.bounds.overlaps(&c.bounds) && intersect_keyed(a, &c) {
                    return Err(Veto::EndStateIntersects { other: t });
                }
            }
        }
        for (i, a) in self.changed.iter().enumerate() {
            for b in &self.changed[i + 1..] {
                if a.bounds.overlaps(&b.bounds) && intersect_keyed(a, b) {
                    return Err(Veto::EndStateSelfIntersects);
                }
            }
        }
        Ok(())
    }

    /// One pass over the whole batch, in parallel: every moved triangle's end state
    /// against the unmoved triangles near it (one index query each), and the moved
    /// triangles against each other (sweep and prune on x); every move with an
    /// intersecting triangle is blamed.
    fn offending_moves(&mut self, mesh: &LabeledMesh, edit: &Edit) -> Option<Vec<usize>> {
        let mut claimed = std::mem::take(&mut self.claimed);
        let batch = is_batch(mesh, edit, &mut claimed);
        if !batch {
            release(mesh, edit, &mut claimed);
            self.claimed = claimed;
            return match self.check(mesh, edit) {
                Ok(()) => None,
                Err(_) => {
                    let mut blamed = Vec::new();
                    bisect_moves(self, mesh, edit, 0, edit.moves.len(), &mut blamed);
                    Some(blamed)
                }
            };
        }
        self.index.refresh(mesh);
        // The moved triangles at their end positions (only their own move changes them),
        // grouped by move: `spans[i]..spans[i + 1]`.
        let mut changed: Vec<(usize, Keyed)> = Vec::new();
        let mut spans = Vec::with_capacity(edit.moves.len() + 1);
        for (i, m) in edit.moves.iter().enumerate() {
            spans.push(changed.len());
            changed.extend(mesh.vertex_triangles(m.vertex).map(|t| {
                let tri = mesh.tri(t);
                let points = tri.map(|v| {
                    if v == m.vertex {
                        m.end
                    } else {
                        mesh.position(v)
                    }
                });
                (i, Keyed::new(tri.map(|v| v.raw()), points))
            }));
        }
        spans.push(changed.len());
        // The moved triangles' end boxes sorted by their lower x, for the moved-against-
        // moved tests (the index holds only current boxes): a query scans the slab of
        // boxes that can reach it in x, each box once.
        let mut by_x: Vec<u32> = (0..changed.len() as u32).collect();
        by_x.sort_unstable_by(|&a, &b| {
            let (a, b) = (&changed[a as usize].1.bounds, &changed[b as usize].1.bounds);
            a.min.x.total_cmp(&b.min.x)
        });
        let widest = changed
            .iter()
            .map(|(_, a)| a.bounds.max.x - a.bounds.min.x)
            .fold(0.0, f64::max);
        let index = &self.index;
        let moved: &[bool] = &claimed;
        let (changed, by_x) = (&changed, &by_x[..]);
        // Per move: one index query and one grid query with the box around its
        // triangles, the candidates deduplicated (the grid files a box under every cell
        // it spans), then the exact tests.
        let blamed: Vec<[usize; 2]> = (0..edit.moves.len())
            .into_par_iter()
            .with_min_len(16)
            .map_init(Vec::new, |found: &mut Vec<TriId>, i| {
                let mine = &changed[spans[i]..spans[i + 1]];
                let all = mine.iter().fold(Aabb::EMPTY, |u, (_, a)| u.union(a.bounds));
                let hits = |c: &Keyed| {
                    c.bounds.overlaps(&all)
                        && mine
                            .iter()
                            .any(|(_, a)| a.bounds.overlaps(&c.bounds) && intersect_keyed(a, c))
                };
                found.clear();
                let mut unmoved = |t: TriId| {
                    if !moved.get(t.idx()).copied().unwrap_or(true) {
                        found.push(t);
                    }
                };
                index.query(&all, &mut unmoved);
                found.sort_unstable();
                found.dedup();
                let unmoved_hit = found.iter().any(|&t| {
                    mesh.is_triangle_alive(t) && {
                        let tri = mesh.tri(t);
                        hits(&Keyed::new(
                            tri.map(|v| v.raw()),
                            tri.map(|v| mesh.position(v)),
                        ))
                    }
                });
                if unmoved_hit {
                    return Some([i, i]);
                }
                // Another move's triangles at their end positions, each pair tested from
                // its lower move.
                let from = by_x
                    .partition_point(|&k| changed[k as usize].1.bounds.min.x < all.min.x - widest);
                by_x[from..]
                    .iter()
                    .take_while(|&&k| changed[k as usize].1.bounds.min.x <= all.max.x)
                    .find_map(|&k| {
                        let (j, c) = &changed[k as usize];
                        (*j > i && hits(c)).then_some([i, *j])
                    })
            })
            .flatten()
            .collect();
        let mut blamed: Vec<usize> = blamed.into_iter().flatten().collect();
        release(mesh, edit, &mut claimed);
        self.claimed = claimed;
        blamed.sort_unstable();
        blamed.dedup();
        (!blamed.is_empty()).then_some(blamed)
    }

    fn committed(&mut self, mesh: &LabeledMesh, edit: &Edit, applied: &Applied) {
        if !self.index.is_built() {
            return;
        }
        for &t in &applied.triangles {
            self.index.track(mesh, t);
        }
        for m in &edit.moves {
            for t in mesh.vertex_triangles(m.vertex) {
                self.index.track(mesh, t);
            }
        }
    }
}

/// Exact intersection of two keyed triangles, excluding contact at shared vertices and
/// edges.
#[inline]
fn intersect_keyed(a: &Keyed, b: &Keyed) -> bool {
    predicates::intersect_keyed_triangle_triangle((a.keys, &a.points), (b.keys, &b.points))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generators::icosphere;
    use crate::ids::{Label, VertexId};
    use crate::remesh::{EditError, VertexAttributes, VertexMove, apply_edit};
    use crate::validate::{ValidateOptions, validate};

    fn sphere() -> LabeledMesh {
        icosphere(2, DVec3::ZERO, 1.0, [Label::OUTSIDE, Label::new(1)]).unwrap()
    }

    fn move_edit(v: VertexId, to: DVec3) -> Edit {
        Edit {
            moves: vec![VertexMove {
                vertex: v,
                end: to,
                blend: None,
            }],
            ..Edit::default()
        }
    }

    /// A batch check leaves no claim behind, whether the moves formed a batch or not (two
    /// neighbours), so the next batch starts from a clean slate without clearing the
    /// whole mesh's flags.
    #[test]
    fn batch_checks_release_their_claims() {
        let mesh = sphere();
        let mut guard = StaticIntersectionGuard::new();
        let far = |v: u32| {
            let p = mesh.position(VertexId::new(v));
            VertexMove {
                vertex: VertexId::new(v),
                end: p * 1.001,
                blend: None,
            }
        };
        let a = VertexId::new(0);
        let t0 = mesh.vertex_triangles(a).next().expect("a triangle at 0");
        let b = *mesh.tri(t0).iter().find(|&&v| v != a).expect("a neighbour");
        let apart = (1..mesh.num_vertices() as u32)
            .find(|&w| {
                let w = VertexId::new(w);
                !mesh
                    .vertex_triangles(a)
                    .any(|t| mesh.vertex_triangles(w).any(|u| u == t))
            })
            .expect("a vertex sharing no triangle with 0");
        for moves in [vec![far(0), far(apart)], vec![far(0), far(b.raw())]] {
            let edit = Edit {
                moves,
                ..Edit::default()
            };
            assert_eq!(guard.offending_moves(&mesh, &edit), None);
            assert!(guard.claimed.iter().all(|&c| !c), "claims left set");
        }
    }

    #[test]
    fn vetoes_a_vertex_pushed_through_the_far_side() {
        let mesh = sphere();
        let mut guard = StaticIntersectionGuard::new();
        let v = VertexId::new(0);
        let p = mesh.position(v);
        assert!(guard.check(&mesh, &move_edit(v, p * 1.01)).is_ok());
        // Through the centre and out of the other side: its fan crosses the far triangles,
        // and the veto names one of them.
        match guard.check(&mesh, &move_edit(v, -p * 1.5)) {
            Err(Veto::EndStateIntersects { other }) => {
                assert!(mesh.is_triangle_alive(other));
                assert!(!mesh.tri(other).contains(&v), "a far triangle, not v's own");
            }
            r => panic!("{r:?}"),
        }
    }

    /// An edit that re-adds a triangle's own corners (degenerate removal's relabelling)
    /// is passed without exact tests, even where that triangle already crosses another
    /// (it adds no geometry); change a corner, or move one, and it is checked again.
    #[test]
    fn re_adding_a_triangles_own_corners_is_passed_and_nothing_else_is() {
        // Two overlapping spheres: some triangles of the first cross the second.
        let (mut p, mut tris, mut labels) = sphere().to_raw();
        let n = p.len() as u32;
        let (q, qt, ql) = sphere().to_raw();
        p.extend(q.iter().map(|&x| x + DVec3::new(0.5, 0.0, 0.0)));
        tris.extend(qt.iter().map(|t| t.map(|v| v + n)));
        labels.extend(ql.iter().map(|_| [0, 2]));
        let mesh = LabeledMesh::from_raw(p, &tris, &labels).unwrap();
        let mut guard = StaticIntersectionGuard::new();
        let m = qt.len() as u32;
        let crossing = (0..m)
            .map(TriId::new)
            .find(|&t| {
                (m..2 * m).any(|u| crate::validate::triangles_intersect(&mesh, t, TriId::new(u)))
            })
            .expect("a triangle of the first sphere crossing the second");
        let [a, b, c] = mesh.tri(crossing);
        let readd = |corners: [VertexId; 3]| Edit {
            remove_tris: vec![crossing],
            add_tris: vec![(corners.map(VertexRef::Old), [Label::new(3), Label::new(1)])],
            ..Edit::default()
        };
        assert_eq!(guard.check(&mesh, &readd([b, c, a])), Ok(()));
        // The same edit but with a corner moved is an ordinary edit: checked, and vetoed.
        let mut moved = readd([b, c, a]);
        moved.moves.push(VertexMove {
            vertex: a,
            end: mesh.position(a) * 1.0001,
            blend: None,
        });
        assert!(matches!(
            guard.check(&mesh, &moved),
            Err(Veto::EndStateIntersects { .. })
        ));
        // Another corner: new geometry, checked (a chord through the sphere crosses it).
        let far = mesh
            .vertices()
            .filter(|v| v.raw() < n)
            .max_by(|&x, &y| {
                let d = |v: VertexId| mesh.position(v).distance(mesh.position(a));
                d(x).total_cmp(&d(y))
            })
            .unwrap();
        assert!(guard.check(&mesh, &readd([a, b, far])).is_err());
    }

    /// After many committed edits (the dirty list, then a rebuild), the guard still agrees
    /// with a full exact validation of the end state.
    #[test]
    fn stays_exact_through_committed_edits() {
        let mut mesh = sphere();
        let mut guard = StaticIntersectionGuard::new();
        let mut attrs = VertexAttributes::none();
        let exact = ValidateOptions {
            intersections: true,
            ..ValidateOptions::default()
        };
        let vertices: Vec<VertexId> = mesh.vertices().collect();
        let mut vetoed = 0;
        for (k, &v) in vertices.iter().cycle().take(600).enumerate() {
            let p = mesh.position(v);
            // Alternate small safe moves and large inward jumps that may cross the surface.
            let to = if k % 7 == 3 {
                -p * 0.9
            } else {
                p * (1.0 + 0.01 * ((k % 5) as f64 - 2.0))
            };
            let edit = move_edit(v, to);
            let mut trial = mesh.clone();
            trial.set_position(v, to);
            trial.relink_around(v);
            let clean = validate(&trial, &exact).is_valid();
            match apply_edit(&mut mesh, &mut attrs, &mut guard, &edit) {
                Ok(_) => assert!(clean, "guard allowed an intersecting end state at step {k}"),
                Err(_) => {
                    assert!(!clean, "guard vetoed a clean end state at step {k}");
                    vetoed += 1;
                }
            }
        }
        assert!(vetoed > 10, "the test must exercise vetoes ({vetoed})");
        assert!(validate(&mesh, &exact).is_valid());
    }

    /// Flips and splits reuse triangle slots and create triangles outside the indexed
    /// boxes; interleaved with large moves, the guard's verdict must still match an exact
    /// validation of the end state, and the mesh must stay intersection-free.
    #[test]
    fn stays_exact_through_flips_splits_and_moves() {
        use crate::remesh::{FlipParams, SplitPlacement, flip_edge, split_edge};
        let mut mesh = sphere();
        let mut guard = StaticIntersectionGuard::new();
        let mut attrs = VertexAttributes::none();
        let exact = ValidateOptions::with_intersections();
        let any_flip = FlipParams {
            min_improvement: -10.0,
            ..FlipParams::default()
        };
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next =
            |n: usize| (crate::remesh::fixtures::lcg(&mut state) >> 33) as usize % n.max(1);
        let (mut flips, mut splits, mut vetoed) = (0, 0, 0);
        for k in 0..240 {
            let tris: Vec<TriId> = mesh.triangles().collect();
            let tri = mesh.tri(tris[next(tris.len())]);
            let (a, b) = (tri[k % 3], tri[(k + 1) % 3]);
            match k % 3 {
                0 => {
                    // A midpoint split covers exactly the old triangles: always allowed.
                    split_edge(
                        &mut mesh,
                        &mut attrs,
                        &mut guard,
                        a,
                        b,
                        SplitPlacement::Midpoint,
                    )
                    .expect("midpoint split");
                    splits += 1;
                }
                1 => {
                    let mut trial = mesh.clone();
                    let unguarded =
                        flip_edge(&mut trial, &mut attrs, &mut NoGuard, a, b, &any_flip);
                    let clean = unguarded.is_ok() && validate(&trial, &exact).is_valid();
                    match flip_edge(&mut mesh, &mut attrs, &mut guard, a, b, &any_flip) {
                        Ok(()) => {
                            assert!(clean, "guard allowed an intersecting flip at step {k}");
                            flips += 1;
                        }
                        Err(crate::remesh::FlipError::Edit(EditError::Vetoed(_))) => {
                            assert!(!clean, "guard vetoed a clean flip at step {k}");
                            vetoed += 1;
                        }
                        Err(_) => assert!(unguarded.is_err(), "refusals agree at step {k}"),
                    }
                }
                _ => {
                    let p = mesh.position(a);
                    let to = if next(4) == 0 { -p * 0.8 } else { p * 1.02 };
                    let mut trial = mesh.clone();
                    trial.set_position(a, to);
                    trial.relink_around(a);
                    let clean = validate(&trial, &exact).is_valid();
                    match apply_edit(&mut mesh, &mut attrs, &mut guard, &move_edit(a, to)) {
                        Ok(_) => assert!(clean, "guard allowed an intersecting move at step {k}"),
                        Err(_) => {
                            assert!(!clean, "guard vetoed a clean move at step {k}");
                            vetoed += 1;
                        }
                    }
                }
            }
        }
        assert!(
            flips > 10 && splits > 10 && vetoed > 10,
            "{flips} {splits} {vetoed}"
        );
        assert!(validate(&mesh, &exact).is_valid());
    }
}
