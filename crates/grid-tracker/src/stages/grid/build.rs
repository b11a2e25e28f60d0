//! [`build_grid`]: parallel construction of the block-sparse grid.
//!
//! 1. validate ℓ, the options and the live triangles' coordinates;
//! 2. choose the perturbed origin and check that ℓ is representable at these
//!    coordinates;
//! 3. per triangle, the exact cell range of its bounding box; count the incidences and
//!    refuse the grid if it would exceed the memory bound — before allocating it;
//! 4. the set of tiles touched by any cell or corner node, and the triangles of each tile
//!    (one parallel sort of `(tile, triangle)` pairs);
//! 5. per tile, in parallel and without atomics: the cell mask, then the node mask by bit
//!    dilation of its own and its −x/−y/−z neighbours' cell masks ([`corner_nodes`]);
//! 6. ranks and coordinates; per tile, the CSR lists of its cells written into the tile's
//!    own slices of `cell_start` / `cell_tris`, triangles in increasing id order — so
//!    the result does not depend on thread timing.

use glam::{DVec3, IVec3};
use mesh_core::{LabeledMesh, TriId};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use super::tiles::{
    TILE, TILE_LOG2, TILE_VOLUME, TileMap, TileMask, corner_nodes, join, mask_count, mask_iter,
    mask_prefix, mask_rank, mask_set, split,
};
use super::{Grid, GridError, GridOptions, Lattice, TileInfo};

/// At most this many cells along any axis (ids and tile keys stay far from `i32` limits).
pub(super) const MAX_CELLS_PER_AXIS: f64 = (1u64 << 22) as f64;
/// ℓ must exceed the coordinates' magnitude times this, so that consecutive planes are
/// distinct floats and [`Lattice::locate`] corrects its rounded guess in one step.
pub(super) const MIN_RELATIVE_CELL: f64 = 1.0 / (1u64 << 40) as f64;
/// Hard bound on incidences whatever the options say: every id stays a `u32`.
const HARD_ENTRY_LIMIT: u64 = 1 << 28;

/// Builds the sparse background grid of cell size `cell_size` (ℓ) around the live
/// triangles of `mesh`.
///
/// Errors: ℓ not finite and positive, options out of range, a live triangle with a
/// non-finite vertex, ℓ too fine for the coordinates ([`GridError::TooFine`]), or more
/// cell–triangle incidences than [`GridOptions::max_cell_entries`] (checked before the
/// grid is allocated, so a huge triangle or a tiny ℓ gives an error, not an OOM).
pub fn build_grid(
    mesh: &LabeledMesh,
    cell_size: f64,
    options: &GridOptions,
) -> Result<Grid, GridError> {
    if !(cell_size.is_finite() && cell_size > 0.0) {
        return Err(GridError::BadCellSize(cell_size));
    }
    let p = options.perturbation;
    if !(0.0..=0.5).contains(&p) {
        return Err(GridError::BadOption {
            name: "perturbation",
            value: p,
            expected: "in [0, 0.5]",
        });
    }
    let tris: Vec<TriId> = mesh.triangles().collect();
    check_finite(mesh, &tris)?;

    let (min, max) = tris
        .par_iter()
        .fold(
            || (DVec3::INFINITY, DVec3::NEG_INFINITY),
            |(lo, hi), &t| {
                let [a, b, c] = mesh.tri_positions(t);
                (lo.min(a).min(b).min(c), hi.max(a).max(b).max(c))
            },
        )
        .reduce(
            || (DVec3::INFINITY, DVec3::NEG_INFINITY),
            |a, b| (a.0.min(b.0), a.1.max(b.1)),
        );

    let mut rng = ChaCha8Rng::seed_from_u64(options.seed);
    let mut unit = || 2.0 * rng.random::<f64>() - 1.0;
    let shift = DVec3::new(unit(), unit(), unit()) * (p * cell_size);
    let anchor = if tris.is_empty() {
        DVec3::ZERO
    } else {
        (min / cell_size).floor() * cell_size
    };
    let lattice = Lattice {
        origin: anchor + shift,
        cell_size,
    };

    if !tris.is_empty() {
        let magnitude = min
            .abs()
            .max(max.abs())
            .max(lattice.origin.abs())
            .max_element();
        let extent = (max - min).max_element();
        if extent / cell_size > MAX_CELLS_PER_AXIS || magnitude * MIN_RELATIVE_CELL > cell_size {
            return Err(GridError::TooFine {
                cell_size,
                extent,
                magnitude,
            });
        }
    }

    let ranges: Vec<[IVec3; 2]> = tris
        .par_iter()
        .map(|&t| {
            let [a, b, c] = mesh.tri_positions(t);
            lattice.cell_range(a.min(b).min(c), a.max(b).max(c))
        })
        .collect();
    let needed: u64 = ranges
        .par_iter()
        .map(|[lo, hi]| {
            let d = (*hi - *lo + IVec3::ONE).max(IVec3::ZERO).as_u64vec3();
            d.x.saturating_mul(d.y).saturating_mul(d.z)
        })
        .reduce(|| 0, u64::saturating_add);
    let limit = options.max_cell_entries.min(HARD_ENTRY_LIMIT);
    if needed > limit {
        return Err(GridError::TooManyCells { needed, limit });
    }

    // Tiles touched by a cell or by a corner node ([lo, hi + 1] in node terms).
    let tile_set = ranges
        .par_iter()
        .fold(TileMap::<()>::default, |mut set, &[lo, hi]| {
            let (tlo, thi) = (split(lo).0, split(hi + IVec3::ONE).0);
            for z in tlo.z..=thi.z {
                for y in tlo.y..=thi.y {
                    for x in tlo.x..=thi.x {
                        set.insert(IVec3::new(x, y, z), ());
                    }
                }
            }
            set
        })
        .reduce(TileMap::default, |mut a, b| {
            a.extend(b);
            a
        });
    let mut tile_coords: Vec<IVec3> = tile_set.into_keys().collect();
    tile_coords.sort_unstable_by_key(|t| (t.z, t.y, t.x));
    let tiles: TileMap<u32> = tile_coords
        .iter()
        .enumerate()
        .map(|(i, &t)| (t, i as u32))
        .collect();

    // Triangles per tile (by their cell range), in increasing triangle order.
    let (tile_start, tile_tris) = tile_lists(&tiles, &ranges, tile_coords.len());
    let per_tile = |ti: usize| &tile_tris[tile_start[ti] as usize..tile_start[ti + 1] as usize];

    // Pass A, per tile: occupied cells and the number of incidences.
    let cell_masks: Vec<(TileMask, u32)> = (0..tile_coords.len())
        .into_par_iter()
        .map(|ti| {
            let origin = tile_coords[ti] << TILE_LOG2;
            let mut mask = [0u64; TILE as usize];
            let mut entries = 0u32;
            for &i in per_tile(ti) {
                for_each_local(ranges[i as usize], origin, |l| {
                    mask_set(&mut mask, l);
                    entries += 1;
                });
            }
            (mask, entries)
        })
        .collect();
    // Nodes: corners of the cells of this tile and of its −x/−y/−z neighbours.
    let node_masks: Vec<TileMask> = (0..tile_coords.len())
        .into_par_iter()
        .map(|ti| {
            let t = tile_coords[ti];
            corner_nodes(|o| {
                if o == IVec3::ZERO {
                    Some(&cell_masks[ti].0)
                } else {
                    tiles.get(&(t + o)).map(|&j| &cell_masks[j as usize].0)
                }
            })
        })
        .collect();

    let mut tile_info = Vec::with_capacity(tile_coords.len());
    let mut entry_base = Vec::with_capacity(tile_coords.len() + 1);
    let (mut cell_base, mut node_base, mut entries) = (0u32, 0u32, 0u32);
    for (&(cells, n), nodes) in cell_masks.iter().zip(node_masks) {
        let info = TileInfo {
            cell_prefix: mask_prefix(&cells),
            node_prefix: mask_prefix(&nodes),
            cell_base,
            node_base,
            cells,
            nodes,
        };
        entry_base.push(entries);
        cell_base += mask_count(&info.cells);
        node_base += mask_count(&info.nodes);
        entries += n;
        tile_info.push(info);
    }
    entry_base.push(entries);
    drop(cell_masks);
    let coords = |nodes: bool| -> Vec<IVec3> {
        tile_info
            .par_iter()
            .zip(&tile_coords)
            .flat_map_iter(|(info, &tc)| {
                let m = if nodes { &info.nodes } else { &info.cells };
                mask_iter(m).map(move |l| join(tc, l))
            })
            .collect()
    };
    let (cell_coords, node_coords) = (coords(false), coords(true));

    // Pass B, per tile: the cell lists of its cells, written into its own slices.
    let num_cells = cell_coords.len();
    let mut cell_start = vec![0u32; num_cells + 1];
    cell_start[num_cells] = entries;
    let mut cell_tris = vec![TriId::new(0); entries as usize];
    {
        let mut work = Vec::with_capacity(tile_info.len());
        let (mut starts, mut lists) = (&mut cell_start[..num_cells], cell_tris.as_mut_slice());
        for (ti, info) in tile_info.iter().enumerate() {
            let (s, rest) = starts.split_at_mut(mask_count(&info.cells) as usize);
            let (l, rest_l) = lists.split_at_mut((entry_base[ti + 1] - entry_base[ti]) as usize);
            work.push((ti, s, l));
            (starts, lists) = (rest, rest_l);
        }
        work.into_par_iter().for_each(|(ti, starts, list)| {
            let info = &tile_info[ti];
            let origin = tile_coords[ti] << TILE_LOG2;
            let rank = |l: usize| mask_rank(&info.cells, &info.cell_prefix, l) as usize;
            let mut count = [0u32; TILE_VOLUME];
            for &i in per_tile(ti) {
                for_each_local(ranges[i as usize], origin, |l| count[l] += 1);
            }
            let mut acc = 0u32;
            for l in mask_iter(&info.cells) {
                starts[rank(l)] = entry_base[ti] + acc;
                let c = count[l];
                count[l] = acc;
                acc += c;
            }
            for &i in per_tile(ti) {
                for_each_local(ranges[i as usize], origin, |l| {
                    list[count[l] as usize] = tris[i as usize];
                    count[l] += 1;
                });
            }
        });
    }

    let (tile_lo, tile_hi) = tile_coords
        .iter()
        .fold((IVec3::MAX, IVec3::MIN), |(lo, hi), &t| {
            (lo.min(t), hi.max(t))
        });
    let (cell_lo, cell_hi) = cell_coords
        .par_iter()
        .fold(
            || (IVec3::MAX, IVec3::MIN),
            |(lo, hi), &c| (lo.min(c), hi.max(c)),
        )
        .reduce(
            || (IVec3::MAX, IVec3::MIN),
            |a, b| (a.0.min(b.0), a.1.max(b.1)),
        );
    let single_cell_tris = ranges
        .par_iter()
        .zip(&tris)
        .filter(|(r, _)| r[0] == r[1])
        .map(|(_, &t)| t)
        .collect();
    Ok(Grid {
        lattice,
        tiles,
        tile_coords,
        tile_info,
        cell_coords,
        node_coords,
        cell_start,
        cell_tris,
        tile_lo,
        tile_hi,
        cell_lo,
        cell_hi,
        single_cell_tris,
        triangle_capacity: mesh.triangle_capacity(),
    })
}

/// Fails on the first (lowest id) live triangle with a non-finite vertex.
fn check_finite(mesh: &LabeledMesh, tris: &[TriId]) -> Result<(), GridError> {
    let bad = tris
        .par_iter()
        .find_first(|&&t| !mesh.tri_positions(t).iter().all(|p| p.is_finite()));
    if let Some(&t) = bad {
        for v in mesh.tri(t) {
            let position = mesh.position(v);
            if !position.is_finite() {
                return Err(GridError::NonFinite {
                    tri: t,
                    vertex: v.raw(),
                    position,
                });
            }
        }
    }
    Ok(())
}

/// Calls `f(local)` for the cells of the inclusive range `[lo, hi]` that lie in the tile
/// whose first cell is `origin`.
#[inline]
fn for_each_local([lo, hi]: [IVec3; 2], origin: IVec3, mut f: impl FnMut(usize)) {
    let a = (lo - origin).max(IVec3::ZERO);
    let b = (hi - origin).min(IVec3::splat(TILE - 1));
    for z in a.z..=b.z {
        for y in a.y..=b.y {
            for x in a.x..=b.x {
                f((x | (y << TILE_LOG2) | (z << (2 * TILE_LOG2))) as usize);
            }
        }
    }
}

/// Triangle indices (into the live-triangle list) per tile, by each triangle's cell
/// range, as CSR arrays; each tile's list in increasing order.
fn tile_lists(tiles: &TileMap<u32>, ranges: &[[IVec3; 2]], n_tiles: usize) -> (Vec<u32>, Vec<u32>) {
    let mut pairs: Vec<u64> = ranges
        .par_iter()
        .enumerate()
        .fold(Vec::new, |mut out, (i, &[lo, hi])| {
            let (tlo, thi) = (split(lo).0, split(hi).0);
            for z in tlo.z..=thi.z {
                for y in tlo.y..=thi.y {
                    for x in tlo.x..=thi.x {
                        // Every tile of a cell range exists (tiles cover [lo, hi + 1]).
                        if let Some(&t) = tiles.get(&IVec3::new(x, y, z)) {
                            out.push((u64::from(t) << 32) | i as u64);
                        }
                    }
                }
            }
            out
        })
        .flatten_iter()
        .collect();
    pairs.par_sort_unstable();
    let mut start = vec![0u32; n_tiles + 1];
    for &p in &pairs {
        start[(p >> 32) as usize + 1] += 1;
    }
    for i in 0..n_tiles {
        start[i + 1] += start[i];
    }
    (start, pairs.into_par_iter().map(|p| p as u32).collect())
}
