//! Layer 4, intersections (only on request): no two triangles meet except along what
//! they share combinatorially.
//!
//! Broad phase: a [`Bvh`] over the boxes of the checkable triangles, whose parallel
//! self-pair traversal yields each overlapping pair once. Narrow phase, exact
//! ([`intersect_keyed_triangle_triangle`]), chosen by how many vertex ids the two
//! triangles share:
//! - none: [`intersect_triangle_triangle`] (closed: touching counts);
//! - one vertex `v`: [`intersect_sharing_vertex`] — meeting anywhere but at `v`;
//! - one edge `vw`: [`intersect_sharing_edge`] — overlapping beyond `vw` (a fold);
//! - all three: a duplicate, reported by layer 1, not here.
//!
//! The predicates run their own floating-point filters (box test, certain plane
//! separation) before any exact arithmetic, and the sharing-edge test is a single
//! filtered `orient3d` for non-coplanar neighbours, so the common case — adjacent,
//! non-coplanar triangles of a smooth surface — costs a few tens of nanoseconds per pair.
//! Triangles with a repeated vertex or a non-finite coordinate are left out (layers 1 and
//! 3 report them).
//!
//! [`intersect_triangle_triangle`]: crate::predicates::intersect_triangle_triangle
//! [`intersect_sharing_vertex`]: crate::predicates::intersect_sharing_vertex
//! [`intersect_sharing_edge`]: crate::predicates::intersect_sharing_edge

use super::geometry::{CoordinateRange, coordinate_range};
use super::report::Listed;
use super::topology::{EdgeContext, is_degenerate};
use crate::broadphase::{Aabb, Bvh};
use crate::ids::TriId;
use crate::mesh::LabeledMesh;
use crate::predicates::intersect_keyed_triangle_triangle;

/// Intersecting pairs found by one rayon task: the exact count, and the smallest pairs.
struct Found {
    count: usize,
    smallest: Vec<[TriId; 2]>,
}

impl Found {
    fn new() -> Found {
        Found {
            count: 0,
            smallest: Vec::new(),
        }
    }

    /// Keeps at most `cap` of the smallest pairs, trimming in batches so that recording a
    /// pair is amortised O(log cap) whatever the number of intersections.
    fn trim(&mut self, cap: usize, slack: usize) {
        if self.smallest.len() > cap.saturating_add(slack) {
            self.smallest.sort_unstable();
            self.smallest.truncate(cap);
        }
    }
}

/// The broad-phase box of triangle slot `t`: EMPTY (overlapping nothing) unless `usable`
/// (then its vertex ids are safe to look up) and every corner is in `range` (finite and
/// where the predicates are exact), so that the slot's id is its item id in the BVH.
fn checkable_box(mesh: &LabeledMesh, t: u32, usable: bool, range: CoordinateRange) -> Aabb {
    if !usable {
        return Aabb::EMPTY;
    }
    let p = mesh.tri_positions(TriId::new(t));
    if p.into_iter().all(|q| range.contains(q)) {
        Aabb::from_points(&p)
    } else {
        Aabb::EMPTY
    }
}

/// Runs layer 4: every intersecting pair counted, the `cap` smallest (by ids) listed.
pub(super) fn check(
    mesh: &LabeledMesh,
    range: CoordinateRange,
    ctx: &EdgeContext,
    cap: usize,
) -> Listed<[TriId; 2]> {
    let tris = mesh.tris();
    // One box per triangle slot, EMPTY (overlapping nothing) for those not checked, so
    // the item id is the triangle id.
    // `usable` first: only then are the vertex ids safe to look up.
    let box_of = |t: u32| {
        checkable_box(
            mesh,
            t,
            ctx.usable[t as usize] && !is_degenerate(tris[t as usize]),
            range,
        )
    };
    // Triangle slots fit in u32 (the mesh caps them), so the build cannot fail.
    let Ok(bvh) = Bvh::build_from_fn(tris.len(), box_of) else {
        return Listed::default();
    };
    let slack = cap.max(64);
    let found = bvh.self_pairs_fold(
        0.0,
        Found::new,
        |acc, a, b| {
            let (a, b) = (TriId::new(a.min(b)), TriId::new(a.max(b)));
            if triangles_intersect(mesh, a, b) {
                acc.count += 1;
                acc.smallest.push([a, b]);
                acc.trim(cap, slack);
            }
        },
        |mut x, y| {
            x.count += y.count;
            x.smallest.extend(y.smallest);
            x.trim(cap, slack);
            x
        },
    );
    let mut items = found.smallest;
    items.sort_unstable();
    items.truncate(cap);
    Listed {
        count: found.count,
        items,
    }
}

/// Whether any two triangles of `mesh` meet anywhere but along what they share: layer 4 as
/// a yes/no question, for a mesh that passes layers 1–3.
///
/// Why not the full layer 4 ([`super::check_intersections`]): a caller that only asks
/// whether a mesh is clean (`fix` deciding whether its input needs repair) has no use for
/// the count and list of every pair, and on a mesh that is not clean — the usual input of
/// a repair — the first pair is found long before the last: once one is found, every task
/// skips its remaining exact tests.
/// Triangles that layers 1–3 would reject (dead, dangling, degenerate, non-finite or out of
/// range) are left out, so any mesh is safe to ask. The answer does not depend on the thread count.
pub fn any_intersection(mesh: &LabeledMesh) -> bool {
    use std::sync::atomic::{AtomicBool, Ordering};
    let tris = mesh.tris();
    let range = coordinate_range(mesh);
    let box_of = |t: u32| {
        let tri = tris[t as usize];
        let usable = mesh.is_triangle_alive(TriId::new(t))
            && tri.iter().all(|&v| mesh.is_vertex_alive(v))
            && !is_degenerate(tri);
        checkable_box(mesh, t, usable, range)
    };
    let Ok(bvh) = Bvh::build_from_fn(tris.len(), box_of) else {
        return false;
    };
    let found = AtomicBool::new(false);
    bvh.self_pairs_fold(
        0.0,
        || (),
        |_, a, b| {
            if !found.load(Ordering::Relaxed)
                && triangles_intersect(mesh, TriId::new(a), TriId::new(b))
            {
                found.store(true, Ordering::Relaxed);
            }
        },
        |_, _| (),
    );
    found.into_inner()
}

/// Whether triangles `a` and `b` of `mesh` (distinct, non-degenerate, finite) meet
/// anywhere but along what they share: layer 4's exact pair test, also the grid tracker's
/// safety net's.
pub fn triangles_intersect(mesh: &LabeledMesh, a: TriId, b: TriId) -> bool {
    let key = |t: TriId| mesh.tri(t).map(|v| v.raw());
    intersect_keyed_triangle_triangle(
        (key(a), &mesh.tri_positions(a)),
        (key(b), &mesh.tri_positions(b)),
    )
}
