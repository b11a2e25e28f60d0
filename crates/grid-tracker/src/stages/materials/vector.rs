//! Material vectors (§5): sparse integer vectors over material labels.
//!
//! A point inside material `i` once and outside every other has the one-hot vector
//! `e_i` (*physical*); overlaps and inversions give entries above 1 or below 0
//! (*non-physical*, called *mixed* here). Entries always sum to 1.
//!
//! Storage: almost every grid node is physical, so a node stores a 4-byte
//! [`MaterialRef`]: the label itself, or (top bit set) an index into a [`MixedPool`] of
//! `(label, count)` runs. [`MaterialVector`] is the owned, growable form used while
//! sweeping a ray; [`MaterialView`] the borrowed form read back from storage.

use mesh_core::Label;

const MIXED_BIT: u32 = 1 << 31;

/// A node's material vector, compactly: a physical label inline, or a mixed vector by
/// index into the pool of its [`super::Materials`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct MaterialRef(u32);

impl MaterialRef {
    /// The one-hot vector of `label`; `None` for labels ≥ 2³¹ (refused by
    /// [`super::assign_materials`]).
    #[inline]
    pub fn physical(label: Label) -> Option<Self> {
        (label.raw() < MIXED_BIT).then_some(Self(label.raw()))
    }

    /// The label of a physical vector, `None` for a mixed one.
    #[inline]
    pub fn label(self) -> Option<Label> {
        (self.0 & MIXED_BIT == 0).then(|| Label::new(self.0))
    }

    /// True for a one-hot vector.
    #[inline]
    pub fn is_physical(self) -> bool {
        self.0 & MIXED_BIT == 0
    }

    #[inline]
    pub(crate) fn mixed(index: u32) -> Self {
        Self(MIXED_BIT | index)
    }

    #[inline]
    pub(crate) fn mixed_index(self) -> Option<usize> {
        (self.0 & MIXED_BIT != 0).then_some((self.0 & !MIXED_BIT) as usize)
    }
}

/// A borrowed material vector.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MaterialView<'a> {
    /// One-hot on this label.
    Physical(Label),
    /// Non-zero `(label, count)` entries sorted by label; never one-hot.
    Mixed(&'a [(Label, i32)]),
}

impl MaterialView<'_> {
    /// The entry of `label`.
    pub fn get(&self, label: Label) -> i32 {
        match *self {
            MaterialView::Physical(l) => i32::from(l == label),
            MaterialView::Mixed(e) => e
                .binary_search_by_key(&label, |p| p.0)
                .map_or(0, |i| e[i].1),
        }
    }

    /// The label of a physical vector.
    pub fn physical_label(&self) -> Option<Label> {
        match *self {
            MaterialView::Physical(l) => Some(l),
            MaterialView::Mixed(_) => None,
        }
    }

    /// Owned copy.
    pub fn to_vector(&self) -> MaterialVector {
        let mut v = MaterialVector::default();
        v.set_from(*self);
        v
    }

    /// Whether this is the same vector as `v`.
    pub fn same_as(&self, v: &MaterialVector) -> bool {
        match *self {
            MaterialView::Physical(l) => v.entries == [(l, 1)],
            MaterialView::Mixed(e) => v.entries == e,
        }
    }
}

/// An owned material vector: non-zero `(label, count)` entries sorted by label. Reused
/// across a ray so that sweeping allocates nothing per crossing.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct MaterialVector {
    entries: Vec<(Label, i32)>,
}

impl MaterialVector {
    /// `e_label`.
    pub fn one_hot(label: Label) -> Self {
        Self {
            entries: vec![(label, 1)],
        }
    }

    /// Resets to `e_label`, keeping the buffer.
    pub fn set_one_hot(&mut self, label: Label) {
        self.entries.clear();
        self.entries.push((label, 1));
    }

    /// Copies `view` into this buffer.
    pub fn set_from(&mut self, view: MaterialView<'_>) {
        self.entries.clear();
        match view {
            MaterialView::Physical(l) => self.entries.push((l, 1)),
            MaterialView::Mixed(e) => self.entries.extend_from_slice(e),
        }
    }

    /// Non-zero entries, sorted by label.
    pub fn entries(&self) -> &[(Label, i32)] {
        &self.entries
    }

    /// The entry of `label`.
    pub fn get(&self, label: Label) -> i32 {
        self.view().get(label)
    }

    /// Adds `delta` to the entry of `label`, dropping it if it becomes zero.
    pub fn add(&mut self, label: Label, delta: i32) {
        match self.entries.binary_search_by_key(&label, |p| p.0) {
            Ok(i) => {
                self.entries[i].1 += delta;
                if self.entries[i].1 == 0 {
                    self.entries.remove(i);
                }
            }
            Err(i) if delta != 0 => self.entries.insert(i, (label, delta)),
            Err(_) => {}
        }
    }

    /// The update of Fig. 6 for a ray crossing a triangle labelled `[front, back]`:
    /// leaving the material on one side (−1) and entering the other (+1). `direction`
    /// +1 means travelling from the back side to the front side.
    pub fn cross(&mut self, direction: i8, [front, back]: [Label; 2]) {
        let (leave, enter) = if direction > 0 {
            (back, front)
        } else {
            (front, back)
        };
        self.add(leave, -1);
        self.add(enter, 1);
    }

    /// The label if one-hot.
    pub fn physical_label(&self) -> Option<Label> {
        match self.entries.as_slice() {
            [(l, 1)] => Some(*l),
            _ => None,
        }
    }

    /// Borrowed view.
    pub fn view(&self) -> MaterialView<'_> {
        match self.physical_label() {
            Some(l) => MaterialView::Physical(l),
            None => MaterialView::Mixed(&self.entries),
        }
    }
}

/// Mixed vectors, stored back to back.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MixedPool {
    entries: Vec<(Label, i32)>,
    start: Vec<u32>,
}

impl Default for MixedPool {
    fn default() -> Self {
        Self {
            entries: Vec::new(),
            start: vec![0],
        }
    }
}

impl MixedPool {
    /// Number of vectors stored.
    pub fn len(&self) -> usize {
        self.start.len() - 1
    }

    /// True when empty.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Entries of vector `i`.
    pub fn get(&self, i: usize) -> &[(Label, i32)] {
        &self.entries[self.start[i] as usize..self.start[i + 1] as usize]
    }

    /// Appends a vector; returns its index, or `None` when the pool is full (2³¹
    /// vectors or 2³² entries).
    pub fn push(&mut self, e: &[(Label, i32)]) -> Option<u32> {
        let i = u32::try_from(self.len()).ok().filter(|&i| i < MIXED_BIT)?;
        let end = u32::try_from(self.entries.len() + e.len()).ok()?;
        self.entries.extend_from_slice(e);
        self.start.push(end);
        Some(i)
    }

    /// Appends all of `other`; returns the index offset of its vectors here.
    pub fn append(&mut self, other: &MixedPool) -> Option<u32> {
        let offset = u32::try_from(self.len()).ok()?;
        for i in 0..other.len() {
            self.push(other.get(i))?;
        }
        Some(offset)
    }

    /// Heap bytes.
    pub fn heap_bytes(&self) -> usize {
        self.entries.capacity() * std::mem::size_of::<(Label, i32)>() + self.start.capacity() * 4
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn l(i: u32) -> Label {
        Label::new(i)
    }

    #[test]
    fn crossing_updates_follow_fig_6() {
        // Entering a sphere labelled [front = 0 outside, back = 1 inside] against its
        // outward normal: direction −1, leave 0, enter 1.
        let mut v = MaterialVector::one_hot(l(0));
        v.cross(-1, [l(0), l(1)]);
        assert_eq!(v.physical_label(), Some(l(1)));
        // Entering a second, overlapping sphere of label 2.
        v.cross(-1, [l(0), l(2)]);
        assert_eq!(v.entries(), &[(l(0), -1), (l(1), 1), (l(2), 1)]);
        assert_eq!(v.physical_label(), None);
        assert_eq!(v.entries().iter().map(|e| e.1).sum::<i32>(), 1);
        // Leaving both again restores the outside.
        v.cross(1, [l(0), l(2)]);
        v.cross(1, [l(0), l(1)]);
        assert_eq!(v, MaterialVector::one_hot(l(0)));
    }

    #[test]
    fn refs_and_views_round_trip() {
        let r = MaterialRef::physical(l(7)).unwrap();
        assert_eq!(r.label(), Some(l(7)));
        assert!(r.is_physical());
        assert_eq!(MaterialRef::physical(Label::new(1 << 31)), None);
        let m = MaterialRef::mixed(5);
        assert!(!m.is_physical());
        assert_eq!(m.mixed_index(), Some(5));
        assert_eq!(m.label(), None);

        let mut pool = MixedPool::default();
        let e = [(l(0), -1), (l(3), 2)];
        assert_eq!(pool.push(&e), Some(0));
        assert_eq!(pool.push(&[(l(1), 2), (l(2), -1)]), Some(1));
        let view = MaterialView::Mixed(pool.get(0));
        assert_eq!(view.get(l(3)), 2);
        assert_eq!(view.get(l(9)), 0);
        assert!(view.same_as(&view.to_vector()));
        assert!(MaterialView::Physical(l(2)).same_as(&MaterialVector::one_hot(l(2))));
        let mut other = MixedPool::default();
        other.push(&e);
        assert_eq!(other.append(&pool), Some(1));
        assert_eq!(other.get(2), pool.get(1));
    }
}
