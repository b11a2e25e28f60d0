//! Shared mesh improvement and local topology operations (issue 3), written once for both
//! backends. Every operation builds an atomic [`Edit`] that an [`EditGuard`] may veto.
//!
//! - [`edit`]: the edit representation and [`apply_edit`];
//! - [`guard`]: [`EditGuard`], [`NoGuard`], [`StaticIntersectionGuard`];
//! - [`attributes`]: per-vertex data carried through edits.
//! - [`region_graph`]: the region graph of a vertex; regular ⇔ complete (Los Topos §5);
//! - [`separate`]: vertex separation, T1 (Los Topos §5, Algorithm 2);
//! - [`degenerate`]: zero-volume regions and collapsed triangles, T2 (Los Topos §6);
//! - [`pinch`]: duplicating singular vertices (El Topo §3.6).
//! - [`features`]: vertex classification (quadric tensor, feature curves) and null space;
//! - [`split`], [`flip`], [`collapse`], [`smooth`]: the mesh-improvement operations
//!   (El Topo §3.5–3.6);
//! - [`improve()`]: the driver that sweeps them to keep edge lengths in range;
//! - [`blocks`]: the same driver on blocks of space, on every core;
//! - [`fence`]: [`FenceGuard`], improvement restricted to part of the mesh;
//! - [`structure`]: the structural check every edit passes before it commits;
//! - [`snap`]: vertex snapping and splits at given points (Los Topos §7.1 merging).
//!
//! `fixtures` (tests only) holds hand-built scenes shared with `tests/remesh_topology.rs`.

pub mod attributes;
pub mod blocks;
pub mod collapse;
pub mod degenerate;
pub mod edit;
pub mod features;
pub mod fence;
#[cfg(test)]
mod fixtures;
pub mod flip;
pub mod guard;
pub mod improve;
pub mod pinch;
pub mod region_graph;
pub mod separate;
pub mod smooth;
pub mod snap;
pub mod split;
pub mod structure;

pub use attributes::{Blend, VertexAttributes};
pub use blocks::{BlockJob, BlockParams, improve_in_blocks, run_in_blocks};
pub use collapse::{
    CollapseError, CollapseParams, CollapsePlacement, CollapseRefusal, collapse_edge,
};
pub use degenerate::{
    DegenerateReport, ThinRegionParams, ThinRegionReport, remove_degenerate, remove_degenerate_in,
    remove_thin_regions,
};
pub use edit::{Applied, Edit, EditError, NewVertex, VertexMove, VertexRef, apply_edit};
pub use features::{
    FeatureParams, VertexKind, classify_vertex, classify_vertices, max_label_volume_change,
    normal_cos, normals_agree,
};
pub use fence::FenceGuard;
pub use flip::{FlipCriterion, FlipError, FlipParams, FlipRefusal, flip_edge};
pub use guard::{EditGuard, NoGuard, StaticIntersectionGuard, Veto, bisect_moves};
pub use improve::{
    ConserveVolume, ImproveParams, ImproveRegion, ImproveReport, OpCounts, Resmooth, improve,
    improve_in, improve_with,
};
pub use pinch::{pinch_singular_vertices, pinch_singular_vertices_in};
pub use region_graph::{RegionGraph, irregular_vertices};
pub use separate::{
    AreaDecrease, SeparationParams, SeparationReport, SeparationStrength, VelocityDivergence,
    separate_irregular_vertices, separate_irregular_vertices_in,
};
pub use smooth::{Proposal, SmoothOutcome, SmoothParams, commit_moves, smooth_vertices};
pub use snap::{
    SnapError, SnapParams, SnapRefusal, SplitRecord, snap_vertices, split_edge_at,
    split_triangle_at, undo_split,
};
pub use split::{SplitPlacement, split_edge};
pub use structure::StructureFault;
