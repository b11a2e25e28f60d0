//! [`TriangleIndex`]: the one dynamic broad phase over a mesh's triangles that follows the
//! mesh through edits — used by the static edit guard, and through it by the collision
//! guard's sweeps.
//!
//! A [`Bvh`] over the triangles' boxes grown by a slack (a fraction of the mean triangle
//! extent), built lazily, plus a hash grid of the triangles that left their grown box or
//! were created since (the *escaped* ones). Why the slack: remeshing moves most vertices a
//! little (smoothing) and creates triangles near old ones; a triangle that stays inside the
//! box the BVH holds for its slot needs no bookkeeping at all, so a smoothing pass over the
//! whole mesh costs no index updates and no rebuilds. The BVH is rebuilt when the escaped
//! triangles reach a quarter of the mesh.
//!
//! The contract: after [`TriangleIndex::refresh`], every live triangle whose current box
//! meets a query box is reported by [`TriangleIndex::query`], provided every triangle
//! added or moved since was passed to [`TriangleIndex::track`]. A query may also report a
//! triangle twice, a dead one, or one whose current box misses the query (its grown box
//! or an older cell met it): callers filter by liveness and current box.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

use rayon::prelude::*;

use crate::broadphase::{Aabb, Bvh};
use crate::ids::TriId;
use crate::mesh::LabeledMesh;

/// See the [module doc](self).
#[derive(Debug, Default)]
pub struct TriangleIndex {
    bvh: Option<Bvh>,
    /// The box the BVH holds for each triangle slot (the triangle's box at build time grown
    /// by the slack; EMPTY for slots dead then).
    indexed: Vec<Aabb>,
    /// Triangles changed since the BVH was built whose current box is not inside their
    /// slot's indexed box, at their current boxes.
    dirty: DirtyGrid,
}

impl TriangleIndex {
    /// An index with nothing built yet (built by the first [`TriangleIndex::refresh`]).
    pub fn new() -> Self {
        Self::default()
    }

    /// Forgets everything, e.g. after the mesh was changed without [`TriangleIndex::track`]
    /// (a time step moving every vertex); the next refresh rebuilds.
    pub fn reset(&mut self) {
        self.bvh = None;
        self.indexed.clear();
        self.dirty.reset(1.0);
    }

    /// True once built (and not reset since).
    pub fn is_built(&self) -> bool {
        self.bvh.is_some()
    }

    /// Builds the BVH if there is none, or if so much has escaped it since that rebuilding
    /// is cheaper than carrying the changes.
    pub fn refresh(&mut self, mesh: &LabeledMesh) {
        let capacity = mesh.triangle_capacity();
        // Rebuild once a quarter of the mesh has escaped: the grid then holds too much.
        if self.bvh.is_some() && self.dirty.distinct <= 256 + capacity / 4 {
            return;
        }
        let alive = mesh.tri_alive_flags();
        let mut boxes: Vec<Aabb> = (0..capacity)
            .into_par_iter()
            .with_min_len(4096)
            .map(|i| {
                if alive[i] {
                    Aabb::from_points(&mesh.tri_positions(TriId::new(i as u32)))
                } else {
                    Aabb::EMPTY
                }
            })
            .collect();
        let live = mesh.num_triangles().max(1) as f64;
        let mean_extent = crate::geometry::ordered_sum(boxes.len(), |i| {
            let e = (boxes[i].max - boxes[i].min).max_element();
            if !boxes[i].is_empty() && e.is_finite() {
                e
            } else {
                0.0
            }
        }) / live;
        self.dirty.reset(mean_extent);
        let slack = SLACK * mean_extent;
        if slack.is_finite() && slack > 0.0 {
            boxes
                .par_iter_mut()
                .with_min_len(4096)
                .filter(|b| !b.is_empty())
                .for_each(|b| *b = b.inflated(slack));
        }
        // A build only fails for more boxes than ids, which a mesh cannot have; without a
        // BVH every triangle goes to the grid's oversize list, which is slow but complete.
        self.bvh = Bvh::build(&boxes).ok();
        if self.bvh.is_some() {
            self.indexed = boxes;
        } else {
            self.indexed.clear();
            for t in mesh.triangles() {
                self.dirty.oversize.push(t);
            }
        }
    }

    /// Records that triangle `t` was added or moved: nothing if it still lies inside the
    /// box the BVH holds for its slot (and was not filed as escaped before), else
    /// (re)filed under its current box. Dead triangles are ignored (queries may still
    /// report them). Nothing to do before the first build.
    pub fn track(&mut self, mesh: &LabeledMesh, t: TriId) {
        if self.bvh.is_none() || !mesh.is_triangle_alive(t) {
            return;
        }
        let b = Aabb::from_points(&mesh.tri_positions(t));
        let covered = self
            .indexed
            .get(t.idx())
            .is_some_and(|f| f.min.cmple(b.min).all() && b.max.cmple(f.max).all());
        if !covered || self.dirty.is_filed(t) {
            self.dirty.insert(t, &b);
        }
    }

    /// Calls `f` for every triangle whose indexed or escaped box meets `b` (see the
    /// [module doc](self) for what else it may report).
    #[inline]
    pub fn query(&self, b: &Aabb, mut f: impl FnMut(TriId)) {
        if let Some(bvh) = &self.bvh {
            bvh.query(b, 0.0, |id| f(TriId::new(id)));
        }
        self.dirty.query(b, f);
    }
}

/// Slack of the indexed boxes, as a fraction of the mean triangle extent: large enough
/// that smoothing moves (a fraction of an edge length per pass) rarely push a triangle out
/// of its indexed box, small enough that grown boxes add few candidates.
const SLACK: f64 = 0.15;

/// Triangles changed since the BVH was built, bucketed on a uniform grid (cell ≈ a
/// triangle's size) so that a check looks only at the changes near it. A triangle that
/// changes again moves to the cells of its new box, so the grid holds current boxes only.
#[derive(Debug, Default)]
struct DirtyGrid {
    cell: f64,
    buckets: HashMap<u64, Vec<TriId>, BuildHasherDefault<CellHasher>>,
    /// Triangles too large for a few cells, checked against every query.
    oversize: Vec<TriId>,
    /// Where each changed triangle is filed (by triangle slot).
    placed: Vec<Option<Placement>>,
    /// Distinct triangles filed.
    distinct: usize,
}

/// The cells a triangle is filed under, or the oversize list.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Placement {
    Cells([i64; 3], [i64; 3]),
    Oversize,
}

/// A triangle box spanning more cells than this goes to the oversize list.
const MAX_CELLS_PER_BOX: i64 = 27;

/// Calls `f` for every cell of an inclusive integer range.
fn for_cells(lo: [i64; 3], hi: [i64; 3], mut f: impl FnMut([i64; 3])) {
    for x in lo[0]..=hi[0] {
        for y in lo[1]..=hi[1] {
            for z in lo[2]..=hi[2] {
                f([x, y, z]);
            }
        }
    }
}

/// The bucket key of a cell. Distinct cells may share a key; a shared bucket only adds
/// candidates, which the box test then drops.
#[inline]
fn cell_key([x, y, z]: [i64; 3]) -> u64 {
    (x as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
        ^ (y as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
        ^ (z as u64).wrapping_mul(0x1656_67B1_9E37_79F9)
}

/// Hasher for keys that [`cell_key`] already mixed: one multiply spreads them over the
/// high bits the hash table uses (the default SipHash costs more than the lookup).
#[derive(Clone, Copy, Debug, Default)]
struct CellHasher(u64);

impl Hasher for CellHasher {
    fn finish(&self) -> u64 {
        (self.0 ^ (self.0 >> 29)).wrapping_mul(0xBF58_476D_1CE4_E5B9)
    }

    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0.rotate_left(8) ^ u64::from(b)).wrapping_mul(0x0100_0000_01B3);
        }
    }

    fn write_u64(&mut self, key: u64) {
        self.0 ^= key;
    }
}

impl DirtyGrid {
    fn reset(&mut self, cell: f64) {
        self.cell = if cell.is_finite() && cell > 0.0 {
            cell
        } else {
            1.0
        };
        self.buckets.clear();
        self.oversize.clear();
        self.placed.clear();
        self.distinct = 0;
    }

    /// Integer cell range of a box, or `None` if it spans more than `max_cells` cells
    /// (or is not finite).
    fn cells(&self, b: &Aabb, max_cells: f64) -> Option<([i64; 3], [i64; 3])> {
        let lo = (b.min / self.cell).floor();
        let hi = (b.max / self.cell).floor();
        if !lo.is_finite() || !hi.is_finite() {
            return None;
        }
        let span = hi - lo + 1.0;
        if span.x * span.y * span.z > max_cells {
            return None;
        }
        Some((
            [lo.x as i64, lo.y as i64, lo.z as i64],
            [hi.x as i64, hi.y as i64, hi.z as i64],
        ))
    }

    fn is_filed(&self, t: TriId) -> bool {
        self.placed.get(t.idx()).is_some_and(Option::is_some)
    }

    /// Files `t` under box `b`, first removing it from where it was filed before.
    fn insert(&mut self, t: TriId, b: &Aabb) {
        if t.idx() >= self.placed.len() {
            self.placed.resize(t.idx() + 1, None);
        }
        let placement = self.cells(b, MAX_CELLS_PER_BOX as f64);
        let new = match placement {
            Some((lo, hi)) => Placement::Cells(lo, hi),
            None => Placement::Oversize,
        };
        match self.placed[t.idx()] {
            // Same cells: nothing to move.
            Some(old) if old == new => return,
            None => self.distinct += 1,
            Some(Placement::Oversize) => self.oversize.retain(|&x| x != t),
            Some(Placement::Cells(lo, hi)) => {
                let buckets = &mut self.buckets;
                for_cells(lo, hi, |c| {
                    if let Some(bucket) = buckets.get_mut(&cell_key(c))
                        && let Some(i) = bucket.iter().position(|&x| x == t)
                    {
                        bucket.swap_remove(i);
                    }
                });
            }
        }
        match new {
            Placement::Cells(lo, hi) => {
                let buckets = &mut self.buckets;
                for_cells(lo, hi, |c| buckets.entry(cell_key(c)).or_default().push(t));
            }
            Placement::Oversize => self.oversize.push(t),
        }
        self.placed[t.idx()] = Some(new);
    }

    /// Calls `f` for every filed triangle whose cells meet box `b` (possibly repeatedly).
    fn query(&self, b: &Aabb, mut f: impl FnMut(TriId)) {
        self.oversize.iter().for_each(|&t| f(t));
        if self.buckets.is_empty() {
            return;
        }
        // Visiting more cells than there are buckets costs more than visiting every bucket.
        match self.cells(b, self.buckets.len() as f64) {
            Some((lo, hi)) => for_cells(lo, hi, |c| {
                if let Some(bucket) = self.buckets.get(&cell_key(c)) {
                    bucket.iter().for_each(|&t| f(t));
                }
            }),
            None => self.buckets.values().flatten().for_each(|&t| f(t)),
        }
    }
}
