//! Vertex keys of the rebuilt surface: every vertex the rebuild creates is named by the
//! grid element it lies on, in integer lattice coordinates, so that two cells creating
//! "the same" vertex produce equal keys and welding is exact — no floating-point
//! comparison is ever involved.
//!
//! Local numbering inside a cell (shared by the octant tables, the fans and the §8.3
//! averages):
//! - corner `d ∈ 0..8` is node `cell + (d & 1, (d >> 1) & 1, d >> 2)` ([`corner_offset`]);
//! - edge slot `i ∈ 0..12` is [`cell_edges`]`(cell)[i]`: axis `a = i / 4`, shifted by
//!   `i & 1` along `b` and by `(i >> 1) & 1` along `c`, `(b, c)` the other two axes in
//!   cyclic order;
//! - face slot `12 + j`, `j ∈ 0..6`, is [`cell_faces`]`(cell)[j]`: normal `j / 2`, lower
//!   face for even `j`, upper for odd;
//! - slot 18 is the cell centre.
//!
//! [`cell_edges`]: crate::stages::grid::primitives::cell_edges
//! [`cell_faces`]: crate::stages::grid::primitives::cell_faces

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hash, Hasher};

use glam::IVec3;
use mesh_core::Label;
use mesh_core::predicates::Axis;

use crate::stages::grid::primitives::{GridEdge, GridFace, unit};
use crate::stages::grid::tiles::TileHasher;

/// A vertex of the rebuilt surface, named by where it lies.
///
/// Keys are pure lattice coordinates (the grid edge, face or cell the vertex belongs to),
/// so the octant triangles of two cells sharing a face name their common vertices alike
/// and weld exactly. Cut points of the cutting stage (§7), which lie anywhere on a
/// boundary face, get an id of that stage instead.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RebuildVertexKey {
    /// The vertex on a grid edge whose two end labels differ (§8.3: at the breaking point,
    /// or midway between two).
    Edge(GridEdge),
    /// The vertex inside a grid face with two or more labels (§8.3: an average).
    Face(GridFace),
    /// The centre vertex of the cell at this lattice coordinate (§8.3: an average).
    Cell(IVec3),
    /// A vertex made by the cutting stage, by its id there.
    Cut(u32),
}

impl Hash for RebuildVertexKey {
    /// Hashes a tag and the integer coordinates only: cheap with [`TileHasher`], and
    /// consistent with the derived equality (equal keys write equal words).
    fn hash<H: Hasher>(&self, h: &mut H) {
        let node = |h: &mut H, n: IVec3| {
            h.write_i32(n.x);
            h.write_i32(n.y);
            h.write_i32(n.z);
        };
        match *self {
            RebuildVertexKey::Edge(e) => {
                h.write_u32(e.axis.index() as u32);
                node(h, e.node);
            }
            RebuildVertexKey::Face(f) => {
                h.write_u32(3 + f.normal.index() as u32);
                node(h, f.node);
            }
            RebuildVertexKey::Cell(c) => {
                h.write_u32(6);
                node(h, c);
            }
            RebuildVertexKey::Cut(i) => {
                h.write_u32(7);
                h.write_u32(i);
            }
        }
    }
}

/// A hash map from vertex keys, with the grid's fast integer hasher.
pub type KeyMap<V> = HashMap<RebuildVertexKey, V, BuildHasherDefault<TileHasher>>;

/// A triangle of the rebuilt surface: three keyed vertices and `[front, back]` labels,
/// front being the material the right-hand normal `(v1 − v0) × (v2 − v0)` points into
/// (the convention of [`mesh_core::LabeledMesh`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RebuildTriangle {
    /// The vertices, in winding order.
    pub verts: [RebuildVertexKey; 3],
    /// `[front, back]`.
    pub labels: [Label; 2],
}

/// First face slot of the local numbering (edges are `0..12`).
pub(crate) const FACE_SLOT: u8 = 12;
/// The centre slot of the local numbering.
pub(crate) const CENTRE_SLOT: u8 = 18;

/// Offset of corner `d ∈ 0..8` from the cell's lowest node: bit `k` of `d` along axis `k`.
#[inline]
pub fn corner_offset(d: usize) -> IVec3 {
    IVec3::new((d & 1) as i32, ((d >> 1) & 1) as i32, ((d >> 2) & 1) as i32)
}

/// The eight corner nodes of `cell`, in corner order.
#[inline]
pub fn cell_corners(cell: IVec3) -> [IVec3; 8] {
    std::array::from_fn(|d| cell + corner_offset(d))
}

/// Edge slot `i ∈ 0..12` of `cell` (the order of
/// [`cell_edges`](crate::stages::grid::primitives::cell_edges)).
#[inline]
pub fn edge_of_slot(cell: IVec3, i: u8) -> GridEdge {
    let a = usize::from(i / 4) % 3;
    let mut node = cell;
    node[(a + 1) % 3] += i32::from(i & 1);
    node[(a + 2) % 3] += i32::from((i >> 1) & 1);
    GridEdge {
        node,
        axis: Axis::from_index(a),
    }
}

/// Face slot `j ∈ 0..6` of `cell` (the order of
/// [`cell_faces`](crate::stages::grid::primitives::cell_faces)).
#[inline]
pub fn face_of_slot(cell: IVec3, j: u8) -> GridFace {
    let normal = Axis::from_index(usize::from(j / 2));
    let node = if j.is_multiple_of(2) {
        cell
    } else {
        cell + unit(normal)
    };
    GridFace { node, normal }
}

/// The index `j ∈ 0..6` of `face` among the faces of `cell`, if it is one of them.
pub fn cell_face_index(cell: IVec3, face: &GridFace) -> Option<u8> {
    let a = face.normal.index();
    let mut off = face.node - cell;
    let upper = off[a];
    off[a] = 0;
    (off == IVec3::ZERO && (upper == 0 || upper == 1)).then_some(2 * a as u8 + upper as u8)
}

/// The key of local slot `slot` of `cell`: an edge for `0..12`, a face for `12..18`, the
/// centre otherwise.
#[inline]
pub(crate) fn slot_key(cell: IVec3, slot: u8) -> RebuildVertexKey {
    if slot < FACE_SLOT {
        RebuildVertexKey::Edge(edge_of_slot(cell, slot))
    } else if slot < CENTRE_SLOT {
        RebuildVertexKey::Face(face_of_slot(cell, slot - FACE_SLOT))
    } else {
        RebuildVertexKey::Cell(cell)
    }
}
