//! Edge split (El Topo §3.5.1), on any edge, manifold or not.
//!
//! Every triangle on the edge `{a, b}` is cut in two at a new vertex `m`; each half keeps
//! its parent's labels and orientation (the parent's vertex `a` or `b` is replaced by `m`
//! in place), so label consistency around every edge is preserved by construction.
//!
//! The new vertex appears at the midpoint — a position that cannot create an intersection
//! because the halves cover exactly the parent triangles — and may then move to a smooth
//! position (butterfly subdivision, El Topo eq. 3.5) as a pseudo-motion the guard checks.
//! If that position is refused for any reason the split is retried at the midpoint.

use glam::DVec3;

use crate::ids::{CornerId, TriId, VertexId};
use crate::mesh::LabeledMesh;

use super::attributes::{Blend, VertexAttributes};
use super::edit::{Edit, EditError, NewVertex, VertexRef, apply_edit};
use super::features::{self, FeatureParams, VertexKind};
use super::guard::EditGuard;

/// Where the new vertex of a split goes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SplitPlacement {
    /// The edge midpoint (never creates an intersection, never changes a volume).
    Midpoint,
    /// Butterfly subdivision on manifold, non-feature edges between two smooth vertices
    /// (midpoint elsewhere), refused in favour of the midpoint when it would invert a
    /// triangle, change a label volume by more than `max_volume_change`, or be vetoed.
    Butterfly {
        /// Classification thresholds for the endpoints.
        features: FeatureParams,
        /// Largest allowed change of any label's volume (Ω).
        max_volume_change: f64,
    },
}

/// Splits edge `{a, b}` (any number of incident triangles) and returns the new vertex.
/// Attributes of the new vertex interpolate `a` and `b` at the edge parameter ½.
///
/// Errors: [`EditError::Malformed`] when the edge does not exist or a triangle on it is
/// degenerate; [`EditError::Vetoed`] when the guard refuses even the midpoint split.
pub fn split_edge(
    mesh: &mut LabeledMesh,
    attrs: &mut VertexAttributes,
    guard: &mut dyn EditGuard,
    a: VertexId,
    b: VertexId,
    placement: SplitPlacement,
) -> Result<VertexId, EditError> {
    let mut scratch = SplitScratch::default();
    split_edge_in(&mut scratch, mesh, attrs, guard, a, b, placement).map(|s| s.vertex)
}

/// Reusable buffers for [`split_edge_in`].
#[derive(Debug, Default)]
pub(crate) struct SplitScratch {
    edit: Edit,
    tris: Vec<TriId>,
    volumes: Vec<(crate::ids::Label, f64)>,
}

/// What a split did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Split {
    pub vertex: VertexId,
    /// True when a smooth position was wanted but the midpoint was used.
    pub fell_back: bool,
    /// Largest label volume change of the committed edit.
    pub volume_change: f64,
}

/// [`split_edge`] with caller-owned buffers.
pub(crate) fn split_edge_in(
    s: &mut SplitScratch,
    mesh: &mut LabeledMesh,
    attrs: &mut VertexAttributes,
    guard: &mut dyn EditGuard,
    a: VertexId,
    b: VertexId,
    placement: SplitPlacement,
) -> Result<Split, EditError> {
    if a == b || !mesh.is_vertex_alive(a) || !mesh.is_vertex_alive(b) {
        return Err(EditError::Malformed(format!("no edge {a}–{b} to split")));
    }
    s.tris.clear();
    s.tris.extend(mesh.edge_triangles(a, b));
    if s.tris.is_empty() {
        return Err(EditError::Malformed(format!("no edge {a}–{b} to split")));
    }
    for &t in &s.tris {
        let [p, q, r] = mesh.tri(t);
        if p == q || q == r || p == r {
            return Err(EditError::Malformed(format!(
                "edge {a}–{b} lies on degenerate triangle {t}"
            )));
        }
    }
    let (pa, pb) = (mesh.position(a), mesh.position(b));
    let mid = (pa + pb) * 0.5;
    build_split(&mut s.edit, mesh, &s.tris, a, b, mid, mid);

    if let SplitPlacement::Butterfly {
        features,
        max_volume_change,
    } = placement
        && let Some(smooth) = butterfly_position(mesh, a, b, &features)
    {
        s.edit.new_vertices[0].end = smooth;
        let volume_change = features::max_label_volume_change(mesh, &s.edit, &mut s.volumes);
        if volume_change <= max_volume_change && new_triangles_keep_normals(mesh, &s.edit) {
            match apply_edit(mesh, attrs, guard, &s.edit) {
                Ok(applied) => {
                    return Ok(Split {
                        vertex: applied.vertices[0],
                        fell_back: false,
                        volume_change,
                    });
                }
                Err(EditError::Vetoed(_)) => {}
                Err(e) => return Err(e),
            }
        }
        s.edit.new_vertices[0].end = mid;
        let applied = apply_edit(mesh, attrs, guard, &s.edit)?;
        return Ok(Split {
            vertex: applied.vertices[0],
            fell_back: true,
            volume_change: 0.0,
        });
    }
    let applied = apply_edit(mesh, attrs, guard, &s.edit)?;
    Ok(Split {
        vertex: applied.vertices[0],
        fell_back: false,
        volume_change: 0.0,
    })
}

/// Fills `edit` with the split of `tris` (all triangles on `{a, b}`) at a new vertex that
/// starts at `start` and ends at `end`.
fn build_split(
    edit: &mut Edit,
    mesh: &LabeledMesh,
    tris: &[TriId],
    a: VertexId,
    b: VertexId,
    start: DVec3,
    end: DVec3,
) {
    edit.clear();
    edit.new_vertices.push(NewVertex {
        start,
        end,
        blend: Blend::lerp(a, b, 0.5),
    });
    let m = VertexRef::New(0);
    for &t in tris {
        let tri = mesh.tri(t).map(VertexRef::Old);
        let labels = mesh.labels(t);
        edit.remove_tris.push(t);
        // Replace a by m in one half and b by m in the other: orientation is unchanged.
        for replaced in [a, b] {
            let half = tri.map(|v| if v == VertexRef::Old(replaced) { m } else { v });
            edit.add_tris.push((half, labels));
        }
    }
}

/// True when every new triangle of a split keeps (certifiably) the orientation of the
/// parent triangle it came from. Halves are pushed in parent order, two per parent.
fn new_triangles_keep_normals(mesh: &LabeledMesh, edit: &Edit) -> bool {
    edit.remove_tris.iter().enumerate().all(|(i, &t)| {
        let old = mesh.tri_positions(t);
        edit.add_tris[2 * i..2 * i + 2].iter().all(|(verts, _)| {
            features::normals_agree(&old, &verts.map(|v| edit.end_position(mesh, v)))
        })
    })
}

/// The butterfly position of the midpoint of `{a, b}`:
/// `(8(P1+P2) + 2(Q1+Q2) − (R1+R2+R3+R4)) / 16`, or `None` when the stencil is not a plain
/// manifold patch (feature edges, non-smooth endpoints, missing neighbours): there the
/// midpoint is the only placement that respects the feature.
fn butterfly_position(
    mesh: &LabeledMesh,
    a: VertexId,
    b: VertexId,
    params: &FeatureParams,
) -> Option<DVec3> {
    let c = features::edge_corner(mesh, a, b)?;
    if features::edge_star(mesh, c).is_feature() {
        return None;
    }
    for v in [a, b] {
        if !matches!(
            features::classify_vertex(mesh, v, params),
            VertexKind::Smooth { .. }
        ) {
            return None;
        }
    }
    // The two wings: c (on the first triangle) and the corner across the edge.
    let d = mesh.opposite(c)?;
    let mut q = DVec3::ZERO;
    let mut r = DVec3::ZERO;
    for wing in [c, d] {
        q += mesh.position(mesh.corner_vertex(wing));
        // The R vertices lie across the wing triangle's two other edges.
        for k in [wing.next(), wing.prev()] {
            r += mesh.position(far_vertex(mesh, k)?);
        }
    }
    let (pa, pb) = (mesh.position(a), mesh.position(b));
    Some((8.0 * (pa + pb) + 2.0 * q - r) / 16.0)
}

/// The vertex across the (manifold, non-feature) edge opposite corner `k`.
fn far_vertex(mesh: &LabeledMesh, k: CornerId) -> Option<VertexId> {
    if features::edge_star(mesh, k).is_feature() {
        return None;
    }
    mesh.opposite(k).map(|o| mesh.corner_vertex(o))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::geometry::label_volumes;
    use crate::remesh::guard::NoGuard;

    /// Three triangles (a fin) on edge 0–1 plus closing faces: three tetrahedral-ish
    /// regions around a triple edge. Built as a "triangular prism book": regions 1, 2 and
    /// the outside 0 meet along edge 0–1.
    pub(crate) fn triple_edge_scene() -> LabeledMesh {
        // Edge 0–1 along z; three fins to 2, 3, 4 at 120°; closed by caps (0,2,3)... as
        // two tetrahedra sharing the fin 0-1-3: region 1 = tet(0,1,2,3), region 2 =
        // tet(0,1,3,4). Outside label 0.
        let p = vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(0.0, 0.0, 1.0),
            DVec3::new(1.0, 0.0, 0.5),
            DVec3::new(-0.5, 0.866, 0.5),
            DVec3::new(-0.5, -0.866, 0.5),
        ];
        let tris = [
            [0, 1, 3], // shared fin
            [0, 2, 1], // region 1's other fin
            [0, 3, 2],
            [1, 2, 3],
            [0, 1, 4], // region 2
            [0, 4, 3],
            [1, 3, 4],
        ];
        let mut labels = Vec::new();
        let tris_v: Vec<[u32; 3]> = tris.to_vec();
        // Orient labels from geometry: the front side of a face of tet T faces away from T
        // if its normal points away from T's centroid.
        let tets = [([0usize, 1, 2, 3], 1u32), ([0, 1, 3, 4], 2u32)];
        for tri in &tris_v {
            let q = tri.map(|i| p[i as usize]);
            let n = (q[1] - q[0]).cross(q[2] - q[0]);
            let mut pair = [0u32, 0u32];
            for (tet, l) in tets {
                if tri.iter().all(|&i| tet.contains(&(i as usize))) {
                    let c = tet.iter().map(|&i| p[i]).sum::<DVec3>() / 4.0;
                    // Normal pointing towards the centroid: the tet is in front.
                    if n.dot(c - q[0]) > 0.0 {
                        pair[0] = l
                    } else {
                        pair[1] = l
                    }
                }
            }
            labels.push(pair);
        }
        LabeledMesh::from_raw(p, &tris_v, &labels).expect("valid arrays")
    }

    #[test]
    fn split_non_manifold_edge_keeps_labels_and_volumes() {
        let mut m = triple_edge_scene();
        let before = label_volumes(&m);
        let n0 = m.num_triangles();
        let v = split_edge(
            &mut m,
            &mut VertexAttributes::none(),
            &mut NoGuard,
            VertexId::new(0),
            VertexId::new(1),
            SplitPlacement::Midpoint,
        )
        .expect("split");
        assert_eq!(
            m.num_triangles(),
            n0 + 3,
            "three triangles on the triple edge"
        );
        assert!((m.position(v) - DVec3::new(0.0, 0.0, 0.5)).length() < 1e-15);
        let after = label_volumes(&m);
        for (l, vol) in &before {
            assert!(
                (after[l] - vol).abs() < 1e-14,
                "label {l} volume {vol} -> {}",
                after[l]
            );
        }
        assert!(features::is_feature_edge(&m, VertexId::new(0), v));
        assert!(features::is_feature_edge(&m, v, VertexId::new(1)));
        // Every region shell stays closed and consistently labelled, and the mesh validates
        // (intersections included).
        let regions = m.regions();
        assert!(
            regions.shells.iter().all(|s| s.closed && s.consistent),
            "{:?}",
            regions.shells
        );
        let report =
            crate::validate::validate(&m, &crate::validate::ValidateOptions::with_intersections());
        assert!(report.is_valid(), "{report:?}");
    }

    #[test]
    fn split_interpolates_attributes() {
        let mut m = triple_edge_scene();
        let mut attrs = VertexAttributes::zeros(&m, 2);
        attrs.get_mut(VertexId::new(2)).copy_from_slice(&[1.0, 4.0]);
        attrs.get_mut(VertexId::new(3)).copy_from_slice(&[3.0, 0.0]);
        let v = split_edge(
            &mut m,
            &mut attrs,
            &mut NoGuard,
            VertexId::new(2),
            VertexId::new(3),
            SplitPlacement::Midpoint,
        )
        .expect("split");
        assert_eq!(attrs.get(v), &[2.0, 2.0]);
    }

    #[test]
    fn split_of_missing_edge_is_malformed() {
        let mut m = triple_edge_scene();
        let r = split_edge(
            &mut m,
            &mut VertexAttributes::none(),
            &mut NoGuard,
            VertexId::new(2),
            VertexId::new(4),
            SplitPlacement::Midpoint,
        );
        assert!(matches!(r, Err(EditError::Malformed(_))));
    }
}
