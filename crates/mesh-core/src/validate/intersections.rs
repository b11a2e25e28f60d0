//! Layer 4, intersections (only on request): no two triangles meet except along what
//! they share combinatorially.
//!
//! Broad phase: a [`Bvh`] over the boxes of the checkable triangles, whose parallel
//! self-pair traversal yields each overlapping pair once. Narrow phase, exact, chosen by
//! how many vertex ids the two triangles share:
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

use glam::DVec3;

use super::report::Listed;
use super::topology::{EdgeContext, is_degenerate};
use crate::broadphase::{Aabb, Bvh};
use crate::ids::TriId;
use crate::mesh::LabeledMesh;
use crate::predicates::{
    intersect_sharing_edge, intersect_sharing_vertex, intersect_triangle_triangle,
};

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

/// Runs layer 4: every intersecting pair counted, the `cap` smallest (by ids) listed.
pub(super) fn check(mesh: &LabeledMesh, ctx: &EdgeContext, cap: usize) -> Listed<[TriId; 2]> {
    let tris = mesh.tris();
    // One box per triangle slot, EMPTY (overlapping nothing) for those not checked, so
    // the item id is the triangle id.
    let box_of = |t: u32| {
        let id = TriId::new(t);
        let t = t as usize;
        // `usable` first: only then are the vertex ids safe to look up.
        if !ctx.usable[t] || is_degenerate(tris[t]) {
            return Aabb::EMPTY;
        }
        let p = mesh.tri_positions(id);
        if p.iter().all(|q| q.is_finite()) {
            Aabb::from_points(&p)
        } else {
            Aabb::EMPTY
        }
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
            if pair_intersects(mesh, a, b) {
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

/// Exact test of one candidate pair (distinct, non-degenerate, finite triangles).
pub(super) fn pair_intersects(mesh: &LabeledMesh, a: TriId, b: TriId) -> bool {
    let (ta, tb) = (mesh.tri(a), mesh.tri(b));
    // Slot in `tb` of each vertex of `ta` (3 = not shared), by plain comparisons: this
    // runs for millions of pairs, most of them neighbours.
    let mut in_b = [3usize; 3];
    let mut shared = 0;
    for (i, v) in ta.iter().enumerate() {
        for (j, w) in tb.iter().enumerate() {
            if v == w {
                in_b[i] = j;
                shared += 1;
            }
        }
    }
    let (pa, pb): ([DVec3; 3], [DVec3; 3]) = (mesh.tri_positions(a), mesh.tri_positions(b));
    match shared {
        0 => intersect_triangle_triangle(&pa, &pb),
        1 => {
            let i = if in_b[0] < 3 {
                0
            } else if in_b[1] < 3 {
                1
            } else {
                2
            };
            let j = in_b[i];
            let (v, a1, a2) = (pa[i], pa[(i + 1) % 3], pa[(i + 2) % 3]);
            let (b1, b2) = (pb[(j + 1) % 3], pb[(j + 2) % 3]);
            // The usual case on a surface: b's far edge certainly strictly on one side of
            // a's plane, so the triangles can only share v.
            !crate::predicates::tri_tri::certainly_separated(&[v, a1, a2], &[b1, b2])
                && intersect_sharing_vertex(v, [a1, a2], [b1, b2])
        }
        2 => {
            // The apex of a is its unshared slot; the apex of b is the slot of b that no
            // vertex of a maps to (slots sum to 0 + 1 + 2 = 3).
            let i = if in_b[0] == 3 {
                0
            } else if in_b[1] == 3 {
                1
            } else {
                2
            };
            let j = 3 - in_b[(i + 1) % 3] - in_b[(i + 2) % 3];
            intersect_sharing_edge(pa[(i + 1) % 3], pa[(i + 2) % 3], pa[i], pb[j])
        }
        _ => false,
    }
}
