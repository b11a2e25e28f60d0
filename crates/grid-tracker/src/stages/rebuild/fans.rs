//! Fans to the flawed cell centre for boundary faces (§8.2, Fig. 12b).
//!
//! On a face of the flawed boundary the rebuilt surface must meet the clipped mesh of the
//! intact cell exactly. After cutting (§7), every clipped triangle touching the face has
//! exactly one edge lying in it; the mesh's trace on the face is therefore a set of such
//! segments — polylines from face edge to face edge, meeting at non-manifold points where
//! three or more materials meet (never a closed loop: a cycle makes the face complex, and
//! §6.4 grows the region until no boundary face is). Each segment becomes one triangle
//! with the flawed cell's centre, copying the clipped triangle's labels.
//!
//! Orientation: a segment is given as its clipped triangle traverses it (`from → to` in
//! that triangle's winding). The fan triangle `(to, from, centre)` traverses it the other
//! way with the same `[front, back]`, the rule for two consistently oriented triangles
//! continuing one sheet across an edge, so labels agree across the face.

use glam::IVec3;
use mesh_core::Label;

use super::keys::{RebuildTriangle, RebuildVertexKey, cell_face_index};
use crate::stages::grid::primitives::GridFace;

/// One mesh edge lying in a boundary face, oriented as the clipped triangle on the intact
/// side traverses it, with that triangle's labels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BoundarySegment {
    /// First end, in the clipped triangle's winding order.
    pub from: RebuildVertexKey,
    /// Second end.
    pub to: RebuildVertexKey,
    /// The clipped triangle's `[front, back]`.
    pub labels: [Label; 2],
}

/// Why a boundary face could not be fanned; each variant names the face and the segment.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum FanError {
    /// The face is not one of the six faces of the cell.
    #[error("face {face:?} is not a face of cell {cell}")]
    NotAFaceOfCell {
        /// The flawed cell.
        cell: IVec3,
        /// The face given.
        face: GridFace,
    },
    /// A segment's two ends are the same vertex.
    #[error("segment {index} on face {face:?} has both ends at {key:?}")]
    Degenerate {
        /// The face.
        face: GridFace,
        /// Index of the segment in the input.
        index: usize,
        /// The repeated end.
        key: RebuildVertexKey,
    },
    /// A segment has the same label on both sides.
    #[error("segment {index} on face {face:?} has label {label} on both sides")]
    SameLabel {
        /// The face.
        face: GridFace,
        /// Index of the segment in the input.
        index: usize,
        /// The label.
        label: Label,
    },
    /// A segment end is a grid element that does not lie on the face (a cell centre, an
    /// edge not bounding the face, another face).
    #[error("segment {index} on face {face:?} has end {key:?}, which is not on that face")]
    OffFace {
        /// The face.
        face: GridFace,
        /// Index of the segment in the input.
        index: usize,
        /// The offending end.
        key: RebuildVertexKey,
    },
}

/// Appends to `out` one triangle `(to, from, centre of cell)` per segment of boundary face
/// `face` of the flawed cell `cell`, with the segment's labels; returns how many.
///
/// The segments are checked first and nothing is appended on error: ends must differ and
/// lie on the face as far as their keys tell (edge keys on one of its four edges, face
/// keys the face itself; [`RebuildVertexKey::Cut`] ends are trusted), labels must differ.
/// Allocation-free apart from `out` growing.
pub fn fan_boundary_face(
    cell: IVec3,
    face: GridFace,
    segments: &[BoundarySegment],
    out: &mut Vec<RebuildTriangle>,
) -> Result<usize, FanError> {
    if cell_face_index(cell, &face).is_none() {
        return Err(FanError::NotAFaceOfCell { cell, face });
    }
    for (index, s) in segments.iter().enumerate() {
        if s.from == s.to {
            return Err(FanError::Degenerate {
                face,
                index,
                key: s.from,
            });
        }
        if s.labels[0] == s.labels[1] {
            return Err(FanError::SameLabel {
                face,
                index,
                label: s.labels[0],
            });
        }
        for key in [s.from, s.to] {
            if !on_face(&face, key) {
                return Err(FanError::OffFace { face, index, key });
            }
        }
    }
    let centre = RebuildVertexKey::Cell(cell);
    out.extend(segments.iter().map(|s| RebuildTriangle {
        verts: [s.to, s.from, centre],
        labels: s.labels,
    }));
    Ok(segments.len())
}

/// Whether `key` can lie on `face`, as far as its lattice coordinates tell.
fn on_face(face: &GridFace, key: RebuildVertexKey) -> bool {
    match key {
        RebuildVertexKey::Edge(e) => face.edges().contains(&e),
        RebuildVertexKey::Face(f) => f == *face,
        RebuildVertexKey::Cell(_) => false,
        RebuildVertexKey::Cut(_) => true,
    }
}
