//! Typed element ids.
//!
//! Every id is a `u32` index behind a newtype, so a `VertexId` can never be passed where a
//! `TriId` is expected. The index is stored bit-inverted in a `NonZeroU32`: that gives
//! `Option<Id>` the same size as the id (the niche is index `u32::MAX`, which no mesh may
//! use) without a sentinel value leaking into the API.

use std::fmt;
use std::marker::PhantomData;
use std::num::NonZeroU32;
use std::ops::{Index, IndexMut};

/// Largest index any id may hold; meshes refuse to grow beyond it.
pub const MAX_INDEX: u32 = u32::MAX - 1;

/// Common behaviour of the typed ids, so generic containers ([`IdVec`]) can use them.
pub trait Id: Copy + Eq + Ord + std::hash::Hash + fmt::Debug {
    /// The id with this index. Panics only if `index == u32::MAX` (see [`MAX_INDEX`]).
    fn new(index: u32) -> Self;
    /// The index as `u32`.
    fn raw(self) -> u32;
    /// The index as `usize`, for slicing.
    #[inline]
    fn idx(self) -> usize {
        self.raw() as usize
    }
}

macro_rules! define_id {
    ($(#[$meta:meta])* $name:ident, $prefix:literal) => {
        $(#[$meta])*
        #[derive(Clone, Copy, PartialEq, Eq, Hash)]
        #[repr(transparent)]
        pub struct $name(NonZeroU32);

        impl $name {
            /// The id with this index.
            ///
            /// # Panics
            /// If `index == u32::MAX`; meshes cap their size at [`MAX_INDEX`] so this cannot
            /// happen for ids a mesh hands out.
            #[inline]
            pub const fn new(index: u32) -> Self {
                match NonZeroU32::new(!index) {
                    Some(bits) => Self(bits),
                    None => panic!("id index u32::MAX is reserved"),
                }
            }

            /// The index as `u32`.
            #[inline]
            pub const fn raw(self) -> u32 {
                !self.0.get()
            }

            /// The index as `usize`.
            #[inline]
            pub const fn idx(self) -> usize {
                self.raw() as usize
            }

            /// The id with this `usize` index, if it fits.
            #[inline]
            pub fn from_usize(index: usize) -> Option<Self> {
                u32::try_from(index).ok().filter(|&i| i <= MAX_INDEX).map(Self::new)
            }
        }

        impl Id for $name {
            #[inline]
            fn new(index: u32) -> Self {
                $name::new(index)
            }
            #[inline]
            fn raw(self) -> u32 {
                $name::raw(self)
            }
        }

        impl PartialOrd for $name {
            #[inline]
            fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
                Some(self.cmp(other))
            }
        }

        impl Ord for $name {
            #[inline]
            fn cmp(&self, other: &Self) -> std::cmp::Ordering {
                self.raw().cmp(&other.raw())
            }
        }

        impl fmt::Debug for $name {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                write!(f, concat!($prefix, "{}"), self.raw())
            }
        }

        impl fmt::Display for $name {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                write!(f, concat!($prefix, "{}"), self.raw())
            }
        }

        impl serde::Serialize for $name {
            fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                s.serialize_u32(self.raw())
            }
        }
    };
}

define_id!(
    /// A vertex of a [`crate::LabeledMesh`].
    VertexId, "v"
);
define_id!(
    /// A triangle of a [`crate::LabeledMesh`].
    TriId, "t"
);
define_id!(
    /// One of the six corners of a triangle: `6·tri + 3·side + slot` (see [`crate::corner`]).
    CornerId, "c"
);
define_id!(
    /// A material label. Label 0 is, by convention, the outside (ambient) material.
    Label, "L"
);

impl Label {
    /// The conventional outside material.
    pub const OUTSIDE: Label = Label::new(0);
}

/// A `Vec<T>` indexed by a typed id: per-element data that cannot be indexed by the
/// wrong kind of id.
#[derive(Clone, PartialEq)]
pub struct IdVec<I, T> {
    data: Vec<T>,
    _id: PhantomData<fn(I) -> I>,
}

impl<I: Id, T> IdVec<I, T> {
    /// An empty container.
    pub fn new() -> Self {
        Self::from_vec(Vec::new())
    }

    /// Wraps a plain vector; element `i` belongs to id `i`.
    pub fn from_vec(data: Vec<T>) -> Self {
        Self {
            data,
            _id: PhantomData,
        }
    }

    /// Number of slots (live and dead).
    #[inline]
    pub fn len(&self) -> usize {
        self.data.len()
    }

    /// True when there are no slots.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.data.is_empty()
    }

    /// Appends a slot and returns its id.
    #[inline]
    pub fn push(&mut self, value: T) -> I {
        let id = I::new(self.data.len() as u32);
        self.data.push(value);
        id
    }

    /// The element of `id`, if in range.
    #[inline]
    pub fn get(&self, id: I) -> Option<&T> {
        self.data.get(id.idx())
    }

    /// The underlying slice (index = id).
    #[inline]
    pub fn as_slice(&self) -> &[T] {
        &self.data
    }

    /// The underlying mutable slice (index = id).
    #[inline]
    pub fn as_mut_slice(&mut self) -> &mut [T] {
        &mut self.data
    }

    /// Ids and elements.
    pub fn iter_enumerated(&self) -> impl Iterator<Item = (I, &T)> + '_ {
        self.data
            .iter()
            .enumerate()
            .map(|(i, v)| (I::new(i as u32), v))
    }

    /// Consumes the container into its vector.
    pub fn into_vec(self) -> Vec<T> {
        self.data
    }

    /// Resizes to `len` slots, filling with `value`.
    pub fn resize(&mut self, len: usize, value: T)
    where
        T: Clone,
    {
        self.data.resize(len, value);
    }
}

impl<I: Id, T> Default for IdVec<I, T> {
    fn default() -> Self {
        Self::new()
    }
}

impl<I: Id, T: fmt::Debug> fmt::Debug for IdVec<I, T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_list().entries(self.data.iter()).finish()
    }
}

impl<I: Id, T> Index<I> for IdVec<I, T> {
    type Output = T;
    #[inline]
    fn index(&self, id: I) -> &T {
        &self.data[id.idx()]
    }
}

impl<I: Id, T> IndexMut<I> for IdVec<I, T> {
    #[inline]
    fn index_mut(&mut self, id: I) -> &mut T {
        &mut self.data[id.idx()]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn option_of_id_is_niche_optimised() {
        assert_eq!(std::mem::size_of::<Option<VertexId>>(), 4);
        assert_eq!(std::mem::size_of::<Option<CornerId>>(), 4);
    }

    #[test]
    fn ids_round_trip_and_order_by_index() {
        for i in [0, 1, 7, 1 << 20, MAX_INDEX] {
            assert_eq!(TriId::new(i).raw(), i);
        }
        assert!(VertexId::new(3) < VertexId::new(4));
        assert!(VertexId::new(0) < VertexId::new(MAX_INDEX));
        assert_eq!(VertexId::from_usize(u32::MAX as usize), None);
        assert_eq!(format!("{:?}", Label::new(5)), "L5");
    }

    #[test]
    fn id_vec_indexes_by_id() {
        let mut v: IdVec<VertexId, f64> = IdVec::new();
        let a = v.push(1.0);
        let b = v.push(2.0);
        v[a] += 10.0;
        assert_eq!(v[a], 11.0);
        assert_eq!(v[b], 2.0);
        assert_eq!(v.len(), 2);
    }
}
