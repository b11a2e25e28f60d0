//! Layer 1, topology: what can be checked from ids alone — references, repeated
//! vertices, duplicates, boundary edges — plus the integrity of the stored corner table and
//! vertex rings against a recomputation. One pass over the edge groups does the boundary,
//! duplicate and pairing checks together: the groups are the expensive part to visit.
//!
//! The one place positions enter is the radial order of non-manifold edges, needed to
//! recompute which sides face a common wedge (the same `sort_radially` the mesh uses, on
//! the same input order, so a correctly maintained table matches bit for bit).

use std::sync::atomic::{AtomicBool, Ordering};

use rayon::prelude::*;

use super::report::{BoundaryEdge, CornerTableError, DanglingReference, Listed, ValidationReport};
use crate::connectivity::{EdgeIncidence, EdgeTable, pair_sides, sort_radially};
use crate::corner::Side;
use crate::ids::{CornerId, TriId, VertexId};
use crate::mesh::LabeledMesh;

/// Items per rayon task in the per-triangle and per-edge scans.
pub(super) const CHUNK: usize = 8 * 1024;

/// What the topology layer leaves for the layers above.
pub(super) struct EdgeContext {
    /// Edges of the triangles in `usable`, each group radially sorted.
    pub table: EdgeTable,
    /// Per triangle slot: alive and every vertex index inside the vertex array, i.e. safe
    /// to look up positions for.
    pub usable: Vec<bool>,
}

impl EdgeContext {
    /// The edge groups as a vector of slices, for parallel iteration.
    pub fn groups(&self) -> Vec<&[EdgeIncidence]> {
        self.table.groups().collect()
    }
}

/// Runs layer 1, filling its categories of `report`.
pub(super) fn check(mesh: &LabeledMesh, cap: usize, report: &mut ValidationReport) -> EdgeContext {
    report.vertices = mesh.num_vertices();
    report.triangles = mesh.num_triangles();
    let (usable, degenerate_keys) = references(mesh, cap, report);

    let mut table = EdgeTable::build(mesh.tris(), &usable, mesh.vertex_capacity());
    for group in table.groups_mut() {
        if group.len() > 2 {
            sort_radially(group, mesh.tris(), mesh.positions());
        }
    }
    let ctx = EdgeContext { table, usable };
    report.edges = ctx.table.edge_count();
    let mut duplicates = edges(mesh, &ctx, cap, report);
    duplicates.extend(duplicate_degenerates(degenerate_keys));
    // List in order of the later triangle, like every other per-triangle category.
    duplicates.sort_unstable_by_key(|p| (p[1], p[0]));
    for p in duplicates {
        report.duplicates.push(p, cap);
    }
    rings(mesh, &ctx.usable, cap, report);
    ctx
}

/// Sorted vertex triple of a triangle with a repeated vertex, and the triangle.
type DegenerateKey = ([u32; 3], TriId);

/// Dangling references and repeated vertices. Returns the usable-triangle mask and the
/// keys of the usable degenerate triangles (whose duplicates the edge scan cannot see).
fn references(
    mesh: &LabeledMesh,
    cap: usize,
    report: &mut ValidationReport,
) -> (Vec<bool>, Vec<DegenerateKey>) {
    let tris = mesh.tris();
    let alive = mesh.tri_alive_flags();
    let nv = mesh.vertex_capacity();
    let usable: Vec<bool> = (0..tris.len())
        .into_par_iter()
        .with_min_len(CHUNK)
        .map(|t| alive[t] && tris[t].iter().all(|v| v.idx() < nv))
        .collect();
    type Part = (Listed<DanglingReference>, Listed<TriId>, Vec<DegenerateKey>);
    let parts: Vec<Part> = (0..tris.len())
        .into_par_iter()
        .chunks(CHUNK)
        .map(|range| {
            let mut part: Part = Default::default();
            for t in range {
                if !alive[t] {
                    continue;
                }
                let tri = tris[t];
                let id = TriId::new(t as u32);
                for (k, &v) in tri.iter().enumerate() {
                    if !tri[..k].contains(&v) && !mesh.is_vertex_alive(v) {
                        part.0.push(DanglingReference { tri: id, vertex: v }, cap);
                    }
                }
                if is_degenerate(tri) {
                    part.1.push(id, cap);
                    if usable[t] {
                        let mut key = tri.map(|v| v.raw());
                        key.sort_unstable();
                        part.2.push((key, id));
                    }
                }
            }
            part
        })
        .collect();
    let mut keys = Vec::new();
    for (dangling, degenerate, k) in parts {
        report.dangling_references.append(dangling, cap);
        report.degenerate.append(degenerate, cap);
        keys.extend(k);
    }
    (usable, keys)
}

#[inline]
pub(super) fn is_degenerate(tri: [VertexId; 3]) -> bool {
    tri[0] == tri[1] || tri[1] == tri[2] || tri[2] == tri[0]
}

/// Duplicates among degenerate triangles, `[first, later]`, by sorting their keys.
fn duplicate_degenerates(mut keys: Vec<DegenerateKey>) -> Vec<[TriId; 2]> {
    keys.sort_unstable();
    let mut out = Vec::new();
    let mut first = 0;
    for i in 1..keys.len() {
        if keys[i].0 != keys[first].0 {
            first = i;
        } else {
            out.push([keys[first].1, keys[i].1]);
        }
    }
    out
}

/// Duplicates among the non-degenerate triangles of one edge group. A triangle
/// `a < b < c` is seen once, at its edge `{a, b}` (the one whose third vertex exceeds
/// the edge's higher vertex); two triangles there with the same third vertex have the same
/// vertex set. Each is paired with the lowest id of its set, in group order.
///
/// Why two ways: an edge usually has two to four triangles, where comparing every pair is
/// cheapest and allocates nothing; but a hostile file (one triangle repeated a million
/// times, a "book" of pages on one spine) puts them all on one edge, and the pairwise
/// scan took half an hour there. Above [`PAIRWISE_DEGREE`] the lowest id per third vertex
/// comes from one sort.
fn duplicates_at_edge(group: &[EdgeIncidence], tris: &[[VertexId; 3]], out: &mut Vec<[TriId; 2]>) {
    let third = |e: &EdgeIncidence| tris[e.tri.idx()][e.slot as usize];
    let counts = |e: &EdgeIncidence| third(e) > e.hi && !is_degenerate(tris[e.tri.idx()]);
    if group.len() <= PAIRWISE_DEGREE {
        for e in group.iter().filter(|e| counts(e)) {
            let c = third(e);
            let first = group
                .iter()
                .filter(|f| counts(f) && third(f) == c)
                .map(|f| f.tri)
                .min()
                .unwrap_or(e.tri);
            if first != e.tri {
                out.push([first, e.tri]);
            }
        }
        return;
    }
    // (third vertex, lowest triangle id with it), sorted by third vertex.
    let mut lowest: Vec<(VertexId, TriId)> = group
        .iter()
        .filter(|e| counts(e))
        .map(|e| (third(e), e.tri))
        .collect();
    lowest.sort_unstable();
    lowest.dedup_by_key(|x| x.0);
    for e in group.iter().filter(|e| counts(e)) {
        let c = third(e);
        let i = lowest.partition_point(|x| x.0 < c);
        let first = lowest[i].1;
        if first != e.tri {
            out.push([first, e.tri]);
        }
    }
}

/// Edge degree up to which [`duplicates_at_edge`] compares every pair.
const PAIRWISE_DEGREE: usize = 16;

/// Per-edge scan: boundary edges, non-manifold count, duplicates, and the stored
/// opposite pointers against the pairing recomputed from the radial order. Every corner
/// of a usable triangle lies across exactly one edge and, for an edge with two or more
/// triangles, in exactly one recomputed pair, so checking all pairs checks every corner;
/// only corners whose pointer disagrees are diagnosed further (dead target, asymmetric,
/// wrong edge), which keeps the clean case to one pass. Returns the duplicate pairs.
fn edges(
    mesh: &LabeledMesh,
    ctx: &EdgeContext,
    cap: usize,
    report: &mut ValidationReport,
) -> Vec<[TriId; 2]> {
    let tris = mesh.tris();
    let groups = ctx.groups();
    type Part = (
        Listed<BoundaryEdge>,
        Listed<CornerTableError>,
        usize,
        Vec<[TriId; 2]>,
    );
    let parts: Vec<Part> = groups
        .par_chunks(CHUNK)
        .map(|chunk| {
            let mut part: Part = Default::default();
            let (boundary, errs, non_manifold, dups) =
                (&mut part.0, &mut part.1, &mut part.2, &mut part.3);
            for group in chunk {
                let e = group[0];
                if e.lo == e.hi || group.len() < 2 {
                    if e.lo != e.hi {
                        boundary.push(
                            BoundaryEdge {
                                edge: [e.lo, e.hi],
                                tri: e.tri,
                            },
                            cap,
                        );
                    }
                    // No side pairs here: every corner across this edge must be unpaired.
                    for inc in group.iter() {
                        for corner in [inc.ccw_corner(tris), inc.cw_corner(tris)] {
                            if let found @ Some(_) = mesh.opposite(corner) {
                                mismatch(mesh, &ctx.usable, corner, None, found, cap, errs);
                            }
                        }
                    }
                    continue;
                }
                *non_manifold += usize::from(group.len() > 2);
                duplicates_at_edge(group, tris, dups);
                pair_sides(group, tris, |a, b| {
                    for (corner, expected) in [(a, b), (b, a)] {
                        let found = mesh.opposite(corner);
                        if found != Some(expected) {
                            mismatch(mesh, &ctx.usable, corner, Some(expected), found, cap, errs);
                        }
                    }
                });
            }
            part
        })
        .collect();
    let mut duplicates = Vec::new();
    for (boundary, errs, non_manifold, dups) in parts {
        report.boundary_edges.append(boundary, cap);
        report.corner_table.append(errs, cap);
        report.non_manifold_edges += non_manifold;
        duplicates.extend(dups);
    }
    duplicates
}

/// Records a stored opposite that differs from the recomputed one, and what else is wrong
/// with the stored pointer.
fn mismatch(
    mesh: &LabeledMesh,
    usable: &[bool],
    corner: CornerId,
    expected: Option<CornerId>,
    found: Option<CornerId>,
    cap: usize,
    errs: &mut Listed<CornerTableError>,
) {
    errs.push(
        CornerTableError::PairingMismatch {
            corner,
            expected,
            found,
        },
        cap,
    );
    let Some(opposite) = found else { return };
    if !usable.get(opposite.tri().idx()).copied().unwrap_or(false) {
        errs.push(CornerTableError::OppositeDead { corner, opposite }, cap);
        return;
    }
    if mesh.opposite(opposite) != Some(corner) {
        errs.push(
            CornerTableError::OppositeNotSymmetric { corner, opposite },
            cap,
        );
    }
    let [a, b] = mesh.corner_edge(corner);
    if mesh.corner_edge(opposite) != [b, a] {
        errs.push(
            CornerTableError::OppositeWrongEdge { corner, opposite },
            cap,
        );
    }
}

/// Vertex rings hold exactly the front corners of the live triangles at their vertex:
/// every entry is such a corner (checked per entry), none repeats (marks), none is
/// missing (every live triangle's corners are marked afterwards).
fn rings(mesh: &LabeledMesh, usable: &[bool], cap: usize, report: &mut ValidationReport) {
    let n = mesh.triangle_capacity();
    let seen: Vec<AtomicBool> = (0..3 * n).map(|_| AtomicBool::new(false)).collect();
    let parts: Vec<Listed<CornerTableError>> = (0..mesh.vertex_capacity())
        .into_par_iter()
        .chunks(CHUNK)
        .map(|range| {
            let mut errs = Listed::default();
            for v in range {
                let vertex = VertexId::new(v as u32);
                // Stop a ring at its first error: a corrupt ring may be cyclic, and this
                // keeps the whole scan linear in the number of corners.
                for corner in mesh.vertex_corners(vertex) {
                    let t = corner.tri().idx();
                    let own = t < n
                        && usable[t]
                        && corner.side() == Side::Front
                        && mesh.corner_vertex(corner) == vertex;
                    if !own {
                        errs.push(CornerTableError::RingForeignCorner { vertex, corner }, cap);
                        break;
                    }
                    // Only the thread scanning `vertex` marks corners at `vertex`.
                    if seen[3 * t + corner.slot()].swap(true, Ordering::Relaxed) {
                        errs.push(CornerTableError::RingRepeatedCorner { vertex, corner }, cap);
                        break;
                    }
                }
            }
            errs
        })
        .collect();
    let missing: Vec<Listed<CornerTableError>> = (0..n)
        .into_par_iter()
        .chunks(CHUNK)
        .map(|range| {
            let mut errs = Listed::default();
            for t in range {
                if !usable[t] {
                    continue;
                }
                for slot in 0..3 {
                    if !seen[3 * t + slot].load(Ordering::Relaxed) {
                        let corner = CornerId::of(TriId::new(t as u32), Side::Front, slot);
                        let vertex = mesh.corner_vertex(corner);
                        errs.push(CornerTableError::MissingFromRing { vertex, corner }, cap);
                    }
                }
            }
            errs
        })
        .collect();
    for p in parts.into_iter().chain(missing) {
        report.corner_table.append(p, cap);
    }
}
