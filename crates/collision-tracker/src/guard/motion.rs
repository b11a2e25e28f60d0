//! The pseudo-motion of an edit (El Topo §3.5, Los Topos §5): which triangles sweep through
//! space while the edit happens, from where to where, and which vertices count as "the
//! same" for collision purposes.
//!
//! # What moves
//!
//! Every vertex moves on a straight line over a fictitious step `t ∈ [0, 1]`: an existing
//! vertex from its current position to its [`VertexMove::end`](mesh_core::remesh::VertexMove)
//! (or stays), a new vertex from [`NewVertex::start`](mesh_core::remesh::NewVertex) to its
//! end. The triangles carried along (the *swept* triangles) are:
//! - every kept triangle with a moving vertex (smoothing, the stay-behind side of a vertex
//!   separation or pinch);
//! - every added triangle with a moving vertex, read from its start positions (a split's
//!   halves as the new vertex leaves the edge, the moving side of a separation or pinch);
//! - for *merging* edits — those that move a vertex `b` and delete it, the edge collapse
//!   and the vertex snap — the deleted triangles with a moving vertex: `b`'s fan travels
//!   with `b` until it lands on the survivor `a`. Added triangles made only of existing
//!   vertices are then the end state of those deleted ones (`b` replaced by `a`, both at the
//!   same place) and are not swept again from the survivor's old place, which would be a
//!   motion that never happens.
//!
//! # Who is "the same vertex"
//!
//! Pairs of elements that share a vertex touch at every instant, so CCD skips them. Two
//! further kinds of pairs touch by construction and are skipped the same way, by giving
//! the vertices involved one identity (a *key*):
//! - a new vertex born at an existing vertex's position (vertex separation and pinching
//!   create `v_a` at `v`) has `v`'s key: it starts incident to everything at `v`;
//! - a deleted vertex `b` that moves to exactly where a surviving vertex `a` ends (collapse,
//!   snap) has `a`'s key: it ends incident to everything at `a`.
//!
//! Those pairs are covered instead by the static checks on the end state and by the swept
//! tetrahedron test (see the parent module).

use glam::DVec3;
use mesh_core::broadphase::Aabb;
use mesh_core::remesh::{Edit, VertexRef};
use mesh_core::{LabeledMesh, TriId, VertexId};

/// One triangle of the pseudo-motion: vertex keys, positions at `t = 0` and `t = 1`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Swept {
    pub key: [u32; 3],
    pub x0: [DVec3; 3],
    pub x1: [DVec3; 3],
}

impl Swept {
    /// True when corner `k` moves during the step.
    #[inline]
    pub fn moving(&self, k: usize) -> bool {
        self.x0[k] != self.x1[k]
    }

    /// Number of moving corners.
    pub fn movers(&self) -> usize {
        (0..3).filter(|&k| self.moving(k)).count()
    }

    /// The box around both configurations.
    pub fn bounds(&self) -> Aabb {
        Aabb::from_points(&self.x0).union(Aabb::from_points(&self.x1))
    }

    /// True when the triangle has vertex key `k`.
    #[inline]
    pub fn has(&self, k: u32) -> bool {
        self.key.contains(&k)
    }
}

/// The pseudo-motion of one edit (reusable buffers).
#[derive(Debug, Default)]
pub(crate) struct Motion {
    /// Triangles that sweep.
    pub swept: Vec<Swept>,
    /// Kept triangles with a moving vertex (not part of the static rest).
    pub moved_kept: Vec<TriId>,
    /// Vertex references whose key is not their own (see the module doc).
    aliases: Vec<(VertexRef, u32)>,
    /// Existing vertices the edit refers to (candidates for aliases).
    referenced: Vec<VertexId>,
    /// Key of the first new vertex: the mesh's vertex capacity.
    base: u32,
}

impl Motion {
    /// The key of a vertex reference.
    pub fn key(&self, r: VertexRef) -> u32 {
        if let Some(&(_, k)) = self.aliases.iter().find(|(x, _)| *x == r) {
            return k;
        }
        match r {
            VertexRef::Old(v) => v.raw(),
            VertexRef::New(i) => self.base.saturating_add(i),
        }
    }

    /// Builds the pseudo-motion of `edit` on `mesh` (the mesh before the edit).
    pub fn build(&mut self, mesh: &LabeledMesh, edit: &Edit) {
        self.swept.clear();
        self.moved_kept.clear();
        self.aliases.clear();
        self.base = mesh.vertex_capacity() as u32;
        let moving = |v: VertexId| {
            edit.moves
                .iter()
                .any(|m| m.vertex == v && m.end != mesh.position(v))
        };
        let removed = |t: TriId| edit.remove_tris.contains(&t);

        self.referenced.clear();
        self.referenced.extend(edit.moves.iter().map(|m| m.vertex));
        for &t in &edit.remove_tris {
            self.referenced.extend(mesh.tri(t));
        }
        for (verts, _) in &edit.add_tris {
            self.referenced.extend(verts.iter().filter_map(|r| match r {
                VertexRef::Old(v) => Some(*v),
                VertexRef::New(_) => None,
            }));
        }
        self.referenced.sort_unstable();
        self.referenced.dedup();

        // A deleted vertex landing exactly on a survivor is the survivor.
        let mut merging = false;
        for &b in &edit.remove_vertices {
            if !moving(b) {
                continue;
            }
            merging = true;
            let end = edit.end_position(mesh, VertexRef::Old(b));
            if let Some(&a) = self.referenced.iter().find(|&&a| {
                a != b
                    && !edit.remove_vertices.contains(&a)
                    && edit.end_position(mesh, VertexRef::Old(a)) == end
            }) {
                self.aliases.push((VertexRef::Old(b), a.raw()));
            }
        }
        // A new vertex born at an existing (or earlier new) vertex is that vertex.
        for (i, nv) in edit.new_vertices.iter().enumerate() {
            let born_at = self
                .referenced
                .iter()
                .find(|&&u| mesh.position(u) == nv.start)
                .map(|&u| self.key(VertexRef::Old(u)))
                .or_else(|| {
                    edit.new_vertices[..i]
                        .iter()
                        .position(|w| w.start == nv.start)
                        .map(|j| self.key(VertexRef::New(j as u32)))
                });
            if let Some(k) = born_at {
                self.aliases.push((VertexRef::New(i as u32), k));
            }
        }

        // Kept triangles carried by moving vertices.
        for m in &edit.moves {
            if !moving(m.vertex) {
                continue;
            }
            for t in mesh.vertex_triangles(m.vertex) {
                if removed(t) || self.moved_kept.contains(&t) {
                    continue;
                }
                self.moved_kept.push(t);
                let verts = mesh.tri(t).map(VertexRef::Old);
                self.push(mesh, edit, verts, |r| edit.start_position(mesh, r));
            }
        }
        // Deleted triangles travelling with a merging vertex.
        if merging {
            for &t in &edit.remove_tris {
                let tri = mesh.tri(t);
                if tri.iter().any(|&v| moving(v)) {
                    self.push(mesh, edit, tri.map(VertexRef::Old), |r| {
                        edit.start_position(mesh, r)
                    });
                }
            }
        }
        // Added triangles sweeping from their start positions.
        for (verts, _) in &edit.add_tris {
            let sweeps = verts
                .iter()
                .any(|&r| edit.start_position(mesh, r) != edit.end_position(mesh, r));
            let all_old = verts.iter().all(|r| matches!(r, VertexRef::Old(_)));
            if sweeps && !(merging && all_old) {
                self.push(mesh, edit, *verts, |r| edit.start_position(mesh, r));
            }
        }
    }

    fn push(
        &mut self,
        mesh: &LabeledMesh,
        edit: &Edit,
        verts: [VertexRef; 3],
        start: impl Fn(VertexRef) -> DVec3,
    ) {
        self.swept.push(Swept {
            key: verts.map(|r| self.key(r)),
            x0: verts.map(&start),
            x1: verts.map(|r| edit.end_position(mesh, r)),
        });
    }

    /// True when `t` is a kept triangle that moves.
    pub fn is_moved_kept(&self, t: TriId) -> bool {
        self.moved_kept.contains(&t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mesh_core::Label;
    use mesh_core::generators::icosphere;
    use mesh_core::remesh::Blend;
    use mesh_core::remesh::{NewVertex, VertexMove};

    fn sphere() -> LabeledMesh {
        icosphere(1, DVec3::ZERO, 1.0, [Label::OUTSIDE, Label::new(1)]).expect("sphere")
    }

    #[test]
    fn smoothing_sweeps_the_fan_from_current_to_end() {
        let mesh = sphere();
        let v = VertexId::new(0);
        let edit = Edit {
            moves: vec![VertexMove {
                vertex: v,
                end: mesh.position(v) * 0.9,
                blend: None,
            }],
            ..Edit::default()
        };
        let mut m = Motion::default();
        m.build(&mesh, &edit);
        let valence = mesh.vertex_triangles(v).count();
        assert_eq!(m.swept.len(), valence);
        assert_eq!(m.moved_kept.len(), valence);
        assert!(m.swept.iter().all(|s| s.movers() == 1 && s.has(v.raw())));
    }

    #[test]
    fn collapse_sweeps_the_removed_fan_and_aliases_the_removed_vertex() {
        let mesh = sphere();
        let a = VertexId::new(0);
        let b = mesh
            .vertex_triangles(a)
            .flat_map(|t| mesh.tri(t))
            .find(|&w| w != a)
            .expect("neighbour");
        let mid = (mesh.position(a) + mesh.position(b)) * 0.5;
        let mut edit = Edit::default();
        for t in mesh.vertex_triangles(b) {
            edit.remove_tris.push(t);
            let tri = mesh.tri(t);
            if !tri.contains(&a) {
                edit.add_tris.push((
                    tri.map(|w| VertexRef::Old(if w == b { a } else { w })),
                    mesh.labels(t),
                ));
            }
        }
        edit.moves.push(VertexMove {
            vertex: a,
            end: mid,
            blend: Some(Blend::lerp(a, b, 0.5)),
        });
        edit.moves.push(VertexMove {
            vertex: b,
            end: mid,
            blend: None,
        });
        edit.remove_vertices.push(b);
        let mut m = Motion::default();
        m.build(&mesh, &edit);
        assert_eq!(m.key(VertexRef::Old(b)), a.raw());
        let fan_b = mesh.vertex_triangles(b).count();
        let fan_a_kept = mesh
            .vertex_triangles(a)
            .filter(|t| !mesh.tri(*t).contains(&b))
            .count();
        // a's kept fan plus b's whole (removed) fan; re-formed triangles are not re-swept.
        assert_eq!(m.swept.len(), fan_a_kept + fan_b);
    }

    #[test]
    fn a_vertex_born_at_an_existing_one_shares_its_key() {
        let mesh = sphere();
        let v = VertexId::new(3);
        let p = mesh.position(v);
        let edit = Edit {
            new_vertices: vec![NewVertex {
                start: p,
                end: p * 1.01,
                blend: Blend::copy(v),
            }],
            moves: vec![VertexMove {
                vertex: v,
                end: p * 0.99,
                blend: None,
            }],
            ..Edit::default()
        };
        let mut m = Motion::default();
        m.build(&mesh, &edit);
        assert_eq!(m.key(VertexRef::New(0)), v.raw());
    }
}
