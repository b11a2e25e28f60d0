//! Closed intersection tests between points, segments and triangles in the plane, built on
//! the exact [`orient2d`]. The 3-D tests use them for coplanar configurations, after
//! projecting along an axis the common plane projects onto injectively.
//!
//! "Closed" everywhere: touching at a point counts as intersecting.

use glam::DVec2;

use super::orient::{Sign, orient2d};

/// Closed segments `pq` and `rs` share a point. Correct for every degenerate input:
/// collinear overlapping segments, and segments that are single points.
pub(crate) fn segments_intersect(p: DVec2, q: DVec2, r: DVec2, s: DVec2) -> bool {
    let o1 = orient2d(p, q, r);
    let o2 = orient2d(p, q, s);
    if o1 == o2 && o1 != Sign::Zero {
        return false; // r and s strictly on one side of line pq
    }
    let o3 = orient2d(r, s, p);
    let o4 = orient2d(r, s, q);
    if o3 == o4 && o3 != Sign::Zero {
        return false;
    }
    if o1 == Sign::Zero && o2 == Sign::Zero && o3 == Sign::Zero && o4 == Sign::Zero {
        // All four points on one line (or a segment is a point on the other's line). A
        // line that is not a single point is monotone in x or in y, and constant in
        // the other, so overlap of the two bounding boxes is overlap on the line.
        return boxes_overlap(p, q, r, s);
    }
    // Each segment meets the other's line, and not everything is collinear: the two
    // supporting lines are distinct and cross at a point both segments contain.
    true
}

#[inline]
fn boxes_overlap(p: DVec2, q: DVec2, r: DVec2, s: DVec2) -> bool {
    let (lo1, hi1) = (p.min(q), p.max(q));
    let (lo2, hi2) = (r.min(s), r.max(s));
    lo1.cmple(hi2).all() && lo2.cmple(hi1).all()
}

/// `p` lies in the closed triangle `t`, whose exact orientation (`Positive` or
/// `Negative`, never `Zero`) is `orientation`.
#[inline]
pub(crate) fn point_in_triangle(p: DVec2, t: &[DVec2; 3], orientation: Sign) -> bool {
    let outside = orientation.flip();
    orient2d(t[0], t[1], p) != outside
        && orient2d(t[1], t[2], p) != outside
        && orient2d(t[2], t[0], p) != outside
}

/// Closed segment `pq` meets the closed non-degenerate triangle `t` of orientation
/// `orientation`: an endpoint inside, or the segment crossing the boundary.
pub(crate) fn segment_triangle(p: DVec2, q: DVec2, t: &[DVec2; 3], orientation: Sign) -> bool {
    point_in_triangle(p, t, orientation)
        || point_in_triangle(q, t, orientation)
        || (0..3).any(|i| segments_intersect(p, q, t[i], t[(i + 1) % 3]))
}

/// Closed non-degenerate triangles `a` and `b` (orientations `oa`, `ob`) intersect: a
/// vertex of one lies in the other, or two edges cross. If neither holds, the boundaries
/// are disjoint and neither triangle contains the other, so the triangles are disjoint.
pub(crate) fn triangles_intersect(a: &[DVec2; 3], oa: Sign, b: &[DVec2; 3], ob: Sign) -> bool {
    a.iter().any(|&p| point_in_triangle(p, b, ob))
        || b.iter().any(|&p| point_in_triangle(p, a, oa))
        || (0..3)
            .any(|i| (0..3).any(|j| segments_intersect(a[i], a[(i + 1) % 3], b[j], b[(j + 1) % 3])))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    #[test]
    fn segment_cases() {
        let (o, x2) = (v(0.0, 0.0), v(2.0, 0.0));
        // Crossing, touching at an endpoint, T-junction, parallel, disjoint collinear,
        // overlapping collinear, point on segment, point off segment, coincident points.
        assert!(segments_intersect(o, x2, v(1.0, -1.0), v(1.0, 1.0)));
        assert!(segments_intersect(o, x2, x2, v(3.0, 1.0)));
        assert!(segments_intersect(o, x2, v(1.0, 0.0), v(1.0, 1.0)));
        assert!(!segments_intersect(o, x2, v(0.0, 1.0), v(2.0, 1.0)));
        assert!(!segments_intersect(o, x2, v(3.0, 0.0), v(4.0, 0.0)));
        assert!(segments_intersect(o, x2, v(1.0, 0.0), v(4.0, 0.0)));
        assert!(segments_intersect(o, x2, v(1.5, 0.0), v(1.5, 0.0)));
        assert!(!segments_intersect(o, x2, v(2.5, 0.0), v(2.5, 0.0)));
        assert!(!segments_intersect(o, x2, v(1.0, 0.5), v(1.0, 0.5)));
        assert!(segments_intersect(o, o, o, o));
        assert!(!segments_intersect(o, o, x2, x2));
        // Vertical collinear overlap and gap.
        assert!(segments_intersect(o, v(0.0, 2.0), v(0.0, 2.0), v(0.0, 3.0)));
        assert!(!segments_intersect(
            o,
            v(0.0, 2.0),
            v(0.0, 2.5),
            v(0.0, 3.0)
        ));
        // A segment that misses, although r lies on the line of pq beyond q.
        assert!(!segments_intersect(o, x2, v(3.0, 0.0), v(4.0, 1.0)));
    }

    #[test]
    fn triangle_cases() {
        let t = [v(0.0, 0.0), v(4.0, 0.0), v(0.0, 4.0)];
        let o = Sign::Positive;
        assert!(point_in_triangle(v(1.0, 1.0), &t, o));
        assert!(point_in_triangle(v(2.0, 2.0), &t, o)); // on the hypotenuse
        assert!(!point_in_triangle(v(2.5, 2.0), &t, o));
        // Contained triangle: no edge crossing, a vertex inside.
        let inner = [v(1.0, 1.0), v(1.5, 1.0), v(1.0, 1.5)];
        assert!(triangles_intersect(&t, o, &inner, o));
        assert!(triangles_intersect(&inner, o, &t, o));
        // Star of David: edges cross, no vertex inside the other.
        let up = [v(0.0, 0.0), v(6.0, 0.0), v(3.0, 5.0)];
        let down = [v(0.0, 3.0), v(3.0, -2.0), v(6.0, 3.0)];
        assert!(triangles_intersect(&up, o, &down, Sign::Negative));
        // Disjoint, and touching at one vertex.
        let far = [v(5.0, 5.0), v(6.0, 5.0), v(5.0, 6.0)];
        assert!(!triangles_intersect(&t, o, &far, o));
        let touching = [v(4.0, 0.0), v(5.0, 0.0), v(5.0, 1.0)];
        assert!(triangles_intersect(&t, o, &touching, o));
        assert!(segment_triangle(v(-1.0, 1.0), v(5.0, 1.0), &t, o));
        assert!(!segment_triangle(v(-1.0, 5.0), v(5.0, 5.0), &t, o));
    }
}
