//! Test-only exact arithmetic: univariate polynomials with integer coefficients,
//! real-root isolation by Sturm sequences, and exact signs of polynomials at real
//! algebraic roots.
//!
//! The CCD reference ([`reference`]) reduces every question to "the sign of polynomial `g`
//! at a root `r` of polynomial `f` in `[0, 1]`". Roots are isolated in intervals whose
//! rational endpoints are not roots; the sign of `g` at `r` is then decided exactly: the
//! interval is bisected until a Taylor bound shows that `g` keeps one sign on it, and —
//! because that never happens when `g(r) = 0` — after a few steps the square-free
//! `gcd(f, g)` is checked for a sign change across the interval (it has at most the one
//! root `r` there).
//!
//! Everything is integer arithmetic (no normalisation by gcds at every operation, which
//! made a `BigRational` version ten times slower): coefficients are integers, points are
//! unnormalised fractions `p/q` with `q > 0`, a polynomial's sign at `p/q` is the sign of
//! the homogenised `Σ cᵢ pⁱ q^{d−i}`, and Sturm sequences use sign-corrected pseudo-
//! remainders divided by their content.

pub(crate) mod reference;

use std::cmp::Ordering;

use num_bigint::{BigInt, Sign};
use num_rational::BigRational;
use num_traits::{One, Signed, ToPrimitive, Zero};

/// Integers.
pub(crate) type Z = BigInt;

fn zi(x: i64) -> Z {
    Z::from(x)
}

fn sign(x: &Z) -> i32 {
    match x.sign() {
        Sign::Plus => 1,
        Sign::Minus => -1,
        Sign::NoSign => 0,
    }
}

fn gcd(a: &Z, b: &Z) -> Z {
    let (mut a, mut b) = (a.abs(), b.abs());
    while !b.is_zero() {
        let r = &a % &b;
        a = b;
        b = r;
    }
    a
}

/// An exact rational point `num / den`, `den > 0`, with common powers of two removed.
#[derive(Clone, Debug)]
pub(crate) struct Pt {
    num: Z,
    den: Z,
}

impl Pt {
    pub(crate) fn new(num: Z, den: Z) -> Pt {
        assert!(!den.is_zero(), "zero denominator");
        let (num, den) = if den.is_negative() {
            (-num, -den)
        } else {
            (num, den)
        };
        let common = match (num.trailing_zeros(), den.trailing_zeros()) {
            (Some(a), Some(b)) => a.min(b),
            (None, _) => den.trailing_zeros().unwrap_or(0), // num = 0: make den odd
            _ => 0,
        };
        Pt {
            num: num >> common,
            den: den >> common,
        }
    }

    pub(crate) fn int(x: i64) -> Pt {
        Pt::new(zi(x), Z::one())
    }

    /// The exact value of a finite double.
    pub(crate) fn of_f64(x: f64) -> Pt {
        let r =
            BigRational::from_float(x).unwrap_or_else(|| panic!("test input {x} is not finite"));
        Pt::new(r.numer().clone(), r.denom().clone())
    }

    fn mid(a: &Pt, b: &Pt) -> Pt {
        Pt::new(&a.num * &b.den + &b.num * &a.den, &a.den * &b.den * 2)
    }

    /// `a + (b − a) k / d`.
    fn lerp(a: &Pt, b: &Pt, k: i64, d: i64) -> Pt {
        let num = &a.num * &b.den * (d - k) + &b.num * &a.den * k;
        Pt::new(num, &a.den * &b.den * d)
    }

    pub(crate) fn to_f64(&self) -> f64 {
        BigRational::new(self.num.clone(), self.den.clone())
            .to_f64()
            .unwrap_or(f64::NAN)
    }
}

impl PartialEq for Pt {
    fn eq(&self, o: &Pt) -> bool {
        self.cmp(o) == Ordering::Equal
    }
}
impl Eq for Pt {}
impl PartialOrd for Pt {
    fn partial_cmp(&self, o: &Pt) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Pt {
    fn cmp(&self, o: &Pt) -> Ordering {
        (&self.num * &o.den).cmp(&(&o.num * &self.den))
    }
}

/// A polynomial with integer coefficients, constant term first, without trailing zeros
/// (the zero polynomial has none).
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Poly(Vec<Z>);

impl Poly {
    pub(crate) fn zero() -> Poly {
        Poly(Vec::new())
    }

    /// `c0 + c1 t`.
    pub(crate) fn linear(c0: Z, c1: Z) -> Poly {
        Poly(vec![c0, c1]).trim()
    }

    fn trim(mut self) -> Poly {
        while self.0.last().is_some_and(Zero::is_zero) {
            self.0.pop();
        }
        self
    }

    pub(crate) fn is_zero(&self) -> bool {
        self.0.is_empty()
    }

    /// Degree; the zero polynomial reports 0 as well (callers check `is_zero` first).
    pub(crate) fn degree(&self) -> usize {
        self.0.len().saturating_sub(1)
    }

    fn coeff(&self, i: usize) -> Z {
        self.0.get(i).cloned().unwrap_or_else(Z::zero)
    }

    fn lead(&self) -> Z {
        self.0.last().cloned().unwrap_or_else(Z::zero)
    }

    pub(crate) fn add(&self, o: &Poly) -> Poly {
        let n = self.0.len().max(o.0.len());
        Poly((0..n).map(|i| self.coeff(i) + o.coeff(i)).collect()).trim()
    }

    pub(crate) fn sub(&self, o: &Poly) -> Poly {
        let n = self.0.len().max(o.0.len());
        Poly((0..n).map(|i| self.coeff(i) - o.coeff(i)).collect()).trim()
    }

    pub(crate) fn mul(&self, o: &Poly) -> Poly {
        if self.is_zero() || o.is_zero() {
            return Poly::zero();
        }
        let mut c = vec![Z::zero(); self.0.len() + o.0.len() - 1];
        for (i, a) in self.0.iter().enumerate() {
            for (j, b) in o.0.iter().enumerate() {
                c[i + j] += a * b;
            }
        }
        Poly(c).trim()
    }

    fn scale(&self, s: &Z) -> Poly {
        Poly(self.0.iter().map(|c| c * s).collect()).trim()
    }

    /// Sign of the value at `x`: the sign of `Σ cᵢ pⁱ q^{d−i}` (`q > 0`).
    pub(crate) fn sign_at(&self, x: &Pt) -> i32 {
        let Some((last, rest)) = self.0.split_last() else {
            return 0;
        };
        let mut h = last.clone();
        let mut qpow = Z::one();
        for c in rest.iter().rev() {
            qpow *= &x.den;
            h = h * &x.num + c * &qpow;
        }
        sign(&h)
    }

    fn derivative(&self) -> Poly {
        Poly(
            self.0
                .iter()
                .enumerate()
                .skip(1)
                .map(|(i, c)| c * zi(i as i64))
                .collect(),
        )
        .trim()
    }

    /// Divided by the (positive) gcd of its coefficients.
    fn primitive(&self) -> Poly {
        let g = self.0.iter().fold(Z::zero(), |g, c| gcd(&g, c));
        if g.is_zero() || g.is_one() {
            self.clone()
        } else {
            Poly(self.0.iter().map(|c| c / &g).collect())
        }
    }

    /// Pseudo-division by a non-zero `d`: `λ self = quo · d + rem` with `λ > 0` a power of
    /// `|lead(d)|` (the sign is corrected, which Sturm sequences need).
    fn pseudo_divrem(&self, d: &Poly) -> (Poly, Poly) {
        assert!(!d.is_zero(), "division by the zero polynomial");
        let lead = d.lead();
        let dl = d.0.len();
        let mut r = self.clone();
        let mut quo = Poly(vec![Z::zero(); self.0.len().saturating_sub(dl) + 1]);
        let mut steps = 0u32;
        while !r.is_zero() && r.0.len() >= dl {
            let shift = r.0.len() - dl;
            let f = r.lead();
            r = r.scale(&lead);
            quo = quo.scale(&lead);
            for (i, c) in d.0.iter().enumerate() {
                r.0[shift + i] -= &f * c;
            }
            quo.0.resize(quo.0.len().max(shift + 1), Z::zero());
            quo.0[shift] += &f;
            r = r.trim();
            steps += 1;
        }
        if lead.is_negative() && steps % 2 == 1 {
            (Poly::zero().sub(&quo.trim()), Poly::zero().sub(&r))
        } else {
            (quo.trim(), r)
        }
    }

    /// A greatest common divisor, primitive (zero only when both are zero).
    pub(crate) fn gcd(a: &Poly, b: &Poly) -> Poly {
        let (mut a, mut b) = (a.primitive(), b.primitive());
        while !b.is_zero() {
            let r = a.pseudo_divrem(&b).1.primitive();
            a = b;
            b = r;
        }
        a
    }

    /// The square-free part: same roots, all simple.
    fn squarefree(&self) -> Poly {
        if self.degree() == 0 {
            return self.clone();
        }
        let g = Poly::gcd(self, &self.derivative());
        self.pseudo_divrem(&g).0.primitive()
    }

    /// Coefficients of `z ↦ q^d self((p + z)/q)` for the point `p/q` (a Taylor expansion
    /// scaled to integers).
    fn shifted(&self, x: &Pt) -> Poly {
        let d = self.degree();
        let mut qpow = vec![Z::one(); d + 1];
        for i in 1..=d {
            qpow[i] = &qpow[i - 1] * &x.den;
        }
        let mut c: Vec<Z> = self
            .0
            .iter()
            .enumerate()
            .map(|(i, ci)| ci * &qpow[d - i])
            .collect();
        let n = c.len();
        for i in 0..n {
            for j in (i..n - 1).rev() {
                let t = &c[j + 1] * &x.num;
                c[j] += t;
            }
        }
        Poly(c).trim()
    }
}

/// A Sturm sequence: counts distinct real roots between two non-roots.
struct Sturm(Vec<Poly>);

impl Sturm {
    fn new(p: &Poly) -> Sturm {
        let mut seq = vec![p.clone(), p.derivative().primitive()];
        while !seq[seq.len() - 1].is_zero() {
            let n = seq.len();
            let r = seq[n - 2].pseudo_divrem(&seq[n - 1]).1.primitive();
            seq.push(Poly::zero().sub(&r));
        }
        seq.pop();
        Sturm(seq)
    }

    fn variations(&self, x: &Pt) -> usize {
        let signs: Vec<i32> = self
            .0
            .iter()
            .map(|p| p.sign_at(x))
            .filter(|&s| s != 0)
            .collect();
        signs.windows(2).filter(|w| w[0] != w[1]).count()
    }

    /// Distinct roots in `(lo, hi)`, both non-roots of the first polynomial.
    fn count(&self, lo: &Pt, hi: &Pt) -> usize {
        self.variations(lo) - self.variations(hi)
    }
}

/// A real root in `[0, 1]` of a polynomial, exactly.
#[derive(Clone, Debug)]
pub(crate) enum Root {
    /// A rational root.
    Exact(Pt),
    /// The only root of the square-free `sq` in `(lo, hi)`; `sq(lo)`, `sq(hi)` are non-zero.
    Isolated { sq: Poly, lo: Pt, hi: Pt },
}

/// A point of `(a, b)` that is not a root of `p` (which has fewer than seven roots there).
fn non_root_between(p: &Poly, a: &Pt, b: &Pt) -> Pt {
    for (k, d) in [(1, 2), (3, 8), (5, 8), (5, 16), (11, 16), (7, 16), (9, 16)] {
        let m = Pt::lerp(a, b, k, d);
        if p.sign_at(&m) != 0 {
            return m;
        }
    }
    panic!(
        "polynomial of degree {} has too many roots in an interval",
        p.degree()
    )
}

fn isolate(st: &Sturm, sq: &Poly, lo: Pt, hi: Pt, out: &mut Vec<(Pt, Pt)>) {
    match st.count(&lo, &hi) {
        0 => {}
        1 => out.push((lo, hi)),
        _ => {
            let m = non_root_between(sq, &lo, &hi);
            isolate(st, sq, lo, m.clone(), out);
            isolate(st, sq, m, hi, out);
        }
    }
}

/// All roots of the non-zero `f` in the closed interval `[0, 1]`.
pub(crate) fn roots_in_unit(f: &Poly) -> Vec<Root> {
    assert!(!f.is_zero());
    if f.degree() == 0 {
        return Vec::new();
    }
    let sq = f.squarefree();
    let st = Sturm::new(&sq);
    let lo = (1..)
        .map(|k| Pt::int(-k))
        .find(|x| sq.sign_at(x) != 0)
        .unwrap_or_else(|| Pt::int(-1));
    let hi = (2..)
        .map(Pt::int)
        .find(|x| sq.sign_at(x) != 0)
        .unwrap_or_else(|| Pt::int(2));
    let mut found = Vec::new();
    isolate(&st, &sq, lo, hi, &mut found);
    let (zero, one) = (Pt::int(0), Pt::int(1));
    let mut roots = Vec::new();
    for (mut a, mut b) in found {
        loop {
            if b <= zero || a >= one {
                break;
            }
            if a >= zero && b <= one {
                roots.push(Root::Isolated {
                    sq: sq.clone(),
                    lo: a,
                    hi: b,
                });
                break;
            }
            // The interval straddles 0 or 1: that point is the root, or it splits the interval.
            let cut = if a < zero { zero.clone() } else { one.clone() };
            let s = sq.sign_at(&cut);
            if s == 0 {
                roots.push(Root::Exact(cut));
                break;
            }
            if s == sq.sign_at(&a) {
                a = cut;
            } else {
                b = cut;
            }
        }
    }
    roots
}

/// The exact sign of `g` at the root `r`.
pub(crate) fn sign_at_root(g: &Poly, r: &Root) -> i32 {
    let (sq, lo, hi) = match r {
        Root::Exact(x) => return g.sign_at(x),
        Root::Isolated { sq, lo, hi } => (sq, lo, hi),
    };
    if g.is_zero() {
        return 0;
    }
    let (mut a, mut b) = (lo.clone(), hi.clone());
    let sa = sq.sign_at(&a);
    for step in 0.. {
        if step == 6 {
            // gcd(sq, g) is square-free with at most the one root r of sq in (lo, hi): a
            // sign change across (a, b) ∋ r means it vanishes at r, i.e. g(r) = 0.
            let h = Poly::gcd(sq, g);
            if h.degree() >= 1 && h.sign_at(&a) != h.sign_at(&b) {
                return 0;
            }
        }
        let m = Pt::mid(&a, &b);
        let sm = sq.sign_at(&m);
        if sm == 0 {
            return g.sign_at(&m);
        }
        // With G(z) = q^d g((p + z)/q) at m = p/q and |x − m| ≤ ρ, i.e. |z| ≤ R = qρ:
        // |G(z) − G(0)| ≤ Σ_{k≥1} |G_k| Rᵏ. Written over R = Rn/Rd to stay in integers.
        let taylor = g.shifted(&m);
        let half = Pt::new(&b.num * &a.den - &a.num * &b.den, &a.den * &b.den * 2);
        let (rn, rd) = (&half.num * &m.den, half.den.clone());
        let d = taylor.degree();
        let mut bound = Z::zero();
        let mut rn_pow = Z::one();
        for (k, c) in taylor.0.iter().enumerate().skip(1) {
            rn_pow *= &rn;
            bound += c.abs() * &rn_pow * num_traits::pow(rd.clone(), d - k);
        }
        let g0 = taylor.coeff(0);
        if g0.abs() * num_traits::pow(rd.clone(), d) > bound {
            return sign(&g0);
        }
        if sm == sa {
            a = m;
        } else {
            b = m;
        }
    }
    unreachable!("the loop above only ends by returning")
}

/// Is the exact point `t` at most the root `r`?
pub(crate) fn le_root(t: &Pt, r: &Root) -> bool {
    match r {
        Root::Exact(x) => t <= x,
        Root::Isolated { sq, lo, hi } => {
            if t <= lo {
                true
            } else if t >= hi {
                false
            } else {
                let s = sq.sign_at(t);
                s == 0 || s == sq.sign_at(lo)
            }
        }
    }
}

/// A double near the root (for diagnostics and approximate checks).
pub(crate) fn approx(r: &Root) -> f64 {
    match r {
        Root::Exact(x) => x.to_f64(),
        Root::Isolated { sq, lo, hi } => {
            let (mut a, mut b) = (lo.clone(), hi.clone());
            let sa = sq.sign_at(&a);
            for _ in 0..60 {
                let m = Pt::mid(&a, &b);
                match sq.sign_at(&m) {
                    0 => return m.to_f64(),
                    s if s == sa => a = m,
                    _ => b = m,
                }
            }
            Pt::mid(&a, &b).to_f64()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn poly(c: &[i64]) -> Poly {
        Poly(c.iter().map(|&x| zi(x)).collect()).trim()
    }

    fn approx_roots(p: &Poly) -> Vec<f64> {
        let mut r: Vec<f64> = roots_in_unit(p).iter().map(approx).collect();
        r.sort_by(f64::total_cmp);
        r
    }

    #[test]
    fn roots_of_known_polynomials() {
        // (2t − 1)(4t − 1)(t − 3): roots 1/2, 1/4 in [0, 1].
        let p = poly(&[-1, 2]).mul(&poly(&[-1, 4])).mul(&poly(&[-3, 1]));
        assert_eq!(approx_roots(&p), vec![0.25, 0.5]);
        // t (t − 1)² : roots at the ends, one double.
        let p = poly(&[0, 1]).mul(&poly(&[-1, 1])).mul(&poly(&[-1, 1]));
        assert_eq!(approx_roots(&p), vec![0.0, 1.0]);
        // 2t² − 1: the irrational root 1/√2; (3t − 1)² : a double non-dyadic root.
        let r = approx_roots(&poly(&[-1, 0, 2]));
        assert!(r.len() == 1 && (r[0] - 0.5f64.sqrt()).abs() < 1e-15);
        let r = approx_roots(&poly(&[1, -6, 9]));
        assert!(r.len() == 1 && (r[0] - 1.0 / 3.0).abs() < 1e-15);
        // No roots: t² + 1, and −t² − 3t − 2 (roots −1, −2).
        assert!(roots_in_unit(&poly(&[1, 0, 1])).is_empty());
        assert!(roots_in_unit(&poly(&[-2, -3, -1])).is_empty());
    }

    #[test]
    fn signs_at_irrational_roots() {
        let r = roots_in_unit(&poly(&[-1, 0, 2])).remove(0); // 1/√2
        assert_eq!(sign_at_root(&poly(&[-1, 0, 2]), &r), 0);
        assert_eq!(sign_at_root(&poly(&[-1, 0, 4]), &r), 1); // 4/2 − 1 > 0
        assert_eq!(sign_at_root(&poly(&[-3, 4]), &r), -1); // 4·0.7071 − 3 < 0
        assert_eq!(sign_at_root(&poly(&[-7071, 10000]), &r), 1); // 10000/√2 > 7071
        assert_eq!(sign_at_root(&poly(&[-7072, 10000]), &r), -1);
        assert_eq!(sign_at_root(&poly(&[1, 0, -2]).mul(&poly(&[5, 1])), &r), 0);
        let frac = |a: i64, b: i64| Pt::new(zi(a), zi(b));
        assert!(le_root(&frac(7, 10), &r) && !le_root(&frac(71, 100), &r));
    }

    #[test]
    fn points_compare_exactly() {
        assert!(Pt::new(zi(1), zi(3)) < Pt::of_f64(0.3333333333333334));
        assert!(Pt::new(zi(-2), zi(-6)) == Pt::new(zi(1), zi(3)));
        assert!(Pt::mid(&Pt::int(0), &Pt::int(1)) == Pt::of_f64(0.5));
    }
}
