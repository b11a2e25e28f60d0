//! Grid edge × triangle crossings, found triangle by triangle and filed per grid edge.
//!
//! For every live triangle and axis, every grid line within the triangle's projected box
//! is tested with the exact [`cross_axis_line_triangle`] (Simulation of Simplicity: a
//! line through a mesh edge or vertex is counted exactly once). A hit is then placed on
//! its grid edge exactly: starting from the rounded coordinate, the exact
//! [`compare_crossing_with_point`] against the (perturbed) nodes moves the guess until
//! the crossing lies after node `g` and before node `g + 1`.
//!
//! Why the crossing's lower node is always allocated: the exact crossing point `x` lies
//! in the triangle, hence in its box `[min, max]`; with `plane(g) ≤ x ≤ plane(g + 1)`
//! and the box's cell range `[lo, hi]` from [`crate::Lattice::cell_range`]
//! (`plane(lo) < min`, `plane(hi) ≤ max`) we get `lo ≤ g ≤ hi`; likewise the line's
//! other coordinates `j, k` satisfy `lo ≤ j − 1 ≤ hi`. So cell `(g, j − 1, k − 1)` (in
//! axis order) is allocated and nodes `g` and `g + 1` of the line are its corners. A
//! violation would be a bug; it is reported as [`MaterialError::Internal`], not a panic.
//!
//! Filing: counting sort by edge id `3·node + axis` into CSR arrays, then each edge's
//! crossings sorted in their exact order along the (perturbed) line
//! ([`mesh_core::predicates::compare_crossings`]; coplanar ties by triangle id), so the result
//! is exact and does not depend on thread timing.

use glam::{DVec2, DVec3, IVec3};
use mesh_core::predicates::{
    Axis, Sign, compare_crossing_with_point, compare_crossings, cross_axis_line_triangle,
};
use mesh_core::{LabeledMesh, TriId};
use rayon::prelude::*;

use super::MaterialError;
use crate::stages::grid::{Grid, Lattice};

/// One crossing of a grid edge by a triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EdgeCrossing {
    /// The crossing triangle.
    pub tri: TriId,
    /// +1 when a ray travelling towards +axis passes from the triangle's back side to its
    /// front side (leaving its `back` label, entering `front`), −1 otherwise.
    pub direction: i8,
    /// Approximate axis coordinate of the crossing, for geometry only. Which edge the
    /// crossing is on, and the order of the crossings of one edge, are exact; the exact
    /// point is the intersection of the edge's line with the triangle's plane (perturbed
    /// grid point, see [`mesh_core::predicates::crossing`]).
    pub coordinate: f64,
}

/// Corrections of the rounded edge guess; more than two would contradict the error bound
/// of the barycentric coordinate (ℓ ≫ rounding, checked by `build_grid`).
const MAX_STEPS: usize = 16;

/// The crossings of every grid edge, as CSR arrays indexed by `3·node + axis`.
pub(crate) struct EdgeCrossings {
    pub(crate) start: Vec<u32>,
    pub(crate) crossings: Vec<EdgeCrossing>,
}

/// Finds and files all crossings of grid lines with live triangles.
pub(crate) fn find_crossings(
    mesh: &LabeledMesh,
    grid: &Grid,
) -> Result<EdgeCrossings, MaterialError> {
    let lattice = *grid.lattice();
    let tris: Vec<TriId> = mesh.triangles().collect();
    let parts: Vec<Vec<(u64, EdgeCrossing)>> = tris
        .par_iter()
        .try_fold(Vec::new, |mut out, &t| {
            triangle_crossings(mesh, grid, &lattice, t, &mut out)?;
            Ok(out)
        })
        .collect::<Result<_, MaterialError>>()?;

    let n_edges = grid.num_nodes() * 3;
    let mut count = vec![0u32; n_edges + 1];
    for &(e, _) in parts.iter().flatten() {
        count[e as usize + 1] += 1;
    }
    for i in 1..count.len() {
        count[i] += count[i - 1];
    }
    let total = count[n_edges] as usize;
    let mut keyed = vec![(0u64, placeholder()); total];
    let mut cursor = count.clone();
    for &(e, c) in parts.iter().flatten() {
        let at = &mut cursor[e as usize];
        keyed[*at as usize] = (e, c);
        *at += 1;
    }
    drop(parts);
    keyed.par_chunk_by_mut(|a, b| a.0 == b.0).for_each(|run| {
        if run.len() > 1 {
            let node = grid.node_coord(crate::stages::grid::NodeId::new((run[0].0 / 3) as u32));
            let axis = Axis::from_index((run[0].0 % 3) as usize);
            let p = lattice.node_position(node);
            run.sort_unstable_by(|(_, x), (_, y)| {
                compare_crossings(
                    axis,
                    p,
                    mesh.tri_positions(x.tri),
                    mesh.tri_positions(y.tri),
                )
                .then(x.tri.cmp(&y.tri))
            });
        }
    });
    let crossings = keyed.into_par_iter().map(|(_, c)| c).collect();
    Ok(EdgeCrossings {
        start: count,
        crossings,
    })
}

fn placeholder() -> EdgeCrossing {
    EdgeCrossing {
        tri: TriId::new(0),
        direction: 0,
        coordinate: 0.0,
    }
}

/// Appends `(edge id, crossing)` for every grid line that triangle `t` crosses.
fn triangle_crossings(
    mesh: &LabeledMesh,
    grid: &Grid,
    lattice: &Lattice,
    t: TriId,
    out: &mut Vec<(u64, EdgeCrossing)>,
) -> Result<(), MaterialError> {
    let tri = mesh.tri_positions(t);
    let [lo, hi] = lattice.cell_range(
        tri[0].min(tri[1]).min(tri[2]),
        tri[0].max(tri[1]).max(tri[2]),
    );
    for axis in Axis::ALL {
        let a = axis.index();
        let (b, c) = axis.others();
        // Lines with plane(b, j) in [min_b, max_b]: j in lo_b + 1 ..= hi_b (and for c).
        for j in lo[b] + 1..=hi[b] {
            for k in lo[c] + 1..=hi[c] {
                let line = DVec2::new(lattice.plane(b, j), lattice.plane(c, k));
                let Some(hit) = cross_axis_line_triangle(axis, line, tri) else {
                    continue;
                };
                let mut p = DVec3::ZERO;
                p[b] = line.x;
                p[c] = line.y;
                let g = edge_of_crossing(lattice, axis, p, tri, hit.coordinate).ok_or(
                    MaterialError::Internal {
                        what: "crossing not bracketed by grid nodes",
                        tri: t,
                    },
                )?;
                let mut node = IVec3::ZERO;
                node[a] = g;
                node[b] = j;
                node[c] = k;
                let id = grid.node_id(node).ok_or(MaterialError::Internal {
                    what: "crossing outside the allocated band",
                    tri: t,
                })?;
                out.push((
                    u64::from(id.raw()) * 3 + a as u64,
                    EdgeCrossing {
                        tri: t,
                        direction: hit.direction,
                        coordinate: hit.coordinate,
                    },
                ));
            }
        }
    }
    Ok(())
}

/// The node index `g` along `axis` with the crossing strictly between perturbed nodes
/// `g` and `g + 1` of the line through `p` (whose `axis` coordinate is ignored).
pub(crate) fn edge_of_crossing(
    lattice: &Lattice,
    axis: Axis,
    mut p: DVec3,
    tri: [DVec3; 3],
    approx: f64,
) -> Option<i32> {
    let a = axis.index();
    let mut side = |g: i32| {
        p[a] = lattice.plane(a, g);
        compare_crossing_with_point(axis, tri, p)
    };
    let mut g = lattice.locate(a, approx);
    for _ in 0..MAX_STEPS {
        if side(g) != Sign::Positive {
            g -= 1;
        } else if side(g + 1) == Sign::Positive {
            g += 1;
        } else {
            return Some(g);
        }
    }
    None
}
