//! Errors of mesh construction and editing.

use crate::ids::{TriId, VertexId};

/// What went wrong building or editing a [`crate::LabeledMesh`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeshError {
    /// A triangle refers to a vertex index the mesh does not have.
    #[error(
        "triangle {tri} refers to vertex {index}, but the mesh has only {vertex_count} vertices"
    )]
    VertexOutOfRange {
        /// Index of the offending triangle in the input.
        tri: usize,
        /// The out-of-range vertex index.
        index: u64,
        /// How many vertices there are.
        vertex_count: usize,
    },
    /// Parallel input arrays disagree in length.
    #[error("{what}: expected {expected} entries, got {got}")]
    LengthMismatch {
        /// Which array.
        what: &'static str,
        /// Expected length.
        expected: usize,
        /// Actual length.
        got: usize,
    },
    /// A label value is outside the id space (`u32::MAX` is reserved).
    #[error("triangle {tri} has label {label}, above the largest allowed label {max}", max = crate::ids::MAX_INDEX)]
    LabelOutOfRange {
        /// Index of the offending triangle in the input.
        tri: usize,
        /// The label value.
        label: u32,
    },
    /// More elements than the `u32` id space allows.
    #[error("too many {what}: {count} exceeds the u32 id space")]
    TooLarge {
        /// "vertices" or "triangles".
        what: &'static str,
        /// The requested count.
        count: usize,
    },
    /// The vertex was deleted or never existed.
    #[error("vertex {0} does not exist")]
    NoSuchVertex(VertexId),
    /// The triangle was deleted or never existed.
    #[error("triangle {0} does not exist")]
    NoSuchTriangle(TriId),
    /// A vertex cannot be removed while triangles use it.
    #[error("vertex {0} is still used by triangles")]
    VertexInUse(VertexId),
}
