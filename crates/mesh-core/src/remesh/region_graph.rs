//! The region graph of a vertex (Los Topos §5): which regions meet at a vertex, and which
//! of them share a triangle there.
//!
//! Glossary (Los Topos §5 definitions, read locally at a vertex `v`):
//! - **local region**: the sides of `v`'s incident triangles, grouped by connectivity
//!   through opposite pointers across the edges incident to `v`. For the side of corner `c`
//!   at `v`, those edges are the ones opposite `c.next()` (edge `{prev, v}`) and
//!   `c.prev()` (edge `{v, next}`); the opposite corner across either lies in the
//!   neighbouring side that faces the same wedge of space. Each group is one *node*.
//! - **arc**: nodes `A` and `B` are joined when some triangle at `v` has one side in `A`
//!   and the other in `B` — regions are incident *only if they share a triangle*; touching
//!   at `v` or along an edge is not enough.
//!
//! A vertex is **regular** exactly when its region graph is complete (a surface point, a
//! triple curve, a quadruple point — the Plateau configurations); every missing arc names a
//! pair of regions glued together only at `v`, which vertex separation pulls apart
//! ([`super::separate`]). Nodes are *local*: two nodes may carry the same label (two lobes
//! of one material pinched together at `v`), which is precisely the singular-vertex case.
//!
//! [`RegionGraph`] is a reusable buffer: [`RegionGraph::build`] allocates nothing once its
//! vectors have grown to the largest valence seen, so scanning every vertex costs a few
//! sorts of valence-sized arrays.

use rayon::prelude::*;

use crate::corner::Side;
use crate::ids::{CornerId, Label, TriId, VertexId};
use crate::mesh::LabeledMesh;
use crate::union_find::{find, union};

/// One local region at a vertex.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RegionNode {
    /// The material the region's sides face (the first side's label; see `consistent`).
    pub label: Label,
    /// Number of incident triangles with a side in this region.
    pub triangles: u32,
    /// False when the sides of this local region disagree on their label (an invalid mesh).
    pub consistent: bool,
}

/// The region graph of one vertex, rebuilt in place by [`RegionGraph::build`].
#[derive(Clone, Debug, Default)]
pub struct RegionGraph {
    vertex: Option<VertexId>,
    /// The front corner at `v` of each incident triangle, sorted by triangle id.
    corners: Vec<CornerId>,
    /// Union-find parents over local sides (`2·i + side`), then reused as roots.
    parent: Vec<u32>,
    /// Node of each local side (`2·i + side`).
    side_node: Vec<u32>,
    nodes: Vec<RegionNode>,
    /// `n × n` adjacency matrix of the nodes.
    adjacent: Vec<bool>,
    /// Some incident triangle has the vertex twice.
    repeats_vertex: bool,
}

impl RegionGraph {
    /// An empty graph; call [`RegionGraph::build`].
    pub fn new() -> Self {
        Self::default()
    }

    /// Rebuilds the graph for vertex `v` of `mesh`, reusing this graph's buffers.
    pub fn build(&mut self, mesh: &LabeledMesh, v: VertexId) {
        self.vertex = Some(v);
        self.corners.clear();
        self.corners.extend(mesh.vertex_corners(v));
        self.corners.sort_unstable_by_key(|c| c.tri());
        // A triangle with `v` twice is in the ring twice; keep one corner per triangle.
        let ring_len = self.corners.len();
        self.corners.dedup_by_key(|c| c.tri());
        self.repeats_vertex = self.corners.len() != ring_len;

        let k = self.corners.len();
        self.parent.clear();
        self.parent.extend(0..2 * k as u32);
        for i in 0..k {
            for side in [Side::Front, Side::Back] {
                let cs = self.side_corner(i, side);
                let s = (2 * i + side.index()) as u32;
                for e in [cs.next(), cs.prev()] {
                    let Some(o) = mesh.opposite(e) else { continue };
                    if let Some(j) = self.local_index(o.tri()) {
                        union(&mut self.parent, s, (2 * j + o.side().index()) as u32);
                    }
                }
            }
        }

        // Number the roots in order of first appearance: deterministic node ids. Each
        // root is the smallest side of its set, so it is numbered before its members.
        self.nodes.clear();
        self.side_node.clear();
        self.side_node.resize(2 * k, u32::MAX);
        for s in 0..2 * k {
            let root = find(&mut self.parent, s as u32) as usize;
            let label = mesh.corner_label(self.side_corner(s / 2, side_of(s)));
            if root == s {
                self.side_node[s] = self.nodes.len() as u32;
                self.nodes.push(RegionNode {
                    label,
                    triangles: 0,
                    consistent: true,
                });
            }
            let n = self.side_node[root];
            self.side_node[s] = n;
            let node = &mut self.nodes[n as usize];
            node.triangles += 1;
            node.consistent &= node.label == label;
        }

        let n = self.nodes.len();
        self.adjacent.clear();
        self.adjacent.resize(n * n, false);
        for i in 0..k {
            let (f, b) = (
                self.side_node[2 * i] as usize,
                self.side_node[2 * i + 1] as usize,
            );
            if f != b {
                self.adjacent[f * n + b] = true;
                self.adjacent[b * n + f] = true;
            }
        }
    }

    /// The vertex the graph was last built for.
    pub fn vertex(&self) -> Option<VertexId> {
        self.vertex
    }

    /// The local regions (nodes).
    pub fn nodes(&self) -> &[RegionNode] {
        &self.nodes
    }

    /// The label of node `n`.
    pub fn node_label(&self, n: usize) -> Label {
        self.nodes[n].label
    }

    /// True when nodes `a` and `b` share a triangle at the vertex.
    pub fn has_arc(&self, a: usize, b: usize) -> bool {
        self.adjacent[a * self.nodes.len() + b]
    }

    /// Pairs of nodes `(a, b)`, `a < b`, that share no triangle: the irregularities.
    pub fn missing_arcs(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        let n = self.nodes.len();
        (0..n)
            .flat_map(move |a| (a + 1..n).map(move |b| (a, b)))
            .filter(|&(a, b)| !self.has_arc(a, b))
    }

    /// True when every pair of nodes shares a triangle: the vertex is regular.
    pub fn is_complete(&self) -> bool {
        self.missing_arcs().next().is_none()
    }

    /// True when an incident triangle repeats a vertex (T2 removes those first; the graph
    /// of such a vertex is still built but its sides may be paired oddly). Checked on
    /// demand: the scan over all vertices only needs it at irregular ones.
    pub fn has_collapsed_triangle(&self, mesh: &LabeledMesh) -> bool {
        self.repeats_vertex
            || self.corners.iter().any(|&c| {
                let [a, b, d] = mesh.tri(c.tri());
                a == b || b == d || d == a
            })
    }

    /// The front corner at the vertex of each incident triangle, sorted by triangle id;
    /// position `i` here is the *local index* of that triangle.
    pub fn corners(&self) -> &[CornerId] {
        &self.corners
    }

    /// Local index of an incident triangle.
    pub fn local_index(&self, t: TriId) -> Option<usize> {
        // A linear scan beats bisection at the usual valence (about six).
        if self.corners.len() <= 16 {
            self.corners.iter().position(|c| c.tri() == t)
        } else {
            self.corners.binary_search_by_key(&t, |c| c.tri()).ok()
        }
    }

    /// Node of the given side of the incident triangle with local index `i`.
    pub fn side_node(&self, i: usize, side: Side) -> usize {
        self.side_node[2 * i + side.index()] as usize
    }

    /// Node of the side a corner lies on, if the corner's triangle is incident.
    pub fn node_of_corner(&self, c: CornerId) -> Option<usize> {
        self.local_index(c.tri())
            .map(|i| self.side_node(i, c.side()))
    }

    /// True when the incident triangle with local index `i` has a side in node `n`.
    pub fn touches(&self, i: usize, n: usize) -> bool {
        self.side_node(i, Side::Front) == n || self.side_node(i, Side::Back) == n
    }

    /// The corner at the vertex on the given side of local triangle `i`.
    fn side_corner(&self, i: usize, side: Side) -> CornerId {
        match side {
            Side::Front => self.corners[i],
            Side::Back => self.corners[i].dual(),
        }
    }
}

fn side_of(local_side: usize) -> Side {
    if local_side.is_multiple_of(2) {
        Side::Front
    } else {
        Side::Back
    }
}

/// True when the triangles at `v` form one disk: every edge at `v` has exactly two
/// triangles, and walking from triangle to triangle across those edges visits every
/// triangle at `v` before it comes back.
///
/// Why: such a vertex is regular (its region graph has two nodes, the disk's two sides,
/// joined by every triangle) and not singular (its triangles are one component), and
/// nearly every vertex of a mesh is one. The scans of vertex separation and pinching ask
/// this first and build a graph or fan only for the rest: building them at every vertex
/// of the work list was about 7 % of the grid backend's improvement (grid `spheres
/// --spheres 20`, profiled); this walk costs about a third of that.
///
/// Conservative: `false` for what it does not judge (under three triangles, a visited
/// triangle repeating a vertex), which callers then examine in full. At most one step per
/// triangle at `v`.
pub(crate) fn has_disk_fan(mesh: &LabeledMesh, v: VertexId) -> bool {
    let mut corners = mesh.vertex_corners(v);
    let Some(start) = corners.next() else {
        return false;
    };
    let k = 1 + corners.count();
    if k < 3 {
        return false;
    }
    let distinct = |t: TriId| {
        let [a, b, c] = mesh.tri(t);
        a != b && b != c && c != a
    };
    if !distinct(start.tri()) {
        return false;
    }
    // Leave each triangle across the edge at `v` opposite corner `leave`.
    let mut leave = start.next();
    for step in 1..=k {
        if !mesh.is_two_sided(leave) {
            return false;
        }
        let Some(far) = mesh.opposite(leave) else {
            return false;
        };
        // `far` is the next triangle's corner away from the edge just crossed; of its
        // other two corners one is at `v`, and the one that is not is opposite the edge
        // to cross next.
        let (at_v, next) = if mesh.corner_vertex(far.next()) == v {
            (far.next(), far.prev())
        } else if mesh.corner_vertex(far.prev()) == v {
            (far.prev(), far.next())
        } else {
            return false;
        };
        if at_v.tri() == start.tri() {
            return step == k;
        }
        if !distinct(at_v.tri()) {
            return false;
        }
        leave = next;
    }
    false
}

/// True when `v`'s region graph is complete (allocates one graph unless `v` has a
/// [disk fan](has_disk_fan); use [`RegionGraph`] directly in loops).
pub fn is_regular(mesh: &LabeledMesh, v: VertexId) -> bool {
    if has_disk_fan(mesh, v) {
        return true;
    }
    let mut graph = RegionGraph::new();
    graph.build(mesh, v);
    graph.is_complete()
}

/// Every live vertex whose region graph is incomplete, in increasing id order. Vertices
/// are examined in parallel, one reusable graph per rayon task.
pub fn irregular_vertices(mesh: &LabeledMesh) -> Vec<VertexId> {
    (0..mesh.vertex_capacity() as u32)
        .into_par_iter()
        .map(VertexId::new)
        .filter(|&v| mesh.is_vertex_alive(v) && !has_disk_fan(mesh, v))
        .map_init(RegionGraph::new, |graph, v| {
            graph.build(mesh, v);
            (!graph.is_complete()).then_some(v)
        })
        .flatten()
        .collect()
}

/// How many of `vertices` (live or not) are irregular, examined in parallel.
pub fn count_irregular(mesh: &LabeledMesh, vertices: &[VertexId]) -> usize {
    vertices
        .par_iter()
        .with_min_len(64)
        .filter(|&&v| mesh.is_vertex_alive(v) && !has_disk_fan(mesh, v))
        .map_init(RegionGraph::new, |graph, &v| {
            graph.build(mesh, v);
            usize::from(!graph.is_complete())
        })
        .sum()
}

#[cfg(test)]
pub(crate) mod tests {
    use glam::DVec3;

    use super::*;
    use crate::remesh::fixtures::bowtie_raw;

    /// A tetrahedron of label 1 in label 0, oriented so every front faces outwards.
    fn tetrahedron() -> LabeledMesh {
        let p = vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(0.0, 0.0, 1.0),
        ];
        let tris = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];
        LabeledMesh::from_raw(p, &tris, &[[0, 1]; 4]).unwrap()
    }

    #[test]
    fn manifold_vertex_has_two_joined_nodes() {
        let mesh = tetrahedron();
        let mut g = RegionGraph::new();
        for v in mesh.vertices() {
            g.build(&mesh, v);
            assert_eq!(g.nodes().len(), 2, "{v}");
            assert!(g.is_complete());
            let mut labels: Vec<u32> = g.nodes().iter().map(|n| n.label.raw()).collect();
            labels.sort_unstable();
            assert_eq!(labels, [0, 1]);
            assert!(g.nodes().iter().all(|n| n.triangles == 3 && n.consistent));
        }
        assert!(irregular_vertices(&mesh).is_empty());
    }

    #[test]
    fn two_tetrahedra_touching_at_a_vertex_are_four_nodes() {
        // The tetrahedron above and its mirror image through the origin, sharing vertex 0.
        let (p, tris, labels) = bowtie_raw();
        let mesh = LabeledMesh::from_raw(p, &tris, &labels).unwrap();
        let mut g = RegionGraph::new();
        g.build(&mesh, VertexId::new(0));
        assert_eq!(g.nodes().len(), 4);
        // Each inside is joined to its own outside only.
        assert_eq!(g.missing_arcs().count(), 4);
        assert!(!g.is_complete());
        assert_eq!(irregular_vertices(&mesh), vec![VertexId::new(0)]);
        assert!(is_regular(&mesh, VertexId::new(1)));
    }

    /// The meshes the disk-fan shortcut is checked on: a closed sphere (every vertex a
    /// disk), a double bubble and a small foam (triple curves and their corners, where
    /// it must answer no), and the bowtie (a pinch).
    pub(crate) fn disk_fan_meshes() -> Vec<LabeledMesh> {
        let (p, tris, labels) = bowtie_raw();
        vec![
            crate::generators::icosphere(2, DVec3::ZERO, 1.0, [Label::new(0), Label::new(1)])
                .unwrap(),
            crate::generators::double_bubble(1.0, 12).unwrap(),
            crate::generators::voronoi_foam(6, 3, DVec3::ZERO, DVec3::ONE).unwrap(),
            LabeledMesh::from_raw(p, &tris, &labels).unwrap(),
        ]
    }

    /// Where the shortcut says "disk", the full graph has the disk's two sides as its
    /// nodes and is complete; it says so at every vertex of a closed manifold surface and
    /// never at a vertex on a triple curve or at the bowtie's pinch.
    #[test]
    fn disk_fans_are_regular_and_found_on_manifold_sheets() {
        let mut g = RegionGraph::new();
        let mut disks = [0usize; 4];
        for (i, mesh) in disk_fan_meshes().iter().enumerate() {
            for v in mesh.vertices() {
                g.build(mesh, v);
                let on_curve = mesh
                    .vertex_corners(v)
                    .any(|c| !mesh.is_two_sided(c.next()) || !mesh.is_two_sided(c.prev()));
                if has_disk_fan(mesh, v) {
                    disks[i] += 1;
                    assert!(!on_curve, "mesh {i}: {v} is on a non-manifold edge");
                    assert_eq!(g.nodes().len(), 2, "mesh {i}: {v}");
                    assert!(g.is_complete(), "mesh {i}: {v}");
                } else {
                    assert!(i > 0, "every vertex of the sphere is a disk: {v}");
                }
            }
            if i == 1 || i == 2 {
                assert!(disks[i] > 0 && disks[i] < mesh.num_vertices(), "mesh {i}");
            }
        }
        assert_eq!(disks[0], disk_fan_meshes()[0].num_vertices());
        let bowtie = &disk_fan_meshes()[3];
        assert!(!has_disk_fan(bowtie, VertexId::new(0)));
        assert!(has_disk_fan(bowtie, VertexId::new(1)));
    }
}
