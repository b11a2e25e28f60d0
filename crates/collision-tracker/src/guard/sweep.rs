//! The checks of the pseudo-motion: CCD of every swept triangle against the static rest of
//! the mesh and against the other swept triangles, and the exact point-in-tetrahedron tests
//! (Los Topos §5's tunnelling test, El Topo §3.5.2's flip test).

use glam::DVec3;
use mesh_core::TriangleIndex;
use mesh_core::broadphase::Aabb;
use mesh_core::predicates::{Sign, orient3d};
use mesh_core::remesh::{Edit, VertexRef};
use mesh_core::{LabeledMesh, Stamps, TriId};

use super::motion::{Motion, Swept};
use crate::ccd::{CcdOptions, ccd_edge_edge_with, ccd_vertex_triangle_with};
use crate::proximity::{proximity_edge_edge, proximity_vertex_triangle};

/// Why the sweep refused an edit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Hit {
    VertexTriangle,
    EdgeEdge,
    Tunnel,
    FlipVolume,
    Proximity,
}

/// A static triangle near a swept one: keys and positions.
type Near = ([u32; 3], [DVec3; 3]);

/// Reusable buffers of the sweep.
#[derive(Debug, Default)]
pub(crate) struct Scratch {
    candidates: Vec<TriId>,
    /// The static rest near a whole edit, with boxes ([`gather_pool`]).
    pool: Vec<(Near, Aabb)>,
    /// The box the pool was gathered for, for the edit being checked (a later check of the
    /// same edit whose boxes lie inside it reuses the pool).
    pool_bounds: Option<Aabb>,
    /// The pool's distinct vertices, and distinct edges with boxes (in no fixed order:
    /// every check over them asks whether *any* element hits).
    pool_vertices: Vec<(u32, DVec3)>,
    pool_edges: Vec<([u32; 2], [DVec3; 2], Aabb)>,
    /// Per vertex id, pooled in this gather: one look tells a repeat, where sorting the
    /// pool's vertices and edges to drop repeats was 45 % of gathering.
    pooled: Stamps,
    /// Per triangle slot, reported by this gather's index query (likewise).
    queried: Stamps,
    /// Every pooled triangle's edges as `(packed ends, index into edge_ends)`, sorted to
    /// find the distinct ones (small entries: sorting the edges with their ends and boxes
    /// moved six times the bytes).
    edge_keys: Vec<(u64, u32)>,
    edge_ends: Vec<([u32; 2], [DVec3; 2])>,
    near: Vec<Near>,
    vertices: Vec<(u32, DVec3)>,
    edges: Vec<([u32; 2], [DVec3; 2])>,
    /// The distinct moving vertices and moving edges of the edit being swept ([`movers`]).
    movers: Vec<Mover>,
    moving_edges: Vec<MovingEdge>,
    /// CCD queries run (statistics).
    pub queries: u64,
}

/// The static rest near `bounds`: live triangles the edit neither deletes nor moves, whose
/// current box overlaps `bounds`; fills `s.near`, and the distinct vertices and edges.
fn gather(
    s: &mut Scratch,
    index: &TriangleIndex,
    mesh: &LabeledMesh,
    edit: &Edit,
    motion: &Motion,
    bounds: &Aabb,
) {
    gather_pool(s, index, mesh, edit, motion, bounds);
    select(s, bounds);
}

/// The static rest near `bounds` into `s.pool`, with each triangle's box, and its distinct
/// vertices and edges: one index query for a whole edit, which [`select`] then narrows per
/// swept triangle.
fn gather_pool(
    s: &mut Scratch,
    index: &TriangleIndex,
    mesh: &LabeledMesh,
    edit: &Edit,
    motion: &Motion,
    bounds: &Aabb,
) {
    s.pooled.next_pass(mesh.vertex_capacity());
    s.queried.next_pass(mesh.triangle_capacity());
    s.candidates.clear();
    // The index may report a triangle more than once; keep its first report.
    let (candidates, queried) = (&mut s.candidates, &mut s.queried);
    index.query(bounds, |t| {
        if queried.first_sight(t.idx()) {
            candidates.push(t);
        }
    });
    s.pool_bounds = Some(*bounds);
    s.pool.clear();
    s.pool_vertices.clear();
    s.pool_edges.clear();
    s.edge_keys.clear();
    s.edge_ends.clear();
    for &t in &s.candidates {
        if !mesh.is_triangle_alive(t) || edit.remove_tris.contains(&t) || motion.is_moved_kept(t) {
            continue;
        }
        let p = mesh.tri_positions(t);
        let b = Aabb::from_points(&p);
        if b.overlaps(bounds) {
            let key = mesh.tri(t).map(|v| v.raw());
            s.pool.push(((key, p), b));
            for k in 0..3 {
                if s.pooled.first_sight(key[k] as usize) {
                    s.pool_vertices.push((key[k], p[k]));
                }
                let (i, j) = (k, (k + 1) % 3);
                let (a, b) = if key[i] < key[j] { (i, j) } else { (j, i) };
                let packed = (u64::from(key[a]) << 32) | u64::from(key[b]);
                s.edge_keys.push((packed, s.edge_ends.len() as u32));
                s.edge_ends.push(([key[a], key[b]], [p[a], p[b]]));
            }
        }
    }
    s.edge_keys.sort_unstable_by_key(|e| e.0);
    s.edge_keys.dedup_by_key(|e| e.0);
    for &(_, i) in &s.edge_keys {
        let (key, ends) = s.edge_ends[i as usize];
        s.pool_edges.push((key, ends, Aabb::from_points(&ends)));
    }
}

/// The pooled triangles whose box overlaps `bounds` into `s.near`, and the pooled
/// vertices and edges that can meet something inside `bounds`: the vertices not
/// strictly outside it, the edges whose box overlaps it. (A static element outside a
/// swept triangle's box can meet it neither in CCD, whose swept-box test rejects it, nor in
/// the tunnelling test, whose tetrahedron lies in that box; an edit's neighbourhood pools
/// a hundred triangles, and sorting their elements again for each swept triangle cost
/// more than the tests.)
fn select(s: &mut Scratch, bounds: &Aabb) {
    select_vertices(s, bounds);
    select_triangles(s, bounds);
    select_edges(s, bounds);
}

/// [`select`]'s vertices only.
fn select_vertices(s: &mut Scratch, bounds: &Aabb) {
    let outside = |p: DVec3| p.cmplt(bounds.min).any() || p.cmpgt(bounds.max).any();
    s.vertices.clear();
    s.vertices.extend(
        s.pool_vertices
            .iter()
            .filter(|(_, p)| !outside(*p))
            .copied(),
    );
}

/// [`select`]'s triangles only.
fn select_triangles(s: &mut Scratch, bounds: &Aabb) {
    s.near.clear();
    s.near.extend(
        s.pool
            .iter()
            .filter(|(_, b)| b.overlaps(bounds))
            .map(|&(near, _)| near),
    );
}

/// [`select`]'s edges only.
fn select_edges(s: &mut Scratch, bounds: &Aabb) {
    s.edges.clear();
    s.edges.extend(
        s.pool_edges
            .iter()
            .filter(|(_, _, b)| b.overlaps(bounds))
            .map(|&(key, ends, _)| (key, ends)),
    );
}

/// The static elements near `bounds` that `pick` selects: from the edit's pool when it
/// has one, else from a query of their own (an edit of more than [`MAX_POOLED`] swept
/// triangles, rare, then queries the index once per swept triangle, moving vertex and
/// moving edge).
#[allow(clippy::too_many_arguments)]
fn nearby(
    s: &mut Scratch,
    index: &TriangleIndex,
    mesh: &LabeledMesh,
    edit: &Edit,
    motion: &Motion,
    pooled: bool,
    bounds: &Aabb,
    pick: fn(&mut Scratch, &Aabb),
) {
    if !pooled {
        gather_pool(s, index, mesh, edit, motion, bounds);
    }
    pick(s, bounds);
}

/// Swept triangles per edit up to which one index query with the box around them all
/// serves every one of them (an edit's triangles are one neighbourhood); a larger edit
/// queries per triangle, so that a spread-out one does not pool far more than it needs.
const MAX_POOLED: usize = 64;

const EDGES: [(usize, usize); 3] = [(0, 1), (1, 2), (2, 0)];

/// CCD of the pseudo-motion, then the swept-tetrahedron test. The pool is gathered for
/// the swept boxes grown by `margin`, so that [`check_proximity`] with that distance can
/// reuse it.
///
/// A pair's test depends only on the two elements, so each is run once: static vertices
/// against each swept triangle, each distinct moving vertex against the static triangles
/// near its path, each distinct moving edge against the static edges near its sweep.
/// (Tested per swept triangle instead, a smoothing move tested its vertex's path against
/// every static triangle once per triangle of its fan, about six times, and each edge of
/// the fan twice.) Static elements are selected by the box of the moving element's sweep,
/// grown by `margin`: CCD rejects exactly any pair whose swept boxes are disjoint, so the
/// verdict is that of testing every pooled element.
///
/// `proximity`: also run [`check_proximity`]'s test (distance `margin`) on the elements
/// selected for the sweep, for an edit that only moves vertices, whose swept triangles are
/// exactly the triangles that test looks at ([`Motion::moved_kept`]). Why: selecting the
/// static elements near each triangle a second time was most of that test on smoothing and
/// relaxation moves. Every vertex of such an edit is an old one, so a pair can only end
/// closer than it started if one of its elements moves: static vertices against each moved
/// triangle, the moving vertices against static triangles, the moving edges against
/// static edges, the same three kinds of pairs the sweep tests. A pair found too close is
/// reported only when the whole sweep is clean, as when the test ran after it.
#[allow(clippy::too_many_arguments)]
pub(crate) fn check_sweep(
    s: &mut Scratch,
    index: &TriangleIndex,
    mesh: &LabeledMesh,
    edit: &Edit,
    motion: &Motion,
    ccd: &CcdOptions,
    margin: f64,
    proximity: bool,
) -> Result<(), Hit> {
    debug_assert!(
        !proximity || (edit.only_moves() && motion.swept.len() == motion.moved_kept.len())
    );
    let mut too_close = false;
    let pooled = motion.swept.len() <= MAX_POOLED;
    if pooled {
        let all = motion
            .swept
            .iter()
            .fold(Aabb::EMPTY, |u, t| u.union(t.bounds()));
        gather_pool(s, index, mesh, edit, motion, &all.inflated(margin));
    } else {
        s.pool_bounds = None;
    }
    let select_near = |s: &mut Scratch, bounds: &Aabb, pick| {
        nearby(s, index, mesh, edit, motion, pooled, bounds, pick);
    };
    for (i, t) in motion.swept.iter().enumerate() {
        let bounds = t.bounds().inflated(margin);
        select_near(s, &bounds, select_vertices);
        // Static vertices against the moving triangle.
        for &(k, p) in &s.vertices {
            if t.has(k) {
                continue;
            }
            s.queries += 1;
            if ccd_vertex_triangle_with(
                [p, t.x0[0], t.x0[1], t.x0[2]],
                [p, t.x1[0], t.x1[1], t.x1[2]],
                ccd,
            )
            .is_some()
            {
                return Err(Hit::VertexTriangle);
            }
        }
        // Moving against moving.
        for u in &motion.swept[i + 1..] {
            check_swept_pair(s, t, u, ccd)?;
        }
        // Los Topos' tunnelling test: a triangle with one moving corner sweeps a
        // tetrahedron; no vertex may lie strictly inside it. (CCD already covers the
        // static vertices it does not share; this also covers the vertices that share a
        // key with it, e.g. the far side of a vertex separation, at their end positions.)
        if t.movers() == 1 {
            let k = (0..3).find(|&k| t.moving(k)).unwrap_or(0);
            let tet = [t.x0[0], t.x0[1], t.x0[2], t.x1[k]];
            // The box test first: nearly every vertex of the edit is outside the
            // tetrahedron's box, and the exact test costs five orientations.
            let bounds = Aabb::from_points(&tet);
            let outside = |p: DVec3| p.cmplt(bounds.min).any() || p.cmpgt(bounds.max).any();
            let inside =
                |key: u32, p: DVec3| !t.has(key) && !outside(p) && strictly_inside(&tet, p);
            if s.vertices.iter().any(|&(key, p)| inside(key, p))
                || motion
                    .swept
                    .iter()
                    .any(|u| (0..3).any(|j| inside(u.key[j], u.x1[j])))
            {
                return Err(Hit::Tunnel);
            }
        }
        if proximity && !too_close {
            too_close = s.vertices.iter().any(|&(k, p)| {
                !t.has(k) && vertex_triangle_too_close([p, p], [t.x0, t.x1], margin, false)
            });
        }
    }
    movers(motion, &mut s.movers, &mut s.moving_edges);
    // Moving vertices against static triangles.
    for m in 0..s.movers.len() {
        let (key, x0, x1) = s.movers[m];
        let bounds = Aabb::from_points(&[x0, x1]).inflated(margin);
        select_near(s, &bounds, select_triangles);
        for &(skey, q) in &s.near {
            if skey.contains(&key) {
                continue;
            }
            s.queries += 1;
            if ccd_vertex_triangle_with([x0, q[0], q[1], q[2]], [x1, q[0], q[1], q[2]], ccd)
                .is_some()
            {
                return Err(Hit::VertexTriangle);
            }
        }
        if proximity && !too_close {
            too_close = s.near.iter().any(|&(skey, q)| {
                !skey.contains(&key) && vertex_triangle_too_close([x0, x1], [q, q], margin, false)
            });
        }
    }
    // Moving edges against static edges.
    for e in 0..s.moving_edges.len() {
        let (key, x0, x1) = s.moving_edges[e];
        let bounds = Aabb::from_points(&[x0[0], x0[1], x1[0], x1[1]]).inflated(margin);
        select_near(s, &bounds, select_edges);
        for &(skey, q) in &s.edges {
            if skey.contains(&key[0]) || skey.contains(&key[1]) {
                continue;
            }
            s.queries += 1;
            if ccd_edge_edge_with([x0[0], x0[1], q[0], q[1]], [x1[0], x1[1], q[0], q[1]], ccd)
                .is_some()
            {
                return Err(Hit::EdgeEdge);
            }
        }
        if proximity && !too_close {
            too_close = s.edges.iter().any(|&(skey, q)| {
                !skey.contains(&key[0])
                    && !skey.contains(&key[1])
                    && edge_edge_too_close([x0, x1], [q, q], margin, false)
            });
        }
    }
    if too_close {
        return Err(Hit::Proximity);
    }
    Ok(())
}

/// A moving vertex: key, start and end.
type Mover = (u32, DVec3, DVec3);
/// A moving edge: keys, ends at the start, ends at the end.
type MovingEdge = ([u32; 2], [DVec3; 2], [DVec3; 2]);

/// The distinct moving vertices and the distinct edges with a moving end of the swept
/// triangles. Distinct by key and trajectory: a key can move two ways in one edit (a
/// vertex born at another's place), and those are tested apart.
fn movers(motion: &Motion, vertices: &mut Vec<Mover>, edges: &mut Vec<MovingEdge>) {
    vertices.clear();
    edges.clear();
    for t in &motion.swept {
        vertices.extend(
            (0..3)
                .filter(|&k| t.moving(k))
                .map(|k| (t.key[k], t.x0[k], t.x1[k])),
        );
        for (a, b) in EDGES {
            if t.moving(a) || t.moving(b) {
                let (a, b) = if t.key[a] <= t.key[b] { (a, b) } else { (b, a) };
                edges.push(([t.key[a], t.key[b]], [t.x0[a], t.x0[b]], [t.x1[a], t.x1[b]]));
            }
        }
    }
    // Sorted by key alone (positions have no order): where one key moves two ways, two
    // equal entries can end up apart and both stay, which only repeats their tests.
    vertices.sort_unstable_by_key(|m| m.0);
    vertices.dedup();
    edges.sort_unstable_by_key(|e| e.0);
    edges.dedup();
}

/// True when the boxes of `a` and `b` come within `eps`: the cheap rejection in front of
/// each distance below (nearly every gathered element is a neighbour far from the changed
/// element but for a vertex it shares).
fn near(a: &[DVec3], b: &[DVec3], eps: f64) -> bool {
    Aabb::from_points(a)
        .inflated(eps)
        .overlaps(&Aabb::from_points(b))
}

/// The minimum-distance rule for a vertex `p` and a triangle `t`, each given at the start
/// and the end of the edit: closer than `eps` at the end and, unless an element is `new`,
/// closer than at the start (computed only for the rare pair close at the end).
fn vertex_triangle_too_close(p: [DVec3; 2], t: [[DVec3; 3]; 2], eps: f64, new: bool) -> bool {
    near(&[p[1]], &t[1], eps) && {
        let d1 = proximity_vertex_triangle(p[1], t[1]).distance;
        d1 < eps && (new || d1 < proximity_vertex_triangle(p[0], t[0]).distance)
    }
}

/// [`vertex_triangle_too_close`] for two edges `e` and `f`.
fn edge_edge_too_close(e: [[DVec3; 2]; 2], f: [[DVec3; 2]; 2], eps: f64, new: bool) -> bool {
    near(&e[1], &f[1], eps) && {
        let d1 = proximity_edge_edge(e[1][0], e[1][1], f[1][0], f[1][1]).distance;
        d1 < eps && (new || d1 < proximity_edge_edge(e[0][0], e[0][1], f[0][0], f[0][1]).distance)
    }
}

/// CCD between two swept triangles: vertices of each against the other, edges against
/// edges, skipping pairs that share a key and pairs where nothing moves.
fn check_swept_pair(s: &mut Scratch, t: &Swept, u: &Swept, ccd: &CcdOptions) -> Result<(), Hit> {
    if !t.bounds().overlaps(&u.bounds()) {
        return Ok(());
    }
    for (p, q) in [(t, u), (u, t)] {
        for k in 0..3 {
            if q.has(p.key[k]) || !(p.moving(k) || (0..3).any(|j| q.moving(j))) {
                continue;
            }
            s.queries += 1;
            if ccd_vertex_triangle_with(
                [p.x0[k], q.x0[0], q.x0[1], q.x0[2]],
                [p.x1[k], q.x1[0], q.x1[1], q.x1[2]],
                ccd,
            )
            .is_some()
            {
                return Err(Hit::VertexTriangle);
            }
        }
    }
    for (a, b) in EDGES {
        for (c, d) in EDGES {
            let shared = [t.key[a], t.key[b]]
                .iter()
                .any(|k| *k == u.key[c] || *k == u.key[d]);
            if shared || !(t.moving(a) || t.moving(b) || u.moving(c) || u.moving(d)) {
                continue;
            }
            s.queries += 1;
            if ccd_edge_edge_with(
                [t.x0[a], t.x0[b], u.x0[c], u.x0[d]],
                [t.x1[a], t.x1[b], u.x1[c], u.x1[d]],
                ccd,
            )
            .is_some()
            {
                return Err(Hit::EdgeEdge);
            }
        }
    }
    Ok(())
}

/// True when `p` lies strictly inside the tetrahedron (exact; a flat tetrahedron has no
/// inside).
fn strictly_inside(tet: &[DVec3; 4], p: DVec3) -> bool {
    let [a, b, c, d] = *tet;
    let o = orient3d(a, b, c, d);
    if o == Sign::Zero {
        return false;
    }
    // p is inside when replacing any one corner by p keeps the orientation.
    orient3d(p, b, c, d) == o
        && orient3d(a, p, c, d) == o
        && orient3d(a, b, p, d) == o
        && orient3d(a, b, c, p) == o
}

/// El Topo §3.5.2 for edits that move nothing but re-triangulate four vertices (flips):
/// the old and new triangles bound a tetrahedron, and no mesh vertex may lie inside it.
/// (An edge crossing it would cross a new triangle, which the end-state check rejects.)
pub(crate) fn check_retriangulation(
    s: &mut Scratch,
    index: &TriangleIndex,
    mesh: &LabeledMesh,
    edit: &Edit,
    motion: &Motion,
) -> Result<(), Hit> {
    s.pool_bounds = None;
    if edit.add_tris.is_empty() || edit.remove_tris.is_empty() || !edit.new_vertices.is_empty() {
        return Ok(());
    }
    let mut corners = [DVec3::ZERO; 4];
    let mut keys = [u32::MAX; 4];
    let mut n = 0;
    let refs = edit
        .remove_tris
        .iter()
        .flat_map(|&t| mesh.tri(t).map(VertexRef::Old))
        .chain(edit.add_tris.iter().flat_map(|(v, _)| *v));
    for r in refs {
        let key = motion.key(r);
        if keys[..n.min(4)].contains(&key) {
            continue;
        }
        if n < 4 {
            keys[n] = key;
            corners[n] = edit.end_position(mesh, r);
        }
        n += 1;
    }
    if n != 4 {
        return Ok(());
    }
    gather(s, index, mesh, edit, motion, &Aabb::from_points(&corners));
    if s.vertices
        .iter()
        .any(|&(k, p)| !keys.contains(&k) && strictly_inside(&corners, p))
    {
        return Err(Hit::FlipVolume);
    }
    Ok(())
}

/// The minimum-distance option: no non-adjacent pair (a changed triangle's vertex against a
/// static triangle, a static vertex against a changed triangle, a changed edge against a
/// static edge) may end closer than `eps` unless it started at least as close. Changed
/// triangles are the added ones and the kept ones that move; their start is the edit's
/// start positions. New elements (a created vertex, an edge or triangle the edit adds) get
/// no such allowance.
pub(crate) fn check_proximity(
    s: &mut Scratch,
    index: &TriangleIndex,
    mesh: &LabeledMesh,
    edit: &Edit,
    motion: &Motion,
    eps: f64,
) -> Result<(), Hit> {
    // Each changed triangle with whether the edit creates it.
    let changed = || {
        edit.add_tris.iter().map(|(v, _)| (*v, true)).chain(
            motion
                .moved_kept
                .iter()
                .map(|&t| (mesh.tri(t).map(VertexRef::Old), false)),
        )
    };
    let end_bounds = |verts: &[VertexRef; 3]| {
        Aabb::from_points(&verts.map(|r| edit.end_position(mesh, r))).inflated(eps)
    };
    // One pool for the whole edit, as in `check_sweep`: that check's own when it covers
    // this one's boxes (it was grown by `eps` for this), else a new one.
    let pooled = edit.add_tris.len() + motion.moved_kept.len() <= MAX_POOLED;
    if pooled {
        let all = changed().fold(Aabb::EMPTY, |u, (verts, _)| u.union(end_bounds(&verts)));
        let covered = s.pool_bounds.is_some_and(|p| {
            all.is_empty() || (p.min.cmple(all.min).all() && all.max.cmple(p.max).all())
        });
        if !covered {
            gather_pool(s, index, mesh, edit, motion, &all);
        }
    }
    for (verts, added) in changed() {
        if pooled {
            select(s, &end_bounds(&verts));
        } else {
            gather(s, index, mesh, edit, motion, &end_bounds(&verts));
        }
        proximity_of(s, mesh, edit, motion, verts, added, eps)?;
    }
    Ok(())
}

/// [`check_proximity`]'s test of one changed triangle (`verts`; `added` when the edit
/// creates it) against the elements selected in `s` (at least those whose box comes within
/// `eps` of its end box).
fn proximity_of(
    s: &Scratch,
    mesh: &LabeledMesh,
    edit: &Edit,
    motion: &Motion,
    verts: [VertexRef; 3],
    added: bool,
    eps: f64,
) -> Result<(), Hit> {
    let key = verts.map(|r| motion.key(r));
    let x1 = verts.map(|r| edit.end_position(mesh, r));
    let x0 = verts.map(|r| edit.start_position(mesh, r));
    // A pair that started at least as close is the flow's, not the edit's — but only
    // for elements that existed before the edit. A new element has no meaningful
    // start: a split vertex starts where it ends, and a flip's new diagonal (nothing
    // moves) would "start" exactly as close as it ends, so an edit that puts a new
    // vertex, edge or triangle within `eps` of another element is the edit's doing.
    let born = verts.map(|r| !matches!(r, VertexRef::Old(_)));
    let new_tri = added;
    let new_edge = |a: usize, b: usize| match (verts[a], verts[b]) {
        (VertexRef::Old(p), VertexRef::Old(q)) => {
            added && mesh.edge_triangles(p, q).next().is_none()
        }
        _ => true,
    };
    for &(k, p) in &s.vertices {
        if !key.contains(&k) && vertex_triangle_too_close([p, p], [x0, x1], eps, new_tri) {
            return Err(Hit::Proximity);
        }
    }
    for &(skey, q) in &s.near {
        for j in (0..3).filter(|&j| !skey.contains(&key[j])) {
            if vertex_triangle_too_close([x0[j], x1[j]], [q, q], eps, born[j]) {
                return Err(Hit::Proximity);
            }
        }
    }
    for (a, b) in EDGES {
        for &(ekey, q) in &s.edges {
            if ekey.contains(&key[a]) || ekey.contains(&key[b]) {
                continue;
            }
            let e = [[x0[a], x0[b]], [x1[a], x1[b]]];
            if edge_edge_too_close(e, [q, q], eps, new_edge(a, b)) {
                return Err(Hit::Proximity);
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use mesh_core::generators::icosphere;
    use mesh_core::remesh::VertexMove;
    use mesh_core::{Label, VertexId};
    use std::collections::BTreeSet;

    /// The pool holds every distinct vertex and edge of the static triangles whose box
    /// meets the bounds, each once, gather after gather on one scratch (a stale mark from
    /// an earlier gather would drop an element, and with it a collision).
    #[test]
    fn the_pool_holds_each_nearby_vertex_and_edge_once() {
        let mesh = icosphere(3, DVec3::ZERO, 1.0, [Label::new(1), Label::OUTSIDE]).unwrap();
        let mut index = TriangleIndex::new();
        index.refresh(&mesh);
        let mut s = Scratch::default();
        let mut motion = Motion::default();
        let vertices: Vec<VertexId> = mesh.vertices().collect();
        for (round, &v) in vertices.iter().step_by(7).enumerate() {
            let p = mesh.position(v);
            let edit = Edit {
                moves: vec![VertexMove {
                    vertex: v,
                    end: p * 1.01,
                    blend: None,
                }],
                ..Edit::default()
            };
            motion.build(&mesh, &edit);
            let bounds = Aabb::new(p, p).inflated(0.1 + 0.05 * (round % 4) as f64);
            gather_pool(&mut s, &index, &mesh, &edit, &motion, &bounds);

            let mut want_vertices = BTreeSet::new();
            let mut want_edges = BTreeSet::new();
            for t in mesh.triangles() {
                let q = mesh.tri_positions(t);
                if motion.is_moved_kept(t) || !Aabb::from_points(&q).overlaps(&bounds) {
                    continue;
                }
                let key = mesh.tri(t).map(|w| w.raw());
                want_vertices.extend(key);
                for k in 0..3 {
                    let (a, b) = (key[k], key[(k + 1) % 3]);
                    want_edges.insert([a.min(b), a.max(b)]);
                }
            }
            let got_vertices: Vec<u32> = s.pool_vertices.iter().map(|x| x.0).collect();
            let got_edges: Vec<[u32; 2]> = s.pool_edges.iter().map(|x| x.0).collect();
            assert!(!want_vertices.is_empty());
            assert_eq!(got_vertices.len(), want_vertices.len(), "a vertex twice");
            assert_eq!(
                got_vertices.iter().copied().collect::<BTreeSet<_>>(),
                want_vertices
            );
            assert_eq!(got_edges.len(), want_edges.len(), "an edge twice");
            assert_eq!(
                got_edges.iter().copied().collect::<BTreeSet<_>>(),
                want_edges
            );
            for &(k, q) in &s.pool_vertices {
                assert_eq!(q, mesh.position(VertexId::new(k)));
            }
            for &([a, b], ends, bounds) in &s.pool_edges {
                let at = |k: u32| mesh.position(VertexId::new(k));
                assert_eq!(ends, [at(a), at(b)]);
                assert_eq!(bounds, Aabb::from_points(&ends));
            }
        }
    }

    /// Every pair the sweep must test, over the whole static rest, without index or
    /// selection, each pair per swept triangle (as the sweep once ran them), and the
    /// minimum-distance rule on every corner and edge of each moved triangle, static ones
    /// included. `Some(true)`: the sweep collides; `Some(false)`: it is clean but ends too
    /// close; `None`: clean.
    fn brute_force(mesh: &LabeledMesh, motion: &Motion, eps: f64) -> Option<bool> {
        let ccd = CcdOptions::default();
        let vt = |x0: [DVec3; 4], x1: [DVec3; 4]| ccd_vertex_triangle_with(x0, x1, &ccd).is_some();
        let ee = |x0: [DVec3; 4], x1: [DVec3; 4]| ccd_edge_edge_with(x0, x1, &ccd).is_some();
        let rest: Vec<Near> = mesh
            .triangles()
            .filter(|&t| !motion.is_moved_kept(t))
            .map(|t| (mesh.tri(t).map(|v| v.raw()), mesh.tri_positions(t)))
            .collect();
        let mut close = false;
        for (i, t) in motion.swept.iter().enumerate() {
            let mut s = Scratch::default();
            for u in &motion.swept[i + 1..] {
                if check_swept_pair(&mut s, t, u, &ccd).is_err() {
                    return Some(true);
                }
            }
            let tet = (t.movers() == 1).then(|| {
                let k = (0..3).find(|&k| t.moving(k)).unwrap_or(0);
                [t.x0[0], t.x0[1], t.x0[2], t.x1[k]]
            });
            let in_tet =
                |k: u32, p: DVec3| !t.has(k) && tet.is_some_and(|tet| strictly_inside(&tet, p));
            if motion
                .swept
                .iter()
                .any(|u| (0..3).any(|j| in_tet(u.key[j], u.x1[j])))
            {
                return Some(true);
            }
            for &(key, q) in &rest {
                for k in 0..3 {
                    let (a, b) = (k, (k + 1) % 3);
                    if !t.has(key[k])
                        && (vt(
                            [q[k], t.x0[0], t.x0[1], t.x0[2]],
                            [q[k], t.x1[0], t.x1[1], t.x1[2]],
                        ) || in_tet(key[k], q[k]))
                    {
                        return Some(true);
                    }
                    if t.moving(k)
                        && !key.contains(&t.key[k])
                        && vt([t.x0[k], q[0], q[1], q[2]], [t.x1[k], q[0], q[1], q[2]])
                    {
                        return Some(true);
                    }
                    for (c, d) in EDGES {
                        let shared = [key[a], key[b]]
                            .iter()
                            .any(|&x| x == t.key[c] || x == t.key[d]);
                        if (t.moving(c) || t.moving(d))
                            && !shared
                            && ee(
                                [t.x0[c], t.x0[d], q[a], q[b]],
                                [t.x1[c], t.x1[d], q[a], q[b]],
                            )
                        {
                            return Some(true);
                        }
                    }
                    // The minimum distance, on every corner and edge of the moved triangle.
                    let p = q[k];
                    close |= !t.has(key[k])
                        && vertex_triangle_too_close([p, p], [t.x0, t.x1], eps, false);
                    close |= !key.contains(&t.key[k])
                        && vertex_triangle_too_close([t.x0[k], t.x1[k]], [q, q], eps, false);
                    for (c, d) in EDGES {
                        let shared = [key[a], key[b]]
                            .iter()
                            .any(|&x| x == t.key[c] || x == t.key[d]);
                        let e = [[t.x0[c], t.x0[d]], [t.x1[c], t.x1[d]]];
                        close |= !shared && edge_edge_too_close(e, [[q[a], q[b]]; 2], eps, false);
                    }
                }
            }
        }
        close.then_some(false)
    }

    /// The sweep tests each moving vertex and edge once, on the static elements its own
    /// sweep box selects from one pool, and the minimum distance only on pairs with a
    /// moving element: the verdict must be the brute force's on every edit. Random moves of
    /// one to three vertices of a sphere towards a small sphere 0.02 away, long and short,
    /// so that collisions, too-close ends and clean moves all occur (checked).
    #[test]
    fn the_sweep_decides_as_testing_every_pair_of_the_mesh() {
        use rand::{Rng, SeedableRng};
        let a = icosphere(2, DVec3::ZERO, 1.0, [Label::new(1), Label::OUTSIDE]).unwrap();
        let b = icosphere(
            2,
            DVec3::new(1.32, 0.0, 0.0),
            0.3,
            [Label::new(2), Label::OUTSIDE],
        )
        .unwrap();
        let on_a = a.vertex_capacity();
        let mesh = LabeledMesh::disjoint_union(&[a, b]).unwrap();
        let mut index = TriangleIndex::new();
        index.refresh(&mesh);
        let near_b: Vec<VertexId> = mesh
            .vertices()
            .filter(|&v| v.idx() < on_a && mesh.position(v).x > 0.6)
            .collect();
        assert!(near_b.len() > 10);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(19);
        let (mut s, mut motion) = (Scratch::default(), Motion::default());
        let mut seen = [0usize; 3];
        for round in 0..400 {
            let reach = [0.01, 0.06, 0.25][round % 3];
            let mut moves: Vec<VertexMove> = Vec::new();
            for _ in 0..rng.random_range(1..=3) {
                let v = near_b[rng.random_range(0..near_b.len())];
                if moves.iter().any(|m| m.vertex == v) {
                    continue;
                }
                let d = DVec3::new(
                    rng.random_range(0.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                );
                moves.push(VertexMove {
                    vertex: v,
                    end: mesh.position(v) + d * reach,
                    blend: None,
                });
            }
            let edit = Edit {
                moves,
                ..Edit::default()
            };
            motion.build(&mesh, &edit);
            let eps = 0.03;
            let got = check_sweep(
                &mut s,
                &index,
                &mesh,
                &edit,
                &motion,
                &CcdOptions::default(),
                eps,
                true,
            );
            let got = match got {
                Ok(()) => None,
                Err(Hit::Proximity) => Some(false),
                Err(_) => Some(true),
            };
            let want = brute_force(&mesh, &motion, eps);
            assert_eq!(got, want, "round {round}: {edit:?}");
            seen[match want {
                None => 0,
                Some(false) => 1,
                Some(true) => 2,
            }] += 1;
        }
        assert!(
            seen.iter().all(|&n| n >= 20),
            "clean, too close, colliding: {seen:?}"
        );
    }

    #[test]
    fn strictly_inside_is_exact_on_the_boundary() {
        let tet = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
        assert!(strictly_inside(&tet, DVec3::splat(0.1)));
        assert!(
            !strictly_inside(&tet, DVec3::new(0.2, 0.2, 0.0)),
            "on a face"
        );
        assert!(!strictly_inside(&tet, DVec3::splat(0.5)), "outside");
        let flat = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(1.0, 1.0, 0.0)];
        assert!(!strictly_inside(&flat, DVec3::new(0.2, 0.2, 0.0)));
        // Orientation of the corners does not matter.
        let rev = [DVec3::X, DVec3::ZERO, DVec3::Y, DVec3::Z];
        assert!(strictly_inside(&rev, DVec3::splat(0.1)));
    }
}
