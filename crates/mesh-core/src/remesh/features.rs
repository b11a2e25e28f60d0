//! Local feature analysis: what kind of point of the surface a vertex is, and the local
//! geometric measures every remeshing operation checks before it edits.
//!
//! **Vertex kinds.** A vertex on a *feature curve* — incident to an edge with ≠ 2
//! triangles (a triple curve of a foam) or to an edge whose two triangles' label pairs
//! differ as sets — is a [`VertexKind::Curve`] when exactly two feature edges meet there and
//! the curve turns gently, and a [`VertexKind::CurveCorner`] otherwise (a quadruple point,
//! a curve end, a kink). Every other vertex is classified by the eigenvalues
//! `λ1 ≥ λ2 ≥ λ3` of its *quadric metric tensor* `A = Σ areaᵢ nᵢ nᵢᵀ` over the incident
//! triangles (Jiao 2007; El Topo §3.5.3, §3.6.1): the number of eigenvalues above
//! `rank_ratio · λ1` is the dimension of the normal space — 1 on a smooth patch, 2 on a
//! ridge (the ridge runs along the eigenvector of `λ3`), 3 at a corner.
//!
//! **Null space.** [`VertexKind::project`] is the projector of null-space smoothing
//! (El Topo §3.6.1): the tangent plane on a smooth patch, the ridge line on a ridge, and
//! nothing at corners and on feature curves, which therefore never move.
//!
//! **Edit measures** (crate-internal): the per-label volume change of an [`Edit`], and a
//! certified test that a triangle's normal does not invert — the checks every operation
//! makes before asking the guard.

use glam::DVec3;
use nalgebra::Matrix3;
use rayon::prelude::*;

use crate::ids::{CornerId, Label, TriId, VertexId};
use crate::mesh::LabeledMesh;
use crate::{Side, geometry};

use super::edit::{Edit, VertexRef};

/// Thresholds of the vertex classification.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct FeatureParams {
    /// An eigenvalue of the quadric tensor counts towards the normal space when it exceeds
    /// `rank_ratio · λ1`. Default 0.03 (El Topo's `G_EIGENVALUE_RANK_RATIO`): two planes
    /// of equal area meeting at a dihedral turn θ give `λ2/λ1 = tan²(θ/2)`, so ridges
    /// sharper than ≈ 20° are features and gentle curvature is not.
    pub rank_ratio: f64,
    /// A vertex with two feature edges whose curve turns by more than this angle (degrees)
    /// is a [`VertexKind::CurveCorner`]: collapses must not cut such a kink. Default 45°,
    /// far above the few degrees a resolved curve turns per vertex.
    pub curve_corner_angle_deg: f64,
}

impl Default for FeatureParams {
    fn default() -> Self {
        Self {
            rank_ratio: 0.03,
            curve_corner_angle_deg: 45.0,
        }
    }
}

/// What kind of surface point a vertex is (see the module doc).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum VertexKind {
    /// On a smooth patch; `normal` is the dominant eigenvector of the quadric tensor
    /// (unoriented).
    Smooth {
        /// Unit normal of the tangent plane.
        normal: DVec3,
    },
    /// On a geometric ridge of a manifold patch.
    Ridge {
        /// Unit direction of the ridge (unoriented).
        direction: DVec3,
    },
    /// A geometric corner of a manifold patch (or a vertex whose triangles have no area).
    Corner,
    /// Inside a feature curve (triple curve or label boundary): exactly two feature edges.
    Curve {
        /// Unit direction from one curve neighbour to the other.
        tangent: DVec3,
    },
    /// Where ≠ 2 feature edges meet, or a feature curve kinks.
    CurveCorner,
}

impl VertexKind {
    /// Projects a displacement onto the vertex's null space: the part of the motion that
    /// does not change the shape to first order. Zero for corners and feature curves.
    #[inline]
    pub fn project(&self, d: DVec3) -> DVec3 {
        match *self {
            VertexKind::Smooth { normal } => d - normal * normal.dot(d),
            VertexKind::Ridge { direction } => direction * direction.dot(d),
            VertexKind::Corner | VertexKind::Curve { .. } | VertexKind::CurveCorner => DVec3::ZERO,
        }
    }

    /// True on a non-manifold or label feature curve (curve or curve corner).
    #[inline]
    pub fn on_curve(&self) -> bool {
        matches!(self, VertexKind::Curve { .. } | VertexKind::CurveCorner)
    }

    /// True for every kind but [`VertexKind::Smooth`].
    #[inline]
    pub fn is_feature(&self) -> bool {
        !matches!(self, VertexKind::Smooth { .. })
    }
}

/// The star of one edge, walked radially from a corner opposite it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct EdgeStar {
    /// Number of incident triangles.
    pub count: usize,
    /// Smallest incident triangle id (used to visit each edge once).
    pub min_tri: TriId,
    /// True when every incident triangle has the same label set `{front, back}`.
    pub labels_agree: bool,
}

impl EdgeStar {
    /// A feature edge: not exactly two triangles, or two with different label sets.
    #[inline]
    pub fn is_feature(&self) -> bool {
        self.count != 2 || !self.labels_agree
    }
}

#[inline]
fn label_set(mesh: &LabeledMesh, t: TriId) -> [Label; 2] {
    let [f, b] = mesh.labels(t);
    if f <= b { [f, b] } else { [b, f] }
}

/// The star of the edge opposite corner `c`.
pub(crate) fn edge_star(mesh: &LabeledMesh, c: CornerId) -> EdgeStar {
    let first = label_set(mesh, c.tri());
    let mut star = EdgeStar {
        count: 0,
        min_tri: c.tri(),
        labels_agree: true,
    };
    for r in mesh.radial_corners(c) {
        star.count += 1;
        star.min_tri = star.min_tri.min(r.tri());
        star.labels_agree &= label_set(mesh, r.tri()) == first;
    }
    star
}

/// The front corner of some triangle on edge `{a, b}` that lies opposite the edge, if the
/// edge exists (and is not only part of degenerate triangles).
pub(crate) fn edge_corner(mesh: &LabeledMesh, a: VertexId, b: VertexId) -> Option<CornerId> {
    mesh.vertex_corners(a).find_map(|c| {
        let tri = mesh.tri(c.tri());
        let k = (0..3).find(|&k| {
            tri[(k + 1) % 3] != tri[(k + 2) % 3] && {
                let (p, q) = (tri[(k + 1) % 3], tri[(k + 2) % 3]);
                (p == a && q == b) || (p == b && q == a)
            }
        })?;
        Some(CornerId::of(c.tri(), Side::Front, k))
    })
}

/// True when `{a, b}` is an edge with ≠ 2 triangles or whose triangles' label sets differ.
/// False when the edge does not exist.
pub fn is_feature_edge(mesh: &LabeledMesh, a: VertexId, b: VertexId) -> bool {
    edge_corner(mesh, a, b).is_some_and(|c| edge_star(mesh, c).is_feature())
}

/// Number of feature edges at `v`: 2 inside a feature curve (kinked or not), another
/// number at a junction of curves or a curve's end.
pub(crate) fn feature_degree(mesh: &LabeledMesh, v: VertexId) -> usize {
    let mut count = 0;
    for_each_edge_at(mesh, v, |_, star| count += usize::from(star.is_feature()));
    count
}

/// Calls `f(w, star)` once for every edge `{v, w}` at `v` (skipping degenerate triangles).
pub(crate) fn for_each_edge_at(
    mesh: &LabeledMesh,
    v: VertexId,
    mut f: impl FnMut(VertexId, EdgeStar),
) {
    for c in mesh.vertex_corners(v) {
        let t = c.tri();
        let tri = mesh.tri(t);
        if tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] {
            continue;
        }
        // The two edges at v are opposite the other two corners of the triangle.
        for k in [c.next(), c.prev()] {
            let star = edge_star(mesh, k);
            if star.min_tri == t {
                let [p, q] = mesh.corner_edge(k);
                f(if p == v { q } else { p }, star);
            }
        }
    }
}

/// True when the triangles at `v` form a single closed fan whose every edge at `v` has
/// exactly two triangles with equal label sets: then `v` has no feature edge. Walks the fan
/// once on one side (valence steps, O(1) each), which is about half the work of visiting
/// every edge star; `false` means "not proven" (non-manifold, feature or degenerate).
fn plain_fan(mesh: &LabeledMesh, v: VertexId) -> bool {
    let mut valence = 0usize;
    let mut first = None;
    for c in mesh.vertex_corners(v) {
        let tri = mesh.tri(c.tri());
        if tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] {
            return false;
        }
        first.get_or_insert(c);
        valence += 1;
    }
    let Some(c0) = first else { return false };
    let labels = label_set(mesh, c0.tri());
    // Leave each triangle through the edge {v, w} opposite the corner `k` at w's partner.
    let start = c0.prev();
    let mut k = start;
    for step in 1..=valence {
        let Some(o) = mesh.opposite(k) else {
            return false;
        };
        if mesh.opposite(o.dual()) != Some(k.dual()) || label_set(mesh, o.tri()) != labels {
            return false;
        }
        let [p, q] = mesh.corner_edge(k);
        let w = if p == v { q } else { p };
        // In the neighbour, the next exit edge {v, x} lies opposite the corner at w.
        k = if mesh.corner_vertex(o.next()) == w {
            o.next()
        } else if mesh.corner_vertex(o.prev()) == w {
            o.prev()
        } else {
            return false;
        };
        if k == start {
            return step == valence;
        }
    }
    false
}

/// The quadric metric tensor `Σ area · n nᵀ` of the triangles at `v`.
pub fn quadric_tensor(mesh: &LabeledMesh, v: VertexId) -> Matrix3<f64> {
    quadric_with_normal(mesh, v).0
}

/// The quadric tensor and the sum of the area-weighted normals (a hint for
/// [`classify_with_hint`]).
pub(crate) fn quadric_with_normal(mesh: &LabeledMesh, v: VertexId) -> (Matrix3<f64>, DVec3) {
    let mut a = Matrix3::zeros();
    let mut sum = DVec3::ZERO;
    for t in mesh.vertex_triangles(v) {
        let an = geometry::area_normal(&mesh.tri_positions(t));
        add_to_quadric(&mut a, an);
        sum += an;
    }
    (a, sum)
}

/// Adds `area · n̂ n̂ᵀ = an anᵀ / area` for an area-weighted normal `an`.
#[inline]
pub(crate) fn add_to_quadric(a: &mut Matrix3<f64>, an: DVec3) {
    let area = an.length();
    if area > 0.0 && area.is_finite() {
        let n = nalgebra::Vector3::new(an.x, an.y, an.z);
        *a += n * n.transpose() / area;
    }
}

/// [`classify_by_quadric`] with a cheap certificate first: for any direction `h`, the
/// Rayleigh quotient `ρ = hᵀAh/|h|²` is at most `λ1`, and `λ2 + λ3 = tr A − λ1 ≤ tr A − ρ`.
/// So `tr A − ρ < rank_ratio · ρ` proves the vertex smooth without an eigen-decomposition;
/// with `h` the summed area normal this settles almost every vertex of a smooth surface.
/// The normal is then `A h` normalised (one power-iteration step towards the eigenvector).
pub(crate) fn classify_with_hint(
    a: Matrix3<f64>,
    hint: DVec3,
    params: &FeatureParams,
) -> VertexKind {
    let n2 = hint.length_squared();
    let trace = a.trace();
    if n2 > 0.0 && trace > 0.0 && trace.is_finite() {
        let h = nalgebra::Vector3::new(hint.x, hint.y, hint.z);
        let ah = a * h;
        let rho = h.dot(&ah) / n2;
        // The 0.99 absorbs rounding in ρ and the trace.
        if trace - rho < 0.99 * params.rank_ratio * rho {
            let normal = DVec3::new(ah[0], ah[1], ah[2]).normalize_or_zero();
            if normal != DVec3::ZERO {
                return VertexKind::Smooth { normal };
            }
        }
    }
    classify_by_quadric(a, params)
}

/// Classifies a vertex (see the module doc). Dead or isolated vertices are corners.
pub fn classify_vertex(mesh: &LabeledMesh, v: VertexId, params: &FeatureParams) -> VertexKind {
    if !mesh.is_vertex_alive(v) {
        return VertexKind::Corner;
    }
    if plain_fan(mesh, v) {
        let (a, hint) = quadric_with_normal(mesh, v);
        return classify_with_hint(a, hint, params);
    }
    let mut count = 0usize;
    let mut ends = [v; 2];
    for_each_edge_at(mesh, v, |w, star| {
        if star.is_feature() {
            if count < 2 {
                ends[count] = w;
            }
            count += 1;
        }
    });
    match count {
        0 => {
            let (a, hint) = quadric_with_normal(mesh, v);
            classify_with_hint(a, hint, params)
        }
        2 => {
            let p = mesh.position(v);
            let (d0, d1) = (p - mesh.position(ends[0]), mesh.position(ends[1]) - p);
            let turn_cos = d0.normalize_or_zero().dot(d1.normalize_or_zero());
            let tangent = (mesh.position(ends[1]) - mesh.position(ends[0])).normalize_or_zero();
            if turn_cos < params.curve_corner_angle_deg.to_radians().cos() || tangent == DVec3::ZERO
            {
                VertexKind::CurveCorner
            } else {
                VertexKind::Curve { tangent }
            }
        }
        _ => VertexKind::CurveCorner,
    }
}

/// Classifies a vertex of a manifold patch from its quadric tensor.
pub fn classify_by_quadric(a: Matrix3<f64>, params: &FeatureParams) -> VertexKind {
    if !a.iter().all(|x| x.is_finite()) {
        return VertexKind::Corner;
    }
    let eig = a.symmetric_eigen();
    let mut order = [0usize, 1, 2];
    order.sort_by(|&i, &j| eig.eigenvalues[j].total_cmp(&eig.eigenvalues[i]));
    let l1 = eig.eigenvalues[order[0]];
    if l1 <= 0.0 {
        return VertexKind::Corner;
    }
    let column = |i: usize| {
        let c = eig.eigenvectors.column(order[i]);
        DVec3::new(c[0], c[1], c[2]).normalize_or_zero()
    };
    let rank = 1 + order[1..]
        .iter()
        .filter(|&&i| eig.eigenvalues[i] > params.rank_ratio * l1)
        .count();
    match rank {
        1 => VertexKind::Smooth { normal: column(0) },
        2 => VertexKind::Ridge {
            direction: column(2),
        },
        _ => VertexKind::Corner,
    }
}

/// Classifies every vertex slot in parallel (dead slots are corners).
pub fn classify_vertices(mesh: &LabeledMesh, params: &FeatureParams) -> Vec<VertexKind> {
    (0..mesh.vertex_capacity() as u32)
        .into_par_iter()
        .map(|i| classify_vertex(mesh, VertexId::new(i), params))
        .collect()
}

// ----- edit measures -------------------------------------------------------------------

/// Largest absolute change of any label's enclosed volume that `edit` causes: removed
/// triangles and the start state of kept triangles at moved vertices count out, added
/// triangles and the end state of kept moved triangles count in (each triangle adds its
/// cone volume to its back label and subtracts it from its front label, as in
/// [`geometry::label_volumes`]). `buf` is scratch space.
///
/// Whether any label's change in `changes` (as [`max_label_volume_change`] leaves them in
/// its buffer) exceeds that label's cap in `caps` (sorted by label; a label without a
/// cap is unbounded).
pub(crate) fn exceeds_caps(changes: &[(Label, f64)], caps: &[(Label, f64)]) -> bool {
    !caps.is_empty()
        && changes.iter().any(|&(l, dv)| {
            caps.binary_search_by_key(&l, |c| c.0)
                .is_ok_and(|i| dv.abs() > caps[i].1)
        })
}

/// The caps of [`exceeds_caps`] for `mesh`: `share` of the volume of each bounded
/// material that is *thin and extended* — its area at least [`EXTENDED_AREA_RATIO`] times
/// that of a ball of its own thickness `t = 3V/A` (a ball: 1; a cube: 1.9; a plate 2.2 ×
/// 1 × 0.2: 8.5). Label 0, the outside, and materials of no positive volume have none.
///
/// Why not every material: a compact material shrinking under the flow (a foam cell
/// before its T2) must be coarsened by collapses that each take a large share of it until
/// it is small enough to remove; a plate thinner than the target edge must not be.
pub(crate) fn material_caps(mesh: &LabeledMesh, share: f64) -> Vec<(Label, f64)> {
    if !(share.is_finite() && share > 0.0) {
        return Vec::new();
    }
    let mut area: std::collections::BTreeMap<Label, f64> = std::collections::BTreeMap::new();
    for t in mesh.triangles() {
        let a = geometry::triangle_area(&mesh.tri_positions(t));
        let [f, b] = mesh.labels(t);
        *area.entry(f).or_default() += a;
        if b != f {
            *area.entry(b).or_default() += a;
        }
    }
    geometry::label_volumes(mesh)
        .into_iter()
        .filter(|&(l, v)| {
            let a = area.get(&l).copied().unwrap_or(0.0);
            let t = 3.0 * v / a.max(f64::MIN_POSITIVE);
            l != Label::OUTSIDE
                && v > 0.0
                && a >= EXTENDED_AREA_RATIO * 4.0 * std::f64::consts::PI * t * t
        })
        .map(|(l, v)| (l, share * v))
        .collect()
}

/// See [`material_caps`]: 4 keeps every roughly round material (cubes, foam cells, their
/// elongated cousins up to about 3:1) free of the cap.
const EXTENDED_AREA_RATIO: f64 = 4.0;

/// Public because every operation bounded by Ω needs it, in mesh-core and in the
/// backends' own edits (the collision tracker's wall relaxation).
pub fn max_label_volume_change(
    mesh: &LabeledMesh,
    edit: &Edit,
    buf: &mut Vec<(Label, f64)>,
) -> f64 {
    buf.clear();
    // A reference point near the edit keeps the cone volumes small and their sum exact-ish.
    let r = match (edit.moves.first(), edit.remove_tris.first()) {
        (Some(m), _) => mesh.position(m.vertex),
        (None, Some(&t)) => mesh.position(mesh.tri(t)[0]),
        (None, None) => return 0.0,
    };
    let mut add = |labels: [Label; 2], p: [DVec3; 3], sign: f64| {
        let v = sign * geometry::signed_cone_volume(p[0] - r, p[1] - r, p[2] - r);
        for (l, dv) in [(labels[1], v), (labels[0], -v)] {
            match buf.iter_mut().find(|e| e.0 == l) {
                Some(e) => e.1 += dv,
                None => buf.push((l, dv)),
            }
        }
    };
    for &t in &edit.remove_tris {
        add(mesh.labels(t), mesh.tri_positions(t), -1.0);
    }
    for (verts, labels) in &edit.add_tris {
        add(*labels, verts.map(|v| edit.end_position(mesh, v)), 1.0);
    }
    for (i, m) in edit.moves.iter().enumerate() {
        for t in mesh.vertex_triangles(m.vertex) {
            let tri = mesh.tri(t);
            let seen = edit.moves[..i].iter().any(|e| tri.contains(&e.vertex));
            if seen || edit.remove_tris.contains(&t) {
                continue;
            }
            add(mesh.labels(t), mesh.tri_positions(t), -1.0);
            add(
                mesh.labels(t),
                tri.map(|v| edit.end_position(mesh, VertexRef::Old(v))),
                1.0,
            );
        }
    }
    buf.iter().fold(0.0, |m, e| m.max(e.1.abs()))
}

/// Shifts the end positions of all of `edit`'s moves by one common offset along `dir` so
/// that no label's volume changes, and returns the shift (`None`, with the edit
/// untouched, when that is not possible within `max_shift`).
///
/// Why it is exact: with every other vertex fixed, each label's enclosed volume is an
/// affine function of the one position the moves share (a cone volume is linear in each
/// of its corners), so two evaluations give the slope along `dir` and the root is the
/// shift. An edit between exactly two labels has one volume to keep (the other changes by
/// its negative); an edit touching more labels is left alone, as is one whose volume does
/// not depend on the shift (slope below rounding). Used by smoothing, by midpoint
/// collapses on smooth patches and by flips (the new edge's ends), so that remeshing stops
/// feeding volume drift (El Topo bounds each edit's change by Ω; this removes it to
/// rounding where the surface allows).
pub(crate) fn conserve_volume_along(
    mesh: &LabeledMesh,
    edit: &mut Edit,
    dir: DVec3,
    max_shift: f64,
    buf: &mut Vec<(Label, f64)>,
) -> Option<f64> {
    let usable = max_shift > 0.0 && dir.is_finite() && dir != DVec3::ZERO;
    if edit.moves.is_empty() || !usable {
        return None;
    }
    let dir = dir.normalize();
    max_label_volume_change(mesh, edit, buf);
    let (label, dv0) = match buf.as_slice() {
        [] => return Some(0.0),
        [(_, dv), (_, _)] if *dv == 0.0 => return Some(0.0),
        [(l, dv), (_, _)] => (*l, *dv),
        _ => return None,
    };
    let shift_all = |edit: &mut Edit, by: DVec3| edit.moves.iter_mut().for_each(|m| m.end += by);
    // A probe step of the size the shift may take: the volume is affine, so the size only
    // sets the rounding of the slope.
    let h = max_shift;
    shift_all(edit, h * dir);
    max_label_volume_change(mesh, edit, buf);
    let dv1 = buf.iter().find(|e| e.0 == label).map_or(0.0, |e| e.1);
    let slope = (dv1 - dv0) / h;
    let s = -dv0 / slope;
    if slope.is_finite()
        && slope.abs() > 1e-12 * (dv0.abs() + dv1.abs()) / h
        && s.abs() <= max_shift
    {
        shift_all(edit, (s - h) * dir);
        Some(s)
    } else {
        shift_all(edit, -h * dir);
        None
    }
}

/// Unit-free cosine of the angle between the normals of two triangles, or `None` when
/// either is degenerate.
#[inline]
pub fn normal_cos(old: &[DVec3; 3], new: &[DVec3; 3]) -> Option<f64> {
    let (a, b) = (geometry::unit_normal(old), geometry::unit_normal(new));
    (a != DVec3::ZERO && b != DVec3::ZERO).then(|| a.dot(b))
}

/// Certified test that the right-hand normals of `old` and `new` point into the same half
/// space: `n_old · n_new > 0` evaluated in floating point and accepted only when it
/// exceeds a forward error bound. Conservative: an uncertain sign (or a degenerate
/// triangle) counts as an inversion, so a `true` is never wrong. The inversion test of
/// every operation that moves or re-forms triangles, here and in the backends.
///
/// Bound: each normal component `a_j b_k − a_k b_j` of differences carries an error below
/// `4u·(|a_j b_k| + |a_k b_j|)`; the dot product of two such vectors then errs by less than
/// `(2·4 + 3 + O(u))·u·Σ Mᵒᵢ Mⁿᵢ` with `Mᵢ` the component magnitudes — 16u leaves margin.
pub fn normals_agree(old: &[DVec3; 3], new: &[DVec3; 3]) -> bool {
    let cross_mag = |p: &[DVec3; 3]| {
        let (a, b) = (p[1] - p[0], p[2] - p[0]);
        let n = a.cross(b);
        let m = DVec3::new(
            (a.y * b.z).abs() + (a.z * b.y).abs(),
            (a.z * b.x).abs() + (a.x * b.z).abs(),
            (a.x * b.y).abs() + (a.y * b.x).abs(),
        );
        (n, m)
    };
    let (no, mo) = cross_mag(old);
    let (nn, mn) = cross_mag(new);
    let d = no.dot(nn);
    let bound = 16.0 * (f64::EPSILON / 2.0) * mo.dot(mn);
    d.is_finite() && d > bound
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tetra_pair() -> LabeledMesh {
        // Two tetrahedra glued on a face: the shared face's edges are triple edges.
        let p = vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(0.2, 0.2, 1.0),
            DVec3::new(0.2, 0.2, -1.0),
        ];
        // Region 1 above z=0 (apex 3), region 2 below (apex 4); outside 0.
        let tris = [
            [0, 2, 1],
            [0, 1, 3],
            [1, 2, 3],
            [2, 0, 3],
            [0, 1, 4],
            [1, 2, 4],
            [2, 0, 4],
        ];
        let labels = [[2, 1], [0, 1], [0, 1], [0, 1], [2, 0], [2, 0], [2, 0]];
        LabeledMesh::from_raw(p, &tris, &labels).expect("valid arrays")
    }

    /// A tangential move of one sphere vertex changes the volume; the conserving shift
    /// along the normal cancels it to rounding. At a vertex where three materials meet
    /// there are two volumes to keep and one shift: the edit is left alone.
    #[test]
    fn conserving_shift_cancels_a_moves_volume_change() {
        let m = crate::generators::icosphere(2, DVec3::ZERO, 1.0, [Label::new(0), Label::new(1)])
            .expect("sphere");
        // Not one of the icosahedron's 12 vertices: their neighbours are coplanar, and a
        // move parallel to that plane keeps the fan's volume exactly.
        let v = VertexId::new(30);
        let p = m.position(v);
        let tangent = p.any_orthonormal_vector();
        let start = p + 0.1 * tangent + 0.01 * p;
        let mut edit = Edit::default();
        edit.moves.push(super::super::edit::VertexMove {
            vertex: v,
            end: start,
            blend: None,
        });
        let mut buf = Vec::new();
        let before = max_label_volume_change(&m, &edit, &mut buf);
        assert!(before > 1e-5, "{before}");
        let shift = conserve_volume_along(&m, &mut edit, p, 0.1, &mut buf).expect("a shift");
        assert!(shift != 0.0 && shift.abs() < 0.05, "small: {shift}");
        let end = edit.moves[0].end;
        assert!((end - (start + shift * p.normalize())).length() < 1e-15);
        assert!(max_label_volume_change(&m, &edit, &mut buf) < 1e-15);

        let m = tetra_pair();
        let v = VertexId::new(0);
        let start = m.position(v) + DVec3::new(0.1, 0.1, 0.05);
        edit.moves[0] = super::super::edit::VertexMove {
            vertex: v,
            end: start,
            blend: None,
        };
        assert_eq!(
            conserve_volume_along(&m, &mut edit, DVec3::Z, 0.1, &mut buf),
            None
        );
        assert_eq!(edit.moves[0].end, start);
    }

    #[test]
    fn quadric_ranks_plane_ridge_corner() {
        let params = FeatureParams::default();
        let mut a = Matrix3::zeros();
        let z = nalgebra::Vector3::new(0.0, 0.0, 1.0);
        a += z * z.transpose();
        assert!(
            matches!(classify_by_quadric(a, &params), VertexKind::Smooth { normal } if normal.z.abs() > 0.999)
        );
        let x = nalgebra::Vector3::new(1.0, 0.0, 0.0);
        a += x * x.transpose();
        match classify_by_quadric(a, &params) {
            VertexKind::Ridge { direction } => assert!(direction.y.abs() > 0.999),
            k => panic!("expected ridge, got {k:?}"),
        }
        let y = nalgebra::Vector3::new(0.0, 1.0, 0.0);
        a += y * y.transpose();
        assert_eq!(classify_by_quadric(a, &params), VertexKind::Corner);
        // A 10° fold is below the threshold (tan²(5°) ≈ 0.0077 < 0.03).
        let t = 10f64.to_radians();
        let n = nalgebra::Vector3::new(t.sin(), 0.0, t.cos());
        let fold = z * z.transpose() + n * n.transpose();
        assert!(matches!(
            classify_by_quadric(fold, &params),
            VertexKind::Smooth { .. }
        ));
    }

    #[test]
    fn hint_certificate_agrees_with_the_eigen_decomposition() {
        let params = FeatureParams::default();
        let mut rng_state = 12345u64;
        let mut next = || {
            let x = crate::remesh::fixtures::lcg(&mut rng_state);
            ((x >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        };
        for spread in [0.05, 0.15, 0.3, 0.6] {
            for _ in 0..200 {
                let mut a = Matrix3::zeros();
                let mut sum = DVec3::ZERO;
                for _ in 0..6 {
                    let n = DVec3::new(spread * next(), spread * next(), 1.0).normalize()
                        * (1.0 + next().abs());
                    add_to_quadric(&mut a, n);
                    sum += n;
                }
                let slow = classify_by_quadric(a, &params);
                let fast = classify_with_hint(a, sum, &params);
                match (slow, fast) {
                    (VertexKind::Smooth { normal: n1 }, VertexKind::Smooth { normal: n2 }) => {
                        assert!(n1.dot(n2).abs() > 0.999, "{n1} vs {n2}")
                    }
                    (s, f) => assert_eq!(s, f),
                }
            }
        }
    }

    #[test]
    fn triple_edges_make_curve_corners_and_feature_edges() {
        let m = tetra_pair();
        let params = FeatureParams::default();
        // Every vertex of the shared face has two triple edges meeting at 90°–135°: kinks.
        for v in 0..3 {
            assert_eq!(
                classify_vertex(&m, VertexId::new(v), &params),
                VertexKind::CurveCorner
            );
        }
        assert!(is_feature_edge(&m, VertexId::new(0), VertexId::new(1)));
        assert!(!is_feature_edge(&m, VertexId::new(0), VertexId::new(3)));
        assert!(
            !is_feature_edge(&m, VertexId::new(3), VertexId::new(4)),
            "not an edge"
        );
        // The apices are corners of a manifold patch.
        assert_eq!(
            classify_vertex(&m, VertexId::new(3), &params),
            VertexKind::Corner
        );
        let mut edges = 0;
        for_each_edge_at(&m, VertexId::new(0), |_, _| edges += 1);
        assert_eq!(edges, 4, "vertex 0 has edges to 1, 2, 3, 4");
        assert!(!plain_fan(&m, VertexId::new(0)));
        assert!(plain_fan(&m, VertexId::new(3)), "the apex fan is plain");
    }

    #[test]
    fn plain_fan_agrees_with_edge_stars_on_a_sphere_and_a_bubble() {
        let sphere =
            crate::generators::icosphere(2, DVec3::ZERO, 1.0, [Label::new(0), Label::new(1)])
                .expect("sphere");
        let bubble = crate::generators::double_bubble(1.0, 12).expect("bubble");
        for m in [&sphere, &bubble] {
            for v in m.vertices() {
                let mut features = 0;
                for_each_edge_at(m, v, |_, star| features += usize::from(star.is_feature()));
                assert_eq!(plain_fan(m, v), features == 0, "vertex {v}");
            }
        }
    }

    #[test]
    fn projector_keeps_tangent_and_ridge_parts() {
        let d = DVec3::new(1.0, 2.0, 3.0);
        let s = VertexKind::Smooth { normal: DVec3::Z };
        assert_eq!(s.project(d), DVec3::new(1.0, 2.0, 0.0));
        let r = VertexKind::Ridge {
            direction: DVec3::Y,
        };
        assert_eq!(r.project(d), DVec3::new(0.0, 2.0, 0.0));
        assert_eq!(VertexKind::CurveCorner.project(d), DVec3::ZERO);
        assert_eq!(
            VertexKind::Curve { tangent: DVec3::X }.project(d),
            DVec3::ZERO
        );
    }

    #[test]
    fn normals_agree_is_certified() {
        let t = [DVec3::ZERO, DVec3::X, DVec3::Y];
        assert!(normals_agree(&t, &t));
        let flipped = [DVec3::ZERO, DVec3::Y, DVec3::X];
        assert!(!normals_agree(&t, &flipped));
        let flat = [DVec3::ZERO, DVec3::X, DVec3::X * 2.0];
        assert!(!normals_agree(&t, &flat), "degenerate counts as inverted");
        // Almost perpendicular but positive: accepted.
        let steep = [DVec3::ZERO, DVec3::X, DVec3::new(0.0, 1e-6, 1.0)];
        assert!(normals_agree(&t, &steep));
    }

    #[test]
    fn volume_change_of_a_move_matches_tetra_volume() {
        let m = tetra_pair();
        let mut edit = Edit::default();
        edit.moves.push(super::super::edit::VertexMove {
            vertex: VertexId::new(3),
            end: DVec3::new(0.2, 0.2, 2.0),
            blend: None,
        });
        let mut buf = Vec::new();
        let dv = max_label_volume_change(&m, &edit, &mut buf);
        // Region 1 is the tetra (0,0,0),(1,0,0),(0,1,0),apex: volume = h/6.
        assert!((dv - 1.0 / 6.0).abs() < 1e-12, "dv = {dv}");
        let l1 = buf.iter().find(|e| e.0 == Label::new(1)).map(|e| e.1);
        assert!(l1.is_some_and(|x| (x - 1.0 / 6.0).abs() < 1e-12));
    }
}
