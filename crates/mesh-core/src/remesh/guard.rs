//! Edit guards: who may veto an edit before it is committed.
//!
//! The shared remeshing operations never decide on their own whether an edit is safe; they
//! ask the guard the backend passes in. The grid tracker passes a cheap guard (its output is
//! checked per region anyway); the collision tracker passes one that sweeps the
//! pseudo-motion with exact CCD. [`StaticIntersectionGuard`] ships here: it rejects edits
//! whose end state would make a new or moved triangle intersect the rest of the mesh.

use glam::DVec3;

use crate::broadphase::{Aabb, Bvh};
use crate::ids::TriId;
use crate::mesh::LabeledMesh;
use crate::predicates;

use super::edit::{Applied, Edit, VertexRef};

/// Consulted before each edit; `Err(reason)` vetoes it.
///
/// A guard follows the mesh through [`super::apply_edit`], which calls
/// [`EditGuard::committed`] after every edit it commits, so guards that index the mesh can
/// stay current cheaply.
pub trait EditGuard {
    /// Decides on `edit`, seen against the mesh *before* it is applied.
    fn check(&mut self, mesh: &LabeledMesh, edit: &Edit) -> Result<(), &'static str>;

    /// Told after `edit` was committed (`mesh` is the mesh after it).
    fn committed(&mut self, _mesh: &LabeledMesh, _edit: &Edit, _applied: &Applied) {}
}

/// Allows everything.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoGuard;

impl EditGuard for NoGuard {
    fn check(&mut self, _mesh: &LabeledMesh, _edit: &Edit) -> Result<(), &'static str> {
        Ok(())
    }
}

/// A triangle of an edit's end state: positions, and vertex keys to recognise shared
/// vertices (new vertices get keys past the mesh's ids).
type Keyed = [(u32, DVec3); 3];

/// Rejects an edit if, in its end state, a triangle it adds or moves intersects (exactly)
/// any other triangle, except at shared vertices and edges. It checks the end state, not
/// the sweep: on an intersection-free mesh with small edits (the remeshing case) that keeps
/// the mesh intersection-free; the collision backend adds the sweep test.
///
/// Candidates come from a BVH over the triangles' boxes, built lazily, plus a list of the
/// triangles changed since it was built (whose boxes in the BVH may be stale); the BVH is
/// rebuilt when that list grows past a fraction of the mesh. So a check costs
/// O(log n + changes since the last rebuild). The guard learns of changes through
/// [`EditGuard::committed`]: if the mesh is changed any other way, call
/// [`StaticIntersectionGuard::reset`].
#[derive(Debug, Default)]
pub struct StaticIntersectionGuard {
    index: Option<Bvh>,
    /// Triangle slots changed since the BVH was built.
    dirty: Vec<TriId>,
    is_dirty: Vec<bool>,
    /// Scratch buffers, kept to avoid allocation per check.
    moved: Vec<TriId>,
    changed: Vec<Keyed>,
    candidates: Vec<TriId>,
}

impl StaticIntersectionGuard {
    /// A guard with no index yet (built on first use).
    pub fn new() -> Self {
        Self::default()
    }

    /// Forgets the index, e.g. after the mesh was changed outside `apply_edit`.
    pub fn reset(&mut self) {
        self.index = None;
        self.dirty.clear();
        self.is_dirty.clear();
    }

    /// Builds the BVH if there is none, or if enough has changed since that rechecking the
    /// dirty list would cost more than rebuilding.
    fn refresh(&mut self, mesh: &LabeledMesh) {
        let capacity = mesh.triangle_capacity();
        let stale = self.dirty.len() > 64 + capacity / 32 || self.is_dirty.len() > capacity;
        if self.index.is_some() && !stale {
            return;
        }
        let boxes: Vec<Aabb> = (0..capacity)
            .map(|i| {
                let t = TriId::new(i as u32);
                if mesh.is_triangle_alive(t) {
                    Aabb::from_points(&mesh.tri_positions(t))
                } else {
                    Aabb::EMPTY
                }
            })
            .collect();
        // A build only fails for more boxes than ids, which a mesh cannot have; without an
        // index every triangle is treated as dirty, which is slow but still exact.
        self.index = Bvh::build(&boxes).ok();
        self.dirty.clear();
        self.is_dirty.clear();
        self.is_dirty.resize(capacity, false);
        if self.index.is_none() {
            self.dirty.extend(mesh.triangles());
            self.is_dirty.fill(true);
        }
    }

    fn mark_dirty(&mut self, t: TriId) {
        if t.idx() >= self.is_dirty.len() {
            self.is_dirty.resize(t.idx() + 1, false);
        }
        if !self.is_dirty[t.idx()] {
            self.is_dirty[t.idx()] = true;
            self.dirty.push(t);
        }
    }
}

impl EditGuard for StaticIntersectionGuard {
    fn check(&mut self, mesh: &LabeledMesh, edit: &Edit) -> Result<(), &'static str> {
        self.refresh(mesh);
        let removed = |t: TriId| edit.remove_tris.contains(&t);
        // Kept triangles that move with the edit.
        self.moved.clear();
        for m in &edit.moves {
            for t in mesh.vertex_triangles(m.vertex) {
                if !removed(t) && !self.moved.contains(&t) {
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
            self.changed.push(verts.map(|r| (key(r), edit.end_position(mesh, r))));
        }
        for &t in &self.moved {
            self.changed
                .push(mesh.tri(t).map(|v| (v.raw(), edit.end_position(mesh, VertexRef::Old(v)))));
        }
        for (i, a) in self.changed.iter().enumerate() {
            let points = a.map(|x| x.1);
            let bounds = Aabb::from_points(&points);
            self.candidates.clear();
            if let Some(index) = &self.index {
                let candidates = &mut self.candidates;
                index.query(&bounds, 0.0, |id| candidates.push(TriId::new(id)));
            }
            for &t in self.candidates.iter().chain(self.dirty.iter()) {
                if !mesh.is_triangle_alive(t) || removed(t) || self.moved.contains(&t) {
                    continue;
                }
                let b = mesh.tri(t).map(|v| (v.raw(), mesh.position(v)));
                if bounds.overlaps(&Aabb::from_points(&b.map(|x| x.1))) && intersect_keyed(a, &b) {
                    return Err("end state intersects the mesh");
                }
            }
            for b in &self.changed[i + 1..] {
                if intersect_keyed(a, b) {
                    return Err("end state intersects itself");
                }
            }
        }
        Ok(())
    }

    fn committed(&mut self, mesh: &LabeledMesh, edit: &Edit, applied: &Applied) {
        if self.index.is_none() {
            return;
        }
        for &t in &applied.triangles {
            self.mark_dirty(t);
        }
        for m in &edit.moves {
            let around: Vec<TriId> = mesh.vertex_triangles(m.vertex).collect();
            for t in around {
                self.mark_dirty(t);
            }
        }
    }
}

/// Exact intersection of two keyed triangles, excluding contact at shared vertices and
/// edges.
fn intersect_keyed(a: &Keyed, b: &Keyed) -> bool {
    let mut shared = [(0usize, 0usize); 3];
    let mut n = 0;
    for (i, (ka, _)) in a.iter().enumerate() {
        for (j, (kb, _)) in b.iter().enumerate() {
            if ka == kb {
                shared[n.min(2)] = (i, j);
                n += 1;
            }
        }
    }
    let pa = a.map(|x| x.1);
    let pb = b.map(|x| x.1);
    match n {
        0 => predicates::intersect_triangle_triangle(&pa, &pb),
        1 => {
            let (i, j) = shared[0];
            predicates::intersect_sharing_vertex(
                pa[i],
                [pa[(i + 1) % 3], pa[(i + 2) % 3]],
                [pb[(j + 1) % 3], pb[(j + 2) % 3]],
            )
        }
        2 => {
            let ((i0, j0), (i1, j1)) = (shared[0], shared[1]);
            predicates::intersect_sharing_edge(pa[i0], pa[i1], pa[3 - i0 - i1], pb[3 - j0 - j1])
        }
        // Same vertex set: a duplicate, which validation reports separately.
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generators::icosphere;
    use crate::ids::{Label, VertexId};
    use crate::remesh::{VertexAttributes, VertexMove, apply_edit};
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

    #[test]
    fn vetoes_a_vertex_pushed_through_the_far_side() {
        let mesh = sphere();
        let mut guard = StaticIntersectionGuard::new();
        let v = VertexId::new(0);
        let p = mesh.position(v);
        assert!(guard.check(&mesh, &move_edit(v, p * 1.01)).is_ok());
        // Through the centre and out of the other side: its fan crosses the far triangles.
        assert!(guard.check(&mesh, &move_edit(v, -p * 1.5)).is_err());
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
            let to = if k % 7 == 3 { -p * 0.9 } else { p * (1.0 + 0.01 * ((k % 5) as f64 - 2.0)) };
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
}
