//! One triangle's constrained Delaunay triangulation (App. A, after Pavić et al. 2010).
//!
//! A triangle crossing the flawed boundary is triangulated in its parameter frame
//! ([`super::points`]) with its corners, the cut points on its edges, the grid-edge points
//! inside it, and its trace segments on the boundary faces as constraints, so every
//! sub-triangle lies on one side of the boundary. The corners span the convex hull
//! exactly (edge points are exactly collinear with them, interior points strictly inside),
//! so the triangulation covers precisely the triangle and no face needs deleting. The
//! sub-triangles are then coloured ([`super::classify`]) and only the intact ones kept,
//! with the trace edges they own (the boundary segments handed to the rebuild).
//!
//! Everything a triangle produces goes into a [`Batch`] shared by a chunk of triangles, and
//! all buffers live in a per-worker [`Workspace`], so a triangle allocates nothing once the
//! buffers are warm (spade's `try_add_constraint` returns a small vector per constraint).

use std::ops::Range;

use glam::{DVec3, IVec3};
use mesh_core::{LabeledMesh, TriId, VertexId};
use spade::handles::{FixedFaceHandle, FixedVertexHandle, InnerTag};
use spade::{Point2, Triangulation};

use super::CutError;
use super::classify::{Cdt, FLAWED, colour_faces};
use super::points::{
    CORNER_UV, LocalPoint, PointKey, Quantum, edge_uv, grid_edge_point, mesh_edge_point,
    vertex_cell,
};
use crate::stages::flaws::{BoundaryFace, FacePoint, FlawedRegion};
use crate::stages::grid::Grid;
use crate::stages::materials::Materials;

/// One triangle's trace on one boundary face (a segment of [`crate::intersect_face`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct TraceSegment {
    /// The triangle.
    pub(crate) tri: TriId,
    /// Index of the face in the region's boundary faces.
    pub(crate) face: u32,
    /// Its two ends.
    pub(crate) ends: [FacePoint; 2],
}

/// What the per-triangle cut reads.
pub(crate) struct Context<'a> {
    pub(crate) mesh: &'a LabeledMesh,
    pub(crate) grid: &'a Grid,
    pub(crate) materials: &'a Materials,
    pub(crate) region: &'a FlawedRegion,
    pub(crate) faces: &'a [BoundaryFace],
    pub(crate) quantum: Quantum,
    pub(crate) max_points: usize,
}

/// Reusable per-worker buffers.
pub(crate) struct Workspace {
    cdt: Cdt,
    points: Vec<LocalPoint>,
    handles: Vec<FixedVertexHandle>,
    /// `[from, to, face]` per constraint, local point indices.
    constraints: Vec<[u32; 3]>,
    colour: Vec<u8>,
    stack: Vec<FixedFaceHandle<InnerTag>>,
}

impl Workspace {
    pub(crate) fn new() -> Self {
        Self {
            cdt: Cdt::new(),
            points: Vec::new(),
            handles: Vec::new(),
            constraints: Vec::new(),
            colour: Vec::new(),
            stack: Vec::new(),
        }
    }
}

/// An intact sub-triangle edge lying in a boundary face, local point indices in the
/// sub-triangle's winding.
#[derive(Clone, Copy, Debug)]
pub(crate) struct LocalSegment {
    pub(crate) from: u32,
    pub(crate) to: u32,
    pub(crate) face: u32,
}

/// One cut triangle's share of a [`Batch`].
#[derive(Clone, Debug)]
pub(crate) struct TriangleCut {
    pub(crate) tri: TriId,
    /// Its points in [`Batch::points`] (corners first); sub-triangles and segments index
    /// into this range.
    pub(crate) points: Range<usize>,
    /// Its intact sub-triangles in [`Batch::subs`].
    pub(crate) subs: Range<usize>,
    /// Its boundary segments in [`Batch::segments`].
    pub(crate) segments: Range<usize>,
}

/// The output of a chunk of triangles, in triangle order.
#[derive(Default)]
pub(crate) struct Batch {
    pub(crate) tris: Vec<TriangleCut>,
    pub(crate) points: Vec<(PointKey, DVec3)>,
    pub(crate) subs: Vec<[u32; 3]>,
    pub(crate) segments: Vec<LocalSegment>,
    pub(crate) errors: Vec<CutError>,
    /// Points moved off a corner or the triangle boundary by the quantisation.
    pub(crate) nudged: usize,
    /// Sub-triangles on the flawed side (deleted).
    pub(crate) flawed_subs: usize,
}

/// The cells beside the boundary faces `trace` lies on: where a failure is reported.
pub(crate) fn trace_cells(faces: &[BoundaryFace], trace: &[TraceSegment]) -> Vec<IVec3> {
    let mut cells: Vec<IVec3> = trace
        .iter()
        .flat_map(|s| {
            let f = &faces[s.face as usize];
            [f.flawed, f.intact]
        })
        .collect();
    cells.sort_unstable_by_key(|c| c.to_array());
    cells.dedup();
    cells
}

/// Cuts triangle `t` along its `trace` (all its segments, any order) and appends the
/// intact part to `out`; on failure `out` is left as it was.
pub(crate) fn cut_triangle(
    ctx: &Context<'_>,
    t: TriId,
    trace: &[TraceSegment],
    ws: &mut Workspace,
    out: &mut Batch,
) -> Result<(), CutError> {
    let marks = (out.points.len(), out.subs.len(), out.segments.len());
    let r = triangulate(ctx, t, trace, ws, out);
    if r.is_err() {
        out.points.truncate(marks.0);
        out.subs.truncate(marks.1);
        out.segments.truncate(marks.2);
    }
    r
}

fn triangulate(
    ctx: &Context<'_>,
    t: TriId,
    trace: &[TraceSegment],
    ws: &mut Workspace,
    out: &mut Batch,
) -> Result<(), CutError> {
    let cells = || trace_cells(ctx.faces, trace);
    let verts = ctx.mesh.tri(t);
    let corners = ctx.mesh.tri_positions(t);
    ws.points.clear();
    ws.constraints.clear();
    for (k, &pos) in corners.iter().enumerate() {
        ws.points.push(LocalPoint {
            key: PointKey::Corner(k as u8),
            uv: CORNER_UV[k],
            pos,
        });
    }

    // Points and constraints.
    for s in trace {
        let face = ctx.faces[s.face as usize].face;
        let mut ends = [0u32; 2];
        for (slot, end) in ends.iter_mut().zip(s.ends) {
            let key = match end {
                FacePoint::MeshEdge(lo, hi) => PointKey::MeshEdge {
                    lo,
                    hi,
                    face: s.face,
                },
                FacePoint::GridEdge(i) => PointKey::Grid(face.edges()[usize::from(i) % 4]),
            };
            *slot = match ws.points.iter().position(|p| p.key == key) {
                Some(j) => j as u32,
                None => {
                    if ws.points.len() >= ctx.max_points {
                        return Err(CutError::TooManyPoints {
                            tri: t,
                            limit: ctx.max_points,
                            cells: cells(),
                        });
                    }
                    let p = place_point(ctx, t, verts, corners, key, &mut out.nudged).ok_or_else(
                        || CutError::MissingPoint {
                            tri: t,
                            cells: cells(),
                        },
                    )?;
                    ws.points.push(p);
                    (ws.points.len() - 1) as u32
                }
            };
        }
        ws.constraints.push([ends[0], ends[1], s.face]);
    }

    // The triangulation.
    ws.cdt.clear();
    ws.handles.clear();
    for (i, p) in ws.points.iter().enumerate() {
        let h =
            ws.cdt
                .insert(Point2::new(p.uv[0], p.uv[1]))
                .map_err(|e| CutError::Triangulation {
                    tri: t,
                    reason: e.to_string(),
                    cells: cells(),
                })?;
        // Spade overwrites a vertex at an existing position instead of adding one.
        if h.index() != i {
            return Err(CutError::CoincidentPoints {
                tri: t,
                cells: cells(),
            });
        }
        ws.handles.push(h);
    }
    for &[a, b, _] in &ws.constraints {
        let (ha, hb) = (ws.handles[a as usize], ws.handles[b as usize]);
        // Empty: it would cross a constraint; several: it runs through another point.
        if ws.cdt.try_add_constraint(ha, hb).len() != 1 {
            return Err(CutError::ConstraintConflict {
                tri: t,
                cells: cells(),
            });
        }
    }

    // Flawed or intact, from the corners' cells.
    let lattice = ctx.grid.lattice();
    let seeds: [(FixedVertexHandle, bool); 3] = std::array::from_fn(|k| {
        (
            ws.handles[k],
            ctx.region.is_flawed(vertex_cell(lattice, corners[k])),
        )
    });
    colour_faces(&ws.cdt, seeds, &mut ws.colour, &mut ws.stack).map_err(|_| {
        CutError::ColouringConflict {
            tri: t,
            cells: cells(),
        }
    })?;

    // The intact sub-triangles and the boundary segments they own.
    let first_point = out.points.len();
    out.points.extend(ws.points.iter().map(|p| (p.key, p.pos)));
    let (first_sub, first_seg) = (out.subs.len(), out.segments.len());
    for f in ws.cdt.inner_faces() {
        if ws.colour[f.fix().index()] == FLAWED {
            out.flawed_subs += 1;
            continue;
        }
        out.subs.push(f.vertices().map(|v| v.fix().index() as u32));
        for e in f.adjacent_edges() {
            if !e.is_constraint_edge() {
                continue;
            }
            let (from, to) = (e.from().fix().index() as u32, e.to().fix().index() as u32);
            let face = ws
                .constraints
                .iter()
                .find(|c| (c[0] == from && c[1] == to) || (c[0] == to && c[1] == from))
                .map(|c| c[2])
                .ok_or_else(|| CutError::ConstraintConflict {
                    tri: t,
                    cells: cells(),
                })?;
            out.segments.push(LocalSegment { from, to, face });
        }
    }
    out.tris.push(TriangleCut {
        tri: t,
        points: first_point..out.points.len(),
        subs: first_sub..out.subs.len(),
        segments: first_seg..out.segments.len(),
    });
    Ok(())
}

/// Frame coordinates and position of the cut point `key` of triangle `t`; `None` when the
/// key does not fit the triangle (a mesh edge not its own, a grid edge it does not cross).
fn place_point(
    ctx: &Context<'_>,
    t: TriId,
    verts: [VertexId; 3],
    corners: [DVec3; 3],
    key: PointKey,
    nudged: &mut usize,
) -> Option<LocalPoint> {
    let lattice = ctx.grid.lattice();
    let (uv, moved, pos) = match key {
        PointKey::Corner(k) => {
            return Some(LocalPoint {
                key,
                uv: CORNER_UV[usize::from(k) % 3],
                pos: corners[usize::from(k) % 3],
            });
        }
        PointKey::MeshEdge { lo, hi, face } => {
            let k = (0..3).find(|&k| {
                let (a, b) = (verts[k], verts[(k + 1) % 3]);
                (a == lo && b == hi) || (a == hi && b == lo)
            })?;
            let face = ctx.faces[face as usize].face;
            let (t_lo, moved, pos) = mesh_edge_point(
                lattice,
                face,
                ctx.mesh.position(lo),
                ctx.mesh.position(hi),
                ctx.quantum,
            );
            // The canonical parameter runs from `lo`; 1 − t is exact for dyadic t.
            let s = if verts[k] == lo { t_lo } else { 1.0 - t_lo };
            (edge_uv(k, s), moved, pos)
        }
        PointKey::Grid(edge) => {
            let n = ctx.grid.node_id(edge.node)?;
            let x = ctx
                .materials
                .edge_crossings(n, edge.axis)
                .iter()
                .find(|x| x.tri == t)?;
            grid_edge_point(lattice, edge, x.coordinate, corners, ctx.quantum)
        }
    };
    *nudged += usize::from(moved);
    Some(LocalPoint { key, uv, pos })
}
