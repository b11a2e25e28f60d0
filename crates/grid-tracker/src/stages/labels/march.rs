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

/// The nodes a march runs over, as [`march_over`] needs them.
pub trait Nodes {
    /// Number of nodes.
    fn len(&self) -> usize;
    /// True without nodes.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Calls `offer(j, position of j)` for every stencil neighbour `j` of node `i`, in
    /// [`OFFSETS`] order.
    fn for_each_neighbour(&self, i: u32, offer: impl FnMut(u32, DVec3));
    /// Position of node `i`.
    fn position(&self, i: u32) -> DVec3;
}

/// What a node holds during a march: its nearest point so far (an index into the
/// points) and the distance to it. One 16-byte slot per node, so that a neighbour costs
/// one memory access (the stencil touches 9 lattice rows per pop).
#[derive(Clone, Copy, Debug)]
pub struct Slot {
    /// Distance to `point` (meaningless while `point` is [`Slot::NONE`] or [`Slot::CLOSED`]).
    pub distance: f64,
    /// Index of the nearest point, [`Slot::NONE`] or [`Slot::CLOSED`].
    pub point: u32,
}

impl Slot {
    /// An open node no point has reached.
    pub const NONE: u32 = u32::MAX;
    /// A closed node: never entered or changed.
    pub const CLOSED: u32 = u32::MAX - 1;
    /// The slot of an open node.
    pub const OPEN: Slot = Slot {
        distance: f64::INFINITY,
        point: Slot::NONE,
    };
    /// The slot of a closed node.
    pub const SHUT: Slot = Slot {
        distance: f64::INFINITY,
        point: Slot::CLOSED,
    };
}

/// Marches from `seeds` (`(node, index into points)`) over the nodes whose slot is open
/// ([`Slot::OPEN`] or already reached), improving `slots`. Returns the number of updates.
///
/// Same propagation as [`march`] (which wraps it): nodes finalised in order of
/// (distance, node), neighbours offered the point in [`OFFSETS`] order, a strictly
/// nearer point replaces the current one.
pub fn march_over(
    nodes: &impl Nodes,
    points: &[BreakingPoint],
    seeds: impl Iterator<Item = (u32, u32)>,
    slots: &mut [Slot],
) -> usize {
    let mut heap = BinaryHeap::new();
    let mut updates = 0usize;
    #[inline(always)]
    fn offer(
        heap: &mut BinaryHeap<Item>,
        slots: &mut [Slot],
        updates: &mut usize,
        j: u32,
        at: DVec3,
        point: u32,
        position: DVec3,
    ) {
        let slot = &mut slots[j as usize];
        if slot.point == Slot::CLOSED {
            return;
        }
        let distance = at.distance(position);
        if slot.point == Slot::NONE || distance < slot.distance {
            *slot = Slot { distance, point };
            heap.push(Item { distance, node: j });
            *updates += 1;
        }
    }
    for (i, point) in seeds {
        if (i as usize) < slots.len() {
            let at = nodes.position(i);
            offer(
                &mut heap,
                slots,
                &mut updates,
                i,
                at,
                point,
                points[point as usize].position,
            );
        }
    }
    let budget = heap.len() + UPDATES_PER_NODE * nodes.len();
    for _ in 0..budget {
        let Some(Item { distance, node }) = heap.pop() else {
            break;
        };
        let cur = slots[node as usize];
        if cur.point >= Slot::CLOSED || cur.distance < distance {
            continue; // stale entry
        }
        let position = points[cur.point as usize].position;
        nodes.for_each_neighbour(node, |j, at| {
            offer(&mut heap, slots, &mut updates, j, at, cur.point, position);
        });
    }
    updates
}

/// Marches from `seeds` (`(node, breaking point)`) over the nodes with `open[node]`,
/// improving `best`; `neighbours(i, out)` writes the stencil neighbours of node `i` into
/// `out` and returns how many. Returns the number of updates made.
///
/// Closed nodes are never entered or changed. A convenience over [`march_over`].
pub fn march(
    positions: &[DVec3],
    open: &[bool],
    neighbours: &impl Fn(u32, &mut [u32; STENCIL]) -> usize,
    seeds: impl Iterator<Item = (u32, BreakingPoint)>,
    best: &mut [Option<Nearest>],
) -> usize {
    struct Listed<'a, F> {
        positions: &'a [DVec3],
        neighbours: &'a F,
    }
    impl<F: Fn(u32, &mut [u32; STENCIL]) -> usize> Nodes for Listed<'_, F> {
        fn len(&self) -> usize {
            self.positions.len()
        }
        fn for_each_neighbour(&self, i: u32, mut offer: impl FnMut(u32, DVec3)) {
            let mut nb = [0u32; STENCIL];
            let k = (self.neighbours)(i, &mut nb);
            for &j in &nb[..k] {
                offer(j, self.positions[j as usize]);
            }
        }
        fn position(&self, i: u32) -> DVec3 {
            self.positions[i as usize]
        }
    }
    let mut points: Vec<BreakingPoint> = best.iter().flatten().map(|b| b.point).collect();
    let mut slots: Vec<Slot> = Vec::with_capacity(best.len());
    let mut known = 0u32;
    for (i, b) in best.iter().enumerate() {
        slots.push(match (open.get(i).copied().unwrap_or(false), b) {
            (false, _) => Slot::SHUT,
            (true, Some(b)) => {
                known += 1;
                Slot {
                    distance: b.distance,
                    point: known - 1,
                }
            }
            (true, None) => Slot::OPEN,
        });
    }
    let seeds: Vec<(u32, u32)> = seeds
        .map(|(i, p)| {
            points.push(p);
            (i, points.len() as u32 - 1)
        })
        .collect();
    let nodes = Listed {
        positions,
        neighbours,
    };
    let updates = march_over(&nodes, &points, seeds.into_iter(), &mut slots);
    for (b, s) in best.iter_mut().zip(&slots) {
        if s.point < Slot::CLOSED {
            *b = Some(Nearest {
                point: points[s.point as usize],
                distance: s.distance,
            });
        }
    }
    updates
}
