//! Stage 6 (§8.4 of Heiss-Synak et al. 2024): transfer per-vertex attributes (velocities,
//! texture coordinates, …) from the discarded mesh to the rebuilt one through the grid,
//! particle-in-cell style (Harlow 1964).
//!
//! 1. **to the grid**: every node of the flawed region (a corner of a flawed cell) takes
//!    the average of the old vertices lying in its adjacent flawed cells;
//! 2. **flood fill**: nodes without data take it by breadth-first search from those with
//!    data; a node reached from several in the same round takes their average;
//! 3. **to the mesh**: each new vertex interpolates trilinearly in the flawed cell holding
//!    it.
//!
//! Fallback (not in the paper): a connected part of the region that no old vertex lies in
//! (possible when ℓ is below the old triangles' size) takes the average of all old
//! vertices given, counted in [`TransferStats::fallback_nodes`].
//!
//! Entry point: [`transfer_pic`].

use glam::{DVec3, IVec3};
use mesh_core::remesh::VertexAttributes;
use mesh_core::{LabeledMesh, VertexId};
use rayon::prelude::*;

use crate::stages::flaws::FlawedRegion;
use crate::stages::grid::primitives::unit;
use crate::stages::grid::{Grid, Lattice};
use crate::stages::labels::region_nodes;
use crate::stages::rebuild::{cell_corners, corner_offset};
use mesh_core::predicates::Axis;

/// The old mesh's side of the transfer: vertex positions and attributes by old vertex
/// slot, and which old vertices to use (those of the discarded part; vertices outside
/// the flawed cells are ignored by step 1 and only feed the fallback).
#[derive(Clone, Copy, Debug)]
pub struct OldVertices<'a> {
    /// Positions by old vertex slot.
    pub positions: &'a [DVec3],
    /// Attributes by old vertex slot.
    pub attrs: &'a VertexAttributes,
    /// The vertices to transfer from.
    pub vertices: &'a [VertexId],
}

/// Why attributes could not be transferred.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum TransferError {
    /// Old and new attributes have different numbers of values per vertex.
    #[error("old attributes have {old} values per vertex, new ones {new}")]
    DimensionMismatch {
        /// Old dimension.
        old: usize,
        /// New dimension.
        new: usize,
    },
    /// An old vertex id has no position.
    #[error("old vertex {vertex} has no position (only {len} given)")]
    NoOldPosition {
        /// The vertex.
        vertex: VertexId,
        /// Positions given.
        len: usize,
    },
    /// A new vertex is not a live vertex of the mesh.
    #[error("new vertex {vertex} is not a live vertex of the mesh")]
    DeadVertex {
        /// The vertex.
        vertex: VertexId,
    },
    /// A new vertex lies in no flawed cell, so the grid has no data for it.
    #[error("new vertex {vertex} at {position} lies in no flawed cell")]
    OutsideRegion {
        /// The vertex.
        vertex: VertexId,
        /// Its position.
        position: DVec3,
    },
    /// More region nodes than `u32` indices.
    #[error("the flawed region has {nodes} grid nodes, more than u32 indices")]
    TooManyNodes {
        /// Nodes counted.
        nodes: usize,
    },
    /// New vertices need data but no old vertex was given.
    #[error("no old vertex to transfer attributes from")]
    NoSource,
}

/// Counts describing a transfer.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TransferStats {
    /// Region nodes.
    pub nodes: usize,
    /// Old vertices that fell in flawed cells (step 1).
    pub splatted_vertices: usize,
    /// Nodes that received data in step 1.
    pub seeded_nodes: usize,
    /// Nodes filled by the flood (step 2).
    pub flooded_nodes: usize,
    /// Flood rounds.
    pub rounds: usize,
    /// Nodes given the average of all old vertices (fallback).
    pub fallback_nodes: usize,
    /// New vertices interpolated (step 3).
    pub interpolated: usize,
}

/// Transfers vertex attributes from the old vertices to `new_vertices` of `mesh` through
/// the grid nodes of the flawed region (§8.4), writing into `attrs`.
///
/// `attrs` must cover every vertex slot of `mesh` (e.g. `VertexAttributes::zeros(mesh,
/// dim)` after the rebuild, with the intact vertices' values copied in) and have the old
/// attributes' dimension. Only the new vertices' values are written.
///
/// Errors: a dimension mismatch, an old vertex without a position, a dead new vertex or
/// one outside the flawed region, or no old vertex at all.
pub fn transfer_pic(
    old: &OldVertices<'_>,
    grid: &Grid,
    region: &FlawedRegion,
    mesh: &LabeledMesh,
    new_vertices: &[VertexId],
    attrs: &mut VertexAttributes,
) -> Result<TransferStats, TransferError> {
    let dim = attrs.dim();
    if dim != old.attrs.dim() {
        return Err(TransferError::DimensionMismatch {
            old: old.attrs.dim(),
            new: dim,
        });
    }
    let mut stats = TransferStats::default();
    if dim == 0 || new_vertices.is_empty() {
        return Ok(stats);
    }
    if old.vertices.is_empty() {
        return Err(TransferError::NoSource);
    }
    for &v in old.vertices {
        if v.idx() >= old.positions.len() {
            return Err(TransferError::NoOldPosition {
                vertex: v,
                len: old.positions.len(),
            });
        }
    }
    for &v in new_vertices {
        if !mesh.is_vertex_alive(v) {
            return Err(TransferError::DeadVertex { vertex: v });
        }
    }
    let lattice = *grid.lattice();

    // Region nodes.
    let (nodes, index) =
        region_nodes(region).map_err(|e| TransferError::TooManyNodes { nodes: e.0 })?;
    stats.nodes = nodes.len();

    // (1) Old vertices to the corners of their flawed cells.
    let n = nodes.len();
    let mut values = vec![0.0; n * dim];
    let mut counts = vec![0u32; n];
    let located: Vec<Option<IVec3>> = old
        .vertices
        .par_iter()
        .map(|&v| {
            let p = old.positions[v.idx()];
            let c = locate_cell(&lattice, p)?;
            region.is_flawed(c).then_some(c)
        })
        .collect();
    let mut global = vec![0.0; dim];
    for (&v, c) in old.vertices.iter().zip(&located) {
        let a = old.attrs.get(v);
        for (g, x) in global.iter_mut().zip(a) {
            *g += x;
        }
        let Some(c) = c else { continue };
        stats.splatted_vertices += 1;
        for corner in cell_corners(*c) {
            if let Some(i) = index.get(corner) {
                let i = i as usize;
                counts[i] += 1;
                for (o, x) in values[i * dim..(i + 1) * dim].iter_mut().zip(a) {
                    *o += x;
                }
            }
        }
    }
    for g in &mut global {
        *g /= old.vertices.len() as f64;
    }
    let mut has: Vec<bool> = counts.iter().map(|&c| c > 0).collect();
    for (i, &c) in counts.iter().enumerate().filter(|(_, c)| **c > 0) {
        for o in &mut values[i * dim..(i + 1) * dim] {
            *o /= f64::from(c);
        }
    }
    stats.seeded_nodes = has.iter().filter(|&&h| h).count();

    // (2) Breadth-first flood: each round, the nodes next to the last round's take the
    // average of those neighbours.
    let mut frontier: Vec<u32> = (0..n as u32).filter(|&i| has[i as usize]).collect();
    let mut pending: Vec<u32> = Vec::new();
    let mut sum = vec![0.0; n * dim];
    let mut hits = vec![0u32; n];
    for _ in 0..n {
        if frontier.is_empty() {
            break;
        }
        stats.rounds += 1;
        pending.clear();
        for &i in &frontier {
            let p = nodes[i as usize];
            for axis in Axis::ALL {
                for step in [-1, 1] {
                    let Some(j) = index.get(p + step * unit(axis)) else {
                        continue;
                    };
                    let j = j as usize;
                    if has[j] {
                        continue;
                    }
                    if hits[j] == 0 {
                        pending.push(j as u32);
                    }
                    hits[j] += 1;
                    let src = &values[i as usize * dim..(i as usize + 1) * dim];
                    for (s, x) in sum[j * dim..(j + 1) * dim].iter_mut().zip(src) {
                        *s += x;
                    }
                }
            }
        }
        for &j in &pending {
            let j = j as usize;
            let h = f64::from(hits[j]);
            for (o, s) in values[j * dim..(j + 1) * dim]
                .iter_mut()
                .zip(&sum[j * dim..(j + 1) * dim])
            {
                *o = s / h;
            }
            has[j] = true;
        }
        stats.flooded_nodes += pending.len();
        std::mem::swap(&mut frontier, &mut pending);
    }
    for (i, h) in has.iter_mut().enumerate().filter(|(_, h)| !**h) {
        values[i * dim..(i + 1) * dim].copy_from_slice(&global);
        *h = true;
        stats.fallback_nodes += 1;
    }

    // (3) Trilinear interpolation at the new vertices.
    let mut out = vec![0.0; new_vertices.len() * dim];
    out.par_chunks_mut(dim)
        .zip(new_vertices)
        .try_for_each(|(acc, &v)| {
            let p = mesh.position(v);
            let cell = flawed_cell_of(&lattice, region, p).ok_or(TransferError::OutsideRegion {
                vertex: v,
                position: p,
            })?;
            let f = ((p - lattice.node_position(cell)) / lattice.cell_size)
                .clamp(DVec3::ZERO, DVec3::ONE);
            for d in 0..8 {
                let o = corner_offset(d);
                let w: f64 = (0..3)
                    .map(|a| if o[a] == 1 { f[a] } else { 1.0 - f[a] })
                    .product();
                // Every corner of a flawed cell is a region node.
                if let Some(i) = index.get(cell + o).filter(|_| w != 0.0) {
                    let i = i as usize;
                    for (a, x) in acc.iter_mut().zip(&values[i * dim..(i + 1) * dim]) {
                        *a += w * x;
                    }
                }
            }
            Ok(())
        })?;
    for (&v, src) in new_vertices.iter().zip(out.chunks(dim)) {
        attrs.get_mut(v).copy_from_slice(src);
    }
    stats.interpolated = new_vertices.len();
    Ok(stats)
}

/// The cell holding `p` (lowest corner `locate` on each axis); `None` for non-finite `p`.
fn locate_cell(lattice: &Lattice, p: DVec3) -> Option<IVec3> {
    p.is_finite().then(|| {
        IVec3::new(
            lattice.locate(0, p.x),
            lattice.locate(1, p.y),
            lattice.locate(2, p.z),
        )
    })
}

/// A flawed cell whose closed box holds `p` (up to rounding, 10⁻⁹ℓ): new vertices on a
/// face or edge of the region belong to any flawed cell beside it.
fn flawed_cell_of(lattice: &Lattice, region: &FlawedRegion, p: DVec3) -> Option<IVec3> {
    let c = locate_cell(lattice, p)?;
    if region.is_flawed(c) {
        return Some(c);
    }
    let tol = 1e-9 * lattice.cell_size;
    (0..27)
        .map(|k| c + IVec3::new(k % 3 - 1, (k / 3) % 3 - 1, k / 9 - 1))
        .find(|&nb| {
            let (lo, hi) = (
                lattice.node_position(nb),
                lattice.node_position(nb + IVec3::ONE),
            );
            region.is_flawed(nb)
                && p.cmpge(lo - DVec3::splat(tol)).all()
                && p.cmple(hi + DVec3::splat(tol)).all()
        })
}

#[cfg(test)]
mod tests;
