//! Exact orientation predicates and the small vocabulary ([`Sign`], [`Axis`]) the other
//! predicate modules share.
//!
//! Both predicates delegate to Shewchuk's adaptive-precision determinants (crate
//! `robust`): a cheap floating-point evaluation with an error bound, refined with
//! expansion arithmetic only when the bound cannot certify the sign. Only the *sign*
//! is exact, so that is all these functions return.

use std::ops::{Mul, Neg};

use glam::{DVec2, DVec3};
use robust::{Coord, Coord3D};

/// The exact sign of a determinant, or of a comparison.
///
/// Ordered `Negative < Zero < Positive`, so `max`/`min` behave as on the integers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Sign {
    /// Strictly below zero.
    Negative,
    /// Exactly zero: the degenerate case.
    Zero,
    /// Strictly above zero.
    Positive,
}

impl Sign {
    /// The sign of `x`. NaN maps to [`Sign::Zero`] so that a non-finite input reads as
    /// "degenerate" downstream instead of picking an arbitrary side.
    #[inline]
    pub fn of(x: f64) -> Sign {
        if x > 0.0 {
            Sign::Positive
        } else if x < 0.0 {
            Sign::Negative
        } else {
            Sign::Zero
        }
    }

    /// The exact sign of `a - b`: a plain comparison, so no rounding is involved.
    #[inline]
    pub fn of_difference(a: f64, b: f64) -> Sign {
        Sign::of_ordering(a.partial_cmp(&b))
    }

    #[inline]
    fn of_ordering(o: Option<std::cmp::Ordering>) -> Sign {
        match o {
            Some(std::cmp::Ordering::Greater) => Sign::Positive,
            Some(std::cmp::Ordering::Less) => Sign::Negative,
            _ => Sign::Zero,
        }
    }

    /// The opposite sign (`Zero` stays `Zero`).
    #[inline]
    pub fn flip(self) -> Sign {
        match self {
            Sign::Negative => Sign::Positive,
            Sign::Zero => Sign::Zero,
            Sign::Positive => Sign::Negative,
        }
    }

    /// −1, 0 or +1.
    #[inline]
    pub fn as_i32(self) -> i32 {
        match self {
            Sign::Negative => -1,
            Sign::Zero => 0,
            Sign::Positive => 1,
        }
    }

    /// True for [`Sign::Zero`].
    #[inline]
    pub fn is_zero(self) -> bool {
        self == Sign::Zero
    }

    /// `self` unless it is `Zero`, in which case `tie_break()` decides: the shape of every
    /// Simulation-of-Simplicity evaluation (the exact term first, perturbation terms only
    /// on a tie). The closure keeps the tie-breaking terms unevaluated on the fast path.
    #[inline]
    pub fn or_else(self, tie_break: impl FnOnce() -> Sign) -> Sign {
        if self == Sign::Zero {
            tie_break()
        } else {
            self
        }
    }
}

impl Neg for Sign {
    type Output = Sign;
    #[inline]
    fn neg(self) -> Sign {
        self.flip()
    }
}

impl Mul for Sign {
    type Output = Sign;
    /// The sign of a product.
    #[inline]
    fn mul(self, rhs: Sign) -> Sign {
        match self.as_i32() * rhs.as_i32() {
            1 => Sign::Positive,
            -1 => Sign::Negative,
            _ => Sign::Zero,
        }
    }
}

/// A coordinate axis.
///
/// Projections along an axis keep the two *other* coordinates in cyclic order
/// (X → (y, z), Y → (z, x), Z → (x, y)). With that order, the orientation of a projected
/// triangle is the sign of the `axis` component of its right-hand normal, for every
/// axis alike (no per-axis sign fix-ups).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Axis {
    /// The x axis (index 0).
    X,
    /// The y axis (index 1).
    Y,
    /// The z axis (index 2).
    Z,
}

impl Axis {
    /// The three axes in index order.
    pub const ALL: [Axis; 3] = [Axis::X, Axis::Y, Axis::Z];

    /// 0, 1 or 2: the coordinate this axis selects in a `DVec3`.
    #[inline]
    pub fn index(self) -> usize {
        match self {
            Axis::X => 0,
            Axis::Y => 1,
            Axis::Z => 2,
        }
    }

    /// The axis of a coordinate index, taken modulo 3.
    #[inline]
    pub fn from_index(i: usize) -> Axis {
        Axis::ALL[i % 3]
    }

    /// The indices of the two other coordinates, in cyclic order: X → (1, 2), Y → (2, 0),
    /// Z → (0, 1).
    #[inline]
    pub fn others(self) -> (usize, usize) {
        match self {
            Axis::X => (1, 2),
            Axis::Y => (2, 0),
            Axis::Z => (0, 1),
        }
    }

    /// `p` projected along this axis: its two other coordinates, in the order of
    /// [`Axis::others`].
    #[inline]
    pub fn project(self, p: DVec3) -> DVec2 {
        let (i, j) = self.others();
        DVec2::new(p[i], p[j])
    }

    /// The axis of the largest |component| of `v` (X on ties and for NaN): the best
    /// conditioned projection of a plane with normal `v`.
    #[inline]
    pub fn dominant(v: DVec3) -> Axis {
        let a = v.abs();
        if a.x >= a.y && a.x >= a.z {
            Axis::X
        } else if a.y >= a.z {
            Axis::Y
        } else {
            Axis::Z
        }
    }
}

#[inline]
fn coord2(p: DVec2) -> Coord<f64> {
    Coord { x: p.x, y: p.y }
}

#[inline]
fn coord3(p: DVec3) -> Coord3D<f64> {
    Coord3D {
        x: p.x,
        y: p.y,
        z: p.z,
    }
}

/// Exact orientation of three points in the plane: `Positive` when `a, b, c` turn
/// counter-clockwise, `Negative` when clockwise, `Zero` when collinear.
#[inline]
pub fn orient2d(a: DVec2, b: DVec2, c: DVec2) -> Sign {
    Sign::of(robust::orient2d(coord2(a), coord2(b), coord2(c)))
}

/// Exact side of `d` relative to the plane through `a, b, c`: the sign of
/// `((b − a) × (c − a)) · (d − a)`. `Positive` when `d` lies on the side the right-hand
/// normal of triangle `a, b, c` points into (the triangle's *front*), `Zero` when the four
/// points are coplanar (or `a, b, c` are collinear).
///
/// This is the opposite of Shewchuk's / `robust`'s convention ("positive when `d` is
/// below"); the negation happens here, once.
#[inline]
pub fn orient3d(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> Sign {
    Sign::of(robust::orient3d(coord3(a), coord3(b), coord3(c), coord3(d))).flip()
}

/// [`orient2d`] of the three points projected along `axis` (see [`Axis::project`]).
/// Equals the exact sign of the `axis` component of the normal `(b − a) × (c − a)`.
#[inline]
pub fn orient2d_axis(axis: Axis, a: DVec3, b: DVec3, c: DVec3) -> Sign {
    orient2d(axis.project(a), axis.project(b), axis.project(c))
}

/// Exactly collinear points: the normal `(b − a) × (c − a)` is exactly zero, i.e.
/// [`orient2d_axis`] is zero along all three axes. A triangle on such points has zero
/// area (validation's layer 3, and the structural check of every remeshing edit).
#[inline]
pub fn collinear(a: DVec3, b: DVec3, c: DVec3) -> bool {
    Axis::ALL
        .iter()
        .all(|&axis| orient2d_axis(axis, a, b, c) == Sign::Zero)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::predicates::exact_ref::{orient2d_ref, orient3d_ref};
    use proptest::prelude::*;

    #[test]
    fn sign_algebra() {
        assert_eq!(Sign::of(2.0), Sign::Positive);
        assert_eq!(Sign::of(-0.0), Sign::Zero);
        assert_eq!(Sign::of(f64::NAN), Sign::Zero);
        assert_eq!(Sign::of_difference(1.0, 2.0), Sign::Negative);
        assert_eq!(-Sign::Positive, Sign::Negative);
        assert_eq!(Sign::Negative * Sign::Negative, Sign::Positive);
        assert_eq!(Sign::Negative * Sign::Zero, Sign::Zero);
        assert_eq!(Sign::Zero.or_else(|| Sign::Negative), Sign::Negative);
        assert_eq!(Sign::Positive.or_else(|| Sign::Negative), Sign::Positive);
        assert_eq!(Sign::Negative.as_i32(), -1);
    }

    #[test]
    fn conventions() {
        let o = DVec3::ZERO;
        // Right-hand normal of (o, x, y) is +z: +z is the front side.
        assert_eq!(orient3d(o, DVec3::X, DVec3::Y, DVec3::Z), Sign::Positive);
        assert_eq!(orient3d(o, DVec3::Y, DVec3::X, DVec3::Z), Sign::Negative);
        assert_eq!(
            orient3d(o, DVec3::X, DVec3::Y, DVec3::X + DVec3::Y),
            Sign::Zero
        );
        assert_eq!(orient2d(DVec2::ZERO, DVec2::X, DVec2::Y), Sign::Positive);
        // A triangle whose normal points along +axis projects counter-clockwise.
        for axis in Axis::ALL {
            let (i, j) = axis.others();
            let mut b = DVec3::ZERO;
            b[i] = 1.0;
            let mut c = DVec3::ZERO;
            c[j] = 1.0;
            let n = b.cross(c);
            assert!(n[axis.index()] > 0.0);
            assert_eq!(orient2d_axis(axis, o, b, c), Sign::Positive);
            assert_eq!(Axis::from_index(axis.index()), axis);
        }
        assert_eq!(Axis::dominant(DVec3::new(1.0, -3.0, 2.0)), Axis::Y);
    }

    fn small() -> impl Strategy<Value = f64> {
        (-3i32..=3).prop_map(f64::from)
    }
    fn half() -> impl Strategy<Value = f64> {
        (-6i32..=6).prop_map(|k| f64::from(k) * 0.5)
    }
    fn any_float() -> impl Strategy<Value = f64> {
        prop_oneof![small(), half(), -1.0e3..1.0e3f64]
    }
    fn v3<S: Strategy<Value = f64>>(s: impl Fn() -> S) -> impl Strategy<Value = DVec3> {
        (s(), s(), s()).prop_map(|(x, y, z)| DVec3::new(x, y, z))
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(1000))]

        #[test]
        fn orient2d_matches_rationals(a in v3(any_float), b in v3(any_float), c in v3(any_float)) {
            for axis in Axis::ALL {
                let (pa, pb, pc) = (axis.project(a), axis.project(b), axis.project(c));
                prop_assert_eq!(orient2d(pa, pb, pc), orient2d_ref(pa, pb, pc));
                prop_assert_eq!(orient2d_axis(axis, a, b, c), orient2d_ref(pa, pb, pc));
            }
        }

        #[test]
        fn orient3d_matches_rationals(
            a in v3(small), b in v3(small), c in v3(half), d in v3(any_float),
        ) {
            prop_assert_eq!(orient3d(a, b, c, d), orient3d_ref(a, b, c, d));
            // Even permutations keep the sign, odd ones flip it.
            prop_assert_eq!(orient3d(b, c, a, d), orient3d(a, b, c, d));
            prop_assert_eq!(orient3d(b, a, c, d), -orient3d(a, b, c, d));
            // The normal's components are the projected orientations.
            let n = (b - a).cross(c - a);
            for axis in Axis::ALL {
                prop_assert_eq!(orient2d_axis(axis, a, b, c), Sign::of(n[axis.index()]));
            }
        }

        /// Points rounded onto a line or plane: the exact answer is decided by the last
        /// bits, where the floating-point filter alone would guess.
        #[test]
        fn nearly_degenerate_match_rationals(
            a in v3(|| -1.0..1.0f64), b in v3(|| -1.0..1.0f64), c in v3(|| -1.0..1.0f64),
            s in -2.0..2.0f64, t in -2.0..2.0f64,
        ) {
            let on_line = a + s * (b - a);
            let (pa, pb, pl) = (Axis::Z.project(a), Axis::Z.project(b), Axis::Z.project(on_line));
            prop_assert_eq!(orient2d(pa, pb, pl), orient2d_ref(pa, pb, pl));
            let on_plane = a + s * (b - a) + t * (c - a);
            prop_assert_eq!(orient3d(a, b, c, on_plane), orient3d_ref(a, b, c, on_plane));
        }
    }
}
