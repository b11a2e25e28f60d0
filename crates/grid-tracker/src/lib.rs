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
//! Mesh cutting (§7), replacement (§8) and the tracker itself come next; until then the
//! facade reports the backend as unavailable ([`UNAVAILABLE`]).
#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod stages;

pub use stages::grid::{CellId, Grid, GridError, GridOptions, GridStats, Lattice, NodeId, build_grid};
pub use stages::materials::{
    EdgeCrossing, MaterialError, MaterialOptions, MaterialRef, MaterialStats, MaterialVector, MaterialView, Materials,
    assign_materials,
};

/// Why this backend cannot be constructed yet; the facade reports it to the user.
pub const UNAVAILABLE: Option<&str> = Some("the grid backend is not implemented yet (issue 4)");

#[cfg(test)]
mod test_util;
