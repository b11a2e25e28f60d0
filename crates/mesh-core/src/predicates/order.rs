//! Exact order of two crossings along one axis-aligned grid line, under the same
//! Simulation of Simplicity as [`super::crossing`].
//!
//! The line along axis `a` through `p* = p + (ε, ε², ε³)` meets the plane of triangle
//! `i` (normal `n_i`, vertex `a_i`) at `t_i = −N_i / n_ia`, with
//! `N_i = n_i · (p* − a_i)`. Hence
//!
//! ```text
//! sign(t_1 − t_2) = sign(D) · sign(n_1a) · sign(n_2a),   D = N_2·n_1a − N_1·n_2a
//! D = D_0 + Σ_{k ≠ a} (n_2k·n_1a − n_1k·n_2a) ε^(k+1)        (the ε^(a+1) terms cancel)
//! ```
//!
//! `D_0` (degree 5 in the coordinates) decides; on an exact tie the ε-coefficients do,
//! lowest power first; if all vanish the two planes cross the line at the same point for
//! every perturbation (coplanar triangles) and the order is left `Equal`.
//!
//! Evaluation: interval arithmetic with outward rounding settles almost every case; the
//! rest (true ties, e.g. a line tangent to a surface at a mesh vertex lying on a grid
//! node) is evaluated exactly in big integers — every `f64` is an integer times a power of
//! two, and the polynomials are homogeneous, so scaling all inputs by one power of two
//! keeps the signs.

use std::cmp::Ordering;
use std::ops::{Add, Mul, Sub};

use glam::DVec3;
use num_bigint::BigInt;

use super::Axis;

/// The order along +`axis` of the crossings of triangles `t1` and `t2` with the grid
/// line through `p` (its `axis` coordinate is irrelevant). Both triangles must cross the
/// line (non-zero projected area). `Equal` only for coplanar triangles.
pub fn compare_crossings(axis: Axis, p: DVec3, t1: [DVec3; 3], t2: [DVec3; 3]) -> Ordering {
    let iv = |v: DVec3| v.to_array().map(Iv::point);
    let terms = Terms::of(axis, iv(p), t1.map(iv), t2.map(iv));
    if let Some(o) = terms.decide(Iv::sign) {
        return o;
    }
    let exact = Exact::new(p, t1, t2);
    let terms = Terms::of(axis, exact.p.clone(), exact.t1.clone(), exact.t2.clone());
    terms
        .decide(|x: &BigInt| Some(sign_of(x)))
        .unwrap_or(Ordering::Equal)
}

/// The polynomials of the module documentation, over any ring.
struct Terms<R> {
    d0: R,
    ties: [R; 2],
    n1a: R,
    n2a: R,
}

impl<R> Terms<R>
where
    R: Clone,
    for<'x> &'x R: Add<&'x R, Output = R> + Sub<&'x R, Output = R> + Mul<&'x R, Output = R>,
{
    fn of(axis: Axis, p: [R; 3], t1: [[R; 3]; 3], t2: [[R; 3]; 3]) -> Self {
        let a = axis.index();
        let (b, c) = axis.others();
        let (lo, hi) = (b.min(c), b.max(c));
        let (n1, v1) = normal_and_volume(&t1, &p);
        let (n2, v2) = normal_and_volume(&t2, &p);
        let cross = |k: usize| &(&n2[k] * &n1[a]) - &(&n1[k] * &n2[a]);
        Terms {
            d0: &(&v2 * &n1[a]) - &(&v1 * &n2[a]),
            ties: [cross(lo), cross(hi)],
            n1a: n1[a].clone(),
            n2a: n2[a].clone(),
        }
    }

    /// `sign(t1 − t2)` as an ordering, if every sign needed is known.
    fn decide(&self, sign: impl Fn(&R) -> Option<Ordering>) -> Option<Ordering> {
        let mut d = sign(&self.d0)?;
        for t in &self.ties {
            if d != Ordering::Equal {
                break;
            }
            d = sign(t)?;
        }
        let s = mul(mul(d, sign(&self.n1a)?), sign(&self.n2a)?);
        Some(s)
    }
}

fn mul(a: Ordering, b: Ordering) -> Ordering {
    match (a, b) {
        (Ordering::Equal, _) | (_, Ordering::Equal) => Ordering::Equal,
        (x, y) if x == y => Ordering::Greater,
        _ => Ordering::Less,
    }
}

/// Normal `(b − a) × (c − a)` and `N = normal · (p − a)`.
fn normal_and_volume<R>(t: &[[R; 3]; 3], p: &[R; 3]) -> ([R; 3], R)
where
    R: Clone,
    for<'x> &'x R: Add<&'x R, Output = R> + Sub<&'x R, Output = R> + Mul<&'x R, Output = R>,
{
    let d = |u: &[R; 3], v: &[R; 3]| -> [R; 3] { [&u[0] - &v[0], &u[1] - &v[1], &u[2] - &v[2]] };
    let (e1, e2, q) = (d(&t[1], &t[0]), d(&t[2], &t[0]), d(p, &t[0]));
    let n = [
        &(&e1[1] * &e2[2]) - &(&e1[2] * &e2[1]),
        &(&e1[2] * &e2[0]) - &(&e1[0] * &e2[2]),
        &(&e1[0] * &e2[1]) - &(&e1[1] * &e2[0]),
    ];
    let v = &(&(&n[0] * &q[0]) + &(&n[1] * &q[1])) + &(&n[2] * &q[2]);
    (n, v)
}

/// A closed interval `[lo, hi]` with outward-rounded arithmetic: every result is widened
/// by one unit in the last place, which covers round-to-nearest.
#[derive(Clone, Copy, Debug)]
struct Iv {
    lo: f64,
    hi: f64,
}

fn next_down(x: f64) -> f64 {
    if !x.is_finite() {
        x
    } else if x == 0.0 {
        -f64::from_bits(1)
    } else if x > 0.0 {
        f64::from_bits(x.to_bits() - 1)
    } else {
        f64::from_bits(x.to_bits() + 1)
    }
}

fn next_up(x: f64) -> f64 {
    -next_down(-x)
}

impl Iv {
    fn point(x: f64) -> Iv {
        Iv { lo: x, hi: x }
    }

    fn widen(lo: f64, hi: f64) -> Iv {
        Iv {
            lo: next_down(lo),
            hi: next_up(hi),
        }
    }

    fn sign(&self) -> Option<Ordering> {
        if self.lo > 0.0 {
            Some(Ordering::Greater)
        } else if self.hi < 0.0 {
            Some(Ordering::Less)
        } else {
            None
        }
    }
}

impl Add for &Iv {
    type Output = Iv;
    fn add(self, o: &Iv) -> Iv {
        Iv::widen(self.lo + o.lo, self.hi + o.hi)
    }
}

impl Sub for &Iv {
    type Output = Iv;
    fn sub(self, o: &Iv) -> Iv {
        Iv::widen(self.lo - o.hi, self.hi - o.lo)
    }
}

impl Mul for &Iv {
    type Output = Iv;
    fn mul(self, o: &Iv) -> Iv {
        let p = [
            self.lo * o.lo,
            self.lo * o.hi,
            self.hi * o.lo,
            self.hi * o.hi,
        ];
        // NaN (0 · ∞ from overflow) makes the interval unknown, sending us to the exact path.
        if p.iter().any(|x| x.is_nan()) {
            return Iv {
                lo: f64::NEG_INFINITY,
                hi: f64::INFINITY,
            };
        }
        Iv::widen(
            p.iter().copied().fold(f64::INFINITY, f64::min),
            p.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        )
    }
}

fn sign_of(x: &BigInt) -> Ordering {
    match x.sign() {
        num_bigint::Sign::Minus => Ordering::Less,
        num_bigint::Sign::NoSign => Ordering::Equal,
        num_bigint::Sign::Plus => Ordering::Greater,
    }
}

/// All inputs as big integers, scaled by one common power of two.
struct Exact {
    p: [BigInt; 3],
    t1: [[BigInt; 3]; 3],
    t2: [[BigInt; 3]; 3],
}

/// `x = m · 2^e` with integer `m` (finite `x`).
fn decompose(x: f64) -> (i64, i32) {
    let bits = x.to_bits();
    let sign = if bits >> 63 == 1 { -1 } else { 1 };
    let exp = ((bits >> 52) & 0x7ff) as i32;
    let frac = (bits & ((1 << 52) - 1)) as i64;
    if exp == 0 {
        (sign * frac, -1074)
    } else {
        (sign * (frac | (1 << 52)), exp - 1075)
    }
}

impl Exact {
    fn new(p: DVec3, t1: [DVec3; 3], t2: [DVec3; 3]) -> Exact {
        let all: Vec<f64> = [p]
            .iter()
            .chain(&t1)
            .chain(&t2)
            .flat_map(|v| v.to_array())
            .collect();
        let min_exp = all
            .iter()
            .filter(|x| **x != 0.0)
            .map(|&x| decompose(x).1)
            .min()
            .unwrap_or(0);
        let big = |x: f64| -> BigInt {
            let (m, e) = decompose(x);
            BigInt::from(m) << ((e - min_exp).max(0) as usize)
        };
        let v = |q: DVec3| q.to_array().map(big);
        Exact {
            p: v(p),
            t1: t1.map(v),
            t2: t2.map(v),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::predicates::cross_axis_line_triangle;
    use num_rational::BigRational;
    use proptest::prelude::*;

    fn q(x: f64) -> BigRational {
        BigRational::from_float(x).unwrap_or_default()
    }

    /// Exact crossing coordinate (unperturbed) by rationals.
    fn exact_t(axis: Axis, p: DVec3, t: [DVec3; 3]) -> BigRational {
        let a = axis.index();
        let d = |u: DVec3, v: DVec3| [q(u.x) - q(v.x), q(u.y) - q(v.y), q(u.z) - q(v.z)];
        let (e1, e2) = (d(t[1], t[0]), d(t[2], t[0]));
        let n = [
            &e1[1] * &e2[2] - &e1[2] * &e2[1],
            &e1[2] * &e2[0] - &e1[0] * &e2[2],
            &e1[0] * &e2[1] - &e1[1] * &e2[0],
        ];
        let mut pp = p;
        pp[a] = 0.0;
        let w = d(pp, t[0]);
        let nv = &n[0] * &w[0] + &n[1] * &w[1] + &n[2] * &w[2];
        -(nv / &n[a])
    }

    /// A triangle whose projection along `axis` contains the square [−0.2, 0.2]²: its
    /// `axis` coordinates are free, the others jittered around a fixed big triangle.
    fn tri(axis: Axis, raw: [(f64, f64, f64); 3]) -> [DVec3; 3] {
        let base = [(-1.0, -1.0), (1.0, -1.0), (0.0, 1.0)];
        let (b, c) = axis.others();
        std::array::from_fn(|i| {
            let (along, j1, j2) = raw[i];
            let mut v = DVec3::ZERO;
            v[axis.index()] = along;
            v[b] = base[i].0 + 0.3 * j1;
            v[c] = base[i].1 + 0.3 * j2;
            v
        })
    }

    fn raw() -> impl Strategy<Value = [(f64, f64, f64); 3]> {
        proptest::array::uniform3((-4.0..4.0f64, -0.5..0.5f64, -0.5..0.5f64))
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(500))]

        #[test]
        fn generic_order_matches_rationals(r1 in raw(), r2 in raw(), u in -0.2..0.2f64, w in -0.2..0.2f64, ax in 0usize..3) {
            let axis = Axis::from_index(ax);
            let (t1, t2) = (tri(axis, r1), tri(axis, r2));
            let mut p = DVec3::ZERO;
            let (b, c) = axis.others();
            p[b] = u;
            p[c] = w;
            prop_assert!(cross_axis_line_triangle(axis, axis.project(p), t1).is_some());
            prop_assert!(cross_axis_line_triangle(axis, axis.project(p), t2).is_some());
            let (x1, x2) = (exact_t(axis, p, t1), exact_t(axis, p, t2));
            prop_assume!(x1 != x2);
            prop_assert_eq!(compare_crossings(axis, p, t1, t2), x1.cmp(&x2));
            prop_assert_eq!(compare_crossings(axis, p, t2, t1), x2.cmp(&x1));
        }

        /// Near-ties: the second triangle is the first shifted along the axis by a few
        /// units in the last place, so the interval filter fails and the exact path runs.
        #[test]
        fn near_ties_are_exact(r1 in raw(), ulps in -3i64..=3, u in -0.2..0.2f64, w in -0.2..0.2f64, ax in 0usize..3) {
            let axis = Axis::from_index(ax);
            let t1 = tri(axis, r1);
            let a = axis.index();
            let t2 = t1.map(|mut v| {
                v[a] = f64::from_bits((v[a].to_bits() as i64 + ulps) as u64);
                v
            });
            let mut p = DVec3::ZERO;
            let (b, c) = axis.others();
            p[b] = u;
            p[c] = w;
            let (x1, x2) = (exact_t(axis, p, t1), exact_t(axis, p, t2));
            prop_assume!(x1 != x2);
            prop_assert_eq!(compare_crossings(axis, p, t1, t2), x1.cmp(&x2));
        }
    }

    #[test]
    fn tangent_ties_are_broken_by_the_perturbation() {
        // Two triangles through the point (0, 0, 0) on the x-line through the origin,
        // the first rising in y faster: under y + ε² the line meets it... first or last
        // as the signs say; the order must be antisymmetric and non-Equal.
        let t1 = [
            DVec3::ZERO,
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(0.0, 0.0, 1.0),
        ];
        let t2 = [
            DVec3::ZERO,
            DVec3::new(-1.0, 2.0, 0.0),
            DVec3::new(0.0, 0.0, 1.0),
        ];
        let o = compare_crossings(Axis::X, DVec3::ZERO, t1, t2);
        assert_ne!(o, Ordering::Equal);
        assert_eq!(compare_crossings(Axis::X, DVec3::ZERO, t2, t1), o.reverse());
        // Plane 1: x = y, crossing at t = ε²; plane 2: x = −y/2, crossing at −ε²/2.
        assert_eq!(o, Ordering::Greater);
        // Coplanar triangles cross at the same point for every perturbation.
        let t3 = [
            DVec3::new(-1.0, -1.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(0.0, 0.0, 1.0),
        ];
        assert_eq!(
            compare_crossings(Axis::X, DVec3::ZERO, t1, t3),
            Ordering::Equal
        );
    }
}
