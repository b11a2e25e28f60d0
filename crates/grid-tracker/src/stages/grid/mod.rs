//! Stage 1 (§4 of Heiss-Synak et al. 2024): the sparse background grid.
//!
//! A lattice of cubic cells of edge ℓ whose origin is randomly perturbed
//! ([`GridOptions::perturbation`]), so that grid planes rarely pass through mesh vertices
//! — in particular through the vertices a previous step placed at grid-face and cell
//! centres. A cell is *allocated* when its closed box meets the bounding box of a live
//! triangle ([`Lattice::cell_range`]): a narrow band around the surface, O(n) cells for n
//! triangles of size ~ℓ. A *node* (grid vertex) is allocated when it is a corner of an
//! allocated cell.
//!
//! Storage is block-sparse ([`tiles`]): 8³ tiles in a hash map, occupancy masks, and dense
//! [`CellId`] / [`NodeId`] numbering by rank, so per-cell and per-node arrays of the later
//! stages hold only allocated elements. Each cell lists its triangles in one flat CSR
//! array (`cell_start`, `cell_tris`), triangles in increasing id order.
//!
//! Entry point: [`build_grid`].

mod build;
pub mod lattice;
pub mod primitives;
pub mod tiles;

use glam::IVec3;
use mesh_core::TriId;

pub use build::build_grid;
pub use lattice::Lattice;
use tiles::{TILE, TileMap, TileMask, mask_get, mask_rank, split};

/// Dense index of an allocated cell.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct CellId(u32);

/// Dense index of an allocated node (grid vertex).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct NodeId(u32);

macro_rules! dense_id {
    ($t:ident) => {
        impl $t {
            /// The id with this index.
            #[inline]
            pub const fn new(i: u32) -> Self {
                Self(i)
            }
            /// The index as `u32`.
            #[inline]
            pub const fn raw(self) -> u32 {
                self.0
            }
            /// The index as `usize`, for slicing per-element arrays.
            #[inline]
            pub const fn idx(self) -> usize {
                self.0 as usize
            }
        }
    };
}
dense_id!(CellId);
dense_id!(NodeId);

/// Options of [`build_grid`].
#[derive(Clone, Debug, PartialEq)]
pub struct GridOptions {
    /// Largest random shift of the lattice origin, as a fraction of ℓ, per axis (the shift
    /// is uniform in `[−p·ℓ, p·ℓ]`). Default 0.1. Zero places the planes exactly on the
    /// multiples of ℓ (`plane(a, i) = ℓ·(i + floor(min[a]/ℓ))`), which tests use to put
    /// mesh vertices exactly on grid nodes. Must lie in `[0, 0.5]`.
    pub perturbation: f64,
    /// Seed of the perturbation. Default 0. A tracker should vary it between steps so that
    /// vertices placed on one step's grid are not on the next step's planes.
    pub seed: u64,
    /// Bound on the number of (cell, triangle) incidences, i.e. on the size of the cell
    /// lists, checked before anything is allocated. Each incidence costs about 12 bytes
    /// at peak (plus ~70 bytes per allocated cell and node); the default, 2²⁶ ≈ 67 M,
    /// bounds the grid at roughly 1–2 GB. A ~1M-triangle surface with ℓ equal to its mean
    /// edge length needs about 6 M.
    pub max_cell_entries: u64,
}

impl Default for GridOptions {
    fn default() -> Self {
        Self {
            perturbation: 0.1,
            seed: 0,
            max_cell_entries: 1 << 26,
        }
    }
}

/// Why a grid could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GridError {
    /// ℓ must be finite and positive.
    #[error("cell size ℓ = {0} must be finite and > 0")]
    BadCellSize(f64),
    /// An option is out of its documented range.
    #[error("grid option {name} = {value} is invalid: must be {expected}")]
    BadOption {
        /// Option name.
        name: &'static str,
        /// Value given.
        value: f64,
        /// Valid range.
        expected: &'static str,
    },
    /// A vertex of a live triangle has a NaN or infinite coordinate.
    #[error("vertex {vertex} of triangle {tri} has a non-finite position {position}")]
    NonFinite {
        /// The triangle using the vertex.
        tri: TriId,
        /// The vertex index.
        vertex: u32,
        /// Its position.
        position: glam::DVec3,
    },
    /// ℓ is too small for the coordinates: too many cells per axis, or below the
    /// resolution of `f64` at the mesh's distance from the origin.
    #[error(
        "cell size ℓ = {cell_size} is too fine for a mesh spanning {extent} at coordinates up to {magnitude}: {remedy}",
        remedy = too_fine_remedy(*cell_size, *extent, *magnitude)
    )]
    TooFine {
        /// ℓ.
        cell_size: f64,
        /// Largest bounding-box extent.
        extent: f64,
        /// Largest absolute coordinate.
        magnitude: f64,
    },
    /// The grid would exceed [`GridOptions::max_cell_entries`].
    #[error(
        "grid needs {needed} cell–triangle incidences, above the limit of {limit}; raise ℓ or the limit"
    )]
    TooManyCells {
        /// Incidences the mesh needs at this ℓ.
        needed: u64,
        /// The configured limit.
        limit: u64,
    },
}

/// Per-tile occupancy and rank bases.
#[derive(Clone, Debug, Default)]
pub(crate) struct TileInfo {
    pub(crate) cells: TileMask,
    pub(crate) nodes: TileMask,
    pub(crate) cell_prefix: [u16; TILE as usize],
    pub(crate) node_prefix: [u16; TILE as usize],
    pub(crate) cell_base: u32,
    pub(crate) node_base: u32,
}

/// Sizes of a grid, for reports and memory accounting.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct GridStats {
    /// Tiles allocated.
    pub tiles: usize,
    /// Allocated cells.
    pub cells: usize,
    /// Allocated nodes.
    pub nodes: usize,
    /// Cell–triangle incidences.
    pub entries: usize,
    /// Heap bytes held by the grid.
    pub heap_bytes: usize,
}

/// The sparse background grid: lattice, allocated cells and nodes, and the triangles of
/// every cell. Built by [`build_grid`]; read-only afterwards.
#[derive(Clone, Debug)]
pub struct Grid {
    pub(crate) lattice: Lattice,
    pub(crate) tiles: TileMap<u32>,
    pub(crate) tile_coords: Vec<IVec3>,
    pub(crate) tile_info: Vec<TileInfo>,
    pub(crate) cell_coords: Vec<IVec3>,
    pub(crate) node_coords: Vec<IVec3>,
    pub(crate) cell_start: Vec<u32>,
    pub(crate) cell_tris: Vec<TriId>,
    /// Smallest and largest tile coordinates (inclusive); empty grid: lo > hi.
    pub(crate) tile_lo: IVec3,
    pub(crate) tile_hi: IVec3,
    /// Bounds of the allocated cells (inclusive); empty grid: lo > hi.
    pub(crate) cell_lo: IVec3,
    pub(crate) cell_hi: IVec3,
    /// Live triangles whose bounding box lies in a single cell, sorted.
    pub(crate) single_cell_tris: Vec<TriId>,
    /// `triangle_capacity` of the mesh it was built from, to catch a mismatched mesh.
    pub(crate) triangle_capacity: usize,
}

impl Grid {
    /// The lattice (origin and ℓ).
    #[inline]
    pub fn lattice(&self) -> &Lattice {
        &self.lattice
    }

    /// Cell edge length ℓ.
    #[inline]
    pub fn cell_size(&self) -> f64 {
        self.lattice.cell_size
    }

    /// Number of allocated cells.
    #[inline]
    pub fn num_cells(&self) -> usize {
        self.cell_coords.len()
    }

    /// Number of allocated nodes.
    #[inline]
    pub fn num_nodes(&self) -> usize {
        self.node_coords.len()
    }

    /// `triangle_capacity()` of the mesh this grid was built from.
    #[inline]
    pub fn triangle_capacity(&self) -> usize {
        self.triangle_capacity
    }

    /// All allocated cells, in id order (tile by tile).
    pub fn cells(&self) -> impl Iterator<Item = CellId> + use<> {
        (0..self.cell_coords.len() as u32).map(CellId)
    }

    /// All allocated nodes, in id order.
    pub fn nodes(&self) -> impl Iterator<Item = NodeId> + use<> {
        (0..self.node_coords.len() as u32).map(NodeId)
    }

    /// Lattice coordinate of an allocated cell (its lowest corner node).
    #[inline]
    pub fn cell_coord(&self, c: CellId) -> IVec3 {
        self.cell_coords[c.idx()]
    }

    /// Lattice coordinate of an allocated node.
    #[inline]
    pub fn node_coord(&self, n: NodeId) -> IVec3 {
        self.node_coords[n.idx()]
    }

    /// The allocated cell at lattice coordinate `c`, if any.
    #[inline]
    pub fn cell_id(&self, c: IVec3) -> Option<CellId> {
        let (t, l) = split(c);
        let info = &self.tile_info[*self.tiles.get(&t)? as usize];
        mask_get(&info.cells, l)
            .then(|| CellId(info.cell_base + mask_rank(&info.cells, &info.cell_prefix, l)))
    }

    /// The allocated node at lattice coordinate `n`, if any.
    #[inline]
    pub fn node_id(&self, n: IVec3) -> Option<NodeId> {
        let (t, l) = split(n);
        let info = &self.tile_info[*self.tiles.get(&t)? as usize];
        mask_get(&info.nodes, l)
            .then(|| NodeId(info.node_base + mask_rank(&info.nodes, &info.node_prefix, l)))
    }

    /// Triangles whose bounding box meets the cell, in increasing id order.
    #[inline]
    pub fn cell_triangles(&self, c: CellId) -> &[TriId] {
        let (a, b) = (
            self.cell_start[c.idx()] as usize,
            self.cell_start[c.idx() + 1] as usize,
        );
        &self.cell_tris[a..b]
    }

    /// The allocated cells of tile `tile` (8³ cells from `tile · 8`; none for a tile that
    /// does not exist).
    pub fn tile_cells(&self, tile: IVec3) -> TileMask {
        self.tiles
            .get(&tile)
            .map_or([0; TILE as usize], |&i| self.tile_info[i as usize].cells)
    }

    /// Live triangles whose bounding box lies inside a single cell, in increasing id
    /// order: the only ones that can bound a volume smaller than a cell.
    pub fn single_cell_triangles(&self) -> &[TriId] {
        &self.single_cell_tris
    }

    /// The nearest allocated node at or below `n` along −x on the same grid line, if
    /// any. No mesh crosses the stretch between them (any crossing would have allocated
    /// the cells around it), which is what lets a query at an unallocated node borrow the
    /// material of this one. Cost: one tile lookup per tile passed.
    pub fn node_at_or_below_x(&self, n: IVec3) -> Option<NodeId> {
        let mut cur = n;
        if self.tile_lo.x > self.tile_hi.x {
            return None;
        }
        // Nothing lies beyond the last tile: start the walk there.
        cur.x = cur.x.min(((self.tile_hi.x + 1) << tiles::TILE_LOG2) - 1);
        let span = (self.tile_hi.x - self.tile_lo.x + 2).max(1) as usize;
        for _ in 0..span {
            let (t, l) = split(cur);
            if t.x < self.tile_lo.x {
                return None;
            }
            if let Some(&ti) = self.tiles.get(&t) {
                let info = &self.tile_info[ti as usize];
                let (w, row) = (l >> 6, (l & 63) & !(TILE as usize - 1));
                let x = l & (TILE as usize - 1);
                // Bits row..=row+x of word w: nodes (0..=x, y, z) of this tile.
                let bits = (info.nodes[w] >> row) & ((2u64 << x) - 1);
                if bits != 0 {
                    let lx = 63 - bits.leading_zeros() as usize;
                    let local = (w << 6) | row | lx;
                    return Some(NodeId(
                        info.node_base + mask_rank(&info.nodes, &info.node_prefix, local),
                    ));
                }
            }
            cur.x = (t.x << tiles::TILE_LOG2) - 1;
        }
        None
    }

    /// The smallest box `[lo, hi]` (inclusive) of lattice cells holding every allocated
    /// cell; `None` for an empty grid. A region of unallocated cells enclosed by the band
    /// lies inside it.
    pub fn cell_bounds(&self) -> Option<[IVec3; 2]> {
        (!self.cell_coords.is_empty()).then_some([self.cell_lo, self.cell_hi])
    }

    /// Sizes and memory.
    pub fn stats(&self) -> GridStats {
        use std::mem::size_of;
        let heap_bytes = self.tiles.capacity() * (size_of::<(IVec3, u32)>() + 1)
            + self.tile_coords.capacity() * size_of::<IVec3>()
            + self.tile_info.capacity() * size_of::<TileInfo>()
            + (self.cell_coords.capacity() + self.node_coords.capacity()) * size_of::<IVec3>()
            + self.cell_start.capacity() * size_of::<u32>()
            + (self.cell_tris.capacity() + self.single_cell_tris.capacity()) * size_of::<TriId>();
        GridStats {
            tiles: self.tile_coords.len(),
            cells: self.num_cells(),
            nodes: self.num_nodes(),
            entries: self.cell_tris.len(),
            heap_bytes,
        }
    }

    /// Tile indices grouped into rows along `axis`: tiles sharing their two other tile
    /// coordinates, each row sorted by the `axis` coordinate. Returns the flat order and
    /// the row boundaries (`rows[r]..rows[r + 1]`).
    pub(crate) fn tile_rows(&self, axis: usize) -> (Vec<u32>, Vec<usize>) {
        let (b, c) = ((axis + 1) % 3, (axis + 2) % 3);
        let mut order: Vec<u32> = (0..self.tile_coords.len() as u32).collect();
        let key = |t: u32| {
            let p = self.tile_coords[t as usize];
            (p[b], p[c], p[axis])
        };
        order.sort_unstable_by_key(|&t| key(t));
        let mut rows = vec![0];
        for i in 1..order.len() {
            let (p, q) = (key(order[i - 1]), key(order[i]));
            if (p.0, p.1) != (q.0, q.1) {
                rows.push(i);
            }
        }
        if !order.is_empty() {
            rows.push(order.len());
        }
        (order, rows)
    }

    /// Node id of `local` in tile `tile` (which must be set in its node mask).
    #[inline]
    pub(crate) fn node_in_tile(&self, tile: u32, local: usize) -> NodeId {
        let info = &self.tile_info[tile as usize];
        NodeId(info.node_base + mask_rank(&info.nodes, &info.node_prefix, local))
    }
}

/// What a [`GridError::TooFine`] asks of the user: the bound that was broken, with the
/// smallest ℓ it allows, and the remedy (a mesh far from the origin is fixed by moving it,
/// not by a coarser grid the user may not want).
fn too_fine_remedy(cell_size: f64, extent: f64, magnitude: f64) -> String {
    let near_origin = magnitude * build::MIN_RELATIVE_CELL;
    if near_origin > cell_size {
        format!(
            "cell corners are distinct floats only for ℓ of at least 2^-40 ≈ 9.1e-13 × the \
             largest coordinate ({near_origin:.3e} here); move the mesh towards the origin \
             (or give a larger ℓ)"
        )
    } else {
        format!(
            "at most 2^22 cells per axis (ℓ ≥ {:.3e} here); give a larger ℓ",
            extent / build::MAX_CELLS_PER_AXIS
        )
    }
}

#[cfg(test)]
mod tests;
