//! Non-manifold curve smoothing (end of §8.3): the rebuilt surface's triple curves come
//! out as staircases along the octant mid-planes; each new vertex on a non-manifold edge
//! is moved, for a fixed number of steps, to the average of its non-manifold neighbours.
//!
//! Differences from the paper, both for robustness:
//! - a vertex moves only within its grid element (an edge vertex along its edge, a face
//!   vertex within its face, a centre within its cell, `margin·ℓ` from their borders).
//!   §8.3 notes that vertices may slide so without changing connectivity, and the
//!   embedding argument of [`super::average_cell_points`] (each cell's part is a cone
//!   from an interior centre over non-crossing segments on the cell's boundary) keeps
//!   holding, so smoothing cannot create intersections;
//! - only vertices with two or more non-manifold neighbours move (a curve vertex or a
//!   junction); a lone non-manifold edge would otherwise collapse onto its end.
//!
//! Steps are Jacobi iterations (all new positions from the old ones), parallel over the
//! vertices; the corner table is relinked around every moved vertex at the end, since
//! radial orders around non-manifold edges depend on positions.

use glam::DVec3;
use mesh_core::{LabeledMesh, VertexId};
use rayon::prelude::*;

use super::keys::RebuildVertexKey;
use crate::stages::grid::Lattice;
use crate::stages::grid::primitives::unit;

/// The closed box a vertex keyed `key` may move in: its grid element shrunk by `margin·ℓ`
/// in the free directions, flat in the fixed ones; `None` for cut vertices, which never
/// move.
pub fn element_bounds(lattice: &Lattice, key: RebuildVertexKey, margin: f64) -> Option<[DVec3; 2]> {
    let m = margin * lattice.cell_size;
    let (lo_node, free) = match key {
        RebuildVertexKey::Edge(e) => (e.node, unit(e.axis)),
        RebuildVertexKey::Face(f) => {
            let (b, c) = f.normal.others();
            let mut free = glam::IVec3::ZERO;
            free[b] = 1;
            free[c] = 1;
            (f.node, free)
        }
        RebuildVertexKey::Cell(c) => (c, glam::IVec3::ONE),
        RebuildVertexKey::Cut(_) => return None,
    };
    let lo = lattice.node_position(lo_node);
    let hi = lattice.node_position(lo_node + free);
    let shrink = free.as_dvec3() * m;
    Some([lo + shrink, hi - shrink])
}

/// Smooths the non-manifold curves through `vertices` (new vertices with their element
/// boxes from [`element_bounds`]) for `steps` Jacobi steps; returns how many vertices
/// were smoothed. Only the listed vertices move; the rest of the mesh is read, not
/// changed.
pub fn smooth_nonmanifold_curves(
    mesh: &mut LabeledMesh,
    vertices: &[(VertexId, [DVec3; 2])],
    steps: usize,
) -> usize {
    // Non-manifold neighbours of every listed vertex, as CSR.
    let mut start = Vec::with_capacity(vertices.len() + 1);
    let mut neighbours: Vec<VertexId> = Vec::new();
    start.push(0usize);
    for &(v, _) in vertices {
        let first = neighbours.len();
        for t in mesh.vertex_triangles(v) {
            for w in mesh.tri(t) {
                if w == v || neighbours[first..].contains(&w) {
                    continue;
                }
                if mesh.edge_triangles(v, w).nth(2).is_some() {
                    neighbours.push(w);
                }
            }
        }
        start.push(neighbours.len());
    }
    let moving: Vec<usize> = (0..vertices.len())
        .filter(|&i| start[i + 1] - start[i] >= 2)
        .collect();
    if moving.is_empty() || steps == 0 {
        return 0;
    }
    let mut next = vec![DVec3::ZERO; moving.len()];
    for _ in 0..steps {
        let mesh_ref: &LabeledMesh = mesh;
        next.par_iter_mut().zip(&moving).for_each(|(out, &i)| {
            let nb = &neighbours[start[i]..start[i + 1]];
            let sum: DVec3 = nb.iter().map(|&w| mesh_ref.position(w)).sum();
            let [lo, hi] = vertices[i].1;
            *out = (sum / nb.len() as f64).clamp(lo, hi);
        });
        for (&i, &p) in moving.iter().zip(&next) {
            mesh.set_position(vertices[i].0, p);
        }
    }
    for &i in &moving {
        mesh.relink_around(vertices[i].0);
    }
    moving.len()
}
