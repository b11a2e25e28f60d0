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
use std::collections::{BTreeMap, BinaryHeap, HashMap};
use std::hash::BuildHasherDefault;

use glam::{DVec3, IVec3};

use super::BreakingPoint;
use super::nearest::nearest_of;
use crate::stages::grid::tiles::TileHasher;

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

/// The open nodes of a march, popped in exactly the order of one binary heap over all of
/// them ((distance, node), nearest first), but held in buckets of nearby distances of
/// which only the nearest is a heap.
///
/// Why: a march over a million nodes keeps hundreds of thousands of entries queued, and
/// every pop of one heap that size sifts through levels far apart in memory (on 6 bunnies
/// the time per update grew fourfold from 522k to 1.35M triangles). Here a pop sifts
/// through one bucket's heap, and an entry for a later bucket is only appended to its
/// list.
///
/// Buckets are ranges of the distance's bit pattern (its exponent and top mantissa bits:
/// 256 buckets per doubling of the distance), so they need no length scale and order
/// like the distances themselves. An entry nearer than the current bucket (a node can be
/// offered a point nearer to it than the node offering it) joins the current heap, which
/// stays correct: every entry of a later bucket is farther than every entry of the
/// current one, so the current heap's top is always the nearest entry of all.
#[derive(Debug, Default)]
struct BucketQueue {
    /// The entries of bucket `current` and of nearer ones pushed since it became current.
    near: BinaryHeap<Item>,
    /// Bucket of `near`.
    current: u32,
    /// Later buckets, unordered inside.
    later: BTreeMap<u32, Vec<Item>>,
    /// Entries held in all.
    len: usize,
    /// Emptied bucket lists kept for reuse, so that a march allocates a handful of them.
    spare: Vec<Vec<Item>>,
}

impl BucketQueue {
    /// The bucket of `distance`: a non-decreasing function of it in `f64::total_cmp`
    /// order (negative distances, which a march never makes, all map to bucket 0).
    #[inline]
    fn bucket(distance: f64) -> u32 {
        if distance.is_sign_negative() {
            0
        } else {
            (distance.to_bits() >> 44) as u32
        }
    }

    fn len(&self) -> usize {
        self.len
    }

    #[inline]
    fn push(&mut self, item: Item) {
        self.len += 1;
        let b = Self::bucket(item.distance);
        if b <= self.current {
            self.near.push(item);
        } else {
            let spare = &mut self.spare;
            self.later
                .entry(b)
                .or_insert_with(|| spare.pop().unwrap_or_default())
                .push(item);
        }
    }

    /// Makes the nearest non-empty bucket current if the current one is empty.
    #[inline]
    fn fill(&mut self) {
        if !self.near.is_empty() {
            return;
        }
        if let Some((b, mut items)) = self.later.pop_first() {
            self.current = b;
            let mut heap = std::mem::take(&mut self.near).into_vec();
            heap.clear();
            heap.append(&mut items);
            self.spare.push(items);
            self.near = BinaryHeap::from(heap);
        }
    }

    /// The nearest entry.
    #[inline]
    fn peek(&mut self) -> Option<Item> {
        self.fill();
        self.near.peek().copied()
    }

    /// Removes the nearest entry.
    #[inline]
    fn pop(&mut self) -> Option<Item> {
        self.fill();
        let item = self.near.pop();
        self.len -= usize::from(item.is_some());
        item
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

/// A Dijkstra-ordered closest-point propagation in progress: the heap of open nodes and
/// the number of updates made. Shared by the plain march and the levels of the far-field
/// march, which differ only in which nodes they start from and where they stop.
struct Marching {
    heap: BucketQueue,
    updates: usize,
}

impl Marching {
    fn new() -> Self {
        Marching {
            heap: BucketQueue::default(),
            updates: 0,
        }
    }

    /// Offers `point` (at `position`) to node `j` (at `at`): taken when `j` is open and
    /// the point is strictly nearer than what it has.
    #[inline(always)]
    fn offer(&mut self, slots: &mut [Slot], j: u32, at: DVec3, point: u32, position: DVec3) {
        let slot = &mut slots[j as usize];
        if slot.point == Slot::CLOSED {
            return;
        }
        let distance = at.distance(position);
        if slot.point == Slot::NONE || distance < slot.distance {
            *slot = Slot { distance, point };
            self.heap.push(Item { distance, node: j });
            self.updates += 1;
        }
    }

    /// Offers every seed `(node, index into points)` to its node.
    fn seed(
        &mut self,
        nodes: &impl Nodes,
        points: &[BreakingPoint],
        seeds: impl Iterator<Item = (u32, u32)>,
        slots: &mut [Slot],
    ) {
        for (i, point) in seeds {
            if (i as usize) < slots.len() {
                let at = nodes.position(i);
                self.offer(slots, i, at, point, points[point as usize].position);
            }
        }
    }

    /// Queues node `i` with the point it already holds (resuming from an earlier level).
    fn resume(&mut self, slots: &[Slot], i: u32) {
        let slot = slots[i as usize];
        if slot.point < Slot::CLOSED {
            self.heap.push(Item {
                distance: slot.distance,
                node: i,
            });
        }
    }

    /// Finalises nodes in order of (distance, node) until the heap is empty or the work
    /// bound is spent.
    fn run(&mut self, nodes: &impl Nodes, points: &[BreakingPoint], slots: &mut [Slot]) {
        let budget = self.heap.len() + UPDATES_PER_NODE * nodes.len();
        for _ in 0..budget {
            let Some(Item { distance, node }) = self.heap.peek() else {
                break;
            };
            self.heap.pop();
            let cur = slots[node as usize];
            if cur.point >= Slot::CLOSED || cur.distance < distance {
                continue; // stale entry
            }
            let position = points[cur.point as usize].position;
            nodes.for_each_neighbour(node, |j, at| {
                self.offer(slots, j, at, cur.point, position);
            });
        }
    }
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
    let mut marching = Marching::new();
    marching.seed(nodes, points, seeds, slots);
    marching.run(nodes, points, slots);
    marching.updates
}

/// The region's nodes at the two resolutions of [`march_far_field`], in lattice order
/// (z, then y, then x).
pub trait Levels {
    /// The nodes with the full stencil (every neighbour one lattice step away).
    fn fine(&self) -> &(impl Nodes + Sync);
    /// The coarse nodes (lattice coordinates multiples of the block) with the stencil
    /// scaled by the block; [`Nodes::for_each_neighbour`] is only asked about them.
    fn coarse(&self) -> &(impl Nodes + Sync);
    /// Whether node `i` is a coarse node.
    fn is_coarse(&self, i: u32) -> bool;
    /// The coarse cell holding node `i`, in block units (a coarse node is the lowest
    /// corner of its own cell).
    fn cell(&self, i: u32) -> IVec3;
    /// The part of the region node `i` lies in; a node takes only points of its own part.
    fn part(&self, i: u32) -> u32;
    /// The centre of the nodes of `cell` (those [`Levels::cell`] maps to it).
    fn centre(&self, cell: IVec3) -> DVec3;
    /// Calls `visit(j)` for every region node `j` at a corner of the 3 × 3 × 3 coarse
    /// cells centred on `cell`, and for every region node within one lattice step of
    /// `cell` (so for every stencil neighbour of its nodes); some more than once.
    fn around(&self, cell: IVec3, visit: impl FnMut(u32));
}

/// What [`march_far_field`] did, for the stage's statistics.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FarFieldStats {
    /// Updates of all levels (work measure).
    pub updates: usize,
    /// Nodes beyond the band, given a point from the coarse march.
    pub far_nodes: usize,
    /// Far nodes no point of their part reached that way, marched from their neighbours.
    pub rest_nodes: usize,
}

/// The nearest breaking points of the nodes beyond the band, for regions deep in volume
/// such as the overlap of solids. Why not [`march_over`] everywhere: where rotated copies
/// of a solid overlap, the non-physical region is a volume, and a full-resolution march
/// over it is memory-bound work per node of that volume (measured on 6 bunnies at 5.4M
/// triangles: 19M region cells, labels 39 s of a 121 s `fix`), while labels change only
/// across surfaces.
///
/// On entry `slots` holds, for every node `near` (in the band: within a few cells of a
/// breaking point), its nearest point (found exactly by the caller, see
/// [`super::nearest`]); every other node is [`Slot::OPEN`] or [`Slot::CLOSED`].
/// `groups[k]` is the part of point `k` ([`Levels::part`]); `slabs` split the nodes
/// into ranges whose coarse cells share their z coordinate.
///
/// 1. **Coarse**: the march resumes from every coarse node holding a point, over the
///    coarse nodes of its part only (block³ times fewer nodes).
/// 2. **Gather**: every node beyond the band takes the nearest point of its part among
///    those held by the coarse nodes of the 3 × 3 × 3 coarse cells around its own and by
///    the band nodes next to its cell. The candidates are gathered once per coarse cell
///    (block³ nodes share them, and deep inside an overlap they are a handful of distinct
///    points), in parallel over slabs of coarse cells. A node scans them nearest to the
///    cell's centre first and stops at the first that cannot beat its best, so it costs
///    a few distances and no lookups.
/// 3. **Rest**: a node that none of those reach (its coarse neighbours lie outside the
///    region or hold points of another part) is marched over such nodes only, from its
///    reached neighbours.
///
/// Beyond the band a node's point may be up to about ℓ/2 farther than the nearest (the
/// coarse march's error); labels change across surfaces where two coarse points meet,
/// and both are candidates there.
///
/// Deterministic: levels 1 and 3 are sequential in the order of [`march_over`], level 2
/// is a pure function per node (ties go to the lower point id).
pub fn march_far_field(
    levels: &(impl Levels + Sync),
    slabs: &[std::ops::Range<usize>],
    points: &[BreakingPoint],
    groups: &[u32],
    slots: &mut [Slot],
    near: &[bool],
) -> FarFieldStats {
    use rayon::prelude::*;
    let fine = levels.fine();
    let n = fine.len();
    let mut stats = FarFieldStats::default();
    let far = |slots: &[Slot], i: usize| !near[i] && slots[i].point != Slot::CLOSED;
    if !(0..n).any(|i| far(slots, i)) {
        return stats; // nothing beyond the band
    }

    // 1. Coarse.
    let mut marching = Marching::new();
    for i in 0..n as u32 {
        if levels.is_coarse(i) {
            marching.resume(slots, i);
        }
    }
    // Within each part only: coarse neighbours are a block apart, so they may lie across
    // a gap between parts, and a point of one part must not reach (nor replace the exact
    // point of) a node of another.
    let coarse = Only {
        nodes: levels.coarse(),
        keep: |i, j| levels.part(i) == levels.part(j),
    };
    marching.run(&coarse, points, slots);
    stats.updates += marching.updates;
    drop(marching);

    // 2. Gather, per slab of coarse cells.
    let snapshot: &[Slot] = slots;
    let gathered: Vec<Vec<Slot>> = slabs
        .par_iter()
        .map(|range| {
            let mut candidates = CellCandidates::default();
            range
                .clone()
                .map(|i| {
                    if !far(snapshot, i) {
                        return snapshot[i];
                    }
                    let i = i as u32;
                    let cell = levels.cell(i);
                    let centre = levels.centre(cell);
                    let around = |visit: &mut dyn FnMut(u32)| levels.around(cell, visit);
                    let list = candidates.of(cell, centre, around, snapshot, points);
                    let (at, part) = (fine.position(i), levels.part(i));
                    // With a margin for rounding: the scan's bound must not cut too early.
                    let offset = at.distance(centre) * (1.0 + 1e-12) + 1e-300;
                    let position = |k: u32| points[k as usize].position;
                    match nearest_of(list, at, offset, part, groups, position, f64::INFINITY) {
                        Some((distance, point)) => Slot { distance, point },
                        None => Slot::OPEN,
                    }
                })
                .collect()
        })
        .collect();
    for (range, slab) in slabs.iter().zip(gathered) {
        slots[range.clone()].copy_from_slice(&slab);
    }
    let mut rest: Vec<u32> = Vec::new();
    for i in 0..n {
        if far(slots, i) {
            stats.far_nodes += 1;
            if slots[i].point == Slot::NONE {
                rest.push(i as u32);
            }
        }
    }
    stats.rest_nodes = rest.len();

    // 3. Rest.
    if rest.is_empty() {
        return stats;
    }
    let mut open = vec![false; n];
    for &i in &rest {
        open[i as usize] = true;
    }
    let only = Only {
        nodes: fine,
        keep: |_, j: u32| open[j as usize],
    };
    let mut marching = Marching::new();
    for &i in &rest {
        let at = fine.position(i);
        fine.for_each_neighbour(i, |j, _| {
            let s = slots[j as usize];
            if !open[j as usize] && s.point < Slot::CLOSED {
                let position = points[s.point as usize].position;
                marching.offer(slots, i, at, s.point, position);
            }
        });
    }
    marching.run(&only, points, slots);
    stats.updates += marching.updates;
    stats
}

/// The candidate points of the coarse cells of one slab (see [`march_far_field`]),
/// gathered on a cell's first node and kept for the rest: distinct points with their
/// distance from the cell's centre, nearest first.
#[derive(Default)]
struct CellCandidates {
    /// Cell to its range in `list`.
    cells: HashMap<IVec3, (u32, u32), BuildHasherDefault<TileHasher>>,
    list: Vec<(f64, u32)>,
    /// The last cell asked about (consecutive nodes along x share it), and its range.
    last: Option<(IVec3, (u32, u32))>,
    scratch: Vec<u32>,
}

impl CellCandidates {
    /// The candidates of `cell` (centred on `centre`): the points `slots` holds at the
    /// nodes `around` visits ([`Levels::around`]).
    fn of(
        &mut self,
        cell: IVec3,
        centre: DVec3,
        around: impl FnOnce(&mut dyn FnMut(u32)),
        slots: &[Slot],
        points: &[BreakingPoint],
    ) -> &[(f64, u32)] {
        let range = match self.last {
            Some((c, range)) if c == cell => range,
            _ => {
                let (list, scratch) = (&mut self.list, &mut self.scratch);
                let range = *self.cells.entry(cell).or_insert_with(|| {
                    scratch.clear();
                    around(&mut |j| {
                        let point = slots[j as usize].point;
                        if point < Slot::CLOSED {
                            scratch.push(point);
                        }
                    });
                    scratch.sort_unstable();
                    scratch.dedup();
                    let first = list.len();
                    list.extend(
                        scratch
                            .iter()
                            .map(|&k| (centre.distance(points[k as usize].position), k)),
                    );
                    list[first..].sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                    (first as u32, list.len() as u32)
                });
                self.last = Some((cell, range));
                range
            }
        };
        &self.list[range.0 as usize..range.1 as usize]
    }
}

/// The neighbours `j` of each node `i` of `nodes` for which `keep(i, j)` holds.
struct Only<'a, N, F> {
    nodes: &'a N,
    keep: F,
}

impl<N: Nodes, F: Fn(u32, u32) -> bool> Nodes for Only<'_, N, F> {
    fn len(&self) -> usize {
        self.nodes.len()
    }
    #[inline]
    fn for_each_neighbour(&self, i: u32, mut offer: impl FnMut(u32, DVec3)) {
        self.nodes.for_each_neighbour(i, |j, at| {
            if (self.keep)(i, j) {
                offer(j, at);
            }
        });
    }
    fn position(&self, i: u32) -> DVec3 {
        self.nodes.position(i)
    }
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

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// The bucket queue must pop exactly what one binary heap over the same entries
        /// pops, including entries pushed nearer than the bucket being drained (a march
        /// offers those) and ties in distance, so that labels do not depend on it.
        #[test]
        fn bucket_queue_pops_like_one_heap(
            ops in prop::collection::vec((0u8..3, 0.0f64..4.0, 0u32..50), 1..400),
        ) {
            let mut heap = BinaryHeap::new();
            let mut queue = BucketQueue::default();
            for (op, distance, node) in ops {
                if op == 0 {
                    prop_assert_eq!(queue.pop().map(|i| (i.distance, i.node)),
                        heap.pop().map(|i: Item| (i.distance, i.node)));
                } else {
                    // Rounded distances make exact ties; tiny ones share a bucket.
                    let distance = if op == 1 { (distance * 4.0).round() / 4.0 } else { distance * 1e-3 };
                    let item = Item { distance, node };
                    heap.push(item);
                    queue.push(item);
                }
                prop_assert_eq!(queue.len(), heap.len());
                prop_assert_eq!(queue.peek().map(|i| (i.distance, i.node)),
                    heap.peek().map(|i| (i.distance, i.node)));
            }
            while let Some(expected) = heap.pop() {
                let got = queue.pop().expect("queue ran out before the heap");
                prop_assert_eq!((got.distance, got.node), (expected.distance, expected.node));
            }
            prop_assert_eq!(queue.len(), 0);
        }
    }
}
