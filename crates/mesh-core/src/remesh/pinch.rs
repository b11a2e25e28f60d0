//! Pinching singular vertices (El Topo §3.6): a vertex whose incident triangles fall into
//! several components — joined to each other only at the vertex, never through an edge at
//! it — is duplicated once per component.
//!
//! Why: two lobes touching at a point share a vertex but no surface; keeping them glued
//! there locks their motion and confuses every operation that assumes a vertex's
//! triangles form one fan. After a T2 removal or a separation such contacts are common.
//! Each copy is moved a little ([`PINCH_PULL_FRACTION`] of the way) towards the centroid
//! of its component, so that no two vertices coincide, which collision detection cannot
//! handle. The first component (in triangle-id order) keeps the original vertex; the others
//! get new vertices whose attributes copy it. Each pinch is one [`Edit`] through
//! [`apply_edit`]: the original moves, the copies appear at the vertex and move off — the
//! pseudo-motion a collision guard checks.

use glam::DVec3;
use rayon::prelude::*;

use crate::ids::{TriId, VertexId};
use crate::mesh::LabeledMesh;

use super::attributes::{Blend, VertexAttributes};
use super::edit::{Edit, NewVertex, VertexMove, VertexRef, apply_edit};
use super::guard::EditGuard;
use super::region_graph::has_disk_fan;
use crate::union_find::{find, union};

/// How far each copy of a pinched vertex moves towards its component's centroid, as a
/// fraction of the distance: far enough to separate the copies beyond rounding, close
/// enough to leave the shape unchanged for any purpose.
pub const PINCH_PULL_FRACTION: f64 = 0.01;

/// The triangles at one vertex and their components (reusable buffers).
#[derive(Clone, Debug, Default)]
struct Fan {
    /// Incident triangles, sorted, each once.
    tris: Vec<TriId>,
    /// Component of each triangle (numbered by first appearance).
    component: Vec<u32>,
    components: usize,
    collapsed: bool,
    /// (neighbour, local triangle) incidences, and the union-find forest.
    links: Vec<(VertexId, u32)>,
    parent: Vec<u32>,
}

impl Fan {
    fn build(&mut self, mesh: &LabeledMesh, v: VertexId) {
        self.tris.clear();
        self.tris.extend(mesh.vertex_triangles(v));
        self.tris.sort_unstable();
        self.tris.dedup();
        self.links.clear();
        self.collapsed = false;
        for (i, &t) in self.tris.iter().enumerate() {
            let [a, b, c] = mesh.tri(t);
            self.collapsed |= a == b || b == c || c == a;
            self.links.extend(
                mesh.tri(t)
                    .into_iter()
                    .filter(|&w| w != v)
                    .map(|w| (w, i as u32)),
            );
        }
        // Triangles sharing a neighbour w share the edge vw.
        self.links.sort_unstable();
        self.parent.clear();
        self.parent.extend(0..self.tris.len() as u32);
        for pair in self.links.windows(2) {
            if pair[0].0 == pair[1].0 {
                union(&mut self.parent, pair[0].1, pair[1].1);
            }
        }
        self.component.clear();
        self.component.resize(self.tris.len(), u32::MAX);
        self.components = 0;
        for i in 0..self.tris.len() {
            let root = find(&mut self.parent, i as u32) as usize;
            if self.component[root] == u32::MAX {
                self.component[root] = self.components as u32;
                self.components += 1;
            }
            self.component[i] = self.component[root];
        }
    }

    /// True when the vertex should be pinched (collapsed triangles are T2's business).
    fn is_singular(&self) -> bool {
        self.components > 1 && !self.collapsed
    }
}

/// Live vertices whose incident triangles form more than one edge-connected component,
/// in increasing id order (found in parallel).
pub fn singular_vertices(mesh: &LabeledMesh) -> Vec<VertexId> {
    singular_vertices_in(mesh, None)
}

/// [`singular_vertices`] among `only` (increasing, each once; `None`: every vertex).
fn singular_vertices_in(mesh: &LabeledMesh, only: Option<&[VertexId]>) -> Vec<VertexId> {
    let singular = |fan: &mut Fan, v: VertexId| {
        if !mesh.is_vertex_alive(v) || has_disk_fan(mesh, v) {
            return None;
        }
        fan.build(mesh, v);
        fan.is_singular().then_some(v)
    };
    match only {
        None => (0..mesh.vertex_capacity() as u32)
            .into_par_iter()
            .map(VertexId::new)
            .map_init(Fan::default, singular)
            .flatten()
            .collect(),
        Some(vertices) => vertices
            .par_iter()
            .with_min_len(64)
            .map_init(Fan::default, |fan, &v| singular(fan, v))
            .flatten()
            .collect(),
    }
}

/// Duplicates every singular vertex once per component of its triangles (see the module
/// doc). Returns the number of vertices pinched (edits applied; vetoed ones are skipped).
pub fn pinch_singular_vertices(
    mesh: &mut LabeledMesh,
    attrs: &mut VertexAttributes,
    guard: &mut dyn EditGuard,
) -> usize {
    pinch_singular_vertices_in(mesh, attrs, guard, None)
}

/// [`pinch_singular_vertices`] among the `only` vertices (`None`: every vertex), the work
/// list of [`super::improve_in`].
pub fn pinch_singular_vertices_in(
    mesh: &mut LabeledMesh,
    attrs: &mut VertexAttributes,
    guard: &mut dyn EditGuard,
    only: Option<&[VertexId]>,
) -> usize {
    let mut fan = Fan::default();
    let mut edit = Edit::default();
    let mut centroids: Vec<(DVec3, f64)> = Vec::new();
    let mut pinched = 0;
    for v in singular_vertices_in(mesh, only) {
        // Pinching one vertex never changes another's fan, but rebuild to stay honest.
        fan.build(mesh, v);
        if !fan.is_singular() {
            continue;
        }
        centroids.clear();
        centroids.resize(fan.components, (DVec3::ZERO, 0.0));
        for (i, &t) in fan.tris.iter().enumerate() {
            let [a, b, c] = mesh.tri_positions(t);
            let entry = &mut centroids[fan.component[i] as usize];
            entry.0 += (a + b + c) / 3.0;
            entry.1 += 1.0;
        }
        let p = mesh.position(v);
        let pulled = |k: usize| {
            let (sum, n) = centroids[k];
            p + PINCH_PULL_FRACTION * (sum / n - p)
        };
        edit.clear();
        edit.moves.push(VertexMove {
            vertex: v,
            end: pulled(0),
            blend: None,
        });
        for k in 1..fan.components {
            edit.new_vertices.push(NewVertex {
                start: p,
                end: pulled(k),
                blend: Blend::copy(v),
            });
        }
        // Every triangle at v is re-added (the first component's on the moved v) so the
        // mesh re-pairs the sides around their edges for the new positions.
        for (i, &t) in fan.tris.iter().enumerate() {
            let copy = match fan.component[i] {
                0 => VertexRef::Old(v),
                k => VertexRef::New(k - 1),
            };
            edit.remove_tris.push(t);
            edit.add_tris.push((
                mesh.tri(t)
                    .map(|x| if x == v { copy } else { VertexRef::Old(x) }),
                mesh.labels(t),
            ));
        }
        if apply_edit(mesh, attrs, guard, &edit).is_ok() {
            pinched += 1;
        }
    }
    pinched
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::remesh::NoGuard;
    use crate::remesh::fixtures::bowtie_raw;

    /// Two tetrahedra of label 1 in label 0 sharing vertex 0, the second mirrored.
    fn bowtie() -> LabeledMesh {
        let (p, tris, labels) = bowtie_raw();
        LabeledMesh::from_raw(p, &tris, &labels).unwrap()
    }

    #[test]
    fn bowtie_vertex_is_split_and_attributes_copied() {
        let mut mesh = bowtie();
        assert_eq!(singular_vertices(&mesh), vec![VertexId::new(0)]);
        let mut attrs = VertexAttributes::zeros(&mesh, 2);
        attrs
            .get_mut(VertexId::new(0))
            .copy_from_slice(&[4.0, -2.0]);
        assert_eq!(
            pinch_singular_vertices(&mut mesh, &mut attrs, &mut NoGuard),
            1
        );
        assert_eq!(mesh.num_vertices(), 8);
        assert!(singular_vertices(&mesh).is_empty());
        let copy = VertexId::new(7);
        assert_eq!(attrs.get(copy), &[4.0, -2.0]);
        // The original keeps the first tetrahedron (triangles 0..3), the copy the second.
        let v0 = VertexId::new(0);
        assert_eq!(mesh.vertex_triangles(v0).count(), 3);
        assert_eq!(mesh.vertex_triangles(copy).count(), 3);
        for t in mesh.vertex_triangles(copy) {
            assert!(mesh.tri(t).iter().all(|w| [4, 5, 6, 7].contains(&w.raw())));
        }
        // Each copy moved a little into its own tetrahedron.
        let (p0, p7) = (mesh.position(v0), mesh.position(copy));
        assert!(p0.min_element() > 0.0 && p0.length() < 0.01, "{p0}");
        assert!(p7.max_element() < 0.0 && p7.length() < 0.01, "{p7}");
    }

    #[test]
    fn pinching_is_local_and_idempotent() {
        let mut mesh = bowtie();
        let before = mesh.to_raw();
        pinch_singular_vertices(&mut mesh, &mut VertexAttributes::none(), &mut NoGuard);
        // Only vertex 0 changed; pinching twice changes nothing more.
        let after = mesh.to_raw();
        assert_eq!(before.0[1..7], after.0[1..7]);
        let again = pinch_singular_vertices(&mut mesh, &mut VertexAttributes::none(), &mut NoGuard);
        assert_eq!(again, 0);
        assert_eq!(mesh.to_raw(), after);
    }

    /// A vertex the disk-fan shortcut skips has one component: the shortcut never hides a
    /// vertex to pinch.
    #[test]
    fn disk_fans_are_one_component() {
        let mut fan = Fan::default();
        for mesh in crate::remesh::region_graph::tests::disk_fan_meshes() {
            for v in mesh.vertices() {
                fan.build(&mesh, v);
                if has_disk_fan(&mesh, v) {
                    assert_eq!(fan.components, 1, "{v}");
                }
            }
            assert!(
                singular_vertices(&mesh)
                    .iter()
                    .all(|&v| !has_disk_fan(&mesh, v))
            );
        }
        assert_eq!(singular_vertices(&bowtie()), vec![VertexId::new(0)]);
    }
}
