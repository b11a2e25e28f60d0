//! Block-sparse storage: the lattice is cut into tiles of 8×8×8 cells (or nodes), and
//! only tiles that hold something exist, in a hash map keyed by tile coordinate.
//!
//! Inside a tile an element has a *local index* `x + 8·y + 64·z` (x fastest), so a tile's
//! occupancy is a 512-bit mask stored as eight `u64` words, one per z-slice. A dense id
//! for an occupied element is its tile's base plus the number of occupied elements before
//! it in the tile (a rank: a few popcounts), so per-element arrays hold only occupied
//! elements while a lookup stays O(1).
//!
//! Why 8³: a surface band occupies about a quarter of the cells of the tiles it passes
//! through at this size, the masks fit one cache line, and a z-slice is one machine word.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

use glam::IVec3;

/// log2 of the tile edge, in cells.
pub const TILE_LOG2: i32 = 3;
/// Tile edge, in cells.
pub const TILE: i32 = 1 << TILE_LOG2;
/// Elements per tile.
pub const TILE_VOLUME: usize = (TILE * TILE * TILE) as usize;

/// Occupancy of one tile: bit `x + 8·y` of word `z`.
pub type TileMask = [u64; TILE as usize];

/// The tile holding lattice point `c` and its local index there. Arithmetic shifts floor
/// negative coordinates correctly.
#[inline]
pub fn split(c: IVec3) -> (IVec3, usize) {
    let tile = IVec3::new(c.x >> TILE_LOG2, c.y >> TILE_LOG2, c.z >> TILE_LOG2);
    let m = TILE - 1;
    let local = (c.x & m) | ((c.y & m) << TILE_LOG2) | ((c.z & m) << (2 * TILE_LOG2));
    (tile, local as usize)
}

/// Inverse of [`split`].
#[inline]
pub fn join(tile: IVec3, local: usize) -> IVec3 {
    let m = (TILE - 1) as usize;
    let l = IVec3::new(
        (local & m) as i32,
        ((local >> TILE_LOG2) & m) as i32,
        (local >> (2 * TILE_LOG2)) as i32,
    );
    (tile << TILE_LOG2) + l
}

/// Whether bit `local` is set.
#[inline]
pub fn mask_get(mask: &TileMask, local: usize) -> bool {
    mask[local >> 6] >> (local & 63) & 1 == 1
}

/// Sets bit `local`; returns whether it was clear before.
#[inline]
pub fn mask_set(mask: &mut TileMask, local: usize) -> bool {
    let (w, b) = (local >> 6, local & 63);
    let was = mask[w] >> b & 1 == 1;
    mask[w] |= 1 << b;
    !was
}

/// Number of set bits strictly before `local` (the rank of `local` in the tile).
#[inline]
pub fn mask_rank(mask: &TileMask, prefix: &[u16; TILE as usize], local: usize) -> u32 {
    let (w, b) = (local >> 6, local & 63);
    u32::from(prefix[w]) + (mask[w] & ((1u64 << b) - 1)).count_ones()
}

/// Per-word exclusive prefix counts of a mask, for [`mask_rank`].
pub fn mask_prefix(mask: &TileMask) -> [u16; TILE as usize] {
    let mut out = [0u16; TILE as usize];
    let mut acc = 0u16;
    for (o, w) in out.iter_mut().zip(mask) {
        *o = acc;
        acc += w.count_ones() as u16;
    }
    out
}

/// Total set bits of a mask.
#[inline]
pub fn mask_count(mask: &TileMask) -> u32 {
    mask.iter().map(|w| w.count_ones()).sum()
}

/// Set bits of a mask in increasing local order.
pub fn mask_iter(mask: &TileMask) -> impl Iterator<Item = usize> + '_ {
    mask.iter().enumerate().flat_map(|(w, &bits)| {
        let mut rest = bits;
        std::iter::from_fn(move || {
            (rest != 0).then(|| {
                let b = rest.trailing_zeros() as usize;
                rest &= rest - 1;
                w * 64 + b
            })
        })
    })
}

/// Bits with x = 0 in a z-slice word.
const COL0: u64 = 0x0101_0101_0101_0101;

/// Moves every bit from (x, y) to (x + 1, y) within a slice (x = 7 drops out).
#[inline]
fn shift_x(m: u64) -> u64 {
    (m << 1) & !COL0
}

/// Moves every bit from (x, y) to (x, y + 1) within a slice (y = 7 drops out).
#[inline]
fn shift_y(m: u64) -> u64 {
    m << 8
}

/// Bits with x = 7 in a z-slice word.
const COL7: u64 = COL0 << 7;

/// The cells of a tile face-adjacent to a cell of `m`, and `m` itself (within the tile).
pub fn dilate(m: &TileMask) -> TileMask {
    let mut out = [0u64; TILE as usize];
    for (z, o) in out.iter_mut().enumerate() {
        let w = m[z];
        *o = w | shift_x(w) | ((w >> 1) & !COL7) | shift_y(w) | (w >> 8);
        if z > 0 {
            *o |= m[z - 1];
        }
        if z + 1 < TILE as usize {
            *o |= m[z + 1];
        }
    }
    out
}

/// The cells with local coordinates in `[lo, hi]` (inclusive, per axis, clamped to the
/// tile); empty when the range is empty on some axis.
pub fn box_mask(lo: IVec3, hi: IVec3) -> TileMask {
    let (lo, hi) = (lo.max(IVec3::ZERO), hi.min(IVec3::splat(TILE - 1)));
    let mut out = [0u64; TILE as usize];
    if lo.cmpgt(hi).any() {
        return out;
    }
    let row = (0xffu64 >> (TILE - 1 - (hi.x - lo.x))) << lo.x;
    let slice = (lo.y..=hi.y).fold(0u64, |acc, y| acc | row << (8 * y));
    for w in &mut out[lo.z as usize..=hi.z as usize] {
        *w = slice;
    }
    out
}

/// The cells of the neighbouring tile in direction `(axis, positive)` that share a face
/// with a cell of `m`: `m`'s cells on that side of the tile, moved across.
pub fn across_face(m: &TileMask, axis: usize, positive: bool) -> TileMask {
    let mut out = [0u64; TILE as usize];
    let last = TILE as usize - 1;
    match (axis, positive) {
        (0, true) => out = m.map(|w| (w & COL7) >> 7),
        (0, false) => out = m.map(|w| (w & COL0) << 7),
        (1, true) => out = m.map(|w| w >> 56),
        (1, false) => out = m.map(|w| w << 56),
        (_, true) => out[0] = m[last],
        (_, false) => out[last] = m[0],
    }
    out
}

/// The node mask of a tile: node `(x, y, z)` is set when one of the eight cells
/// `(x − {0,1}, y − {0,1}, z − {0,1})` is set — the corners of the occupied cells.
/// `cells(o)` gives the cell mask of the tile at offset `o ∈ {−1, 0}³` from this one
/// (cells at local −1 live in those neighbours), `None` where there is no tile.
pub fn corner_nodes<'a>(cells: impl Fn(IVec3) -> Option<&'a TileMask>) -> TileMask {
    let zero = [0u64; TILE as usize];
    let get = |x: i32, y: i32, z: i32| *cells(IVec3::new(x, y, z)).unwrap_or(&zero);
    // [oz][oy][ox] with offsets 0 or −1 stored at index 0 or 1.
    let t = [0, -1].map(|oz| [0, -1].map(|oy| [0, -1].map(|ox| get(ox, oy, oz))));
    let mut out = [0u64; TILE as usize];
    for (z, o) in out.iter_mut().enumerate() {
        for dz in 0..2 {
            // Source slice: z − dz, in this tile or (for −1) slice 7 of the −z tile.
            let (oz, zs) = if z >= dz {
                (0, z - dz)
            } else {
                (1, TILE as usize - 1)
            };
            let a = t[oz][0][0][zs];
            let bx = (t[oz][0][1][zs] >> 7) & COL0; // x = 7 of the −x tile, moved to x = 0
            let by = t[oz][1][0][zs] >> 56; // y = 7 of the −y tile, moved to y = 0
            let bxy = t[oz][1][1][zs] >> 63; // (7, 7) of the −x−y tile, moved to (0, 0)
            let p = a
                | shift_x(a)
                | shift_y(a)
                | shift_y(shift_x(a))
                | bx
                | shift_y(bx)
                | by
                | shift_x(by)
                | bxy;
            *o |= p;
        }
    }
    out
}

/// A fast hasher for small integer keys (tile coordinates): multiply-xor accumulation and
/// a murmur3 finaliser, so that the high bits hashbrown uses are well mixed. Not
/// DoS-resistant, which is irrelevant for geometry keys.
#[derive(Clone, Copy, Default)]
pub struct TileHasher(u64);

impl Hasher for TileHasher {
    #[inline]
    fn finish(&self) -> u64 {
        let mut h = self.0;
        h ^= h >> 33;
        h = h.wrapping_mul(0xff51_afd7_ed55_8ccd);
        h ^= h >> 33;
        h = h.wrapping_mul(0xc4ce_b9fe_1a85_ec53);
        h ^ (h >> 33)
    }

    #[inline]
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }

    #[inline]
    fn write_u32(&mut self, i: u32) {
        self.write_u64(u64::from(i));
    }

    #[inline]
    fn write_i32(&mut self, i: i32) {
        self.write_u64(u64::from(i as u32));
    }

    #[inline]
    fn write_u64(&mut self, i: u64) {
        self.0 = (self.0.rotate_left(21) ^ i).wrapping_mul(0x9e37_79b9_7f4a_7c15);
    }
}

/// Hash map from tile (or lattice) coordinates.
pub type TileMap<V> = HashMap<IVec3, V, BuildHasherDefault<TileHasher>>;

/// A set of lattice cells of unbounded extent, stored as one 512-bit mask per touched
/// tile: 1 bit per cell plus ~100 bytes per tile, so even a flood through a large empty
/// volume stays small.
#[derive(Clone, Debug, Default)]
pub struct CellSet {
    tiles: TileMap<TileMask>,
    len: usize,
}

impl CellSet {
    /// An empty set.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds `c`; returns whether it was new.
    pub fn insert(&mut self, c: IVec3) -> bool {
        let (t, l) = split(c);
        let new = mask_set(self.tiles.entry(t).or_insert([0; TILE as usize]), l);
        self.len += usize::from(new);
        new
    }

    /// Adds the cells of `mask` to tile `tile`; returns how many were new.
    pub fn insert_mask(&mut self, tile: IVec3, mask: &TileMask) -> usize {
        let m = self.tiles.entry(tile).or_insert([0; TILE as usize]);
        let mut new = 0;
        for (w, add) in m.iter_mut().zip(mask) {
            new += (add & !*w).count_ones() as usize;
            *w |= add;
        }
        self.len += new;
        new
    }

    /// The cells of tile `tile` in the set (none when the tile was never touched).
    pub fn tile(&self, tile: IVec3) -> TileMask {
        self.tiles.get(&tile).copied().unwrap_or([0; TILE as usize])
    }

    /// Whether `c` is in the set.
    pub fn contains(&self, c: IVec3) -> bool {
        let (t, l) = split(c);
        self.tiles.get(&t).is_some_and(|m| mask_get(m, l))
    }

    /// Number of cells in the set.
    pub fn len(&self) -> usize {
        self.len
    }

    /// True when the set is empty.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Every cell, in no particular order.
    pub fn iter(&self) -> impl Iterator<Item = IVec3> + '_ {
        self.tiles
            .iter()
            .flat_map(|(&t, m)| mask_iter(m).map(move |l| join(t, l)))
    }

    /// Approximate heap bytes held.
    pub fn heap_bytes(&self) -> usize {
        self.tiles.capacity() * (std::mem::size_of::<(IVec3, TileMask)>() + 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn split_join_round_trip_including_negatives() {
        for c in [
            IVec3::new(0, 0, 0),
            IVec3::new(-1, 7, 8),
            IVec3::new(-9, -8, 15),
            IVec3::new(1000, -1000, 3),
        ] {
            let (t, l) = split(c);
            assert!(l < TILE_VOLUME);
            assert_eq!(join(t, l), c);
        }
        assert_eq!(split(IVec3::new(-1, 0, 0)).0, IVec3::new(-1, 0, 0));
        assert_eq!(split(IVec3::new(-1, 0, 0)).1, 7);
    }

    #[test]
    fn rank_counts_earlier_bits() {
        let mut m = [0u64; 8];
        let set = [3usize, 64, 65, 200, 511];
        for &l in &set {
            assert!(mask_set(&mut m, l));
        }
        assert!(!mask_set(&mut m, 64));
        let p = mask_prefix(&m);
        for (rank, &l) in set.iter().enumerate() {
            assert_eq!(mask_rank(&m, &p, l) as usize, rank);
        }
        assert_eq!(mask_iter(&m).collect::<Vec<_>>(), set);
        assert_eq!(mask_count(&m), 5);
    }

    /// The flood's mask operations, cell by cell: `dilate` adds exactly the face
    /// neighbours inside the tile, `across_face` moves exactly the cells on one face to
    /// the touching cells of the next tile, `box_mask` holds exactly the box's cells.
    #[test]
    fn flood_masks_match_cell_by_cell() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let cell = |l: usize| join(IVec3::ZERO, l);
        let holds = |m: &TileMask, c: IVec3| {
            c.cmpge(IVec3::ZERO).all()
                && c.cmplt(IVec3::splat(TILE)).all()
                && mask_get(m, split(c).1)
        };
        for _ in 0..50 {
            let mut m = [0u64; TILE as usize];
            for _ in 0..rng.random_range(1..40) {
                mask_set(&mut m, rng.random_range(0..TILE_VOLUME));
            }
            let d = dilate(&m);
            for l in 0..TILE_VOLUME {
                let c = cell(l);
                let want = holds(&m, c)
                    || (0..3).any(|a| {
                        [-1, 1].into_iter().any(|s| {
                            let mut n = c;
                            n[a] += s;
                            holds(&m, n)
                        })
                    });
                assert_eq!(mask_get(&d, l), want, "dilate at {c}");
            }
            for axis in 0..3 {
                for positive in [false, true] {
                    let a = across_face(&m, axis, positive);
                    let mut step = IVec3::ZERO;
                    step[axis] = if positive { TILE } else { -TILE };
                    for l in 0..TILE_VOLUME {
                        // Cell c of the next tile touches cell c - step ± 1 along axis of
                        // this one, which is in the tile only on the shared face.
                        let c = cell(l);
                        let mut from = c + step;
                        from[axis] += if positive { -1 } else { 1 };
                        assert_eq!(
                            mask_get(&a, l),
                            holds(&m, from),
                            "across {axis} {positive} at {c}"
                        );
                    }
                }
            }
            let lo = IVec3::new(
                rng.random_range(-2..8),
                rng.random_range(-2..8),
                rng.random_range(-2..8),
            );
            let hi = lo
                + IVec3::new(
                    rng.random_range(-1..9),
                    rng.random_range(-1..9),
                    rng.random_range(-1..9),
                );
            let b = box_mask(lo, hi);
            for l in 0..TILE_VOLUME {
                let c = cell(l);
                assert_eq!(
                    mask_get(&b, l),
                    c.cmpge(lo).all() && c.cmple(hi).all(),
                    "box at {c}"
                );
            }
        }
    }

    #[test]
    fn corner_nodes_match_brute_force() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for _ in 0..20 {
            // Random sparse cells in a 2×2×2 block of tiles at offsets −1..=0.
            let mut tiles: TileMap<TileMask> = TileMap::default();
            let mut set = std::collections::HashSet::new();
            for _ in 0..rng.random_range(1..300) {
                let c = IVec3::new(
                    rng.random_range(-8..8),
                    rng.random_range(-8..8),
                    rng.random_range(-8..8),
                );
                set.insert(c);
                let (t, l) = split(c);
                mask_set(tiles.entry(t).or_insert([0; 8]), l);
            }
            let nodes = corner_nodes(|o| tiles.get(&o));
            for l in 0..TILE_VOLUME {
                let n = join(IVec3::ZERO, l);
                let want =
                    (0..8).any(|d| set.contains(&(n - IVec3::new(d & 1, (d >> 1) & 1, d >> 2))));
                assert_eq!(mask_get(&nodes, l), want, "node {n}");
            }
        }
    }

    #[test]
    fn cell_set_counts_distinct_cells() {
        let mut s = CellSet::new();
        assert!(s.insert(IVec3::new(-3, 4, 100)));
        assert!(!s.insert(IVec3::new(-3, 4, 100)));
        assert!(s.insert(IVec3::new(5, 4, 100)));
        assert_eq!(s.len(), 2);
        assert!(s.contains(IVec3::new(5, 4, 100)));
        assert!(!s.contains(IVec3::new(5, 4, 101)));
        let mut all: Vec<_> = s.iter().map(|c| c.to_array()).collect();
        all.sort_unstable();
        assert_eq!(all, vec![[-3, 4, 100], [5, 4, 100]]);
    }
}
