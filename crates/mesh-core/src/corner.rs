//! Corner arithmetic of the two-sided corner table (Heiss-Synak et al. 2024, §4, Fig. 4).
//!
//! Glossary:
//! - **side**: each triangle has two sides. Side 0 (*front*) faces the material its
//!   right-hand normal `(v1-v0)×(v2-v0)` points into (`labels[t][0]`); side 1 (*back*)
//!   faces the other one (`labels[t][1]`).
//! - **corner**: a side has three corners, one per vertex. Corner id = `6·t + 3·side + slot`,
//!   where `slot` is the index of the corner's vertex in the triangle's `[v0, v1, v2]`.
//! - **next / prev**: the corners of the same side, in the order that traverses the side
//!   with its normal pointing into the region it faces (front: slot+1, back: slot−1).
//! - **dual**: the same vertex on the other side of the same triangle.
//! - **opposite**: stored in the mesh (it is the only non-arithmetic pointer): the corner,
//!   across the edge opposite this corner, of the neighbouring triangle side that faces the
//!   *same region* — the radial neighbour around a non-manifold edge.
//!
//! Everything here is arithmetic on ids: next, prev, dual, triangle, side and slot cost a
//! few instructions and no memory.

use crate::ids::{CornerId, TriId};

/// Which side of a triangle a corner lies on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
pub enum Side {
    /// Faces the material the right-hand normal points into (`labels[t][0]`).
    Front = 0,
    /// Faces the material behind the triangle (`labels[t][1]`).
    Back = 1,
}

impl Side {
    /// The other side.
    #[inline]
    pub fn flip(self) -> Side {
        match self {
            Side::Front => Side::Back,
            Side::Back => Side::Front,
        }
    }

    /// 0 for front, 1 for back: the index into a triangle's label pair.
    #[inline]
    pub fn index(self) -> usize {
        self as usize
    }
}

impl CornerId {
    /// The corner of triangle `t`, side `side`, at the vertex in position `slot` (0..3).
    #[inline]
    pub fn of(t: TriId, side: Side, slot: usize) -> CornerId {
        debug_assert!(slot < 3);
        CornerId::new(t.raw() * 6 + side as u32 * 3 + slot as u32)
    }

    /// The triangle this corner belongs to.
    #[inline]
    pub fn tri(self) -> TriId {
        TriId::new(self.raw() / 6)
    }

    /// The side of the triangle this corner lies on.
    #[inline]
    pub fn side(self) -> Side {
        if self.raw() % 6 < 3 {
            Side::Front
        } else {
            Side::Back
        }
    }

    /// Position (0..3) of this corner's vertex in the triangle's vertex triple.
    #[inline]
    pub fn slot(self) -> usize {
        (self.raw() % 3) as usize
    }

    /// Next corner on the same side (front: slot+1; back: slot−1).
    #[inline]
    pub fn next(self) -> CornerId {
        let base = self.raw() - self.raw() % 3;
        let step = if self.side() == Side::Front { 1 } else { 2 };
        CornerId::new(base + (self.raw() % 3 + step) % 3)
    }

    /// Previous corner on the same side.
    #[inline]
    pub fn prev(self) -> CornerId {
        let base = self.raw() - self.raw() % 3;
        let step = if self.side() == Side::Front { 2 } else { 1 };
        CornerId::new(base + (self.raw() % 3 + step) % 3)
    }

    /// The corner at the same vertex on the other side of the triangle.
    #[inline]
    pub fn dual(self) -> CornerId {
        let r = self.raw();
        if r % 6 < 3 {
            CornerId::new(r + 3)
        } else {
            CornerId::new(r - 3)
        }
    }

    /// Index of this corner's side among all sides (`2·t + side`), for per-side arrays.
    #[inline]
    pub fn side_index(self) -> usize {
        (self.raw() / 3) as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn corner_arithmetic_is_consistent() {
        for t in [0u32, 1, 17] {
            let t = TriId::new(t);
            for side in [Side::Front, Side::Back] {
                for slot in 0..3 {
                    let c = CornerId::of(t, side, slot);
                    assert_eq!(c.tri(), t);
                    assert_eq!(c.side(), side);
                    assert_eq!(c.slot(), slot);
                    assert_eq!(c.next().prev(), c);
                    assert_eq!(c.next().next().next(), c);
                    assert_eq!(c.dual().dual(), c);
                    assert_eq!(c.dual().slot(), slot);
                    assert_eq!(c.dual().side(), side.flip());
                    assert_eq!(c.next().tri(), t);
                    assert_eq!(c.next().side(), side);
                }
            }
        }
    }

    #[test]
    fn back_side_runs_the_other_way() {
        let t = TriId::new(2);
        let f = CornerId::of(t, Side::Front, 0);
        let b = CornerId::of(t, Side::Back, 0);
        assert_eq!(f.next().slot(), 1);
        assert_eq!(b.next().slot(), 2);
        assert_eq!(f.side_index(), 4);
        assert_eq!(b.side_index(), 5);
    }
}
