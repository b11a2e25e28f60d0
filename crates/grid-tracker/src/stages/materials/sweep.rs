//! Ray sweeps along grid lines: the material vector of every allocated node, per axis.
//!
//! Why a ray may start at the first allocated node of its line with `e_0`: every
//! crossing of a line lies on a grid edge whose lower node is allocated (proof in
//! [`super::crossings`]), and crossings are gathered from *all* triangles, not only from
//! those listed in the cells the line borders. So no crossing precedes the line's first
//! allocated node, and the vector there is the vector at −∞: the outside, `e_0`. The
//! same holds across a gap in the band (a stretch of unallocated nodes): no crossing lies
//! in it, so the vector carries over unchanged. A sweep thus visits the allocated nodes
//! of a line in order and, after each node, applies the crossings of its +axis edge.
//!
//! Lines are enumerated tile row by tile row (tiles sharing their two other tile
//! coordinates, sorted along the axis): 64 lines per row, rows in parallel.

use std::sync::atomic::{AtomicU32, Ordering::Relaxed};

use mesh_core::{Label, LabeledMesh};
use rayon::prelude::*;

use super::crossings::EdgeCrossings;
use super::vector::{MaterialRef, MaterialVector, MaterialView, MixedPool};
use crate::stages::grid::tiles::{TILE, TILE_LOG2, TileMask};
use crate::stages::grid::{Grid, NodeId};

/// What a worker collects while sweeping: mixed vectors it met, and which nodes got them
/// (x sweep) or which nodes disagreed with the x sweep (y and z sweeps).
#[derive(Default)]
pub(crate) struct SweepPart {
    pub(crate) pool: MixedPool,
    /// `(node, index into pool)` for nodes whose vector is mixed (x sweep).
    pub(crate) mixed: Vec<(u32, u32)>,
    /// `(node, vector)` where this axis disagrees with x (y and z sweeps); a physical
    /// vector inline, a mixed one by index into `pool`.
    pub(crate) disagree: Vec<(u32, MaterialRef)>,
    pub(crate) overflow: bool,
}

/// Where a sweep puts node vectors.
pub(crate) enum Sink<'a> {
    /// The x sweep writes every node's vector (physical ones inline).
    Write(&'a [AtomicU32]),
    /// The y and z sweeps compare with the finished x result.
    Compare {
        x: &'a [MaterialRef],
        pool: &'a MixedPool,
    },
}

/// Sweeps every line along `axis` (0, 1, 2).
pub(crate) fn sweep_axis(
    mesh: &LabeledMesh,
    grid: &Grid,
    edges: &EdgeCrossings,
    axis: usize,
    sink: &Sink<'_>,
) -> Vec<SweepPart> {
    let (order, rows) = grid.tile_rows(axis);
    let labels = mesh.label_pairs();
    rows.par_windows(2)
        .fold(SweepPart::default, |mut part, w| {
            let row = &order[w[0]..w[1]];
            let mut state = MaterialVector::default();
            for lb in 0..TILE {
                for lc in 0..TILE {
                    state.set_one_hot(Label::new(0));
                    // Mixed vector of the previous node of this line, while unchanged.
                    let mut last: Option<u32> = None;
                    for &tile in row {
                        let nodes = &grid.tile_info[tile as usize].nodes;
                        let mut bits = line_bits(nodes, axis, lb as usize, lc as usize);
                        while bits != 0 {
                            let la = bits.trailing_zeros() as i32;
                            bits &= bits - 1;
                            let mut c = [0i32; 3];
                            c[axis] = la;
                            c[(axis + 1) % 3] = lb;
                            c[(axis + 2) % 3] = lc;
                            let local =
                                (c[0] | (c[1] << TILE_LOG2) | (c[2] << (2 * TILE_LOG2))) as usize;
                            let node = grid.node_in_tile(tile, local);
                            record(&mut part, sink, node, &state, &mut last);
                            let e = node.idx() * 3 + axis;
                            let (s, t) = (edges.start[e] as usize, edges.start[e + 1] as usize);
                            if s < t {
                                last = None;
                                for x in &edges.crossings[s..t] {
                                    state.cross(x.direction, labels[x.tri.idx()]);
                                }
                            }
                        }
                    }
                }
            }
            part
        })
        .collect()
}

/// The 8 node bits of a tile along `axis` on local line `(lb, lc)` (the two other local
/// coordinates in cyclic order), bit `k` = local coordinate `k` along the axis.
#[inline]
fn line_bits(nodes: &TileMask, axis: usize, lb: usize, lc: usize) -> u32 {
    match axis {
        // x along a row: y = lb, z = lc.
        0 => ((nodes[lc] >> (8 * lb)) & 0xff) as u32,
        // y: z = lb, x = lc; bit x + 8y of word z.
        1 => (0..8).fold(0, |acc, y| {
            acc | ((((nodes[lb] >> (lc + 8 * y)) & 1) as u32) << y)
        }),
        // z: x = lb, y = lc; bit x + 8y of word z.
        _ => (0..8).fold(0, |acc, z| {
            acc | ((((nodes[z] >> (lb + 8 * lc)) & 1) as u32) << z)
        }),
    }
}

fn record(
    part: &mut SweepPart,
    sink: &Sink<'_>,
    node: NodeId,
    state: &MaterialVector,
    last: &mut Option<u32>,
) {
    match sink {
        Sink::Write(out) => match state.physical_label().and_then(MaterialRef::physical) {
            Some(r) => out[node.idx()].store(encode(r), Relaxed),
            None => {
                let i = match *last {
                    Some(i) => i,
                    None => match part.pool.push(state.entries()) {
                        Some(i) => i,
                        None => {
                            part.overflow = true;
                            return;
                        }
                    },
                };
                *last = Some(i);
                part.mixed.push((node.raw(), i));
            }
        },
        Sink::Compare { x, pool } => {
            let r = x[node.idx()];
            let view = match r.mixed_index() {
                Some(i) => MaterialView::Mixed(pool.get(i)),
                None => r
                    .label()
                    .map_or(MaterialView::Mixed(&[]), MaterialView::Physical),
            };
            if view.same_as(state) {
                return;
            }
            let mine = match state.physical_label().and_then(MaterialRef::physical) {
                Some(p) => p,
                None => match part.pool.push(state.entries()) {
                    Some(i) => MaterialRef::mixed(i),
                    None => {
                        part.overflow = true;
                        return;
                    }
                },
            };
            part.disagree.push((node.raw(), mine));
        }
    }
}

/// The raw bits of a physical ref, for the atomic store.
#[inline]
fn encode(r: MaterialRef) -> u32 {
    r.label().map_or(0, |l| l.raw())
}
