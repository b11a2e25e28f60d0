//! Broad phase: a bounding-volume hierarchy over axis-aligned boxes, to find the pairs of
//! items (triangles, swept primitives) whose boxes overlap, before any exact test.
//!
//! Used by the self-intersection check in [`crate::validate`], and meant for the collision
//! tracker's proximity and CCD candidates: items are any boxes with `u32` ids, and a
//! [`Bvh::refit`] reuses the tree when boxes move a little.
//!
//! **Design** (a *linear* BVH with an implicit tree). Items are sorted along a 63-bit
//! Morton curve of their box centres (rayon parallel sort) and cut into a power-of-two
//! number of leaves of [`MIN_LEAF_SIZE`] to twice that many consecutive items; the tree
//! over the leaves is a complete binary tree stored as an implicit heap (node `k` has
//! children `2k`, `2k + 1`, leaf `i` is node `leaves + i`). Why this shape:
//! - building is a sort plus one parallel pass per level — no recursion, no pointers,
//!   nothing to balance, no padding;
//! - [`Bvh::self_pairs_fold`] is a dual-tree traversal ("pairs within a node" = pairs
//!   within each child + pairs across the children), so every unordered pair is found
//!   exactly once and the shared upper levels are visited once, not once per item;
//! - every traversal runs on a fixed-size array stack bounded by the tree height: no
//!   recursion and no heap allocation per query or per pair.
//!
//! A uniform hash grid was the alternative. Measured on the 1.3M triangle boxes of an
//! icosphere (one thread, CPU time, see the ignored `bench` test): BVH build 0.15 s +
//! all 7.9M overlapping pairs 0.35 s, against 0.9 s for a sort-based grid with the cell
//! size of the largest box (each box lands in up to 8 cells, so it sorts ~4× more keys,
//! and each pair must be de-duplicated across cells). A grid also needs a cell size and
//! degrades on adaptive meshes (large and tiny triangles together) and on the long thin
//! swept boxes of CCD, where a hierarchy adapts.
//!
//! Boxes are *closed*: touching boxes overlap, because touching triangles must reach the
//! exact tests. A box with a NaN coordinate overlaps nothing (every comparison with NaN is
//! false), so non-finite input is silently left out rather than poisoning the tree.

use glam::DVec3;
use rayon::prelude::*;

/// Fewest items per leaf (except in trees of fewer items). Leaves hold between
/// `MIN_LEAF_SIZE` and `2·MIN_LEAF_SIZE` items: the leaf count is a power of two, so
/// the implicit tree needs no padding. Leaf sizes from 2 to 8 measured alike; larger
/// leaves make a smaller tree.
pub const MIN_LEAF_SIZE: usize = 4;

/// Bound on the tree height: fewer than 2^32 items, at least [`MIN_LEAF_SIZE`] per leaf,
/// so fewer than 2^30 leaves and node indices fit in `u32`. Sizes the traversal stacks.
const MAX_HEIGHT: usize = 33;

/// A closed axis-aligned box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    /// Lower corner.
    pub min: DVec3,
    /// Upper corner.
    pub max: DVec3,
}

impl Aabb {
    /// The empty box (min = +∞, max = −∞): the identity of [`Aabb::union`].
    pub const EMPTY: Aabb = Aabb {
        min: DVec3::INFINITY,
        max: DVec3::NEG_INFINITY,
    };

    /// The box with these corners.
    #[inline]
    pub fn new(min: DVec3, max: DVec3) -> Aabb {
        Aabb { min, max }
    }

    /// The smallest box containing the points (EMPTY for none).
    #[inline]
    pub fn from_points(points: &[DVec3]) -> Aabb {
        points.iter().fold(Aabb::EMPTY, |b, &p| b.including(p))
    }

    /// This box grown to contain `p`.
    #[inline]
    pub fn including(self, p: DVec3) -> Aabb {
        self.union(Aabb { min: p, max: p })
    }

    /// The smallest box containing both. NaN coordinates are ignored (`f64::min`
    /// semantics), so one NaN item cannot hide its neighbours inside a NaN node box.
    #[inline]
    pub fn union(self, other: Aabb) -> Aabb {
        Aabb {
            min: DVec3::new(
                self.min.x.min(other.min.x),
                self.min.y.min(other.min.y),
                self.min.z.min(other.min.z),
            ),
            max: DVec3::new(
                self.max.x.max(other.max.x),
                self.max.y.max(other.max.y),
                self.max.z.max(other.max.z),
            ),
        }
    }

    /// This box grown by `margin` on every side (for proximity queries; `margin ≥ 0`).
    #[inline]
    pub fn inflated(self, margin: f64) -> Aabb {
        Aabb {
            min: self.min - DVec3::splat(margin),
            max: self.max + DVec3::splat(margin),
        }
    }

    /// True when the closed boxes share a point. False whenever a coordinate is NaN.
    #[inline]
    pub fn overlaps(&self, other: &Aabb) -> bool {
        // Non-short-circuit `&`: branch-free, which matters in traversal loops where the
        // outcome is a coin flip (glam's `BVec3::all` short-circuits).
        (self.min.x <= other.max.x)
            & (self.min.y <= other.max.y)
            & (self.min.z <= other.max.z)
            & (other.min.x <= self.max.x)
            & (other.min.y <= self.max.y)
            & (other.min.z <= self.max.z)
    }

    /// True when `p` lies in the open box (strictly inside every face). False whenever a
    /// coordinate is NaN. Blocks of space use it: their open boxes never overlap.
    #[inline]
    pub fn contains_strictly(&self, p: DVec3) -> bool {
        (self.min.x < p.x)
            & (p.x < self.max.x)
            & (self.min.y < p.y)
            & (p.y < self.max.y)
            & (self.min.z < p.z)
            & (p.z < self.max.z)
    }

    /// Centre of the box.
    #[inline]
    pub fn center(&self) -> DVec3 {
        (self.min + self.max) * 0.5
    }

    /// True when the box contains no point (some `min > max`, or a NaN).
    #[inline]
    pub fn is_empty(&self) -> bool {
        !self.min.cmple(self.max).all()
    }
}

/// Errors building a [`Bvh`].
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum BroadphaseError {
    /// `boxes` and `ids` (or a refit's new boxes) disagree in length.
    #[error("broad phase: {boxes} boxes but {ids} ids")]
    LengthMismatch {
        /// Number of boxes given.
        boxes: usize,
        /// Number of ids (or of boxes the tree was built with).
        ids: usize,
    },
    /// More items than leaves can be indexed with `u32`.
    #[error("broad phase: {0} items exceed the u32 index space")]
    TooLarge(usize),
}

/// A linear BVH over boxes with `u32` ids (see the module doc).
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    /// Item boxes in tree (Morton) order.
    boxes: Vec<Aabb>,
    /// Item ids in tree order.
    ids: Vec<u32>,
    /// Input position of each item in tree order (for [`Bvh::refit`]).
    order: Vec<u32>,
    /// Implicit tree: `nodes[1]` is the root, `nodes[k]` has children `2k`, `2k+1`, leaf
    /// `i` is `nodes[leaves + i]`; `nodes[0]` is unused.
    nodes: Vec<Aabb>,
    /// Padded leaf count, a power of two (0 for an empty tree).
    leaves: usize,
    /// Items per leaf (the last leaves may hold fewer).
    leaf_size: usize,
    /// `log2(leaves)`.
    height: u32,
}

impl Bvh {
    /// Builds the tree over `boxes`, item `i` having id `i`.
    pub fn build(boxes: &[Aabb]) -> Result<Bvh, BroadphaseError> {
        Self::build_from_fn(boxes.len(), |i| boxes[i as usize])
    }

    /// Builds the tree over `boxes` with the given ids (`ids[i]` names `boxes[i]`).
    pub fn build_with_ids(boxes: &[Aabb], ids: &[u32]) -> Result<Bvh, BroadphaseError> {
        if boxes.len() != ids.len() {
            return Err(BroadphaseError::LengthMismatch {
                boxes: boxes.len(),
                ids: ids.len(),
            });
        }
        let n = u32::try_from(boxes.len()).map_err(|_| BroadphaseError::TooLarge(boxes.len()))?;
        Self::build_impl(n, |i| boxes[i as usize], |i| ids[i as usize])
    }

    /// Builds the tree over `n` items whose boxes come from `box_of(i)`, item `i` having
    /// id `i`. Saves materialising a box array when boxes are cheap to compute (triangles
    /// from shared vertex positions); `box_of` is called three times per item.
    pub fn build_from_fn(
        n: usize,
        box_of: impl Fn(u32) -> Aabb + Sync,
    ) -> Result<Bvh, BroadphaseError> {
        let n = u32::try_from(n).map_err(|_| BroadphaseError::TooLarge(n))?;
        Self::build_impl(n, box_of, |i| i)
    }

    fn build_impl(
        n: u32,
        box_of: impl Fn(u32) -> Aabb + Sync,
        id_of: impl Fn(u32) -> u32 + Sync,
    ) -> Result<Bvh, BroadphaseError> {
        if n == 0 {
            return Ok(Bvh::default());
        }
        // Bounds of the finite centres, to quantise them onto the Morton grid.
        let (lo, hi) = (0..n)
            .into_par_iter()
            .with_min_len(4096)
            .map(|i| box_of(i).center())
            .filter(|c| c.is_finite())
            .fold(
                || (DVec3::INFINITY, DVec3::NEG_INFINITY),
                |(lo, hi), c| (lo.min(c), hi.max(c)),
            )
            .reduce(
                || (DVec3::INFINITY, DVec3::NEG_INFINITY),
                |a, b| (a.0.min(b.0), a.1.max(b.1)),
            );
        let extent = hi - lo;
        let scale = DVec3::select(extent.cmpgt(DVec3::ZERO), 2097151.0 / extent, DVec3::ZERO);
        let mut keys: Vec<(u64, u32)> = (0..n)
            .into_par_iter()
            .with_min_len(4096)
            .map(|i| {
                let c = box_of(i).center();
                let code = if c.is_finite() {
                    let q = ((c - lo) * scale).clamp(DVec3::ZERO, DVec3::splat(2097151.0));
                    morton3(q.x as u64, q.y as u64, q.z as u64)
                } else {
                    u64::MAX // non-finite centres last
                };
                (code, i)
            })
            .collect();
        keys.par_sort_unstable();
        let order: Vec<u32> = keys.into_par_iter().map(|(_, i)| i).collect();
        let sorted: Vec<Aabb> = order.par_iter().map(|&i| box_of(i)).collect();
        let ids: Vec<u32> = order.par_iter().map(|&i| id_of(i)).collect();
        let n_items = n as usize;
        let leaves = if n_items < 2 * MIN_LEAF_SIZE {
            1
        } else {
            // Largest power of two ≤ n / MIN_LEAF_SIZE.
            1usize << (usize::BITS - 1 - (n_items / MIN_LEAF_SIZE).leading_zeros())
        };
        let leaf_size = n_items.div_ceil(leaves);
        let mut bvh = Bvh {
            boxes: sorted,
            ids,
            order,
            nodes: vec![Aabb::EMPTY; 2 * leaves],
            leaves,
            leaf_size,
            height: leaves.trailing_zeros(),
        };
        bvh.fit_nodes();
        Ok(bvh)
    }

    /// Replaces the item boxes (same items, same order as given to `build`: `boxes[i]`
    /// for input item `i`) and recomputes the node boxes, keeping the tree shape. Cheap
    /// when items moved a little; rebuild after large motions to keep the tree tight.
    pub fn refit(&mut self, boxes: &[Aabb]) -> Result<(), BroadphaseError> {
        if boxes.len() != self.boxes.len() {
            return Err(BroadphaseError::LengthMismatch {
                boxes: boxes.len(),
                ids: self.boxes.len(),
            });
        }
        let order = &self.order;
        self.boxes
            .par_iter_mut()
            .with_min_len(4096)
            .zip(order.par_iter())
            .for_each(|(b, &i)| *b = boxes[i as usize]);
        self.fit_nodes();
        Ok(())
    }

    /// Leaf boxes from the items, then each level from the one below, in parallel.
    fn fit_nodes(&mut self) {
        if self.leaves == 0 {
            return;
        }
        let leaves = self.leaves;
        let leaf_size = self.leaf_size;
        let boxes = &self.boxes;
        self.nodes[leaves..]
            .par_iter_mut()
            .with_min_len(1024)
            .enumerate()
            .for_each(|(i, node)| {
                let start = (i * leaf_size).min(boxes.len());
                let end = (start + leaf_size).min(boxes.len());
                *node = boxes[start..end]
                    .iter()
                    .fold(Aabb::EMPTY, |a, b| a.union(*b));
            });
        let mut width = leaves / 2;
        while width >= 1 {
            // Parents are nodes[width..2·width], their children nodes[2·width..4·width].
            let (upper, lower) = self.nodes.split_at_mut(2 * width);
            upper[width..]
                .par_iter_mut()
                .with_min_len(1024)
                .zip(lower[..2 * width].par_chunks(2))
                .for_each(|(parent, kids)| *parent = kids[0].union(kids[1]));
            width /= 2;
        }
    }

    /// Number of items.
    pub fn len(&self) -> usize {
        self.boxes.len()
    }

    /// True when the tree holds no item.
    pub fn is_empty(&self) -> bool {
        self.boxes.is_empty()
    }

    /// Box around every item (EMPTY for an empty tree).
    pub fn bounds(&self) -> Aabb {
        self.nodes.get(1).copied().unwrap_or(Aabb::EMPTY)
    }

    /// Items of leaf `leaf` as a range of tree positions.
    #[inline]
    fn leaf_items(&self, leaf: usize) -> std::ops::Range<usize> {
        let start = (leaf * self.leaf_size).min(self.boxes.len());
        start..(start + self.leaf_size).min(self.boxes.len())
    }

    /// Calls `f(id)` for every item whose box overlaps `query` grown by `margin`.
    /// Sequential and allocation-free; run many queries in parallel from the caller.
    pub fn query(&self, query: &Aabb, margin: f64, mut f: impl FnMut(u32)) {
        if self.leaves == 0 {
            return;
        }
        let q = query.inflated(margin);
        let mut stack = [0u32; MAX_HEIGHT + 1];
        let mut top = 1;
        stack[0] = 1;
        while top > 0 {
            top -= 1;
            let k = stack[top] as usize;
            if !self.nodes[k].overlaps(&q) {
                continue;
            }
            if k >= self.leaves {
                for i in self.leaf_items(k - self.leaves) {
                    if self.boxes[i].overlaps(&q) {
                        f(self.ids[i]);
                    }
                }
            } else {
                // Depth-first: at most one pending sibling per level, so `top ≤ height + 1`.
                stack[top] = (2 * k + 1) as u32;
                stack[top + 1] = (2 * k) as u32;
                top += 2;
            }
        }
    }

    /// Every unordered pair of distinct items whose boxes overlap once one of them is
    /// grown by `margin`, each reported exactly once, folded in parallel: each rayon task
    /// starts from `identity()`, calls `fold(&mut acc, id_a, id_b)` per pair, and the
    /// task results are combined with `reduce`. Nothing is allocated per pair.
    ///
    /// Dual-tree traversal: "pairs within node k" splits into pairs within each child
    /// plus pairs across the two children, and "pairs across a and b" into the four
    /// child combinations, pruned when the boxes do not overlap. The top
    /// [`SPLIT_DEPTH`] levels are expanded breadth-first into independent jobs for rayon;
    /// each job then runs depth-first on a fixed-size stack.
    pub fn self_pairs_fold<A, I, F, R>(&self, margin: f64, identity: I, fold: F, reduce: R) -> A
    where
        A: Send,
        I: Fn() -> A + Sync + Send,
        F: Fn(&mut A, u32, u32) + Sync + Send,
        R: Fn(A, A) -> A + Sync + Send,
    {
        if self.boxes.len() < 2 {
            return identity();
        }
        // The root job is "pairs within the root"; pair jobs only arise from expansion.
        let mut jobs = vec![Job { a: 1, b: 1 }];
        for _ in 0..self.height.min(SPLIT_DEPTH) {
            let mut next = Vec::with_capacity(jobs.len() * 4);
            for job in jobs {
                self.expand(job, margin, |j| next.push(j));
            }
            jobs = next;
        }
        jobs.into_par_iter()
            .fold(&identity, |mut acc, job| {
                self.run_job(job, margin, &mut |a, b| fold(&mut acc, a, b));
                acc
            })
            .reduce(&identity, reduce)
    }

    /// Calls `f(id_a, id_b)` in parallel for every overlapping pair (see
    /// [`Bvh::self_pairs_fold`]).
    pub fn self_pairs(&self, margin: f64, f: impl Fn(u32, u32) + Sync + Send) {
        self.self_pairs_fold(margin, || (), |_, a, b| f(a, b), |_, _| ());
    }

    /// Every overlapping pair, collected (order unspecified). Convenient for tests and
    /// small inputs; prefer [`Bvh::self_pairs_fold`] for large ones.
    pub fn self_pairs_collect(&self, margin: f64) -> Vec<(u32, u32)> {
        self.self_pairs_fold(
            margin,
            Vec::new,
            |v, a, b| v.push((a, b)),
            |mut a, mut b| {
                a.append(&mut b);
                a
            },
        )
    }

    /// First leaf under node `k`.
    #[inline]
    fn first_leaf(&self, k: usize) -> usize {
        let depth = usize::BITS - 1 - k.leading_zeros();
        (k - (1 << depth)) << (self.height - depth)
    }

    /// One step of the dual traversal of an internal-node job: its sub-jobs, pruned.
    /// Invariant: a pair job is only ever pushed when its two nodes overlap (within
    /// `margin`), so popping one needs no test.
    #[inline]
    fn expand(&self, job: Job, margin: f64, mut push: impl FnMut(Job)) {
        let (a, b) = (job.a as usize, job.b as usize);
        if a == b {
            if self.first_leaf(a) * self.leaf_size >= self.boxes.len() {
                return; // beyond the last item
            }
            let (l, r) = (2 * job.a, 2 * job.a + 1);
            push(Job { a: l, b: l });
            push(Job { a: r, b: r });
            if self.near(l as usize, r as usize, margin) {
                push(Job { a: l, b: r });
            }
        } else {
            // A child of `a` can only meet a child of `b` if it meets `b` itself: two
            // tests per side first, then only the surviving combinations.
            let a_meets_b = [0, 1].map(|x| self.near(2 * a + x, b, margin));
            let b_meets_a = [0, 1].map(|y| self.near(a, 2 * b + y, margin));
            for (x, &ax) in a_meets_b.iter().enumerate() {
                for (y, &by) in b_meets_a.iter().enumerate() {
                    if ax && by && self.near(2 * a + x, 2 * b + y, margin) {
                        push(Job {
                            a: job.a * 2 + x as u32,
                            b: job.b * 2 + y as u32,
                        });
                    }
                }
            }
        }
    }

    /// Nodes `a` (grown by `margin`) and `b` overlap.
    #[inline]
    fn near(&self, a: usize, b: usize, margin: f64) -> bool {
        self.nodes[a].inflated(margin).overlaps(&self.nodes[b])
    }

    /// Runs one job depth-first. Each internal job pushes at most four sub-jobs one level
    /// down, so the stack never holds more than `3·(height + 1) + 1` jobs.
    fn run_job(&self, job: Job, margin: f64, emit: &mut impl FnMut(u32, u32)) {
        let mut stack = [Job { a: 0, b: 0 }; STACK];
        let mut top = 1;
        stack[0] = job;
        while top > 0 {
            top -= 1;
            let job = stack[top];
            let (a, b) = (job.a as usize, job.b as usize);
            if a < self.leaves {
                self.expand(job, margin, |j| {
                    stack[top] = j;
                    top += 1;
                });
                continue;
            }
            let own = self.leaf_items(a - self.leaves);
            if a == b {
                for i in own.clone() {
                    let bi = self.boxes[i].inflated(margin);
                    for j in i + 1..own.end {
                        if bi.overlaps(&self.boxes[j]) {
                            emit(self.ids[i], self.ids[j]);
                        }
                    }
                }
            } else {
                // The nodes overlap (pair jobs are pushed only then). Usually two leaves touch along a seam: keep the items of each that reach
                // the other leaf's box, then test only those against each other.
                let (grown_a, box_b) = (self.nodes[a].inflated(margin), self.nodes[b]);
                let mut near_a = [0u32; 2 * MIN_LEAF_SIZE];
                let mut near_b = [0u32; 2 * MIN_LEAF_SIZE];
                let (mut na, mut nb) = (0, 0);
                for i in own {
                    if na < near_a.len() && self.boxes[i].inflated(margin).overlaps(&box_b) {
                        near_a[na] = i as u32;
                        na += 1;
                    }
                }
                for j in self.leaf_items(b - self.leaves) {
                    if nb < near_b.len() && self.boxes[j].overlaps(&grown_a) {
                        near_b[nb] = j as u32;
                        nb += 1;
                    }
                }
                for &i in &near_a[..na] {
                    let bi = self.boxes[i as usize].inflated(margin);
                    for &j in &near_b[..nb] {
                        if bi.overlaps(&self.boxes[j as usize]) {
                            emit(self.ids[i as usize], self.ids[j as usize]);
                        }
                    }
                }
            }
        }
    }
}

/// A unit of self-pair work: the pairs within node `a` when `a == b`, else the pairs with
/// one item under `a` and the other under `b` (disjoint subtrees at the same depth).
#[derive(Clone, Copy)]
struct Job {
    a: u32,
    b: u32,
}

/// Levels expanded breadth-first into parallel jobs: about `4^depth` jobs at most, a few
/// thousand in practice, plenty for load balancing without a large job list.
pub const SPLIT_DEPTH: u32 = 8;

/// Depth-first job stack size (see [`Bvh::run_job`]).
const STACK: usize = 3 * (MAX_HEIGHT + 1) + 1;

/// Interleaves the low 21 bits of three coordinates into a 63-bit Morton code.
#[inline]
fn morton3(x: u64, y: u64, z: u64) -> u64 {
    spread21(x) | (spread21(y) << 1) | (spread21(z) << 2)
}

/// Spreads the low 21 bits of `v` so that bit `i` lands on bit `3i`.
#[inline]
fn spread21(v: u64) -> u64 {
    let mut x = v & 0x1f_ffff;
    x = (x | (x << 32)) & 0x001f_0000_0000_ffff;
    x = (x | (x << 16)) & 0x001f_0000_ff00_00ff;
    x = (x | (x << 8)) & 0x100f_00f0_0f00_f00f;
    x = (x | (x << 4)) & 0x10c3_0c30_c30c_30c3;
    x = (x | (x << 2)) & 0x1249_2492_4924_9249;
    x
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use std::collections::BTreeSet;

    fn brute_pairs(boxes: &[Aabb], margin: f64) -> BTreeSet<(u32, u32)> {
        let mut out = BTreeSet::new();
        for i in 0..boxes.len() {
            for j in i + 1..boxes.len() {
                if boxes[i].inflated(margin).overlaps(&boxes[j]) {
                    out.insert((i as u32, j as u32));
                }
            }
        }
        out
    }

    fn normalized(pairs: Vec<(u32, u32)>) -> (usize, BTreeSet<(u32, u32)>) {
        let n = pairs.len();
        (
            n,
            pairs
                .into_iter()
                .map(|(a, b)| (a.min(b), a.max(b)))
                .collect(),
        )
    }

    fn random_boxes(rng: &mut ChaCha8Rng, n: usize, size: f64) -> Vec<Aabb> {
        (0..n)
            .map(|_| {
                let c = DVec3::new(rng.random(), rng.random(), rng.random());
                let h = DVec3::new(rng.random(), rng.random(), rng.random()) * size;
                Aabb::new(c - h, c + h)
            })
            .collect()
    }

    #[test]
    fn spread_and_morton_interleave_bits() {
        assert_eq!(spread21(0b111), 0b1001001);
        assert_eq!(spread21(0x1f_ffff).count_ones(), 21);
        assert_eq!(morton3(1, 0, 0), 1);
        assert_eq!(morton3(0, 1, 0), 2);
        assert_eq!(morton3(0, 0, 1), 4);
        assert_eq!(morton3(0x1f_ffff, 0x1f_ffff, 0x1f_ffff), (1 << 63) - 1);
    }

    #[test]
    fn self_pairs_match_brute_force_on_many_sizes() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for n in [0, 1, 2, 3, 4, 5, 9, 17, 64, 300] {
            let boxes = random_boxes(&mut rng, n, 0.08);
            let bvh = Bvh::build(&boxes).unwrap();
            for margin in [0.0, 0.05] {
                let (count, set) = normalized(bvh.self_pairs_collect(margin));
                let expect = brute_pairs(&boxes, margin);
                assert_eq!(count, set.len(), "a pair was reported twice (n = {n})");
                assert_eq!(set, expect, "n = {n}, margin = {margin}");
            }
        }
    }

    #[test]
    fn touching_boxes_overlap_and_nan_boxes_never_do() {
        let a = Aabb::new(DVec3::ZERO, DVec3::ONE);
        let b = Aabb::new(DVec3::ONE, DVec3::splat(2.0));
        let nan = Aabb::new(DVec3::splat(f64::NAN), DVec3::ONE);
        assert!(a.overlaps(&b) && b.overlaps(&a));
        assert!(!a.overlaps(&nan) && !nan.overlaps(&a));
        assert!(!Aabb::EMPTY.overlaps(&a));
        assert!(Aabb::EMPTY.is_empty() && nan.is_empty() && !a.is_empty());
        let bvh = Bvh::build(&[a, nan, b]).unwrap();
        assert_eq!(
            normalized(bvh.self_pairs_collect(0.0)).1,
            BTreeSet::from([(0, 2)])
        );
        assert_eq!(bvh.bounds(), a.union(b));
        assert_eq!(a.union(nan), a);
        // A NaN item among many must not hide the others (its node boxes stay finite).
        let mut many: Vec<Aabb> = (0..50)
            .map(|i| Aabb::new(DVec3::X * i as f64, DVec3::X * i as f64 + 0.6))
            .collect();
        many[1] = nan;
        let bvh = Bvh::build(&many).unwrap();
        let (_, got) = normalized(bvh.self_pairs_collect(0.0));
        assert_eq!(got, brute_pairs(&many, 0.0));
        assert_eq!(got.len(), 0);
        let mut hits = Vec::new();
        bvh.query(
            &Aabb::new(DVec3::splat(-1.0), DVec3::new(2.5, 1.0, 1.0)),
            0.0,
            |id| hits.push(id),
        );
        hits.sort_unstable();
        assert_eq!(hits, vec![0, 2]);
    }

    #[test]
    fn query_and_refit_and_ids() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let boxes = random_boxes(&mut rng, 200, 0.05);
        let ids: Vec<u32> = (0..200).map(|i| 1000 + 3 * i).collect();
        let mut bvh = Bvh::build_with_ids(&boxes, &ids).unwrap();
        let probe = Aabb::new(DVec3::splat(0.3), DVec3::splat(0.5));
        for margin in [0.0, 0.1] {
            let mut got = Vec::new();
            bvh.query(&probe, margin, |id| got.push(id));
            got.sort_unstable();
            let want: Vec<u32> = (0..200)
                .filter(|&i| boxes[i].overlaps(&probe.inflated(margin)))
                .map(|i| ids[i])
                .collect();
            assert_eq!(got, want);
        }
        // Move every box; the refitted tree must answer as a fresh one would.
        let moved: Vec<Aabb> = boxes
            .iter()
            .map(|b| Aabb::new(b.min + DVec3::X * 0.3, b.max + DVec3::X * 0.3))
            .collect();
        bvh.refit(&moved).unwrap();
        let (_, got) = normalized(bvh.self_pairs_collect(0.0));
        let want: BTreeSet<(u32, u32)> = brute_pairs(&moved, 0.0)
            .into_iter()
            .map(|(a, b)| (ids[a as usize], ids[b as usize]))
            .collect();
        assert_eq!(got, want);
        assert!(bvh.refit(&moved[..3]).is_err());
        assert!(Bvh::build_with_ids(&boxes, &ids[..5]).is_err());
    }

    #[test]
    fn identical_centres_and_flat_extent_are_handled() {
        // All centres equal (zero extent on every axis) and all centres on a plane.
        let same = vec![Aabb::new(DVec3::ZERO, DVec3::ONE); 23];
        let bvh = Bvh::build(&same).unwrap();
        assert_eq!(bvh.self_pairs_collect(0.0).len(), 23 * 22 / 2);
        let flat: Vec<Aabb> = (0..40)
            .map(|i| {
                let c = DVec3::new(i as f64 * 0.1, 0.0, 0.0);
                Aabb::new(c - DVec3::splat(0.06), c + DVec3::splat(0.06))
            })
            .collect();
        let bvh = Bvh::build(&flat).unwrap();
        assert_eq!(
            normalized(bvh.self_pairs_collect(0.0)).1,
            brute_pairs(&flat, 0.0)
        );
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        #[test]
        fn self_pairs_equal_brute_force(
            seed in any::<u64>(),
            n in 0usize..120,
            size in 0.0f64..0.3,
            margin in prop_oneof![Just(0.0), 0.0f64..0.1],
        ) {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let boxes = random_boxes(&mut rng, n, size);
            let bvh = Bvh::build(&boxes).unwrap();
            let (count, set) = normalized(bvh.self_pairs_collect(margin));
            prop_assert_eq!(count, set.len());
            prop_assert_eq!(set, brute_pairs(&boxes, margin));
        }
    }
}

#[cfg(test)]
mod bench {
    //! Throughput of build and self-pair traversal on the boxes of a ~1.3M-triangle sphere,
    //! against a uniform hash grid. Run with
    //! `cargo test --release -p mesh-core broadphase::bench -- --ignored --nocapture`
    //! (with `RAYON_NUM_THREADS=1` for single-thread figures, on an idle machine).
    use super::*;
    use crate::validate::testmesh::icosphere;
    use std::time::Instant;

    fn sphere_boxes() -> Vec<Aabb> {
        let (p, t, _) = icosphere(DVec3::ZERO, 1.0, 8, 1);
        t.iter()
            .map(|tri| Aabb::from_points(&tri.map(|i| p[i as usize])))
            .collect()
    }

    /// Uniform grid, cell = largest box extent; each pair reported in the cell holding
    /// the min corner of the two boxes' intersection.
    fn grid_pairs(boxes: &[Aabb]) -> usize {
        let cell = boxes
            .iter()
            .map(|b| (b.max - b.min).max_element())
            .fold(0.0, f64::max);
        let lo = boxes.iter().fold(DVec3::INFINITY, |a, b| a.min(b.min));
        let key = |c: glam::I64Vec3| ((c.x as u64) << 42) | ((c.y as u64) << 21) | c.z as u64;
        let cell_of = |p: DVec3| ((p - lo) / cell).floor().as_i64vec3();
        let mut entries: Vec<(u64, u32)> = boxes
            .par_iter()
            .enumerate()
            .flat_map_iter(|(i, b)| {
                let (c0, c1) = (cell_of(b.min), cell_of(b.max));
                let mut v = Vec::with_capacity(8);
                for x in c0.x..=c1.x {
                    for y in c0.y..=c1.y {
                        for z in c0.z..=c1.z {
                            v.push((key(glam::I64Vec3::new(x, y, z)), i as u32));
                        }
                    }
                }
                v
            })
            .collect();
        entries.par_sort_unstable();
        let starts: Vec<usize> = (0..entries.len())
            .filter(|&i| i == 0 || entries[i - 1].0 != entries[i].0)
            .collect();
        starts
            .par_iter()
            .enumerate()
            .map(|(g, &s)| {
                let e = starts.get(g + 1).copied().unwrap_or(entries.len());
                let cell_key = entries[s].0;
                let mut n = 0;
                for i in s..e {
                    for j in i + 1..e {
                        let (a, b) = (&boxes[entries[i].1 as usize], &boxes[entries[j].1 as usize]);
                        if a.overlaps(b) && key(cell_of(a.min.max(b.min))) == cell_key {
                            n += 1;
                        }
                    }
                }
                n
            })
            .sum()
    }

    #[test]
    #[ignore]
    fn throughput_sphere_boxes() {
        let boxes = sphere_boxes();
        for _ in 0..3 {
            let t0 = Instant::now();
            let bvh = Bvh::build(&boxes).unwrap();
            let t1 = Instant::now();
            let n = bvh.self_pairs_fold(0.0, || 0usize, |a, _, _| *a += 1, |a, b| a + b);
            let t2 = Instant::now();
            let g = grid_pairs(&boxes);
            let t3 = Instant::now();
            assert_eq!(n, g);
            eprintln!(
                "{} boxes, {n} pairs: bvh build {:.1?}, pairs {:.1?}; grid {:.1?}",
                boxes.len(),
                t1 - t0,
                t2 - t1,
                t3 - t2
            );
        }
    }
}
