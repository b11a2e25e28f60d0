//! Growing the flawed region: through unallocated non-physical space (§6.1), then until
//! its boundary has no complex edge or face (§6.4).

use glam::IVec3;
use mesh_core::LabeledMesh;
use rayon::prelude::*;

use super::face::{FaceScratch, intersect_face};
use super::{BoundaryFace, CellFlaws, FlawError, FlawedRegion};
use crate::stages::grid::Grid;
use crate::stages::grid::primitives::{GridEdge, cell_faces};
use crate::stages::grid::tiles::{
    TILE, TILE_LOG2, TILE_VOLUME, TileMap, TileMask, across_face, box_mask, dilate, join,
    mask_iter, split,
};
use crate::stages::materials::Materials;

/// Floods the flawed region from unallocated non-physical seed cells through unallocated
/// cells.
///
/// Why every unallocated face neighbour belongs: no mesh touches a closed unallocated
/// cell, so the vector is constant across such cells sharing a face — equal to the seed's
/// non-physical vector. Allocated neighbours need nothing: they share the face's four
/// (allocated, non-physical) nodes and were flagged from those. Termination: a
/// non-physical unallocated component is enclosed by the band (far from the mesh the
/// vector is `e_0`), hence inside [`Grid::cell_bounds`], where the flood is clamped.
///
/// The flood runs on tiles, never on single cells, because the volume inside large
/// overlaps grows faster than the mesh (a flood by cells was most of this stage at 2M
/// triangles): a tile without allocated cells joins whole, and inside a partly allocated
/// tile the flood spreads by bit operations on the tile's 512-cell mask ([`dilate`])
/// from the cells it entered by, then hands the cells on its six faces to the
/// neighbouring tiles ([`across_face`]).
///
/// A broken mesh (holes: the materials have flawed nodes) breaks the constancy argument —
/// a hole's "shadow" along a ray is non-physical up to infinity — so then each cell's own
/// vector is checked ([`Materials::material_at`]) before it joins (once per cell, when
/// the flood first enters its tile). The clamp and [`FlawError::TooManyUnallocated`] bound the work either way.
pub(crate) fn flood(
    grid: &Grid,
    materials: &Materials,
    region: &mut FlawedRegion,
    seeds: &[IVec3],
    limit: usize,
) -> Result<(), FlawError> {
    let Some([lo, hi]) = grid.cell_bounds() else {
        return Ok(());
    };
    let check = !materials.flawed_nodes().is_empty();
    // Per tile, the cells that may join: unallocated, inside the bounds, and (broken
    // input) non-physical, each cell's vector looked up once.
    let mut checked: TileMap<TileMask> = TileMap::default();
    let mut open = |t: IVec3| -> TileMask {
        if let Some(m) = checked.get(&t) {
            return *m;
        }
        let base = t << TILE_LOG2;
        let allocated = grid.tile_cells(t);
        let mut m = box_mask(lo - base, hi - base);
        for (w, a) in m.iter_mut().zip(allocated) {
            *w &= !a;
        }
        if check {
            for l in mask_iter(&m.clone()) {
                if materials.material_at(grid, join(t, l)).is_physical() {
                    m[l >> 6] &= !(1 << (l & 63));
                }
            }
            checked.insert(t, m);
        }
        m
    };
    let full = [u64::MAX; TILE as usize];
    // Tiles to spread from, with the cells that just joined there (a whole tile's all).
    let mut stack: Vec<(IVec3, TileMask)> = Vec::new();
    // Cells of `t` that `seeds` reaches: the whole tile when it may join whole, else the
    // flood inside it; new cells join the region and the tile is queued.
    let mut enter =
        |region: &mut FlawedRegion, stack: &mut Vec<(IVec3, TileMask)>, t, seeds: &TileMask| {
            let allowed = open(t);
            let joined = region.cells.tile(t);
            let free = |m: &TileMask| -> TileMask {
                std::array::from_fn(|z| m[z] & allowed[z] & !joined[z])
            };
            let mut reached = free(seeds);
            if reached.iter().all(|&w| w == 0) {
                return;
            }
            if allowed == full {
                reached = free(&full);
            } else {
                // At most one step per cell of the tile.
                for _ in 0..TILE_VOLUME {
                    let next = free(&dilate(&reached));
                    if next == reached {
                        break;
                    }
                    reached = next;
                }
            }
            region.unallocated += region.cells.insert_mask(t, &reached);
            stack.push((t, reached));
        };
    for &c in seeds {
        let (t, l) = split(c);
        let mut m = [0u64; TILE as usize];
        m[l >> 6] = 1 << (l & 63);
        enter(region, &mut stack, t, &m);
    }
    while let Some((t, reached)) = stack.pop() {
        if region.unallocated > limit {
            return Err(FlawError::TooManyUnallocated { limit });
        }
        for axis in 0..3 {
            for positive in [false, true] {
                let across = across_face(&reached, axis, positive);
                if across.iter().any(|&w| w != 0) {
                    let mut step = IVec3::ZERO;
                    step[axis] = if positive { 1 } else { -1 };
                    enter(region, &mut stack, t + step, &across);
                }
            }
        }
    }
    Ok(())
}

/// Counters of one growth run.
#[derive(Default)]
pub(crate) struct GrowthCounts {
    pub(crate) rounds: usize,
    pub(crate) grown: usize,
    pub(crate) cycle_faces: usize,
    pub(crate) inconsistent_faces: usize,
}

fn edge_is_complex(grid: &Grid, materials: &Materials, e: GridEdge) -> bool {
    grid.node_id(e.node)
        .is_some_and(|n| materials.edge_crossing_count(n, e.axis) >= 2)
}

/// Adds cells until no boundary face of the region is complex: every boundary face of
/// every cell that joined in the last round is checked — its four edges (a complex edge
/// adds its four cells) and, if none is complex, its intersection graph (a cycle, or a
/// triangle meeting it in other than two points, adds the intact cell across it).
///
/// Why checking only the newest cells suffices: the flawed set only grows, and a face's
/// complexity does not depend on the set, so a boundary face at the end was a boundary
/// face, and was checked, when its flawed cell joined. Termination: complex edges and
/// faces touch the mesh, so every added cell is an allocated cell not yet flawed; at most
/// `num_cells` rounds add anything.
pub(crate) fn grow(
    mesh: &LabeledMesh,
    grid: &Grid,
    materials: &Materials,
    region: &mut FlawedRegion,
    mut frontier: Vec<IVec3>,
) -> GrowthCounts {
    let mut counts = GrowthCounts::default();
    for _ in 0..=grid.num_cells() + 1 {
        if frontier.is_empty() {
            break;
        }
        counts.rounds += 1;
        let found: Vec<(Vec<IVec3>, usize, usize)> = frontier
            .par_iter()
            .fold(
                || (FaceScratch::new(), Vec::new(), 0, 0),
                |(mut scratch, mut add, mut cycles, mut bad), &c| {
                    for (face, nb) in cell_faces(c) {
                        if region.cells.contains(nb) {
                            continue;
                        }
                        let mut complex_edge = false;
                        for e in face.edges() {
                            if edge_is_complex(grid, materials, e) {
                                complex_edge = true;
                                add.extend(
                                    e.cells().into_iter().filter(|&x| !region.cells.contains(x)),
                                );
                            }
                        }
                        if !complex_edge {
                            let r = intersect_face(mesh, grid, materials, face, &mut scratch);
                            cycles += usize::from(r.cycle);
                            bad += usize::from(r.inconsistent);
                            if r.cycle || r.inconsistent {
                                add.push(nb);
                            }
                        }
                    }
                    (scratch, add, cycles, bad)
                },
            )
            .map(|(_, add, cycles, bad)| (add, cycles, bad))
            .collect();
        frontier.clear();
        for (add, cycles, bad) in found {
            counts.cycle_faces += cycles;
            counts.inconsistent_faces += bad;
            for c in add {
                if region.cells.insert(c) {
                    counts.grown += 1;
                    match grid.cell_id(c) {
                        Some(id) => region.flags[id.idx()].insert(CellFlaws::GROWN),
                        None => {
                            region.unallocated += 1;
                            region.loose.push((c, CellFlaws::GROWN));
                        }
                    }
                    frontier.push(c);
                }
            }
        }
    }
    counts
}

/// All faces between a flawed and an intact cell, sorted. Cells filled by [`flood`] are
/// skipped: all their neighbours are flawed (see there).
pub(crate) fn boundary_faces(grid: &Grid, region: &FlawedRegion) -> Vec<BoundaryFace> {
    let mut out: Vec<BoundaryFace> = (0..region.flags.len())
        .into_par_iter()
        .filter(|&i| !region.flags[i].is_empty())
        .map(|i| grid.cell_coord(crate::stages::grid::CellId::new(i as u32)))
        .chain(region.loose.par_iter().map(|l| l.0))
        .flat_map_iter(|c| {
            cell_faces(c)
                .into_iter()
                .filter(|(_, nb)| !region.cells.contains(*nb))
                .map(move |(face, nb)| BoundaryFace {
                    face,
                    flawed: c,
                    intact: nb,
                })
        })
        .collect();
    out.sort_unstable_by_key(|b| (b.face.node.to_array(), b.face.normal.index()));
    out.dedup();
    out
}
