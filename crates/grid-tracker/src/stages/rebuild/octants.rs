//! Multi-material marching cubes in the octant style of Reitinger et al. 2005, as §8.2 of
//! Heiss-Synak et al. 2024 uses it for the internal faces of the flawed region.
//!
//! The three mid-planes of a cell split it into eight *octants*, octant `d` being the
//! sub-cube between corner `d`, the three edge vertices and three face vertices next to
//! it, and the cell centre. Octant `d` takes the label of corner `d`. Two octants that
//! differ in one bit `a` share a quad in the mid-plane normal to axis `a`:
//!
//! ```text
//!   E (edge vertex of the cell edge joining the two corners)
//!   F_b, F_c (vertices of the two cell faces containing that edge)
//!   C (cell centre)
//!   quad E – F_b – C – F_c, split along E – C into (E, F_b, C) and (E, C, F_c)
//! ```
//!
//! and it is emitted exactly when the two corner labels differ. Across cells, octants are
//! the eighths of the dual cells of the grid vertices, so the union of all quads is the
//! boundary between the unions of same-label dual cells: a closed, consistently labelled,
//! generally non-manifold surface, with non-manifold curves where three or more labels
//! meet. Each triangle has exactly one edge (`E – F`) inside a grid face and *belongs* to
//! that face (§8.2, Fig. 12a); the two cells beside a face create the same `E – F`
//! segments there, traversed in opposite directions, so they conform.
//!
//! Orientation: every triangle's right-hand normal points along `+a`, into the octant of
//! the upper corner, so its labels are `[label(upper), label(lower)]`.

use glam::IVec3;
use mesh_core::Label;

use super::keys::{CENTRE_SLOT, FACE_SLOT, RebuildTriangle, RebuildVertexKey, slot_key};

/// A set of the six faces of a cell (bit `j` = face slot `j`, the order of
/// [`cell_faces`](crate::stages::grid::primitives::cell_faces)): which faces' triangles
/// [`triangulate_octants`] emits. The rebuild emits octant triangles for internal faces
/// and fans ([`super::fan_boundary_face`]) for boundary faces.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct FaceMask(u8);

impl FaceMask {
    /// All six faces: the whole octant surface of the cell.
    pub const ALL: FaceMask = FaceMask(0x3f);
    /// No face.
    pub const NONE: FaceMask = FaceMask(0);

    /// The set with bits `bits & 0x3f`.
    #[inline]
    pub const fn from_bits(bits: u8) -> FaceMask {
        FaceMask(bits & 0x3f)
    }

    /// The bits.
    #[inline]
    pub const fn bits(self) -> u8 {
        self.0
    }

    /// This set plus face `j` (ignored unless `j < 6`).
    #[inline]
    pub const fn with(self, j: u8) -> FaceMask {
        FaceMask(self.0 | bit(j))
    }

    /// This set minus face `j` (ignored unless `j < 6`).
    #[inline]
    pub const fn without(self, j: u8) -> FaceMask {
        FaceMask(self.0 & !bit(j))
    }

    /// Whether face `j` is in the set.
    #[inline]
    pub const fn contains(self, j: u8) -> bool {
        self.0 & bit(j) != 0
    }
}

/// The bit of face `j`; none for `j ≥ 6`.
const fn bit(j: u8) -> u8 {
    if j < 6 { 1 << j } else { 0 }
}

/// The quad between the two octants of cell edge `i`, as two triangles of local slots.
#[derive(Clone, Copy, Debug)]
struct EdgeQuad {
    /// Lower and upper corner of the edge.
    corners: [u8; 2],
    /// `(face slot j, triangle)`: each half belongs to one face containing the edge;
    /// normals point along `+a`.
    tris: [(u8, [u8; 3]); 2],
}

/// The twelve quads, one per cell edge.
const QUADS: [EdgeQuad; 12] = build_quads();

const fn build_quads() -> [EdgeQuad; 12] {
    let mut out = [EdgeQuad {
        corners: [0, 0],
        tris: [(0, [0; 3]); 2],
    }; 12];
    let mut i = 0;
    while i < 12 {
        let a = i / 4;
        let (b, c) = ((a + 1) % 3, (a + 2) % 3);
        let (beta, gamma) = (i & 1, (i >> 1) & 1);
        let lower = (beta << b) | (gamma << c);
        let (jb, jc) = ((2 * b + beta) as u8, (2 * c + gamma) as u8);
        let (e, fb, fc, centre) = (i as u8, FACE_SLOT + jb, FACE_SLOT + jc, CENTRE_SLOT);
        // In coordinates (a, b, c) doubled so that every vertex is integral:
        // E = (1, 2β, 2γ), F_b = (1, 2β, 1), F_c = (1, 1, 2γ), C = (1, 1, 1). With σ = 1 − 2·bit,
        // ((F_b − E) × (C − E))_a = −σ_β·σ_γ (the a-component of e_b × e_c is +1 for the
        // cyclic order), positive exactly when β ≠ γ; (E, C, F_c) has the same sign.
        let tris = if beta != gamma {
            [(jb, [e, fb, centre]), (jc, [e, centre, fc])]
        } else {
            [(jb, [e, centre, fb]), (jc, [e, fc, centre])]
        };
        out[i] = EdgeQuad {
            corners: [lower as u8, (lower | (1 << a)) as u8],
            tris,
        };
        i += 1;
    }
    out
}

/// Appends to `out` the octant triangles of `cell` that belong to the faces in `faces`,
/// given the labels of its eight corners (corner order of
/// [`corner_offset`](super::corner_offset)); returns how many were appended (at most 24).
///
/// A cell with a single label yields nothing. Allocation-free apart from `out` growing
/// (reuse it across cells). With [`FaceMask::ALL`] the vertices used are exactly the edge
/// vertex of every cell edge whose end labels differ, the face vertex of every face with
/// two or more labels, and the centre; with a smaller mask, those of them on the faces in
/// the mask, and the centre. These are the vertices the caller must place.
///
/// `cell` must be at least one below `i32::MAX` on every axis (grids are far smaller).
pub fn triangulate_octants(
    cell: IVec3,
    labels: &[Label; 8],
    faces: FaceMask,
    out: &mut Vec<RebuildTriangle>,
) -> usize {
    if !has_interface(labels) {
        return 0;
    }
    let keys: [RebuildVertexKey; 19] = std::array::from_fn(|s| slot_key(cell, s as u8));
    let start = out.len();
    for quad in &QUADS {
        let [lo, hi] = quad.corners.map(|d| labels[usize::from(d)]);
        if lo == hi {
            continue;
        }
        for &(j, tri) in &quad.tris {
            if faces.contains(j) {
                out.push(RebuildTriangle {
                    verts: [
                        keys[usize::from(tri[0])],
                        keys[usize::from(tri[1])],
                        keys[usize::from(tri[2])],
                    ],
                    labels: [hi, lo],
                });
            }
        }
    }
    out.len() - start
}

/// Whether the corner labels are not all equal, i.e. the cell holds an interface and its
/// centre vertex is used.
#[inline]
pub fn has_interface(labels: &[Label; 8]) -> bool {
    labels.iter().any(|&l| l != labels[0])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::stages::grid::primitives::{cell_edges, cell_faces};
    use crate::stages::rebuild::keys::{
        RebuildVertexKey, corner_offset, edge_of_slot, face_of_slot,
    };

    #[test]
    fn slots_match_the_grid_primitives() {
        let c = IVec3::new(-3, 7, 2);
        for (i, e) in cell_edges(c).iter().enumerate() {
            assert_eq!(edge_of_slot(c, i as u8), *e);
            // The quad's corners are the edge's end nodes.
            let q = QUADS[i];
            assert_eq!(c + corner_offset(usize::from(q.corners[0])), e.node);
            assert_eq!(c + corner_offset(usize::from(q.corners[1])), e.end());
            for (j, tri) in q.tris {
                // The half belongs to a face containing the edge, and has one vertex each
                // of edge, face and centre kind.
                assert!(face_of_slot(c, j).edges().contains(e));
                assert!(
                    tri.contains(&(i as u8))
                        && tri.contains(&(FACE_SLOT + j))
                        && tri.contains(&CENTRE_SLOT)
                );
            }
        }
        for (j, (f, _)) in cell_faces(c).iter().enumerate() {
            assert_eq!(face_of_slot(c, j as u8), *f);
            assert_eq!(super::super::keys::cell_face_index(c, f), Some(j as u8));
        }
        assert_eq!(slot_key(c, CENTRE_SLOT), RebuildVertexKey::Cell(c));
    }

    #[test]
    fn face_mask_bits() {
        let m = FaceMask::NONE.with(2).with(5).with(9).with(14);
        assert_eq!(m.bits(), 0b100100);
        assert!(m.contains(2) && m.contains(5) && !m.contains(0) && !m.contains(9));
        assert_eq!(m.without(2).bits(), 0b100000);
        assert_eq!(FaceMask::ALL.without(0).without(1).bits(), 0b111100);
        assert_eq!(FaceMask::from_bits(0xff), FaceMask::ALL);
    }
}
