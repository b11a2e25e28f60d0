//! Stage 5 (§8.2–§8.3 of Heiss-Synak et al. 2024): fill the hole the cutting stage left
//! with a new surface extracted from the node labels, welded to the clipped mesh.
//!
//! [`rebuild_region`], in the order of the paper:
//! 1. **triangles per flawed cell** (§8.2, parallel): octant triangles
//!    ([`triangulate_octants`]) for the internal faces, fans to the centre
//!    ([`fan_boundary_face`]) for the boundary faces; each cell writes into its worker's
//!    buffer, nothing is allocated per cell;
//! 2. **boundary check**: on every edge of a boundary face, the end labels differ exactly
//!    when the cut left a vertex there, and that vertex ends exactly one of the face's
//!    segments — what makes octant triangles and fans meet (§8.2, last paragraph; it
//!    holds when §6.4 left no complex edge or face on the boundary and the boundary
//!    nodes are physical). A violation is an error naming its cells, so the tracker can
//!    grow the region there and retry (§9.2);
//! 3. **weld** ([`Welder`]): the edge vertex of every grid edge with a cut vertex slides
//!    onto it ([`Welder::alias`]), equal keys become one vertex;
//! 4. **place** (§8.3, parallel): edge vertices by [`edge_vertex_position`], face and
//!    centre vertices at the average of their edge vertices ([`average_cell_points`]);
//! 5. **add** the vertices and triangles to the mesh (each addition relinks its edges);
//! 6. **smooth** the non-manifold curves through new vertices
//!    ([`smooth_nonmanifold_curves`]).
//!
//! Everything that can fail on the input is checked before the mesh is touched, so an
//! error leaves it as it was (only a `u32` overflow of the mesh's own ids, reported as
//! [`RebuildError::Mesh`], can strike midway).

use std::collections::HashMap;
use std::hash::BuildHasherDefault;

use glam::{DVec3, IVec3};
use mesh_core::{Label, LabeledMesh, MeshError, TriId, VertexId};
use rayon::prelude::*;

use super::fans::{BoundarySegment, FanError, fan_boundary_face};
use super::keys::{RebuildTriangle, RebuildVertexKey, cell_corners, cell_face_index};
use super::octants::{FaceMask, triangulate_octants};
use super::place::{average_cell_points, midpoint_position};
use super::position::edge_vertex_position;
use super::smooth_curves::{element_bounds, smooth_nonmanifold_curves};
use super::weld::{WeldError, Welder};
use crate::stages::flaws::FlawedRegion;
use crate::stages::grid::Grid;
use crate::stages::grid::primitives::{GridEdge, GridFace, cell_faces};
use crate::stages::grid::tiles::TileHasher;
use crate::stages::labels::NodeLabels;
use crate::stages::materials::Materials;

/// Options of [`rebuild_region`].
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RebuildOptions {
    /// Steps of non-manifold curve smoothing (§8.3). Default 10, the paper's. Zero
    /// switches it off.
    pub curve_smoothing_steps: usize,
    /// How far, as a fraction of ℓ, new vertices keep from the ends of their grid edge and
    /// the borders of their face or cell. Default 0.01. Must lie in `(0, 0.25]`: positive
    /// so that no triangle degenerates, small so that placement is barely constrained.
    pub margin: f64,
}

impl Default for RebuildOptions {
    fn default() -> Self {
        Self {
            curve_smoothing_steps: 10,
            margin: 0.01,
        }
    }
}

/// Counts describing a rebuild.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RebuildStats {
    /// Flawed cells processed.
    pub cells: usize,
    /// Octant triangles (internal faces).
    pub octant_triangles: usize,
    /// Fan triangles (boundary faces).
    pub fan_triangles: usize,
    /// Boundary faces of the region.
    pub boundary_faces: usize,
    /// Cut vertices the new triangles connect to (fan ends, and the cut vertices edge
    /// vertices slid onto).
    pub cut_vertices: usize,
    /// Vertices created.
    pub new_vertices: usize,
    /// Vertices moved by curve smoothing.
    pub smoothed_vertices: usize,
}

/// What [`rebuild_region`] added to the mesh.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RebuildReport {
    /// The vertices created (edge, face and centre vertices), in creation order.
    pub new_vertices: Vec<VertexId>,
    /// The triangles created.
    pub new_triangles: Vec<TriId>,
    /// Counts.
    pub stats: RebuildStats,
}

/// Why the region could not be rebuilt. Variants for local inconsistencies carry the
/// cells where they arose ([`RebuildError::cells`]): growing the region there and
/// restarting is the safety net of §9.2.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum RebuildError {
    /// Inputs that do not belong together.
    #[error("mismatched inputs: {0}")]
    Mismatch(&'static str),
    /// An option is out of range.
    #[error("rebuild option {name} = {value} is invalid: must be {expected}")]
    BadOption {
        /// Option name.
        name: &'static str,
        /// Value given.
        value: f64,
        /// Valid range.
        expected: &'static str,
    },
    /// A corner of a flawed cell has no label (the labels were computed for another
    /// region).
    #[error("grid node {node} of flawed cells {cells:?} has no label")]
    MissingLabel {
        /// The node.
        node: IVec3,
        /// The cells around it.
        cells: Vec<IVec3>,
    },
    /// A boundary entry names a face that is not between a flawed and an intact cell.
    #[error("face {face:?} given with cell {cell} is not a face of the flawed boundary")]
    NotBoundary {
        /// The face.
        face: GridFace,
        /// The cell it was given with.
        cell: IVec3,
        /// The cells beside the face.
        cells: Vec<IVec3>,
    },
    /// A boundary face's segments cannot be fanned.
    #[error("boundary face fan failed in cells {cells:?}: {source}")]
    Fan {
        /// What was wrong with the segments.
        source: FanError,
        /// The flawed cell and the intact cell beside the face.
        cells: Vec<IVec3>,
    },
    /// The labels and the cut disagree on a boundary edge: octant triangles and fans
    /// would not meet there.
    #[error("boundary edge {edge:?} in cells {cells:?}: {what}")]
    BoundaryMismatch {
        /// The grid edge.
        edge: GridEdge,
        /// Which disagreement.
        what: &'static str,
        /// The cells around the edge.
        cells: Vec<IVec3>,
    },
    /// Two cut vertices are given on one grid edge.
    #[error("grid edge {edge:?} has two cut vertices, {first} and {second}")]
    DuplicateEdgePoint {
        /// The edge.
        edge: GridEdge,
        /// One vertex.
        first: VertexId,
        /// The other.
        second: VertexId,
        /// The cells around the edge.
        cells: Vec<IVec3>,
    },
    /// A cut vertex id is not a live vertex of the mesh.
    #[error("cut vertex {vertex} is not a live vertex of the mesh (cells {cells:?})")]
    BadCutVertex {
        /// The id given.
        vertex: u32,
        /// Cells using it.
        cells: Vec<IVec3>,
    },
    /// Welding failed.
    #[error("welding failed in cells {cells:?}: {source}")]
    Weld {
        /// Why.
        source: WeldError,
        /// Where.
        cells: Vec<IVec3>,
    },
    /// The mesh refused an addition.
    #[error("adding to the mesh failed in cells {cells:?}: {source}")]
    Mesh {
        /// Why.
        source: MeshError,
        /// Where.
        cells: Vec<IVec3>,
    },
}

impl RebuildError {
    /// The cells where a local inconsistency arose (empty for global errors).
    pub fn cells(&self) -> &[IVec3] {
        match self {
            RebuildError::Mismatch(_) | RebuildError::BadOption { .. } => &[],
            RebuildError::MissingLabel { cells, .. }
            | RebuildError::NotBoundary { cells, .. }
            | RebuildError::Fan { cells, .. }
            | RebuildError::BoundaryMismatch { cells, .. }
            | RebuildError::DuplicateEdgePoint { cells, .. }
            | RebuildError::BadCutVertex { cells, .. }
            | RebuildError::Weld { cells, .. }
            | RebuildError::Mesh { cells, .. } => cells,
        }
    }

    fn cells_mut(&mut self) -> Option<&mut Vec<IVec3>> {
        match self {
            RebuildError::Mismatch(_) | RebuildError::BadOption { .. } => None,
            RebuildError::MissingLabel { cells, .. }
            | RebuildError::NotBoundary { cells, .. }
            | RebuildError::Fan { cells, .. }
            | RebuildError::BoundaryMismatch { cells, .. }
            | RebuildError::DuplicateEdgePoint { cells, .. }
            | RebuildError::BadCutVertex { cells, .. }
            | RebuildError::Weld { cells, .. }
            | RebuildError::Mesh { cells, .. } => Some(cells),
        }
    }
}

/// The first of `errors` with the cells of all of them (so one retry grows everywhere).
fn merge_errors(mut errors: Vec<RebuildError>) -> Result<(), RebuildError> {
    if errors.is_empty() {
        return Ok(());
    }
    let mut extra: Vec<IVec3> = errors
        .iter()
        .skip(1)
        .flat_map(|e| e.cells().iter().copied())
        .collect();
    let mut first = errors.swap_remove(0);
    if let Some(cells) = first.cells_mut() {
        cells.append(&mut extra);
        cells.sort_unstable_by_key(|c| c.to_array());
        cells.dedup();
    }
    Err(first)
}

/// A hash map from grid edges, with the grid's integer hasher.
type EdgeMap<V> = HashMap<GridEdge, V, BuildHasherDefault<TileHasher>>;

/// One face of the flawed boundary with the segments the cut left in it.
#[derive(Clone, Copy, Debug)]
struct Boundary<'a> {
    face: GridFace,
    flawed: IVec3,
    intact: IVec3,
    segments: &'a [BoundarySegment],
}

/// The flawed cells of an edge's four, as an error location.
fn edge_cells(region: &FlawedRegion, e: &GridEdge) -> Vec<IVec3> {
    e.cells()
        .into_iter()
        .filter(|&c| region.is_flawed(c))
        .collect()
}

/// The labels of a cell's corners, or the first corner without one.
fn corner_labels(labels: &NodeLabels, cell: IVec3) -> Result<[Label; 8], IVec3> {
    let nodes = cell_corners(cell);
    let mut out = [Label::OUTSIDE; 8];
    for (o, n) in out.iter_mut().zip(nodes) {
        *o = labels.label(n).ok_or(n)?;
    }
    Ok(out)
}

/// Adds the rebuilt triangles of every flawed cell to `mesh` (the cut mesh), welded to
/// its boundary (§8.2), places the new vertices (§8.3) and smooths the non-manifold curves
/// through them.
///
/// `boundary` yields every face of the flawed boundary the cut left segments in (faces
/// without segments may be omitted), with its flawed cell and the segments, whose ends are
/// [`RebuildVertexKey::Cut`]`(vertex index in mesh)`; `edge_points` the cut vertices on
/// grid edges of boundary faces. `labels` must come from [`crate::stages::labels::correct_labels`]
/// on the same region. `materials` is only checked against the grid: everything §8.3
/// needs from the original mesh is in `labels`.
///
/// Errors: mismatched inputs, a bad option, or a local inconsistency naming its cells
/// ([`RebuildError::cells`]); on error the mesh is unchanged (see the module docs for the
/// one exception).
#[allow(clippy::too_many_arguments)] // the contract with the cut stage: its pieces, apart
pub fn rebuild_region<'a>(
    mesh: &mut LabeledMesh,
    boundary: impl Iterator<Item = (GridFace, IVec3, &'a [BoundarySegment])>,
    edge_points: &[(GridEdge, VertexId)],
    grid: &Grid,
    materials: &Materials,
    region: &FlawedRegion,
    labels: &NodeLabels,
    options: &RebuildOptions,
) -> Result<RebuildReport, RebuildError> {
    if !(options.margin > 0.0 && options.margin <= 0.25) {
        return Err(RebuildError::BadOption {
            name: "margin",
            value: options.margin,
            expected: "in (0, 0.25]",
        });
    }
    if materials.num_nodes() != grid.num_nodes() {
        return Err(RebuildError::Mismatch(
            "the materials were assigned on another grid",
        ));
    }
    let lattice = *grid.lattice();
    let mut stats = RebuildStats::default();

    // The boundary, keyed by the region's own list of boundary faces.
    let faces = boundary_faces(region, boundary)?;
    stats.boundary_faces = faces.len();
    let edge_map = edge_point_map(mesh, region, edge_points)?;

    // 1. Triangles per flawed cell.
    let mut cells: Vec<IVec3> = region.cells().collect();
    cells.par_sort_unstable_by_key(|c| [c.z, c.y, c.x]);
    stats.cells = cells.len();
    let parts: Vec<CellPart> = cells
        .par_iter()
        .fold(CellPart::default, |mut part, &cell| {
            if let Err(e) = cell_triangles(cell, region, labels, &faces, &mut part) {
                part.errors.push(e);
            }
            part
        })
        .collect();
    merge_errors(
        parts
            .iter()
            .flat_map(|p| p.errors.iter().cloned())
            .collect(),
    )?;

    // 2. Labels and cut agree on every boundary edge.
    merge_errors(
        faces
            .par_iter()
            .filter_map(|b| check_boundary_face(b, region, labels, &edge_map).err())
            .collect(),
    )?;

    // 3. Weld: slide edge vertices onto cut vertices, then add every triangle.
    let mut welder = Welder::new();
    let mut slides: Vec<(&GridEdge, &VertexId)> = edge_map.iter().collect();
    slides.sort_unstable_by_key(|(e, _)| [e.node.z, e.node.y, e.node.x, e.axis.index() as i32]);
    for (e, v) in slides {
        welder
            .alias(RebuildVertexKey::Edge(*e), RebuildVertexKey::Cut(v.raw()))
            .map_err(|source| RebuildError::Weld {
                source,
                cells: edge_cells(region, e),
            })?;
    }
    let mut tri_cells: Vec<IVec3> = Vec::new();
    for part in &parts {
        stats.octant_triangles += part.octants;
        stats.fan_triangles += part.fans;
        for (t, &cell) in part.triangles.iter().zip(&part.cells) {
            welder.add(t).map_err(|source| RebuildError::Weld {
                source,
                cells: vec![cell],
            })?;
            tri_cells.push(cell);
        }
    }
    drop(parts);

    // 4. Place the new vertices.
    let keys = welder.keys();
    for k in keys {
        if let RebuildVertexKey::Cut(i) = *k {
            let v = VertexId::new(i);
            if !mesh.is_vertex_alive(v) {
                return Err(RebuildError::BadCutVertex {
                    vertex: i,
                    cells: cells_using(&welder, &tri_cells, *k),
                });
            }
        }
    }
    let place = Placement {
        mesh,
        lattice: &lattice,
        region,
        labels,
        edge_map: &edge_map,
        margin: options.margin,
    };
    let positions: Vec<Option<DVec3>> = keys.par_iter().map(|&k| place.position(k)).collect();
    stats.cut_vertices = keys
        .iter()
        .filter(|k| matches!(k, RebuildVertexKey::Cut(_)))
        .count();

    // 5. Add vertices and triangles.
    let mut ids: Vec<VertexId> = Vec::with_capacity(keys.len());
    let mut report = RebuildReport::default();
    for (&k, p) in keys.iter().zip(&positions) {
        let id = match (k, p) {
            (RebuildVertexKey::Cut(i), _) => VertexId::new(i),
            (_, Some(p)) => {
                let v = mesh.add_vertex(*p).map_err(|source| RebuildError::Mesh {
                    source,
                    cells: cells_using(&welder, &tri_cells, k),
                })?;
                report.new_vertices.push(v);
                v
            }
            (_, None) => {
                return Err(RebuildError::Weld {
                    source: WeldError::Unplaced { key: k },
                    cells: cells_using(&welder, &tri_cells, k),
                });
            }
        };
        ids.push(id);
    }
    for ((t, l), &cell) in welder
        .triangles()
        .iter()
        .zip(welder.labels())
        .zip(&tri_cells)
    {
        let verts = t.map(|i| ids[i as usize]);
        let id = mesh
            .add_triangle(verts, *l)
            .map_err(|source| RebuildError::Mesh {
                source,
                cells: vec![cell],
            })?;
        report.new_triangles.push(id);
    }
    stats.new_vertices = report.new_vertices.len();

    // 6. Smooth the non-manifold curves through new vertices.
    let movable: Vec<(VertexId, [DVec3; 2])> = keys
        .iter()
        .zip(&ids)
        .filter_map(|(&k, &v)| element_bounds(&lattice, k, options.margin).map(|b| (v, b)))
        .collect();
    stats.smoothed_vertices =
        smooth_nonmanifold_curves(mesh, &movable, options.curve_smoothing_steps);
    report.stats = stats;
    Ok(report)
}

/// The cells of the triangles using welded key `key` (an error location).
fn cells_using(welder: &Welder, tri_cells: &[IVec3], key: RebuildVertexKey) -> Vec<IVec3> {
    let Some(v) = welder.get(key) else {
        return Vec::new();
    };
    let mut out: Vec<IVec3> = welder
        .triangles()
        .iter()
        .zip(tri_cells)
        .filter(|(t, _)| t.contains(&v))
        .map(|(_, &c)| c)
        .collect();
    out.sort_unstable_by_key(|c| c.to_array());
    out.dedup();
    out
}

/// The region's boundary faces, sorted by flawed cell, each with the segments `given`
/// for it (none if not given). Every given face must be a boundary face of its cell.
fn boundary_faces<'a>(
    region: &FlawedRegion,
    given: impl Iterator<Item = (GridFace, IVec3, &'a [BoundarySegment])>,
) -> Result<Vec<Boundary<'a>>, RebuildError> {
    let mut faces: Vec<Boundary<'a>> = region
        .boundary_faces()
        .iter()
        .map(|b| Boundary {
            face: b.face,
            flawed: b.flawed,
            intact: b.intact,
            segments: &[],
        })
        .collect();
    let key = |cell: IVec3, face: &GridFace| {
        (
            [cell.z, cell.y, cell.x],
            [
                face.node.z,
                face.node.y,
                face.node.x,
                face.normal.index() as i32,
            ],
        )
    };
    faces.sort_unstable_by_key(|b| key(b.flawed, &b.face));
    for (face, cell, segments) in given {
        match faces.binary_search_by_key(&key(cell, &face), |b| key(b.flawed, &b.face)) {
            Ok(i) => faces[i].segments = segments,
            Err(_) => {
                return Err(RebuildError::NotBoundary {
                    face,
                    cell,
                    cells: face.cells().to_vec(),
                });
            }
        }
    }
    Ok(faces)
}

/// Cut vertices by grid edge, checked: live, one per edge.
fn edge_point_map(
    mesh: &LabeledMesh,
    region: &FlawedRegion,
    edge_points: &[(GridEdge, VertexId)],
) -> Result<EdgeMap<VertexId>, RebuildError> {
    let mut map: EdgeMap<VertexId> = EdgeMap::default();
    map.reserve(edge_points.len());
    for &(e, v) in edge_points {
        if !mesh.is_vertex_alive(v) {
            return Err(RebuildError::BadCutVertex {
                vertex: v.raw(),
                cells: edge_cells(region, &e),
            });
        }
        if let Some(&first) = map.get(&e)
            && first != v
        {
            return Err(RebuildError::DuplicateEdgePoint {
                edge: e,
                first,
                second: v,
                cells: edge_cells(region, &e),
            });
        }
        map.insert(e, v);
    }
    Ok(map)
}

/// One worker's triangles, with the cell of each.
#[derive(Default)]
struct CellPart {
    triangles: Vec<RebuildTriangle>,
    cells: Vec<IVec3>,
    octants: usize,
    fans: usize,
    errors: Vec<RebuildError>,
}

/// §8.2 for one flawed cell: octant triangles for its internal faces, fans for its
/// boundary faces, appended to `part`.
fn cell_triangles(
    cell: IVec3,
    region: &FlawedRegion,
    labels: &NodeLabels,
    faces: &[Boundary<'_>],
    part: &mut CellPart,
) -> Result<(), RebuildError> {
    let corner = corner_labels(labels, cell).map_err(|node| RebuildError::MissingLabel {
        node,
        cells: vec![cell],
    })?;
    let mut internal = FaceMask::NONE;
    for (j, (_, nb)) in cell_faces(cell).iter().enumerate() {
        if region.is_flawed(*nb) {
            internal = internal.with(j as u8);
        }
    }
    let start = part.triangles.len();
    part.octants += triangulate_octants(cell, &corner, internal, &mut part.triangles);
    let key = [cell.z, cell.y, cell.x];
    let first = faces.partition_point(|b| [b.flawed.z, b.flawed.y, b.flawed.x] < key);
    for b in faces[first..].iter().take_while(|b| b.flawed == cell) {
        if cell_face_index(cell, &b.face).is_none() {
            return Err(RebuildError::NotBoundary {
                face: b.face,
                cell,
                cells: vec![cell],
            });
        }
        part.fans +=
            fan_boundary_face(cell, b.face, b.segments, &mut part.triangles).map_err(|source| {
                RebuildError::Fan {
                    source,
                    cells: vec![b.flawed, b.intact],
                }
            })?;
    }
    let added = part.triangles.len() - start;
    part.cells.extend(std::iter::repeat_n(cell, added));
    Ok(())
}

/// §8.2's condition for octant triangles and fans to meet on boundary face `b`: on each
/// of its edges, the end labels differ exactly when the cut left a vertex there, and that
/// vertex ends exactly one of the face's segments.
fn check_boundary_face(
    b: &Boundary<'_>,
    region: &FlawedRegion,
    labels: &NodeLabels,
    edge_map: &EdgeMap<VertexId>,
) -> Result<(), RebuildError> {
    for e in b.face.edges() {
        let mismatch = |what| RebuildError::BoundaryMismatch {
            edge: e,
            what,
            cells: edge_cells(region, &e),
        };
        let (la, lb) = (labels.label(e.node), labels.label(e.end()));
        let (Some(la), Some(lb)) = (la, lb) else {
            return Err(RebuildError::MissingLabel {
                node: if la.is_none() { e.node } else { e.end() },
                cells: vec![b.flawed],
            });
        };
        match (la != lb, edge_map.get(&e)) {
            (true, None) => return Err(mismatch("end labels differ but the cut left no vertex")),
            (false, Some(_)) => return Err(mismatch("the cut left a vertex but end labels agree")),
            (true, Some(v)) => {
                let key = RebuildVertexKey::Cut(v.raw());
                let ends = b
                    .segments
                    .iter()
                    .filter(|s| s.from == key || s.to == key)
                    .count();
                if ends != 1 {
                    return Err(mismatch("the cut vertex does not end exactly one segment"));
                }
            }
            (false, None) => {}
        }
    }
    Ok(())
}

/// §8.3 placement of welded keys.
struct Placement<'a> {
    mesh: &'a LabeledMesh,
    lattice: &'a crate::stages::grid::Lattice,
    region: &'a FlawedRegion,
    labels: &'a NodeLabels,
    edge_map: &'a EdgeMap<VertexId>,
    margin: f64,
}

impl Placement<'_> {
    /// The vertex on edge `e`: the cut vertex if there is one, else §8.3's point.
    fn edge_point(&self, e: &GridEdge) -> DVec3 {
        match self.edge_map.get(e) {
            Some(&v) => self.mesh.position(v),
            None => edge_vertex_position(self.lattice, self.labels, e, self.margin),
        }
    }

    /// The position of a new vertex; `None` for cut vertices (already placed) and keys
    /// whose cell has unlabelled corners (checked earlier, so never). A face or centre
    /// vertex without edge vertices around it (only possible when a fan reaches a cell
    /// whose corners share one label, which the boundary check rules out) sits at the
    /// element's centre.
    fn position(&self, key: RebuildVertexKey) -> Option<DVec3> {
        let m = self.margin * self.lattice.cell_size;
        let inside = |p: DVec3, lo: IVec3, hi: IVec3, free: DVec3| {
            let (a, b) = (
                self.lattice.node_position(lo),
                self.lattice.node_position(hi),
            );
            p.clamp(a + free * m, b - free * m)
        };
        match key {
            RebuildVertexKey::Cut(_) => None,
            RebuildVertexKey::Edge(e) => Some(self.edge_point(&e)),
            RebuildVertexKey::Face(f) => {
                // One canonical cell beside the face, so the average is computed once.
                let [below, above] = f.cells();
                let cell = if self.region.is_flawed(above) {
                    above
                } else {
                    below
                };
                let j = cell_face_index(cell, &f)?;
                let corner = corner_labels(self.labels, cell).ok()?;
                let p = average_cell_points(cell, &corner, |e| self.edge_point(&e)).faces
                    [usize::from(j)]
                .or_else(|| midpoint_position(self.lattice, key))?;
                let (b, c) = f.normal.others();
                let mut far = f.node;
                far[b] += 1;
                far[c] += 1;
                let mut free = DVec3::ZERO;
                free[b] = 1.0;
                free[c] = 1.0;
                Some(inside(p, f.node, far, free))
            }
            RebuildVertexKey::Cell(c) => {
                let corner = corner_labels(self.labels, c).ok()?;
                let p = average_cell_points(c, &corner, |e| self.edge_point(&e))
                    .centre
                    .or_else(|| midpoint_position(self.lattice, key))?;
                Some(inside(p, c, c + IVec3::ONE, DVec3::ONE))
            }
        }
    }
}
