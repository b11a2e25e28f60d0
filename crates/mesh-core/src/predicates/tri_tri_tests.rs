//! Tests of [`super`]: hand cases, and random small-integer configurations (so that
//! coplanar, touching and degenerate cases are frequent) against the exact
//! linear-programming reference of `exact_ref`.

use super::*;
use crate::predicates::exact_ref::{
    self, hull_intersection_vertices, hulls_intersect, on_segment, orient3d_ref, q3,
};
use proptest::prelude::*;

fn v(x: i32, y: i32, z: i32) -> DVec3 {
    DVec3::new(f64::from(x), f64::from(y), f64::from(z))
}

fn degenerate(t: &[DVec3; 3]) -> bool {
    projection_axis(t).is_none()
}

#[test]
fn hand_cases() {
    let t = [v(0, 0, 0), v(4, 0, 0), v(0, 4, 0)];
    // Piercing, disjoint above, touching at a vertex, along an edge, coplanar overlap,
    // coplanar touching, coplanar containment, coplanar disjoint.
    assert!(intersect_triangle_triangle(
        &t,
        &[v(1, 1, -1), v(1, 1, 1), v(2, 2, 1)]
    ));
    assert!(!intersect_triangle_triangle(
        &t,
        &[v(1, 1, 1), v(2, 1, 1), v(1, 2, 1)]
    ));
    assert!(intersect_triangle_triangle(
        &t,
        &[v(4, 0, 0), v(5, 0, 1), v(5, 1, 1)]
    ));
    assert!(intersect_triangle_triangle(
        &t,
        &[v(0, 0, 0), v(4, 0, 0), v(0, 0, 4)]
    ));
    assert!(intersect_triangle_triangle(
        &t,
        &[v(1, 1, 0), v(5, 1, 0), v(1, 5, 0)]
    ));
    assert!(intersect_triangle_triangle(
        &t,
        &[v(2, 2, 0), v(4, 4, 0), v(2, 4, 0)]
    ));
    assert!(intersect_triangle_triangle(
        &t,
        &[v(1, 1, 0), v(2, 1, 0), v(1, 2, 0)]
    ));
    assert!(!intersect_triangle_triangle(
        &t,
        &[v(3, 3, 0), v(4, 4, 0), v(3, 4, 0)]
    ));
    // Coplanar strict containment in a tilted plane, either way round, either orientation.
    let big = [v(0, 0, 0), v(6, 0, 6), v(0, 6, 6)];
    let small = [v(1, 1, 2), v(2, 1, 3), v(1, 2, 3)];
    for s in [small, [small[0], small[2], small[1]]] {
        assert!(intersect_triangle_triangle(&big, &s));
        assert!(intersect_triangle_triangle(&s, &big));
    }
    // Vertex of b touching the interior of a; an edge of b lying in a's plane.
    assert!(intersect_triangle_triangle(
        &t,
        &[v(1, 1, 0), v(1, 1, 2), v(2, 1, 2)]
    ));
    assert!(intersect_triangle_triangle(
        &t,
        &[v(-1, 1, 0), v(5, 1, 0), v(1, 1, 3)]
    ));
    assert!(!intersect_triangle_triangle(
        &t,
        &[v(3, 3, 0), v(5, 3, 0), v(3, 3, 3)]
    ));
    // Degenerate: a segment through the triangle, a point on it, a point off it.
    assert!(intersect_triangle_triangle(
        &t,
        &[v(1, 1, -1), v(1, 1, 1), v(1, 1, 3)]
    ));
    assert!(intersect_triangle_triangle(
        &t,
        &[v(2, 2, 0), v(2, 2, 0), v(2, 2, 0)]
    ));
    assert!(!intersect_triangle_triangle(
        &t,
        &[v(2, 2, 1), v(2, 2, 1), v(2, 2, 1)]
    ));
    assert!(intersect_segment_triangle(v(1, 1, 1), v(1, 1, -1), &t));
    assert!(intersect_segment_triangle(v(4, 0, 3), v(4, 0, 0), &t));
    assert!(!intersect_segment_triangle(v(3, 3, -1), v(3, 3, 1), &t));
}

#[test]
fn sphere_neighbours_do_not_intersect() {
    // Including coplanar neighbours: the base octahedron's faces are split in four.
    for m in [
        exact_ref::icosphere_like(),
        exact_ref::cube(),
        exact_ref::octahedron(3),
    ] {
        for (i, a) in m.tris.iter().enumerate() {
            for b in &m.tris[i + 1..] {
                let shared: Vec<usize> = a.iter().copied().filter(|x| b.contains(x)).collect();
                let (ta, tb) = (a.map(|k| m.verts[k]), b.map(|k| m.verts[k]));
                let got = match shared[..] {
                    [] => intersect_triangle_triangle(&ta, &tb),
                    [s] => intersect_sharing_vertex(m.verts[s], others(a, s, &m), others(b, s, &m)),
                    [s, t] => {
                        let apex = |x: &[usize; 3]| {
                            x.iter()
                                .find(|&&k| k != s && k != t)
                                .map_or(DVec3::NAN, |&k| m.verts[k])
                        };
                        intersect_sharing_edge(m.verts[s], m.verts[t], apex(a), apex(b))
                    }
                    _ => true,
                };
                assert!(!got, "{a:?} {b:?}");
            }
        }
    }
}

/// The two corners of `t` other than `s`, in the triangle's cyclic order after `s`.
fn others(t: &[usize; 3], s: usize, m: &exact_ref::Mesh) -> [DVec3; 2] {
    let k = t.iter().position(|&x| x == s).unwrap_or(0);
    [m.verts[t[(k + 1) % 3]], m.verts[t[(k + 2) % 3]]]
}

#[test]
fn folded_and_overlapping_neighbours_are_reported() {
    let (v0, w) = (v(0, 0, 0), v(4, 0, 0));
    // Folded flat onto each other across the shared edge, and coplanar opposite sides.
    assert!(intersect_sharing_edge(v0, w, v(1, 3, 0), v(3, 2, 0)));
    assert!(!intersect_sharing_edge(v0, w, v(1, 3, 0), v(3, -2, 0)));
    assert!(!intersect_sharing_edge(v0, w, v(1, 3, 0), v(3, 2, 1)));
    // Degenerate apex on the edge's line: only the shared edge is common, unless both
    // apexes stick out beyond the same end.
    assert!(!intersect_sharing_edge(v0, w, v(1, 3, 0), v(6, 0, 0)));
    assert!(!intersect_sharing_edge(v0, w, v(-1, 0, 0), v(6, 0, 0)));
    assert!(!intersect_sharing_edge(v0, w, v(2, 0, 0), v(6, 0, 0)));
    assert!(intersect_sharing_edge(v0, w, v(5, 0, 0), v(6, 0, 0)));
    assert!(intersect_sharing_edge(v0, w, v(-2, 0, 0), v(-1, 0, 0)));
    // Sharing a vertex: coplanar overlapping wedges, a fold piercing the other, a
    // coplanar wedge touching along a spoke, and disjoint ones.
    assert!(intersect_sharing_vertex(
        v0,
        [v(4, 0, 0), v(0, 4, 0)],
        [v(4, 1, 0), v(1, 4, 0)]
    ));
    assert!(intersect_sharing_vertex(
        v0,
        [v(4, 0, 0), v(0, 4, 0)],
        [v(2, 1, -1), v(1, 2, 1)]
    ));
    assert!(intersect_sharing_vertex(
        v0,
        [v(4, 0, 0), v(0, 4, 0)],
        [v(0, 2, 0), v(-3, 3, 0)]
    ));
    assert!(!intersect_sharing_vertex(
        v0,
        [v(4, 0, 0), v(0, 4, 0)],
        [v(-4, 0, 0), v(0, -4, 0)]
    ));
    assert!(!intersect_sharing_vertex(
        v0,
        [v(4, 0, 0), v(0, 4, 0)],
        [v(-4, 0, 1), v(0, -4, 1)]
    ));
    assert!(!intersect_sharing_vertex(
        v0,
        [v(4, 0, 0), v(0, 4, 0)],
        [v(1, 1, 1), v(1, 2, 2)]
    ));
}

fn small_tri(r: i32) -> impl Strategy<Value = [DVec3; 3]> {
    proptest::array::uniform3((-r..=r, -r..=r, -r..=r)).prop_map(|t| t.map(|(x, y, z)| v(x, y, z)))
}

/// A triangle in the plane z = 0, often the case that needs the 2-D path.
fn flat_tri() -> impl Strategy<Value = [DVec3; 3]> {
    proptest::array::uniform3((-2i32..=2, -2i32..=2)).prop_map(|t| t.map(|(x, y)| v(x, y, 0)))
}

fn any_tri() -> impl Strategy<Value = [DVec3; 3]> {
    prop_oneof![3 => small_tri(2), 1 => flat_tri(), 1 => small_tri(1)]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(600))]

    #[test]
    fn triangles_match_reference(a in any_tri(), b in any_tri()) {
        let expected = hulls_intersect(&a, &b);
        prop_assert_eq!(intersect_triangle_triangle(&a, &b), expected);
        prop_assert_eq!(intersect_triangle_triangle(&b, &a), expected);
        let (a2, b2) = ([a[1], a[2], a[0]], [b[0], b[2], b[1]]);
        prop_assert_eq!(intersect_triangle_triangle(&a2, &b2), expected);
    }

    /// The filtered plane sides are the exact ones, on points rounded onto (or within a
    /// few ulps of) the plane, where the filter must hand over to the exact predicate.
    #[test]
    fn filtered_sides_are_exact(
        t in proptest::array::uniform3((-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64)),
        st in proptest::array::uniform3((-2.0..2.0f64, -2.0..2.0f64, -1.0e-15..1.0e-15f64)),
    ) {
        let t = t.map(|(x, y, z)| DVec3::new(x, y, z));
        let n = (t[1] - t[0]).cross(t[2] - t[0]);
        let pts = st.map(|(s, u, h)| t[0] + s * (t[1] - t[0]) + u * (t[2] - t[0]) + h * n);
        prop_assert_eq!(plane_sides(&t, &pts), pts.map(|p| orient3d_ref(t[0], t[1], t[2], p)));
    }

    #[test]
    fn segments_match_reference(s in small_tri(2), t in any_tri()) {
        let (p, q) = (s[0], s[1]);
        prop_assert_eq!(intersect_segment_triangle(p, q, &t), hulls_intersect(&[p, q], &t));
    }

    #[test]
    fn sharing_vertex_matches_reference(v0 in small_tri(1), a in small_tri(2), b in small_tri(2)) {
        let s = v0[0];
        let (ta, tb) = ([s, a[0], a[1]], [s, b[0], b[1]]);
        // Meeting elsewhere than at s: some vertex of the intersection differs from s.
        let expected = hull_intersection_vertices(&ta, &tb).iter().any(|x| *x != q3(s));
        let got = intersect_sharing_vertex(s, [a[0], a[1]], [b[0], b[1]]);
        if degenerate(&ta) || degenerate(&tb) {
            prop_assert!(got || !expected, "conservative on degenerate input");
        } else {
            prop_assert_eq!(got, expected);
        }
    }

    /// The keyed test against the reference for every way two triangles of a mesh can
    /// share: nothing, a vertex or an edge, in any slots of either triangle, with the
    /// unshared corners anywhere (also on the shared ones: equal points under different
    /// keys are not shared, so they touch).
    #[test]
    fn keyed_matches_reference(
        a in small_tri(2),
        b in small_tri(2),
        shared in 0usize..=2,
        (ra, rb) in (0usize..3, 0usize..3),
    ) {
        prop_assume!(!degenerate(&a));
        let pb: [DVec3; 3] = std::array::from_fn(|k| if k < shared { a[k] } else { b[k] });
        prop_assume!(!degenerate(&pb));
        let kb: [u32; 3] = std::array::from_fn(|k| if k < shared { k as u32 } else { 10 + k as u32 });
        let rotate = |r: usize, x: [DVec3; 3]| std::array::from_fn(|k| x[(k + r) % 3]);
        let rotate_keys = |r: usize, x: [u32; 3]| std::array::from_fn(|k| x[(k + r) % 3]);
        let (pa, ka) = (rotate(ra, a), rotate_keys(ra, [0, 1, 2]));
        let (pb, kb) = (rotate(rb, pb), rotate_keys(rb, kb));
        let meets = hull_intersection_vertices(&pa, &pb);
        let expected = match shared {
            0 => !meets.is_empty(),
            1 => meets.iter().any(|x| *x != q3(a[0])),
            _ => meets.iter().any(|x| !on_segment(x, a[0], a[1])),
        };
        prop_assert_eq!(intersect_keyed_triangle_triangle((ka, &pa), (kb, &pb)), expected);
        prop_assert_eq!(intersect_keyed_triangle_triangle((kb, &pb), (ka, &pa)), expected);
    }

    #[test]
    fn sharing_edge_matches_reference(e in small_tri(2), b in (-2i32..=2, -2i32..=2, -2i32..=2)) {
        let (s, t, a, b) = (e[0], e[1], e[2], v(b.0, b.1, b.2));
        prop_assume!(s != t);
        let outside_st = |x: &_| !on_segment(x, s, t);
        let expected = hull_intersection_vertices(&[s, t, a], &[s, t, b]).iter().any(outside_st);
        prop_assert_eq!(intersect_sharing_edge(s, t, a, b), expected);
        // Coplanar cases, which are the interesting ones, by construction.
        let flat = DVec3::new(b.x, b.y, a.z);
        let (s, t) = (s.with_z(a.z), t.with_z(a.z));
        prop_assume!(s != t);
        let outside_st = |x: &_| !on_segment(x, s, t);
        let expected = hull_intersection_vertices(&[s, t, a], &[s, t, flat]).iter().any(outside_st);
        prop_assert_eq!(intersect_sharing_edge(s, t, a, flat), expected);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(100))]

    /// Translated copies with a non-representable-by-integers offset: the filter must
    /// stay conservative when coordinates carry rounding. (Few cases: the rationals get
    /// long.)
    #[test]
    fn translated_triangles_match_reference(a in any_tri(), b in any_tri(), s in 0.0..1.0f64) {
        let shift = DVec3::new(s, 0.3 * s, 1.0e-3);
        let (a, b) = (a.map(|p| p * 0.1 + shift), b.map(|p| p * 0.1 + shift));
        prop_assert_eq!(intersect_triangle_triangle(&a, &b), hulls_intersect(&a, &b));
    }
}
