//! Test-only exact CCD reference: the contact times of a vertex–triangle or edge–edge
//! pair on linear trajectories, decided in rational arithmetic.
//!
//! # The case analysis (why it is complete)
//!
//! Positions are linear polynomials in `t`. A contact needs the four points coplanar, i.e.
//! a root of the cubic `f = det[e₁, e₂, r]`.
//!
//! - `f ≢ 0`: contacts happen only at its finitely many roots in `[0, 1]`; at each root the
//!   points are coplanar and an exact static test decides (signs of polynomials at the
//!   root; degenerate elements fall back to point-in-segment tests).
//! - `f ≡ 0` (always coplanar): the contact times form a closed set. If `t* > 0` is the
//!   first, then just before `t*` there is no contact, so at `t*` the contact is not
//!   stable under perturbation: a vertex strictly inside a non-degenerate triangle, or two
//!   non-parallel segments crossing at interior points, keep touching nearby (their
//!   barycentric / segment parameters are continuous while coplanar). Hence at `t*` a
//!   vertex lies on an edge: the first contact is at 0 or is a vertex–edge contact.
//! - vertex–edge: collinearity needs the three components of `(b − a) × (p − a)` to vanish
//!   together: the roots of their gcd, tested for `p` between `a` and `b`. When they
//!   vanish identically (always collinear), the same argument as above reduces the first
//!   contact to `t = 0` or a vertex–vertex contact, a linear system.
//!
//! Each function returns contact times that include the first one (possibly more), so a
//! kernel time `t` is conservative iff `t ≤` every listed time.

use glam::DVec3;

use super::{Poly, Pt, Root, Z, roots_in_unit, sign_at_root};

/// A trajectory or a polynomial vector (one polynomial per axis).
type PV = [Poly; 3];

/// Trajectories of the eight input points, all coordinates multiplied by one power of two
/// that makes them integers. Every sign in the analysis is invariant under a positive
/// uniform scale (each polynomial is homogeneous in the coordinates) and the times are
/// unchanged, while integer coefficients keep the rational arithmetic fast.
fn trajectories(x0: [DVec3; 4], x1: [DVec3; 4]) -> [PV; 4] {
    // x = mantissa · 2^exponent with an integer mantissa (zero: no constraint).
    let split = |x: f64| -> (i64, i32) {
        let b = x.abs().to_bits();
        let e = ((b >> 52) & 0x7ff) as i32;
        let m = (b & ((1u64 << 52) - 1)) as i64;
        let (m, e) = if e == 0 {
            (m, -1074)
        } else {
            (m | (1i64 << 52), e - 1075)
        };
        (if x < 0.0 { -m } else { m }, e)
    };
    let low = x0
        .iter()
        .chain(&x1)
        .flat_map(|v| v.to_array())
        .filter(|&x| x != 0.0)
        .map(|x| split(x).1)
        .min()
        .unwrap_or(0);
    let int = |x: f64| -> Z {
        let (m, e) = split(x);
        Z::from(m) << (e - low) as usize
    };
    let lin = |a: f64, b: f64| Poly::linear(int(a), int(b) - int(a));
    std::array::from_fn(|i| {
        [
            lin(x0[i].x, x1[i].x),
            lin(x0[i].y, x1[i].y),
            lin(x0[i].z, x1[i].z),
        ]
    })
}

fn sub(a: &PV, b: &PV) -> PV {
    [a[0].sub(&b[0]), a[1].sub(&b[1]), a[2].sub(&b[2])]
}

fn dot(a: &PV, b: &PV) -> Poly {
    a[0].mul(&b[0]).add(&a[1].mul(&b[1])).add(&a[2].mul(&b[2]))
}

fn cross(a: &PV, b: &PV) -> PV {
    [
        a[1].mul(&b[2]).sub(&a[2].mul(&b[1])),
        a[2].mul(&b[0]).sub(&a[0].mul(&b[2])),
        a[0].mul(&b[1]).sub(&a[1].mul(&b[0])),
    ]
}

fn is_zero(v: &PV) -> bool {
    v.iter().all(Poly::is_zero)
}

fn vanishes_at(v: &PV, r: &Root) -> bool {
    v.iter().all(|c| sign_at_root(c, r) == 0)
}

fn at_zero() -> Root {
    Root::Exact(Pt::int(0))
}

/// Is `p` on the closed segment `[a, b]` at time `r`?
fn point_in_segment_at(r: &Root, p: &PV, a: &PV, b: &PV) -> bool {
    let e = sub(b, a);
    let w = sub(p, a);
    if !vanishes_at(&cross(&e, &w), r) {
        return false;
    }
    let ee = dot(&e, &e);
    if sign_at_root(&ee, r) == 0 {
        // Zero-length segment: p must coincide with a.
        return sign_at_root(&dot(&w, &w), r) == 0;
    }
    let k = dot(&w, &e);
    sign_at_root(&k, r) >= 0 && sign_at_root(&ee.sub(&k), r) >= 0
}

/// Times in `[0, 1]` when `p(t) = a(t)` (at most one unless always equal: then `[0]`).
fn vv_times(p: &PV, a: &PV) -> Vec<Root> {
    let d = sub(p, a);
    if is_zero(&d) {
        return vec![at_zero()];
    }
    let mut t: Option<Pt> = None;
    for c in &d {
        if c.is_zero() {
            continue;
        }
        if c.degree() == 0 {
            return Vec::new(); // a non-zero constant component never vanishes
        }
        // c0 + c1 t = 0
        let root = Pt::new(-c.coeff(0), c.coeff(1));
        match &t {
            Some(s) if *s != root => return Vec::new(),
            _ => t = Some(root),
        }
    }
    match t {
        Some(s) if s >= Pt::int(0) && s <= Pt::int(1) => vec![Root::Exact(s)],
        _ => Vec::new(),
    }
}

/// Contact times of the point `p` with the segment `[a, b]`.
fn ve_times(p: &PV, a: &PV, b: &PV) -> Vec<Root> {
    let c = cross(&sub(b, a), &sub(p, a));
    if is_zero(&c) {
        if point_in_segment_at(&at_zero(), p, a, b) {
            return vec![at_zero()];
        }
        let mut out = vv_times(p, a);
        out.extend(vv_times(p, b));
        return out;
    }
    let g = c.iter().fold(Poly::zero(), |g, ci| Poly::gcd(&g, ci));
    roots_in_unit(&g)
        .into_iter()
        .filter(|r| point_in_segment_at(r, p, a, b))
        .collect()
}

/// Is the coplanar point `p` in the closed triangle `abc` at time `r`?
fn in_triangle_at(r: &Root, p: &PV, a: &PV, b: &PV, c: &PV) -> bool {
    let n = cross(&sub(b, a), &sub(c, a));
    if vanishes_at(&n, r) {
        return point_in_segment_at(r, p, a, b)
            || point_in_segment_at(r, p, b, c)
            || point_in_segment_at(r, p, c, a);
    }
    [(a, b), (b, c), (c, a)]
        .iter()
        .all(|(x, y)| sign_at_root(&dot(&n, &cross(&sub(y, x), &sub(p, x))), r) >= 0)
}

/// Do the coplanar closed segments `[p0, p1]` and `[q0, q1]` meet at time `r`?
fn segments_meet_at(r: &Root, p0: &PV, p1: &PV, q0: &PV, q1: &PV) -> bool {
    let ep = sub(p1, p0);
    let eq = sub(q1, q0);
    let n = cross(&ep, &eq);
    if vanishes_at(&n, r) {
        return point_in_segment_at(r, p0, q0, q1)
            || point_in_segment_at(r, p1, q0, q1)
            || point_in_segment_at(r, q0, p0, p1)
            || point_in_segment_at(r, q1, p0, p1);
    }
    // p0 + s ep = q0 + u eq with w = q0 − p0: s |n|² = (w × eq)·n, u |n|² = (w × ep)·n.
    let w = sub(q0, p0);
    let nn = dot(&n, &n);
    let s = dot(&cross(&w, &eq), &n);
    let u = dot(&cross(&w, &ep), &n);
    [s.clone(), nn.sub(&s), u.clone(), nn.sub(&u)]
        .iter()
        .all(|g| sign_at_root(g, r) >= 0)
}

/// Contact times (including the first) of vertex `x[0]` and triangle `x[1..4]`.
pub(crate) fn vertex_triangle_contacts(x0: [DVec3; 4], x1: [DVec3; 4]) -> Vec<Root> {
    let [p, a, b, c] = trajectories(x0, x1);
    let f = dot(&cross(&sub(&b, &a), &sub(&c, &a)), &sub(&p, &a));
    if !f.is_zero() {
        return roots_in_unit(&f)
            .into_iter()
            .filter(|r| in_triangle_at(r, &p, &a, &b, &c))
            .collect();
    }
    if in_triangle_at(&at_zero(), &p, &a, &b, &c) {
        return vec![at_zero()];
    }
    let mut out = ve_times(&p, &a, &b);
    out.extend(ve_times(&p, &b, &c));
    out.extend(ve_times(&p, &c, &a));
    out
}

/// Contact times (including the first) of edges `x[0] x[1]` and `x[2] x[3]`.
pub(crate) fn edge_edge_contacts(x0: [DVec3; 4], x1: [DVec3; 4]) -> Vec<Root> {
    let [p0, p1, q0, q1] = trajectories(x0, x1);
    let f = dot(&cross(&sub(&p1, &p0), &sub(&q1, &q0)), &sub(&q0, &p0));
    if !f.is_zero() {
        return roots_in_unit(&f)
            .into_iter()
            .filter(|r| segments_meet_at(r, &p0, &p1, &q0, &q1))
            .collect();
    }
    if segments_meet_at(&at_zero(), &p0, &p1, &q0, &q1) {
        return vec![at_zero()];
    }
    let mut out = ve_times(&p0, &q0, &q1);
    out.extend(ve_times(&p1, &q0, &q1));
    out.extend(ve_times(&q0, &p0, &p1));
    out.extend(ve_times(&q1, &p0, &p1));
    out
}

#[cfg(test)]
mod tests {
    use super::super::approx;
    use super::*;

    fn v(x: f64, y: f64, z: f64) -> DVec3 {
        DVec3::new(x, y, z)
    }

    fn first(times: &[Root]) -> Option<f64> {
        times.iter().map(approx).min_by(f64::total_cmp)
    }

    /// The first contact time is `expect` (within 1e-15), or there is none.
    #[track_caller]
    fn assert_first(times: &[Root], expect: Option<f64>) {
        match (first(times), expect) {
            (None, None) => {}
            (Some(t), Some(e)) => assert!((t - e).abs() < 1e-15, "first contact {t}, expected {e}"),
            (got, _) => panic!("first contact {got:?}, expected {expect:?}"),
        }
    }

    const TRI: [DVec3; 3] = [
        DVec3::new(0.0, 0.0, 0.0),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(0.0, 1.0, 0.0),
    ];

    #[track_caller]
    fn vt(p0: DVec3, p1: DVec3, expect: Option<f64>) {
        assert_first(
            &vertex_triangle_contacts([p0, TRI[0], TRI[1], TRI[2]], [p1, TRI[0], TRI[1], TRI[2]]),
            expect,
        );
    }

    #[test]
    fn vertex_triangle_hand_cases() {
        vt(v(0.25, 0.25, 1.0), v(0.25, 0.25, -3.0), Some(0.25));
        vt(v(0.75, 0.75, 1.0), v(0.75, 0.75, -1.0), None);
        // Grazing the hypotenuse, touching at t = 0 and t = 1.
        vt(v(0.5, 0.5, 1.0), v(0.5, 0.5, -1.0), Some(0.5));
        vt(v(0.2, 0.2, 0.0), v(0.2, 0.2, 1.0), Some(0.0));
        vt(v(0.2, 0.2, 1.0), v(0.2, 0.2, 0.0), Some(1.0));
        // Coplanar motion: entering across the hypotenuse; passing beside it; along an edge.
        vt(v(2.0, 2.0, 0.0), v(0.0, 0.0, 0.0), Some(0.75));
        vt(v(2.0, -0.5, 0.0), v(-0.5, 2.0, 0.0), None);
        vt(v(2.0, -1.0, 0.0), v(-1.0, 2.0, 0.0), Some(1.0 / 3.0)); // along the hypotenuse's line
        vt(v(2.0, 0.0, 0.0), v(-3.0, 0.0, 0.0), Some(0.2));
        // A tilting triangle meets a resting vertex: plane height under p is 1.6 t.
        let x0 = [
            v(0.2, 0.2, 1.0),
            v(0.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(0.0, 1.0, 0.0),
        ];
        let x1 = [
            v(0.2, 0.2, 1.0),
            v(0.0, 0.0, 2.0),
            v(1.0, 0.0, 2.0),
            v(0.0, 1.0, 0.0),
        ];
        assert_first(&vertex_triangle_contacts(x0, x1), Some(0.625));
        // Degenerate triangle (a segment) swept through a vertex, and a point triangle.
        let seg = [v(-1.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.5, 0.0, 0.0)];
        let x0 = [v(0.0, 0.0, 1.0), seg[0], seg[1], seg[2]];
        let x1 = [v(0.0, 0.0, -1.0), seg[0], seg[1], seg[2]];
        assert_first(&vertex_triangle_contacts(x0, x1), Some(0.5));
        let x0 = [v(0.0, 1.0, 1.0), DVec3::ZERO, DVec3::ZERO, DVec3::ZERO];
        let x1 = [v(0.0, 1.0, -1.0), DVec3::ZERO, DVec3::ZERO, DVec3::ZERO];
        assert_first(&vertex_triangle_contacts(x0, x1), None);
    }

    #[test]
    fn irrational_contact_time() {
        // c(t) = (0, 1 − t, t) turns the triangle about the x axis while p rises:
        // coplanar when 5t² − t − 1 = 0, t = (1 + √21)/10, and p is inside then.
        let x0 = [
            v(0.2, 0.3, 0.1),
            v(0.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(0.0, 1.0, 0.0),
        ];
        let x1 = [
            v(0.2, 0.3, 0.6),
            v(0.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(0.0, 0.0, 1.0),
        ];
        let times = vertex_triangle_contacts(x0, x1);
        assert!(matches!(times[..], [Root::Isolated { .. }]), "{times:?}");
        assert_first(&times, Some((1.0 + 21f64.sqrt()) / 10.0));
        // Move p sideways out of the triangle: same coplanarity time, no contact.
        let x0 = [v(0.9, 0.3, 0.1), x0[1], x0[2], x0[3]];
        let x1 = [v(0.9, 0.3, 0.6), x1[1], x1[2], x1[3]];
        assert_first(&vertex_triangle_contacts(x0, x1), None);
    }

    #[test]
    fn edge_edge_hand_cases() {
        let x0 = [
            v(-1.0, 0.0, 1.0),
            v(1.0, 0.0, 1.0),
            v(0.5, -1.0, 0.0),
            v(0.5, 1.0, 0.0),
        ];
        let x1 = [
            v(-1.0, 0.0, -1.0),
            v(1.0, 0.0, -1.0),
            v(0.5, -1.0, 0.0),
            v(0.5, 1.0, 0.0),
        ];
        assert_first(&edge_edge_contacts(x0, x1), Some(0.5));
        let sh = |x: [DVec3; 4]| [x[0], x[1], x[2] + DVec3::X * 0.6, x[3] + DVec3::X * 0.6];
        assert_first(&edge_edge_contacts(sh(x0), sh(x1)), None);
        // Collinear sliding: q1 reaches p0 at t = 1/3.
        let x0 = [
            v(0.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(-3.0, 0.0, 0.0),
            v(-2.0, 0.0, 0.0),
        ];
        let x1 = [
            v(0.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(3.0, 0.0, 0.0),
            v(4.0, 0.0, 0.0),
        ];
        assert_first(&edge_edge_contacts(x0, x1), Some(1.0 / 3.0));
        // The same, parallel at a distance: no contact.
        let g = v(0.0, 1e-6, 0.0);
        let lift = |x: [DVec3; 4]| [x[0], x[1], x[2] + g, x[3] + g];
        assert_first(&edge_edge_contacts(lift(x0), lift(x1)), None);
        // Parallel, always coplanar, one sweeping sideways across the other.
        let x0 = [
            v(0.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(0.5, 1.0, 0.0),
            v(1.5, 1.0, 0.0),
        ];
        let x1 = [
            v(0.0, 0.0, 0.0),
            v(1.0, 0.0, 0.0),
            v(0.5, -1.0, 0.0),
            v(1.5, -1.0, 0.0),
        ];
        assert_first(&edge_edge_contacts(x0, x1), Some(0.5));
        // Both zero-length, meeting at t = 1/2.
        let x0 = [
            v(0.0, 0.0, 1.0),
            v(0.0, 0.0, 1.0),
            v(0.0, 0.0, 0.0),
            v(0.0, 0.0, 0.0),
        ];
        let x1 = [
            v(0.0, 0.0, -1.0),
            v(0.0, 0.0, -1.0),
            v(0.0, 0.0, 0.0),
            v(0.0, 0.0, 0.0),
        ];
        assert_first(&edge_edge_contacts(x0, x1), Some(0.5));
    }
}
