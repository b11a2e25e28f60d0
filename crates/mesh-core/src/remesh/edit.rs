//! Atomic mesh edits: every remeshing operation is expressed as one [`Edit`] — triangles
//! removed, vertices added, triangles added, vertices moved — that an [`EditGuard`] sees
//! as a *pseudo-motion* (El Topo §3.5, Los Topos §4.2) before it is committed.
//!
//! Why one representation: the guard (exact static checks here, CCD in the collision
//! backend), attribute transport and atomicity are then written once instead of once per
//! operation. [`apply_edit`] checks every precondition before touching the mesh, so an edit
//! either completes in full or leaves the mesh exactly as it was.

use glam::DVec3;

use crate::error::MeshError;
use crate::ids::{Label, MAX_INDEX, TriId, VertexId};
use crate::mesh::LabeledMesh;

use super::attributes::{Blend, VertexAttributes};
use super::guard::{EditGuard, Veto};
use super::structure::{MovesOnly, StructureFault, StructureScratch, check_structure};

/// A vertex an edit's new triangles refer to: an existing one or one the edit adds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VertexRef {
    /// A live vertex of the mesh.
    Old(VertexId),
    /// The `i`-th entry of [`Edit::new_vertices`].
    New(u32),
}

/// A vertex created by an edit. It appears at `start` (a position known to be safe, e.g.
/// an edge midpoint) and moves to `end` during the pseudo-motion.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NewVertex {
    /// Where the vertex appears.
    pub start: DVec3,
    /// Where it ends up.
    pub end: DVec3,
    /// How its attributes interpolate existing vertices'.
    pub blend: Blend,
}

/// An existing vertex that the edit moves from its current position to `end`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VertexMove {
    /// The vertex.
    pub vertex: VertexId,
    /// Its position after the edit.
    pub end: DVec3,
    /// New attributes, if they change (e.g. the average of a collapsed edge's ends).
    pub blend: Option<Blend>,
}

/// One atomic change of the mesh. Reuse one `Edit` across operations (`clear`) to keep
/// remeshing loops free of allocation.
#[derive(Clone, Debug, Default)]
pub struct Edit {
    /// Triangles deleted.
    pub remove_tris: Vec<TriId>,
    /// Vertices created.
    pub new_vertices: Vec<NewVertex>,
    /// Triangles created, with `[front, back]` labels.
    pub add_tris: Vec<([VertexRef; 3], [Label; 2])>,
    /// Existing vertices moved.
    pub moves: Vec<VertexMove>,
    /// Existing vertices deleted; each must be unused once the edit is applied.
    pub remove_vertices: Vec<VertexId>,
}

/// Ids created by an applied edit, in the order of [`Edit::new_vertices`] / [`Edit::add_tris`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Applied {
    /// Ids of the new vertices.
    pub vertices: Vec<VertexId>,
    /// Ids of the new triangles.
    pub triangles: Vec<TriId>,
}

/// Why an edit was not applied. The mesh is unchanged in every case.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum EditError {
    /// The guard refused the pseudo-motion.
    #[error("edit vetoed by the guard: {0}")]
    Vetoed(Veto),
    /// The edit refers to something that does not exist or is malformed.
    #[error("malformed edit: {0}")]
    Malformed(String),
    /// The end state would break an invariant of the mesh around the edit (a boundary, a
    /// degenerate, duplicate or zero-area triangle, inconsistently labelled wedges).
    #[error("edit refused: {0}")]
    Structure(StructureFault),
    /// The mesh refused a step (capacity).
    #[error(transparent)]
    Mesh(#[from] MeshError),
}

impl EditError {
    /// A short fixed name of the reason (the guard's own for a veto).
    pub fn reason(&self) -> &'static str {
        match self {
            EditError::Vetoed(veto) => veto.kind(),
            EditError::Malformed(_) => "malformed",
            EditError::Structure(_) => "structure",
            EditError::Mesh(_) => "mesh capacity",
        }
    }
}

impl Edit {
    /// Empties the edit, keeping its allocations.
    pub fn clear(&mut self) {
        self.remove_tris.clear();
        self.new_vertices.clear();
        self.add_tris.clear();
        self.moves.clear();
        self.remove_vertices.clear();
    }

    /// True when the edit only moves existing vertices: it removes, adds and deletes
    /// nothing (smoothing moves and their batches).
    pub fn only_moves(&self) -> bool {
        self.remove_tris.is_empty()
            && self.add_tris.is_empty()
            && self.new_vertices.is_empty()
            && self.remove_vertices.is_empty()
    }

    /// Position of a referenced vertex at the start of the pseudo-motion.
    pub fn start_position(&self, mesh: &LabeledMesh, v: VertexRef) -> DVec3 {
        match v {
            VertexRef::Old(v) => mesh.position(v),
            VertexRef::New(i) => self.new_vertices[i as usize].start,
        }
    }

    /// Position of a referenced vertex after the edit.
    pub fn end_position(&self, mesh: &LabeledMesh, v: VertexRef) -> DVec3 {
        match v {
            VertexRef::Old(v) => self
                .moves
                .iter()
                .find(|m| m.vertex == v)
                .map_or_else(|| mesh.position(v), |m| m.end),
            VertexRef::New(i) => self.new_vertices[i as usize].end,
        }
    }

    /// Checks that the edit is well formed against `mesh` (live ids, no repeats, valid new
    /// vertex references, removed vertices unused afterwards).
    pub fn check(&self, mesh: &LabeledMesh) -> Result<(), EditError> {
        for (i, &t) in self.remove_tris.iter().enumerate() {
            if !mesh.is_triangle_alive(t) {
                return Err(EditError::Malformed(format!("removes dead triangle {t}")));
            }
            if self.remove_tris[..i].contains(&t) {
                return Err(EditError::Malformed(format!("removes triangle {t} twice")));
            }
        }
        for (verts, _) in &self.add_tris {
            for &v in verts {
                match v {
                    VertexRef::Old(v)
                        if !mesh.is_vertex_alive(v) || self.remove_vertices.contains(&v) =>
                    {
                        return Err(EditError::Malformed(format!(
                            "new triangle uses vertex {v}, which will not exist"
                        )));
                    }
                    VertexRef::New(i) if i as usize >= self.new_vertices.len() => {
                        return Err(EditError::Malformed(format!(
                            "new triangle uses new vertex #{i}, not created"
                        )));
                    }
                    _ => {}
                }
            }
        }
        for m in &self.moves {
            if !mesh.is_vertex_alive(m.vertex) {
                return Err(EditError::Malformed(format!(
                    "moves dead vertex {}",
                    m.vertex
                )));
            }
        }
        for &v in &self.remove_vertices {
            if !mesh.is_vertex_alive(v) {
                return Err(EditError::Malformed(format!("removes dead vertex {v}")));
            }
            if mesh
                .vertex_triangles(v)
                .any(|t| !self.remove_tris.contains(&t))
            {
                return Err(EditError::Malformed(format!(
                    "removes vertex {v}, still used by kept triangles"
                )));
            }
        }
        Ok(())
    }
}

/// Checks `edit`, asks `guard`, and commits it. On any error the mesh and attributes are
/// unchanged.
pub fn apply_edit(
    mesh: &mut LabeledMesh,
    attrs: &mut VertexAttributes,
    guard: &mut dyn EditGuard,
    edit: &Edit,
) -> Result<Applied, EditError> {
    edit.check(mesh)?;
    guard.precheck(mesh, edit).map_err(EditError::Vetoed)?;
    STRUCTURE
        .with_borrow_mut(|s| check_structure(mesh, edit, s))
        .map_err(EditError::Structure)?;
    guard.check(mesh, edit).map_err(EditError::Vetoed)?;
    commit_guarded(mesh, attrs, guard, edit)
}

/// [`apply_edit`] without the structural check, for snap merging alone: it brings two
/// surfaces into contact on purpose and leaves coincident triangles and the wedges between
/// them for degenerate removal, so its intermediate states are not locally valid; the
/// backend validates after the stage.
pub(crate) fn apply_snap_edit(
    mesh: &mut LabeledMesh,
    attrs: &mut VertexAttributes,
    guard: &mut dyn EditGuard,
    edit: &Edit,
) -> Result<Applied, EditError> {
    edit.check(mesh)?;
    guard.check(mesh, edit).map_err(EditError::Vetoed)?;
    commit_guarded(mesh, attrs, guard, edit)
}

/// [`check_structure`] for a batch of moves cleared by the guard; the caller blames moves
/// with [`super::structure::blame_moves`].
pub(crate) fn check_batch_structure(mesh: &LabeledMesh, edit: &Edit) -> Result<(), StructureFault> {
    STRUCTURE.with_borrow_mut(|s| check_structure(mesh, edit, s))
}

/// Runs `f`, which must change `mesh` by vertex moves only, inside a moves-only scope of
/// the structural check ([`MovesOnly`]: small-component floods are remembered). The scope
/// is left however `f` ends, a panic included, so no stamp outlives it.
pub(crate) fn with_moves_only<R>(
    mesh: &mut LabeledMesh,
    f: impl FnOnce(&mut LabeledMesh) -> R,
) -> R {
    struct Leave(Option<MovesOnly>);
    impl Drop for Leave {
        fn drop(&mut self) {
            if let Some(scope) = self.0.take() {
                STRUCTURE.with_borrow_mut(|s| scope.leave(s));
            }
        }
    }
    let _leave = Leave(Some(
        STRUCTURE.with_borrow_mut(|s| MovesOnly::enter(s, mesh)),
    ));
    f(mesh)
}

thread_local! {
    /// Buffers of the structural check, one set per thread: `apply_edit` is called for every
    /// edit of every stage, and must not allocate for each.
    static STRUCTURE: std::cell::RefCell<StructureScratch> =
        std::cell::RefCell::new(StructureScratch::default());
}

/// Commits a well-formed edit ([`Edit::check`]) that the guard has already passed (a
/// batch cleared by [`EditGuard::offending_moves`]): the capacity checks of [`apply_edit`]
/// still run, the guard is only told.
pub(crate) fn commit_guarded(
    mesh: &mut LabeledMesh,
    attrs: &mut VertexAttributes,
    guard: &mut dyn EditGuard,
    edit: &Edit,
) -> Result<Applied, EditError> {
    // Capacity is the one thing the mesh could still refuse midway: check it up front
    // (free slots are reused first, so the appended count is at most the added count).
    let vertices_needed = mesh.vertex_capacity() + edit.new_vertices.len();
    if vertices_needed > MAX_INDEX as usize {
        return Err(MeshError::TooLarge {
            what: "vertices",
            count: vertices_needed,
        }
        .into());
    }
    let corners_needed = (mesh.triangle_capacity() + edit.add_tris.len()) * 6;
    if corners_needed > MAX_INDEX as usize {
        return Err(MeshError::TooLarge {
            what: "triangles",
            count: corners_needed,
        }
        .into());
    }

    // From here on nothing can fail: every id was checked above. Triangles come and go
    // without re-pairing; every edge they touched is re-paired once at the end.
    let mut edges = Vec::with_capacity(3 * (edit.remove_tris.len() + edit.add_tris.len()));
    for m in &edit.moves {
        mesh.set_position(m.vertex, m.end);
    }
    for &t in &edit.remove_tris {
        let v = mesh.remove_triangle_unpaired(t)?;
        edges.extend([[v[0], v[1]], [v[1], v[2]], [v[2], v[0]]]);
    }
    let mut applied = Applied::default();
    for nv in &edit.new_vertices {
        let v = mesh.add_vertex(nv.end)?;
        applied.vertices.push(v);
    }
    for (verts, labels) in &edit.add_tris {
        let v = verts.map(|r| match r {
            VertexRef::Old(v) => v,
            VertexRef::New(i) => applied.vertices[i as usize],
        });
        applied
            .triangles
            .push(mesh.add_triangle_unpaired(v, *labels)?);
        edges.extend([[v[0], v[1]], [v[1], v[2]], [v[2], v[0]]]);
    }
    mesh.relink_edges(&mut edges);
    for &v in &edit.remove_vertices {
        mesh.remove_vertex(v)?;
    }
    // Moving a vertex can change the radial order around the non-manifold edges it
    // touches (as an end or as a third vertex): re-pair them from the final geometry.
    for m in &edit.moves {
        mesh.relink_around(m.vertex);
    }
    attrs.apply(mesh, edit, &applied);
    guard.committed(mesh, edit, &applied);
    Ok(applied)
}
