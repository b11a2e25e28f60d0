//! # grid-tracker
//!
//! The hybrid grid/implicit surface tracker of Heiss-Synak et al. 2024 ("Multi-Material
//! Mesh-Based Surface Tracking with Implicit Topology Changes"): let the mesh tangle, find
//! flawed regions on a sparse background grid, cut them out and rebuild them from a
//! multi-material implicit surface, leaving the rest of the mesh untouched.
//!
//! The stages written so far (issue 4), each one public function named after the paper:
//!
//! ```text
//! let grid = build_grid(&mesh, ℓ, &GridOptions::default())?;            // §4
//! let materials = assign_materials(&mesh, &grid, &MaterialOptions::default())?; // §5
//! let flaws = detect_flaws(&mesh, &grid, &materials, &FlawOptions::default())?; // §6
//! ```
//!
//! What each stage hands to the next:
//! - [`Grid`]: lattice ([`Lattice`]: exact plane positions), allocated cells and nodes
//!   with dense ids, the triangles of every cell;
//! - [`Materials`]: a material vector per allocated node (any node via
//!   [`Materials::material_at`]), flawed nodes, and per grid edge its crossings
//!   ([`EdgeCrossing`]: triangle, direction, coordinate) in exact order;
//! - [`FlawedRegion`]: the flawed cells (allocated or not) with their reasons, and the
//!   flawed boundary faces, each of which [`intersect_face`] turns into the segments
//!   the cutting stage constrains its triangulations with.
//!
//! Exactness: every decision about where the mesh meets the grid is made by exact
//! predicates under one Simulation of Simplicity perturbation (grid points stand for
//! `p + (ε, ε², ε³)`), shared by the crossing tests, the crossing order
//! ([`stages::materials::order`]) and the face piercing test
//! ([`stages::flaws::segment_pierces_face`]), so the three agree with each other.
//!
//! Mesh cutting (§7), replacement (§8) and the tracker itself come next; until then the
//! facade reports the backend as unavailable ([`UNAVAILABLE`]).
#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod stages;

pub use stages::flaws::{
    BoundaryFace, CellFlaws, FacePoint, FaceReport, FaceScratch, FaceSegment, FlawError,
    FlawOptions, FlawStats, FlawedRegion, detect_flaws, intersect_face, segment_pierces_face,
};
pub use stages::grid::primitives::{GridEdge, GridFace};
pub use stages::grid::{
    CellId, Grid, GridError, GridOptions, GridStats, Lattice, NodeId, build_grid,
};
pub use stages::materials::{
    EdgeCrossing, MaterialError, MaterialOptions, MaterialRef, MaterialStats, MaterialVector,
    MaterialView, Materials, assign_materials,
};

/// Why this backend cannot be constructed yet; the facade reports it to the user.
pub const UNAVAILABLE: Option<&str> = Some("the grid backend is not implemented yet (issue 4)");

#[cfg(test)]
mod test_util;
