//! Finding proximate pairs (Los Topos §7.1): vertex–triangle and edge–edge pairs of
//! non-adjacent elements closer than the merge distance, nearest first.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use mesh_core::broadphase::{Aabb, Bvh};
use mesh_core::{LabeledMesh, TriId, VertexId};
use rayon::prelude::*;

use crate::proximity::{proximity_edge_edge, proximity_vertex_triangle};

/// Two elements to merge.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub(crate) enum Pair {
    /// A vertex and a triangle not containing it.
    VertexTriangle(VertexId, TriId),
    /// Two edges sharing no vertex (each with sorted ends, the smaller edge first).
    EdgeEdge([VertexId; 2], [VertexId; 2]),
}

/// A proximate pair and its distance when found.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Candidate {
    pub distance: f64,
    pub pair: Pair,
}

fn sorted(a: VertexId, b: VertexId) -> [VertexId; 2] {
    if a < b { [a, b] } else { [b, a] }
}

/// Every non-adjacent vertex–triangle and edge–edge pair closer than `d`, sorted by
/// distance (ties by ids, so the order is deterministic), each once.
///
/// Broad phase: a BVH over the live triangles, pairs of triangles whose boxes overlap once
/// grown by `d`; each such pair contributes its vertex–triangle and edge–edge pairs.
pub(crate) fn proximate_pairs(mesh: &LabeledMesh, d: f64) -> Vec<Candidate> {
    let ids: Vec<u32> = mesh.triangles().map(|t| t.raw()).collect();
    let boxes: Vec<Aabb> = ids
        .iter()
        .map(|&t| Aabb::from_points(&mesh.tri_positions(TriId::new(t))))
        .collect();
    // A build fails only for more boxes than ids, which a mesh cannot have.
    let Ok(bvh) = Bvh::build_with_ids(&boxes, &ids) else {
        return Vec::new();
    };
    let mut found: Vec<Candidate> = bvh.self_pairs_fold(
        d,
        Vec::new,
        |out, t, u| {
            let (t, u) = (TriId::new(t), TriId::new(u));
            pairs_of(mesh, t, u, d, out);
            pairs_of(mesh, u, t, d, out);
        },
        |mut a, b| {
            a.extend(b);
            a
        },
    );
    found.par_sort_unstable_by(|x, y| {
        x.distance
            .total_cmp(&y.distance)
            .then_with(|| x.pair.cmp(&y.pair))
    });
    // The same pair comes from several triangle pairs: keep its first (identical) entry.
    let mut seen = std::collections::HashSet::with_capacity(found.len());
    found.retain(|c| seen.insert(c.pair));
    found
}

/// The vertices of `t` against `u`, and (once per unordered triangle pair: when `t < u`)
/// the edges of `t` against the edges of `u`.
///
/// Every element pair is first tested by boxes grown by `d`: two elements closer than `d`
/// have boxes that close, and most pairs the broad phase hands over are neighbours on one
/// sheet (their triangles share a vertex, so their boxes always overlap) whose other
/// elements are a whole edge apart; the exact distance then runs only for the few that
/// can be near.
fn pairs_of(mesh: &LabeledMesh, t: TriId, u: TriId, d: f64, out: &mut Vec<Candidate>) {
    let (vt, vu) = (mesh.tri(t), mesh.tri(u));
    let (pt, pu) = (mesh.tri_positions(t), mesh.tri_positions(u));
    let near_u = Aabb::from_points(&pu).inflated(d);
    for k in 0..3 {
        if vu.contains(&vt[k]) || !near_u.overlaps(&Aabb::new(pt[k], pt[k])) {
            continue;
        }
        let prox = proximity_vertex_triangle(pt[k], pu);
        if prox.distance < d {
            out.push(Candidate {
                distance: prox.distance,
                pair: Pair::VertexTriangle(vt[k], u),
            });
        }
    }
    if t > u {
        return;
    }
    for i in 0..3 {
        let (a, b) = (i, (i + 1) % 3);
        for j in 0..3 {
            let (c, e) = (j, (j + 1) % 3);
            if [vu[c], vu[e]].iter().any(|w| *w == vt[a] || *w == vt[b])
                || !Aabb::from_points(&[pt[a], pt[b]])
                    .inflated(d)
                    .overlaps(&Aabb::from_points(&[pu[c], pu[e]]))
            {
                continue;
            }
            let prox = proximity_edge_edge(pt[a], pt[b], pu[c], pu[e]);
            if prox.distance < d {
                let (x, y) = (sorted(vt[a], vt[b]), sorted(vu[c], vu[e]));
                out.push(Candidate {
                    distance: prox.distance,
                    pair: Pair::EdgeEdge(x.min(y), x.max(y)),
                });
            }
        }
    }
}

impl Pair {
    /// The vertices of the first and of the second element.
    fn elements(&self, mesh: &LabeledMesh) -> ([VertexId; 3], usize, [VertexId; 3], usize) {
        match *self {
            Pair::VertexTriangle(v, t) => ([v, v, v], 1, mesh.tri(t), 3),
            Pair::EdgeEdge([a, b], [p, q]) => ([a, b, b], 2, [p, q, q], 2),
        }
    }
}

/// Reused buffers of [`SurfaceReach`].
#[derive(Default)]
pub(crate) struct SurfaceReach {
    heap: BinaryHeap<Reverse<(u64, u32)>>,
    settled: Vec<(VertexId, f64)>,
}

/// Bound on the vertices one [`SurfaceReach::near_along_surface`] search settles; a search
/// that hits it answers "near" (the pair is then not merged), so the bound only ever
/// costs a merge, never an intersection.
const MAX_SETTLED: usize = 256;

impl SurfaceReach {
    /// True when the two elements of `pair` are joined by a path of mesh edges shorter than
    /// `reach`: they are then near each other *along the surface*, i.e. neighbours on one
    /// sheet that only look proximate because the edges between them are tiny (sliver
    /// triangles, marching-cubes output), not two sheets that came together. Los Topos
    /// §7.1 merges surfaces that approach each other; snapping such neighbours would
    /// instead crumple one sheet (and leave elements touching for the next step). Two
    /// sheets that touch, even at a fresh snap vertex `s`, are joined only through `s`, so
    /// pairs around it are at least twice their distance from `s` apart along the
    /// surface and still merge.
    ///
    /// Bounded Dijkstra from the first element's vertices over edges, stopping at `reach`.
    pub fn near_along_surface(&mut self, mesh: &LabeledMesh, pair: &Pair, reach: f64) -> bool {
        let (from, nf, to, nt) = pair.elements(mesh);
        let to = &to[..nt];
        self.heap.clear();
        self.settled.clear();
        let key = |d: f64| d.to_bits();
        for &v in &from[..nf] {
            self.heap.push(Reverse((key(0.0), v.raw())));
        }
        while let Some(Reverse((bits, raw))) = self.heap.pop() {
            let (d, v) = (f64::from_bits(bits), VertexId::new(raw));
            if d > reach {
                return false;
            }
            if self.settled.iter().any(|s| s.0 == v) {
                continue;
            }
            if to.contains(&v) {
                return true;
            }
            if self.settled.len() >= MAX_SETTLED {
                return true;
            }
            self.settled.push((v, d));
            let p = mesh.position(v);
            for t in mesh.vertex_triangles(v) {
                for w in mesh.tri(t) {
                    if w == v || self.settled.iter().any(|s| s.0 == w) {
                        continue;
                    }
                    let e = d + p.distance(mesh.position(w));
                    if e <= reach {
                        self.heap.push(Reverse((key(e), w.raw())));
                    }
                }
            }
        }
        false
    }
}
