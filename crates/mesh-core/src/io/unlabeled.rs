//! Labels for unlabelled input: a closed, consistently oriented surface separates an
//! inside (label 1) from the outside (label 0).
//!
//! Why this check: a plain OBJ or PLY says nothing about materials, but a closed surface
//! whose triangles agree on orientation has a well-defined inside. Every edge must be used
//! by exactly two triangles that traverse it in opposite directions; then each connected
//! component is a closed oriented surface, and the sign of its enclosed volume says whether
//! its normals point out (positive: `[front, back] = [0, 1]`) or in (negative: `[1, 0]`).
//! Anything else — an open edge, a non-manifold edge, two triangles disagreeing, a
//! degenerate triangle — makes inside and outside ambiguous, and the reader says which edge
//! is the first (in `(lower, higher)` vertex order) to do so rather than guessing.
//!
//! Limitation: components are labelled independently, so nested shells (a sphere inside a
//! sphere) both get inside = 1; such scenes need labelled files.

use super::error::{EdgeProblem, IoErrorKind};
use crate::LabeledMesh;
use crate::connectivity::EdgeTable;
use crate::geometry::signed_cone_volume;
use crate::ids::{Label, TriId};

/// Checks that the (dense, freshly built) `mesh` is closed and consistently oriented and
/// gives each connected component labels `[0, 1]` or `[1, 0]` by the sign of its volume.
pub(crate) fn label_closed_components(mesh: &mut LabeledMesh) -> Result<(), IoErrorKind> {
    let tris = mesh.tris();
    let table = EdgeTable::build(tris, mesh.tri_alive_flags(), mesh.vertex_capacity());
    let mut components = UnionFind::new(tris.len());
    for group in table.groups() {
        let first = group[0];
        let edge = [first.lo.raw(), first.hi.raw()];
        let problem = if first.lo == first.hi {
            Some(EdgeProblem::Degenerate)
        } else {
            match group {
                [_] => Some(EdgeProblem::Boundary),
                [a, b] if a.runs_lo_to_hi(tris) == b.runs_lo_to_hi(tris) => {
                    Some(EdgeProblem::Inconsistent)
                }
                [a, b] => {
                    components.union(a.tri.idx(), b.tri.idx());
                    None
                }
                _ => Some(EdgeProblem::NonManifold {
                    triangles: group.len(),
                }),
            }
        };
        if let Some(problem) = problem {
            return Err(IoErrorKind::NotClosed { edge, problem });
        }
    }

    // Volumes relative to the bounding-box centre: the sign survives meshes far from the
    // origin better than with cones from the origin.
    let positions = mesh.positions();
    let (lo, hi) = positions.iter().fold(
        (glam::DVec3::INFINITY, glam::DVec3::NEG_INFINITY),
        |(lo, hi), &p| (lo.min(p), hi.max(p)),
    );
    let centre = if positions.is_empty() {
        glam::DVec3::ZERO
    } else {
        (lo + hi) * 0.5
    };
    let mut volume = vec![0.0; tris.len()];
    for (t, tri) in tris.iter().enumerate() {
        let [a, b, c] = tri.map(|v| positions[v.idx()] - centre);
        volume[components.find(t)] += signed_cone_volume(a, b, c);
    }
    let inward = [Label::new(1), Label::OUTSIDE];
    for t in 0..tris.len() {
        if volume[components.find(t)] < 0.0 {
            mesh.set_labels(TriId::new(t as u32), inward);
        }
    }
    Ok(())
}

/// Disjoint sets over `0..n` with path halving and union by size.
struct UnionFind {
    parent: Vec<u32>,
    size: Vec<u32>,
}

impl UnionFind {
    fn new(n: usize) -> Self {
        UnionFind {
            parent: (0..n as u32).collect(),
            size: vec![1; n],
        }
    }

    fn find(&mut self, mut x: usize) -> usize {
        while self.parent[x] as usize != x {
            let grand = self.parent[self.parent[x] as usize];
            self.parent[x] = grand;
            x = grand as usize;
        }
        x
    }

    fn union(&mut self, a: usize, b: usize) {
        let (mut a, mut b) = (self.find(a), self.find(b));
        if a == b {
            return;
        }
        if self.size[a] < self.size[b] {
            std::mem::swap(&mut a, &mut b);
        }
        self.parent[b] = a as u32;
        self.size[a] += self.size[b];
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;

    /// A tetrahedron with outward normals, optionally shifted and with `flip` reversing all.
    fn tet(offset: f64, first: u32, flip: bool) -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let p = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(0.0, 0.0, 1.0),
        ]
        .map(|p| p + DVec3::splat(offset));
        let tris = [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]].map(|[a, b, c]| {
            if flip {
                [a + first, c + first, b + first]
            } else {
                [a + first, b + first, c + first]
            }
        });
        (p.to_vec(), tris.to_vec())
    }

    fn run(positions: Vec<DVec3>, tris: &[[u32; 3]]) -> Result<Vec<[u32; 2]>, IoErrorKind> {
        let mut mesh = LabeledMesh::from_raw(positions, tris, &vec![[0, 1]; tris.len()]).unwrap();
        label_closed_components(&mut mesh)?;
        Ok(mesh.to_raw().2)
    }

    #[test]
    fn components_get_labels_from_their_own_orientation() {
        let (mut p, mut t) = tet(0.0, 0, false);
        let (p2, t2) = tet(5.0, 4, true);
        p.extend(p2);
        t.extend(t2);
        let labels = run(p, &t).unwrap();
        assert_eq!(&labels[..4], &[[0, 1]; 4]);
        assert_eq!(&labels[4..], &[[1, 0]; 4]);
    }

    #[test]
    fn far_from_origin_sign_is_still_right() {
        let (p, t) = tet(1e9, 0, true);
        assert_eq!(run(p, &t).unwrap(), vec![[1, 0]; 4]);
    }

    #[test]
    fn reports_the_first_offending_edge() {
        let (p, t) = tet(0.0, 0, false);
        // Open: drop the face [1, 2, 3]; edge (1, 2) is the smallest boundary edge.
        let open: Vec<_> = t.iter().copied().filter(|f| *f != [1, 2, 3]).collect();
        assert!(matches!(
            run(p.clone(), &open),
            Err(IoErrorKind::NotClosed {
                edge: [1, 2],
                problem: EdgeProblem::Boundary
            })
        ));
        // Inconsistent: flip face [0, 1, 3]; its edges (0,1), (0,3), (1,3) now agree with
        // their neighbours, and (0, 1) comes first.
        let mut flipped = t.clone();
        flipped[1] = [0, 3, 1];
        assert!(matches!(
            run(p.clone(), &flipped),
            Err(IoErrorKind::NotClosed {
                edge: [0, 1],
                problem: EdgeProblem::Inconsistent
            })
        ));
        // Non-manifold: a fin on edge (0, 1).
        let mut p4 = p.clone();
        p4.push(DVec3::new(0.5, -1.0, 0.0));
        let mut fin = t.clone();
        fin.push([0, 1, 4]);
        assert!(matches!(
            run(p4, &fin),
            Err(IoErrorKind::NotClosed {
                edge: [0, 1],
                problem: EdgeProblem::NonManifold { triangles: 3 }
            })
        ));
        let degenerate = vec![[0, 0, 1], [0, 1, 0]];
        assert!(matches!(
            run(p, &degenerate),
            Err(IoErrorKind::NotClosed {
                edge: [0, 0],
                problem: EdgeProblem::Degenerate
            })
        ));
    }

    #[test]
    fn empty_mesh_is_trivially_closed() {
        assert_eq!(run(Vec::new(), &[]).unwrap(), Vec::<[u32; 2]>::new());
    }
}
