//! Certificates that an interval `[t_a, t_b]` of the step holds no contact, each a
//! floating-point computation compared against a rigorous forward error bound.
//!
//! # Error model
//!
//! IEEE double, round to nearest, `u = 2⁻⁵³`; `fl(a ∘ b) = (a ∘ b)(1 + δ)`, `|δ| ≤ u`, plus
//! an absolute error below `2⁻¹⁰⁷⁵` per multiplication when the result underflows (covered
//! by [`TINY`]). Rust never fuses multiply–adds, so the operation counts below are exact.
//! `M` is the per-axis bound on `|x|` over all eight input points (`Scale::m`).
//!
//! - Position at a float time `t ∈ [0, 1]`: `fl(x⁰ + fl(t · fl(x¹ − x⁰)))` (or `x¹` exactly
//!   at `t = 1`). With `|x¹ − x⁰| ≤ 2M` and the exact position bounded by `M`, the error is
//!   `≤ 2M(2u + u²) + u(M + 4.01uM) ≤ 5.001 u M` (+ `TINY`).
//! - Difference of two computed positions `D̃ = fl(Ã − B̃)`:
//!   `|D̃ − D| ≤ 10.002 u M + 1.0001 u |D̃|` (+ `2 TINY`) per axis; [`eta`] rounds the
//!   constants up to `10.02` and `1.01`.
//! - Dot product `fl(n · D̃)`: `≤ γ₃ Σ |nᵢ D̃ᵢ|`, `γ₃ ≤ 3.01u`; with the input error this
//!   gives `Σ |nᵢ| (4.02 u |D̃ᵢ| + 10.02 u Mᵢ)`, rounded up to `4.5` and `10.5`.
//! - Determinant `fl(x · (y × z))`: five roundings per term, so `≤ γ₅ perm(|x|,|y|,|z|)`
//!   with `perm ≤ ‖x‖₁‖y‖₁‖z‖₁`; input errors `hₓ = ‖ηₓ‖₁` enter through the telescoped
//!   trilinear difference `hₓYZ + XhᵧZ + XYh_z`, where `X = ‖x̃‖₁ + hₓ` bounds both the
//!   exact and the computed vector.
//!
//! The bounds themselves are computed in floating point with relative error of a few `u`;
//! the rounded-up constants (and a final factor `1.01` for determinants) absorb it.

use glam::DVec3;

/// Unit roundoff of `f64`, `2⁻⁵³`.
pub(crate) const U: f64 = f64::EPSILON * 0.5;

/// `2⁻¹⁰⁰⁰`: absolute slack that dominates any accumulation of underflow errors
/// (each below `2⁻¹⁰⁷⁵`) in the few dozen operations of a certificate.
pub(crate) const TINY: f64 = f64::from_bits(23u64 << 52);

/// Per-axis error bound of a difference `v` of two computed positions (see module docs).
#[inline]
pub(crate) fn eta(v: DVec3, m: DVec3) -> DVec3 {
    m * (10.02 * U) + v.abs() * (1.01 * U) + DVec3::splat(3.0 * TINY)
}

/// True when some coordinate axis separates: on that axis every pair difference at both
/// ends of the interval has the same strict sign beyond its error bound (a swept,
/// relative bounding-box test). NaN never certifies.
#[inline]
pub(crate) fn separated_on_axis(d: &[DVec3; 8], m: DVec3) -> bool {
    for axis in 0..3 {
        let mut pos = true;
        let mut neg = true;
        for v in d {
            let e = eta(*v, m)[axis];
            let x = v[axis];
            pos &= x - e > 0.0;
            neg &= x + e < 0.0;
        }
        if pos || neg {
            return true;
        }
    }
    false
}

/// True when direction `n` separates: every `n · Dⱼ` at both ends of the interval has the
/// same strict sign beyond its error bound. Any `n` is allowed; it is rescaled to
/// `max |nᵢ| = 1` so that the underflow slack stays a fixed multiple of [`TINY`].
#[inline]
pub(crate) fn separated_along(d: &[DVec3; 8], m: DVec3, n: DVec3) -> bool {
    let s = n.abs().max_element();
    if !(s > 0.0 && s.is_finite()) {
        return false;
    }
    let n = n / s;
    let na = n.abs();
    let base = 10.5 * U * na.dot(m) + 16.0 * TINY;
    let mut pos = true;
    let mut neg = true;
    for v in d {
        let g = n.dot(*v);
        let e = 4.5 * U * na.dot(v.abs()) + base;
        pos &= g > e;
        neg &= g < -e;
    }
    pos || neg
}

/// Error bound of `fl(det(x, y, z))` given the ℓ₁ input error bounds `h` and the ℓ₁
/// magnitudes `big = ‖ṽ‖₁ + h` (see module docs).
#[inline]
fn det_error(h: [f64; 3], big: [f64; 3]) -> f64 {
    let [hx, hy, hz] = h;
    let [x, y, z] = big;
    hx * y * z + x * hy * z + x * y * hz + 5.01 * U * x * y * z
}

#[inline]
fn det(x: DVec3, y: DVec3, z: DVec3) -> f64 {
    x.dot(y.cross(z))
}

/// True when the coplanarity cubic `f(t) = det[e₁, e₂, r]` provably has no zero on the
/// interval: its four Bernstein coefficients there (built from the vectors `a` at `t_a`
/// and `b` at `t_b`) share a strict sign beyond their error bounds.
///
/// With `v(τ) = (1 − τ) v_a + τ v_b`, trilinearity gives
/// `f = Σₖ C(3,k) τᵏ(1 − τ)³⁻ᵏ Bₖ` where `3 B₁` / `3 B₂` are the sums of the three
/// determinants taking one / two of their arguments from `b`. `f` is a convex combination
/// of the `Bₖ`, so one strict sign for all four excludes a root.
pub(crate) fn coplanarity_excluded(a: &[DVec3; 3], b: &[DVec3; 3], m: DVec3) -> bool {
    let l1 = |v: DVec3| v.abs().element_sum();
    let h = |v: DVec3| eta(v, m).element_sum();
    let (ha, hb) = (a.map(h), b.map(h));
    let big_a = [l1(a[0]) + ha[0], l1(a[1]) + ha[1], l1(a[2]) + ha[2]];
    let big_b = [l1(b[0]) + hb[0], l1(b[1]) + hb[1], l1(b[2]) + hb[2]];
    // `pick[i]` chooses argument i from the far end (`true`) or the near end.
    let term = |pick: [bool; 3]| -> (f64, f64) {
        let v = |i: usize| if pick[i] { b[i] } else { a[i] };
        let hh = |i: usize| if pick[i] { hb[i] } else { ha[i] };
        let bb = |i: usize| if pick[i] { big_b[i] } else { big_a[i] };
        (
            det(v(0), v(1), v(2)),
            det_error([hh(0), hh(1), hh(2)], [bb(0), bb(1), bb(2)]),
        )
    };
    let sum3 = |p: [[bool; 3]; 3]| -> (f64, f64) {
        let (d0, e0) = term(p[0]);
        let (d1, e1) = term(p[1]);
        let (d2, e2) = term(p[2]);
        // Two additions: at most 2.01 u Σ|dᵢ| more.
        (
            d0 + d1 + d2,
            e0 + e1 + e2 + 2.01 * U * (d0.abs() + d1.abs() + d2.abs()),
        )
    };
    let coeffs = [
        term([false; 3]),
        sum3([
            [true, false, false],
            [false, true, false],
            [false, false, true],
        ]),
        sum3([
            [false, true, true],
            [true, false, true],
            [true, true, false],
        ]),
        term([true; 3]),
    ];
    let mut pos = true;
    let mut neg = true;
    for (c, e) in coeffs {
        let e = 1.01 * e + 64.0 * TINY;
        pos &= c > e;
        neg &= c < -e;
    }
    pos || neg
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiny_is_two_to_the_minus_thousand() {
        assert_eq!(TINY, 2f64.powi(-1000));
    }

    #[test]
    fn axis_test_needs_a_margin() {
        let m = DVec3::ONE;
        let mut d = [DVec3::new(1.0, -1.0, 0.0); 8];
        assert!(separated_on_axis(&d, m));
        d[3].x = 1e-17; // positive but within the error bound
        d[5].y = 1e-17;
        assert!(!separated_on_axis(&d, m));
        d[0] = DVec3::new(f64::NAN, f64::NAN, f64::NAN);
        assert!(!separated_on_axis(&d, m));
    }

    #[test]
    fn direction_test_is_sign_symmetric() {
        let m = DVec3::splat(2.0);
        let d = [DVec3::new(1.0, 2.0, 0.5); 8];
        assert!(separated_along(&d, m, DVec3::new(1.0, 1.0, 1.0)));
        assert!(separated_along(&d, m, DVec3::new(-1.0, -1.0, -1.0)));
        assert!(!separated_along(&d, m, DVec3::new(2.0, -1.0, 0.0)));
        assert!(!separated_along(&d, m, DVec3::ZERO));
    }

    #[test]
    fn coplanarity_detects_a_sign_change() {
        let m = DVec3::splat(1.0);
        let e1 = DVec3::X;
        let e2 = DVec3::Y;
        // r moves from z = +1 to z = +0.5: no root.
        assert!(coplanarity_excluded(
            &[e1, e2, DVec3::Z],
            &[e1, e2, DVec3::Z * 0.5],
            m
        ));
        // r crosses the plane: root inside.
        assert!(!coplanarity_excluded(
            &[e1, e2, DVec3::Z],
            &[e1, e2, -DVec3::Z],
            m
        ));
        // Always coplanar: never excluded.
        assert!(!coplanarity_excluded(
            &[e1, e2, DVec3::X],
            &[e1, e2, DVec3::Y],
            m
        ));
        // Height at the rounding level relative to M: not excluded.
        assert!(!coplanarity_excluded(
            &[e1, e2, DVec3::Z * 1e-17],
            &[e1, e2, DVec3::Z * 1e-17],
            m
        ));
    }
}
