//! The safety net (§9.2) and the sub-ℓ intersection pass (beyond the paper, its §10).
//!
//! Both turn "something is wrong here" into *cells*, which join the flawed region before
//! the cut → rebuild pass is redone from the moved mesh:
//! - [`inconsistency_cells`]: what layers 1–3 of [`mesh_core::validate`] found wrong with
//!   a rebuilt mesh (a boundary edge, an inconsistently labelled wedge, a zero-area or
//!   duplicate triangle, …), mapped to the cells its triangles overlap. A stage's own
//!   inconsistency (`CutError::cells`, `RebuildError::cells`) arrives as cells directly.
//! - [`intersecting_pairs`]: exact triangle–triangle tests (mesh-core predicates, shared
//!   vertices and edges excluded) between the *changed* triangles and everything near them
//!   (a BVH over all triangles), so that overlaps thinner than ℓ, which no grid ray sees,
//!   are found too; [`pair_cells`] gives the cells where each pair can meet.
//!
//! [`add_cells`] grows the region, dilating when every reported cell is already flawed so
//! that each round makes progress; the callers bound the rounds.

use std::collections::HashSet;

use glam::{DVec3, IVec3};
use mesh_core::broadphase::{Aabb, Bvh};
use mesh_core::validate::{CornerTableError, ValidationReport, triangles_intersect};
use mesh_core::{LabeledMesh, TriId};
use rayon::prelude::*;

use crate::stages::flaws::FlawedRegion;
use crate::stages::grid::{Grid, Lattice};
use crate::stages::materials::Materials;

/// Triangles whose box spans more cells than this per axis are mapped by their vertices
/// only: a huge triangle would otherwise flood the region with cells it merely passes.
const MAX_SPAN: i32 = 16;

/// The cells the closed box `[min, max]` meets, appended to `out` (at most
/// `MAX_SPAN³` cells; a longer box contributes its corner cells only).
fn box_cells(lattice: &Lattice, min: DVec3, max: DVec3, out: &mut Vec<IVec3>) {
    if !(min.is_finite() && max.is_finite()) {
        return;
    }
    let [lo, hi] = lattice.cell_range(min, max);
    let span = hi - lo;
    if span.max_element() >= MAX_SPAN {
        out.push(lo);
        out.push(hi);
        return;
    }
    for x in lo.x..=hi.x {
        for y in lo.y..=hi.y {
            for z in lo.z..=hi.z {
                out.push(IVec3::new(x, y, z));
            }
        }
    }
}

/// The cells a live triangle's box meets.
fn triangle_cells(mesh: &LabeledMesh, lattice: &Lattice, t: TriId, out: &mut Vec<IVec3>) {
    if t.idx() >= mesh.triangle_capacity() || !mesh.is_triangle_alive(t) {
        return;
    }
    let p = mesh.tri_positions(t);
    let b = Aabb::from_points(&p);
    box_cells(lattice, b.min, b.max, out);
}

/// Cells around every defect of `report` (layers 1–4; for a misplaced component, every
/// triangle of it), on `lattice`. Defects that name
/// no live triangle with finite coordinates contribute nothing: the caller treats an
/// invalid report with no cells as a failure it cannot repair.
pub(crate) fn inconsistency_cells(
    mesh: &LabeledMesh,
    lattice: &Lattice,
    report: &ValidationReport,
) -> Vec<IVec3> {
    let mut tris: Vec<TriId> = Vec::new();
    tris.extend(report.dangling_references.items.iter().map(|d| d.tri));
    tris.extend(report.degenerate.items.iter().copied());
    tris.extend(report.duplicates.items.iter().flatten().copied());
    tris.extend(report.boundary_edges.items.iter().map(|e| e.tri));
    tris.extend(report.same_label_triangles.items.iter().map(|s| s.tri));
    for e in &report.inconsistent_edges.items {
        tris.extend(e.tris.iter().copied());
    }
    tris.extend(report.zero_area.items.iter().copied());
    if let Some(misplaced) = report.misplaced_shells.as_ref().filter(|m| !m.is_empty()) {
        let named: Vec<TriId> = misplaced.items.iter().map(|m| m.tri).collect();
        tris.extend(mesh_core::placement::component_triangles(mesh, &named));
    }
    for e in &report.corner_table.items {
        let corner = match *e {
            CornerTableError::OppositeDead { corner, .. }
            | CornerTableError::OppositeNotSymmetric { corner, .. }
            | CornerTableError::OppositeWrongEdge { corner, .. }
            | CornerTableError::PairingMismatch { corner, .. }
            | CornerTableError::RingForeignCorner { corner, .. }
            | CornerTableError::RingRepeatedCorner { corner, .. }
            | CornerTableError::MissingFromRing { corner, .. } => corner,
        };
        tris.push(corner.tri());
    }
    let mut cells = Vec::new();
    for t in tris {
        triangle_cells(mesh, lattice, t, &mut cells);
    }
    for &v in &report.non_finite.items {
        // A non-finite vertex cannot be located; its triangles' other corners can.
        for t in mesh.vertex_triangles(v) {
            for w in mesh.tri(t) {
                let p = mesh.position(w);
                box_cells(lattice, p, p, &mut cells);
            }
        }
    }
    dedup(&mut cells);
    cells
}

/// Whether a live triangle can be tested: three distinct vertices, finite coordinates.
fn testable(mesh: &LabeledMesh, t: TriId) -> bool {
    let [a, b, c] = mesh.tri(t);
    a != b && b != c && a != c && mesh.tri_positions(t).iter().all(|p| p.is_finite())
}

/// Every intersecting pair `[lower, higher]` with at least one triangle in `changed`
/// (`None`: all live triangles), sorted. Broad phase: one BVH over all live triangles;
/// the changed triangles query it in parallel (or, for the whole mesh, the BVH's own
/// parallel self-pair traversal).
pub(crate) fn intersecting_pairs(mesh: &LabeledMesh, changed: Option<&[TriId]>) -> Vec<[TriId; 2]> {
    let alive = mesh.tri_alive_flags();
    let box_of = |i: u32| {
        let t = TriId::new(i);
        if alive[i as usize] && testable(mesh, t) {
            Aabb::from_points(&mesh.tri_positions(t))
        } else {
            Aabb::EMPTY
        }
    };
    // Triangle slots fit in u32 (the mesh caps them), so the build cannot fail.
    let Ok(bvh) = Bvh::build_from_fn(mesh.triangle_capacity(), box_of) else {
        return Vec::new();
    };
    let mut pairs: Vec<[TriId; 2]> = match changed {
        None => bvh.self_pairs_fold(
            0.0,
            Vec::new,
            |acc, a, b| {
                let (a, b) = (TriId::new(a.min(b)), TriId::new(a.max(b)));
                if triangles_intersect(mesh, a, b) {
                    acc.push([a, b]);
                }
            },
            |mut x, mut y| {
                x.append(&mut y);
                x
            },
        ),
        Some(changed) => {
            let mut is_changed = vec![false; mesh.triangle_capacity()];
            for &t in changed {
                if let Some(f) = is_changed.get_mut(t.idx()) {
                    *f = true;
                }
            }
            changed
                .par_iter()
                .filter(|&&t| t.idx() < alive.len() && alive[t.idx()] && testable(mesh, t))
                .fold(Vec::new, |mut acc, &t| {
                    let q = Aabb::from_points(&mesh.tri_positions(t));
                    bvh.query(&q, 0.0, |o| {
                        let o = TriId::new(o);
                        // A changed pair is found from both ends: keep it from the lower.
                        if o == t || (is_changed[o.idx()] && o < t) {
                            return;
                        }
                        if triangles_intersect(mesh, t, o) {
                            acc.push([t.min(o), t.max(o)]);
                        }
                    });
                    acc
                })
                .reduce(Vec::new, |mut x, mut y| {
                    x.append(&mut y);
                    x
                })
        }
    };
    pairs.par_sort_unstable();
    pairs.dedup();
    pairs
}

/// The cells where the triangles of each pair can meet: those meeting the intersection
/// of the two triangles' boxes.
///
/// Memory stays proportional to the distinct cells, not to pairs × cells: many pairs
/// (a thousand overlapping shapes) name the same cells over and over, so the list is
/// deduplicated whenever it has doubled since the last time.
pub(crate) fn pair_cells(
    mesh: &LabeledMesh,
    lattice: &Lattice,
    pairs: &[[TriId; 2]],
) -> Vec<IVec3> {
    let mut cells = Vec::new();
    let mut distinct = 0;
    for &[a, b] in pairs {
        let ba = Aabb::from_points(&mesh.tri_positions(a));
        let bb = Aabb::from_points(&mesh.tri_positions(b));
        box_cells(lattice, ba.min.max(bb.min), ba.max.min(bb.max), &mut cells);
        if cells.len() > 2 * distinct + (1 << 16) {
            dedup(&mut cells);
            distinct = cells.len();
        }
    }
    dedup(&mut cells);
    cells
}

fn dedup(cells: &mut Vec<IVec3>) {
    cells.sort_unstable_by_key(|c| c.to_array());
    cells.dedup();
}

/// Adds `cells` to the region (growing it until its boundary is clean again). When every
/// one of them is already flawed — the inconsistency lies inside the region, so adding
/// them would change nothing — their 26 neighbours join instead, so each round of the
/// caller's bounded loop enlarges the region. Returns the number of cells added.
pub(crate) fn add_cells(
    region: &mut FlawedRegion,
    mesh: &LabeledMesh,
    grid: &Grid,
    materials: &Materials,
    cells: &[IVec3],
) -> usize {
    let before = region.len();
    let fresh: Vec<IVec3> = cells
        .iter()
        .copied()
        .filter(|&c| !region.is_flawed(c))
        .collect();
    let seeds = if fresh.is_empty() {
        let mut ring: HashSet<[i32; 3]> = HashSet::new();
        for &c in cells {
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        let n = c + IVec3::new(dx, dy, dz);
                        if !region.is_flawed(n) {
                            ring.insert(n.to_array());
                        }
                    }
                }
            }
        }
        let mut ring: Vec<IVec3> = ring.into_iter().map(IVec3::from_array).collect();
        dedup(&mut ring);
        ring
    } else {
        fresh
    };
    if !seeds.is_empty() {
        region.grow(mesh, grid, materials, &seeds);
    }
    region.len() - before
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_util::{sphere, union};

    #[test]
    fn overlapping_spheres_intersect_and_separate_ones_do_not() {
        let a = sphere(2, DVec3::ZERO, 1.0, 0, 1);
        let b = sphere(2, DVec3::new(1.2, 0.1, 0.0), 1.0, 0, 2);
        let c = sphere(2, DVec3::new(5.0, 0.0, 0.0), 1.0, 0, 3);
        let overlapping = union(&[a.clone(), b]);
        let apart = union(&[a, c]);
        let all = intersecting_pairs(&overlapping, None);
        assert!(!all.is_empty());
        assert!(intersecting_pairs(&apart, None).is_empty());
        // From the changed side only: the pairs found are those with a changed member.
        let first: Vec<TriId> = (0..80).map(TriId::new).collect();
        let some = intersecting_pairs(&overlapping, Some(&first));
        let expected: Vec<[TriId; 2]> = all
            .iter()
            .copied()
            .filter(|[x, y]| x.idx() < 80 || y.idx() < 80)
            .collect();
        assert_eq!(some, expected);
    }

    #[test]
    fn neighbours_sharing_edges_are_not_intersections() {
        let a = sphere(3, DVec3::ZERO, 1.0, 0, 1);
        assert!(intersecting_pairs(&a, None).is_empty());
        let all: Vec<TriId> = a.triangles().collect();
        assert!(intersecting_pairs(&a, Some(&all)).is_empty());
    }
}
