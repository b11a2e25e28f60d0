//! Structural safety per edit: `check_structure` decides, before anything changes,
//! whether an [`Edit`]'s end state keeps the invariants of layers 1–3 of
//! [`crate::validate`] around everything the edit touches — no boundary edge, no
//! degenerate, duplicate or zero-area triangle, finite positions, and around every touched
//! edge consistently labelled wedges in the radial order the commit will build.
//!
//! Why here and not after the fact: a remeshing move next to a triple curve can fold a
//! sheet past its neighbour and reorder the triangles around the curve's edges, which
//! leaves two wedges of one region with different labels. Checking the whole mesh after
//! improvement and falling back to the unimproved mesh (what the grid backend once did)
//! cost a clone and a linear validation per step and silently threw the step's
//! improvement away; refusing the one edit costs a few radial sorts.
//!
//! The radial order is computed exactly as the commit will compute it
//! ([`crate::connectivity::sort_radially`] on the same positions, with ties broken by the
//! triangle ids the commit will assign, which [`LabeledMesh`] predicts), so the verdict
//! and the committed connectivity always agree.

use glam::DVec3;

use crate::connectivity::{EdgeIncidence, sort_radially};
use crate::corner::Side;
use crate::ids::{CornerId, Label, TriId, VertexId};
use crate::mesh::LabeledMesh;
use crate::predicates::collinear;

#[cfg(test)]
use super::edit::EditError;
use super::edit::{Edit, VertexRef};

/// What an edit's end state would break, and where. Vertex keys are the ids the vertices
/// have (or, for new ones, will have) once the edit is committed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StructureFault {
    /// A new or moved vertex would be at a non-finite position.
    NonFinite {
        /// The vertex.
        vertex: u32,
    },
    /// A new triangle repeats a vertex.
    Degenerate {
        /// Its vertices.
        tri: [u32; 3],
    },
    /// A new or moved triangle would have exactly zero area.
    ZeroArea {
        /// Its vertices.
        tri: [u32; 3],
    },
    /// An edge would be left with a single triangle.
    Boundary {
        /// The edge.
        edge: [u32; 2],
    },
    /// Around an edge, one wedge would be bounded by two different labels.
    Labels {
        /// The edge.
        edge: [u32; 2],
        /// The two labels facing the wedge.
        labels: [Label; 2],
    },
    /// A closed surface component of at most [`SMALL_COMPONENT`] triangles would be turned
    /// inside out: the volume one of its materials encloses changes sign.
    Inverts {
        /// A triangle of the component (an id it has before the edit).
        tri: u32,
        /// The material whose volume changes sign.
        label: Label,
    },
}

/// Components up to this many triangles are checked for inversion by every edit
/// ([`StructureFault::Inverts`]).
///
/// Why: a component a few triangles large (a droplet or bubble smaller than a grid cell,
/// left by a topology change) can be nearly flat, and one collapse that moves its apex
/// through its base by a few degrees of normal change — inside every per-triangle bound —
/// turns it inside out: its labels then say the material outside it is the one it
/// enclosed, and placement (layer 4 of [`crate::validate`]) fails. A component larger
/// than this encloses more than any local edit changes, so it cannot flip.
pub const SMALL_COMPONENT: usize = 64;

impl std::fmt::Display for StructureFault {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::NonFinite { vertex } => write!(f, "vertex {vertex} would not be finite"),
            Self::Degenerate { tri } => write!(f, "new triangle {tri:?} repeats a vertex"),
            Self::ZeroArea { tri } => write!(f, "triangle {tri:?} would have zero area"),
            Self::Boundary { edge } => write!(f, "edge {edge:?} would be a boundary"),
            Self::Labels { edge, labels } => write!(
                f,
                "around edge {edge:?} a wedge would be labelled {} and {}",
                labels[0], labels[1]
            ),
            Self::Inverts { tri, label } => write!(
                f,
                "the small component of t{tri} would be turned inside out (the volume of {label} changes sign)"
            ),
        }
    }
}

/// One end-state triangle on an edge: its vertex keys, labels, and the id it has or will
/// have.
#[derive(Clone, Copy, Debug)]
struct Incident {
    keys: [u32; 3],
    refs: [VertexRef; 3],
    labels: [Label; 2],
    id: TriId,
}

/// Reusable buffers of [`check_structure`].
#[derive(Debug, Default)]
pub(crate) struct StructureScratch {
    new_vertex_ids: Vec<VertexId>,
    new_tri_ids: Vec<TriId>,
    /// The edit's moves sorted by vertex, for end positions.
    moves: Vec<(VertexId, DVec3)>,
    removed: Vec<TriId>,
    edges: Vec<[VertexRef; 2]>,
    incident: Vec<Incident>,
    local_tris: Vec<[VertexId; 3]>,
    local_positions: Vec<DVec3>,
    group: Vec<EdgeIncidence>,
    /// Triangles of the component being flooded ([`small_component`]), in BFS order.
    component: Vec<TriId>,
    /// Per triangle slot, the flood that last reached it ([`Self::epoch`]).
    flooded: Vec<u32>,
    /// The last flood's stamp in `flooded`.
    epoch: u32,
    seeds: Vec<TriId>,
    /// Per triangle slot, `large_epoch` when a flood found its component larger than
    /// [`SMALL_COMPONENT`] inside the current moves-only scope ([`MovesOnly`]).
    large: Vec<u32>,
    /// Bumped on entering and leaving a scope and by every edit that removes or adds
    /// triangles, so a stamp is only ever read back under the connectivity it was made in.
    large_epoch: u32,
    /// The mesh (by address) of the innermost moves-only scope on this thread.
    moves_only: Option<usize>,
}

/// A stretch of work in which the mesh at `mesh` changes only by vertex moves (a
/// smoothing pass), so the triangles' edge-connected components do not change: a move
/// reorders the triangles around a non-manifold edge but keeps them all linked to each
/// other. Inside it, [`check_small_components`] remembers which triangles lie in
/// components too large to invert and does not flood them again (one flood of up to
/// [`SMALL_COMPONENT`] triangles per move was an eighth of a smoothing pass).
///
/// Why keyed by the mesh's address and bumped at both ends: the scratch is per thread,
/// and while a scope waits on a parallel loop, rayon may run another block's job on the
/// same thread; its checks see a different address and neither read nor write the
/// stamps, and its own scope's end invalidates them.
#[derive(Clone, Copy, Debug)]
pub(crate) struct MovesOnly {
    previous: Option<usize>,
}

impl MovesOnly {
    pub(crate) fn enter(s: &mut StructureScratch, mesh: &LabeledMesh) -> Self {
        let previous = s.moves_only.replace(std::ptr::from_ref(mesh) as usize);
        s.bump_large_epoch();
        Self { previous }
    }

    pub(crate) fn leave(self, s: &mut StructureScratch) {
        s.moves_only = self.previous;
        s.bump_large_epoch();
    }
}

impl StructureScratch {
    fn bump_large_epoch(&mut self) {
        if self.large_epoch == u32::MAX {
            self.large.fill(0);
            self.large_epoch = 0;
        }
        self.large_epoch += 1;
    }

    fn key(&self, r: VertexRef) -> u32 {
        match r {
            VertexRef::Old(v) => v.raw(),
            VertexRef::New(i) => self.new_vertex_ids[i as usize].raw(),
        }
    }

    fn end(&self, mesh: &LabeledMesh, edit: &Edit, r: VertexRef) -> DVec3 {
        match r {
            VertexRef::Old(v) => match self.moves.binary_search_by_key(&v, |m| m.0) {
                Ok(i) => self.moves[i].1,
                Err(_) => mesh.position(v),
            },
            VertexRef::New(i) => edit.new_vertices[i as usize].end,
        }
    }
}

/// Checks the end state of a well-formed `edit` ([`Edit::check`]) around everything it
/// touches (see the module doc).
pub(crate) fn check_structure(
    mesh: &LabeledMesh,
    edit: &Edit,
    s: &mut StructureScratch,
) -> Result<(), StructureFault> {
    mesh.next_vertex_ids(edit.new_vertices.len(), &mut s.new_vertex_ids);
    mesh.next_triangle_ids(&edit.remove_tris, edit.add_tris.len(), &mut s.new_tri_ids);
    s.moves.clear();
    s.moves.extend(edit.moves.iter().map(|m| (m.vertex, m.end)));
    s.moves.sort_unstable_by_key(|m| m.0);
    s.removed.clear();
    s.removed.extend_from_slice(&edit.remove_tris);
    s.removed.sort_unstable();
    let removed = |s: &StructureScratch, t: TriId| s.removed.binary_search(&t).is_ok();

    for m in &edit.moves {
        if !m.end.is_finite() {
            return Err(StructureFault::NonFinite {
                vertex: m.vertex.raw(),
            });
        }
    }
    for (i, nv) in edit.new_vertices.iter().enumerate() {
        if !nv.end.is_finite() {
            return Err(StructureFault::NonFinite {
                vertex: s.new_vertex_ids[i].raw(),
            });
        }
    }

    // New triangles: distinct vertices, non-zero area. (Twins are the operations' own
    // business — flips refuse an existing edge, collapses the link condition — and snap
    // merging makes them on purpose for degenerate removal.)
    for (verts, _) in edit.add_tris.iter() {
        let keys = verts.map(|r| s.key(r));
        if keys[0] == keys[1] || keys[1] == keys[2] || keys[0] == keys[2] {
            return Err(StructureFault::Degenerate { tri: keys });
        }
        let p = verts.map(|r| s.end(mesh, edit, r));
        if collinear(p[0], p[1], p[2]) {
            return Err(StructureFault::ZeroArea { tri: keys });
        }
    }

    // Kept triangles at moved vertices: non-zero area at the end positions.
    for m in &edit.moves {
        for t in mesh.vertex_triangles(m.vertex) {
            if removed(s, t) {
                continue;
            }
            let tri = mesh.tri(t);
            let p = tri.map(|v| s.end(mesh, edit, VertexRef::Old(v)));
            if collinear(p[0], p[1], p[2]) {
                return Err(StructureFault::ZeroArea {
                    tri: tri.map(VertexId::raw),
                });
            }
        }
    }

    // The edges whose incidences or radial order the edit changes.
    s.edges.clear();
    for &t in &edit.remove_tris {
        let tri = mesh.tri(t).map(VertexRef::Old);
        s.edges
            .extend((0..3).map(|k| [tri[(k + 1) % 3], tri[(k + 2) % 3]]));
    }
    for (verts, _) in &edit.add_tris {
        s.edges
            .extend((0..3).map(|k| [verts[(k + 1) % 3], verts[(k + 2) % 3]]));
    }
    for m in &edit.moves {
        for c in mesh.vertex_corners(m.vertex) {
            let tri = mesh.tri(c.tri()).map(VertexRef::Old);
            for k in 0..3 {
                if !mesh.is_two_sided(CornerId::of(c.tri(), Side::Front, k)) {
                    s.edges.push([tri[(k + 1) % 3], tri[(k + 2) % 3]]);
                }
            }
        }
    }
    let mut edges = std::mem::take(&mut s.edges);
    for e in &mut edges {
        if s.key(e[0]) > s.key(e[1]) {
            e.swap(0, 1);
        }
    }
    edges.sort_unstable_by_key(|e| (s.key(e[0]), s.key(e[1])));
    edges.dedup_by_key(|e| (s.key(e[0]), s.key(e[1])));
    // An edit may not break an edge; one that was broken before (a repair in progress:
    // degenerate removal taking coincident pairs away one at a time) is not held
    // against it.
    let result =
        edges.iter().try_for_each(
            |&[p, q]| match check_edge(mesh, edit, s, p, q, State::End) {
                Err(fault) if check_edge(mesh, edit, s, p, q, State::Before).is_ok() => Err(fault),
                _ => Ok(()),
            },
        );
    s.edges = edges;
    result?;
    check_small_components(mesh, edit, s)
}

/// Floods the surface component of `seed` over edge neighbours, breadth first, into
/// `out`, stamping each triangle reached with `stamp` in `seen`; true when it has at most
/// [`SMALL_COMPONENT`] triangles (then `out` holds all of them), false as soon as it has
/// more.
fn small_component(
    mesh: &LabeledMesh,
    seed: TriId,
    seen: &mut [u32],
    stamp: u32,
    out: &mut Vec<TriId>,
) -> bool {
    out.clear();
    out.push(seed);
    seen[seed.idx()] = stamp;
    let mut next = 0;
    while next < out.len() {
        let t = out[next];
        next += 1;
        for side in [Side::Front, Side::Back] {
            for k in 0..3 {
                let Some(o) = mesh.opposite(CornerId::of(t, side, k)) else {
                    continue;
                };
                let u = o.tri();
                if seen[u.idx()] != stamp {
                    if out.len() == SMALL_COMPONENT {
                        return false;
                    }
                    seen[u.idx()] = stamp;
                    out.push(u);
                }
            }
        }
    }
    true
}

/// Adds to `volumes` (`(label, before, after)`; `after` says which column) the signed
/// volume each label encloses over the triangles `tris` (corner positions and labels):
/// the cone from `origin` (a vertex of the component, so that a tiny component far from
/// the coordinate origin keeps its digits), `+` for the label behind a triangle, `−` for
/// the one in front.
fn add_label_volumes(
    volumes: &mut Vec<(Label, f64, f64)>,
    after: bool,
    origin: DVec3,
    tris: impl Iterator<Item = ([DVec3; 3], [Label; 2])>,
) {
    for (p, [front, back]) in tris {
        let [a, b, c] = p.map(|q| q - origin);
        let cone = a.dot(b.cross(c)) / 6.0;
        for (label, v) in [(back, cone), (front, -cone)] {
            let slot = match volumes.iter().position(|e| e.0 == label) {
                Some(i) => i,
                None => {
                    volumes.push((label, 0.0, 0.0));
                    volumes.len() - 1
                }
            };
            if after {
                volumes[slot].2 += v;
            } else {
                volumes[slot].1 += v;
            }
        }
    }
}

/// [`StructureFault::Inverts`]: every small component the edit touches keeps the sign of
/// every label's enclosed volume (see [`SMALL_COMPONENT`]).
fn check_small_components(
    mesh: &LabeledMesh,
    edit: &Edit,
    s: &mut StructureScratch,
) -> Result<(), StructureFault> {
    let moves_only = edit.remove_tris.is_empty() && edit.add_tris.is_empty();
    if !moves_only {
        s.bump_large_epoch();
    }
    let cached = moves_only && s.moves_only == Some(std::ptr::from_ref(mesh) as usize);
    if cached && s.large.len() < mesh.triangle_capacity() {
        s.large.resize(mesh.triangle_capacity(), 0);
    }
    let mut component = std::mem::take(&mut s.component);
    let mut seeds = std::mem::take(&mut s.seeds);
    seeds.clear();
    seeds.extend_from_slice(&edit.remove_tris);
    seeds.extend(
        edit.moves
            .iter()
            .flat_map(|m| mesh.vertex_triangles(m.vertex)),
    );
    if s.flooded.len() < mesh.triangle_capacity() {
        s.flooded.resize(mesh.triangle_capacity(), 0);
    }
    // One stamp per flood; a seed stamped since `first` was reached by an earlier flood
    // of this edit. Restart the stamps before they could wrap.
    if s.epoch > u32::MAX - 1 - seeds.len() as u32 {
        s.flooded.fill(0);
        s.epoch = 0;
    }
    let first = s.epoch + 1;
    let mut result = Ok(());
    for &seed in &seeds {
        if s.flooded[seed.idx()] >= first || (cached && s.large[seed.idx()] == s.large_epoch) {
            continue;
        }
        s.epoch += 1;
        let small = small_component(mesh, seed, &mut s.flooded, s.epoch, &mut component);
        if !small {
            if cached {
                for &t in &component {
                    s.large[t.idx()] = s.large_epoch;
                }
            }
            continue;
        }
        let origin = mesh.position(mesh.tri(component[0])[0]);
        let mut volumes: Vec<(Label, f64, f64)> = Vec::new();
        add_label_volumes(
            &mut volumes,
            false,
            origin,
            component
                .iter()
                .map(|&t| (mesh.tri_positions(t), mesh.labels(t))),
        );
        let kept = component
            .iter()
            .filter(|&&t| s.removed.binary_search(&t).is_err())
            .map(|&t| {
                let p = mesh.tri(t).map(|v| s.end(mesh, edit, VertexRef::Old(v)));
                (p, mesh.labels(t))
            });
        // New triangles join the component of the old vertices they use.
        let (seen, stamp) = (&s.flooded, s.epoch);
        let in_component = |v: VertexId| mesh.vertex_triangles(v).any(|t| seen[t.idx()] == stamp);
        let added = edit
            .add_tris
            .iter()
            .filter(|(verts, _)| {
                verts
                    .iter()
                    .any(|r| matches!(r, VertexRef::Old(v) if in_component(*v)))
            })
            .map(|(verts, labels)| (verts.map(|r| s.end(mesh, edit, r)), *labels));
        add_label_volumes(&mut volumes, true, origin, kept.chain(added));
        if let Some(&(label, _, _)) = volumes
            .iter()
            .find(|(_, before, after)| before * after < 0.0)
        {
            result = Err(StructureFault::Inverts {
                tri: component[0].raw(),
                label,
            });
            break;
        }
    }
    s.component = component;
    s.seeds = seeds;
    result
}

/// Which state of an edge [`check_edge`] looks at.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum State {
    /// The mesh as it is.
    Before,
    /// The mesh as the commit will leave it.
    End,
}

/// The state around edge `{p, q}` (`key(p) < key(q)`): no lone triangle, and each wedge of
/// the radial order the commit builds (or built) faced by one label.
fn check_edge(
    mesh: &LabeledMesh,
    edit: &Edit,
    s: &mut StructureScratch,
    p: VertexRef,
    q: VertexRef,
    state: State,
) -> Result<(), StructureFault> {
    let end = state == State::End;
    let (kp, kq) = (s.key(p), s.key(q));
    let edge = [kp, kq];
    s.incident.clear();
    if let (VertexRef::Old(a), VertexRef::Old(b)) = (p, q) {
        for t in mesh.vertex_triangles(a) {
            let tri = mesh.tri(t);
            if tri.contains(&b) && (!end || s.removed.binary_search(&t).is_err()) {
                s.incident.push(Incident {
                    keys: tri.map(VertexId::raw),
                    refs: tri.map(VertexRef::Old),
                    labels: mesh.labels(t),
                    id: t,
                });
            }
        }
    }
    for (j, (verts, labels)) in edit.add_tris.iter().enumerate() {
        let keys = verts.map(|r| s.key(r));
        if end && keys.contains(&kp) && keys.contains(&kq) {
            s.incident.push(Incident {
                keys,
                refs: *verts,
                labels: *labels,
                id: s.new_tri_ids[j],
            });
        }
    }
    match s.incident.len() {
        0 => return Ok(()),
        1 => return Err(StructureFault::Boundary { edge }),
        _ => {}
    }
    // The commit's radial sort, on local copies: local vertex 0 is the edge's lower end and
    // 1 its higher end (so `lo`/`hi` agree), local triangles follow the ids the commit
    // gives them (so ties break alike).
    s.incident.sort_unstable_by_key(|i| i.id);
    s.local_positions.clear();
    let at = |s: &StructureScratch, r: VertexRef| match (state, r) {
        (State::Before, VertexRef::Old(v)) => mesh.position(v),
        _ => s.end(mesh, edit, r),
    };
    s.local_positions.extend([at(s, p), at(s, q)]);
    s.local_tris.clear();
    s.group.clear();
    for n in 0..s.incident.len() {
        let inc = s.incident[n];
        let third = s.local_positions.len() as u32;
        let Some(k) = (0..3).find(|&k| inc.keys[k] != kp && inc.keys[k] != kq) else {
            return Err(StructureFault::Degenerate { tri: inc.keys });
        };
        let third_pos = at(s, inc.refs[k]);
        s.local_positions.push(third_pos);
        let local = inc.keys.map(|k| {
            VertexId::new(if k == kp {
                0
            } else if k == kq {
                1
            } else {
                third
            })
        });
        let slot = local.iter().position(|&v| v.raw() == third).unwrap_or(0);
        s.local_tris.push(local);
        s.group.push(EdgeIncidence {
            lo: VertexId::new(0),
            hi: VertexId::new(1),
            tri: TriId::new(n as u32),
            slot: slot as u8,
        });
    }
    sort_radially(&mut s.group, &s.local_tris, &s.local_positions);
    let m = s.group.len();
    let label = |c: CornerId| s.incident[c.tri().idx()].labels[c.side().index()];
    for i in 0..m {
        let (here, next) = (s.group[i], s.group[(i + 1) % m]);
        let a = label(here.ccw_corner(&s.local_tris));
        let b = label(next.cw_corner(&s.local_tris));
        if a != b {
            return Err(StructureFault::Labels {
                edge,
                labels: [a, b],
            });
        }
    }
    Ok(())
}

/// The moves of a batch (moves only) to blame for `fault`: those whose vertex lies on the
/// faulty triangle or on a triangle of the faulty edge.
pub(crate) fn blame_moves(mesh: &LabeledMesh, edit: &Edit, fault: &StructureFault) -> Vec<usize> {
    let involved = |v: VertexId| -> bool {
        match *fault {
            StructureFault::NonFinite { vertex } => v.raw() == vertex,
            StructureFault::ZeroArea { tri } | StructureFault::Degenerate { tri } => {
                tri.contains(&v.raw())
            }
            StructureFault::Boundary { edge } | StructureFault::Labels { edge, .. } => {
                mesh.vertex_triangles(v).any(|t| {
                    let tri = mesh.tri(t).map(VertexId::raw);
                    tri.contains(&edge[0]) && tri.contains(&edge[1])
                })
            }
            StructureFault::Inverts { tri, .. } => {
                let mut seen = vec![0; mesh.triangle_capacity()];
                let mut component = Vec::new();
                small_component(mesh, TriId::new(tri), &mut seen, 1, &mut component);
                mesh.vertex_triangles(v).any(|t| seen[t.idx()] == 1)
            }
        }
    };
    (0..edit.moves.len())
        .filter(|&i| involved(edit.moves[i].vertex))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ids::Label;

    /// The predicted ids are the ones the mesh then hands out.
    #[test]
    fn predicted_ids_match_the_commit() {
        let mut m =
            crate::generators::icosphere(1, DVec3::ZERO, 1.0, [Label::new(0), Label::new(1)])
                .expect("sphere");
        let removed: Vec<TriId> = m.triangles().take(3).collect();
        let mut tris = Vec::new();
        m.next_triangle_ids(&removed, 5, &mut tris);
        let mut verts = Vec::new();
        m.next_vertex_ids(2, &mut verts);
        let keep: Vec<_> = removed.iter().map(|&t| (m.tri(t), m.labels(t))).collect();
        for &t in &removed {
            m.remove_triangle(t).expect("live");
        }
        let v: Vec<VertexId> = (0..2)
            .map(|_| m.add_vertex(DVec3::ZERO).expect("room"))
            .collect();
        assert_eq!(v, verts);
        let got: Vec<TriId> = (0..5)
            .map(|k| {
                let (tri, labels) = keep[k % 3];
                m.add_triangle(tri, labels).expect("room")
            })
            .collect();
        assert_eq!(got, tris);
    }

    /// A flat droplet of material 1 (5 vertices, 6 triangles, 0.006 thick), left in a grid
    /// run by the implicit-surface follower (three blobs separating, t = 0.8; the
    /// coordinates are that run's). Collapsing the edge between its two highest and lowest
    /// vertices to the midpoint turns each triangle by a few degrees only, but leaves a
    /// tetrahedron whose labels say material 1 outside and 0 inside, in the middle of
    /// material 0 — which placement (layer 4) then reports. The structure check must
    /// refuse it; a collapse on a small component that keeps its orientation is allowed.
    #[test]
    fn collapse_that_turns_a_small_component_inside_out_is_refused() {
        use crate::remesh::edit::{Edit, VertexMove};
        use crate::remesh::{NoGuard, VertexAttributes, apply_edit};
        let p = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
        let positions = vec![
            p(
                0.11517430157303077,
                0.35351834256427944,
                0.004975778501091408,
            ),
            p(
                0.1189201157330418,
                0.33141702713404825,
                0.005212248615293247,
            ),
            p(
                0.12688895810738304,
                0.3356523780751495,
                0.005127944840523488,
            ),
            p(0.126980238531119, 0.3549320587613059, 0.0026312770164543947),
            p(0.126680238531119, 0.35508205876130594, 0.00885977040167954),
        ];
        // Local ids: 0 = 327, 1 = 620, 2 = 644, 3 = 669 (lower apex), 4 = 811 (upper).
        let tris = [
            [4, 3, 0],
            [3, 1, 2],
            [2, 4, 0],
            [4, 2, 3],
            [0, 1, 2],
            [3, 0, 1],
        ];
        let labels = [[0, 1], [1, 0], [0, 1], [0, 1], [0, 1], [1, 0]];
        let build = |positions: Vec<DVec3>| {
            LabeledMesh::from_raw(positions, &tris, &labels).expect("droplet")
        };
        fn collapse_edge_to_midpoint(m: &LabeledMesh, a: VertexId, b: VertexId) -> Edit {
            let mid = (m.position(a) + m.position(b)) / 2.0;
            let mut edit = Edit::default();
            for t in m.vertex_triangles(b) {
                edit.remove_tris.push(t);
                let tri = m.tri(t);
                if !tri.contains(&a) {
                    let verts = tri.map(|v| VertexRef::Old(if v == b { a } else { v }));
                    edit.add_tris.push((verts, m.labels(t)));
                }
            }
            for v in [a, b] {
                edit.moves.push(VertexMove {
                    vertex: v,
                    end: mid,
                    blend: None,
                });
            }
            edit.remove_vertices.push(b);
            edit
        }
        let placed = |m: &LabeledMesh| crate::placement::misplaced_shells(m).is_empty();

        let mut m = build(positions.clone());
        assert!(crate::validate::validate(&m, &Default::default()).is_valid());
        let edit = collapse_edge_to_midpoint(&m, VertexId::new(3), VertexId::new(4));
        let err = apply_edit(&mut m, &mut VertexAttributes::none(), &mut NoGuard, &edit)
            .expect_err("the collapse inverts the droplet");
        assert!(
            matches!(err, EditError::Structure(StructureFault::Inverts { label, .. }) if label == Label::new(1) || label == Label::new(0)),
            "{err}"
        );
        assert!(placed(&m), "a refused edit leaves the mesh as it was");

        // What the check stands between: the same edit committed without it misplaces
        // the droplet.
        let mut unchecked = build(positions.clone());
        crate::remesh::edit::commit_guarded(
            &mut unchecked,
            &mut VertexAttributes::none(),
            &mut NoGuard,
            &edit,
        )
        .expect("commits");
        assert!(!placed(&unchecked), "the inverted tetrahedron is misplaced");

        // A collapse on a small component that keeps its orientation is allowed: an
        // edge of an icosahedron (20 triangles) to its midpoint.
        let mut m =
            crate::generators::icosphere(0, DVec3::ZERO, 1.0, [Label::new(0), Label::new(1)])
                .expect("icosahedron");
        let [a, b, _] = m.tri(TriId::new(0));
        let edit = collapse_edge_to_midpoint(&m, a, b);
        apply_edit(&mut m, &mut VertexAttributes::none(), &mut NoGuard, &edit)
            .expect("a collapse that keeps the component's orientation is allowed");
        assert_eq!(m.num_triangles(), 18);
        assert!(placed(&m));
    }

    /// The moves-only scope remembers large components, never small ones, and never
    /// carries what it learnt on one mesh over to another.
    #[test]
    fn moves_only_scope_still_refuses_turning_a_small_component_inside_out() {
        use crate::remesh::attributes::VertexAttributes;
        use crate::remesh::edit::{EditError, VertexMove, apply_edit, with_moves_only};
        use crate::remesh::guard::NoGuard;
        let labels = [Label::new(0), Label::new(1)];
        let tetra = || {
            let p = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
            let tris = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
            LabeledMesh::from_raw(p, &tris, &[[0, 1]; 4]).expect("tetrahedron")
        };
        let shift = |m: &LabeledMesh, v: VertexId, d: DVec3| Edit {
            moves: vec![VertexMove {
                vertex: v,
                end: m.position(v) + d,
                blend: None,
            }],
            ..Edit::default()
        };
        let through_base = DVec3::new(0.1, 0.1, -2.0);
        let sphere = crate::generators::icosphere(2, DVec3::new(5.0, 0.0, 0.0), 1.0, labels)
            .expect("sphere");
        let mut m = LabeledMesh::disjoint_union(&[sphere.clone(), tetra()]).expect("union");
        let apex = VertexId::new(sphere.num_vertices() as u32 + 3);
        with_moves_only(&mut m, |m| {
            let mut none = VertexAttributes::none();
            // Twice on the sphere (the second check reads the stamps), then the droplet.
            for _ in 0..2 {
                let edit = shift(m, VertexId::new(0), DVec3::splat(1e-3));
                apply_edit(m, &mut none, &mut NoGuard, &edit).expect("a small move");
            }
            let edit = shift(m, apex, through_base);
            let err = apply_edit(m, &mut none, &mut NoGuard, &edit).expect_err("inverts");
            assert!(
                matches!(err, EditError::Structure(StructureFault::Inverts { .. })),
                "{err}"
            );

            // Another mesh checked inside this scope (rayon may run another block's job
            // here): its triangle 0 is small although the scope's triangle 0 is large.
            let mut other = tetra();
            let edit = shift(&other, VertexId::new(3), through_base);
            let err = apply_edit(&mut other, &mut none, &mut NoGuard, &edit).expect_err("inverts");
            assert!(
                matches!(err, EditError::Structure(StructureFault::Inverts { .. })),
                "{err}"
            );
        });
    }
}
