//! [`FenceGuard`]: improvement that may change only part of the mesh.
//!
//! Two callers fence: the grid tracker's *changed* scope (the paper's local mesh
//! improvement, §8.5: only the triangles a step created may change, every other triangle
//! is kept exactly), and the block driver ([`super::blocks`]), whose blocks may change only
//! the triangles strictly inside their box. A block's fence is *held* rather than final:
//! what it refused near the box's border is handed on to a later pass ([`FenceGuard::deferred`]).

use crate::broadphase::Aabb;
use crate::ids::{TriId, VertexId};
use crate::mesh::LabeledMesh;

use super::edit::{Applied, Edit, VertexRef};
use super::guard::{EditGuard, Veto};

/// Vetoes every edit that removes or deforms a fenced triangle, or that puts a vertex
/// outside the fence's box, before the inner guard is asked; triangles the edits create
/// are inside the fence.
pub struct FenceGuard<'g> {
    inner: &'g mut dyn EditGuard,
    /// `editable[t]`: triangle slot `t` may be removed or deformed; `None`: every one.
    editable: Option<Vec<bool>>,
    /// `held[t]`: slot `t` is fenced only by the box, not by the caller's region.
    held: Vec<bool>,
    /// Every vertex an edit moves or creates must end strictly inside this box.
    bounds: Option<Aabb>,
    /// Vertices of edits refused only because of the box (repeats allowed).
    deferred: Vec<VertexId>,
}

impl<'g> FenceGuard<'g> {
    /// Edits may change the triangles with `editable[t]` (slots past its end are fenced)
    /// and the ones they create.
    pub fn new(inner: &'g mut dyn EditGuard, editable: Vec<bool>) -> Self {
        FenceGuard {
            inner,
            editable: Some(editable),
            held: Vec::new(),
            bounds: None,
            deferred: Vec::new(),
        }
    }

    /// No fence: every edit goes to `inner`.
    pub fn open(inner: &'g mut dyn EditGuard) -> Self {
        FenceGuard {
            inner,
            editable: None,
            held: Vec::new(),
            bounds: None,
            deferred: Vec::new(),
        }
    }

    /// A block's fence: `editable` as in [`FenceGuard::new`]; `held[t]` marks the fenced
    /// triangles that only the box holds back; every moved or created vertex must end
    /// strictly inside `bounds`.
    pub(crate) fn block(
        inner: &'g mut dyn EditGuard,
        editable: Vec<bool>,
        held: Vec<bool>,
        bounds: Aabb,
    ) -> Self {
        FenceGuard {
            inner,
            editable: Some(editable),
            held,
            bounds: Some(bounds),
            deferred: Vec::new(),
        }
    }

    /// The vertices of the edits refused only because of the box, in the order refused.
    pub(crate) fn deferred(&self) -> &[VertexId] {
        &self.deferred
    }

    fn editable(&self, t: TriId) -> bool {
        match &self.editable {
            None => true,
            Some(e) => e.get(t.idx()).copied().unwrap_or(false),
        }
    }

    fn held(&self, t: TriId) -> bool {
        self.held.get(t.idx()).copied().unwrap_or(false)
    }

    /// A fenced triangle at `v`, if any: moving or removing `v` would deform it.
    fn fenced(&self, mesh: &LabeledMesh, v: VertexId) -> Option<TriId> {
        self.editable.as_ref()?;
        mesh.vertex_triangles(v).find(|&t| !self.editable(t))
    }

    /// True when `v` is fenced by the caller's region (not only by the box).
    fn fenced_for_good(&self, mesh: &LabeledMesh, v: VertexId) -> bool {
        mesh.vertex_triangles(v)
            .any(|t| !self.editable(t) && !self.held(t))
    }

    fn inside(&self, p: glam::DVec3) -> bool {
        self.bounds.is_none_or(|b| b.contains_strictly(p))
    }

    /// Why `edit` is fenced off, if it is: the first fenced triangle it removes or deforms,
    /// or (as `tri: None`) a vertex it would put outside the box; and whether only the box
    /// holds it back.
    fn refusal(&self, mesh: &LabeledMesh, edit: &Edit) -> Option<(Option<TriId>, bool)> {
        if let Some(&t) = edit.remove_tris.iter().find(|&&t| !self.editable(t)) {
            return Some((Some(t), self.held(t)));
        }
        for m in &edit.moves {
            if let Some(t) = self.fenced(mesh, m.vertex) {
                let held = !self.fenced_for_good(mesh, m.vertex);
                return Some((Some(t), held));
            }
        }
        if self.bounds.is_some()
            && (edit.moves.iter().any(|m| !self.inside(m.end))
                || edit.new_vertices.iter().any(|n| !self.inside(n.end)))
        {
            return Some((None, true));
        }
        None
    }

    /// The fence's own verdict on `edit`, noting what the box alone holds back.
    fn refuse(&mut self, mesh: &LabeledMesh, edit: &Edit) -> Result<(), Veto> {
        let Some((tri, held)) = self.refusal(mesh, edit) else {
            return Ok(());
        };
        if held {
            self.defer(mesh, edit);
        }
        Err(match tri {
            Some(tri) => Veto::OutsideRegion { tri },
            None => Veto::Other("outside the block"),
        })
    }

    /// Notes the vertices of an edit refused only because of the box.
    fn defer(&mut self, mesh: &LabeledMesh, edit: &Edit) {
        for &t in &edit.remove_tris {
            if mesh.is_triangle_alive(t) {
                self.deferred.extend(mesh.tri(t));
            }
        }
        self.deferred.extend(edit.moves.iter().map(|m| m.vertex));
        for (verts, _) in &edit.add_tris {
            self.deferred.extend(verts.iter().filter_map(|r| match r {
                VertexRef::Old(v) => Some(*v),
                VertexRef::New(_) => None,
            }));
        }
    }
}

impl EditGuard for FenceGuard<'_> {
    fn check_vertex(&mut self, mesh: &LabeledMesh, v: VertexId) -> Result<(), Veto> {
        match self.fenced(mesh, v) {
            Some(tri) => {
                if !self.fenced_for_good(mesh, v) {
                    self.deferred.push(v);
                }
                Err(Veto::OutsideRegion { tri })
            }
            None => self.inner.check_vertex(mesh, v),
        }
    }

    fn precheck(&mut self, mesh: &LabeledMesh, edit: &Edit) -> Result<(), Veto> {
        self.refuse(mesh, edit)?;
        self.inner.precheck(mesh, edit)
    }

    fn check(&mut self, mesh: &LabeledMesh, edit: &Edit) -> Result<(), Veto> {
        self.refuse(mesh, edit)?;
        self.inner.check(mesh, edit)
    }

    /// Moves off the fence are blamed first (the caller asks again without them); a batch
    /// inside it goes to the inner guard whole.
    fn offending_moves(&mut self, mesh: &LabeledMesh, edit: &Edit) -> Option<Vec<usize>> {
        let mut outside = Vec::new();
        for (i, m) in edit.moves.iter().enumerate() {
            let fenced = self.fenced(mesh, m.vertex).is_some();
            if fenced || !self.inside(m.end) {
                if !fenced || !self.fenced_for_good(mesh, m.vertex) {
                    self.deferred.push(m.vertex);
                }
                outside.push(i);
            }
        }
        if outside.is_empty() {
            self.inner.offending_moves(mesh, edit)
        } else {
            Some(outside)
        }
    }

    fn committed(&mut self, mesh: &LabeledMesh, edit: &Edit, applied: &Applied) {
        if let Some(editable) = &mut self.editable {
            for &t in &applied.triangles {
                if t.idx() >= editable.len() {
                    editable.resize(t.idx() + 1, false);
                }
                editable[t.idx()] = true;
            }
        }
        for &t in &applied.triangles {
            if let Some(h) = self.held.get_mut(t.idx()) {
                *h = false;
            }
        }
        self.inner.committed(mesh, edit, applied);
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;
    use crate::generators::icosphere;
    use crate::ids::Label;
    use crate::remesh::structure::StructureFault;
    use crate::remesh::{EditError, NoGuard, VertexAttributes, apply_edit};

    /// An edit that takes one triangle out of a closed sphere leaves boundary edges: the
    /// structural check refuses it. Fenced, it is refused by the fence first, without the
    /// structural check being asked (the precheck is the cheap half of the guard).
    #[test]
    fn a_fenced_edit_is_refused_before_its_structure_is_checked() {
        let mut mesh = icosphere(1, DVec3::ZERO, 1.0, [Label::new(0), Label::new(1)]).unwrap();
        let before = mesh.to_raw();
        let hole = Edit {
            remove_tris: vec![TriId::new(3)],
            ..Edit::default()
        };
        let mut attrs = VertexAttributes::none();
        let open = apply_edit(
            &mut mesh,
            &mut attrs,
            &mut FenceGuard::open(&mut NoGuard),
            &hole,
        );
        assert!(
            matches!(
                open,
                Err(EditError::Structure(StructureFault::Boundary { .. }))
            ),
            "{open:?}"
        );
        let mut editable = vec![true; mesh.triangle_capacity()];
        editable[3] = false;
        let fenced = apply_edit(
            &mut mesh,
            &mut attrs,
            &mut FenceGuard::new(&mut NoGuard, editable),
            &hole,
        );
        assert_eq!(
            fenced,
            Err(EditError::Vetoed(Veto::OutsideRegion {
                tri: TriId::new(3)
            }))
        );
        assert_eq!(mesh.to_raw(), before);
    }
}
