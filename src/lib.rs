//! # surftrack
//!
//! Multi-material surface tracking on labelled non-manifold triangle meshes. This facade
//! re-exports the shared mesh crate and both backends, and picks a backend at run time:
//!
//! ```
//! use surftrack::{Backend, make_tracker};
//! use surftrack::mesh_core::generators;
//!
//! let backend: Backend = "grid".parse().unwrap();
//! # let _ = backend;
//! ```
//!
//! Every backend implements [`SurfaceTracker`]: propose new vertex positions, call
//! `advance`, read back a clean mesh. A failed step leaves the previous mesh intact.
//! [`Tracker`] adds named per-vertex attributes (velocities, …) that follow the mesh
//! through every step, on either backend.
#![warn(missing_docs)]
#![forbid(unsafe_code)]

use std::fmt;
use std::str::FromStr;

pub use collision_tracker;
pub use grid_tracker;
pub use mesh_core;
pub use mesh_core::{LabeledMesh, StepReport, SurfaceTracker, TrackError};
pub use tracker::{AttributeError, Tracker};

mod tracker;

/// The tracker backends, selectable by name at run time.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Backend {
    /// Hybrid grid/implicit topology changes (Heiss-Synak et al. 2024).
    Grid,
    /// Explicit, collision-safe tracking (Los Topos / El Topo).
    Collision,
}

impl Backend {
    /// Every backend, in a stable order.
    pub const ALL: [Backend; 2] = [Backend::Grid, Backend::Collision];

    /// The name used on the command line and in records.
    pub fn name(self) -> &'static str {
        match self {
            Backend::Grid => "grid",
            Backend::Collision => "collision",
        }
    }

    /// `None` when the backend can be constructed, otherwise why not.
    pub fn unavailable_reason(self) -> Option<&'static str> {
        match self {
            Backend::Grid => grid_tracker::UNAVAILABLE,
            Backend::Collision => collision_tracker::UNAVAILABLE,
        }
    }
}

impl fmt::Display for Backend {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Backend {
    type Err = BackendError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.to_ascii_lowercase().as_str() {
            "grid" => Ok(Backend::Grid),
            "collision" => Ok(Backend::Collision),
            _ => Err(BackendError::Unknown(s.to_string())),
        }
    }
}

/// Why a backend could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BackendError {
    /// No backend has this name.
    #[error("unknown tracker backend `{0}` (choose `grid` or `collision`)")]
    Unknown(String),
    /// The backend rejected the initial mesh.
    #[error("tracker backend `{backend}` rejected the mesh: {error}")]
    InvalidInput {
        /// The backend.
        backend: Backend,
        /// Its reason.
        error: TrackError,
    },
    /// The backend exists but cannot be constructed in this build.
    #[error("tracker backend `{backend}` is unavailable: {reason}")]
    Unavailable {
        /// The backend.
        backend: Backend,
        /// Why.
        reason: &'static str,
    },
}

/// Backend-independent knobs of [`make_tracker_with`]; everything else takes the
/// backend's documented defaults (`GridParams`, `CollisionParams`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TrackerOptions {
    /// The length scale: the grid backend's cell size ℓ, the collision backend's target
    /// edge length. Default `None`: the mean edge length of the initial mesh.
    pub length_scale: Option<f64>,
    /// Seed of any randomness in the backend (the grid backend's per-step grid shifts).
    pub seed: u64,
    /// Run `validate()` after every step (the step fails rather than return an invalid
    /// mesh). Default `None`: the backend's default (grid: on in debug builds;
    /// collision: structural checks always).
    pub validate_each_step: Option<bool>,
}

/// Every option of both backends, as data: the full [`grid_tracker::GridParams`] and
/// [`collision_tracker::CollisionParams`]. Serialisable (serde, every field optional on
/// input), so a scenario file or a run record can carry exactly the options a run used,
/// and [`make_tracker_from`] can rebuild the same tracker from it.
#[derive(Clone, Debug, Default, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct BackendOptions {
    /// Options of the grid backend (used when the backend is [`Backend::Grid`]).
    pub grid: grid_tracker::GridParams,
    /// Options of the collision backend (used when the backend is [`Backend::Collision`]).
    pub collision: collision_tracker::CollisionParams,
}

/// Makes a tracker of the chosen backend around an initial mesh with the full options of
/// that backend taken from `options` (the other backend's are ignored).
///
/// Errors: as [`make_tracker_with`]; out-of-range options are reported by the backend as
/// an invalid input naming the field.
pub fn make_tracker_from(
    backend: Backend,
    mesh: LabeledMesh,
    options: &BackendOptions,
) -> Result<Box<dyn SurfaceTracker>, BackendError> {
    if let Some(reason) = backend.unavailable_reason() {
        return Err(BackendError::Unavailable { backend, reason });
    }
    let invalid = |e: TrackError| BackendError::InvalidInput { backend, error: e };
    match backend {
        Backend::Grid => {
            let tracker =
                grid_tracker::GridTracker::new(mesh, options.grid.clone()).map_err(invalid)?;
            Ok(Box::new(tracker))
        }
        Backend::Collision => {
            let tracker = collision_tracker::CollisionTracker::new(mesh, options.collision.clone())
                .map_err(invalid)?;
            Ok(Box::new(tracker))
        }
    }
}

/// Makes a tracker of the chosen backend around an initial mesh, with default parameters.
pub fn make_tracker(
    backend: Backend,
    mesh: LabeledMesh,
) -> Result<Box<dyn SurfaceTracker>, BackendError> {
    make_tracker_with(backend, mesh, &TrackerOptions::default())
}

/// Makes a tracker of the chosen backend around an initial mesh.
///
/// Errors: the backend is unavailable in this build, or the mesh is not a valid input
/// for it (open, inconsistently labelled, non-finite; self-intersecting for the
/// collision backend), with the backend's own explanation.
pub fn make_tracker_with(
    backend: Backend,
    mesh: LabeledMesh,
    options: &TrackerOptions,
) -> Result<Box<dyn SurfaceTracker>, BackendError> {
    let mut full = BackendOptions::default();
    full.grid.cell_size = options.length_scale;
    full.grid.seed = options.seed;
    full.collision.target_edge_length = options.length_scale;
    if let Some(v) = options.validate_each_step {
        full.grid.validate_each_step = v;
        full.collision.validation = if v {
            collision_tracker::StepValidation::Structure
        } else {
            collision_tracker::StepValidation::Off
        };
    }
    make_tracker_from(backend, mesh, &full)
}

/// The README's Rust examples, compiled and run as doctests so that they stay true.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
pub struct ReadmeDoctests;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn backends_parse_by_name_and_report_availability() {
        for b in Backend::ALL {
            assert_eq!(b.name().parse::<Backend>().unwrap(), b);
            if let Some(reason) = b.unavailable_reason() {
                let err = make_tracker(b, LabeledMesh::new()).err().unwrap();
                assert!(err.to_string().contains(reason));
            }
        }
        assert!(matches!(
            "levelset".parse::<Backend>(),
            Err(BackendError::Unknown(_))
        ));
    }
}
