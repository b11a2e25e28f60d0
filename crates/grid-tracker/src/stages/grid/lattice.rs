//! The background lattice: grid plane `i` along axis `a` lies at
//! `origin[a] + i·ℓ`, evaluated in `f64` exactly as [`Lattice::plane`] does it, once and
//! for everyone. Every exact predicate of the later stages receives grid points built by
//! this one function, so "the grid" is a well-defined set of floating-point numbers, not
//! an idealised real lattice that rounding would blur.
//!
//! Cell `i` along an axis is the closed interval `[plane(i), plane(i + 1)]`; node `i` is
//! the point `plane(i)`. Under Simulation of Simplicity (see
//! [`mesh_core::predicates::crossing`]) every grid point `p` stands for
//! `p + (ε, ε², ε³)`, so mesh geometry is never exactly *on* a grid plane.

use glam::{DVec3, IVec3};

/// Origin and spacing of the background lattice.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lattice {
    /// Position of node `(0, 0, 0)`.
    pub origin: DVec3,
    /// Cell edge length ℓ.
    pub cell_size: f64,
}

/// Bound on the loops that correct a rounded floor: the rounded guess is off by at most
/// one or two steps when ℓ is far above the coordinates' rounding unit, which
/// `build_grid` checks (`GridError::TooFine`).
const MAX_CORRECTION: usize = 8;

impl Lattice {
    /// Coordinate of grid plane `i` along `axis` (0, 1, 2): `origin[axis] + i·ℓ`.
    #[inline]
    pub fn plane(&self, axis: usize, i: i32) -> f64 {
        self.origin[axis] + f64::from(i) * self.cell_size
    }

    /// Position of node `n`.
    #[inline]
    pub fn node_position(&self, n: IVec3) -> DVec3 {
        DVec3::new(self.plane(0, n.x), self.plane(1, n.y), self.plane(2, n.z))
    }

    /// Centre of cell `c` (approximate; for geometry, not for decisions).
    #[inline]
    pub fn cell_centre(&self, c: IVec3) -> DVec3 {
        self.node_position(c) + DVec3::splat(0.5 * self.cell_size)
    }

    /// The largest `i` with `plane(axis, i) ≤ x`, exactly, for finite `x` within 2³⁰
    /// cells of the origin (farther out the result saturates near ±2³⁰).
    #[inline]
    pub fn locate(&self, axis: usize, x: f64) -> i32 {
        self.locate_with(axis, x, 1.0 / self.cell_size)
    }

    /// [`Self::locate`] with `inv = 1/ℓ` precomputed: the rounded guess only seeds the
    /// exact correction, so a multiplication is as good as a division.
    #[inline]
    fn locate_with(&self, axis: usize, x: f64, inv: f64) -> i32 {
        // Truncation (saturating, NaN → 0) then a floor fix-up: cheaper than `floor()`.
        let v = (x - self.origin[axis]) * inv;
        // Far beyond any grid (|v| > 2^30) the answer saturates; the clamp also keeps the
        // correction steps below from overflowing.
        let t = (v as i32).clamp(-(1 << 30), 1 << 30);
        let mut i = t - i32::from(f64::from(t) > v);
        for _ in 0..MAX_CORRECTION {
            if self.plane(axis, i) > x {
                i -= 1;
            } else if self.plane(axis, i + 1) <= x {
                i += 1;
            } else {
                break;
            }
        }
        i
    }

    /// The largest `i` with `plane(axis, i) < x`, exactly: the first cell of a box whose
    /// minimum is `x`. A box touching plane `i` from above thereby also claims cell
    /// `i − 1`, which the symbolic perturbation of grid points may need (a crossing at
    /// exactly `plane(i)` can belong to the grid edge below node `i`).
    #[inline]
    pub fn locate_strict(&self, axis: usize, x: f64) -> i32 {
        self.locate_strict_with(axis, x, 1.0 / self.cell_size)
    }

    #[inline]
    fn locate_strict_with(&self, axis: usize, x: f64, inv: f64) -> i32 {
        let i = self.locate_with(axis, x, inv);
        if self.plane(axis, i) == x { i - 1 } else { i }
    }

    /// Cells `[lo, hi]` (inclusive) whose closed boxes meet the closed box `[min, max]`.
    #[inline]
    pub fn cell_range(&self, min: DVec3, max: DVec3) -> [IVec3; 2] {
        let inv = 1.0 / self.cell_size;
        let lo = IVec3::new(
            self.locate_strict_with(0, min.x, inv),
            self.locate_strict_with(1, min.y, inv),
            self.locate_strict_with(2, min.z, inv),
        );
        let hi = IVec3::new(
            self.locate_with(0, max.x, inv),
            self.locate_with(1, max.y, inv),
            self.locate_with(2, max.z, inv),
        );
        [lo, hi]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The floats just below and above a non-zero `x`.
    fn neighbours(x: f64) -> (f64, f64) {
        let (a, b) = (
            f64::from_bits(x.to_bits() - 1),
            f64::from_bits(x.to_bits() + 1),
        );
        if x > 0.0 { (a, b) } else { (b, a) }
    }

    #[test]
    fn locate_is_exact_at_and_between_planes() {
        let l = Lattice {
            origin: DVec3::new(0.1234, -0.3, 7.0),
            cell_size: 0.1,
        };
        for i in -50..50 {
            let p = l.plane(0, i);
            assert_eq!(l.locate(0, p), i, "on plane {i}");
            assert_eq!(l.locate_strict(0, p), i - 1, "strict on plane {i}");
            let mid = 0.5 * (p + l.plane(0, i + 1));
            assert_eq!(l.locate(0, mid), i);
            assert_eq!(l.locate_strict(0, mid), i);
            // The neighbouring floats of a plane fall on the right sides.
            let (below, above) = neighbours(p);
            assert_eq!(l.locate(0, below), i - 1);
            assert_eq!(l.locate(0, above), i);
        }
    }

    #[test]
    fn locate_saturates_far_away_without_overflow() {
        let l = Lattice {
            origin: DVec3::ZERO,
            cell_size: 1e-3,
        };
        assert!(l.locate(0, 1e300) >= 1 << 29);
        assert!(l.locate(1, -1e300) <= -(1 << 29));
        assert_eq!(l.locate(2, f64::NAN), l.locate(2, f64::NAN));
    }

    #[test]
    fn cell_range_covers_closed_boxes() {
        let l = Lattice {
            origin: DVec3::ZERO,
            cell_size: 0.25,
        };
        // A point box exactly on node (1, 2, 3) touches the eight cells around it.
        let p = DVec3::new(0.25, 0.5, 0.75);
        assert_eq!(
            l.cell_range(p, p),
            [IVec3::new(0, 1, 2), IVec3::new(1, 2, 3)]
        );
        // Strictly inside one cell.
        let q = DVec3::new(0.3, 0.3, 0.3);
        assert_eq!(l.cell_range(q, q), [IVec3::ONE, IVec3::ONE]);
    }
}
