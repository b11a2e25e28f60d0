//! # mesh-core
//!
//! The labelled non-manifold triangle mesh that both surface-tracker backends share, and
//! every service they both need, written once:
//!
//! - [`LabeledMesh`]: positions, triangles, `[front, back]` label pairs, and the two-sided
//!   corner table of Heiss-Synak et al. 2024 (§4) — see [`corner`] for the glossary;
//! - [`LabeledMesh::regions`]: region shells by flood fill over sides;
//! - [`predicates`]: exact orientation tests, the axis-line crossing test with Simulation
//!   of Simplicity, exact triangle–triangle intersection;
//! - [`SurfaceTracker`]: the trait every backend implements, with [`StepReport`] and
//!   [`TrackError`].
//!
//! Ids are typed `u32` newtypes ([`VertexId`], [`TriId`], [`CornerId`], [`Label`]).
#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod broadphase;
pub mod connectivity;
pub mod corner;
pub mod error;
pub mod generators;
pub mod geometry;
pub mod ids;
pub mod io;
pub mod mesh;
pub mod placement;
pub mod predicates;
pub mod regions;
pub mod remesh;
pub mod solve;
pub mod stamps;
pub mod tracker;
pub mod triangle_index;
pub mod union_find;
pub mod validate;

pub use corner::Side;
pub use error::MeshError;
pub use glam::DVec3;
pub use ids::{CornerId, Id, IdVec, Label, TriId, VertexId};
pub use mesh::{Compaction, LabeledMesh};
pub use regions::{RegionCensus, RegionShell, Regions};
pub use stamps::Stamps;
pub use tracker::{
    ContactChanges, LabelVolume, MaterialCensus, StageTiming, StepReport, SurfaceTracker,
    TopologyEvents, TrackError, check_proposal,
};
pub use triangle_index::TriangleIndex;
