//! Vertex snapping and the subdivisions that prepare it (Los Topos §7.1, generalized
//! snapping).
//!
//! - [`snap_vertices`] coalesces two vertices that do *not* share an edge — an edge
//!   collapse between non-adjacent vertices: both move to their average, every triangle of
//!   the second is re-formed onto the first in place (same orientation and labels), and
//!   the second is deleted. Two triangles that end on the same three vertices are the
//!   zero-volume region that degenerate removal ([`super::remove_degenerate`]) resolves.
//! - [`split_edge_at`] splits an edge at any parameter (not only the midpoint), and
//!   [`split_triangle_at`] trisects a triangle at a point of it: the compatible remeshing
//!   that gives every vertex of a proximate pair a counterpart to snap to.
//!
//! Every operation is one [`Edit`] through [`super::apply_edit`], so the guard sees it as a
//! pseudo-motion: split vertices appear at their final place on the old surface (which
//! cannot create an intersection), and a snap moves both vertices to their average,
//! carrying their triangles, exactly like a collapse.
//!
//! **The fold rule** (Los Topos §7.1): where a triangle at `a` and a triangle at `b` share
//! an edge, the snap folds them onto each other; it is allowed only when the angle between
//! them at that edge is below [`SnapParams::max_fold_angle_deg`] (90°), so folded geometry
//! — the usual case in a collision — snaps, while vertices lying side by side in the plane
//! of a surface do not.

use glam::DVec3;

use crate::ids::{Label, TriId, VertexId};
use crate::mesh::LabeledMesh;

use super::attributes::{Blend, VertexAttributes};
use super::edit::{Edit, EditError, NewVertex, VertexMove, VertexRef, apply_snap_edit};
use super::guard::{EditGuard, Veto};

/// Parameters of [`snap_vertices`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SnapParams {
    /// Two triangles, one at each vertex, that share an edge may be folded onto each other
    /// only if the angle between them at that edge is below this (degrees). Default 90
    /// (Los Topos §7.1).
    pub max_fold_angle_deg: f64,
}

impl Default for SnapParams {
    fn default() -> Self {
        Self {
            max_fold_angle_deg: 90.0,
        }
    }
}

/// Why a snap was not attempted.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum SnapRefusal {
    /// The two ids are equal or not both live vertices with triangles.
    #[error("not two distinct live vertices")]
    NotTwoVertices,
    /// The vertices share an edge: that is an edge collapse, not a snap.
    #[error("vertices share an edge")]
    Adjacent,
    /// A triangle at one of the vertices has a repeated vertex.
    #[error("degenerate triangle at a vertex")]
    Degenerate,
    /// Two triangles sharing an edge would be folded together at too wide an angle.
    #[error("would fold triangles that meet at an angle of 90° or more")]
    FoldAngle,
}

/// Why [`snap_vertices`] failed; the mesh is unchanged.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SnapError {
    /// The snap is not allowed.
    #[error("snap refused: {0}")]
    Refused(#[from] SnapRefusal),
    /// The edit failed (guard veto or malformed).
    #[error(transparent)]
    Edit(#[from] EditError),
}

/// Snaps `b` onto `a` (see the module doc): both move to their average, `b` is deleted,
/// and `a`'s attributes become the average of the two. Returns `a`.
pub fn snap_vertices(
    mesh: &mut LabeledMesh,
    attrs: &mut VertexAttributes,
    guard: &mut dyn EditGuard,
    a: VertexId,
    b: VertexId,
    params: &SnapParams,
) -> Result<VertexId, SnapError> {
    if a == b
        || !mesh.is_vertex_alive(a)
        || !mesh.is_vertex_alive(b)
        || mesh.vertex_triangles(a).next().is_none()
        || mesh.vertex_triangles(b).next().is_none()
    {
        return Err(SnapRefusal::NotTwoVertices.into());
    }
    let degenerate = |t: TriId| {
        let [p, q, r] = mesh.tri(t);
        p == q || q == r || p == r
    };
    if mesh
        .vertex_triangles(a)
        .chain(mesh.vertex_triangles(b))
        .any(degenerate)
    {
        return Err(SnapRefusal::Degenerate.into());
    }
    if mesh.edge_triangles(a, b).next().is_some() {
        return Err(SnapRefusal::Adjacent.into());
    }
    check_fold(mesh, a, b, params)?;

    let target = (mesh.position(a) + mesh.position(b)) * 0.5;
    let mut edit = Edit::default();
    for t in mesh.vertex_triangles(b) {
        edit.remove_tris.push(t);
        let verts = mesh
            .tri(t)
            .map(|v| VertexRef::Old(if v == b { a } else { v }));
        edit.add_tris.push((verts, mesh.labels(t)));
    }
    edit.moves.push(VertexMove {
        vertex: a,
        end: target,
        blend: Some(Blend::lerp(a, b, 0.5)),
    });
    edit.moves.push(VertexMove {
        vertex: b,
        end: target,
        blend: None,
    });
    edit.remove_vertices.push(b);
    apply_snap_edit(mesh, attrs, guard, &edit)?;
    Ok(a)
}

/// The fold rule: every pair (triangle at `a`, triangle at `b`) sharing an edge `x y` must
/// meet at an angle below the limit, measured between the directions from the edge line
/// to `a` and to `b`.
fn check_fold(
    mesh: &LabeledMesh,
    a: VertexId,
    b: VertexId,
    params: &SnapParams,
) -> Result<(), SnapRefusal> {
    let cos_limit = params.max_fold_angle_deg.to_radians().cos();
    let (pa, pb) = (mesh.position(a), mesh.position(b));
    for ta in mesh.vertex_triangles(a) {
        let [x, y] = others(mesh.tri(ta), a);
        if !mesh
            .edge_triangles(x, y)
            .any(|tb| mesh.tri(tb).contains(&b))
        {
            continue;
        }
        let (px, py) = (mesh.position(x), mesh.position(y));
        let e = py - px;
        let off = |p: DVec3| {
            let r = p - px;
            let ee = e.length_squared();
            if ee > 0.0 { r - e * (r.dot(e) / ee) } else { r }
        };
        let (u, w) = (off(pa), off(pb));
        let norms = u.length() * w.length();
        // The angle is below the limit when cos(angle) > cos(limit).
        if !(norms > 0.0 && u.dot(w) > cos_limit * norms) {
            return Err(SnapRefusal::FoldAngle);
        }
    }
    Ok(())
}

/// The two vertices of `tri` other than `v`, in the triangle's order after `v`.
fn others(tri: [VertexId; 3], v: VertexId) -> [VertexId; 2] {
    let k = tri.iter().position(|&w| w == v).unwrap_or(0);
    [tri[(k + 1) % 3], tri[(k + 2) % 3]]
}

/// Splits edge `{a, b}` at `a + s (b − a)`, `s ∈ (0, 1)`, through every triangle on it (each
/// half keeps its parent's labels and orientation). The new vertex appears at that point
/// (no pseudo-motion); its attributes interpolate `a` and `b` at `s`.
///
/// Errors: [`EditError::Malformed`] when the edge does not exist, `s` is not strictly
/// inside `(0, 1)`, or a triangle on the edge is degenerate; otherwise the guard's veto.
pub fn split_edge_at(
    mesh: &mut LabeledMesh,
    attrs: &mut VertexAttributes,
    guard: &mut dyn EditGuard,
    a: VertexId,
    b: VertexId,
    s: f64,
) -> Result<VertexId, EditError> {
    if !(s > 0.0 && s < 1.0) {
        return Err(EditError::Malformed(format!(
            "split parameter {s} of edge {a}–{b} is not inside (0, 1)"
        )));
    }
    if a == b || !mesh.is_vertex_alive(a) || !mesh.is_vertex_alive(b) {
        return Err(EditError::Malformed(format!("no edge {a}–{b} to split")));
    }
    let tris: Vec<TriId> = mesh.edge_triangles(a, b).collect();
    if tris.is_empty() {
        return Err(EditError::Malformed(format!("no edge {a}–{b} to split")));
    }
    let (pa, pb) = (mesh.position(a), mesh.position(b));
    let p = pa + (pb - pa) * s;
    let mut edit = Edit::default();
    edit.new_vertices.push(NewVertex {
        start: p,
        end: p,
        blend: Blend::lerp(a, b, s),
    });
    let m = VertexRef::New(0);
    for t in tris {
        let tri = mesh.tri(t);
        if tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] {
            return Err(EditError::Malformed(format!(
                "edge {a}–{b} lies on degenerate triangle {t}"
            )));
        }
        edit.remove_tris.push(t);
        let tri = tri.map(VertexRef::Old);
        for replaced in [a, b] {
            let half = tri.map(|v| if v == VertexRef::Old(replaced) { m } else { v });
            edit.add_tris.push((half, mesh.labels(t)));
        }
    }
    apply_snap_edit(mesh, attrs, guard, &edit).map(|applied| applied.vertices[0])
}

/// Trisects triangle `t = [p, q, r]` at the point with barycentric coordinates `bary`
/// (all strictly positive, summing to 1): three triangles `[p, q, m]`, `[q, r, m]`,
/// `[r, p, m]` with `t`'s labels and orientation. The new vertex appears at that point;
/// its attributes interpolate the corners with `bary`.
///
/// Errors: [`EditError::Malformed`] for a dead or degenerate triangle or coordinates not
/// strictly inside; otherwise the guard's veto.
pub fn split_triangle_at(
    mesh: &mut LabeledMesh,
    attrs: &mut VertexAttributes,
    guard: &mut dyn EditGuard,
    t: TriId,
    bary: [f64; 3],
) -> Result<VertexId, EditError> {
    if !mesh.is_triangle_alive(t) {
        return Err(EditError::Malformed(format!("no triangle {t} to split")));
    }
    let sum: f64 = bary.iter().sum();
    let near_one = (sum - 1.0).abs() < 1e-9;
    if !bary.iter().all(|&w| w > 0.0 && w < 1.0) || !near_one {
        return Err(EditError::Malformed(format!(
            "barycentric coordinates {bary:?} are not strictly inside triangle {t}"
        )));
    }
    let tri = mesh.tri(t);
    if tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] {
        return Err(EditError::Malformed(format!("triangle {t} is degenerate")));
    }
    let x = mesh.tri_positions(t);
    let p = x[0] * bary[0] + x[1] * bary[1] + x[2] * bary[2];
    let mut edit = Edit::default();
    edit.new_vertices.push(NewVertex {
        start: p,
        end: p,
        blend: Blend::barycentric(tri, bary),
    });
    edit.remove_tris.push(t);
    let [v0, v1, v2] = tri.map(VertexRef::Old);
    let m = VertexRef::New(0);
    let labels = mesh.labels(t);
    for corners in [[v0, v1, m], [v1, v2, m], [v2, v0, m]] {
        edit.add_tris.push((corners, labels));
    }
    apply_snap_edit(mesh, attrs, guard, &edit).map(|applied| applied.vertices[0])
}

/// The triangles a split replaced, kept so that [`undo_split`] can put them back when the
/// snap the split prepared does not happen. Without it, a vetoed snap would leave the new
/// vertex where it was born — on the far side of a proximate pair, arbitrarily close to
/// the vertex it was meant to join — and the next collision step would start with two
/// elements in contact.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SplitRecord {
    replaced: Vec<([VertexId; 3], [Label; 2])>,
    /// Triangles around the new vertex right after the split.
    fan: usize,
}

impl SplitRecord {
    /// Records the triangles on edge `{a, b}` before [`split_edge_at`] splits it.
    pub fn edge(mesh: &LabeledMesh, a: VertexId, b: VertexId) -> Self {
        let replaced: Vec<_> = mesh
            .edge_triangles(a, b)
            .map(|t| (mesh.tri(t), mesh.labels(t)))
            .collect();
        let fan = 2 * replaced.len();
        Self { replaced, fan }
    }

    /// Records triangle `t` before [`split_triangle_at`] trisects it.
    pub fn triangle(mesh: &LabeledMesh, t: TriId) -> Self {
        Self {
            replaced: vec![(mesh.tri(t), mesh.labels(t))],
            fan: 3,
        }
    }
}

/// Undoes the split that created `vertex`, which must be the last edit applied since
/// `record` was taken: the triangles around `vertex` are replaced by the recorded ones and
/// `vertex` is deleted. The guard is told of the change but not asked: the result is the
/// mesh before the split, which was already accepted.
///
/// Errors: [`EditError::Malformed`] when `vertex` is dead or its triangles do not use only
/// the recorded triangles' vertices (the split was not the last edit).
pub fn undo_split(
    mesh: &mut LabeledMesh,
    attrs: &mut VertexAttributes,
    guard: &mut dyn EditGuard,
    vertex: VertexId,
    record: &SplitRecord,
) -> Result<(), EditError> {
    if !mesh.is_vertex_alive(vertex) {
        return Err(EditError::Malformed(format!(
            "no split vertex {vertex} to undo"
        )));
    }
    let mut edit = Edit::default();
    edit.remove_tris.extend(mesh.vertex_triangles(vertex));
    let known = |v: VertexId| v == vertex || record.replaced.iter().any(|(t, _)| t.contains(&v));
    if edit.remove_tris.len() != record.fan
        || !edit
            .remove_tris
            .iter()
            .all(|&t| mesh.tri(t).into_iter().all(known))
    {
        return Err(EditError::Malformed(format!(
            "vertex {vertex} is not the last split of the recorded triangles"
        )));
    }
    for &(tri, labels) in &record.replaced {
        edit.add_tris.push((tri.map(VertexRef::Old), labels));
    }
    edit.remove_vertices.push(vertex);
    apply_snap_edit(mesh, attrs, &mut Trusted(guard), &edit).map(|_| ())
}

/// Forwards commits to the wrapped guard without asking it: for edits that restore a
/// state the guard already accepted.
struct Trusted<'a>(&'a mut dyn EditGuard);

impl EditGuard for Trusted<'_> {
    fn check(&mut self, _mesh: &LabeledMesh, _edit: &Edit) -> Result<(), Veto> {
        Ok(())
    }

    fn committed(&mut self, mesh: &LabeledMesh, edit: &Edit, applied: &super::edit::Applied) {
        self.0.committed(mesh, edit, applied);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generators::icosphere;
    use crate::geometry::label_volumes;
    use crate::ids::Label;
    use crate::remesh::{NoGuard, remove_degenerate};
    use crate::validate::{ValidateOptions, validate};

    /// Two tetrahedra, mirror images across the plane z = 0, facing each other with
    /// parallel faces at z = ±h: region `l1` below, `l2` above, outside 0.
    fn facing_tets(h: f64, l1: u32, l2: u32) -> LabeledMesh {
        let base = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
        ];
        let mut p: Vec<DVec3> = base.iter().map(|&q| q + DVec3::Z * h).collect();
        p.push(DVec3::new(0.3, 0.3, 1.0));
        p.extend(base.iter().map(|&q| q - DVec3::Z * h));
        p.push(DVec3::new(0.3, 0.3, -1.0));
        // Outward-facing triangles of each tet, front = outside (0), back = inside.
        let upper = [[0u32, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]];
        let lower = [[4u32, 5, 6], [4, 7, 5], [5, 7, 6], [6, 7, 4]];
        let mut tris = Vec::new();
        let mut labels = Vec::new();
        for t in upper {
            tris.push(t);
            labels.push([0, l2]);
        }
        for t in lower {
            tris.push(t);
            labels.push([0, l1]);
        }
        LabeledMesh::from_raw(p, &tris, &labels).expect("valid")
    }

    fn snap_all(m: &mut LabeledMesh) {
        for (a, b) in [(4u32, 0u32), (5, 1), (6, 2)] {
            snap_vertices(
                m,
                &mut VertexAttributes::none(),
                &mut NoGuard,
                VertexId::new(a),
                VertexId::new(b),
                &SnapParams::default(),
            )
            .expect("snap");
        }
    }

    /// Live triangles as sorted `(corners, labels)`, rotated to start at the smallest id.
    fn triangle_set(m: &LabeledMesh) -> Vec<([VertexId; 3], [Label; 2])> {
        let mut out: Vec<_> = m
            .triangles()
            .map(|t| {
                let mut c = m.tri(t);
                let k = (0..3).min_by_key(|&k| c[k]).unwrap_or(0);
                c.rotate_left(k);
                (c, m.labels(t))
            })
            .collect();
        out.sort();
        out
    }

    #[test]
    fn undone_splits_restore_the_triangles_and_the_vertex_count() {
        let m0 = icosphere(1, DVec3::ZERO, 1.0, [Label::OUTSIDE, Label::new(1)]).expect("sphere");
        let mut m = m0.clone();
        let mut attrs = VertexAttributes::none();
        let t = m.triangles().next().expect("triangle");
        let record = SplitRecord::triangle(&m, t);
        let w = split_triangle_at(&mut m, &mut attrs, &mut NoGuard, t, [0.2, 0.3, 0.5])
            .expect("trisect");
        assert_ne!(triangle_set(&m), triangle_set(&m0));
        undo_split(&mut m, &mut attrs, &mut NoGuard, w, &record).expect("undo");
        assert_eq!(triangle_set(&m), triangle_set(&m0));
        assert_eq!(m.num_vertices(), m0.num_vertices());
        assert!(validate(&m, &ValidateOptions::with_intersections()).is_valid());

        let [a, b, _] = m.tri(m.triangles().next().expect("triangle"));
        let record = SplitRecord::edge(&m, a, b);
        let w = split_edge_at(&mut m, &mut attrs, &mut NoGuard, a, b, 0.3).expect("split");
        undo_split(&mut m, &mut attrs, &mut NoGuard, w, &record).expect("undo");
        assert_eq!(triangle_set(&m), triangle_set(&m0));
        assert!(validate(&m, &ValidateOptions::with_intersections()).is_valid());

        // A record that does not describe the vertex's split is refused, mesh unchanged.
        let w = split_edge_at(&mut m, &mut attrs, &mut NoGuard, a, b, 0.5).expect("split");
        let other = SplitRecord::triangle(&m, m.triangles().next().expect("triangle"));
        let before = triangle_set(&m);
        assert!(undo_split(&mut m, &mut attrs, &mut NoGuard, w, &other).is_err());
        assert_eq!(triangle_set(&m), before);
    }

    #[test]
    fn ideal_snap_of_equal_labels_merges_the_regions() {
        let mut m = facing_tets(0.01, 1, 1);
        snap_all(&mut m);
        assert_eq!(m.num_vertices(), 5);
        let r = remove_degenerate(&mut m, &mut VertexAttributes::none(), &mut NoGuard);
        assert_eq!(r.pairs_removed, 1, "{r:?}");
        let v = validate(&m, &ValidateOptions::with_intersections());
        assert!(v.is_valid(), "{v:?}");
        let bounded: Vec<_> = m.regions().bounded().cloned().collect();
        assert_eq!(bounded.len(), 1, "{bounded:?}");
        assert_eq!(bounded[0].label, Label::new(1));
    }

    #[test]
    fn ideal_snap_of_different_labels_makes_an_interface() {
        let mut m = facing_tets(0.01, 1, 2);
        snap_all(&mut m);
        let r = remove_degenerate(&mut m, &mut VertexAttributes::none(), &mut NoGuard);
        assert_eq!(r.pairs_relabelled, 1, "{r:?}");
        let v = validate(&m, &ValidateOptions::with_intersections());
        assert!(v.is_valid(), "{v:?}");
        let shared: Vec<TriId> = m
            .triangles()
            .filter(|&t| {
                let mut l = m.labels(t);
                l.sort();
                l == [Label::new(1), Label::new(2)]
            })
            .collect();
        assert_eq!(shared.len(), 1);
        let [x, y, _] = m.tri(shared[0]);
        assert_eq!(m.edge_triangles(x, y).count(), 3, "a triple curve");
        let vol = label_volumes(&m);
        assert!(vol[&Label::new(1)] > 0.0 && vol[&Label::new(2)] > 0.0);
    }

    #[test]
    fn snap_refuses_neighbours_and_flat_folds() {
        let mut m = icosphere(1, DVec3::ZERO, 1.0, [Label::OUTSIDE, Label::new(1)]).unwrap();
        let a = VertexId::new(0);
        let t = m.vertex_triangles(a).next().unwrap();
        let [b, c] = others(m.tri(t), a);
        let g = &mut NoGuard;
        let attrs = &mut VertexAttributes::none();
        let p = SnapParams::default();
        assert_eq!(
            snap_vertices(&mut m, attrs, g, a, b, &p),
            Err(SnapRefusal::Adjacent.into())
        );
        // The vertex across edge b–c from a: the two triangles are nearly coplanar.
        let d = m
            .edge_triangles(b, c)
            .flat_map(|u| m.tri(u))
            .find(|&w| w != a && w != b && w != c)
            .unwrap();
        assert_eq!(
            snap_vertices(&mut m, attrs, g, a, d, &p),
            Err(SnapRefusal::FoldAngle.into())
        );
    }

    #[test]
    fn splits_at_parameters_keep_volumes_and_validity() {
        let mut m = icosphere(1, DVec3::ZERO, 1.0, [Label::OUTSIDE, Label::new(1)]).unwrap();
        let before = label_volumes(&m)[&Label::new(1)];
        let (a, b) = {
            let t = m.triangles().next().unwrap();
            let [a, b, _] = m.tri(t);
            (a, b)
        };
        let attrs = &mut VertexAttributes::none();
        let v = split_edge_at(&mut m, attrs, &mut NoGuard, a, b, 0.3).unwrap();
        let want = m.position(a) + (m.position(b) - m.position(a)) * 0.3;
        assert!((m.position(v) - want).length() < 1e-15);
        let t = m.triangles().nth(5).unwrap();
        split_triangle_at(&mut m, attrs, &mut NoGuard, t, [0.2, 0.3, 0.5]).unwrap();
        assert!(split_edge_at(&mut m, attrs, &mut NoGuard, a, b, 1.0).is_err());
        assert!(split_triangle_at(&mut m, attrs, &mut NoGuard, t, [0.0, 0.5, 0.5]).is_err());
        assert_eq!(m.num_triangles(), 80 + 2 + 2);
        assert!((label_volumes(&m)[&Label::new(1)] - before).abs() < 1e-12);
        assert!(validate(&m, &ValidateOptions::with_intersections()).is_valid());
    }
}
