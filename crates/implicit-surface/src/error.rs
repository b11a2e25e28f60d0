//! Typed errors of the crate: each names the offending parameter or stage and the value.

use mesh_core::MeshError;
use mesh_core::TrackError;

/// Why a field, a follower, a refinement or a polygonization could not be built or run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ImplicitError {
    /// A parameter is outside its documented range.
    #[error("{what}: invalid `{name}` = {value}: expected {expected}")]
    InvalidParameter {
        /// The type or function that refused it.
        what: &'static str,
        /// The parameter.
        name: &'static str,
        /// Its value, printed.
        value: String,
        /// The accepted range.
        expected: &'static str,
    },
    /// The field returned a non-finite value or gradient where the algorithm needed one.
    #[error("{stage}: the field is not finite at {at:?} (t = {t})")]
    NonFiniteField {
        /// The stage that evaluated it.
        stage: &'static str,
        /// The point.
        at: [f64; 3],
        /// The time.
        t: f64,
    },
    /// The zero set is empty where a mesh was asked for.
    #[error("{stage}: the surface F = 0 is empty at t = {t} (no sign change on the grid)")]
    EmptySurface {
        /// The stage.
        stage: &'static str,
        /// The time.
        t: f64,
    },
    /// The tracker backend refused a step; the follower keeps its previous mesh.
    #[error("tracker step at t = {t} failed: {source}")]
    Track {
        /// The time of the failed frame.
        t: f64,
        /// The tracker's error.
        #[source]
        source: TrackError,
    },
    /// Building a mesh from arrays failed (an internal inconsistency, reported rather than
    /// panicking).
    #[error("{stage}: building the mesh failed: {source}")]
    Mesh {
        /// The stage.
        stage: &'static str,
        /// The mesh error.
        #[source]
        source: MeshError,
    },
}

/// Shorthand for an [`ImplicitError::InvalidParameter`].
pub(crate) fn invalid(
    what: &'static str,
    name: &'static str,
    value: impl std::fmt::Display,
    expected: &'static str,
) -> ImplicitError {
    ImplicitError::InvalidParameter {
        what,
        name,
        value: value.to_string(),
        expected,
    }
}
