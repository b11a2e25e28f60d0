//! Stage 5a (§8.1 of Heiss-Synak et al. 2024): one material label per grid node of the
//! flawed region ("correcting material vectors").
//!
//! Glossary:
//! - **region node**: a corner of a flawed cell; these are the nodes the rebuild reads.
//! - **physical node**: its material vector is one-hot and the three ray axes agree
//!   ([`Materials::physical_label`]; [`Materials::material_at`] for unallocated nodes).
//!   It keeps its label. Every other region node is **non-physical** (mixed, or flawed).
//! - **breaking point** ([`BreakingPoint`]): a point on a grid edge where, walking along
//!   the edge, the material vector turns from physical to non-physical (or back) — the
//!   last point with a well-defined label before an ill-defined stretch (Fig. 10). Its
//!   label is the physical side's. Found from the crossings of §5 ([`breaking`]).
//! - **nearest breaking point**: every non-physical node takes the label of its nearest
//!   breaking point. The paper finds it by fast marching (Sethian 1999), a
//!   Dijkstra-ordered propagation of closest points over the region's grid nodes
//!   ([`march`]). Here, within 8 cells of a breaking point (the band, where labels
//!   change) each node takes the exact nearest breaking point of its part of the region
//!   from a k-d tree, gathered once per block of 4³ nodes ([`nearest`]), which the
//!   propagation approximates;
//!   farther away (the inside of overlapping solids) the closest points are marched on a
//!   4× coarser lattice and every node takes the nearest of the points of the coarse
//!   nodes around its coarse cell and of the band nodes next to it
//!   ([`march::march_far_field`]).
//!   Neither is in the paper, which marches every node; both are for speed on large
//!   overlaps ([`nearest`] says why).
//!
//! Fallback (not in the paper, which assumes every non-physical component touches a
//! breaking point): a non-physical node that no breaking point reaches (none lies in its
//! connected part of the region) takes the label of the nearest physical region node
//! adjacent to its non-physical component, propagated by fast marching
//! (its "breaking point" is that node's position); a component with no physical neighbour
//! at all — impossible for a region inside the grid, since nodes next to intact cells are
//! physical — gets the outside label 0. Both cases are counted in [`LabelStats`].
//!
//! Besides the labels, [`NodeLabels`] keeps for every region edge crossed by the mesh the
//! data §8.3 places vertices with ([`EdgeTransitions`]): the rebuild runs on the cut mesh,
//! whose triangle ids no longer match the crossings of §5, so everything the placement
//! needs from the original mesh is gathered here.
//!
//! The region's nodes are numbered once ([`region_nodes`], shared with the PIC transfer of
//! §8.4), with a dense lookup for compact regions.
//!
//! Entry point: [`correct_labels`].

pub mod breaking;
pub mod march;
pub mod nearest;
pub mod nodes;

use std::collections::HashMap;
use std::hash::BuildHasherDefault;

use glam::{DVec3, IVec3};
use mesh_core::predicates::Axis;
use mesh_core::{Label, LabeledMesh};
use rayon::prelude::*;

use crate::stages::flaws::FlawedRegion;
use crate::stages::grid::primitives::{GridEdge, unit};
use crate::stages::grid::tiles::TileHasher;
use crate::stages::grid::{Grid, NodeId};
use crate::stages::materials::{MaterialVector, Materials};

pub use breaking::{BreakingPoint, EdgeTransitions};
pub use nodes::{NodeIndex, region_nodes};

/// How non-physical nodes get their label: the research ablation of §8.1.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LabelCorrection {
    /// The paper's: the label of the nearest *breaking point* (the exact point along a
    /// grid edge where the material vector stops being physical), which the paper finds
    /// by fast marching; here exactly within 8 cells of one and by a coarse march beyond
    /// (module docs).
    #[default]
    FastMarching,
    /// The simpler choice the paper improves on: the label of the nearest *physical grid
    /// node* (marched over the non-physical nodes from their physical neighbours), which
    /// ignores where between two nodes the material actually changes. Vertex placement
    /// (§8.3) still uses the nearest breaking point where one exists.
    NearestVertex,
}

/// Why labels could not be assigned.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum LabelError {
    /// Mesh, grid and materials do not belong together (the mesh must be the one the
    /// materials were assigned for, i.e. the mesh *before* cutting).
    #[error("mismatched inputs: {0}")]
    Mismatch(&'static str),
    /// More region nodes than `u32` indices.
    #[error("the flawed region has {nodes} grid nodes, more than u32 indices")]
    TooManyNodes {
        /// Nodes counted.
        nodes: usize,
    },
}

/// Counts describing a labelling.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LabelStats {
    /// Region nodes (corners of flawed cells).
    pub nodes: usize,
    /// Region nodes with a physical vector.
    pub physical_nodes: usize,
    /// Region nodes labelled from breaking points (nearest-point queries and the far
    /// field).
    pub marched_nodes: usize,
    /// Region edges walked for crossings and breaking points.
    pub scanned_edges: usize,
    /// Breaking points found.
    pub breaking_points: usize,
    /// Non-physical nodes no breaking point reached, labelled from the nearest physical
    /// node instead (fallback).
    pub fallback_nodes: usize,
    /// Non-physical nodes not reached at all, labelled 0 (last resort).
    pub unreached_nodes: usize,
    /// Label updates of the far field's marching (work measure).
    pub updates: usize,
    /// Nodes farther than the far-field band from every breaking point, labelled from the
    /// coarse march ([`march::march_far_field`]).
    pub far_nodes: usize,
    /// Of those, the nodes no coarse point of their part reached, marched from their
    /// neighbours.
    pub rest_nodes: usize,
}

/// What one region node knows.
#[derive(Clone, Copy, Debug, PartialEq)]
struct NodeEntry {
    label: Label,
    physical: bool,
    /// The nearest breaking point of a non-physical node: an index into the breaking
    /// points, then the fallback points (see [`NodeLabels::breaking_point`]), or
    /// [`NodeEntry::NONE`]. An index, not a position, so that an entry is 12 bytes: there
    /// is one per node of the region, millions where solids overlap.
    breaking: u32,
}

impl NodeEntry {
    /// No breaking point.
    const NONE: u32 = u32::MAX;
}

/// The [`EdgeTransitions`] of region edges by the edge's lower node: node `i`'s are
/// `transitions[first[i]..first[i + 1]]`, one per axis at most. Why not a hash map: the
/// edge scan already yields them in node order, so this is built by appending, where
/// inserting every crossed edge into a map was sequential and a tenth of the stage (0.3 s
/// at 2.1M triangles).
#[derive(Clone, Debug, Default)]
struct EdgeTable {
    first: Vec<u32>,
    transitions: Vec<(Axis, EdgeTransitions)>,
}

impl EdgeTable {
    /// The table of `transitions` (each with its lower node's index below `nodes`).
    fn new(nodes: usize, mut transitions: Vec<(u32, Axis, EdgeTransitions)>) -> Self {
        let key = |t: &(u32, Axis, EdgeTransitions)| (t.0, t.1.index());
        if !transitions.is_sorted_by_key(key) {
            transitions.sort_unstable_by_key(key);
        }
        let mut first = Vec::with_capacity(nodes + 1);
        for (k, t) in transitions.iter().enumerate() {
            while first.len() <= t.0 as usize {
                first.push(k as u32);
            }
        }
        first.resize(nodes + 1, transitions.len() as u32);
        EdgeTable {
            first,
            transitions: transitions.into_iter().map(|t| (t.1, t.2)).collect(),
        }
    }
}

/// One label per region node (§8.1), sparse over lattice nodes, plus the per-edge data of
/// §8.3. Built by [`correct_labels`]; read-only afterwards.
#[derive(Clone, Debug, Default)]
pub struct NodeLabels {
    index: NodeIndex,
    nodes: Vec<IVec3>,
    entries: Vec<NodeEntry>,
    edges: EdgeTable,
    breaking_points: Vec<BreakingPoint>,
    /// The physical node positions fallback nodes took their labels from.
    fallback_points: Vec<DVec3>,
    stats: LabelStats,
}

impl NodeLabels {
    /// The label of region node `node`; `None` outside the region.
    #[inline]
    pub fn label(&self, node: IVec3) -> Option<Label> {
        self.entry(node).map(|e| e.label)
    }

    /// The nearest breaking point of a non-physical region node (for a fallback node, the
    /// physical node it took its label from); `None` for physical nodes, nodes outside the
    /// region and nodes labelled by the last resort.
    #[inline]
    pub fn breaking_point(&self, node: IVec3) -> Option<DVec3> {
        let k = self.entry(node)?.breaking as usize;
        match self.breaking_points.get(k) {
            Some(b) => Some(b.position),
            None => self
                .fallback_points
                .get(k - self.breaking_points.len())
                .copied(),
        }
    }

    /// Whether `node` is a region node with a physical vector (its label is its own).
    #[inline]
    pub fn is_physical(&self, node: IVec3) -> bool {
        self.entry(node).is_some_and(|e| e.physical)
    }

    /// Crossings and breaking points of region edge `edge`, if the mesh crosses it or a
    /// breaking point lies on it (§8.3 places edge vertices with them).
    #[inline]
    pub fn edge_transitions(&self, edge: &GridEdge) -> Option<EdgeTransitions> {
        let i = self.index.get(edge.node)? as usize;
        let (lo, hi) = (self.edges.first[i], self.edges.first[i + 1]);
        self.edges.transitions[lo as usize..hi as usize]
            .iter()
            .find(|(axis, _)| *axis == edge.axis)
            .map(|(_, t)| *t)
    }

    /// Every breaking point found, in a deterministic order.
    pub fn breaking_points(&self) -> &[BreakingPoint] {
        &self.breaking_points
    }

    /// Every region node with its label, in lattice order (z, then y, then x).
    pub fn nodes(&self) -> impl Iterator<Item = (IVec3, Label)> + '_ {
        self.nodes
            .iter()
            .zip(&self.entries)
            .map(|(&n, e)| (n, e.label))
    }

    /// Number of region nodes.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// True for an empty region.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Counts.
    pub fn stats(&self) -> LabelStats {
        self.stats
    }

    fn entry(&self, node: IVec3) -> Option<&NodeEntry> {
        self.index.get(node).map(|i| &self.entries[i as usize])
    }
}

/// The allocated id and physical label of every node of `nodes` (in lattice order):
/// allocated nodes by their vector and axis agreement, unallocated ones by the vector
/// they inherit along x (never flawed).
///
/// By chunks of consecutive nodes, carrying along each run of x neighbours the allocated
/// node an unallocated one inherits from: it is the one its −x neighbour inherits from,
/// or that neighbour itself. Why: [`Grid::node_at_or_below_x`] walks a tile lookup per
/// tile back to the surface, and deep inside a large overlap that was a walk per node
/// growing with the overlap's width; now it is one per run.
fn physical_status(
    grid: &Grid,
    materials: &Materials,
    nodes: &[IVec3],
) -> (Vec<Option<NodeId>>, Vec<Option<Label>>) {
    nodes
        .par_chunks(4096)
        .flat_map_iter(|chunk| {
            // The previous node and the allocated node its vector comes from.
            let mut previous: Option<(IVec3, Option<NodeId>)> = None;
            chunk.iter().map(move |&p| {
                let id = grid.node_id(p);
                let source = match (id, previous) {
                    (Some(n), _) => Some(n),
                    (None, Some((q, source))) if q + IVec3::X == p => source,
                    (None, _) => grid.node_at_or_below_x(p),
                };
                previous = Some((p, source));
                let label = match id {
                    Some(n) => materials.physical_label(n),
                    None => materials.material_from(source).label(),
                };
                (id, label)
            })
        })
        .unzip()
}

/// Assigns a label to every corner of every flawed cell (§8.1).
///
/// `mesh` must be the mesh the materials were assigned for (before cutting): breaking
/// points are found by walking the crossings of §5, which name its triangles.
///
/// Physical nodes keep their label. Breaking points are found on every edge of every
/// flawed cell ([`breaking`]); each non-physical node then takes the label of the nearest
/// one (exactly near breaking points, see the module docs), with the fallback described
/// there.
/// Deterministic: the result does not depend on thread timing.
pub fn correct_labels(
    mesh: &LabeledMesh,
    grid: &Grid,
    materials: &Materials,
    region: &FlawedRegion,
) -> Result<NodeLabels, LabelError> {
    correct_labels_with(mesh, grid, materials, region, LabelCorrection::FastMarching)
}

/// [`correct_labels`] with a choice of [`LabelCorrection`] (for ablations).
pub fn correct_labels_with(
    mesh: &LabeledMesh,
    grid: &Grid,
    materials: &Materials,
    region: &FlawedRegion,
    method: LabelCorrection,
) -> Result<NodeLabels, LabelError> {
    if grid.triangle_capacity() != mesh.triangle_capacity() {
        return Err(LabelError::Mismatch("the grid was built from another mesh"));
    }
    if materials.num_nodes() != grid.num_nodes() {
        return Err(LabelError::Mismatch(
            "the materials were assigned on another grid",
        ));
    }
    let lattice = *grid.lattice();
    let clock = std::time::Instant::now();
    let mut phase = [0.0f64; 4];

    // Region nodes, in lattice order.
    let (nodes, index) =
        nodes::region_nodes(region).map_err(|e| LabelError::TooManyNodes { nodes: e.0 })?;
    // Each node's allocated id (looked up once: the edge scan asks about both ends of
    // three edges per node) and physical label.
    let (ids, status) = physical_status(grid, materials, &nodes);
    let idx = |p: IVec3| index.get(p).map(|i| i as usize);
    phase[0] = clock.elapsed().as_secs_f64();

    // Breaking points and crossing data on every edge of a flawed cell: edge (n, a) for
    // every region node n whose +a neighbour is a region node and which borders a flawed
    // cell.
    let scans: Vec<breaking::EdgeScans> = (0..nodes.len())
        .into_par_iter()
        .fold(
            || (MaterialVector::default(), breaking::EdgeScans::default()),
            |(mut buf, mut out), i| {
                let n = nodes[i];
                for axis in Axis::ALL {
                    let edge = GridEdge { node: n, axis };
                    let Some(j) = idx(n + unit(axis)) else {
                        continue;
                    };
                    // The cheap test first: deep inside an overlap no edge is walked.
                    let ends = [ids[i], ids[j]];
                    if !breaking::needs_walk(materials, edge, ends)
                        || !edge.cells().iter().any(|&c| region.is_flawed(c))
                    {
                        continue;
                    }
                    let walked = breaking::scan_edge(
                        mesh,
                        grid,
                        materials,
                        edge,
                        [status[i], status[j]],
                        &mut buf,
                        &mut out,
                    );
                    if let Some(t) = walked {
                        out.transitions.push((i as u32, axis, t));
                    }
                }
                (buf, out)
            },
        )
        .map(|(_, out)| out)
        .collect();
    drop(ids); // freed before the march allocates its per-node arrays, not added to them

    let mut stats = LabelStats {
        nodes: nodes.len(),
        physical_nodes: status.par_iter().filter(|s| s.is_some()).count(),
        ..LabelStats::default()
    };
    let mut transitions: Vec<(u32, Axis, EdgeTransitions)> = Vec::new();
    let mut points: Vec<(GridEdge, BreakingPoint)> = Vec::new();
    for s in scans {
        stats.scanned_edges += s.scanned;
        transitions.extend(s.transitions);
        points.extend(s.points);
    }
    let edges = EdgeTable::new(nodes.len(), transitions);
    // Deterministic order, independent of how rayon split the work.
    points.sort_unstable_by(|a, b| {
        let key = |(e, p): &(GridEdge, BreakingPoint)| {
            (
                [e.node.z, e.node.y, e.node.x, e.axis.index() as i32],
                p.label,
            )
        };
        key(a).cmp(&key(b)).then(
            a.1.position
                .to_array()
                .partial_cmp(&b.1.position.to_array())
                .unwrap_or(std::cmp::Ordering::Equal),
        )
    });
    stats.breaking_points = points.len();
    phase[1] = clock.elapsed().as_secs_f64();

    // Fast marching from the breaking points. Physical nodes relay the nearest point
    // without taking its label: a breaking point between two physical ends (a mixed
    // stretch inside one edge) or across a physical node may still be the nearest one.
    let neighbours = |i: u32, out: &mut [u32; march::STENCIL]| {
        let p = nodes[i as usize];
        let mut k = 0;
        for d in march::OFFSETS {
            if let Some(j) = index.get(p + d) {
                out[k] = j;
                k += 1;
            }
        }
        k
    };
    let bps: Vec<BreakingPoint> = points.iter().map(|p| p.1).collect();
    let mut slots = vec![march::Slot::OPEN; nodes.len()];
    if status.iter().any(Option::is_none) {
        let far;
        (slots, far) = nearest_points(&nodes, &index, &lattice, &bps, |k| idx(points[k].0.node));
        stats.updates += far.updates;
        stats.far_nodes = far.far_nodes;
        stats.rest_nodes = far.rest_nodes;
    }
    // Every node's entry; a non-physical node takes its nearest breaking point's label
    // (with `NearestVertex`, only its position: the label is the fallback's).
    let nearest_vertex = method == LabelCorrection::NearestVertex;
    let reached = |i: usize| status[i].is_none() && slots[i].point < march::Slot::CLOSED;
    let mut entries: Vec<NodeEntry> = (0..nodes.len())
        .into_par_iter()
        .map(|i| match status[i] {
            Some(label) => NodeEntry {
                label,
                physical: true,
                breaking: NodeEntry::NONE,
            },
            None if reached(i) => NodeEntry {
                label: if nearest_vertex {
                    Label::OUTSIDE
                } else {
                    bps[slots[i].point as usize].label
                },
                physical: false,
                breaking: slots[i].point,
            },
            None => NodeEntry {
                label: Label::OUTSIDE,
                physical: false,
                breaking: NodeEntry::NONE,
            },
        })
        .collect();
    stats.marched_nodes = (0..nodes.len())
        .into_par_iter()
        .filter(|&i| reached(i))
        .count();
    phase[2] = clock.elapsed().as_secs_f64();

    // Fallback: components no breaking point reached take the nearest physical label
    // (with `NearestVertex`, every non-physical node does; its breaking point, where
    // marched, is kept for vertex placement).
    let unreached: Vec<bool> = (0..nodes.len())
        .into_par_iter()
        .map(|i| status[i].is_none() && (nearest_vertex || !reached(i)))
        .collect();
    let mut fallback_points: Vec<DVec3> = Vec::new();
    if unreached.par_iter().any(|&u| u) {
        let positions: Vec<DVec3> = nodes.iter().map(|&n| lattice.node_position(n)).collect();
        let mut fallback: Vec<Option<march::Nearest>> = vec![None; nodes.len()];
        let mut seeds: Vec<(u32, BreakingPoint)> = Vec::new();
        let mut nb = [0u32; march::STENCIL];
        for (i, _) in unreached.iter().enumerate().filter(|(_, u)| **u) {
            let k = neighbours(i as u32, &mut nb);
            for &j in &nb[..k] {
                if let Some(label) = status[j as usize] {
                    seeds.push((
                        i as u32,
                        BreakingPoint {
                            position: positions[j as usize],
                            label,
                        },
                    ));
                }
            }
        }
        stats.updates += march::march(
            &positions,
            &unreached,
            &neighbours,
            seeds.into_iter(),
            &mut fallback,
        );
        for (i, f) in fallback.into_iter().enumerate() {
            let entry = &mut entries[i];
            match f {
                Some(f) => {
                    stats.fallback_nodes += 1;
                    entry.label = f.point.label;
                    if entry.breaking == NodeEntry::NONE {
                        entry.breaking = (bps.len() + fallback_points.len()) as u32;
                        fallback_points.push(f.point.position);
                    }
                }
                // Not even a physical node reached it: the last resort.
                None if unreached[i] => {
                    entry.label = Label::OUTSIDE;
                    entry.breaking = NodeEntry::NONE;
                }
                None => {}
            }
        }
    }
    stats.unreached_nodes = entries
        .par_iter()
        .filter(|e| !e.physical && e.breaking == NodeEntry::NONE)
        .count();
    drop(slots);
    phase[3] = clock.elapsed().as_secs_f64();
    // Where the time went (`RUST_LOG=grid_tracker=debug`): seconds since the start at the
    // end of each phase.
    tracing::debug!(
        nodes = phase[0],
        breaking_points = phase[1],
        nearest_and_entries = phase[2],
        fallback = phase[3],
        dense = matches!(index, NodeIndex::Dense { .. }),
        ?stats,
        "labels: seconds at the end of each phase"
    );
    Ok(NodeLabels {
        index,
        nodes,
        entries,
        edges,
        breaking_points: bps,
        fallback_points,
        stats,
    })
}

/// The region's nodes as the marching sees them: stencil neighbours looked up in the
/// node index, positions computed from lattice coordinates (no per-node position array).
/// The stencil is [`march::OFFSETS`] scaled by `step` lattice cells (1: the fine march;
/// [`FAR_FIELD_BLOCK`]: its coarse level). For a dense index and a node at least `step`
/// away from the box's faces, the 26 neighbours are fixed offsets into the box array,
/// without bounds checks.
struct RegionNodes<'a> {
    nodes: &'a [IVec3],
    index: &'a NodeIndex,
    lattice: &'a crate::stages::grid::Lattice,
    step: i32,
    /// Box-array offsets of the scaled stencil (dense index only).
    deltas: [isize; march::STENCIL],
}

impl<'a> RegionNodes<'a> {
    fn new(
        nodes: &'a [IVec3],
        index: &'a NodeIndex,
        lattice: &'a crate::stages::grid::Lattice,
        step: i32,
    ) -> Self {
        let mut deltas = [0isize; march::STENCIL];
        if let NodeIndex::Dense { dims, .. } = index {
            let (dx, dy) = (dims.x as isize, dims.y as isize);
            for (k, d) in march::OFFSETS.iter().enumerate() {
                let d = *d * step;
                deltas[k] = d.x as isize + dx * (d.y as isize + dy * d.z as isize);
            }
        }
        RegionNodes {
            nodes,
            index,
            lattice,
            step,
            deltas,
        }
    }
}

impl march::Nodes for RegionNodes<'_> {
    fn len(&self) -> usize {
        self.nodes.len()
    }

    #[inline]
    fn for_each_neighbour(&self, i: u32, mut offer: impl FnMut(u32, DVec3)) {
        let p = self.nodes[i as usize];
        let step = self.step;
        if let NodeIndex::Dense { lo, dims, index } = self.index {
            let d = p - *lo;
            if d.cmpge(IVec3::splat(step)).all() && d.cmplt(*dims - IVec3::splat(step)).all() {
                let base = d.x as isize
                    + dims.x as isize * (d.y as isize + dims.y as isize * d.z as isize);
                for (k, &delta) in self.deltas.iter().enumerate() {
                    let j = index[(base + delta) as usize];
                    if j != nodes::NONE {
                        offer(j, self.lattice.node_position(p + march::OFFSETS[k] * step));
                    }
                }
                return;
            }
        }
        for d in march::OFFSETS {
            if let Some(j) = self.index.get(p + d * step) {
                offer(j, self.lattice.node_position(p + d * step));
            }
        }
    }

    #[inline]
    fn position(&self, i: u32) -> DVec3 {
        self.lattice.node_position(self.nodes[i as usize])
    }
}

/// Every region node's nearest breaking point (`points`, each on an edge with region
/// node `seed(k)` at one end): exactly within [`FAR_FIELD_BAND_CELLS`] of one, from
/// candidates a [`nearest::PointTree`] gathers per block of nodes, and from the coarse march of
/// [`march::march_far_field`] beyond. A node only takes points of its own 26-connected
/// part of the region, the points a march over the region's nodes could carry to it
/// (beyond the band too).
///
/// Why not march the band too: a march finalises nodes in order of distance, sweeping the
/// band of the whole surface at once, so every step touches neighbours scattered over a
/// working set as large as the band; it was bound by memory latency and slowed down per
/// node as the band outgrew the caches (6 bunnies: 3.1 µs per band node at 337k
/// triangles, 4.8 µs at 1.35M, where the band was three quarters of the stage). The
/// queries are independent, run on every core in lattice order, and give the exact
/// nearest point, which the march's closest-point propagation approximates.
fn nearest_points(
    nodes: &[IVec3],
    index: &NodeIndex,
    lattice: &crate::stages::grid::Lattice,
    points: &[BreakingPoint],
    seed: impl Fn(usize) -> Option<usize>,
) -> (Vec<march::Slot>, march::FarFieldStats) {
    let clock = std::time::Instant::now();
    let band = FAR_FIELD_BAND_CELLS * lattice.cell_size;
    let parts = components(nodes);
    // Each point's part: the part of the node at one end of its edge.
    let groups: Vec<u32> = (0..points.len())
        .map(|k| seed(k).map_or(u32::MAX, |i| parts[i]))
        .collect();
    let tree = nearest::PointTree::new(points.iter().zip(&groups).map(|(p, &g)| (p.position, g)));
    // Queries go by slabs of blocks (the far field's coarse cells). A block whose nodes
    // all lie in one part gathers once the points of that part that can be nearest to
    // any of its nodes within the band, nearest its centre first, and each node scans
    // that list (`nearest::nearest_of`): the same answers as a tree query per node, at a
    // fraction of the cost, and a cost that does not grow with the tree. A block's nodes
    // lie within the half-diagonal `h` of its centre `c`, so a node's nearest point `p`
    // has |p − c| ≤ |c − q| + 2h for the nearest point `q` to the centre, and
    // |p − c| ≤ band + h when it is within the band. A block straddling parts (rare: thin
    // gaps) asks the tree per node.
    let half_diagonal = 0.5 * (FAR_FIELD_BLOCK - 1) as f64 * 3f64.sqrt() * lattice.cell_size;
    let reach = band + half_diagonal;
    let slabs = slabs(nodes);
    let (parts, tree, groups) = (&parts, &tree, &groups);
    let position = |k: u32| points[k as usize].position;
    let per_slab: Vec<(Vec<march::Slot>, Vec<bool>)> = slabs
        .par_iter()
        .map(|range| {
            // Each block's part; consecutive nodes along x mostly share both, so the map
            // is asked only when either changes.
            let key = |i: usize| nodes[i].div_euclid(IVec3::splat(FAR_FIELD_BLOCK));
            let mut blocks: HashMap<IVec3, BandBlock, BuildHasherDefault<TileHasher>> =
                HashMap::default();
            let mut last = None;
            for i in range.clone() {
                if last == Some((key(i), parts[i])) {
                    continue;
                }
                last = Some((key(i), parts[i]));
                let block = blocks.entry(key(i)).or_insert(BandBlock {
                    part: parts[i],
                    candidates: (0, 0),
                });
                if block.part != parts[i] {
                    block.part = BandBlock::MIXED;
                }
            }
            // Each one-part block's candidates.
            let mut list: Vec<(f64, u32)> = Vec::new();
            for (&key, block) in blocks.iter_mut() {
                let first = list.len();
                let centre = block_centre(lattice, key);
                let margin = 1.0 + 1e-9;
                let nearest = (block.part != BandBlock::MIXED)
                    .then(|| tree.nearest(centre, block.part, reach * margin, None))
                    .flatten();
                if let Some(q) = nearest {
                    let radius = (q.distance + 2.0 * half_diagonal).min(reach);
                    tree.within(centre, block.part, radius * margin, &mut list);
                    list[first..].sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                }
                block.candidates = (first as u32, list.len() as u32);
            }
            let mut hint = None;
            let mut last: Option<(IVec3, BandBlock)> = None;
            range
                .clone()
                .map(|i| {
                    let key = key(i);
                    let block = match last {
                        Some((k, block)) if k == key => block,
                        _ => {
                            let block = blocks.get(&key).copied().unwrap_or(BandBlock {
                                part: BandBlock::MIXED,
                                candidates: (0, 0),
                            });
                            last = Some((key, block));
                            block
                        }
                    };
                    let at = lattice.node_position(nodes[i]);
                    let found = if block.part == BandBlock::MIXED {
                        tree.nearest(at, parts[i], band, hint).map(|found| {
                            hint = Some(found);
                            (found.distance, found.id)
                        })
                    } else {
                        let centre = block_centre(lattice, key);
                        let offset = at.distance(centre) * (1.0 + 1e-12) + 1e-300;
                        let (lo, hi) = block.candidates;
                        let candidates = &list[lo as usize..hi as usize];
                        nearest::nearest_of(
                            candidates, at, offset, block.part, groups, position, band,
                        )
                    };
                    match found {
                        Some((distance, point)) => (march::Slot { distance, point }, true),
                        None => (march::Slot::OPEN, false),
                    }
                })
                .unzip()
        })
        .collect();
    let mut slots = Vec::with_capacity(nodes.len());
    let mut near = Vec::with_capacity(nodes.len());
    for (s, n) in per_slab {
        slots.extend(s);
        near.extend(n);
    }
    let band_seconds = clock.elapsed().as_secs_f64();
    let levels = RegionLevels::new(nodes, index, lattice, parts);
    let far = march::march_far_field(&levels, &slabs, points, groups, &mut slots, &near);
    tracing::debug!(
        band = band_seconds,
        far_field = clock.elapsed().as_secs_f64() - band_seconds,
        "labels: seconds of the nearest points"
    );
    (slots, far)
}

/// A block of the band's queries in [`nearest_points`].
#[derive(Clone, Copy)]
struct BandBlock {
    /// The part of the region all its nodes lie in, or [`BandBlock::MIXED`].
    part: u32,
    /// Its candidate points: a range of its slab's list (empty for a mixed block).
    candidates: (u32, u32),
}

impl BandBlock {
    /// Nodes of more than one part.
    const MIXED: u32 = u32::MAX;
}

/// The region's nodes (in lattice order) by slabs of [`FAR_FIELD_BLOCK`] lattice layers:
/// the ranges of nodes whose blocks share a z coordinate. Work per block (the far field's
/// candidates, the band's test) is done once, by the task of the block's slab.
fn slabs(nodes: &[IVec3]) -> Vec<std::ops::Range<usize>> {
    let layer = |i: usize| nodes[i].z.div_euclid(FAR_FIELD_BLOCK);
    let mut out = Vec::new();
    let mut start = 0;
    while start < nodes.len() {
        let z = layer(start);
        let end = start + nodes[start..].partition_point(|p| p.z.div_euclid(FAR_FIELD_BLOCK) == z);
        out.push(start..end);
        start = end;
    }
    out
}

/// The 26-connected parts of the region (the march's stencil), each node's as its part's
/// smallest node. `nodes` must be in lattice order (z, then y, then x), as
/// [`region_nodes`] numbers them.
///
/// Works on runs (nodes consecutive along x in one lattice row, which are consecutive
/// ids): a run is one part by itself, and two runs in neighbouring rows touch when their
/// x ranges come within one of each other. Why: inside an overlap a row is one long run,
/// so this is union–find over far fewer elements than nodes, with no per-node lookup of
/// 13 neighbours (that was 0.37 s at 2.1M triangles, sequential).
fn components(nodes: &[IVec3]) -> Vec<u32> {
    // Runs as (first node, last node); rows as (z, y, first run) in order.
    let mut runs: Vec<(u32, u32)> = Vec::new();
    let mut rows: Vec<(i32, i32, u32)> = Vec::new();
    for (i, &p) in nodes.iter().enumerate() {
        let i = i as u32;
        match runs.last_mut() {
            Some(run) if nodes[run.1 as usize] + IVec3::X == p => run.1 = i,
            _ => {
                if rows.last().is_none_or(|r| (r.0, r.1) != (p.z, p.y)) {
                    rows.push((p.z, p.y, runs.len() as u32));
                }
                runs.push((i, i));
            }
        }
    }
    let row_runs = |k: usize| {
        let end = rows.get(k + 1).map_or(runs.len(), |r| r.2 as usize);
        rows[k].2 as usize..end
    };
    let mut parent: Vec<u32> = (0..runs.len() as u32).collect();
    for k in 0..rows.len() {
        let (z, y, _) = rows[k];
        // The rows after this one that the stencil reaches: each pair of rows once.
        for (dz, dy) in [(0, 1), (1, -1), (1, 0), (1, 1)] {
            let key = (z + dz, y + dy);
            let Ok(m) = rows.binary_search_by(|r| (r.0, r.1).cmp(&key)) else {
                continue;
            };
            let others = row_runs(m);
            for r in row_runs(k) {
                let (lo, hi) = (nodes[runs[r].0 as usize].x, nodes[runs[r].1 as usize].x);
                // Runs of the other row, in x order, from the first ending at lo − 1 or
                // later while they start at hi + 1 or earlier.
                let first = others.start
                    + runs[others.clone()].partition_point(|s| nodes[s.1 as usize].x < lo - 1);
                for s in first..others.end {
                    if nodes[runs[s].0 as usize].x > hi + 1 {
                        break;
                    }
                    mesh_core::union_find::union(&mut parent, r as u32, s as u32);
                }
            }
        }
    }
    let mut parts = vec![0u32; nodes.len()];
    for r in 0..runs.len() {
        // A run's root is the part's first run, whose first node is the part's smallest.
        let root = mesh_core::union_find::find(&mut parent, r as u32);
        let (first, last) = runs[r];
        parts[first as usize..=last as usize].fill(runs[root as usize].0);
    }
    parts
}

/// Lattice cells between the coarse nodes of the far-field march
/// ([`march::march_far_field`]): 4³ = 64 times fewer nodes marched far from the breaking
/// points.
const FAR_FIELD_BLOCK: i32 = 4;

/// The centre of the nodes of `block` (those whose lattice coordinates divided by
/// [`FAR_FIELD_BLOCK`] round down to it).
fn block_centre(lattice: &crate::stages::grid::Lattice, block: IVec3) -> DVec3 {
    lattice.node_position(block * FAR_FIELD_BLOCK)
        + DVec3::splat(0.5 * (FAR_FIELD_BLOCK - 1) as f64 * lattice.cell_size)
}

/// Distance from the nearest breaking point, in cells, within which every node gets the
/// exact nearest point (the band of [`nearest_points`]): two coarse cells. Narrower is
/// cheaper in the band but coarser beyond it, where a node's candidates are the points
/// of coarse nodes up to 2 cells off along each axis, so its point is off by about
/// 4ℓ²/d at distance d: on the test block whose faces carry six labels, 0.41ℓ with 8
/// cells, 0.68ℓ with 4.
const FAR_FIELD_BAND_CELLS: f64 = 2.0 * FAR_FIELD_BLOCK as f64;

/// The region's nodes at the far-field march's two resolutions.
struct RegionLevels<'a> {
    fine: RegionNodes<'a>,
    coarse: RegionNodes<'a>,
    /// Each node's part of the region ([`components`]).
    parts: &'a [u32],
}

impl<'a> RegionLevels<'a> {
    fn new(
        nodes: &'a [IVec3],
        index: &'a NodeIndex,
        lattice: &'a crate::stages::grid::Lattice,
        parts: &'a [u32],
    ) -> Self {
        RegionLevels {
            fine: RegionNodes::new(nodes, index, lattice, 1),
            coarse: RegionNodes::new(nodes, index, lattice, FAR_FIELD_BLOCK),
            parts,
        }
    }
}

impl march::Levels for RegionLevels<'_> {
    fn fine(&self) -> &(impl march::Nodes + Sync) {
        &self.fine
    }

    fn coarse(&self) -> &(impl march::Nodes + Sync) {
        &self.coarse
    }

    #[inline]
    fn is_coarse(&self, i: u32) -> bool {
        let p = self.fine.nodes[i as usize];
        let b = self.coarse.step;
        p.x.rem_euclid(b) == 0 && p.y.rem_euclid(b) == 0 && p.z.rem_euclid(b) == 0
    }

    #[inline]
    fn cell(&self, i: u32) -> IVec3 {
        self.fine.nodes[i as usize].div_euclid(IVec3::splat(self.coarse.step))
    }

    #[inline]
    fn part(&self, i: u32) -> u32 {
        self.parts[i as usize]
    }

    #[inline]
    fn centre(&self, cell: IVec3) -> DVec3 {
        block_centre(self.fine.lattice, cell)
    }

    fn around(&self, cell: IVec3, mut visit: impl FnMut(u32)) {
        let b = self.coarse.step;
        let index = self.fine.index;
        for k in 0..64 {
            let corner = (cell + IVec3::new(k & 3, (k >> 2) & 3, k >> 4) - IVec3::ONE) * b;
            if let Some(j) = index.get(corner) {
                visit(j);
            }
        }
        let lo = cell * b - IVec3::ONE;
        for z in lo.z..=lo.z + b + 1 {
            for y in lo.y..=lo.y + b + 1 {
                for x in lo.x..=lo.x + b + 1 {
                    if let Some(j) = index.get(IVec3::new(x, y, z)) {
                        visit(j);
                    }
                }
            }
        }
    }
}

#[cfg(test)]
pub(crate) mod tests;
