//! Stage 2 (§5 of Heiss-Synak et al. 2024): material vectors on grid nodes by exact ray
//! casting along grid lines.
//!
//! Label 0 is the ambient material: a ray starts at −∞ with `e_0`. Crossing a triangle
//! labelled `[front, back]` (front = the side its right-hand normal points into) while
//! travelling from its back to its front subtracts 1 from `back` and adds 1 to `front`,
//! and the reverse for the other direction (Fig. 6).
//!
//! 1. [`crossings`]: every grid edge × triangle crossing, exact (Simulation of
//!    Simplicity), filed per grid edge with the triangle id, direction and coordinate;
//! 2. sweeps: rays along x give every allocated node its vector; rays along y and z
//!    repeat the computation and every node where an axis disagrees is *flawed*
//!    (following Müller 2009; with exact predicates and a closed, consistently labelled
//!    mesh this never happens — it flags broken input such as holes).
//!
//! **Where a ray starts.** A ray is swept only over the allocated nodes of its grid line,
//! starting at the line's first allocated node with `e_0`. That is sound although the
//! first allocated node may lie deep inside the mesh's bounding box, and although the
//! band may be interrupted along the line: (a) crossings are gathered from *every*
//! triangle, triangle by triangle, not from the cells the line happens to border, so no
//! crossing of the line is missed; (b) every crossing lies on a grid edge whose lower node
//! is allocated (proof in [`crossings`]: the closed cell boxes that meet a triangle's box
//! are all allocated). Hence no crossing precedes the first allocated node — the vector
//! there equals the vector at −∞, `e_0` — and none lies in a gap of the band, across
//! which the vector carries over unchanged.
//!
//! Storage, measured on a 1.31 M-triangle icosphere with ℓ = mean edge length (2.0 M
//! allocated nodes, 0.85 M crossings): one 4-byte [`MaterialRef`] per allocated node
//! (8 MB) — the label itself for the physical majority, an index into a pool of `(label,
//! count)` runs for mixed vectors, shared by consecutive nodes of a line with the same
//! vector. Storing vectors only where they change along a ray (§5) would keep about one
//! entry per crossing plus one per line (≈ 1 M entries, 4–8 MB) and turn every lookup
//! into a search along the line, so every allocated node stores its vector. The
//! crossings take 16 bytes each (13.5 MB) plus the CSR offsets, 4 bytes per edge
//! (24 MB). Unallocated nodes are answered by [`Materials::material_at`].
//!
//! Entry point: [`assign_materials`].

pub mod crossings;
mod sweep;
pub mod vector;

use std::sync::atomic::AtomicU32;

use glam::IVec3;
use mesh_core::predicates::Axis;
use mesh_core::{Label, LabeledMesh, TriId};

pub use crossings::EdgeCrossing;
use sweep::{Sink, SweepPart, sweep_axis};
pub use vector::{MaterialRef, MaterialVector, MaterialView, MixedPool};

use crate::stages::grid::{Grid, NodeId};

/// Options of [`assign_materials`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MaterialOptions {
    /// Also cast rays along y and z and mark nodes where the axes disagree as flawed
    /// (§5, Müller 2009). Default true. Switching it off saves two of the three sweeps
    /// (the crossings are found for all axes either way) but leaves broken input, such as
    /// a mesh with holes, undetected.
    pub check_all_axes: bool,
}

impl Default for MaterialOptions {
    fn default() -> Self {
        Self {
            check_all_axes: true,
        }
    }
}

/// Why material vectors could not be assigned.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MaterialError {
    /// The grid was built from a different mesh (or the mesh changed since).
    #[error("grid was built for a mesh with {grid} triangle slots, this mesh has {mesh}")]
    GridMismatch {
        /// Triangle capacity recorded by the grid.
        grid: usize,
        /// Triangle capacity of the mesh given.
        mesh: usize,
    },
    /// A label does not fit the compact encoding (labels must be below 2³¹).
    #[error("triangle {tri} has label {label}, labels must be below 2^31")]
    LabelTooLarge {
        /// The triangle.
        tri: TriId,
        /// Its offending label.
        label: Label,
    },
    /// More distinct mixed vectors than the pool can index (2³¹).
    #[error("too many non-physical material vectors to store")]
    TooManyMixed,
    /// An internal invariant failed (a bug): `what` says which, `tri` where.
    #[error("internal error at triangle {tri}: {what}")]
    Internal {
        /// The broken invariant.
        what: &'static str,
        /// The triangle being processed.
        tri: TriId,
    },
}

/// Sizes and memory of a [`Materials`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MaterialStats {
    /// Grid edge × triangle crossings.
    pub crossings: usize,
    /// Allocated nodes with a non-physical (mixed) vector.
    pub mixed_nodes: usize,
    /// Distinct mixed vectors stored.
    pub mixed_vectors: usize,
    /// Nodes where the three axes disagree.
    pub flawed_nodes: usize,
    /// Heap bytes held.
    pub heap_bytes: usize,
}

/// Material vectors of all allocated nodes and the crossings of all grid edges.
#[derive(Clone, Debug)]
pub struct Materials {
    node: Vec<MaterialRef>,
    pool: MixedPool,
    /// Nodes whose axes disagree, sorted: `(node, [x, y, z] vectors)`.
    flawed: Vec<(NodeId, [MaterialRef; 3])>,
    edge_start: Vec<u32>,
    crossings: Vec<EdgeCrossing>,
}

impl Materials {
    /// Number of nodes covered (the grid's allocated nodes).
    pub fn num_nodes(&self) -> usize {
        self.node.len()
    }

    /// The vector of node `n` (from the ray along x).
    #[inline]
    pub fn node_material(&self, n: NodeId) -> MaterialRef {
        self.node[n.idx()]
    }

    /// The vector behind a ref.
    #[inline]
    pub fn view(&self, r: MaterialRef) -> MaterialView<'_> {
        match (r.label(), r.mixed_index()) {
            (Some(l), _) => MaterialView::Physical(l),
            (None, Some(i)) => MaterialView::Mixed(self.pool.get(i)),
            (None, None) => MaterialView::Mixed(&[]),
        }
    }

    /// The vector of node `n`, borrowed.
    #[inline]
    pub fn node_vector(&self, n: NodeId) -> MaterialView<'_> {
        self.view(self.node[n.idx()])
    }

    /// True when the three axes gave node `n` different vectors.
    pub fn is_flawed(&self, n: NodeId) -> bool {
        self.flawed.binary_search_by_key(&n, |f| f.0).is_ok()
    }

    /// The physical label of node `n`: one-hot and not flawed.
    pub fn physical_label(&self, n: NodeId) -> Option<Label> {
        self.node[n.idx()].label().filter(|_| !self.is_flawed(n))
    }

    /// Nodes whose axes disagree, sorted by node, with their `[x, y, z]` vectors.
    pub fn flawed_nodes(&self) -> &[(NodeId, [MaterialRef; 3])] {
        &self.flawed
    }

    /// The vector node `n` got from the ray along `axis`: the start of that axis' edge
    /// sweep from `n`. Differs from [`Self::node_material`] only at flawed nodes.
    pub fn axis_material(&self, n: NodeId, axis: Axis) -> MaterialRef {
        match self.flawed.binary_search_by_key(&n, |f| f.0) {
            Ok(i) => self.flawed[i].1[axis.index()],
            Err(_) => self.node[n.idx()],
        }
    }

    /// Crossings of the grid edge from node `n` towards +`axis`, in order along it.
    #[inline]
    pub fn edge_crossings(&self, n: NodeId, axis: Axis) -> &[EdgeCrossing] {
        let e = n.idx() * 3 + axis.index();
        &self.crossings[self.edge_start[e] as usize..self.edge_start[e + 1] as usize]
    }

    /// Walks the grid edge from `n` towards +`axis`: calls `f(None, v)` with the vector at
    /// `n` (along that axis), then `f(Some(crossing), v)` with the vector just after each
    /// crossing, in order. `buf` is reused, so walking many edges allocates nothing. This
    /// is how non-physical stretches (§6.1) and breaking points (§8.1) are found.
    pub fn edge_vectors(
        &self,
        mesh: &LabeledMesh,
        n: NodeId,
        axis: Axis,
        buf: &mut MaterialVector,
        mut f: impl FnMut(Option<&EdgeCrossing>, &MaterialVector),
    ) {
        buf.set_from(self.view(self.axis_material(n, axis)));
        f(None, buf);
        for x in self.edge_crossings(n, axis) {
            buf.cross(x.direction, mesh.labels(x.tri));
            f(Some(x), buf);
        }
    }

    /// Number of crossings on the grid edge from `n` towards +`axis`.
    #[inline]
    pub fn edge_crossing_count(&self, n: NodeId, axis: Axis) -> usize {
        let e = n.idx() * 3 + axis.index();
        (self.edge_start[e + 1] - self.edge_start[e]) as usize
    }

    /// The vector at any lattice node, allocated or not: an unallocated node has the
    /// vector of the nearest allocated node below it along x (no mesh lies between, see
    /// [`Grid::node_at_or_below_x`]), or `e_0` when there is none.
    pub fn material_at(&self, grid: &Grid, p: IVec3) -> MaterialRef {
        self.material_from(grid.node_id(p).or_else(|| grid.node_at_or_below_x(p)))
    }

    /// The vector an unallocated node takes from `source`, its nearest allocated node
    /// at or below it along x ([`Materials::material_at`]), or `e_0` for none.
    #[inline]
    pub fn material_from(&self, source: Option<NodeId>) -> MaterialRef {
        source.map_or_else(outside, |n| self.node[n.idx()])
    }

    /// Sizes and memory.
    pub fn stats(&self) -> MaterialStats {
        use std::mem::size_of;
        MaterialStats {
            crossings: self.crossings.len(),
            mixed_nodes: self.node.iter().filter(|r| !r.is_physical()).count(),
            mixed_vectors: self.pool.len(),
            flawed_nodes: self.flawed.len(),
            heap_bytes: self.node.capacity() * size_of::<MaterialRef>()
                + self.pool.heap_bytes()
                + self.flawed.capacity() * size_of::<(NodeId, [MaterialRef; 3])>()
                + self.edge_start.capacity() * 4
                + self.crossings.capacity() * size_of::<EdgeCrossing>(),
        }
    }
}

fn outside() -> MaterialRef {
    MaterialRef::physical(Label::new(0))
        .unwrap_or_else(|| unreachable!("label 0 is always encodable"))
}

/// Assigns a material vector to every allocated node of `grid` and files the crossings
/// of every grid edge (§5).
///
/// Errors: a grid built from another mesh, labels ≥ 2³¹, or an internal invariant
/// failure (reported, never a panic).
pub fn assign_materials(
    mesh: &LabeledMesh,
    grid: &Grid,
    options: &MaterialOptions,
) -> Result<Materials, MaterialError> {
    if grid.triangle_capacity() != mesh.triangle_capacity() {
        return Err(MaterialError::GridMismatch {
            grid: grid.triangle_capacity(),
            mesh: mesh.triangle_capacity(),
        });
    }
    for t in mesh.triangles() {
        for label in mesh.labels(t) {
            if MaterialRef::physical(label).is_none() {
                return Err(MaterialError::LabelTooLarge { tri: t, label });
            }
        }
    }
    let edges = crossings::find_crossings(mesh, grid)?;

    let out: Vec<AtomicU32> = (0..grid.num_nodes()).map(|_| AtomicU32::new(0)).collect();
    let parts = sweep_axis(mesh, grid, &edges, 0, &Sink::Write(&out));
    let mut node: Vec<MaterialRef> = out
        .into_iter()
        .map(|a| MaterialRef::physical(Label::new(a.into_inner())).unwrap_or_else(outside))
        .collect();
    let mut pool = MixedPool::default();
    for part in &parts {
        let offset = merge(&mut pool, part)?;
        for &(n, i) in &part.mixed {
            node[n as usize] = MaterialRef::mixed(offset + i);
        }
    }
    drop(parts);

    let mut flawed: Vec<(NodeId, [MaterialRef; 3])> = Vec::new();
    if options.check_all_axes {
        let mut disagree: Vec<(u32, usize, MaterialRef)> = Vec::new();
        for axis in 1..3 {
            let parts = sweep_axis(
                mesh,
                grid,
                &edges,
                axis,
                &Sink::Compare {
                    x: &node,
                    pool: &pool,
                },
            );
            for part in &parts {
                let offset = merge(&mut pool, part)?;
                disagree.extend(part.disagree.iter().map(|&(n, r)| {
                    let r = r
                        .mixed_index()
                        .map_or(r, |i| MaterialRef::mixed(offset + i as u32));
                    (n, axis, r)
                }));
            }
        }
        disagree.sort_unstable_by_key(|d| (d.0, d.1));
        for (n, axis, r) in disagree {
            let id = NodeId::new(n);
            if flawed.last().is_none_or(|f| f.0 != id) {
                let x = node[n as usize];
                flawed.push((id, [x, x, x]));
            }
            if let Some(f) = flawed.last_mut() {
                f.1[axis] = r;
            }
        }
    }

    Ok(Materials {
        node,
        pool,
        flawed,
        edge_start: edges.start,
        crossings: edges.crossings,
    })
}

/// Appends a worker's pool to the global one; returns the index offset.
fn merge(pool: &mut MixedPool, part: &SweepPart) -> Result<u32, MaterialError> {
    if part.overflow {
        return Err(MaterialError::TooManyMixed);
    }
    pool.append(&part.pool).ok_or(MaterialError::TooManyMixed)
}

#[cfg(test)]
mod tests;
