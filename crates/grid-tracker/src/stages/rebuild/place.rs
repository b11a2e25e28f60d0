//! Vertex placement helpers (§8.3): where the keyed vertices go.
//!
//! Placement is separate from connectivity: the octant triangles and fans fix the
//! topology, and every vertex can then slide along its grid edge, within its grid face or
//! within its cell without changing it. [`midpoint_position`] is the plain placement
//! (edge midpoints, face and cell centres), exact in dyadic coordinates, used by tests
//! and as a fallback; [`average_cell_points`] is the paper's heuristic for face and cell
//! vertices: the average of the edge vertices around them.

use glam::{DVec3, IVec3};
use mesh_core::Label;

use super::keys::{RebuildVertexKey, edge_of_slot, face_of_slot};
use crate::stages::grid::Lattice;
use crate::stages::grid::primitives::GridEdge;

/// The plain position of a key: the midpoint of an edge, the centre of a face or cell;
/// `None` for a cut point, whose position only the cutting stage knows.
pub fn midpoint_position(lattice: &Lattice, key: RebuildVertexKey) -> Option<DVec3> {
    let mid = |a: IVec3, b: IVec3| 0.5 * (lattice.node_position(a) + lattice.node_position(b));
    match key {
        RebuildVertexKey::Edge(e) => Some(mid(e.node, e.end())),
        RebuildVertexKey::Face(f) => {
            let (b, c) = f.normal.others();
            let mut far = f.node;
            far[b] += 1;
            far[c] += 1;
            Some(mid(f.node, far))
        }
        RebuildVertexKey::Cell(c) => Some(mid(c, c + IVec3::ONE)),
        RebuildVertexKey::Cut(_) => None,
    }
}

/// Positions of a cell's face and centre vertices, where they exist.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CellPoints {
    /// Face slot `j` (the order of
    /// [`cell_faces`](crate::stages::grid::primitives::cell_faces)): `Some` when the face
    /// has two or more labels.
    pub faces: [Option<DVec3>; 6],
    /// The centre, `Some` when the cell has two or more labels.
    pub centre: Option<DVec3>,
}

/// §8.3's averages for one cell: each face vertex at the mean of the edge vertices on the
/// face's four edges, the centre at the mean of all the cell's edge vertices. Only edges
/// whose end labels differ carry a vertex; `edge_point` is called once for each of them.
///
/// A face vertex depends only on its face (its edges summed in
/// [`GridFace::edges`](crate::stages::grid::primitives::GridFace::edges) order), so the
/// two cells beside a face compute it bit for bit alike. Edge points strictly inside their
/// edges give face vertices strictly inside their faces and a centre strictly inside the
/// cell (a cut of the cube's corners never lies within one face), so no triangle of
/// [`triangulate_octants`](super::triangulate_octants) degenerates — and the surface
/// stays embedded: in each cell it is the cone from the centre over segments on the cell
/// boundary that meet only at their ends (stars from each face vertex to its edge
/// vertices), and rays from an interior point of a convex cell meet only at that point.
/// The same argument covers a fan over a boundary face whose clipped segments do not
/// cross.
pub fn average_cell_points(
    cell: IVec3,
    labels: &[Label; 8],
    mut edge_point: impl FnMut(GridEdge) -> DVec3,
) -> CellPoints {
    let corner = |n: IVec3| {
        let d = n - cell;
        labels[(d.x + 2 * d.y + 4 * d.z) as usize & 7]
    };
    let mut points = [None; 12];
    let (mut sum, mut count) = (DVec3::ZERO, 0u32);
    for (i, slot) in points.iter_mut().enumerate() {
        let e = edge_of_slot(cell, i as u8);
        if corner(e.node) != corner(e.end()) {
            let p = edge_point(e);
            sum += p;
            count += 1;
            *slot = Some(p);
        }
    }
    let centre = (count > 0).then(|| sum / f64::from(count));
    let faces = std::array::from_fn(|j| {
        let (mut sum, mut count) = (DVec3::ZERO, 0u32);
        for e in face_of_slot(cell, j as u8).edges() {
            if let Some(p) = points[slot_of_edge(cell, &e)] {
                sum += p;
                count += 1;
            }
        }
        (count > 0).then(|| sum / f64::from(count))
    });
    CellPoints { faces, centre }
}

/// The slot of edge `e` of `cell` (inverse of `edge_of_slot`).
fn slot_of_edge(cell: IVec3, e: &GridEdge) -> usize {
    let a = e.axis.index();
    let off = e.node - cell;
    debug_assert_eq!(off[a], 0, "edge {e:?} is not an edge of cell {cell}");
    (4 * a + off[(a + 1) % 3] as usize + 2 * off[(a + 2) % 3] as usize) % 12
}
