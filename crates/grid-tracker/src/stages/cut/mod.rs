//! Stage 4 (§7 and Appendix A of Heiss-Synak et al. 2024): local mesh cutting — delete the
//! part of the mesh inside the flawed region, leaving an open intact mesh whose hole the
//! rebuild (§8) fills.
//!
//! Glossary:
//! - **trace**: a triangle's intersection with one flawed-boundary face, a segment between
//!   two cut points ([`crate::intersect_face`], Fig. 8), decided by exact predicates under
//!   the one symbolic perturbation of the grid;
//! - **cut point**: a *mesh-edge point* (a mesh edge pierces a boundary face; shared by
//!   every triangle around the edge) or a *grid-edge point* (a triangle crosses an edge of
//!   a boundary face; owned by that triangle) — see `points.rs`;
//! - **crossing triangle**: one with at least one trace segment. It is re-triangulated
//!   with its trace as constraints (`triangulate.rs`, a CDT per triangle as in Pavić et al.
//!   2010), its sub-triangles coloured flawed/intact by flood fill from its corners with
//!   no new numerical test (`classify.rs`), and only the intact ones kept;
//! - every other triangle lies wholly on one side: the side of the cell of its first
//!   vertex (under the perturbation a vertex on a grid plane lies in the cell below).
//!
//! The steps, in order ([`cut_mesh`]): trace the boundary faces → sort triangles into
//! untouched, removed and crossing → cut the crossing ones in parallel (per-worker CDT
//! and buffers) → apply serially to a clone of the mesh, creating one vertex per distinct
//! cut point, and collect each boundary face's segments for the fans of §8.2.
//!
//! Every local failure (a trace the triangulation cannot honour: crossing constraints,
//! coincident points, a colouring conflict, a spade refusal) is a [`CutError`] carrying
//! the cells where it happened ([`CutError::cells`]), so the tracker can grow the flawed
//! region there ([`crate::FlawedRegion::grow`]) and retry (§9.2).

mod classify;
mod points;
mod triangulate;

use std::collections::HashMap;
use std::collections::hash_map::Entry;

use glam::IVec3;
use mesh_core::{LabeledMesh, MeshError, TriId, VertexId};
use rayon::prelude::*;

use crate::stages::flaws::{BoundaryFace, FaceScratch, FlawedRegion, intersect_face};
use crate::stages::grid::primitives::{GridEdge, GridFace};
use crate::stages::grid::{CellId, Grid};
use crate::stages::materials::Materials;
use crate::stages::rebuild::{BoundarySegment, RebuildVertexKey};
use points::{PointKey, Quantum, vertex_cell};
use triangulate::{Batch, Context, TraceSegment, Workspace, cut_triangle};

/// Crossing triangles per parallel work item: large enough to amortise the scheduling,
/// small enough to balance two to a few dozen workers.
const CHUNK: usize = 64;

/// Options of [`cut_mesh`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CutOptions {
    /// Cut points are placed in each triangle's parameter frame on multiples of
    /// `2^−quantum_bits` (App. A's integer coordinates), which makes points on a triangle
    /// edge exactly collinear with it and identical in every triangle around the edge.
    /// Default 40 (points closer than ~1e-12 of an edge length collide and are reported).
    /// Must lie in `16..=50`.
    pub quantum_bits: u32,
    /// Bound on the points of one triangle's triangulation (corners + cut points); a
    /// triangle spanning more grid faces is reported ([`CutError::TooManyPoints`]).
    /// Default 4096. Must be at least 3.
    pub max_triangle_points: usize,
}

impl Default for CutOptions {
    fn default() -> Self {
        Self {
            quantum_bits: 40,
            max_triangle_points: 4096,
        }
    }
}

/// Counts describing a [`Cut`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CutStats {
    /// Live triangles of the input.
    pub triangles_in: usize,
    /// Triangles kept as they were (same id, vertices and labels).
    pub untouched: usize,
    /// Crossing triangles replaced by their intact sub-triangles.
    pub clipped: usize,
    /// Triangles wholly inside the flawed region, deleted.
    pub removed: usize,
    /// Intact sub-triangles created.
    pub sub_triangles: usize,
    /// Flawed sub-triangles discarded.
    pub flawed_sub_triangles: usize,
    /// Vertices created (cut points).
    pub cut_vertices: usize,
    /// Original vertices deleted because no triangle used them any more.
    pub removed_vertices: usize,
    /// Cut points the quantisation moved off a corner or off the triangle boundary: a
    /// mesh vertex on a grid plane or a grid line through a mesh edge. The cut stays
    /// consistent, but such points coincide (nearly) with mesh vertices in space.
    pub nudged_points: usize,
}

/// Why the mesh could not be cut.
///
/// Every variant that is a local inconsistency carries `cells`: the cells beside the
/// boundary faces where it happened (when several triangles fail, the union over all of
/// them, on the first error). Growing the flawed region by them moves the boundary away
/// and usually lets a retry succeed (§9.2).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CutError {
    /// Grid, materials, region and mesh do not belong together.
    #[error("mismatched inputs: {0}")]
    Mismatch(&'static str),
    /// An option is out of range.
    #[error("cut option {name} = {value} is invalid: must be {expected}")]
    BadOption {
        /// Option name.
        name: &'static str,
        /// Value given.
        value: u64,
        /// Valid range.
        expected: &'static str,
    },
    /// A boundary face is complex or flawed (the flaw stage should have grown past it).
    #[error("boundary face {face:?} is complex or flawed")]
    ComplexBoundaryFace {
        /// The face.
        face: GridFace,
        /// Cells where it happened.
        cells: Vec<IVec3>,
    },
    /// A trace end does not fit its triangle: a mesh edge not of the triangle, or a grid
    /// edge without the triangle among its crossings.
    #[error("triangle {tri}: a trace end does not belong to it")]
    MissingPoint {
        /// The triangle.
        tri: TriId,
        /// Cells where it happened.
        cells: Vec<IVec3>,
    },
    /// A triangle needs more points than [`CutOptions::max_triangle_points`].
    #[error("triangle {tri} needs more than {limit} cut points")]
    TooManyPoints {
        /// The triangle.
        tri: TriId,
        /// The configured limit.
        limit: usize,
        /// Cells where it happened.
        cells: Vec<IVec3>,
    },
    /// Two cut points of a triangle fall on one place of its quantised frame.
    #[error("triangle {tri}: two cut points coincide")]
    CoincidentPoints {
        /// The triangle.
        tri: TriId,
        /// Cells where it happened.
        cells: Vec<IVec3>,
    },
    /// Trace segments cross each other or run through a cut point in the triangle's frame.
    #[error("triangle {tri}: its trace segments cross or overlap")]
    ConstraintConflict {
        /// The triangle.
        tri: TriId,
        /// Cells where it happened.
        cells: Vec<IVec3>,
    },
    /// The flood fill reached a sub-triangle from both sides of the boundary.
    #[error("triangle {tri}: flawed/intact colouring conflict")]
    ColouringConflict {
        /// The triangle.
        tri: TriId,
        /// Cells where it happened.
        cells: Vec<IVec3>,
    },
    /// Spade refused a point.
    #[error("triangle {tri}: triangulation refused a point: {reason}")]
    Triangulation {
        /// The triangle.
        tri: TriId,
        /// Spade's message.
        reason: String,
        /// Cells where it happened.
        cells: Vec<IVec3>,
    },
    /// Editing the mesh failed (e.g. the id space is exhausted).
    #[error("mesh edit failed: {0}")]
    Mesh(#[from] MeshError),
}

impl CutError {
    /// The cells where a local inconsistency happened (empty for global errors): add them
    /// to the flawed region and retry.
    pub fn cells(&self) -> &[IVec3] {
        match self {
            CutError::ComplexBoundaryFace { cells, .. }
            | CutError::MissingPoint { cells, .. }
            | CutError::TooManyPoints { cells, .. }
            | CutError::CoincidentPoints { cells, .. }
            | CutError::ConstraintConflict { cells, .. }
            | CutError::ColouringConflict { cells, .. }
            | CutError::Triangulation { cells, .. } => cells,
            CutError::Mismatch(_) | CutError::BadOption { .. } | CutError::Mesh(_) => &[],
        }
    }

    fn cells_mut(&mut self) -> Option<&mut Vec<IVec3>> {
        match self {
            CutError::ComplexBoundaryFace { cells, .. }
            | CutError::MissingPoint { cells, .. }
            | CutError::TooManyPoints { cells, .. }
            | CutError::CoincidentPoints { cells, .. }
            | CutError::ConstraintConflict { cells, .. }
            | CutError::ColouringConflict { cells, .. }
            | CutError::Triangulation { cells, .. } => Some(cells),
            CutError::Mismatch(_) | CutError::BadOption { .. } | CutError::Mesh(_) => None,
        }
    }
}

/// The first of `errors` with the cells of all of them, or `Ok` when there are none.
fn merge_errors(errors: Vec<CutError>) -> Result<(), CutError> {
    let mut it = errors.into_iter();
    let Some(mut first) = it.next() else {
        return Ok(());
    };
    let mut extra: Vec<IVec3> = it.flat_map(|e| e.cells().to_vec()).collect();
    if let Some(cells) = first.cells_mut() {
        cells.append(&mut extra);
        cells.sort_unstable_by_key(|c| c.to_array());
        cells.dedup();
    }
    Err(first)
}

/// The result of [`cut_mesh`]: the intact part of the mesh and the boundary the rebuild
/// must meet.
#[derive(Clone, Debug)]
pub struct Cut {
    /// The intact part: the input mesh (cloned) with flawed-side triangles removed,
    /// crossing triangles replaced by their intact sub-triangles, and the cut vertices
    /// added. Surviving original vertices and untouched triangles keep their ids (new
    /// triangles may reuse the ids of removed ones; see [`Cut::new_triangles`]). Vertices
    /// left with no triangle are removed. The hole is open until the rebuild fills it;
    /// the corner table is linked, so adding the filling triangles relinks its edges.
    pub mesh: LabeledMesh,
    /// Cut vertices lying on grid edges (grid-edge points of boundary faces), for the
    /// sliding of §8.2.
    pub edge_points: Vec<(GridEdge, VertexId)>,
    /// Every vertex the cut created.
    pub new_vertices: Vec<VertexId>,
    /// Triangles created by the cut (intact sub-triangles).
    pub new_triangles: Vec<TriId>,
    /// Counts.
    pub stats: CutStats,
    /// The region's boundary faces, in its order.
    faces: Vec<BoundaryFace>,
    /// CSR: face `i`'s segments are `segments[face_start[i]..face_start[i + 1]]`.
    face_start: Vec<u32>,
    segments: Vec<BoundarySegment>,
}

impl Cut {
    /// The flawed-boundary faces, each with the flawed cell beside it and the segments of
    /// the clipped mesh lying in it: [`BoundarySegment`]s whose ends are
    /// [`RebuildVertexKey::Cut`]`(vertex index in self.mesh)`, oriented as the intact
    /// sub-triangle owning the segment traverses it, with that triangle's labels — the
    /// contract of [`crate::stages::rebuild::fan_boundary_face`]. Faces the mesh does not
    /// meet come with no segments.
    pub fn boundary(&self) -> impl Iterator<Item = (GridFace, IVec3, &[BoundarySegment])> + '_ {
        self.faces.iter().enumerate().map(|(i, f)| {
            let r = self.face_start[i] as usize..self.face_start[i + 1] as usize;
            (f.face, f.flawed, &self.segments[r])
        })
    }

    /// Number of boundary segments over all faces (each is one boundary edge of
    /// [`Cut::mesh`]).
    pub fn num_boundary_segments(&self) -> usize {
        self.segments.len()
    }
}

/// Cuts the flawed region out of `mesh` (§7, App. A): triangles crossing the flawed
/// boundary are clipped along it by a constrained Delaunay triangulation each, those
/// inside are deleted, the rest stay untouched.
///
/// Errors: inputs that do not belong together, a bad option, a mesh edit failure, or a
/// local inconsistency with the cells where it happened ([`CutError::cells`]).
pub fn cut_mesh(
    mesh: &LabeledMesh,
    grid: &Grid,
    materials: &Materials,
    region: &FlawedRegion,
    options: &CutOptions,
) -> Result<Cut, CutError> {
    check_inputs(mesh, grid, materials, options)?;
    let faces = region.boundary_faces();
    let trace = trace_boundary(mesh, grid, materials, faces)?;
    let sorted = sort_triangles(mesh, grid, region, &trace);
    let ctx = Context {
        mesh,
        grid,
        materials,
        region,
        faces,
        quantum: Quantum::new(options.quantum_bits),
        max_points: options.max_triangle_points,
    };
    let batches = cut_crossing_triangles(&ctx, &trace, &sorted.crossing);
    merge_errors(
        batches
            .iter()
            .flat_map(|b| b.errors.iter().cloned())
            .collect(),
    )?;
    apply(mesh, faces, &sorted, &batches)
}

fn check_inputs(
    mesh: &LabeledMesh,
    grid: &Grid,
    materials: &Materials,
    options: &CutOptions,
) -> Result<(), CutError> {
    if grid.triangle_capacity() != mesh.triangle_capacity() {
        return Err(CutError::Mismatch("the grid was built from another mesh"));
    }
    if materials.num_nodes() != grid.num_nodes() {
        return Err(CutError::Mismatch(
            "the materials were assigned on another grid",
        ));
    }
    if !(16..=50).contains(&options.quantum_bits) {
        return Err(CutError::BadOption {
            name: "quantum_bits",
            value: u64::from(options.quantum_bits),
            expected: "in 16..=50",
        });
    }
    if options.max_triangle_points < 3 {
        return Err(CutError::BadOption {
            name: "max_triangle_points",
            value: options.max_triangle_points as u64,
            expected: "at least 3",
        });
    }
    Ok(())
}

/// Every triangle's trace on every boundary face, sorted by (triangle, face).
fn trace_boundary(
    mesh: &LabeledMesh,
    grid: &Grid,
    materials: &Materials,
    faces: &[BoundaryFace],
) -> Result<Vec<TraceSegment>, CutError> {
    let parts: Vec<(Vec<TraceSegment>, Vec<CutError>)> = faces
        .par_iter()
        .enumerate()
        .fold(
            || (FaceScratch::new(), Vec::new(), Vec::new()),
            |(mut scratch, mut out, mut errors), (i, b)| {
                let report = intersect_face(mesh, grid, materials, b.face, &mut scratch);
                if report.cycle || report.inconsistent {
                    errors.push(CutError::ComplexBoundaryFace {
                        face: b.face,
                        cells: vec![b.flawed, b.intact],
                    });
                } else {
                    out.extend(scratch.segments().iter().map(|s| TraceSegment {
                        tri: s.tri,
                        face: i as u32,
                        ends: s.ends,
                    }));
                }
                (scratch, out, errors)
            },
        )
        .map(|(_, out, errors)| (out, errors))
        .collect();
    let mut errors = Vec::new();
    let mut trace = Vec::with_capacity(parts.iter().map(|p| p.0.len()).sum());
    for (out, errs) in parts {
        trace.extend(out);
        errors.extend(errs);
    }
    merge_errors(errors)?;
    // One segment per (triangle, face): the key is unique, so the order is deterministic.
    trace.sort_unstable_by_key(|s| (s.tri, s.face));
    Ok(trace)
}

/// The triangles by what happens to them.
struct Sorted {
    /// Crossing triangles with their range in the trace, in id order.
    crossing: Vec<(TriId, std::ops::Range<usize>)>,
    /// Triangles wholly inside the flawed region, in id order.
    removed: Vec<TriId>,
    /// Live triangles of the input.
    live: usize,
}

fn sort_triangles(
    mesh: &LabeledMesh,
    grid: &Grid,
    region: &FlawedRegion,
    trace: &[TraceSegment],
) -> Sorted {
    let mut crossing = Vec::new();
    let mut is_crossing = vec![false; mesh.triangle_capacity()];
    let mut i = 0;
    while i < trace.len() {
        let t = trace[i].tri;
        let run = trace[i..].iter().take_while(|s| s.tri == t).count();
        crossing.push((t, i..i + run));
        is_crossing[t.idx()] = true;
        i += run;
    }
    // A triangle is removed when its first vertex lies in a flawed cell; that cell is in
    // the triangle's closed cell range (`Lattice::cell_range` claims the cell below a
    // plane a box touches), so it is allocated and lists the triangle. Scanning the
    // flawed cells' lists finds each removed triangle exactly once, without visiting the
    // untouched bulk of the mesh.
    let lattice = grid.lattice();
    let is_crossing = &is_crossing;
    let mut removed: Vec<TriId> = if region.is_empty() {
        Vec::new()
    } else {
        (0..grid.num_cells() as u32)
            .into_par_iter()
            .map(CellId::new)
            .filter(|&c| region.is_flawed(grid.cell_coord(c)))
            .flat_map_iter(|c| {
                let coord = grid.cell_coord(c);
                grid.cell_triangles(c).iter().copied().filter(move |&t| {
                    !is_crossing[t.idx()]
                        && vertex_cell(lattice, mesh.position(mesh.tri(t)[0])) == coord
                })
            })
            .collect()
    };
    removed.par_sort_unstable();
    Sorted {
        crossing,
        removed,
        live: mesh.num_triangles(),
    }
}

/// Cuts every crossing triangle, in parallel chunks with per-worker buffers; the batches
/// come back in triangle order.
fn cut_crossing_triangles(
    ctx: &Context<'_>,
    trace: &[TraceSegment],
    crossing: &[(TriId, std::ops::Range<usize>)],
) -> Vec<Batch> {
    crossing
        .par_chunks(CHUNK)
        .map_init(Workspace::new, |ws, chunk| {
            let mut batch = Batch::default();
            for (t, r) in chunk {
                if let Err(e) = cut_triangle(ctx, *t, &trace[r.clone()], ws, &mut batch) {
                    batch.errors.push(e);
                }
            }
            batch
        })
        .collect()
}

/// Applies the cut to a clone of `mesh`: deletes removed and crossing triangles, adds one
/// vertex per distinct cut point and the intact sub-triangles, deletes orphaned vertices,
/// and files the boundary segments by face.
fn apply(
    mesh: &LabeledMesh,
    faces: &[BoundaryFace],
    sorted: &Sorted,
    batches: &[Batch],
) -> Result<Cut, CutError> {
    let mut out = mesh.clone();
    let gone = || {
        sorted
            .removed
            .iter()
            .copied()
            .chain(sorted.crossing.iter().map(|c| c.0))
    };
    for t in gone() {
        out.remove_triangle(t)?;
    }

    let mut shared: HashMap<(VertexId, VertexId, u32), VertexId> = HashMap::new();
    let mut local: Vec<VertexId> = Vec::new();
    let mut new_vertices = Vec::new();
    let mut new_triangles = Vec::new();
    let mut edge_points = Vec::new();
    let mut filed: Vec<(u32, BoundarySegment)> = Vec::new();
    let (mut nudged, mut flawed_subs) = (0, 0);
    for b in batches {
        nudged += b.nudged;
        flawed_subs += b.flawed_subs;
        for tc in &b.tris {
            let verts = mesh.tri(tc.tri);
            let labels = mesh.labels(tc.tri);
            local.clear();
            for &(key, pos) in &b.points[tc.points.clone()] {
                let v = match key {
                    PointKey::Corner(k) => verts[usize::from(k) % 3],
                    PointKey::MeshEdge { lo, hi, face } => match shared.entry((lo, hi, face)) {
                        Entry::Occupied(e) => *e.get(),
                        Entry::Vacant(e) => {
                            let v = out.add_vertex(pos)?;
                            new_vertices.push(v);
                            *e.insert(v)
                        }
                    },
                    PointKey::Grid(edge) => {
                        let v = out.add_vertex(pos)?;
                        new_vertices.push(v);
                        edge_points.push((edge, v));
                        v
                    }
                };
                local.push(v);
            }
            for s in &b.subs[tc.subs.clone()] {
                let t = out.add_triangle(s.map(|i| local[i as usize]), labels)?;
                new_triangles.push(t);
            }
            for s in &b.segments[tc.segments.clone()] {
                let key = |i: u32| RebuildVertexKey::Cut(local[i as usize].raw());
                filed.push((
                    s.face,
                    BoundarySegment {
                        from: key(s.from),
                        to: key(s.to),
                        labels,
                    },
                ));
            }
        }
    }

    let mut removed_vertices = 0;
    for t in gone() {
        for v in mesh.tri(t) {
            if out.is_vertex_alive(v) && out.vertex_triangles(v).next().is_none() {
                out.remove_vertex(v)?;
                removed_vertices += 1;
            }
        }
    }

    // File the segments by face (stable: triangle order within a face).
    filed.sort_by_key(|f| f.0);
    let mut face_start = vec![0u32; faces.len() + 1];
    for &(f, _) in &filed {
        face_start[f as usize + 1] += 1;
    }
    for i in 1..face_start.len() {
        face_start[i] += face_start[i - 1];
    }
    let stats = CutStats {
        triangles_in: sorted.live,
        untouched: sorted.live - sorted.removed.len() - sorted.crossing.len(),
        clipped: sorted.crossing.len(),
        removed: sorted.removed.len(),
        sub_triangles: new_triangles.len(),
        flawed_sub_triangles: flawed_subs,
        cut_vertices: new_vertices.len(),
        removed_vertices,
        nudged_points: nudged,
    };
    Ok(Cut {
        mesh: out,
        edge_points,
        new_vertices,
        new_triangles,
        stats,
        faces: faces.to_vec(),
        face_start,
        segments: filed.into_iter().map(|f| f.1).collect(),
    })
}

#[cfg(test)]
mod tests;
