//! Building the corner table: grouping triangle edges and pairing sides radially.
//!
//! Every triangle edge is seen as an *incidence* `(t, k)`: the edge of triangle `t` opposite
//! its slot `k`. Incidences of the same undirected edge are grouped by a counting sort on
//! the lower vertex id followed by a tiny sort on the higher one — linear time and
//! cache-friendly, which is what lets a million-triangle mesh connect in tens of
//! milliseconds.
//!
//! Pairing (why it is right): look down the edge axis `d = p(hi) − p(lo)` and give each
//! incident triangle the angle θ of its third vertex. A triangle whose front traversal runs
//! `lo → hi` has a right-hand normal pointing towards increasing θ, so its *front* side
//! faces the wedge after it (counter-clockwise about `d`) and its back side the wedge
//! before it; a triangle running `hi → lo` is the other way round. Sorting by θ and pairing
//! each triangle's "+θ" side with the next triangle's "−θ" side joins exactly the sides
//! that bound the same wedge of space — the *opposite* pointers of the 2024 paper. With two
//! triangles the cyclic order is unique and no geometry is needed.

use glam::DVec3;

use crate::corner::Side;
use crate::ids::{CornerId, TriId, VertexId};

/// One incidence of an undirected edge `lo < hi`: triangle `tri`, whose edge opposite
/// `slot` is `{lo, hi}`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EdgeIncidence {
    /// Lower vertex id of the edge.
    pub lo: VertexId,
    /// Higher vertex id of the edge (equal to `lo` for a degenerate triangle's edge).
    pub hi: VertexId,
    /// The incident triangle.
    pub tri: TriId,
    /// Slot (0..3) of the triangle's vertex opposite the edge.
    pub slot: u8,
}

impl EdgeIncidence {
    /// True when the triangle's front side traverses the edge from `lo` to `hi`.
    #[inline]
    pub fn runs_lo_to_hi(&self, tris: &[[VertexId; 3]]) -> bool {
        tris[self.tri.idx()][(self.slot as usize + 1) % 3] == self.lo
    }

    /// The corner of the side that faces increasing θ about `lo → hi` (see module doc).
    #[inline]
    pub fn ccw_corner(&self, tris: &[[VertexId; 3]]) -> CornerId {
        let side = if self.runs_lo_to_hi(tris) {
            Side::Front
        } else {
            Side::Back
        };
        CornerId::of(self.tri, side, self.slot as usize)
    }

    /// The corner of the side that faces decreasing θ about `lo → hi`.
    #[inline]
    pub fn cw_corner(&self, tris: &[[VertexId; 3]]) -> CornerId {
        self.ccw_corner(tris).dual()
    }
}

/// All edge incidences of a set of triangles, grouped by undirected edge.
#[derive(Clone, Debug, Default)]
pub struct EdgeTable {
    incidences: Vec<EdgeIncidence>,
    /// `group_starts[i]..group_starts[i+1]` is edge `i`; one extra entry at the end.
    group_starts: Vec<u32>,
}

impl EdgeTable {
    /// Groups the edges of the live triangles (`alive[t]`) of a mesh with `vertex_count`
    /// vertices. Triangles must reference vertices `< vertex_count`.
    pub fn build(tris: &[[VertexId; 3]], alive: &[bool], vertex_count: usize) -> EdgeTable {
        // Counting sort by the lower vertex id.
        let mut starts = vec![0u32; vertex_count + 1];
        for (t, tri) in tris.iter().enumerate() {
            if !alive[t] {
                continue;
            }
            for k in 0..3 {
                let (a, b) = (tri[(k + 1) % 3], tri[(k + 2) % 3]);
                starts[a.min(b).idx() + 1] += 1;
            }
        }
        for i in 0..vertex_count {
            starts[i + 1] += starts[i];
        }
        let total = starts[vertex_count] as usize;
        let placeholder = EdgeIncidence {
            lo: VertexId::new(0),
            hi: VertexId::new(0),
            tri: TriId::new(0),
            slot: 0,
        };
        let mut incidences = vec![placeholder; total];
        let mut fill = starts.clone();
        for (t, tri) in tris.iter().enumerate() {
            if !alive[t] {
                continue;
            }
            for k in 0..3 {
                let (a, b) = (tri[(k + 1) % 3], tri[(k + 2) % 3]);
                let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
                let at = &mut fill[lo.idx()];
                incidences[*at as usize] = EdgeIncidence {
                    lo,
                    hi,
                    tri: TriId::new(t as u32),
                    slot: k as u8,
                };
                *at += 1;
            }
        }
        // Within each lower-vertex bucket (a handful of entries), sort by the higher vertex.
        let mut group_starts = Vec::with_capacity(total / 2 + 2);
        for v in 0..vertex_count {
            let bucket = &mut incidences[starts[v] as usize..starts[v + 1] as usize];
            if bucket.len() > 1 {
                bucket.sort_unstable_by_key(|e| (e.hi, e.tri, e.slot));
            }
            let base = starts[v];
            for (i, e) in bucket.iter().enumerate() {
                if i == 0 || bucket[i - 1].hi != e.hi {
                    group_starts.push(base + i as u32);
                }
            }
        }
        group_starts.push(total as u32);
        EdgeTable {
            incidences,
            group_starts,
        }
    }

    /// Number of distinct undirected edges.
    pub fn edge_count(&self) -> usize {
        self.group_starts.len() - 1
    }

    /// The incidences of each edge, one slice per edge, ordered by `(lo, hi)`.
    pub fn groups(&self) -> impl Iterator<Item = &[EdgeIncidence]> + '_ {
        self.group_starts
            .windows(2)
            .map(|w| &self.incidences[w[0] as usize..w[1] as usize])
    }

    /// Mutable incidences of each edge (to sort them radially in place).
    pub fn groups_mut(&mut self) -> impl Iterator<Item = &mut [EdgeIncidence]> + '_ {
        let mut rest: &mut [EdgeIncidence] = &mut self.incidences;
        let mut consumed = 0u32;
        self.group_starts.windows(2).map(move |w| {
            let len = (w[1] - w[0]) as usize;
            debug_assert_eq!(w[0], consumed);
            consumed = w[1];
            let (head, tail) = std::mem::take(&mut rest).split_at_mut(len);
            rest = tail;
            head
        })
    }
}

/// Sorts the incidences of one edge by the angle of their third vertex about `lo → hi`.
///
/// Floating-point angles suffice here: the order only matters where sheets meet at a
/// non-manifold edge, and ties (coincident sheets) are broken by triangle id so the result
/// is deterministic. Non-finite positions sort last instead of panicking.
pub fn sort_radially(group: &mut [EdgeIncidence], tris: &[[VertexId; 3]], positions: &[DVec3]) {
    if group.len() <= 2 {
        return;
    }
    let lo = positions[group[0].lo.idx()];
    let axis = (positions[group[0].hi.idx()] - lo).normalize_or_zero();
    let third = |e: &EdgeIncidence| {
        let w = positions[tris[e.tri.idx()][e.slot as usize].idx()] - lo;
        w - axis * axis.dot(w)
    };
    // Reference direction: the first incident triangle's third vertex.
    let e1 = third(&group[0]).normalize_or_zero();
    let e1 = if e1 == DVec3::ZERO {
        axis.any_orthonormal_vector()
    } else {
        e1
    };
    let e2 = axis.cross(e1);
    group.sort_by(|a, b| {
        let angle = |e: &EdgeIncidence| {
            let w = third(e);
            w.dot(e2).atan2(w.dot(e1))
        };
        angle(a)
            .total_cmp(&angle(b))
            .then(a.tri.cmp(&b.tri))
            .then(a.slot.cmp(&b.slot))
    });
}

/// Calls `pair(a, b)` for each pair of corners whose sides face the same wedge around one
/// radially sorted edge. A lone incidence (a boundary edge) or a degenerate edge
/// (`lo == hi`) produces no pair.
pub fn pair_sides(
    group: &[EdgeIncidence],
    tris: &[[VertexId; 3]],
    mut pair: impl FnMut(CornerId, CornerId),
) {
    let m = group.len();
    if m < 2 || group[0].lo == group[0].hi {
        return;
    }
    for i in 0..m {
        let here = group[i];
        let next = group[(i + 1) % m];
        pair(here.ccw_corner(tris), next.cw_corner(tris));
    }
}
