//! # collision-tracker
//!
//! The explicit, collision-safe multi-material tracker in the style of Los Topos (Da et al.
//! 2014) on El Topo (Brochu & Bridson 2009): exact continuous collision detection, impact
//! zones, snap merging, T1/T2 vertex separation — the mesh never tangles.
//!
//! Built so far (issue 5, item 1):
//! - [`ccd`]: continuous collision detection with no false negatives —
//!   [`ccd::ccd_vertex_triangle`], [`ccd::ccd_edge_edge`] returning an [`ccd::Impact`];
//! - [`proximity`]: static closest points — [`proximity::proximity_vertex_triangle`],
//!   [`proximity::proximity_edge_edge`] returning a [`proximity::Proximity`].
//!
//! The tracker, [`CollisionTracker`] (a [`mesh_core::SurfaceTracker`], parameters in
//! [`CollisionParams`]), runs Los Topos Algorithm 1 — resolve, merge, improve, t1t2,
//! validate — on a clone of its mesh and swaps it in only when the whole step succeeded.
//!
//! The backend is available ([`UNAVAILABLE`] is `None`): the merge, foam and rotation
//! scenes of issue 5 pass through the trait (`tests/tracker.rs`).
#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod broadphase;
pub mod ccd;
pub mod guard;
pub mod merge;
pub mod params;
pub mod proximity;
mod relax;
pub mod resolve;
mod step;
mod t1t2;
pub mod tracker;

pub use broadphase::{Broadphase, Candidates, Elements};
pub use guard::{CollisionGuard, CollisionGuardOptions, GuardStats};
pub use merge::{
    MergeError, MergeOptions, MergeReport, snap_merge, snap_merge_from, snap_merge_with,
};
pub use params::{AmbientFlow, CollisionParams, ParamsError, StepValidation, VelocityGradientFn};
pub use resolve::{ResolveError, ResolveOptions, ResolveReport, Resolved, resolve_step};
pub use tracker::CollisionTracker;

/// Why this backend cannot be constructed, if it cannot; the facade reports it to the
/// user. `None`: the backend is available.
pub const UNAVAILABLE: Option<&str> = None;
