//! Grid edges and faces, named by their lowest node and an axis, and their adjacency.
//!
//! Cell `c` spans nodes `c .. c + (1, 1, 1)`. An edge `(n, a)` joins node `n` to
//! `n + e_a`; the four cells around it are `n − {0, e_b} − {0, e_c}`. A face `(n, a)` is
//! normal to `a` and spans `n .. n + e_b + e_c`; its cells are `n − e_a` (below) and `n`
//! (above). `(b, c)` are always the other two axes in cyclic order ([`Axis::others`]).

use glam::IVec3;
use mesh_core::predicates::Axis;

/// The unit lattice vector along `axis`.
#[inline]
pub fn unit(axis: Axis) -> IVec3 {
    let mut v = IVec3::ZERO;
    v[axis.index()] = 1;
    v
}

/// A grid edge: from `node` to `node + e_axis`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct GridEdge {
    /// Lower end.
    pub node: IVec3,
    /// Direction.
    pub axis: Axis,
}

impl GridEdge {
    /// The four cells sharing this edge.
    pub fn cells(&self) -> [IVec3; 4] {
        let (b, c) = self.axis.others();
        let (eb, ec) = (unit(Axis::from_index(b)), unit(Axis::from_index(c)));
        let n = self.node;
        [n, n - eb, n - ec, n - eb - ec]
    }

    /// Upper end.
    pub fn end(&self) -> IVec3 {
        self.node + unit(self.axis)
    }
}

/// A grid face: normal to `normal`, spanning `node .. node + e_b + e_c`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct GridFace {
    /// Lowest corner.
    pub node: IVec3,
    /// Normal axis.
    pub normal: Axis,
}

impl GridFace {
    /// `[below, above]`: the cells on either side.
    pub fn cells(&self) -> [IVec3; 2] {
        [self.node - unit(self.normal), self.node]
    }

    /// The four boundary edges, in the order `(n, b)`, `(n + e_c, b)`, `(n, c)`,
    /// `(n + e_b, c)`: the slot numbers of [`crate::stages::flaws::FacePoint::GridEdge`].
    pub fn edges(&self) -> [GridEdge; 4] {
        let (b, c) = self.normal.others();
        let (ab, ac) = (Axis::from_index(b), Axis::from_index(c));
        let n = self.node;
        [
            GridEdge { node: n, axis: ab },
            GridEdge {
                node: n + unit(ac),
                axis: ab,
            },
            GridEdge { node: n, axis: ac },
            GridEdge {
                node: n + unit(ab),
                axis: ac,
            },
        ]
    }
}

/// The eight cells around a node.
pub fn node_cells(n: IVec3) -> [IVec3; 8] {
    std::array::from_fn(|d| n - IVec3::new((d & 1) as i32, ((d >> 1) & 1) as i32, (d >> 2) as i32))
}

/// The six faces of cell `c` with the neighbour across each.
pub fn cell_faces(c: IVec3) -> [(GridFace, IVec3); 6] {
    std::array::from_fn(|i| {
        let axis = Axis::from_index(i / 2);
        let e = unit(axis);
        if i % 2 == 0 {
            (
                GridFace {
                    node: c,
                    normal: axis,
                },
                c - e,
            )
        } else {
            (
                GridFace {
                    node: c + e,
                    normal: axis,
                },
                c + e,
            )
        }
    })
}

/// The twelve edges of cell `c`.
pub fn cell_edges(c: IVec3) -> [GridEdge; 12] {
    std::array::from_fn(|i| {
        let axis = Axis::from_index(i / 4);
        let (b, cc) = axis.others();
        let mut n = c;
        n[b] += (i & 1) as i32;
        n[cc] += ((i >> 1) & 1) as i32;
        GridEdge { node: n, axis }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn adjacency_is_consistent() {
        let c = IVec3::new(3, -2, 5);
        // Every face of a cell has the cell on one side and the neighbour on the other.
        for (f, nb) in cell_faces(c) {
            let [lo, hi] = f.cells();
            assert!((lo == c && hi == nb) || (hi == c && lo == nb));
            // Each face edge is shared by both face cells.
            for e in f.edges() {
                assert!(e.cells().contains(&lo) && e.cells().contains(&hi));
            }
        }
        // Every cell edge lists the cell among its four cells; a node's cells have it as corner.
        for e in cell_edges(c) {
            assert!(e.cells().contains(&c));
        }
        for cell in node_cells(c) {
            let d = c - cell;
            assert!(d.min_element() >= 0 && d.max_element() <= 1);
        }
        let mut all: Vec<[i32; 3]> = cell_edges(c)
            .iter()
            .map(|e| (e.node * 3 + e.axis.index() as i32).to_array())
            .collect();
        all.sort_unstable();
        all.dedup();
        assert_eq!(all.len(), 12);
    }
}
