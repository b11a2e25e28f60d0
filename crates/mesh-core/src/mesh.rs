//! [`LabeledMesh`]: the labelled non-manifold triangle mesh with its corner table.
//!
//! Storage is struct-of-arrays over typed ids: positions per vertex; vertex triple, label
//! pair and liveness per triangle; six `opposite` pointers per triangle (the only stored
//! part of the corner table, see [`crate::corner`]); and an intrusive doubly linked *ring*
//! per vertex threading the front corners at that vertex, so adding or removing a triangle
//! touches O(1) ring links and no per-vertex heap allocation exists.
//!
//! Deleted elements go to free lists and are reused; [`LabeledMesh::compact`] renumbers.

use glam::DVec3;

use crate::connectivity::{EdgeIncidence, EdgeTable, pair_sides, sort_radially};
use crate::corner::Side;
use crate::error::MeshError;
use crate::ids::{CornerId, IdVec, Label, MAX_INDEX, TriId, VertexId};

/// A labelled non-manifold triangle mesh: every triangle separates two materials,
/// `labels[t] = [front, back]`, front being the material its right-hand normal points into.
#[derive(Clone, Debug, Default)]
pub struct LabeledMesh {
    positions: IdVec<VertexId, DVec3>,
    vertex_alive: Vec<bool>,
    ring_head: IdVec<VertexId, Option<CornerId>>,
    free_vertices: Vec<VertexId>,
    live_vertices: usize,

    tris: IdVec<TriId, [VertexId; 3]>,
    labels: IdVec<TriId, [Label; 2]>,
    tri_alive: Vec<bool>,
    free_tris: Vec<TriId>,
    live_tris: usize,

    /// Six per triangle, indexed by `CornerId`.
    opposite: Vec<Option<CornerId>>,
    /// Three per triangle (front corners only), indexed by `3·t + slot`.
    ring_next: Vec<Option<CornerId>>,
    ring_prev: Vec<Option<CornerId>>,

    /// Reused buffer for relinking one edge (keeps edits allocation-free).
    scratch: Vec<EdgeIncidence>,
}

/// Old-to-new id maps returned by [`LabeledMesh::compact`].
#[derive(Clone, Debug, Default)]
pub struct Compaction {
    /// `vertex_map[old] = Some(new)` for kept vertices.
    pub vertex_map: Vec<Option<VertexId>>,
    /// `tri_map[old] = Some(new)` for kept triangles.
    pub tri_map: Vec<Option<TriId>>,
}

#[inline]
fn ring_slot(c: CornerId) -> usize {
    c.tri().idx() * 3 + c.slot()
}

impl LabeledMesh {
    /// An empty mesh.
    pub fn new() -> Self {
        Self::default()
    }

    /// Builds a mesh from plain arrays: positions, triangles as vertex indices, and per
    /// triangle `[front, back]` labels. Fails on out-of-range indices and mismatched lengths;
    /// everything else (boundary edges, degenerate triangles, non-finite coordinates,
    /// inconsistent labels) is representable and reported by [`crate::validate`].
    pub fn from_raw(
        positions: Vec<DVec3>,
        triangles: &[[u32; 3]],
        labels: &[[u32; 2]],
    ) -> Result<Self, MeshError> {
        if labels.len() != triangles.len() {
            return Err(MeshError::LengthMismatch {
                what: "label pairs",
                expected: triangles.len(),
                got: labels.len(),
            });
        }
        check_count("vertices", positions.len())?;
        check_count("triangles", triangles.len().saturating_mul(6))?;
        let n = positions.len();
        let mut tris = Vec::with_capacity(triangles.len());
        for (t, tri) in triangles.iter().enumerate() {
            for &i in tri {
                if i as usize >= n {
                    return Err(MeshError::VertexOutOfRange {
                        tri: t,
                        index: i as u64,
                        vertex_count: n,
                    });
                }
            }
            tris.push(tri.map(VertexId::new));
        }
        let mut typed_labels = Vec::with_capacity(labels.len());
        for (t, pair) in labels.iter().enumerate() {
            if let Some(&bad) = pair.iter().find(|&&l| l > MAX_INDEX) {
                return Err(MeshError::LabelOutOfRange { tri: t, label: bad });
            }
            typed_labels.push(pair.map(Label::new));
        }
        Ok(Self::from_parts(positions, tris, typed_labels))
    }

    /// Builds a mesh from typed arrays whose indices are known to be in range.
    fn from_parts(
        positions: Vec<DVec3>,
        tris: Vec<[VertexId; 3]>,
        labels: Vec<[Label; 2]>,
    ) -> Self {
        let opposite = vec![None; tris.len() * 6];
        let mut mesh = Self::dense(positions, tris, labels, opposite);
        mesh.rebuild_opposites();
        mesh
    }

    /// A mesh with every slot live and no free lists, from dense arrays and a given
    /// opposite table; the vertex rings are rebuilt.
    fn dense(
        positions: Vec<DVec3>,
        tris: Vec<[VertexId; 3]>,
        labels: Vec<[Label; 2]>,
        opposite: Vec<Option<CornerId>>,
    ) -> Self {
        let nv = positions.len();
        let nt = tris.len();
        let mut mesh = LabeledMesh {
            positions: IdVec::from_vec(positions),
            vertex_alive: vec![true; nv],
            ring_head: IdVec::from_vec(vec![None; nv]),
            free_vertices: Vec::new(),
            live_vertices: nv,
            tris: IdVec::from_vec(tris),
            labels: IdVec::from_vec(labels),
            tri_alive: vec![true; nt],
            free_tris: Vec::new(),
            live_tris: nt,
            opposite,
            ring_next: vec![None; nt * 3],
            ring_prev: vec![None; nt * 3],
            scratch: Vec::new(),
        };
        mesh.rebuild_rings();
        mesh
    }

    /// Recomputes every vertex ring from the triangle list.
    fn rebuild_rings(&mut self) {
        self.ring_head.as_mut_slice().fill(None);
        self.ring_next.fill(None);
        self.ring_prev.fill(None);
        for t in 0..self.tris.len() {
            if !self.tri_alive[t] {
                continue;
            }
            for k in 0..3 {
                self.ring_insert(CornerId::of(TriId::new(t as u32), Side::Front, k));
            }
        }
    }

    /// Recomputes every opposite pointer: group edges, sort non-manifold ones radially,
    /// pair the sides that face a common wedge.
    fn rebuild_opposites(&mut self) {
        self.opposite.fill(None);
        let mut table =
            EdgeTable::build(self.tris.as_slice(), &self.tri_alive, self.positions.len());
        let tris = self.tris.as_slice();
        let positions = self.positions.as_slice();
        let opposite = &mut self.opposite;
        for group in table.groups_mut() {
            sort_radially(group, tris, positions);
            pair_sides(group, tris, |a, b| {
                opposite[a.idx()] = Some(b);
                opposite[b.idx()] = Some(a);
            });
        }
    }

    // ----- counts and iteration -------------------------------------------------------

    /// Number of live vertices.
    pub fn num_vertices(&self) -> usize {
        self.live_vertices
    }

    /// Number of live triangles.
    pub fn num_triangles(&self) -> usize {
        self.live_tris
    }

    /// Number of vertex slots, live or free (ids are below this).
    pub fn vertex_capacity(&self) -> usize {
        self.positions.len()
    }

    /// Number of triangle slots, live or free (ids are below this).
    pub fn triangle_capacity(&self) -> usize {
        self.tris.len()
    }

    /// Live vertex ids, in increasing order.
    pub fn vertices(&self) -> impl Iterator<Item = VertexId> + '_ {
        (0..self.positions.len() as u32)
            .filter(|&i| self.vertex_alive[i as usize])
            .map(VertexId::new)
    }

    /// Live triangle ids, in increasing order.
    pub fn triangles(&self) -> impl Iterator<Item = TriId> + '_ {
        (0..self.tris.len() as u32)
            .filter(|&i| self.tri_alive[i as usize])
            .map(TriId::new)
    }

    /// True if `v` names a live vertex.
    pub fn is_vertex_alive(&self, v: VertexId) -> bool {
        self.vertex_alive.get(v.idx()).copied().unwrap_or(false)
    }

    /// True if `t` names a live triangle.
    pub fn is_triangle_alive(&self, t: TriId) -> bool {
        self.tri_alive.get(t.idx()).copied().unwrap_or(false)
    }

    // ----- geometry and labels ----------------------------------------------------------

    /// Position of a vertex.
    #[inline]
    pub fn position(&self, v: VertexId) -> DVec3 {
        self.positions[v]
    }

    /// Moves a vertex. Connectivity is combinatorial and does not change.
    #[inline]
    pub fn set_position(&mut self, v: VertexId, p: DVec3) {
        self.positions[v] = p;
    }

    /// All vertex positions by id (dead slots included, with stale values).
    #[inline]
    pub fn positions(&self) -> &[DVec3] {
        self.positions.as_slice()
    }

    /// Mutable positions by id, e.g. to apply a whole displacement field at once.
    #[inline]
    pub fn positions_mut(&mut self) -> &mut [DVec3] {
        self.positions.as_mut_slice()
    }

    /// Vertex triple of a triangle, `[v0, v1, v2]`; the front normal is `(v1−v0)×(v2−v0)`.
    #[inline]
    pub fn tri(&self, t: TriId) -> [VertexId; 3] {
        self.tris[t]
    }

    /// All triangle vertex triples by id (dead slots included, with stale values).
    #[inline]
    pub fn tris(&self) -> &[[VertexId; 3]] {
        self.tris.as_slice()
    }

    /// Liveness flag of every triangle slot.
    #[inline]
    pub fn tri_alive_flags(&self) -> &[bool] {
        &self.tri_alive
    }

    /// The three corner positions of a triangle.
    #[inline]
    pub fn tri_positions(&self, t: TriId) -> [DVec3; 3] {
        self.tris[t].map(|v| self.positions[v])
    }

    /// `[front, back]` labels of a triangle.
    #[inline]
    pub fn labels(&self, t: TriId) -> [Label; 2] {
        self.labels[t]
    }

    /// All label pairs by triangle id (dead slots included).
    #[inline]
    pub fn label_pairs(&self) -> &[[Label; 2]] {
        self.labels.as_slice()
    }

    /// Sets the labels of a triangle (e.g. when a region is relabelled).
    #[inline]
    pub fn set_labels(&mut self, t: TriId, labels: [Label; 2]) {
        self.labels[t] = labels;
    }

    /// Reverses a triangle's orientation, swapping its labels so the same materials stay on
    /// the same sides of space. Opposite pointers are recomputed for its edges.
    pub fn flip_orientation(&mut self, t: TriId) -> Result<(), MeshError> {
        let verts = self.tri_checked(t)?;
        let labels = self.labels[t];
        self.remove_triangle(t)?;
        let new = self.add_triangle([verts[0], verts[2], verts[1]], [labels[1], labels[0]])?;
        debug_assert_eq!(new, t);
        Ok(())
    }

    /// Sorted list of the distinct labels used by live triangles.
    pub fn label_set(&self) -> Vec<Label> {
        let mut all: Vec<Label> = self.triangles().flat_map(|t| self.labels[t]).collect();
        all.sort_unstable();
        all.dedup();
        all
    }

    // ----- corner table ---------------------------------------------------------------

    /// Vertex of a corner.
    #[inline]
    pub fn corner_vertex(&self, c: CornerId) -> VertexId {
        self.tris[c.tri()][c.slot()]
    }

    /// The material the side of this corner faces.
    #[inline]
    pub fn corner_label(&self, c: CornerId) -> Label {
        self.labels[c.tri()][c.side().index()]
    }

    /// The opposite corner (see [`crate::corner`]); `None` across a boundary edge.
    #[inline]
    pub fn opposite(&self, c: CornerId) -> Option<CornerId> {
        self.opposite[c.idx()]
    }

    /// The two vertices of the edge opposite a corner, in the order its side traverses them.
    #[inline]
    pub fn corner_edge(&self, c: CornerId) -> [VertexId; 2] {
        [self.corner_vertex(c.next()), self.corner_vertex(c.prev())]
    }

    /// Front corners at a vertex (one per incident triangle), by walking its ring.
    pub fn vertex_corners(&self, v: VertexId) -> VertexCorners<'_> {
        VertexCorners {
            mesh: self,
            at: self.ring_head.get(v).copied().flatten(),
            budget: self.tris.len(),
        }
    }

    /// Triangles incident to a vertex.
    pub fn vertex_triangles(&self, v: VertexId) -> impl Iterator<Item = TriId> + '_ {
        self.vertex_corners(v).map(|c| c.tri())
    }

    /// The corners facing successive wedges around the edge opposite `c`, starting with `c`:
    /// `c, dual(opposite(c)), …` — one per incident triangle, in radial order.
    /// Stops at a boundary (missing opposite) or after visiting every triangle.
    pub fn radial_corners(&self, c: CornerId) -> RadialCorners<'_> {
        RadialCorners {
            mesh: self,
            start: c,
            at: Some(c),
            budget: self.tris.len(),
        }
    }

    /// Triangles incident to the edge `{a, b}` (found through the ring of `a`).
    pub fn edge_triangles(&self, a: VertexId, b: VertexId) -> impl Iterator<Item = TriId> + '_ {
        self.vertex_corners(a)
            .map(|c| c.tri())
            .filter(move |&t| self.tris[t].contains(&b))
    }

    // ----- edits -----------------------------------------------------------------------

    /// Adds an isolated vertex (reusing a free slot if any).
    pub fn add_vertex(&mut self, p: DVec3) -> Result<VertexId, MeshError> {
        self.live_vertices += 1;
        if let Some(v) = self.free_vertices.pop() {
            self.positions[v] = p;
            self.vertex_alive[v.idx()] = true;
            self.ring_head[v] = None;
            return Ok(v);
        }
        check_count("vertices", self.positions.len() + 1)
            .inspect_err(|_| self.live_vertices -= 1)?;
        self.vertex_alive.push(true);
        self.ring_head.push(None);
        Ok(self.positions.push(p))
    }

    /// Removes a vertex that no triangle uses.
    pub fn remove_vertex(&mut self, v: VertexId) -> Result<(), MeshError> {
        if !self.is_vertex_alive(v) {
            return Err(MeshError::NoSuchVertex(v));
        }
        if self.ring_head[v].is_some() {
            return Err(MeshError::VertexInUse(v));
        }
        self.vertex_alive[v.idx()] = false;
        self.free_vertices.push(v);
        self.live_vertices -= 1;
        Ok(())
    }

    /// The ids the next `n` calls of [`Self::add_vertex`] will return: free slots, the
    /// last freed first, then appended ones. (Edits predict the ids they will create, so
    /// that their structural check sees exactly what the commit will build.)
    pub(crate) fn next_vertex_ids(&self, n: usize, out: &mut Vec<VertexId>) {
        out.clear();
        out.extend(self.free_vertices.iter().rev().take(n).copied());
        let appended = n - out.len();
        out.extend((0..appended).map(|k| VertexId::new((self.positions.len() + k) as u32)));
    }

    /// The ids `n` calls of [`Self::add_triangle`] will return right after
    /// [`Self::remove_triangle`] of each of `removed`, in order (freed slots are reused last
    /// freed first).
    pub(crate) fn next_triangle_ids(&self, removed: &[TriId], n: usize, out: &mut Vec<TriId>) {
        out.clear();
        out.extend(
            removed
                .iter()
                .rev()
                .chain(self.free_tris.iter().rev())
                .take(n)
                .copied(),
        );
        let appended = n - out.len();
        out.extend((0..appended).map(|k| TriId::new((self.tris.len() + k) as u32)));
    }

    /// Adds a triangle and links it into the corner table: its three edges are re-paired
    /// radially (O(edge degree)).
    pub fn add_triangle(
        &mut self,
        verts: [VertexId; 3],
        labels: [Label; 2],
    ) -> Result<TriId, MeshError> {
        let t = self.add_triangle_unpaired(verts, labels)?;
        self.relink_triangle_edges(verts);
        Ok(t)
    }

    /// [`Self::add_triangle`] without re-pairing its edges: the caller re-pairs them (with
    /// [`Self::relink_edges`]) before anything reads the corner table's opposites. An
    /// edit that adds and removes many triangles around the same edges re-pairs each edge
    /// once instead of once per triangle.
    pub(crate) fn add_triangle_unpaired(
        &mut self,
        verts: [VertexId; 3],
        labels: [Label; 2],
    ) -> Result<TriId, MeshError> {
        for v in verts {
            if !self.is_vertex_alive(v) {
                return Err(MeshError::NoSuchVertex(v));
            }
        }
        let t = match self.free_tris.pop() {
            Some(t) => {
                self.tris[t] = verts;
                self.labels[t] = labels;
                self.tri_alive[t.idx()] = true;
                t
            }
            None => {
                check_count("triangles", (self.tris.len() + 1) * 6)?;
                self.tri_alive.push(true);
                self.labels.push(labels);
                self.opposite.extend([None; 6]);
                self.ring_next.extend([None; 3]);
                self.ring_prev.extend([None; 3]);
                self.tris.push(verts)
            }
        };
        self.live_tris += 1;
        for k in 0..3 {
            self.ring_insert(CornerId::of(t, Side::Front, k));
        }
        Ok(t)
    }

    /// Removes a triangle; its edges are re-paired among the remaining triangles.
    /// Its vertices stay (remove them with [`Self::remove_vertex`] if they became isolated).
    pub fn remove_triangle(&mut self, t: TriId) -> Result<(), MeshError> {
        let verts = self.remove_triangle_unpaired(t)?;
        self.relink_triangle_edges(verts);
        Ok(())
    }

    /// [`Self::remove_triangle`] without re-pairing the edges it leaves (see
    /// [`Self::add_triangle_unpaired`]); returns its vertices.
    pub(crate) fn remove_triangle_unpaired(
        &mut self,
        t: TriId,
    ) -> Result<[VertexId; 3], MeshError> {
        let verts = self.tri_checked(t)?;
        for k in 0..3 {
            self.ring_remove(CornerId::of(t, Side::Front, k));
        }
        self.opposite[t.idx() * 6..t.idx() * 6 + 6].fill(None);
        self.tri_alive[t.idx()] = false;
        self.free_tris.push(t);
        self.live_tris -= 1;
        Ok(verts)
    }

    fn relink_triangle_edges(&mut self, verts: [VertexId; 3]) {
        for k in 0..3 {
            self.relink_edge(verts[(k + 1) % 3], verts[(k + 2) % 3]);
        }
    }

    /// Re-pairs each distinct edge among `edges` (either orientation) once; `edges` is
    /// sorted and deduplicated in place.
    pub(crate) fn relink_edges(&mut self, edges: &mut Vec<[VertexId; 2]>) {
        for e in edges.iter_mut() {
            if e[1] < e[0] {
                e.swap(0, 1);
            }
        }
        edges.sort_unstable();
        edges.dedup();
        for &[a, b] in edges.iter() {
            self.relink_edge(a, b);
        }
    }

    /// Re-pairs the sides around one edge from the current geometry.
    pub fn relink_edge(&mut self, a: VertexId, b: VertexId) {
        if a == b {
            return;
        }
        let (lo, hi) = if a < b { (a, b) } else { (b, a) };
        let mut group = std::mem::take(&mut self.scratch);
        group.clear();
        for c in self.vertex_corners(lo) {
            let t = c.tri();
            let tri = self.tris[t];
            // Every slot of t opposite {lo, hi} (twice for a triangle with a repeated vertex).
            for k in 0..3 {
                let (p, q) = (tri[(k + 1) % 3], tri[(k + 2) % 3]);
                if (p == lo && q == hi) || (p == hi && q == lo) {
                    group.push(EdgeIncidence {
                        lo,
                        hi,
                        tri: t,
                        slot: k as u8,
                    });
                }
            }
        }
        // A triangle with a repeated vertex appears once per ring entry; dedupe.
        group.sort_unstable_by_key(|e| (e.tri, e.slot));
        group.dedup();
        for e in &group {
            self.opposite[CornerId::of(e.tri, Side::Front, e.slot as usize).idx()] = None;
            self.opposite[CornerId::of(e.tri, Side::Back, e.slot as usize).idx()] = None;
        }
        sort_radially(&mut group, self.tris.as_slice(), self.positions.as_slice());
        let opposite = &mut self.opposite;
        pair_sides(&group, self.tris.as_slice(), |x, y| {
            opposite[x.idx()] = Some(y);
            opposite[y.idx()] = Some(x);
        });
        self.scratch = group;
    }

    /// True when the edge opposite corner `c` has exactly two triangles: its radial walk
    /// comes back to `c` in two steps. Such an edge pairs the same way whatever the
    /// geometry, so no move can mislabel or reorder it.
    #[inline]
    pub fn is_two_sided(&self, c: CornerId) -> bool {
        self.opposite(c)
            .is_some_and(|o| self.opposite(o.dual()).map(CornerId::dual) == Some(c))
    }

    /// Re-pairs every edge of every triangle incident to `v` from the current geometry:
    /// call after moving `v`, since the radial order around a non-manifold edge depends on
    /// the positions of its ends and of its triangles' third vertices.
    pub fn relink_around(&mut self, v: VertexId) {
        if !self.is_vertex_alive(v) {
            return;
        }
        let mut at = self.ring_head[v];
        let mut budget = self.tris.len();
        while let (Some(c), Some(rest)) = (at, budget.checked_sub(1)) {
            budget = rest;
            at = self.ring_next[ring_slot(c)];
            let tri = self.tris[c.tri()];
            for k in 0..3 {
                // Two-triangle edges pair the same way whatever the geometry. The radial
                // walk tells in two steps (the ring walk of `edge_triangles` took a
                // vertex's degree); an unpaired corner falls back to the ring.
                let manifold = self.is_two_sided(CornerId::of(c.tri(), Side::Front, k));
                let (a, b) = (tri[(k + 1) % 3], tri[(k + 2) % 3]);
                if !manifold && self.edge_triangles(a, b).nth(2).is_some() {
                    self.relink_edge(a, b);
                }
            }
        }
    }

    /// Renumbers live vertices and triangles densely (keeping their relative order) and
    /// drops free slots. Returns the old → new maps so callers can carry their own data.
    pub fn compact(&mut self) -> Compaction {
        let mut vertex_map = vec![None; self.positions.len()];
        let mut positions = Vec::with_capacity(self.live_vertices);
        for v in self.vertices() {
            vertex_map[v.idx()] = Some(VertexId::new(positions.len() as u32));
            positions.push(self.positions[v]);
        }
        let mut tri_map = vec![None; self.tris.len()];
        let mut tris = Vec::with_capacity(self.live_tris);
        let mut labels = Vec::with_capacity(self.live_tris);
        for t in self.triangles() {
            tri_map[t.idx()] = Some(TriId::new(tris.len() as u32));
            // Live triangles only use live vertices (add_triangle checks, remove_vertex refuses).
            tris.push(self.tris[t].map(|v| vertex_map[v.idx()].unwrap_or(VertexId::new(0))));
            labels.push(self.labels[t]);
        }
        let mut opposite = vec![None; tris.len() * 6];
        for t in self.triangles() {
            let Some(nt) = tri_map[t.idx()] else { continue };
            for i in 0..6 {
                let old = self.opposite[t.idx() * 6 + i];
                opposite[nt.idx() * 6 + i] = old.and_then(|c| {
                    tri_map[c.tri().idx()].map(|nt2| CornerId::new(nt2.raw() * 6 + c.raw() % 6))
                });
            }
        }
        *self = Self::dense(positions, tris, labels, opposite);
        Compaction {
            vertex_map,
            tri_map,
        }
    }

    /// The meshes side by side as one (each densely renumbered, ids offset in order):
    /// how separately made parts of an assembly are put together. Nothing is merged,
    /// so parts that touch or overlap stay as they are (`fix` resolves them), and a part
    /// nested in another keeps the outside label it was made with (see
    /// [`crate::placement`]). Fails only past the id limits.
    pub fn disjoint_union(parts: &[LabeledMesh]) -> Result<LabeledMesh, MeshError> {
        let (mut positions, mut tris, mut labels) = (Vec::new(), Vec::new(), Vec::new());
        for m in parts {
            let (p, t, l) = m.to_raw();
            let base = u32::try_from(positions.len()).map_err(|_| MeshError::TooLarge {
                what: "vertices",
                count: positions.len(),
            })?;
            positions.extend(p);
            tris.extend(t.iter().map(|t| t.map(|v| v + base)));
            labels.extend(l);
        }
        LabeledMesh::from_raw(positions, &tris, &labels)
    }

    /// Plain arrays of the live mesh, densely renumbered: positions, triangles, labels.
    pub fn to_raw(&self) -> (Vec<DVec3>, Vec<[u32; 3]>, Vec<[u32; 2]>) {
        let mut map = vec![u32::MAX; self.positions.len()];
        let mut positions = Vec::with_capacity(self.live_vertices);
        for v in self.vertices() {
            map[v.idx()] = positions.len() as u32;
            positions.push(self.positions[v]);
        }
        let (tris, labels) = self
            .triangles()
            .map(|t| {
                (
                    self.tris[t].map(|v| map[v.idx()]),
                    self.labels[t].map(|l| l.raw()),
                )
            })
            .unzip();
        (positions, tris, labels)
    }

    // ----- internals -------------------------------------------------------------------

    fn tri_checked(&self, t: TriId) -> Result<[VertexId; 3], MeshError> {
        if self.is_triangle_alive(t) {
            Ok(self.tris[t])
        } else {
            Err(MeshError::NoSuchTriangle(t))
        }
    }

    fn ring_insert(&mut self, c: CornerId) {
        let v = self.corner_vertex(c);
        let head = self.ring_head[v];
        self.ring_next[ring_slot(c)] = head;
        self.ring_prev[ring_slot(c)] = None;
        if let Some(h) = head {
            self.ring_prev[ring_slot(h)] = Some(c);
        }
        self.ring_head[v] = Some(c);
    }

    fn ring_remove(&mut self, c: CornerId) {
        let v = self.corner_vertex(c);
        let (prev, next) = (self.ring_prev[ring_slot(c)], self.ring_next[ring_slot(c)]);
        match prev {
            Some(p) => self.ring_next[ring_slot(p)] = next,
            None => self.ring_head[v] = next,
        }
        if let Some(n) = next {
            self.ring_prev[ring_slot(n)] = prev;
        }
        self.ring_next[ring_slot(c)] = None;
        self.ring_prev[ring_slot(c)] = None;
    }
}

fn check_count(what: &'static str, count: usize) -> Result<(), MeshError> {
    if count > MAX_INDEX as usize {
        Err(MeshError::TooLarge { what, count })
    } else {
        Ok(())
    }
}

/// Iterator over the front corners at a vertex (see [`LabeledMesh::vertex_corners`]).
pub struct VertexCorners<'a> {
    mesh: &'a LabeledMesh,
    at: Option<CornerId>,
    budget: usize,
}

impl Iterator for VertexCorners<'_> {
    type Item = CornerId;
    #[inline]
    fn next(&mut self) -> Option<CornerId> {
        let c = self.at?;
        // The ring is acyclic by construction; the budget only guards against corruption.
        self.budget = self.budget.checked_sub(1)?;
        self.at = self.mesh.ring_next[ring_slot(c)];
        Some(c)
    }
}

/// Iterator around an edge (see [`LabeledMesh::radial_corners`]).
pub struct RadialCorners<'a> {
    mesh: &'a LabeledMesh,
    start: CornerId,
    at: Option<CornerId>,
    budget: usize,
}

impl Iterator for RadialCorners<'_> {
    type Item = CornerId;
    fn next(&mut self) -> Option<CornerId> {
        let c = self.at?;
        self.budget = self.budget.checked_sub(1)?;
        self.at = self
            .mesh
            .opposite(c)
            .map(CornerId::dual)
            .filter(|&n| n != self.start);
        Some(c)
    }
}
