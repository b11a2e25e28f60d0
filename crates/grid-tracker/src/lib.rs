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
//! ([`mesh_core::predicates::compare_crossings`]) and the face piercing test
//! ([`stages::flaws::segment_pierces_face`]), so the three agree with each other.
//!
//! The whole step ([`GridTracker`], behind [`mesh_core::SurfaceTracker`]; one-shot repair
//! and multi-material union: [`fix`] / [`fix_with`]):
//!
//! ```text
//! move a copy → grid → materials → flaws → cut → labels → rebuild → transfer → improve
//!                                  ↑_______ safety net (§9.2), sub-ℓ pass ____|
//! ```
//!
//! - safety net (§9.2): a stage's local inconsistency, or a rebuilt mesh failing layers
//!   1–3 of validation, adds its cells to the flawed region and redoes cut → rebuild from
//!   the moved mesh, a bounded number of times ([`GridParams::max_safety_rounds`]);
//! - sub-ℓ pass (beyond the paper, its §10): exact triangle–triangle tests of the changed
//!   triangles against everything near them; the cells of intersecting pairs join the
//!   region and the pass repeats, bounded ([`SubcellPass`]), so the output is free of
//!   intersections at every scale, not only above ℓ;
//! - improvement (§8.5) keeps edge lengths in 0.5–1.5 ℓ, on the whole mesh or only the
//!   rebuilt parts ([`ImproveScope`]), each edit checked exactly against the rest.
#![warn(missing_docs)]
#![forbid(unsafe_code)]

mod fix;
mod params;
mod pipeline;
mod safety;
mod scale;
pub mod stages;
mod tracker;
mod union_volume;

pub use fix::{
    FixError, FixOptions, FixOutcome, FixReport, MaterialLoss, ReferenceMethod, VolumeCheck, fix,
    fix_with,
};
pub use params::{GridParams, ImproveScope, SubcellPass};
pub use pipeline::{PassStats, PipelineError};
pub use scale::{
    CELLS_PER_THICKNESS, CellSizeChoice, CellSizeRule, MAX_SURFACE_CELLS, default_cell_size,
    thinnest_shell, tracker_cell_size,
};
pub use tracker::GridTracker;
pub use union_volume::{UNION_LINES, UnionVolume, union_volume};

pub use stages::cut::{Cut, CutError, CutOptions, CutStats, cut_mesh};
pub use stages::flaws::{
    BoundaryFace, CellFlaws, FacePoint, FaceReport, FaceScratch, FaceSegment, FlawError,
    FlawOptions, FlawStats, FlawedRegion, detect_flaws, intersect_face, segment_pierces_face,
};
pub use stages::grid::primitives::{GridEdge, GridFace};
pub use stages::grid::{
    CellId, Grid, GridError, GridOptions, GridStats, Lattice, NodeId, build_grid,
};
pub use stages::labels::{
    BreakingPoint, EdgeTransitions, LabelError, LabelStats, NodeLabels, correct_labels,
};
pub use stages::materials::{
    EdgeCrossing, MaterialError, MaterialOptions, MaterialRef, MaterialStats, MaterialVector,
    MaterialView, Materials, assign_materials,
};
pub use stages::rebuild::{
    RebuildError, RebuildOptions, RebuildReport, RebuildStats, rebuild_region,
};
pub use stages::transfer::{OldVertices, TransferError, TransferStats, transfer_pic};

/// Why this backend cannot be constructed (`None`: it can); the facade reports it to the
/// user.
pub const UNAVAILABLE: Option<&str> = None;

#[cfg(test)]
mod test_util;
