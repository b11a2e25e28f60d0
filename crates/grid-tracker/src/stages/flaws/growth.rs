//! Growing the flawed region: through unallocated non-physical space (§6.1), then until
//! its boundary has no complex edge or face (§6.4).

use glam::IVec3;
use mesh_core::LabeledMesh;
use rayon::prelude::*;

use super::face::{FaceScratch, intersect_face};
use super::{BoundaryFace, CellFlaws, FlawError, FlawedRegion};
use crate::stages::grid::Grid;
use crate::stages::grid::primitives::{GridEdge, cell_faces};
use crate::stages::grid::tiles::{TILE, TILE_LOG2, split};
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
/// Tiles without allocated cells join whole, so a large overlap volume costs per tile,
/// not per cell.
///
/// A broken mesh (holes: the materials have flawed nodes) breaks the constancy argument —
/// a hole's "shadow" along a ray is non-physical up to infinity — so then each cell's own
/// vector is checked ([`Materials::material_at`]) before it joins. The clamp and
/// [`FlawError::TooManyUnallocated`] bound the work either way.
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
    let inside = |c: IVec3| c.cmpge(lo).all() && c.cmple(hi).all();
    let joins = |c: IVec3| {
        inside(c)
            && grid.cell_id(c).is_none()
            && (!check || !materials.material_at(grid, c).is_physical())
    };
    // A whole tile without allocated cells, inside the bounds, is one face-connected block
    // of unallocated cells: it joins at once (not with broken input, checked per cell).
    let whole_uncached = |t: IVec3| {
        !check
            && inside(t << TILE_LOG2)
            && inside((t << TILE_LOG2) + IVec3::splat(TILE - 1))
            && grid.tile_is_empty(t)
    };
    // Neighbours mostly share the tile of the cell they come from: remember the last one.
    let last = std::cell::Cell::new((IVec3::MAX, false));
    let whole = |t: IVec3| {
        let (lt, lw) = last.get();
        if lt == t {
            return lw;
        }
        let w = whole_uncached(t);
        last.set((t, w));
        w
    };
    enum Item {
        Cell(IVec3),
        Tile(IVec3),
    }
    let mut stack: Vec<Item> = Vec::new();
    // Queues `c`, or its whole tile; returns the number of cells added.
    let add = |region: &mut FlawedRegion, stack: &mut Vec<Item>, c: IVec3| {
        let t = split(c).0;
        if whole(t) {
            if !region.cells.contains(t << TILE_LOG2) {
                stack.push(Item::Tile(t));
                return region.cells.insert_tile(t);
            }
        } else if joins(c) && region.cells.insert(c) {
            stack.push(Item::Cell(c));
            return 1;
        }
        0
    };
    for &s in seeds {
        region.unallocated += add(region, &mut stack, s);
    }
    while let Some(item) = stack.pop() {
        if region.unallocated > limit {
            return Err(FlawError::TooManyUnallocated { limit });
        }
        match item {
            Item::Cell(c) => {
                for (_, nb) in cell_faces(c) {
                    region.unallocated += add(region, &mut stack, nb);
                }
            }
            Item::Tile(t) => {
                // The cells just across each of the tile's six faces.
                let base = t << TILE_LOG2;
                for axis in 0..3 {
                    let (b, c) = ((axis + 1) % 3, (axis + 2) % 3);
                    for (side, offset) in [(0, -1), (TILE - 1, 1)] {
                        for u in 0..TILE {
                            for v in 0..TILE {
                                let mut nb = base;
                                nb[axis] += side + offset;
                                nb[b] += u;
                                nb[c] += v;
                                region.unallocated += add(region, &mut stack, nb);
                            }
                        }
                    }
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
