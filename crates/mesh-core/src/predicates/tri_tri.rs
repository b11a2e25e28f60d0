//! Exact closed intersection tests between triangles and segments in 3-D, and the variants
//! used when validating a mesh, where neighbours touch along what they share.
//!
//! Every decision is an exact [`orient3d`] / [`orient2d`](super::orient2d) sign, so the
//! answers are exact for finite inputs whose products neither overflow nor underflow (the
//! assumption of Shewchuk's predicates). The typical far-apart or plane-separated pair
//! is rejected in well under 20 ns: a closed bounding-box test (plain comparisons), then
//! the sides of one triangle's vertices relative to the other's plane from one
//! floating-point normal with a forward error bound. Only points within that bound of the
//! plane pay for an exact [`orient3d`]; the edge-piercing tests of the exact path are
//! filtered the same way.
//!
//! Degenerate triangles (collinear or coincident vertices) are handled as the segment or
//! point they span, exactly.

use glam::DVec3;

use super::orient::{Axis, Sign, orient2d_axis, orient3d};
use super::planar;

/// Relative error bound of the filter's plane evaluation `n · (p − t0)` with
/// `n = (t1 − t0) × (t2 − t0)`: each monomial of the expanded determinant passes through
/// at most 8 roundings (3 differences, 2 products, the final product, 2 additions), so
/// the error is at most `γ8 · P ≈ 8.9e-16 · P`, `P` being the sum of the monomials'
/// magnitudes; evaluating `P` itself in floating point costs a few more ulps. `1e-15`
/// covers both with a margin.
const FILTER_EPS: f64 = 1.0e-15;

/// The three edges of a triangle as index pairs.
const EDGES: [(usize, usize); 3] = [(0, 1), (1, 2), (2, 0)];

#[inline]
fn bounds<const N: usize>(pts: &[DVec3; N]) -> (DVec3, DVec3) {
    pts.iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(*p), hi.max(*p))
        })
}

/// Closed boxes overlap (touching counts): plain comparisons, exact.
#[inline]
fn boxes_overlap((alo, ahi): (DVec3, DVec3), (blo, bhi): (DVec3, DVec3)) -> bool {
    alo.cmple(bhi).all() && blo.cmple(ahi).all()
}

/// Float cross product `u × w` and, per component, the magnitudes of its two monomials.
/// For differences `u`, `w`, `f` of input points, `f · (u × w)` is then within
/// `FILTER_EPS · (|f| · perm)` of the exact determinant: the filter's error bound.
#[inline]
fn cross_and_permanent(u: DVec3, w: DVec3) -> (DVec3, DVec3) {
    let perm = DVec3::new(
        (u.y * w.z).abs() + (u.z * w.y).abs(),
        (u.z * w.x).abs() + (u.x * w.z).abs(),
        (u.x * w.y).abs() + (u.y * w.x).abs(),
    );
    (u.cross(w), perm)
}

/// Float normal of `t` with its permanent (see [`cross_and_permanent`]).
#[inline]
fn normal_and_permanent(t: &[DVec3; 3]) -> (DVec3, DVec3) {
    cross_and_permanent(t[1] - t[0], t[2] - t[0])
}

/// The sign of `d` if the error bound certifies it, else `None`.
#[inline]
fn certified(d: f64, bound: f64) -> Option<Sign> {
    if d > bound {
        Some(Sign::Positive)
    } else if d < -bound {
        Some(Sign::Negative)
    } else {
        None
    }
}

/// True when every point of `pts` is *certainly* strictly on one side of the plane of
/// `t`: the branch-free early rejection. `false` proves nothing.
#[inline]
pub(crate) fn certainly_separated<const N: usize>(t: &[DVec3; 3], pts: &[DVec3; N]) -> bool {
    let (n, perm) = normal_and_permanent(t);
    let mut above = true;
    let mut below = true;
    for p in pts {
        let f = *p - t[0];
        let d = n.dot(f);
        let bound = FILTER_EPS * perm.dot(f.abs());
        above &= d > bound;
        below &= d < -bound;
    }
    above || below
}

/// The exact sides of `pts` relative to the plane of `t` ([`orient3d`] signs).
///
/// The plane is evaluated once in floating point (one normal for all points) with a
/// forward error bound; only a point within the bound of the plane pays for an exact
/// [`orient3d`]. Non-finite input fails the filter and reads as `Zero` from the exact
/// predicate.
#[inline]
fn plane_sides<const N: usize>(t: &[DVec3; 3], pts: &[DVec3; N]) -> [Sign; N] {
    let (n, perm) = normal_and_permanent(t);
    let mut sides = [Sign::Zero; N];
    let mut uncertain = false;
    for (side, p) in sides.iter_mut().zip(pts) {
        let f = *p - t[0];
        match certified(n.dot(f), FILTER_EPS * perm.dot(f.abs())) {
            Some(s) => *side = s,
            None => uncertain = true,
        }
    }
    if uncertain {
        exact_sides(t, pts, &mut sides);
    }
    sides
}

/// The filter's fallback, out of line so that the fast path stays small.
#[cold]
#[inline(never)]
fn exact_sides(t: &[DVec3; 3], pts: &[DVec3], sides: &mut [Sign]) {
    for (side, p) in sides.iter_mut().zip(pts) {
        *side = orient3d(t[0], t[1], t[2], *p);
    }
}

/// All signs equal and non-zero: everything strictly on one side.
#[inline]
fn strictly_one_side(s: &[Sign; 3]) -> bool {
    s[0] != Sign::Zero && s[1] == s[0] && s[2] == s[0]
}

/// An axis along which `t` projects to a triangle of non-zero area, with that projected
/// orientation, or `None` when `t` is degenerate (collinear vertices). The float normal's
/// dominant axis is tried first, for well-conditioned projections; the exact sign decides.
fn projection_axis(t: &[DVec3; 3]) -> Option<(Axis, Sign)> {
    let first = Axis::dominant((t[1] - t[0]).cross(t[2] - t[0])).index();
    (0..3).find_map(|k| {
        let axis = Axis::from_index(first + k);
        let s = orient2d_axis(axis, t[0], t[1], t[2]);
        (s != Sign::Zero).then_some((axis, s))
    })
}

/// Closed segments `pq` and `rs` in 3-D share a point. Coplanar closed convex sets are
/// disjoint iff they are disjoint in some axis projection (one projection is injective on
/// their common plane or line) and meet in every projection otherwise.
fn segments_intersect_3d(p: DVec3, q: DVec3, r: DVec3, s: DVec3) -> bool {
    orient3d(p, q, r, s) == Sign::Zero
        && Axis::ALL.iter().all(|&axis| {
            planar::segments_intersect(
                axis.project(p),
                axis.project(q),
                axis.project(r),
                axis.project(s),
            )
        })
}

/// The line through `p` and `q`, known to cross the plane of the non-degenerate `t` at a
/// single point `x`, does so inside the closed triangle. `orient3d(p, q, ti, tj)` is
/// `sign((q − p) · n) · sign(area(x, ti, tj))`, the same first factor for all three
/// edges, so `x` is inside iff the three signs are not mixed (they cannot all be zero
/// for a non-degenerate `t` and a line not in its plane).
#[inline]
fn line_pierces_triangle(p: DVec3, q: DVec3, t: &[DVec3; 3]) -> bool {
    // orient3d(p, q, ti, tj) = (q − p) · ((ti − p) × (tj − p)): filtered in floating
    // point first; these calls sit on a chain of dependent branches, where a batch of
    // branch-free float evaluations is several times faster than three exact calls.
    let e = q - p;
    let u = t.map(|v| v - p);
    let filtered = EDGES.map(|(i, j)| {
        let (n, perm) = cross_and_permanent(u[i], u[j]);
        certified(e.dot(n), FILTER_EPS * perm.dot(e.abs()))
    });
    let s = match filtered {
        [Some(a), Some(b), Some(c)] => [a, b, c],
        _ => exact_pierce_signs(p, q, t),
    };
    !(s.contains(&Sign::Positive) && s.contains(&Sign::Negative))
}

/// The filter's fallback for [`line_pierces_triangle`], out of line.
#[cold]
#[inline(never)]
fn exact_pierce_signs(p: DVec3, q: DVec3, t: &[DVec3; 3]) -> [Sign; 3] {
    EDGES.map(|(i, j)| orient3d(p, q, t[i], t[j]))
}

/// Exact closed segment–triangle test without the filter, for any degenerate input.
///
/// The degeneracy check is deferred to the one case that needs it: a degenerate `t` has
/// every point on its "plane", so it can only reach the `(Zero, Zero)` arm.
fn segment_triangle_exact(p: DVec3, q: DVec3, t: &[DVec3; 3]) -> bool {
    let [sp, sq] = plane_sides(t, &[p, q]);
    match (sp, sq) {
        (Sign::Zero, Sign::Zero) => match projection_axis(t) {
            Some(axis) => segment_in_plane_meets(p, q, t, axis),
            // A degenerate triangle is the union of its edges.
            None => EDGES
                .iter()
                .any(|&(i, j)| segments_intersect_3d(p, q, t[i], t[j])),
        },
        _ if sp == sq => false,
        _ => line_pierces_triangle(p, q, t),
    }
}

/// Closed segment `pq`, lying in the plane of the non-degenerate `t`, meets `t`: tested in
/// the projection along `axis`, injective on that plane, where `t` has orientation `o`.
fn segment_in_plane_meets(p: DVec3, q: DVec3, t: &[DVec3; 3], (axis, o): (Axis, Sign)) -> bool {
    let tp = t.map(|v| axis.project(v));
    planar::segment_triangle(axis.project(p), axis.project(q), &tp, o)
}

/// Edges of `a` (with exact sides `sa` relative to the plane of `b`, not all zero, so `b`
/// is non-degenerate) meet the closed `b`.
fn edges_meet_triangle(a: &[DVec3; 3], sa: &[Sign; 3], b: &[DVec3; 3]) -> bool {
    EDGES.iter().any(|&(i, j)| match (sa[i], sa[j]) {
        // An edge in b's plane: the projection axis is found only in this rare case.
        (Sign::Zero, Sign::Zero) => {
            projection_axis(b).is_some_and(|axis| segment_in_plane_meets(a[i], a[j], b, axis))
        }
        (si, sj) if si == sj => false,
        _ => line_pierces_triangle(a[i], a[j], b),
    })
}

/// The rare cases where one triangle lies in the other's plane: coplanar triangles, or a
/// degenerate one.
fn coplanar_or_degenerate(a: &[DVec3; 3], b: &[DVec3; 3]) -> bool {
    match (projection_axis(a), projection_axis(b)) {
        (Some((axis, oa)), Some(_)) => {
            // One lies in the other's plane and both span a plane: the same plane, which
            // projects injectively along `axis`, so b keeps a non-zero orientation.
            let ta = a.map(|v| axis.project(v));
            let tb = b.map(|v| axis.project(v));
            let ob = orient2d_axis(axis, b[0], b[1], b[2]);
            planar::triangles_intersect(&ta, oa, &tb, ob)
        }
        // A degenerate triangle is the union of its edges; not knowing which one is
        // degenerate, test both ways.
        _ => {
            EDGES
                .iter()
                .any(|&(i, j)| intersect_segment_triangle(a[i], a[j], b))
                || EDGES
                    .iter()
                    .any(|&(i, j)| intersect_segment_triangle(b[i], b[j], a))
        }
    }
}

/// The closed triangles `a` and `b` share at least one point (touching counts).
///
/// Coplanar triangles are tested exactly in an injective axis projection; degenerate
/// triangles count as the segment or point they span.
pub fn intersect_triangle_triangle(a: &[DVec3; 3], b: &[DVec3; 3]) -> bool {
    if !boxes_overlap(bounds(a), bounds(b))
        || certainly_separated(a, b)
        || certainly_separated(b, a)
    {
        return false;
    }
    let sb = plane_sides(a, b);
    if strictly_one_side(&sb) {
        return false;
    }
    let sa = plane_sides(b, a);
    if strictly_one_side(&sa) {
        return false;
    }
    if sb == [Sign::Zero; 3] || sa == [Sign::Zero; 3] {
        return coplanar_or_degenerate(a, b);
    }
    // Both triangles are non-degenerate (a degenerate one puts everything on its
    // "plane") and not coplanar: the intersection is a segment of the line where the
    // planes meet, and each end of it is where an edge of one meets the other triangle.
    edges_meet_triangle(a, &sa, b) || edges_meet_triangle(b, &sb, a)
}

/// The closed segment `pq` and the closed triangle `tri` share at least one point.
/// Degenerate inputs (a point segment, a collinear triangle) are handled exactly.
pub fn intersect_segment_triangle(p: DVec3, q: DVec3, tri: &[DVec3; 3]) -> bool {
    boxes_overlap(bounds(&[p, q]), bounds(tri))
        && !certainly_separated(tri, &[p, q])
        && segment_triangle_exact(p, q, tri)
}

/// Triangles `(v, a1, a2)` and `(v, b1, b2)`, which share the vertex `v`, meet somewhere
/// other than at `v`.
///
/// For non-degenerate triangles, coplanar ones included, this holds exactly when segment
/// `a1a2` meets triangle B or segment `b1b2` meets triangle A: the intersection is a
/// convex set with `v` as an extreme point, and any other extreme point of it lies on one
/// of those far edges (or is a far vertex inside the other triangle). For a degenerate
/// triangle (whose `v` may lie *inside* the segment it spans) the answer is conservative:
/// it may report `true` for triangles that meet only at `v`, never `false` wrongly.
pub fn intersect_sharing_vertex(v: DVec3, [a1, a2]: [DVec3; 2], [b1, b2]: [DVec3; 2]) -> bool {
    intersect_segment_triangle(a1, a2, &[v, b1, b2])
        || intersect_segment_triangle(b1, b2, &[v, a1, a2])
}

/// Triangles `(v, w, a)` and `(v, w, b)`, which share the edge `vw`, meet somewhere other
/// than along `vw`.
///
/// Non-coplanar triangles meet only on the line where their planes cross, which is the
/// line of `vw`, and each triangle meets that line in exactly `vw`. Coplanar ones overlap
/// iff `a` and `b` lie strictly on the same side of line `vw`. Degenerate triangles (apex
/// on line `vw`) are the segments they span, exactly as sets: one of them meets a
/// non-degenerate neighbour only along `vw`; two of them overlap beyond `vw` iff both
/// apexes lie beyond the same end of it. (Flagging zero-area triangles is a separate
/// check.) Requires `v ≠ w`; returns `false` otherwise.
pub fn intersect_sharing_edge(v: DVec3, w: DVec3, a: DVec3, b: DVec3) -> bool {
    if orient3d(v, w, a, b) != Sign::Zero {
        return false;
    }
    let Some((axis, sa)) = projection_axis(&[v, w, a]) else {
        return projection_axis(&[v, w, b]).is_none() && beyond_same_end(v, w, a, b);
    };
    orient2d_axis(axis, v, w, b) == sa
}

/// Triangles `a` and `b` of one mesh, their vertices named by `keys` (equal keys: the same
/// vertex), meet somewhere other than at what they share: anywhere for no shared vertex
/// ([`intersect_triangle_triangle`]), away from `v` for one shared vertex `v`
/// ([`intersect_sharing_vertex`]), beyond the edge for a shared edge
/// ([`intersect_sharing_edge`]); two triangles on the same three vertices are a duplicate,
/// which validation reports on its own, and give `false`.
///
/// The one narrow phase of validation, the edit guards and the grid's safety net. Why it
/// filters before the shared-vertex test: on a surface, most pairs that share a vertex
/// are neighbours around it whose far edge lies certainly and strictly on one side of the
/// other's plane, which proves they meet only at `v` for the price of one float normal.
/// A triangle with a repeated key whose sharing cannot be told apart (two of its slots
/// matching one slot of the other) is reported as meeting: the conservative answer for a
/// shape no test here is defined on.
pub fn intersect_keyed_triangle_triangle(
    (ka, pa): ([u32; 3], &[DVec3; 3]),
    (kb, pb): ([u32; 3], &[DVec3; 3]),
) -> bool {
    // The pairs of slots with equal keys, by plain comparisons: this runs for millions of
    // pairs, most of them neighbours.
    let mut shared = [(0usize, 0usize); 2];
    let mut n = 0;
    for (i, x) in ka.iter().enumerate() {
        for (j, y) in kb.iter().enumerate() {
            if x == y {
                if n < 2 {
                    shared[n] = (i, j);
                }
                n += 1;
            }
        }
    }
    match n {
        0 => intersect_triangle_triangle(pa, pb),
        1 => {
            let (i, j) = shared[0];
            let (v, a) = (pa[i], [pa[(i + 1) % 3], pa[(i + 2) % 3]]);
            let b = [pb[(j + 1) % 3], pb[(j + 2) % 3]];
            !certainly_separated(&[v, a[0], a[1]], &b) && intersect_sharing_vertex(v, a, b)
        }
        2 => {
            let ((i0, j0), (i1, j1)) = (shared[0], shared[1]);
            if i0 == i1 || j0 == j1 {
                return true;
            }
            intersect_sharing_edge(pa[i0], pa[i1], pa[3 - i0 - i1], pb[3 - j0 - j1])
        }
        _ => false,
    }
}

/// For `a` and `b` on the line of `vw`: both lie strictly beyond `w`, or both strictly
/// beyond `v`. Compared along a coordinate that varies on the line: plain comparisons.
fn beyond_same_end(v: DVec3, w: DVec3, a: DVec3, b: DVec3) -> bool {
    let Some(k) = (0..3).find(|&k| v[k] != w[k]) else {
        return false;
    };
    let dir = Sign::of_difference(w[k], v[k]);
    let beyond_w = |x: DVec3| Sign::of_difference(x[k], w[k]) == dir;
    let beyond_v = |x: DVec3| Sign::of_difference(x[k], v[k]) == -dir;
    (beyond_w(a) && beyond_w(b)) || (beyond_v(a) && beyond_v(b))
}

#[cfg(test)]
#[path = "tri_tri_tests.rs"]
mod tests;
