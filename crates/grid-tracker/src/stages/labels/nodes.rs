//! The grid nodes of a flawed region (the corners of its cells), numbered densely in
//! lattice order, with a lookup from lattice coordinates.
//!
//! Labelling (§8.1) and the PIC transfer (§8.4) both walk these nodes and their lattice
//! neighbours, tens of lookups per node, so the lookup matters: a compact region (the
//! usual case: one or a few blobs) gets a dense array over its bounding box, a scattered
//! one a hash map.

use glam::IVec3;
use rayon::prelude::*;

use crate::stages::flaws::FlawedRegion;
use crate::stages::grid::tiles::TileMap;
use crate::stages::rebuild::cell_corners;

/// A dense box is used while it has at most this many entries per flawed cell (4 bytes
/// each).
const DENSE_RATIO: usize = 8;

/// Marks a box entry that is no region node.
pub(crate) const NONE: u32 = u32::MAX;

/// Region nodes by lattice coordinate.
#[derive(Clone, Debug)]
pub enum NodeIndex {
    /// An array over the box `[lo, lo + dims)`, x fastest; `u32::MAX` where no node is.
    Dense {
        /// Lowest corner of the box.
        lo: IVec3,
        /// Extent of the box.
        dims: IVec3,
        /// Node index per box entry.
        index: Vec<u32>,
    },
    /// A hash map, for regions much sparser than their bounding box.
    Sparse(TileMap<u32>),
}

impl Default for NodeIndex {
    fn default() -> Self {
        NodeIndex::Sparse(TileMap::default())
    }
}

impl NodeIndex {
    /// The index of node `p`, if it is a region node.
    #[inline]
    pub fn get(&self, p: IVec3) -> Option<u32> {
        match self {
            NodeIndex::Dense { lo, dims, index } => {
                let d = p - *lo;
                if d.cmplt(IVec3::ZERO).any() || d.cmpge(*dims).any() {
                    return None;
                }
                let i = d.x as usize
                    + dims.x as usize * (d.y as usize + dims.y as usize * d.z as usize);
                Some(index[i]).filter(|&j| j != NONE)
            }
            NodeIndex::Sparse(map) => map.get(&p).copied(),
        }
    }
}

/// Why the nodes could not be numbered: more than `u32` indices.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TooManyNodes(pub usize);

/// The corners of every flawed cell, in lattice order (z, then y, then x), and their
/// index.
pub fn region_nodes(region: &FlawedRegion) -> Result<(Vec<IVec3>, NodeIndex), TooManyNodes> {
    let cells: Vec<IVec3> = region.cells().collect();
    let Some((lo, hi)) = cells.iter().fold(None, |acc: Option<(IVec3, IVec3)>, &c| {
        Some(acc.map_or((c, c), |(lo, hi)| (lo.min(c), hi.max(c))))
    }) else {
        return Ok((Vec::new(), NodeIndex::default()));
    };
    let dims = hi + IVec3::splat(2) - lo;
    let volume = dims.as_i64vec3().element_product();
    if volume > 0 && (volume as u64) <= (DENSE_RATIO as u64) * (cells.len() as u64) {
        let volume = volume as usize;
        if volume >= NONE as usize {
            return Err(TooManyNodes(volume));
        }
        // Mark corners, then number them in box order, which is lattice order.
        let mut index = vec![NONE; volume];
        let at = |p: IVec3| {
            let d = p - lo;
            d.x as usize + dims.x as usize * (d.y as usize + dims.y as usize * d.z as usize)
        };
        for &c in &cells {
            for n in cell_corners(c) {
                index[at(n)] = 0;
            }
        }
        let mut nodes = Vec::new();
        for (i, slot) in index.iter_mut().enumerate() {
            if *slot != NONE {
                *slot = nodes.len() as u32;
                let (x, yz) = (i % dims.x as usize, i / dims.x as usize);
                let (y, z) = (yz % dims.y as usize, yz / dims.y as usize);
                nodes.push(lo + IVec3::new(x as i32, y as i32, z as i32));
            }
        }
        return Ok((nodes, NodeIndex::Dense { lo, dims, index }));
    }
    let mut nodes: Vec<IVec3> = cells
        .par_iter()
        .flat_map_iter(|&c| cell_corners(c))
        .collect();
    nodes.par_sort_unstable_by_key(|n| [n.z, n.y, n.x]);
    nodes.dedup();
    if u32::try_from(nodes.len()).is_err() {
        return Err(TooManyNodes(nodes.len()));
    }
    let map: TileMap<u32> = nodes
        .iter()
        .enumerate()
        .map(|(i, &n)| (n, i as u32))
        .collect();
    Ok((nodes, NodeIndex::Sparse(map)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dense_and_sparse_lookups_agree() {
        let dims = IVec3::new(3, 4, 5);
        let lo = IVec3::new(-1, 2, 0);
        let mut index = vec![NONE; 60];
        index[1 + 3 * (2 + 4 * 3)] = 7;
        let dense = NodeIndex::Dense { lo, dims, index };
        let p = lo + IVec3::new(1, 2, 3);
        assert_eq!(dense.get(p), Some(7));
        assert_eq!(dense.get(p + IVec3::X), None);
        assert_eq!(dense.get(lo - IVec3::X), None);
        assert_eq!(dense.get(lo + dims), None);
        let sparse = NodeIndex::Sparse([(p, 7)].into_iter().collect());
        assert_eq!(sparse.get(p), Some(7));
        assert_eq!(sparse.get(lo), None);
    }
}
