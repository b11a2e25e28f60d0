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
    let Some((lo, hi)) = region.cells().fold(None, |acc: Option<(IVec3, IVec3)>, c| {
        Some(acc.map_or((c, c), |(lo, hi)| (lo.min(c), hi.max(c))))
    }) else {
        return Ok((Vec::new(), NodeIndex::default()));
    };
    let dims = hi + IVec3::splat(2) - lo;
    let volume = dims.as_i64vec3().element_product();
    if volume > 0 && (volume as u64) <= (DENSE_RATIO as u64) * (region.len() as u64) {
        if volume as u64 >= u64::from(NONE) {
            return Err(TooManyNodes(volume as usize));
        }
        return Ok(dense_nodes(region, lo, dims));
    }
    let cells: Vec<IVec3> = region.cells().collect();
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

/// [`region_nodes`] over the box `[lo, lo + dims)`, which holds every corner of the
/// region's cells and fewer than `u32::MAX` entries.
///
/// Why layer by layer: where solids overlap the region is a volume (millions of nodes at
/// 2M triangles), and marking the 8 corners of every cell and then numbering the box was
/// one sequential pass each. Here only the flawed cells are marked sequentially (one
/// flag each); each layer of nodes then finds its corners from the two layers of cells
/// it bounds, counts them, and numbers them from the counts of the layers below, in
/// parallel.
fn dense_nodes(region: &FlawedRegion, lo: IVec3, dims: IVec3) -> (Vec<IVec3>, NodeIndex) {
    let (nx, ny) = (dims.x as usize, dims.y as usize);
    let layer = nx * ny;
    let at = |p: IVec3| {
        let d = p - lo;
        d.x as usize + nx * (d.y as usize + ny * d.z as usize)
    };
    // Flawed cells by their lowest corner (the box's last row, column and layer hold none).
    let mut flawed = vec![false; layer * dims.z as usize];
    for c in region.cells() {
        flawed[at(c)] = true;
    }
    // A node is a corner of the cells at its own position minus 0 or 1 along each axis.
    let flawed = &flawed;
    let cell = |x: usize, y: usize, z: usize| flawed[x + nx * (y + ny * z)];
    let mut index = vec![NONE; layer * dims.z as usize];
    let counts: Vec<u32> = index
        .par_chunks_mut(layer)
        .enumerate()
        .map(|(z, out)| {
            let mut count = 0u32;
            for y in 0..ny {
                for x in 0..nx {
                    let corner = (z.saturating_sub(1)..=z).any(|cz| {
                        (y.saturating_sub(1)..=y)
                            .any(|cy| cell(x, cy, cz) || (x > 0 && cell(x - 1, cy, cz)))
                    });
                    if corner {
                        out[x + nx * y] = count;
                        count += 1;
                    }
                }
            }
            count
        })
        .collect();
    let bases: Vec<u32> = counts
        .iter()
        .scan(0u32, |acc, &c| {
            let base = *acc;
            *acc += c;
            Some(base)
        })
        .collect();
    let nodes: Vec<IVec3> = index
        .par_chunks_mut(layer)
        .zip(bases)
        .enumerate()
        .flat_map_iter(|(z, (out, base))| {
            let mut layer_nodes = Vec::new();
            for (k, slot) in out.iter_mut().enumerate() {
                if *slot != NONE {
                    *slot += base;
                    let (x, y) = (k % nx, k / nx);
                    layer_nodes.push(lo + IVec3::new(x as i32, y as i32, z as i32));
                }
            }
            layer_nodes
        })
        .collect();
    (nodes, NodeIndex::Dense { lo, dims, index })
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
