//! Floating-point numbers that carry a rigorous bound on their distance to the exact
//! value, and the Bernstein forms (over one interval of the step) of the quadratics and
//! quartics built from them. Used by the kernels' "side" certificates.
//!
//! Error model as in `certify.rs`: `u = 2⁻⁵³`, one rounding per operation, `TINY` for
//! underflow. Each operation adds its own rounding to the propagated bound and inflates the
//! bound by `1 + 6u`, which covers the rounding committed while computing the bound itself
//! (a sum of at most five non-negative rounded terms).

use glam::DVec3;

use super::certify::{TINY, U, eta};

/// A computed value `v` and a bound `e` with `|v − exact| ≤ e`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Bf {
    v: f64,
    e: f64,
}

const INFLATE: f64 = 1.0 + 6.0 * U;

impl Bf {
    #[inline]
    fn add(self, o: Bf) -> Bf {
        let v = self.v + o.v;
        Bf {
            v,
            e: (self.e + o.e + U * v.abs()) * INFLATE + TINY,
        }
    }

    #[inline]
    fn sub(self, o: Bf) -> Bf {
        self.add(Bf { v: -o.v, e: o.e })
    }

    #[inline]
    fn mul(self, o: Bf) -> Bf {
        let v = self.v * o.v;
        // |AB − ab| ≤ |a| e_B + |b| e_A + e_A e_B, plus the rounding of the product.
        Bf {
            v,
            e: (self.v.abs() * o.e + o.v.abs() * self.e + self.e * o.e + U * v.abs()) * INFLATE
                + TINY,
        }
    }

    /// Provably negative (false for NaN or infinite values).
    #[inline]
    fn negative(self) -> bool {
        self.v + self.e < 0.0
    }
}

/// A vector difference of two computed positions, with the per-axis bound of
/// [`eta`] (`m` = per-axis bound of the input magnitudes).
#[derive(Clone, Copy, Debug)]
pub(crate) struct BVec([Bf; 3]);

impl BVec {
    #[inline]
    pub(crate) fn difference(v: DVec3, m: DVec3) -> BVec {
        let e = eta(v, m);
        BVec([
            Bf { v: v.x, e: e.x },
            Bf { v: v.y, e: e.y },
            Bf { v: v.z, e: e.z },
        ])
    }

    #[inline]
    fn dot(&self, o: &BVec) -> Bf {
        self.0[0]
            .mul(o.0[0])
            .add(self.0[1].mul(o.0[1]))
            .add(self.0[2].mul(o.0[2]))
    }
}

/// A vector that moves linearly over the interval: its values at the two ends.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Moving {
    pub(crate) a: BVec,
    pub(crate) b: BVec,
}

/// Scaled Bernstein coefficients `[A₀, 2A₁, A₂]` of a quadratic on the interval.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Quadratic([Bf; 3]);

/// The quadratic `x(τ) · y(τ)` of two linearly moving vectors.
#[inline]
pub(crate) fn dot(x: &Moving, y: &Moving) -> Quadratic {
    Quadratic([
        x.a.dot(&y.a),
        x.a.dot(&y.b).add(x.b.dot(&y.a)),
        x.b.dot(&y.b),
    ])
}

/// Scaled Bernstein coefficients `[C(4,k) Qₖ]` of a quartic on the interval; a positive
/// scale per coefficient keeps every sign.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Quartic([Bf; 5]);

impl Quartic {
    /// `x y − z w`. With scaled quadratic coefficients `Xᵢ = C(2,i) xᵢ`, the product's
    /// scaled coefficients are `Σ_{i+j=k} Xᵢ Yⱼ`.
    #[inline]
    pub(crate) fn product_difference(
        x: &Quadratic,
        y: &Quadratic,
        z: &Quadratic,
        w: &Quadratic,
    ) -> Quartic {
        let (x, y, z, w) = (&x.0, &y.0, &z.0, &w.0);
        let c = |k: usize| {
            let mut s: Option<Bf> = None;
            for i in k.saturating_sub(2)..=k.min(2) {
                let t = x[i].mul(y[k - i]).sub(z[i].mul(w[k - i]));
                s = Some(s.map_or(t, |s| s.add(t)));
            }
            s.unwrap_or(Bf { v: 0.0, e: 0.0 })
        };
        Quartic([c(0), c(1), c(2), c(3), c(4)])
    }

    /// `self − o`, coefficient by coefficient.
    #[inline]
    pub(crate) fn minus(&self, o: &Quartic) -> Quartic {
        Quartic(std::array::from_fn(|k| self.0[k].sub(o.0[k])))
    }

    /// Provably negative on the whole interval: every Bernstein coefficient is (the
    /// quartic is their convex combination).
    #[inline]
    pub(crate) fn negative(&self) -> bool {
        self.0.iter().all(|c| c.negative())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn moving(a: DVec3, b: DVec3) -> Moving {
        let m = DVec3::splat(4.0);
        Moving {
            a: BVec::difference(a, m),
            b: BVec::difference(b, m),
        }
    }

    #[test]
    fn quartic_matches_direct_evaluation() {
        // x = (1 + τ, 0, 0), y = (2 − τ, 1, 0): x·y = (1 + τ)(2 − τ); same for z, w swapped.
        let x = moving(DVec3::new(1.0, 0.0, 0.0), DVec3::new(2.0, 0.0, 0.0));
        let y = moving(DVec3::new(2.0, 1.0, 0.0), DVec3::new(1.0, 1.0, 0.0));
        let z = moving(DVec3::new(0.0, 1.0, 0.0), DVec3::new(0.0, 3.0, 0.0));
        let w = moving(DVec3::new(0.0, 1.0, 1.0), DVec3::new(0.0, 1.0, 1.0));
        let q = Quartic::product_difference(&dot(&x, &x), &dot(&y, &y), &dot(&z, &z), &dot(&w, &w));
        // Evaluate the Bernstein form at τ and compare with the direct product.
        for k in 0..=8 {
            let t = f64::from(k) / 8.0;
            let basis = [
                (1.0 - t).powi(4),
                t * (1.0 - t).powi(3),
                t * t * (1.0 - t).powi(2),
                t.powi(3) * (1.0 - t),
                t.powi(4),
            ];
            let value: f64 = (0..5).map(|i| q.0[i].v * basis[i]).sum();
            let (xv, yv, zv, wv) = (
                1.0 + t,
                DVec3::new(2.0 - t, 1.0, 0.0),
                1.0 + 2.0 * t,
                DVec3::new(0.0, 1.0, 1.0),
            );
            let direct = xv * xv * yv.length_squared() - zv * zv * wv.length_squared();
            assert!(
                (value - direct).abs() < 1e-12,
                "τ = {t}: {value} vs {direct}"
            );
        }
    }

    #[test]
    fn negativity_needs_a_margin() {
        let tiny = moving(DVec3::new(1e-20, 0.0, 0.0), DVec3::new(1e-20, 0.0, 0.0));
        let one = moving(DVec3::X, DVec3::X);
        // 0·1 − (1e-20)²·… is negative but far inside the error bound.
        let zero = moving(DVec3::ZERO, DVec3::ZERO);
        let q = Quartic::product_difference(
            &dot(&zero, &one),
            &dot(&one, &one),
            &dot(&tiny, &tiny),
            &dot(&one, &one),
        );
        assert!(!q.negative());
        let q = Quartic::product_difference(
            &dot(&zero, &one),
            &dot(&one, &one),
            &dot(&one, &one),
            &dot(&one, &one),
        );
        assert!(q.negative());
    }
}
