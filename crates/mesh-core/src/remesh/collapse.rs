//! Feature-aware edge collapse (El Topo §3.5.3, Los Topos §4.3).
//!
//! `collapse_edge(a, b)` removes `b`: every triangle on the edge disappears, every other
//! triangle of `b` is re-formed onto `a` in place (same slot, so the same orientation and
//! labels), and `a` moves to the merged position. The pseudo-motion the guard sees moves
//! both `a` and `b` to that position.
//!
//! **Where the merged vertex goes** depends on the endpoints' [`VertexKind`]s: two smooth
//! vertices meet at the midpoint (with `conserve_volume`, shifted along their normal by
//! what keeps every label's volume: the midpoint sits on a chord and shaves a sliver off
//! a convex patch); a feature vertex (ridge, corner, curve) keeps its place
//! against a smooth one; two ridge vertices merge at the midpoint only along their ridge;
//! two vertices of a feature curve merge only along a curve edge, onto one endpoint, so
//! the curve keeps its vertices exactly. Everything else is refused. On an edge shorter
//! than [`CollapseParams::min_feature_size`], ridges and corners count as smooth: a
//! geometric feature that small is noise (feature curves are kept at every size, and so
//! are their junctions; a kink of a curve that small merges like a curve vertex). In the
//! [`CollapsePlacement::Midpoint`] mode (the collision tracker's T1/T2-initiating
//! collapse) the endpoints always meet at the midpoint and their kinds are not asked.
//!
//! **Refusals** (the mesh is untouched): joining two feature curves through a non-feature
//! edge (a pinch, which would glue two curves into one and change topology); a violated
//! link condition (common neighbours of `a` and `b` that are not wings of the edge, or a
//! re-formed triangle that duplicates an existing one) unless degenerate results are
//! asked for; an inverted surviving triangle (certified sign test, see
//! [`features`]); a normal rotating more than allowed; a new edge longer than allowed; a
//! label volume changing by more than Ω.

use glam::DVec3;

use crate::ids::{Label, TriId, VertexId};
use crate::mesh::LabeledMesh;

use super::attributes::{Blend, VertexAttributes};
use super::edit::{Edit, EditError, VertexMove, VertexRef, apply_edit};
use super::features::{self, FeatureParams, VertexKind};
use super::guard::EditGuard;

/// Parameters of [`collapse_edge`].
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct CollapseParams {
    /// Classification thresholds for the endpoints.
    pub features: FeatureParams,
    /// Largest allowed change of any label's volume (Ω). Default: no limit.
    pub max_volume_change: f64,
    /// Largest allowed length of an edge at the merged vertex; keeps a collapse from
    /// creating an edge that the next split would cut again. Default: no limit.
    pub max_edge_length: f64,
    /// Smallest allowed cosine between a surviving triangle's normal before and after.
    /// Default 0.5 (60°): larger rotations fold the surface even when nothing inverts.
    pub min_normal_cos: f64,
    /// Two ridge vertices merge only if both ridge directions make an angle with the edge
    /// whose cosine is at least this. Default cos 30°.
    pub ridge_alignment_cos: f64,
    /// Skip the link condition (duplicate triangles may result, for T2 removal to
    /// resolve). Default false.
    pub allow_degenerate: bool,
    /// Move a midpoint collapse of two smooth vertices along their normal by what keeps
    /// every label's volume (see the module doc). Default false (see
    /// [`super::ImproveParams::conserve_volume`]).
    pub conserve_volume: bool,
    /// Where the merged vertex goes. Default [`CollapsePlacement::Features`].
    pub placement: CollapsePlacement,
    /// Geometric features (ridges and corners of a patch; feature curves are not
    /// geometric) shorter than this are noise: an edge shorter than it is placed as if
    /// its ridge and corner endpoints were smooth. Why: a crumple below the mesh's
    /// resolution classifies as corners and ridges, which collapses and smoothing both
    /// keep in place, so it never goes away. Measured before this existed: after two
    /// spheres touched, 5–11 % of the collision backend's triangles had an angle under
    /// 10° and the shortest 1 % of edges were a fiftieth of the target length. Default 0
    /// (every geometric feature kept).
    pub min_feature_size: f64,
}

/// Where [`collapse_edge`] puts the merged vertex.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub enum CollapsePlacement {
    /// By the endpoints' kinds (see the module doc); collapses that would join two feature
    /// curves or corners, and so change topology, are refused. Mesh improvement's collapse.
    #[default]
    Features,
    /// Always the midpoint, whatever the endpoints' kinds: the collapse that *starts* a T1
    /// or T2 process (Los Topos §5–6) by joining exactly the feature curves and corners
    /// that improvement keeps apart. Pair it with `allow_degenerate`: it may flatten a
    /// tetrahedron into coincident triangles, which T2 then removes.
    Midpoint,
}

impl Default for CollapseParams {
    fn default() -> Self {
        Self {
            features: FeatureParams::default(),
            max_volume_change: f64::INFINITY,
            max_edge_length: f64::INFINITY,
            min_normal_cos: 0.5,
            ridge_alignment_cos: 30f64.to_radians().cos(),
            allow_degenerate: false,
            conserve_volume: false,
            placement: CollapsePlacement::Features,
            min_feature_size: 0.0,
        }
    }
}

/// Why a collapse was not attempted.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum CollapseRefusal {
    /// `{a, b}` is not an edge, or a triangle at `a` or `b` is degenerate.
    #[error("not a collapsible edge")]
    NoEdge,
    /// Both endpoints are features that must keep their places.
    #[error("both endpoints are features")]
    Features,
    /// Both endpoints lie on feature curves but the edge is not a curve edge.
    #[error("would pinch two feature curves together")]
    Pinch,
    /// The link condition fails: the collapse would change topology or duplicate a triangle.
    #[error("link condition violated")]
    Link,
    /// A surviving triangle would invert (or degenerate).
    #[error("would invert a triangle")]
    Inversion,
    /// A surviving triangle's normal would rotate too much.
    #[error("normal would rotate too much")]
    NormalChange,
    /// An edge at the merged vertex would be too long.
    #[error("would create a long edge")]
    EdgeLength,
    /// A label volume would change by more than Ω.
    #[error("volume change above the limit")]
    VolumeChange,
    /// A material's volume would change by more than its share
    /// ([`super::ImproveParams::max_material_share`]): the material is too thin for the
    /// target edge length, and the collapse would flatten it.
    #[error("would change a thin material's volume by more than its share")]
    MaterialShare,
}

/// Why [`collapse_edge`] failed; the mesh is unchanged.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CollapseError {
    /// The collapse is not allowed.
    #[error("collapse refused: {0}")]
    Refused(#[from] CollapseRefusal),
    /// The edit failed (guard veto or malformed).
    #[error(transparent)]
    Edit(#[from] EditError),
}

impl CollapseError {
    /// A short fixed name of the reason, for counting refusals per kind without
    /// formatting a message for each.
    pub fn reason(&self) -> &'static str {
        match self {
            CollapseError::Refused(r) => match r {
                CollapseRefusal::NoEdge => "no edge",
                CollapseRefusal::Features => "features",
                CollapseRefusal::Pinch => "pinch",
                CollapseRefusal::Link => "link condition",
                CollapseRefusal::Inversion => "inversion",
                CollapseRefusal::NormalChange => "normal change",
                CollapseRefusal::EdgeLength => "edge length",
                CollapseRefusal::VolumeChange => "volume change",
                CollapseRefusal::MaterialShare => "material share",
            },
            CollapseError::Edit(e) => e.reason(),
        }
    }
}

/// Where the merged vertex goes, as the parameter `t` along `a → b` (0, ½ or 1).
fn placement(
    ka: VertexKind,
    kb: VertexKind,
    curve_edge: bool,
    dir: DVec3,
    p: &CollapseParams,
) -> Result<f64, CollapseRefusal> {
    use VertexKind::*;
    let aligned = |k: VertexKind| match k {
        Ridge { direction } => direction.dot(dir).abs() >= p.ridge_alignment_cos,
        _ => true,
    };
    match (ka, kb) {
        (Smooth { .. }, Smooth { .. }) => Ok(0.5),
        (Smooth { .. }, _) => Ok(1.0),
        (_, Smooth { .. }) => Ok(0.0),
        (Ridge { .. }, Ridge { .. }) if aligned(ka) && aligned(kb) => Ok(0.5),
        (a, b) if a.on_curve() && b.on_curve() => match (curve_edge, a, b) {
            (false, ..) => Err(CollapseRefusal::Pinch),
            (true, Curve { .. }, Curve { .. }) | (true, CurveCorner, Curve { .. }) => Ok(0.0),
            (true, Curve { .. }, CurveCorner) => Ok(1.0),
            _ => Err(CollapseRefusal::Features),
        },
        (Ridge { .. }, Corner | Curve { .. } | CurveCorner) if aligned(ka) => Ok(1.0),
        (Corner | Curve { .. } | CurveCorner, Ridge { .. }) if aligned(kb) => Ok(0.0),
        _ => Err(CollapseRefusal::Features),
    }
}

/// Reusable buffers for [`collapse_edge_in`].
#[derive(Debug, Default)]
pub(crate) struct CollapseScratch {
    edit: Edit,
    wings: Vec<VertexId>,
    nbr_a: Vec<VertexId>,
    tris: Vec<TriId>,
    volumes: Vec<(Label, f64)>,
    /// Per material, the largest volume change one collapse may cause besides Ω (see
    /// [`CollapseRefusal::MaterialShare`]); empty: none.
    pub(crate) caps: Vec<(Label, f64)>,
}

/// Collapses edge `{a, b}` onto `a`, removing `b` (see the module doc). The attributes of
/// `a` become those interpolated at the merged position along the edge (the average for
/// a midpoint collapse, a copy when one endpoint keeps its place).
pub fn collapse_edge(
    mesh: &mut LabeledMesh,
    attrs: &mut VertexAttributes,
    guard: &mut dyn EditGuard,
    a: VertexId,
    b: VertexId,
    params: &CollapseParams,
) -> Result<(), CollapseError> {
    collapse_edge_in(
        &mut CollapseScratch::default(),
        mesh,
        attrs,
        guard,
        a,
        b,
        params,
    )
    .map(|_| ())
}

/// [`collapse_edge`] with caller-owned buffers; returns the largest label volume change.
pub(crate) fn collapse_edge_in(
    s: &mut CollapseScratch,
    mesh: &mut LabeledMesh,
    attrs: &mut VertexAttributes,
    guard: &mut dyn EditGuard,
    a: VertexId,
    b: VertexId,
    params: &CollapseParams,
) -> Result<f64, CollapseError> {
    if a == b || !mesh.is_vertex_alive(a) || !mesh.is_vertex_alive(b) {
        return Err(CollapseRefusal::NoEdge.into());
    }
    let corner = features::edge_corner(mesh, a, b).ok_or(CollapseRefusal::NoEdge)?;
    for v in [a, b] {
        if mesh.vertex_triangles(v).any(|t| is_degenerate(mesh.tri(t))) {
            return Err(CollapseRefusal::NoEdge.into());
        }
    }
    // b is removed whatever the placement: a guard that refuses that refuses the edit.
    guard.check_vertex(mesh, b).map_err(EditError::Vetoed)?;
    let (pa, pb) = (mesh.position(a), mesh.position(b));
    // The endpoints' kinds, where the placement asks for them.
    let (kinds, t) = match params.placement {
        CollapsePlacement::Features => {
            let curve_edge = features::edge_star(mesh, corner).is_feature();
            let ka = features::classify_vertex(mesh, a, &params.features);
            let kb = features::classify_vertex(mesh, b, &params.features);
            let below_features = pa.distance(pb) < params.min_feature_size;
            let dir = (pb - pa).normalize_or_zero();
            let placed = |k: VertexKind, v: VertexId| match k {
                VertexKind::Ridge { .. } | VertexKind::Corner if below_features => {
                    VertexKind::Smooth {
                        normal: DVec3::ZERO,
                    }
                }
                // A kink of a feature curve (two feature edges) that small is noise too:
                // the curve goes on through it, so it merges along its curve edge like any
                // curve vertex. Junctions of curves keep their place at every size.
                VertexKind::CurveCorner
                    if below_features && curve_edge && features::feature_degree(mesh, v) == 2 =>
                {
                    VertexKind::Curve { tangent: dir }
                }
                _ => k,
            };
            let t = placement(placed(ka, a), placed(kb, b), curve_edge, dir, params)?;
            (Some((ka, kb)), t)
        }
        CollapsePlacement::Midpoint => (None, 0.5),
    };
    // a moves unless it keeps its place: a guard that refuses moving it refuses the edit,
    // asked before the edit is built and measured.
    if t != 0.0 {
        guard.check_vertex(mesh, a).map_err(EditError::Vetoed)?;
    }
    let mut target = if t == 0.0 {
        pa
    } else if t == 1.0 {
        pb
    } else {
        pa + (pb - pa) * t
    };

    // Wings: far vertices of the triangles on the edge.
    s.wings.clear();
    for tri in mesh.edge_triangles(a, b).map(|t| mesh.tri(t)) {
        s.wings
            .extend(tri.iter().copied().filter(|&v| v != a && v != b));
    }
    if !params.allow_degenerate {
        link_condition(s, mesh, a, b)?;
    }

    // The edit: every triangle of b is removed; those not on the edge come back on a.
    let edit = &mut s.edit;
    edit.clear();
    s.tris.clear();
    s.tris.extend(mesh.vertex_triangles(b));
    for &tb in &s.tris {
        let tri = mesh.tri(tb);
        edit.remove_tris.push(tb);
        if !tri.contains(&a) {
            let verts = tri.map(|v| VertexRef::Old(if v == b { a } else { v }));
            edit.add_tris.push((verts, mesh.labels(tb)));
        }
    }
    if t != 0.0 {
        edit.moves.push(VertexMove {
            vertex: a,
            end: target,
            blend: Some(Blend::lerp(a, b, t)),
        });
    }
    edit.moves.push(VertexMove {
        vertex: b,
        end: target,
        blend: None,
    });
    edit.remove_vertices.push(b);

    if let (true, Some((VertexKind::Smooth { normal: na }, VertexKind::Smooth { normal: nb }))) =
        (params.conserve_volume, kinds)
    {
        // Two smooth vertices meet at the midpoint, a chord below (or above) the surface
        // they sampled: the shift puts the merged vertex where the volume is kept. A
        // quarter of the edge bounds it; beyond that the patch is not smooth enough for
        // the shift to be the surface, and the Ω check decides as before.
        let normal = na + nb * na.dot(nb).signum();
        let reach = 0.25 * pa.distance(pb);
        if features::conserve_volume_along(mesh, edit, normal, reach, &mut s.volumes).is_some() {
            target = edit.moves[0].end;
        }
    }
    check_geometry(edit, mesh, a, b, target, params)?;
    let dv = features::max_label_volume_change(mesh, edit, &mut s.volumes);
    if dv > params.max_volume_change {
        return Err(CollapseRefusal::VolumeChange.into());
    }
    if features::exceeds_caps(&s.volumes, &s.caps) {
        return Err(CollapseRefusal::MaterialShare.into());
    }
    apply_edit(mesh, attrs, guard, edit)?;
    Ok(dv)
}

fn is_degenerate(t: [VertexId; 3]) -> bool {
    t[0] == t[1] || t[1] == t[2] || t[0] == t[2]
}

/// The link condition: every common neighbour of `a` and `b` is a wing of the edge, and no
/// re-formed triangle duplicates a triangle of `a`.
fn link_condition(
    s: &mut CollapseScratch,
    mesh: &LabeledMesh,
    a: VertexId,
    b: VertexId,
) -> Result<(), CollapseRefusal> {
    s.nbr_a.clear();
    for t in mesh.vertex_triangles(a) {
        s.nbr_a
            .extend(mesh.tri(t).iter().copied().filter(|&v| v != a));
    }
    for tb in mesh.vertex_triangles(b) {
        let tri = mesh.tri(tb);
        if tri.contains(&a) {
            continue;
        }
        for &w in &tri {
            if w != b && s.nbr_a.contains(&w) && !s.wings.contains(&w) {
                return Err(CollapseRefusal::Link);
            }
        }
        // Both other vertices are wings: (a, x, y) may already exist.
        let others: [VertexId; 2] = {
            let k = tri.iter().position(|&v| v == b).unwrap_or(0);
            [tri[(k + 1) % 3], tri[(k + 2) % 3]]
        };
        if others.iter().all(|w| s.wings.contains(w))
            && mesh.vertex_triangles(a).any(|ta| {
                let t2 = mesh.tri(ta);
                t2.contains(&others[0]) && t2.contains(&others[1])
            })
        {
            return Err(CollapseRefusal::Link);
        }
    }
    Ok(())
}

/// Orientation, normal rotation and edge length of every triangle that survives and moves.
fn check_geometry(
    edit: &Edit,
    mesh: &LabeledMesh,
    a: VertexId,
    b: VertexId,
    target: DVec3,
    params: &CollapseParams,
) -> Result<(), CollapseRefusal> {
    let check = |old: [DVec3; 3], new: [DVec3; 3]| {
        if !features::normals_agree(&old, &new) {
            return Err(CollapseRefusal::Inversion);
        }
        if features::normal_cos(&old, &new).is_none_or(|c| c < params.min_normal_cos) {
            return Err(CollapseRefusal::NormalChange);
        }
        Ok(())
    };
    let too_long = |w: VertexId| (mesh.position(w) - target).length() > params.max_edge_length;
    // Re-formed triangles of b (added in the order of b's triangles not on the edge).
    let mut added = edit.add_tris.iter();
    for tb in mesh.vertex_triangles(b) {
        let tri = mesh.tri(tb);
        if tri.contains(&a) {
            continue;
        }
        let Some((verts, _)) = added.next() else {
            break;
        };
        check(
            mesh.tri_positions(tb),
            verts.map(|v| edit.end_position(mesh, v)),
        )?;
        if tri.iter().any(|&w| w != b && too_long(w)) {
            return Err(CollapseRefusal::EdgeLength);
        }
    }
    // Kept triangles of a, if a moves.
    if edit.moves.iter().any(|m| m.vertex == a) {
        for ta in mesh.vertex_triangles(a) {
            let tri = mesh.tri(ta);
            if tri.contains(&b) {
                continue;
            }
            check(
                mesh.tri_positions(ta),
                tri.map(|v| if v == a { target } else { mesh.position(v) }),
            )?;
            if tri.iter().any(|&w| w != a && too_long(w)) {
                return Err(CollapseRefusal::EdgeLength);
            }
        }
    }
    Ok(())
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::remesh::guard::NoGuard;

    /// An octahedron with vertex 0 at `p0` (regular when `p0 = (1, 0, 0)`).
    fn octahedron(p0: DVec3) -> LabeledMesh {
        octahedron_at([p0, DVec3::Y, -DVec3::X, -DVec3::Y, DVec3::Z, -DVec3::Z])
    }

    /// The octahedron's triangles over vertices `±x, ±y` (0–3, counter-clockwise from
    /// `+x`), `+z` (4) and `−z` (5), outward.
    const OCTAHEDRON: [[u32; 3]; 8] = [
        [0, 1, 4],
        [1, 2, 4],
        [2, 3, 4],
        [3, 0, 4],
        [1, 0, 5],
        [2, 1, 5],
        [3, 2, 5],
        [0, 3, 5],
    ];

    /// The regular octahedron's vertices, in [`OCTAHEDRON`]'s order.
    const UNIT_OCTAHEDRON: [DVec3; 6] = [
        DVec3::X,
        DVec3::Y,
        DVec3::NEG_X,
        DVec3::NEG_Y,
        DVec3::Z,
        DVec3::NEG_Z,
    ];

    /// The octahedron of label 1 in label 0 with corners `p`, listed as +x, +y, −x, −y,
    /// +z, −z of the regular one; fronts face outwards while `p` keeps that shape. Shared
    /// with the flip tests, which squash it.
    pub(crate) fn octahedron_at(p: [DVec3; 6]) -> LabeledMesh {
        LabeledMesh::from_raw(p.to_vec(), &OCTAHEDRON, &[[0, 1]; 8]).expect("valid arrays")
    }

    /// Collapses edge 0–1 of `m` onto vertex 0 with no normal limit and the given smallest
    /// feature size; the outcome and the mesh after it.
    fn collapse_first_edge(
        mut m: LabeledMesh,
        min_feature_size: f64,
    ) -> (Result<(), CollapseError>, LabeledMesh) {
        let p = CollapseParams {
            min_normal_cos: -1.0,
            min_feature_size,
            ..CollapseParams::default()
        };
        let (a, b) = (VertexId::new(0), VertexId::new(1));
        let r = collapse_edge(
            &mut m,
            &mut VertexAttributes::none(),
            &mut NoGuard,
            a,
            b,
            &p,
        );
        (r, m)
    }

    /// Everything smooth (no eigenvalue can exceed 2·λ1), no geometric limits.
    fn lenient() -> CollapseParams {
        CollapseParams {
            features: FeatureParams {
                rank_ratio: 2.0,
                ..FeatureParams::default()
            },
            min_normal_cos: -1.0,
            ..CollapseParams::default()
        }
    }

    /// Two unit boxes side by side along x, labels 1 and 2, outside 0; the shared square
    /// at x = 1 has corners 1, 4, 10, 7 and diagonal 1–10.
    pub(crate) fn double_box() -> LabeledMesh {
        let mut p = Vec::new();
        for iz in 0..2 {
            for iy in 0..2 {
                for ix in 0..3 {
                    p.push(DVec3::new(ix as f64, iy as f64, iz as f64));
                }
            }
        }
        let mut quads = vec![[0u32, 3, 9, 6], [1, 4, 10, 7], [2, 5, 11, 8]];
        for ix in 0..2u32 {
            quads.push([ix, ix + 1, ix + 7, ix + 6]);
            quads.push([ix + 3, ix + 4, ix + 10, ix + 9]);
            quads.push([ix, ix + 1, ix + 4, ix + 3]);
            quads.push([ix + 6, ix + 7, ix + 10, ix + 9]);
        }
        let label_at = |q: DVec3| {
            let inside = q.y > 0.0 && q.y < 1.0 && q.z > 0.0 && q.z < 1.0;
            match (inside, q.x) {
                (true, x) if x > 0.0 && x < 1.0 => 1,
                (true, x) if x > 1.0 && x < 2.0 => 2,
                _ => 0,
            }
        };
        let mut tris = Vec::new();
        let mut labels = Vec::new();
        for q in quads {
            for tri in [[q[0], q[1], q[2]], [q[0], q[2], q[3]]] {
                let t = tri.map(|i| p[i as usize]);
                let n = (t[1] - t[0]).cross(t[2] - t[0]).normalize();
                let c = (t[0] + t[1] + t[2]) / 3.0;
                tris.push(tri);
                labels.push([label_at(c + 1e-3 * n), label_at(c - 1e-3 * n)]);
            }
        }
        LabeledMesh::from_raw(p, &tris, &labels).expect("valid arrays")
    }

    #[test]
    fn collapse_averages_attributes_and_removes_b() {
        let mut m = octahedron(DVec3::X);
        let mut attrs = VertexAttributes::zeros(&m, 1);
        attrs.get_mut(VertexId::new(0))[0] = 2.0;
        attrs.get_mut(VertexId::new(4))[0] = 6.0;
        collapse_edge(
            &mut m,
            &mut attrs,
            &mut NoGuard,
            VertexId::new(0),
            VertexId::new(4),
            &lenient(),
        )
        .expect("collapse");
        assert!(!m.is_vertex_alive(VertexId::new(4)));
        assert_eq!(m.num_triangles(), 6);
        assert_eq!(attrs.get(VertexId::new(0)), &[4.0]);
        assert!((m.position(VertexId::new(0)) - DVec3::new(0.5, 0.0, 0.5)).length() < 1e-15);
        let regions = m.regions();
        assert!(regions.shells.iter().all(|s| s.closed && s.consistent));
    }

    #[test]
    fn collapse_refuses_inversion_and_leaves_mesh_identical() {
        // Vertex 0 far out: the midpoint of 0–4 lies beyond edge 1–2 of triangle (1,2,4).
        let mut m = octahedron(DVec3::new(-4.0, 4.0, 0.0));
        let before = m.to_raw();
        let r = collapse_edge(
            &mut m,
            &mut VertexAttributes::none(),
            &mut NoGuard,
            VertexId::new(0),
            VertexId::new(4),
            &lenient(),
        );
        assert_eq!(r, Err(CollapseError::Refused(CollapseRefusal::Inversion)));
        assert_eq!(m.to_raw(), before);
    }

    #[test]
    fn collapse_refuses_pinch_of_two_curve_vertices() {
        let mut m = double_box();
        let before = m.to_raw();
        for angle in [45.0, 100.0] {
            let p = CollapseParams {
                features: FeatureParams {
                    curve_corner_angle_deg: angle,
                    ..FeatureParams::default()
                },
                ..CollapseParams::default()
            };
            let r = collapse_edge(
                &mut m,
                &mut VertexAttributes::none(),
                &mut NoGuard,
                VertexId::new(1),
                VertexId::new(10),
                &p,
            );
            assert_eq!(
                r,
                Err(CollapseError::Refused(CollapseRefusal::Pinch)),
                "angle {angle}"
            );
        }
        assert_eq!(m.to_raw(), before);
    }

    /// The T1/T2-initiating mode joins the two curve vertices that the feature placement
    /// refuses to pinch, at the midpoint; the geometric checks still hold it back.
    #[test]
    fn midpoint_mode_joins_what_feature_placement_refuses() {
        let mut m = double_box();
        let (a, b) = (VertexId::new(1), VertexId::new(10));
        let (pa, pb) = (m.position(a), m.position(b));
        let p = CollapseParams {
            placement: CollapsePlacement::Midpoint,
            allow_degenerate: true,
            min_normal_cos: 0.0,
            ..CollapseParams::default()
        };
        collapse_edge(
            &mut m,
            &mut VertexAttributes::none(),
            &mut NoGuard,
            a,
            b,
            &p,
        )
        .expect("the initiating collapse");
        assert!(m.position(a).distance(0.5 * (pa + pb)) < 1e-12);
        assert!(!m.is_vertex_alive(b));
        // Allowing the survivors no turn at all refuses it, and the mesh is untouched.
        let mut m = double_box();
        let before = m.to_raw();
        let strict = CollapseParams {
            min_normal_cos: 1.0,
            ..p
        };
        let r = collapse_edge(
            &mut m,
            &mut VertexAttributes::none(),
            &mut NoGuard,
            a,
            b,
            &strict,
        );
        assert!(
            matches!(
                r,
                Err(CollapseError::Refused(
                    CollapseRefusal::NormalChange | CollapseRefusal::Inversion
                ))
            ),
            "{r:?}"
        );
        assert_eq!(m.to_raw(), before);
    }

    #[test]
    fn collapse_along_a_curve_keeps_the_curve_vertex() {
        let mut m = double_box();
        let p = CollapseParams {
            features: FeatureParams {
                curve_corner_angle_deg: 100.0,
                ..FeatureParams::default()
            },
            min_normal_cos: -1.0,
            ..CollapseParams::default()
        };
        // 1 and 4 are curve vertices joined by a triple edge: 4 merges onto 1's position.
        collapse_edge(
            &mut m,
            &mut VertexAttributes::none(),
            &mut NoGuard,
            VertexId::new(1),
            VertexId::new(4),
            &p,
        )
        .expect("collapse along the curve");
        assert_eq!(m.position(VertexId::new(1)), DVec3::new(1.0, 0.0, 0.0));
        let report =
            crate::validate::validate(&m, &crate::validate::ValidateOptions::with_intersections());
        assert!(report.is_valid(), "{report:?}");
        // Smooth–feature: a box corner (rank 3) against a smooth vertex is refused as two
        // features only when both are features; corner 0 and curve 1 are both features.
        let r = collapse_edge(
            &mut m,
            &mut VertexAttributes::none(),
            &mut NoGuard,
            VertexId::new(0),
            VertexId::new(1),
            &p,
        );
        assert_eq!(r, Err(CollapseError::Refused(CollapseRefusal::Features)));
    }

    /// The regular octahedron's vertices are all corners: an edge between two of them is
    /// kept as a feature, unless it is shorter than the smallest feature size, when it
    /// collapses to its midpoint like a smooth edge.
    #[test]
    fn corners_below_the_feature_size_collapse_to_the_midpoint() {
        let (a, b) = (VertexId::new(0), VertexId::new(1));
        let collapse = |size| collapse_first_edge(octahedron_at(UNIT_OCTAHEDRON), size);
        let (r, _) = collapse(1.0);
        assert_eq!(r, Err(CollapseError::Refused(CollapseRefusal::Features)));
        let (r, m) = collapse(1.5);
        r.expect("an edge of √2 below a feature size of 1.5 collapses");
        assert_eq!(m.position(a), DVec3::new(0.5, 0.5, 0.0));
        assert!(!m.is_vertex_alive(b));
    }

    /// A double-bubble octahedron: labels 1 (top) and 2 (bottom) with the equatorial
    /// square as their wall, so the equator is a triple curve with a 90° kink at every
    /// vertex (two feature edges each). A curve edge between two kinks is kept while the
    /// kinks are larger than the smallest feature size, and collapses along the curve onto
    /// one end (the curve keeps its vertices) once they are smaller; the result is valid.
    #[test]
    fn curve_kinks_below_the_feature_size_collapse_along_the_curve() {
        let mut tris = OCTAHEDRON.to_vec();
        tris.extend([[0, 1, 2], [0, 2, 3]]);
        let mut labels = vec![[0, 1]; 4];
        labels.extend([[0, 2]; 4]);
        labels.extend([[1, 2]; 2]);
        let mesh =
            LabeledMesh::from_raw(UNIT_OCTAHEDRON.to_vec(), &tris, &labels).expect("valid arrays");
        let valid = |m: &LabeledMesh| {
            crate::validate::validate(m, &crate::validate::ValidateOptions::default()).is_valid()
        };
        assert!(valid(&mesh));
        let (a, b) = (VertexId::new(0), VertexId::new(1));
        let collapse = |size| collapse_first_edge(mesh.clone(), size);
        let (r, _) = collapse(1.0);
        assert_eq!(r, Err(CollapseError::Refused(CollapseRefusal::Features)));
        let (r, m) = collapse(1.5);
        r.expect("a curve edge of √2 between kinks below a feature size of 1.5 collapses");
        assert_eq!(m.position(a), DVec3::X);
        assert!(!m.is_vertex_alive(b));
        assert!(valid(&m));
    }

    #[test]
    fn link_condition_guards_duplicates_unless_asked() {
        let p = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
        let tris = [[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]];
        let mut m = LabeledMesh::from_raw(p, &tris, &[[0, 1]; 4]).expect("valid arrays");
        let (a, b) = (VertexId::new(0), VertexId::new(1));
        let r = collapse_edge(
            &mut m,
            &mut VertexAttributes::none(),
            &mut NoGuard,
            a,
            b,
            &lenient(),
        );
        assert_eq!(r, Err(CollapseError::Refused(CollapseRefusal::Link)));
        // Asked for: the tetrahedron flattens into a coincident pair, which T2 then removes.
        let asked = CollapseParams {
            allow_degenerate: true,
            ..lenient()
        };
        collapse_edge(
            &mut m,
            &mut VertexAttributes::none(),
            &mut NoGuard,
            a,
            b,
            &asked,
        )
        .expect("collapse");
        assert_eq!(m.num_triangles(), 2);
        let report = crate::validate::validate(&m, &crate::validate::ValidateOptions::default());
        assert_eq!(report.duplicates.count, 1);
        let t2 =
            crate::remesh::remove_degenerate(&mut m, &mut VertexAttributes::none(), &mut NoGuard);
        assert_eq!(t2.pairs_removed, 1);
        assert_eq!(m.num_triangles(), 0);
    }

    #[test]
    fn placement_rules() {
        let p = CollapseParams::default();
        let s = VertexKind::Smooth { normal: DVec3::Z };
        let r = VertexKind::Ridge {
            direction: DVec3::X,
        };
        let c = VertexKind::Curve { tangent: DVec3::X };
        assert_eq!(placement(s, s, false, DVec3::X, &p), Ok(0.5));
        assert_eq!(placement(s, r, false, DVec3::X, &p), Ok(1.0));
        assert_eq!(placement(c, s, false, DVec3::X, &p), Ok(0.0));
        assert_eq!(placement(r, r, false, DVec3::X, &p), Ok(0.5));
        assert_eq!(
            placement(r, r, false, DVec3::Y, &p),
            Err(CollapseRefusal::Features)
        );
        assert_eq!(placement(c, c, true, DVec3::X, &p), Ok(0.0));
        assert_eq!(
            placement(c, c, false, DVec3::X, &p),
            Err(CollapseRefusal::Pinch)
        );
        assert_eq!(
            placement(c, VertexKind::CurveCorner, true, DVec3::X, &p),
            Ok(1.0)
        );
        assert_eq!(
            placement(
                VertexKind::CurveCorner,
                VertexKind::CurveCorner,
                true,
                DVec3::X,
                &p
            ),
            Err(CollapseRefusal::Features)
        );
        assert_eq!(
            placement(VertexKind::Corner, c, true, DVec3::X, &p),
            Err(CollapseRefusal::Features)
        );
    }
}
