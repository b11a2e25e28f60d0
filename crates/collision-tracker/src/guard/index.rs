//! The guard's broad phase: which triangles of the mesh lie near a swept box.
//!
//! A BVH over the triangles' boxes, built lazily, plus a list of the triangles changed since
//! it was built, at their current boxes. The BVH may still hold stale boxes for changed or
//! deleted triangles, so callers re-check liveness and the current box of every candidate;
//! a changed triangle whose *new* box overlaps the query is found through the list. The BVH
//! is rebuilt once the list outgrows a fraction of the mesh, so a query costs O(log n) plus
//! the bounded list. The guard keeps the index current through
//! [`mesh_core::remesh::EditGuard::committed`].

use mesh_core::broadphase::{Aabb, Bvh};
use mesh_core::{LabeledMesh, TriId};

/// Changed triangles carried in the list before the BVH is rebuilt: a constant plus this
/// fraction of the mesh (a linear scan of the list then costs about as much as the amortised
/// rebuild).
const REBUILD_CONSTANT: usize = 64;
const REBUILD_DIVISOR: usize = 16;

/// A BVH over triangle boxes plus the triangles changed since it was built.
#[derive(Debug, Default)]
pub(crate) struct TriangleIndex {
    bvh: Option<Bvh>,
    /// Triangles changed since the build, at their current boxes.
    changed: Vec<(TriId, Aabb)>,
    /// `position[t] = i + 1` when `changed[i]` holds `t`, 0 when `t` is not in the list.
    position: Vec<u32>,
}

impl TriangleIndex {
    /// Forgets everything; the next query rebuilds.
    pub(crate) fn reset(&mut self) {
        self.bvh = None;
        self.changed.clear();
        self.position.clear();
    }

    /// Builds the BVH if there is none or the change list outgrew its bound.
    pub(crate) fn refresh(&mut self, mesh: &LabeledMesh) {
        let bound = REBUILD_CONSTANT + mesh.triangle_capacity() / REBUILD_DIVISOR;
        if self.bvh.is_some() && self.changed.len() <= bound {
            return;
        }
        let alive = mesh.tri_alive_flags();
        let boxes: Vec<Aabb> = (0..mesh.triangle_capacity())
            .map(|i| {
                if alive[i] {
                    Aabb::from_points(&mesh.tri_positions(TriId::new(i as u32)))
                } else {
                    Aabb::EMPTY
                }
            })
            .collect();
        self.changed.clear();
        self.position.clear();
        // A build fails only for more boxes than ids, which a mesh cannot have; without a
        // BVH every live triangle goes to the list: slow, but still complete.
        self.bvh = Bvh::build(&boxes).ok();
        if self.bvh.is_none() {
            for t in mesh.triangles() {
                self.changed
                    .push((t, Aabb::from_points(&mesh.tri_positions(t))));
            }
        }
    }

    /// Records that `t` was added or moved (or deleted: then it is dropped from the list;
    /// callers skip dead triangles the BVH still returns).
    pub(crate) fn mark(&mut self, mesh: &LabeledMesh, t: TriId) {
        // Without a BVH the next refresh rebuilds from the mesh anyway.
        if self.bvh.is_none() {
            return;
        }
        if t.idx() >= self.position.len() {
            self.position.resize(t.idx() + 1, 0);
        }
        let slot = self.position[t.idx()] as usize;
        if !mesh.is_triangle_alive(t) {
            if slot > 0 {
                self.changed.swap_remove(slot - 1);
                self.position[t.idx()] = 0;
                if let Some(&(moved, _)) = self.changed.get(slot - 1) {
                    self.position[moved.idx()] = slot as u32;
                }
            }
            return;
        }
        let b = Aabb::from_points(&mesh.tri_positions(t));
        if slot > 0 {
            self.changed[slot - 1].1 = b;
        } else {
            self.changed.push((t, b));
            self.position[t.idx()] = self.changed.len() as u32;
        }
    }

    /// Appends to `out` every triangle whose box (as indexed) overlaps `query`. May list a
    /// triangle twice, and dead or stale ones: the caller filters.
    pub(crate) fn query(&self, query: &Aabb, out: &mut Vec<TriId>) {
        if let Some(bvh) = &self.bvh {
            bvh.query(query, 0.0, |id| out.push(TriId::new(id)));
        }
        out.extend(
            self.changed
                .iter()
                .filter(|(_, b)| b.overlaps(query))
                .map(|&(t, _)| t),
        );
    }
}
