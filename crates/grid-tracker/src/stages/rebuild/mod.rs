//! Stage 5 building blocks (§8.2 of Heiss-Synak et al. 2024): the new triangles of the
//! flawed region, as pure per-cell functions the rebuild stage calls.
//!
//! Glossary:
//! - **octant** (Reitinger et al. 2005): one eighth of a cell, next to one corner and
//!   labelled by it; the surface separates octants of different labels ([`octants`]).
//! - **internal face**: a grid face between two flawed cells; its triangles come from
//!   [`triangulate_octants`]. **Boundary face**: between a flawed and an intact cell; its
//!   triangles are fans from the clipped mesh's segments to the flawed cell's centre
//!   ([`fan_boundary_face`]). Every new triangle has exactly one edge in a grid face and
//!   belongs to that face, so the two kinds are chosen face by face ([`FaceMask`]).
//! - **key** ([`RebuildVertexKey`]): a vertex named by the grid edge, face or cell it lies
//!   on (or by its cut-stage id), in integer lattice coordinates; [`Welder`] turns equal
//!   keys into one vertex, and [`Welder::alias`] slides an edge vertex onto the cut point
//!   where a boundary face meets an internal one.
//! - **placement** (§8.3): positions come last, per key ([`midpoint_position`],
//!   [`average_cell_points`]); connectivity never depends on them.
//!
//! A flawed cell's part, in order: labels of its corners (§8.1) → `triangulate_octants`
//! with the mask of its internal faces → `fan_boundary_face` for each boundary face →
//! weld all cells, aliasing edge vertices on boundary edges to their cut points → place.

pub mod fans;
pub mod keys;
pub mod octants;
pub mod place;
pub mod position;
pub mod region;
pub mod smooth_curves;
pub mod weld;

pub use fans::{BoundarySegment, FanError, fan_boundary_face};
pub use keys::{
    KeyMap, RebuildTriangle, RebuildVertexKey, cell_corners, cell_face_index, corner_offset,
    edge_of_slot, face_of_slot,
};
pub use octants::{FaceMask, has_interface, triangulate_octants};
pub use place::{CellPoints, average_cell_points, midpoint_position};
pub use position::edge_vertex_position;
pub use region::{RebuildError, RebuildOptions, RebuildReport, RebuildStats, rebuild_region};
pub use smooth_curves::{element_bounds, smooth_nonmanifold_curves};
pub use weld::{WeldError, Welder};

#[cfg(test)]
mod region_tests;
#[cfg(test)]
mod tests;
