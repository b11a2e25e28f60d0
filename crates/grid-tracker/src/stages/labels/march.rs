//! Fast marching of nearest breaking points over grid nodes (§8.1, after Sethian 1999).
//!
//! Each open node keeps the nearest breaking point found so far and its Euclidean
//! distance. Nodes are finalised in order of increasing distance (a binary heap, as in
//! Dijkstra's algorithm and the fast marching method); a finalised node offers its
//! breaking point to its lattice neighbours ([`STENCIL`]), which take it if it is nearer than what
//! they have. Propagating the point itself rather than a distance value means the
//! distances are exact distances to actual breaking points, and the label travels with
//! the point (the closest-point variant of fast marching used for label and velocity
//! extension).

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use glam::{DVec3, IVec3};

use super::BreakingPoint;

/// The nearest breaking point known for a node, and its distance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Nearest {
    /// The breaking point.
    pub point: BreakingPoint,
    /// Its distance from the node.
    pub distance: f64,
}

/// Neighbours a finalised node offers its point to: the 26 around it. The face
/// neighbours alone (6) already connect the lattice; the diagonals let a point reach
/// nodes whose nearest point is not the nearest point of any face neighbour, which cuts
/// the error of closest-point propagation several-fold for little extra work.
pub const STENCIL: usize = 26;

/// The lattice offsets of the stencil.
pub const OFFSETS: [IVec3; STENCIL] = offsets();

const fn offsets() -> [IVec3; STENCIL] {
    let mut out = [IVec3::ZERO; STENCIL];
    let (mut i, mut k) = (0, 0);
    while i < 27 {
        if i != 13 {
            out[k] = IVec3::new(i % 3 - 1, (i / 3) % 3 - 1, i / 9 - 1);
            k += 1;
        }
        i += 1;
    }
    out
}

/// A heap entry: smallest distance first, then smallest node (deterministic ties).
#[derive(Clone, Copy, Debug)]
struct Item {
    distance: f64,
    node: u32,
}

impl PartialEq for Item {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for Item {}
impl PartialOrd for Item {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Item {
    /// Reversed, so that `BinaryHeap` (a max-heap) pops the nearest first.
    fn cmp(&self, other: &Self) -> Ordering {
        other
            .distance
            .total_cmp(&self.distance)
            .then(other.node.cmp(&self.node))
    }
}

/// Work bound per node: a node's distance only decreases, by taking a strictly nearer
/// breaking point, which in practice happens a handful of times, and each decrease pushes
/// one heap entry; past this many pops per node (plus the seeds) the marching stops,
/// keeping what it has.
const UPDATES_PER_NODE: usize = 64;

/// Marches from `seeds` (`(node, breaking point)`) over the nodes with `open[node]`,
/// improving `best`; `neighbours(i, out)` writes the stencil neighbours of node `i` into
/// `out` and returns how many. Returns the number of updates made.
///
/// Closed nodes are never entered or changed. Allocation-free apart from the heap.
pub fn march(
    positions: &[DVec3],
    open: &[bool],
    neighbours: &impl Fn(u32, &mut [u32; STENCIL]) -> usize,
    seeds: impl Iterator<Item = (u32, BreakingPoint)>,
    best: &mut [Option<Nearest>],
) -> usize {
    let mut heap = BinaryHeap::new();
    let mut updates = 0usize;
    let mut offer = |heap: &mut BinaryHeap<Item>,
                     best: &mut [Option<Nearest>],
                     j: u32,
                     point: BreakingPoint| {
        let distance = positions[j as usize].distance(point.position);
        if best[j as usize].is_none_or(|b| distance < b.distance) {
            best[j as usize] = Some(Nearest { point, distance });
            heap.push(Item { distance, node: j });
            updates += 1;
        }
    };
    for (i, point) in seeds {
        if open.get(i as usize).copied().unwrap_or(false) {
            offer(&mut heap, best, i, point);
        }
    }
    let budget = heap.len() + UPDATES_PER_NODE * positions.len();
    let mut nb = [0u32; STENCIL];
    for _ in 0..budget {
        let Some(Item { distance, node }) = heap.pop() else {
            break;
        };
        let Some(cur) = best[node as usize] else {
            continue;
        };
        if cur.distance < distance {
            continue; // stale entry
        }
        let k = neighbours(node, &mut nb);
        for &j in &nb[..k] {
            if open[j as usize] {
                offer(&mut heap, best, j, cur.point);
            }
        }
    }
    updates
}
