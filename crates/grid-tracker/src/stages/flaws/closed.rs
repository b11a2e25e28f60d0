//! Cells whose intersection with the mesh contains a closed volume (§6.2, third kind of
//! complex cell): a region shell — a closed 2-manifold of triangle sides, see
//! [`mesh_core::regions`] — lying entirely inside one cell, such as a bubble smaller
//! than ℓ, possibly attached to a larger interface.
//!
//! Only triangles whose box lies in a single cell can belong to such a shell
//! ([`Grid::single_cell_triangles`]), so the flood fill over opposite pointers starts
//! from those and stops (marking the shell as
//! escaping) at the first neighbour in another cell or across a boundary edge. Each side
//! is visited at most once, since shells partition the sides.

use mesh_core::{CornerId, LabeledMesh, TriId};
use rayon::prelude::*;

use crate::stages::grid::{CellId, Grid};

/// The cell holding the whole box of triangle `t`, if there is one.
fn single_cell(mesh: &LabeledMesh, grid: &Grid, t: TriId) -> Option<CellId> {
    grid.single_cell_triangles().binary_search(&t).ok()?;
    let [a, b, c] = mesh.tri_positions(t);
    let [lo, hi] = grid.lattice().cell_range(a.min(b).min(c), a.max(b).max(c));
    if lo == hi { grid.cell_id(lo) } else { None }
}

/// Cells containing a closed region shell, sorted and without repeats.
pub(crate) fn closed_volume_cells(mesh: &LabeledMesh, grid: &Grid) -> Vec<CellId> {
    let seeds: Vec<(TriId, CellId)> = grid
        .single_cell_triangles()
        .par_iter()
        .filter_map(|&t| single_cell(mesh, grid, t).map(|c| (t, c)))
        .collect();
    let mut visited = vec![false; mesh.triangle_capacity() * 2];
    let mut stack: Vec<usize> = Vec::new();
    let mut out = Vec::new();
    for &(t, cell) in &seeds {
        for side in 0..2 {
            let start = t.idx() * 2 + side;
            if visited[start] {
                continue;
            }
            visited[start] = true;
            stack.push(start);
            let mut escapes = false;
            while let Some(s) = stack.pop() {
                for k in 0..3 {
                    let Some(o) = mesh.opposite(CornerId::new((s * 3 + k) as u32)) else {
                        escapes = true;
                        continue;
                    };
                    let os = o.side_index();
                    if visited[os] {
                        continue;
                    }
                    if single_cell(mesh, grid, o.tri()) != Some(cell) {
                        escapes = true;
                        continue;
                    }
                    visited[os] = true;
                    stack.push(os);
                }
            }
            if !escapes {
                out.push(cell);
            }
        }
    }
    out.sort_unstable();
    out.dedup();
    out
}
