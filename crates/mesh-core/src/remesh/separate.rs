//! Vertex separation (T1 processes, Los Topos §5, Algorithm 2): pulling apart regions that
//! touch only at a vertex, so that every vertex ends regular.
//!
//! At an irregular vertex `v` (incomplete [`RegionGraph`]) each missing arc `{A, B}` is a
//! candidate. Its direction `d_AB` is the difference of the centroids of the one-ring
//! vertices incident to `A` and to `B`; its *strength* comes from a [`SeparationStrength`]
//! (the flow's divergence along `d`, or the area the separation saves). Candidates over all
//! irregular vertices are found in parallel, sorted by strength (strongest first, so the
//! outcome depends on the physics, not on vertex numbering), re-evaluated one by one and
//! committed serially. Separating `{A, B}` at `v`:
//! - `v` becomes `v_b = v − (ε/2)·d`, a new vertex `v_a = v + (ε/2)·d` is created, where
//!   `ε = separation_fraction ×` the mean length of `v`'s edges is the gap width;
//! - triangles with a side in `A` move to `v_a`, all others stay on `v_b` (the edit
//!   removes and re-adds every triangle at `v`, so the sides around all their edges are
//!   re-paired for the new positions);
//! - for each edge `vw` bounding `A`, if the labels outside `A`'s two triangles on it
//!   differ, a gap triangle `(v_a, v_b, w)` keeps those two materials apart; it is oriented
//!   so that each of its sides faces the wedge whose label it carries (its side facing the
//!   region outside the first triangle traverses the edge against that triangle's side).
//!
//! The region graphs of `v_a` and `v_b` have strictly fewer nodes than `v`'s, so iterating
//! (bounded by [`SeparationParams::max_iterations`]) reaches regular vertices.
//!
//! **Collision safety** belongs to the guard, as for every operation here. The [`Edit`]
//! expresses the separation as Los Topos' pseudo-motion: `v` moves to `v_b` (a
//! [`VertexMove`]) and `v_a` appears at `v` and moves to its end position (a [`NewVertex`]
//! with `start = v`), carrying `A`'s triangles; gap triangles are the sweep of the edges
//! `v_b w`. A CCD guard sweeps exactly that. Elements that start incident to `v` collide
//! trivially in such a sweep, so Los Topos adds static checks on the end state (the moved
//! triangles against all edges, their edges against all triangles) — what
//! [`super::StaticIntersectionGuard`] does — and, against tunnelling of tiny components,
//! a point-in-tetrahedron test of every vertex against the volume each moving triangle
//! sweeps (one vertex moves, so that volume is a tetrahedron built from the triangle's
//! start and end positions, both in the edit).

use glam::{DMat3, DVec3};
use rayon::prelude::*;

use crate::geometry::triangle_area;
use crate::ids::{CornerId, Label, VertexId};
use crate::mesh::LabeledMesh;

use super::attributes::{Blend, VertexAttributes};
use super::edit::{Edit, EditError, NewVertex, VertexMove, VertexRef, apply_edit};
use super::guard::EditGuard;
use super::region_graph::{RegionGraph, has_disk_fan};

/// How strongly the flow wants regions `A` and `B` at a vertex pulled apart along `d`
/// (unit, pointing from `B` towards `A`). Only positive strengths separate.
///
/// `proposal` is the separation that would be committed (see the module doc), so that
/// measures of the outcome, like [`AreaDecrease`], need not rebuild it.
pub trait SeparationStrength: Sync {
    /// The strength of separating at `v` along `d`.
    fn strength(&self, mesh: &LabeledMesh, v: VertexId, d: DVec3, proposal: &Edit) -> f64;
}

/// Any `Fn(mesh, v, d, proposal) -> f64` is a strength (handy for tests and one-off flows).
impl<F: Fn(&LabeledMesh, VertexId, DVec3, &Edit) -> f64 + Sync> SeparationStrength for F {
    fn strength(&self, mesh: &LabeledMesh, v: VertexId, d: DVec3, proposal: &Edit) -> f64 {
        self(mesh, v, d, proposal)
    }
}

/// Separation strength for ambient velocity fields (Los Topos §5): `d · (∇u d)`, how fast
/// the flow diverges along `d` at the vertex. `gradient(p)` returns the velocity gradient
/// `∂u_i/∂x_j` (row `i`, column `j`) at `p`, analytic or by finite differences.
#[derive(Clone, Copy, Debug)]
pub struct VelocityDivergence<F> {
    /// The velocity gradient at a point.
    pub gradient: F,
}

impl<F: Fn(DVec3) -> DMat3 + Sync> SeparationStrength for VelocityDivergence<F> {
    fn strength(&self, mesh: &LabeledMesh, v: VertexId, d: DVec3, _proposal: &Edit) -> f64 {
        d.dot((self.gradient)(mesh.position(v)) * d)
    }
}

/// Separation strength for mean-curvature flows (Los Topos §5): the surface area the
/// proposed separation removes (negative when it adds area).
#[derive(Clone, Copy, Debug, Default)]
pub struct AreaDecrease;

impl SeparationStrength for AreaDecrease {
    fn strength(&self, mesh: &LabeledMesh, _v: VertexId, _d: DVec3, proposal: &Edit) -> f64 {
        -edit_area_change(mesh, proposal)
    }
}

/// Options of [`separate_irregular_vertices`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SeparationParams {
    /// Gap width `|v_a − v_b|` as a fraction of the mean length of the vertex's edges.
    /// Default 0.1 (Los Topos: "typically 10 %").
    pub separation_fraction: f64,
    /// Bound on the find-sort-commit passes of Algorithm 2. Each pass strictly shrinks the
    /// region graphs it touches, so a handful suffices; default 16.
    pub max_iterations: usize,
}

impl Default for SeparationParams {
    fn default() -> Self {
        Self {
            separation_fraction: 0.1,
            max_iterations: 16,
        }
    }
}

/// What [`separate_irregular_vertices`] did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct SeparationReport {
    /// Separations committed.
    pub separations: usize,
    /// Find-sort-commit passes run.
    pub iterations: usize,
    /// Candidates (missing arcs with positive strength) found over all passes.
    pub candidates: usize,
    /// Candidates skipped at re-evaluation: the arc was gone or the strength was ≤ 0.
    pub skipped: usize,
    /// Separations the guard refused.
    pub vetoed: usize,
    /// Missing arcs this operation cannot resolve (no direction, a region met twice around
    /// one edge, an open edge), counted per pass.
    pub unseparable: usize,
    /// Irregular vertices left at the end.
    pub irregular_remaining: usize,
}

/// A missing arc worth separating, remembered by vertex, labels and direction: ids of the
/// local regions do not survive neighbouring edits, these do.
#[derive(Clone, Copy, Debug)]
struct Candidate {
    strength: f64,
    vertex: VertexId,
    labels: [Label; 2],
    direction: DVec3,
}

/// Why a missing arc cannot be separated.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Unseparable {
    /// The two one-ring centroids coincide.
    NoDirection,
    /// Region `A` occupies several wedges around one edge, or an edge is open: one gap
    /// triangle per edge cannot keep the materials apart.
    AmbiguousEdge,
    /// Exactly one gap triangle would be needed, leaving the edge `v_a v_b` open.
    LoneGap,
}

/// Buffers reused across vertices (one set per rayon task).
#[derive(Default)]
struct Scratch {
    graph: RegionGraph,
    edit: Edit,
    ring: Vec<VertexId>,
    walk: Vec<CornerId>,
    arcs: Vec<(usize, usize)>,
}

/// Separates irregular vertices until all are regular, no candidate has positive
/// strength, or `params.max_iterations` passes have run (Los Topos Algorithm 2). Each
/// separation is one [`Edit`] through [`apply_edit`]: `guard` may veto it, and `attrs`
/// of the new vertex copy the separated one's.
pub fn separate_irregular_vertices(
    mesh: &mut LabeledMesh,
    attrs: &mut VertexAttributes,
    guard: &mut dyn EditGuard,
    params: &SeparationParams,
    strength: &dyn SeparationStrength,
) -> SeparationReport {
    separate_irregular_vertices_in(mesh, attrs, guard, params, strength, None)
}

/// [`separate_irregular_vertices`] among the `only` vertices (increasing, each once;
/// `None`: every vertex), the work list of [`super::improve_in`]. `irregular_remaining`
/// then counts the irregular vertices among them.
pub fn separate_irregular_vertices_in(
    mesh: &mut LabeledMesh,
    attrs: &mut VertexAttributes,
    guard: &mut dyn EditGuard,
    params: &SeparationParams,
    strength: &dyn SeparationStrength,
    only: Option<&[VertexId]>,
) -> SeparationReport {
    let mut report = SeparationReport::default();
    let mut scratch = Scratch::default();
    let mut scanned_current = false;
    for _ in 0..params.max_iterations {
        report.iterations += 1;
        let (mut candidates, irregular, unseparable) =
            find_candidates(mesh, params, strength, only);
        report.unseparable += unseparable;
        report.irregular_remaining = irregular;
        scanned_current = true;
        if candidates.is_empty() {
            break;
        }
        report.candidates += candidates.len();
        candidates.sort_by(|a, b| {
            b.strength
                .total_cmp(&a.strength)
                .then(a.vertex.cmp(&b.vertex))
                .then(a.labels.cmp(&b.labels))
        });
        let before = report.separations;
        for c in &candidates {
            commit_candidate(
                mesh,
                attrs,
                guard,
                params,
                strength,
                c,
                &mut scratch,
                &mut report,
            );
        }
        if report.separations == before {
            break;
        }
        scanned_current = false;
    }
    if !scanned_current {
        report.irregular_remaining = match only {
            None => super::region_graph::irregular_vertices(mesh).len(),
            Some(vertices) => super::region_graph::count_irregular(mesh, vertices),
        };
    }
    report
}

/// All candidates of the current mesh (unsorted), the number of irregular vertices and the
/// number of unseparable missing arcs. Vertices are examined in parallel.
fn find_candidates(
    mesh: &LabeledMesh,
    params: &SeparationParams,
    strength: &dyn SeparationStrength,
    only: Option<&[VertexId]>,
) -> (Vec<Candidate>, usize, usize) {
    let all: Vec<VertexId>;
    let vertices = match only {
        Some(vertices) => vertices,
        None => {
            all = mesh.vertices().collect();
            &all
        }
    };
    vertices
        .par_iter()
        .copied()
        .filter(|&v| mesh.is_vertex_alive(v) && !has_disk_fan(mesh, v))
        .map_init(Scratch::default, |s, v| {
            s.graph.build(mesh, v);
            if s.graph.is_complete() {
                return (Vec::new(), 0, 0);
            }
            let mut found = Vec::new();
            let mut unseparable = 0;
            if separable_vertex(mesh, &s.graph) {
                s.arcs.clear();
                s.arcs.extend(s.graph.missing_arcs());
                for i in 0..s.arcs.len() {
                    let (a, b) = orient(&s.graph, s.arcs[i]);
                    match propose(mesh, s, a, b, params.separation_fraction) {
                        Ok(d) => {
                            let t = strength.strength(mesh, v, d, &s.edit);
                            if t > 0.0 {
                                let labels = [s.graph.node_label(a), s.graph.node_label(b)];
                                found.push(Candidate {
                                    strength: t,
                                    vertex: v,
                                    labels,
                                    direction: d,
                                });
                            }
                        }
                        Err(_) => unseparable += 1,
                    }
                }
            }
            (found, 1, unseparable)
        })
        .reduce(
            || (Vec::new(), 0, 0),
            |mut x, y| {
                x.0.extend(y.0);
                (x.0, x.1 + y.1, x.2 + y.2)
            },
        )
}

/// Re-evaluates one candidate against the current mesh and commits it if still wanted.
#[allow(clippy::too_many_arguments)]
fn commit_candidate(
    mesh: &mut LabeledMesh,
    attrs: &mut VertexAttributes,
    guard: &mut dyn EditGuard,
    params: &SeparationParams,
    strength: &dyn SeparationStrength,
    c: &Candidate,
    s: &mut Scratch,
    report: &mut SeparationReport,
) {
    if !mesh.is_vertex_alive(c.vertex) {
        report.skipped += 1;
        return;
    }
    s.graph.build(mesh, c.vertex);
    if !separable_vertex(mesh, &s.graph) {
        report.skipped += 1;
        return;
    }
    // The same candidate now: a missing arc with the same labels, in the orientation
    // whose direction is closest to the one found.
    s.arcs.clear();
    s.arcs.extend(s.graph.missing_arcs());
    let mut best: Option<(f64, usize, usize)> = None;
    for i in 0..s.arcs.len() {
        let (x, y) = s.arcs[i];
        for (a, b) in [(x, y), (y, x)] {
            if [s.graph.node_label(a), s.graph.node_label(b)] != c.labels {
                continue;
            }
            let d = direction(mesh, &s.graph, a, b, &mut s.ring);
            if d != DVec3::ZERO && best.is_none_or(|(dot, _, _)| d.dot(c.direction) > dot) {
                best = Some((d.dot(c.direction), a, b));
            }
        }
    }
    let Some((_, a, b)) = best else {
        report.skipped += 1;
        return;
    };
    let d = match propose(mesh, s, a, b, params.separation_fraction) {
        Ok(d) => d,
        Err(_) => {
            report.unseparable += 1;
            return;
        }
    };
    let t = strength.strength(mesh, c.vertex, d, &s.edit);
    if t.is_nan() || t <= 0.0 {
        report.skipped += 1;
        return;
    }
    match apply_edit(mesh, attrs, guard, &s.edit) {
        Ok(_) => report.separations += 1,
        Err(EditError::Vetoed(_)) => report.vetoed += 1,
        // Malformed or capacity: the mesh is unchanged; report as unseparable.
        Err(_) => report.unseparable += 1,
    }
}

/// Vertices with collapsed triangles or inconsistent labels are left to T2 / validation.
fn separable_vertex(mesh: &LabeledMesh, graph: &RegionGraph) -> bool {
    !graph.has_collapsed_triangle(mesh) && graph.nodes().iter().all(|n| n.consistent)
}

/// Which of the two nodes moves to `v_a`: the one with fewer triangles (the smaller edit),
/// ties broken by label, then node index, so the choice is deterministic.
fn orient(graph: &RegionGraph, (x, y): (usize, usize)) -> (usize, usize) {
    let key = |n: usize| (graph.nodes()[n].triangles, graph.node_label(n), n);
    if key(x) <= key(y) { (x, y) } else { (y, x) }
}

/// Mean of the distinct one-ring vertices of the triangles with a side in `node`.
fn ring_centroid(
    mesh: &LabeledMesh,
    graph: &RegionGraph,
    node: usize,
    ring: &mut Vec<VertexId>,
) -> DVec3 {
    let Some(v) = graph.vertex() else {
        return DVec3::ZERO;
    };
    ring.clear();
    for (i, c) in graph.corners().iter().enumerate() {
        if graph.touches(i, node) {
            ring.extend(mesh.tri(c.tri()).into_iter().filter(|&w| w != v));
        }
    }
    ring.sort_unstable();
    ring.dedup();
    if ring.is_empty() {
        return DVec3::ZERO;
    }
    ring.iter().map(|&w| mesh.position(w)).sum::<DVec3>() / ring.len() as f64
}

/// The unit separation direction `d_AB` (from `B` towards `A`), or zero.
fn direction(
    mesh: &LabeledMesh,
    graph: &RegionGraph,
    a: usize,
    b: usize,
    ring: &mut Vec<VertexId>,
) -> DVec3 {
    let ca = ring_centroid(mesh, graph, a, ring);
    let cb = ring_centroid(mesh, graph, b, ring);
    (ca - cb).normalize_or_zero()
}

/// Builds into `s.edit` the separation of node `a` (to `v_a`) from node `b` at the graph's
/// vertex, returning the direction used.
fn propose(
    mesh: &LabeledMesh,
    s: &mut Scratch,
    a: usize,
    b: usize,
    fraction: f64,
) -> Result<DVec3, Unseparable> {
    let Scratch {
        graph,
        edit,
        ring,
        walk,
        ..
    } = s;
    let v = graph.vertex().ok_or(Unseparable::NoDirection)?;
    let d = direction(mesh, graph, a, b, ring);
    if d == DVec3::ZERO || !d.is_finite() {
        return Err(Unseparable::NoDirection);
    }
    let p = mesh.position(v);

    // Gap width from the mean length of the distinct edges at v; `ring` ends holding the
    // distinct neighbours of v.
    ring.clear();
    for c in graph.corners() {
        ring.extend(mesh.tri(c.tri()).into_iter().filter(|&w| w != v));
    }
    ring.sort_unstable();
    ring.dedup();
    let mean = ring
        .iter()
        .map(|&w| (mesh.position(w) - p).length())
        .sum::<f64>()
        / ring.len().max(1) as f64;
    let half = 0.5 * fraction * mean;

    edit.clear();
    edit.moves.push(VertexMove {
        vertex: v,
        end: p - half * d,
        blend: None,
    });
    edit.new_vertices.push(NewVertex {
        start: p,
        end: p + half * d,
        blend: Blend::copy(v),
    });
    // Every triangle at v is re-added — A's on v_a, the others on the moved v — so that
    // the mesh re-pairs the sides around all their edges for the new positions (a move
    // alone would leave radial orders at non-manifold edges as they were).
    let va = VertexRef::New(0);
    for (i, c) in graph.corners().iter().enumerate() {
        let t = c.tri();
        let to = if graph.touches(i, a) {
            va
        } else {
            VertexRef::Old(v)
        };
        edit.remove_tris.push(t);
        edit.add_tris.push((
            mesh.tri(t)
                .map(|x| if x == v { to } else { VertexRef::Old(x) }),
            mesh.labels(t),
        ));
    }

    // Gap triangles, one per edge vw bounding A where A's outside labels differ.
    let mut gaps = 0;
    for &w in ring.iter() {
        // A triangle of A on the edge vw, if any, and its corner opposite the edge.
        let start = graph.corners().iter().enumerate().find_map(|(i, c)| {
            let tri = mesh.tri(c.tri());
            (graph.touches(i, a) && tri.contains(&w))
                .then(|| tri.iter().position(|&x| x != v && x != w))
                .flatten()
                .map(|k| CornerId::of(c.tri(), crate::corner::Side::Front, k))
        });
        let Some(c0) = start else { continue };
        walk.clear();
        walk.extend(mesh.radial_corners(c0));
        let m = walk.len();
        let closed = walk
            .last()
            .and_then(|&c| mesh.opposite(c))
            .map(CornerId::dual)
            == Some(c0);
        if !closed || m < 2 {
            return Err(Unseparable::AmbiguousEdge);
        }
        // walk[j]'s side faces wedge j, which lies between triangles j and j+1.
        let mut a_wedges = 0;
        let mut k = 0;
        for (j, &c) in walk.iter().enumerate() {
            if graph.node_of_corner(c) == Some(a) {
                a_wedges += 1;
                k = j;
            }
        }
        let a_tris = walk
            .iter()
            .filter(|c| {
                graph
                    .local_index(c.tri())
                    .is_some_and(|i| graph.touches(i, a))
            })
            .count();
        if a_tris == m {
            continue; // the whole edge moves to v_a
        }
        if a_wedges != 1 {
            return Err(Unseparable::AmbiguousEdge);
        }
        // A's triangles on this edge are k and k+1; outside them lie wedges k−1 and k+1.
        let t1_out = walk[k].dual();
        let t2_out = walk[(k + 1) % m];
        let (l1, l2) = (mesh.corner_label(t1_out), mesh.corner_label(t2_out));
        if l1 == l2 {
            continue;
        }
        // The gap's side facing t1's outside wedge traverses the edge against t1's side.
        let runs_v_to_w = mesh.corner_vertex(t1_out.next()) == v;
        let verts = if runs_v_to_w {
            [va, VertexRef::Old(v), VertexRef::Old(w)]
        } else {
            [va, VertexRef::Old(w), VertexRef::Old(v)]
        };
        edit.add_tris.push((verts, [l1, l2]));
        gaps += 1;
    }
    if gaps == 1 {
        return Err(Unseparable::LoneGap);
    }
    Ok(d)
}

/// Area after minus area before of everything an edit touches: removed and added
/// triangles, and kept triangles at moved vertices (counted once each).
pub(crate) fn edit_area_change(mesh: &LabeledMesh, edit: &Edit) -> f64 {
    let mut change = 0.0;
    for &t in &edit.remove_tris {
        change -= triangle_area(&mesh.tri_positions(t));
    }
    for (verts, _) in &edit.add_tris {
        change += triangle_area(&verts.map(|r| edit.end_position(mesh, r)));
    }
    for (i, m) in edit.moves.iter().enumerate() {
        for t in mesh.vertex_triangles(m.vertex) {
            let tri = mesh.tri(t);
            let first_mover = edit.moves.iter().position(|n| tri.contains(&n.vertex));
            if edit.remove_tris.contains(&t) || first_mover != Some(i) {
                continue;
            }
            change -= triangle_area(&mesh.tri_positions(t));
            change += triangle_area(&tri.map(|x| edit.end_position(mesh, VertexRef::Old(x))));
        }
    }
    change
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::remesh::NoGuard;
    use crate::remesh::fixtures::bowtie_raw;
    use crate::remesh::region_graph::irregular_vertices;

    /// Two tetrahedra of label 1 in label 0 touching at vertex 0 (the second mirrored).
    fn bowtie() -> LabeledMesh {
        let (p, tris, labels) = bowtie_raw();
        LabeledMesh::from_raw(p, &tris, &labels).unwrap()
    }

    #[test]
    fn area_change_of_an_edit_counts_moved_and_replaced_triangles() {
        let mesh = bowtie();
        let v = VertexId::new(0);
        let mut edit = Edit::default();
        // Moving the shared vertex along +x by 0.5 changes the areas of all six triangles
        // at it; replacing triangle 3 by itself changes nothing.
        edit.moves.push(VertexMove {
            vertex: v,
            end: DVec3::new(0.5, 0.0, 0.0),
            blend: None,
        });
        edit.remove_tris.push(crate::ids::TriId::new(3));
        edit.add_tris.push((
            [1, 2, 3].map(|i| VertexRef::Old(VertexId::new(i))),
            [Label::new(0), Label::new(1)],
        ));
        let expected: f64 = mesh
            .vertex_triangles(v)
            .map(|t| {
                let before = mesh.tri_positions(t);
                let after = mesh.tri(t).map(|w| {
                    if w == v {
                        DVec3::new(0.5, 0.0, 0.0)
                    } else {
                        mesh.position(w)
                    }
                });
                triangle_area(&after) - triangle_area(&before)
            })
            .sum();
        assert!((edit_area_change(&mesh, &edit) - expected).abs() < 1e-12);
        assert!(
            expected.abs() > 0.1,
            "the test must move something: {expected}"
        );
    }

    #[test]
    fn separation_subsumes_pinching_and_copies_attributes() {
        let mut mesh = bowtie();
        let mut attrs = VertexAttributes::zeros(&mesh, 1);
        attrs.get_mut(VertexId::new(0))[0] = 3.5;
        let params = SeparationParams::default();
        let report = separate_irregular_vertices(
            &mut mesh,
            &mut attrs,
            &mut NoGuard,
            &params,
            &AreaDecrease,
        );
        // Four missing arcs at the touching vertex; one separation resolves all of them and
        // needs no gap triangle (each lobe's outside is one material).
        assert_eq!(report.separations, 1, "{report:?}");
        assert_eq!(report.irregular_remaining, 0);
        assert!(irregular_vertices(&mesh).is_empty());
        assert_eq!(mesh.num_triangles(), 8);
        assert_eq!(mesh.num_vertices(), 8);
        let copy = VertexId::new(7);
        assert_eq!(attrs.get(copy)[0], 3.5);
        // The copies moved apart along the line between the lobes, by 10 % of the mean
        // edge length (1) in total.
        let gap = mesh.position(copy) - mesh.position(VertexId::new(0));
        assert!((gap.length() - 0.1).abs() < 1e-12, "{gap}");
    }

    #[test]
    fn velocity_divergence_is_the_directional_stretch() {
        let mesh = bowtie();
        let flow = VelocityDivergence {
            gradient: |p: DVec3| DMat3::from_diagonal(DVec3::new(2.0, -1.0, 0.0) + p),
        };
        let v = VertexId::new(1); // at +x: gradient diag(3, −1, 0)
        let edit = Edit::default();
        assert!((flow.strength(&mesh, v, DVec3::X, &edit) - 3.0).abs() < 1e-15);
        assert!((flow.strength(&mesh, v, DVec3::Y, &edit) + 1.0).abs() < 1e-15);
        let d = DVec3::new(1.0, 1.0, 0.0).normalize();
        assert!((flow.strength(&mesh, v, d, &edit) - 1.0).abs() < 1e-12);
    }
}
