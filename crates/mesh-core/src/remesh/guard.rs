//! Edit guards: who may veto an edit before it is committed.
//!
//! The shared remeshing operations never decide on their own whether an edit is safe; they
//! ask the guard the backend passes in. The grid tracker passes a cheap guard (its output is
//! checked per region anyway); the collision tracker passes one that sweeps the
//! pseudo-motion with exact CCD. [`StaticIntersectionGuard`] ships here: it rejects edits
//! whose end state would make a new or moved triangle intersect the rest of the mesh.

use std::collections::HashMap;

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
/// Candidates come from a BVH over the triangles' boxes, built lazily, plus a hash grid of
/// the triangles changed since it was built (whose boxes in the BVH may be stale); the BVH
/// is rebuilt when the changed triangles reach a quarter of the mesh. So a check costs
/// O(log n) plus the changes near it. The guard learns of changes through
/// [`EditGuard::committed`]: if the mesh is changed any other way, call
/// [`StaticIntersectionGuard::reset`].
#[derive(Debug, Default)]
pub struct StaticIntersectionGuard {
    index: Option<Bvh>,
    /// Triangles changed since the BVH was built, at their current boxes.
    dirty: DirtyGrid,
    /// Scratch buffers, kept to avoid allocation per check.
    moved: Vec<TriId>,
    changed: Vec<Keyed>,
    candidates: Vec<TriId>,
}

/// Triangles changed since the BVH was built, bucketed on a uniform grid (cell ≈ a
/// triangle's size) so that a check looks only at the changes near it. A triangle that
/// changes again moves to the cells of its new box, so the grid holds current boxes only.
#[derive(Debug, Default)]
struct DirtyGrid {
    cell: f64,
    buckets: HashMap<[i64; 3], Vec<TriId>>,
    /// Triangles too large for a few cells, checked against every query.
    oversize: Vec<TriId>,
    /// Where each changed triangle is filed (by triangle slot).
    placed: Vec<Option<Placement>>,
    /// Distinct triangles filed.
    distinct: usize,
}

/// The cells a triangle is filed under, or the oversize list.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Placement {
    Cells([i64; 3], [i64; 3]),
    Oversize,
}

/// A triangle box spanning more cells than this goes to the oversize list.
const MAX_CELLS_PER_BOX: i64 = 27;

/// Calls `f` for every cell of an inclusive integer range.
fn for_cells(lo: [i64; 3], hi: [i64; 3], mut f: impl FnMut([i64; 3])) {
    for x in lo[0]..=hi[0] {
        for y in lo[1]..=hi[1] {
            for z in lo[2]..=hi[2] {
                f([x, y, z]);
            }
        }
    }
}

impl DirtyGrid {
    fn reset(&mut self, cell: f64) {
        self.cell = if cell.is_finite() && cell > 0.0 {
            cell
        } else {
            1.0
        };
        self.buckets.clear();
        self.oversize.clear();
        self.placed.clear();
        self.distinct = 0;
    }

    /// Integer cell range of a box, or `None` if it is too large (or not finite).
    fn cells(&self, b: &Aabb) -> Option<([i64; 3], [i64; 3])> {
        let lo = (b.min / self.cell).floor();
        let hi = (b.max / self.cell).floor();
        if !lo.is_finite() || !hi.is_finite() {
            return None;
        }
        let span = hi - lo + 1.0;
        if span.x * span.y * span.z > MAX_CELLS_PER_BOX as f64 {
            return None;
        }
        Some((
            [lo.x as i64, lo.y as i64, lo.z as i64],
            [hi.x as i64, hi.y as i64, hi.z as i64],
        ))
    }

    /// Files `t` under box `b`, first removing it from where it was filed before.
    fn insert(&mut self, t: TriId, b: &Aabb) {
        if t.idx() >= self.placed.len() {
            self.placed.resize(t.idx() + 1, None);
        }
        match self.placed[t.idx()] {
            None => self.distinct += 1,
            Some(Placement::Oversize) => self.oversize.retain(|&x| x != t),
            Some(Placement::Cells(lo, hi)) => {
                let buckets = &mut self.buckets;
                for_cells(lo, hi, |c| {
                    if let Some(bucket) = buckets.get_mut(&c)
                        && let Some(i) = bucket.iter().position(|&x| x == t)
                    {
                        bucket.swap_remove(i);
                    }
                });
            }
        }
        let placement = match self.cells(b) {
            Some((lo, hi)) => {
                let buckets = &mut self.buckets;
                for_cells(lo, hi, |c| buckets.entry(c).or_default().push(t));
                Placement::Cells(lo, hi)
            }
            None => {
                self.oversize.push(t);
                Placement::Oversize
            }
        };
        self.placed[t.idx()] = Some(placement);
    }

    fn query(&self, b: &Aabb, out: &mut Vec<TriId>) {
        out.extend_from_slice(&self.oversize);
        match self.cells(b) {
            Some((lo, hi)) => for_cells(lo, hi, |c| {
                if let Some(bucket) = self.buckets.get(&c) {
                    out.extend_from_slice(bucket);
                }
            }),
            // A query box too large for the grid: every changed triangle is a candidate.
            None => out.extend(self.buckets.values().flatten()),
        }
    }
}

impl StaticIntersectionGuard {
    /// A guard with no index yet (built on first use).
    pub fn new() -> Self {
        Self::default()
    }

    /// Forgets the index, e.g. after the mesh was changed outside `apply_edit`.
    pub fn reset(&mut self) {
        self.index = None;
        self.dirty.reset(1.0);
    }

    /// Builds the BVH if there is none, or if so much has changed since that rebuilding is
    /// cheaper than carrying the changes.
    fn refresh(&mut self, mesh: &LabeledMesh) {
        let capacity = mesh.triangle_capacity();
        // Rebuild once a quarter of the mesh has changed: the BVH then misses too much.
        if self.index.is_some() && self.dirty.distinct <= 256 + capacity / 4 {
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
        let live = mesh.num_triangles().max(1) as f64;
        let mean_extent = boxes
            .iter()
            .filter(|b| !b.is_empty())
            .map(|b| (b.max - b.min).max_element())
            .filter(|e| e.is_finite())
            .sum::<f64>()
            / live;
        self.dirty.reset(mean_extent);
        // A build only fails for more boxes than ids, which a mesh cannot have; without an
        // index every triangle goes to the changed set, which is slow but still exact.
        self.index = Bvh::build(&boxes).ok();
        if self.index.is_none() {
            for t in mesh.triangles() {
                self.dirty.oversize.push(t);
            }
        }
    }

    fn mark_dirty(&mut self, mesh: &LabeledMesh, t: TriId) {
        if mesh.is_triangle_alive(t) {
            self.dirty
                .insert(t, &Aabb::from_points(&mesh.tri_positions(t)));
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
            self.changed
                .push(verts.map(|r| (key(r), edit.end_position(mesh, r))));
        }
        for &t in &self.moved {
            self.changed.push(
                mesh.tri(t)
                    .map(|v| (v.raw(), edit.end_position(mesh, VertexRef::Old(v)))),
            );
        }
        for (i, a) in self.changed.iter().enumerate() {
            let points = a.map(|x| x.1);
            let bounds = Aabb::from_points(&points);
            self.candidates.clear();
            if let Some(index) = &self.index {
                let candidates = &mut self.candidates;
                index.query(&bounds, 0.0, |id| candidates.push(TriId::new(id)));
            }
            self.dirty.query(&bounds, &mut self.candidates);
            for &t in &self.candidates {
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
            self.mark_dirty(mesh, t);
        }
        for m in &edit.moves {
            for t in mesh.vertex_triangles(m.vertex) {
                self.mark_dirty(mesh, t);
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
}
