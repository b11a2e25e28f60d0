//! Stage 3 (§6 of Heiss-Synak et al. 2024): the flawed region — the grid cells whose mesh
//! will be cut away and rebuilt.
//!
//! Glossary (§6):
//! - **non-physical cell** (§6.1): one of the eight cells around a node with a mixed
//!   vector, or one of the four cells around an edge along which the vector becomes
//!   mixed after a crossing. Where such a node borders unallocated cells, the
//!   non-physical volume continues through them (the inside of an overlap has no mesh):
//!   those cells are flooded into the region too (whole empty tiles at a time).
//! - **complex edge**: crossed by more than one triangle. **Complex face**: its mesh
//!   intersection has a cycle, or it borders a complex edge ([`face`]). **Complex cell**:
//!   holds a closed volume (a region shell inside one cell, found from
//!   [`crate::Grid::single_cell_triangles`]) or borders a complex face.
//! - **deep / shallow edge** (§6.3): a complex edge not next to a non-physical cell is
//!   shallow when every label along it is the label of a physical node within Manhattan
//!   distance 2ℓ, deep otherwise. A **deep cell** is a complex cell with a deep edge —
//!   exactly the four cells around each deep edge (a complex edge makes its four faces,
//!   hence its four cells, complex). Complex cells without deep edges, including those
//!   holding a closed volume, stay intact (small features persist), unless
//!   [`FlawOptions::remesh_closed_volumes`].
//! - **flawed vertex** (§5, §6.4): a node where rays along x, y, z disagree; its eight
//!   cells join. **Flawed face** (Fig. 8): a triangle meets it in other than two points.
//!   With the exact predicates used here both arise only from broken input (holes).
//! - **growth** (§6.4): while a boundary face of the region is complex or flawed, or one
//!   of its edges is complex, the cells around it join.
//!
//! Only boundary faces are ever intersected with the mesh (growth and the cutting stage
//! need nothing else), so complex faces and cells inside the intact or flawed region are
//! not enumerated.
//!
//! Entry point: [`detect_flaws`]; [`FlawedRegion::grow`] re-grows after a later stage
//! adds cells (the safety net of §9.2).

mod closed;
mod edges;
pub mod face;
mod growth;

use std::sync::atomic::{AtomicU8, Ordering::Relaxed};

use glam::IVec3;
use mesh_core::LabeledMesh;
use rayon::prelude::*;

pub use face::{
    FacePoint, FaceReport, FaceScratch, FaceSegment, intersect_face, segment_pierces_face,
};

use crate::stages::grid::primitives::{GridFace, node_cells};
use crate::stages::grid::tiles::CellSet;
use crate::stages::grid::{CellId, Grid, NodeId};
use crate::stages::materials::Materials;

/// Which part of the surface a step rebuilds on the grid: the research ablation of the
/// 2024 paper's Fig. 17. The tracker applies it after [`detect_flaws`] (see
/// `GridParams::resampling`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Resampling {
    /// Only the flawed region (§6): the paper's method, which keeps every triangle outside
    /// it exactly.
    #[default]
    Local,
    /// Every allocated cell, i.e. every cell a triangle's box touches, counts as flawed,
    /// so the whole surface is cut out and rebuilt from the grid labels every step (Fig.
    /// 17b, "global resampling"): what a purely implicit tracker does, and what degrades
    /// surface detail below a few cells.
    Global,
}

/// Options of [`detect_flaws`].
#[derive(Clone, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FlawOptions {
    /// Manhattan radius, in cells, within which the deep test looks for the labels of a
    /// complex edge (§6.3). Default 2 (the paper's 2ℓ). Must lie in `0..=8`.
    pub deep_radius: i32,
    /// Also remesh cells holding a closed volume (a shell smaller than a cell). Default
    /// false: the paper keeps complex cells without deep edges intact.
    pub remesh_closed_volumes: bool,
    /// Bound on unallocated cells the region may take from the inside of overlaps, about
    /// 1 bit each plus ~100 bytes per 8³ tile. Default 2²⁶ (~67 M cells, under 100 MB).
    pub max_unallocated_cells: usize,
    /// The deep-cell test of §6.3 (Fig. 9). Default true. Off, every complex edge not
    /// next to a non-physical cell counts as deep, so every complex cell is remeshed —
    /// the "overzealous re-sampling" of small surface bumps the test exists to avoid (a
    /// research ablation).
    pub deep_cell_test: bool,
}

impl Default for FlawOptions {
    fn default() -> Self {
        Self {
            deep_radius: 2,
            remesh_closed_volumes: false,
            max_unallocated_cells: 1 << 26,
            deep_cell_test: true,
        }
    }
}

/// Why flaws could not be detected.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FlawError {
    /// Grid, materials and mesh do not belong together.
    #[error("mismatched inputs: {0}")]
    Mismatch(&'static str),
    /// An option is out of range.
    #[error("flaw option {name} = {value} is invalid: must be {expected}")]
    BadOption {
        /// Option name.
        name: &'static str,
        /// Value given.
        value: i64,
        /// Valid range.
        expected: &'static str,
    },
    /// The non-physical volume exceeds [`FlawOptions::max_unallocated_cells`].
    #[error("the flawed region needs more than {limit} unallocated cells; raise ℓ or the limit")]
    TooManyUnallocated {
        /// The configured limit.
        limit: usize,
    },
}

/// Why a cell is flawed (a set of reasons; empty = intact).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct CellFlaws(u8);

impl CellFlaws {
    /// Around a mixed node or a mixed stretch of an edge (§6.1).
    pub const NON_PHYSICAL: CellFlaws = CellFlaws(1);
    /// Around a node where the three ray axes disagree (§6.4).
    pub const FLAWED_VERTEX: CellFlaws = CellFlaws(2);
    /// Around a deep edge (§6.3).
    pub const DEEP: CellFlaws = CellFlaws(4);
    /// Holds a closed volume, with [`FlawOptions::remesh_closed_volumes`].
    pub const CLOSED_VOLUME: CellFlaws = CellFlaws(8);
    /// Added by growth to clear the boundary of complex edges and faces (§6.4).
    pub const GROWN: CellFlaws = CellFlaws(16);
    /// Added by the caller through [`FlawedRegion::grow`].
    pub const SEED: CellFlaws = CellFlaws(32);

    /// No reason: intact.
    pub fn is_empty(self) -> bool {
        self.0 == 0
    }

    /// Whether all reasons of `other` are present.
    pub fn contains(self, other: CellFlaws) -> bool {
        self.0 & other.0 == other.0
    }

    /// Whether any reason of `other` is present.
    pub fn intersects(self, other: CellFlaws) -> bool {
        self.0 & other.0 != 0
    }

    /// Adds the reasons of `other`.
    pub fn insert(&mut self, other: CellFlaws) {
        self.0 |= other.0;
    }
}

impl std::ops::BitOr for CellFlaws {
    type Output = CellFlaws;
    fn bitor(self, rhs: CellFlaws) -> CellFlaws {
        CellFlaws(self.0 | rhs.0)
    }
}

/// A face of the flawed boundary, between a flawed and an intact cell.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BoundaryFace {
    /// The face.
    pub face: GridFace,
    /// The flawed cell beside it.
    pub flawed: IVec3,
    /// The intact cell beside it.
    pub intact: IVec3,
}

/// Counts describing a [`FlawedRegion`] and how it came about.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FlawStats {
    /// Allocated cells flagged non-physical.
    pub non_physical_cells: usize,
    /// Allocated cells around flawed vertices.
    pub flawed_vertex_cells: usize,
    /// Allocated cells around deep edges.
    pub deep_cells: usize,
    /// Cells holding a closed volume (flawed only with the option).
    pub closed_volume_cells: usize,
    /// Cells added by growth.
    pub grown_cells: usize,
    /// Unallocated flawed cells (inside overlaps).
    pub unallocated_cells: usize,
    /// All flawed cells.
    pub flawed_cells: usize,
    /// Grid edges along which the vector turns non-physical.
    pub non_physical_edges: usize,
    /// Complex edges in the grid.
    pub complex_edges: usize,
    /// Complex edges given the deep test (not next to a non-physical cell).
    pub tested_edges: usize,
    /// Deep edges.
    pub deep_edges: usize,
    /// Boundary faces found with a cycle during growth.
    pub cycle_faces: usize,
    /// Boundary faces found inconsistent (Fig. 8) during growth.
    pub inconsistent_faces: usize,
    /// Growth rounds.
    pub growth_rounds: usize,
    /// Faces of the final flawed boundary.
    pub boundary_faces: usize,
}

/// The flawed region: which cells to remesh, why, and its boundary.
#[derive(Clone, Debug)]
pub struct FlawedRegion {
    /// Every flawed cell, allocated or not.
    cells: CellSet,
    /// Reasons per allocated cell (by [`CellId`]).
    flags: Vec<CellFlaws>,
    /// Unallocated flawed cells not enclosed by the flood (their faces need checking).
    loose: Vec<(IVec3, CellFlaws)>,
    unallocated: usize,
    closed_volumes: Vec<CellId>,
    boundary: Vec<BoundaryFace>,
    stats: FlawStats,
}

impl FlawedRegion {
    /// Whether lattice cell `c` is flawed.
    pub fn is_flawed(&self, c: IVec3) -> bool {
        self.cells.contains(c)
    }

    /// Why allocated cell `c` is flawed (empty when intact).
    pub fn flaws(&self, c: CellId) -> CellFlaws {
        self.flags[c.idx()]
    }

    /// Every flawed cell, allocated or not, in no particular order.
    pub fn cells(&self) -> impl Iterator<Item = IVec3> + '_ {
        self.cells.iter()
    }

    /// Number of flawed cells.
    pub fn len(&self) -> usize {
        self.cells.len()
    }

    /// True when nothing needs remeshing.
    pub fn is_empty(&self) -> bool {
        self.cells.is_empty()
    }

    /// Faces between flawed and intact cells, sorted: where the cutting stage clips the
    /// mesh ([`intersect_face`] gives each one's segments).
    pub fn boundary_faces(&self) -> &[BoundaryFace] {
        &self.boundary
    }

    /// Cells holding a closed volume (complex cells of the third kind), flawed or not.
    pub fn closed_volume_cells(&self) -> &[CellId] {
        &self.closed_volumes
    }

    /// Counts.
    pub fn stats(&self) -> FlawStats {
        self.stats
    }

    /// Adds `extra` cells (e.g. where a later stage found an inconsistency, §9.2), grows
    /// until the boundary is clean again, and recomputes the boundary.
    pub fn grow(
        &mut self,
        mesh: &LabeledMesh,
        grid: &Grid,
        materials: &Materials,
        extra: &[IVec3],
    ) {
        let mut frontier = Vec::new();
        for &c in extra {
            if self.cells.insert(c) {
                match grid.cell_id(c) {
                    Some(id) => self.flags[id.idx()].insert(CellFlaws::SEED),
                    None => {
                        self.unallocated += 1;
                        self.loose.push((c, CellFlaws::SEED));
                    }
                }
                frontier.push(c);
            }
        }
        let counts = growth::grow(mesh, grid, materials, self, frontier);
        self.finish(grid, counts);
    }

    fn finish(&mut self, grid: &Grid, counts: growth::GrowthCounts) {
        self.boundary = growth::boundary_faces(grid, self);
        let count = |f: CellFlaws| self.flags.par_iter().filter(|x| x.intersects(f)).count();
        self.stats = FlawStats {
            non_physical_cells: count(CellFlaws::NON_PHYSICAL),
            flawed_vertex_cells: count(CellFlaws::FLAWED_VERTEX),
            deep_cells: count(CellFlaws::DEEP),
            grown_cells: self.stats.grown_cells + counts.grown,
            unallocated_cells: self.unallocated,
            flawed_cells: self.cells.len(),
            cycle_faces: self.stats.cycle_faces + counts.cycle_faces,
            inconsistent_faces: self.stats.inconsistent_faces + counts.inconsistent_faces,
            growth_rounds: self.stats.growth_rounds + counts.rounds,
            boundary_faces: self.boundary.len(),
            ..self.stats
        };
    }
}

/// Finds the flawed region (§6): non-physical cells (and the non-physical volume they
/// border), cells around flawed vertices and deep edges, then growth until the boundary
/// has no complex or flawed edge or face.
///
/// Errors: inputs that do not belong together, a bad option, or a non-physical volume
/// larger than [`FlawOptions::max_unallocated_cells`].
pub fn detect_flaws(
    mesh: &LabeledMesh,
    grid: &Grid,
    materials: &Materials,
    options: &FlawOptions,
) -> Result<FlawedRegion, FlawError> {
    if grid.triangle_capacity() != mesh.triangle_capacity() {
        return Err(FlawError::Mismatch("the grid was built from another mesh"));
    }
    if materials.num_nodes() != grid.num_nodes() {
        return Err(FlawError::Mismatch(
            "the materials were assigned on another grid",
        ));
    }
    if !(0..=8).contains(&options.deep_radius) {
        return Err(FlawError::BadOption {
            name: "deep_radius",
            value: i64::from(options.deep_radius),
            expected: "in 0..=8",
        });
    }
    let flags: Vec<AtomicU8> = (0..grid.num_cells()).map(|_| AtomicU8::new(0)).collect();
    let mark = |c: IVec3, f: CellFlaws| {
        grid.cell_id(c)
            .map(|id| flags[id.idx()].fetch_or(f.0, Relaxed))
            .is_some()
    };

    // §6.1, §6.4: cells around mixed and flawed nodes, and along mixed stretches of edges.
    let (flood_seeds, loose) = flag_nodes(grid, materials, &mark);
    let np_edges = edges::non_physical_edges(mesh, grid, materials);
    for e in &np_edges {
        for c in e.cells() {
            mark(c, CellFlaws::NON_PHYSICAL);
        }
    }
    // §6.2–6.3: cells around deep edges.
    let bad = CellFlaws::NON_PHYSICAL | CellFlaws::FLAWED_VERTEX;
    let deep = edges::deep_edges(
        mesh,
        grid,
        materials,
        options.deep_radius,
        options.deep_cell_test,
        |c| {
            grid.cell_id(c)
                .is_some_and(|id| CellFlaws(flags[id.idx()].load(Relaxed)).intersects(bad))
        },
    );
    for e in &deep.deep {
        for c in e.cells() {
            mark(c, CellFlaws::DEEP);
        }
    }
    let closed_volumes = closed::closed_volume_cells(mesh, grid);
    if options.remesh_closed_volumes {
        for &c in &closed_volumes {
            flags[c.idx()].fetch_or(CellFlaws::CLOSED_VOLUME.0, Relaxed);
        }
    }

    let mut region = FlawedRegion {
        cells: CellSet::new(),
        flags: flags
            .into_iter()
            .map(|a| CellFlaws(a.into_inner()))
            .collect(),
        loose: Vec::new(),
        unallocated: 0,
        stats: FlawStats {
            closed_volume_cells: closed_volumes.len(),
            non_physical_edges: np_edges.len(),
            complex_edges: deep.complex,
            tested_edges: deep.tested,
            deep_edges: deep.deep.len(),
            ..FlawStats::default()
        },
        closed_volumes,
        boundary: Vec::new(),
    };
    let mut frontier: Vec<IVec3> = Vec::new();
    for (i, f) in region.flags.iter().enumerate() {
        if !f.is_empty() {
            let c = grid.cell_coord(CellId::new(i as u32));
            region.cells.insert(c);
            frontier.push(c);
        }
    }
    // §6.1: the non-physical volume beyond the band.
    growth::flood(
        grid,
        materials,
        &mut region,
        &flood_seeds,
        options.max_unallocated_cells,
    )?;
    for (c, f) in loose {
        if region.cells.insert(c) {
            region.unallocated += 1;
            region.loose.push((c, f));
            frontier.push(c);
        }
    }
    // §6.4: grow until the boundary is clean.
    let counts = growth::grow(mesh, grid, materials, &mut region, frontier);
    region.finish(grid, counts);
    Ok(region)
}

/// Flags the allocated cells around mixed and flawed nodes through `mark` (which returns
/// false for an unallocated cell) and returns the unallocated ones: flood seeds (around
/// mixed nodes) and loose cells (around flawed nodes whose x vector is physical).
fn flag_nodes(
    grid: &Grid,
    materials: &Materials,
    mark: &(impl Fn(IVec3, CellFlaws) -> bool + Sync),
) -> (Vec<IVec3>, Vec<(IVec3, CellFlaws)>) {
    (0..grid.num_nodes() as u32)
        .into_par_iter()
        .map(NodeId::new)
        .fold(
            || (Vec::new(), Vec::new()),
            |(mut seeds, mut loose), n| {
                let mixed = !materials.node_material(n).is_physical();
                let flawed = materials.is_flawed(n);
                if !(mixed || flawed) {
                    return (seeds, loose);
                }
                let mut f = CellFlaws::default();
                if mixed {
                    f.insert(CellFlaws::NON_PHYSICAL);
                }
                if flawed {
                    f.insert(CellFlaws::FLAWED_VERTEX);
                }
                for c in node_cells(grid.node_coord(n)) {
                    if mark(c, f) {
                        continue;
                    }
                    if mixed {
                        seeds.push(c);
                    } else {
                        loose.push((c, f));
                    }
                }
                (seeds, loose)
            },
        )
        .reduce(
            || (Vec::new(), Vec::new()),
            |(mut a, mut b), (c, d)| {
                a.extend(c);
                b.extend(d);
                (a, b)
            },
        )
}

#[cfg(test)]
mod tests;
