//! Per-vertex attributes (velocities, temperatures, …) carried through mesh edits.
//!
//! Attributes live beside the mesh as one flat `f64` array of `dim` values per vertex slot.
//! Each vertex an edit creates or moves names a [`Blend`] of existing vertices, so a split
//! interpolates, a collapse averages and a vertex separation copies — without the
//! operations knowing what the attributes mean.

use crate::ids::VertexId;
use crate::mesh::LabeledMesh;

use super::edit::{Applied, Edit};

/// A convex combination of up to three existing vertices.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Blend {
    /// Source vertices (unused entries have weight 0).
    pub ids: [VertexId; 3],
    /// Weights, summing to 1.
    pub weights: [f64; 3],
}

impl Blend {
    /// A copy of one vertex.
    pub fn copy(v: VertexId) -> Blend {
        Blend {
            ids: [v; 3],
            weights: [1.0, 0.0, 0.0],
        }
    }

    /// `(1−t)·a + t·b`.
    pub fn lerp(a: VertexId, b: VertexId, t: f64) -> Blend {
        Blend {
            ids: [a, b, a],
            weights: [1.0 - t, t, 0.0],
        }
    }

    /// Barycentric combination of three vertices.
    pub fn barycentric(ids: [VertexId; 3], weights: [f64; 3]) -> Blend {
        Blend { ids, weights }
    }
}

/// Values [`VertexAttributes::apply`] stages on the stack (a split, flip, collapse or
/// smoothing move with up to a few dozen values per vertex); larger edits allocate. Edits
/// run by the hundred thousand in `improve`, so the common case must not allocate.
const STACK_VALUES: usize = 64;

/// `dim` values per vertex slot, following the mesh through edits.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct VertexAttributes {
    dim: usize,
    values: Vec<f64>,
}

impl VertexAttributes {
    /// No attributes (edits then cost nothing extra).
    pub fn none() -> Self {
        Self::default()
    }

    /// `dim` values per vertex slot of `mesh`, all zero.
    pub fn zeros(mesh: &LabeledMesh, dim: usize) -> Self {
        Self {
            dim,
            values: vec![0.0; dim * mesh.vertex_capacity()],
        }
    }

    /// Values per vertex.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// The values of a vertex.
    pub fn get(&self, v: VertexId) -> &[f64] {
        &self.values[v.idx() * self.dim..(v.idx() + 1) * self.dim]
    }

    /// The values of a vertex, mutably.
    pub fn get_mut(&mut self, v: VertexId) -> &mut [f64] {
        &mut self.values[v.idx() * self.dim..(v.idx() + 1) * self.dim]
    }

    /// Grows the values to `mesh`'s vertex capacity (new slots zero), after vertices were
    /// added other than by an edit.
    pub(crate) fn fit(&mut self, mesh: &LabeledMesh) {
        let need = mesh.vertex_capacity() * self.dim;
        if self.values.len() < need {
            self.values.resize(need, 0.0);
        }
    }

    /// Updates the attributes for an applied edit: blends for new and moved vertices.
    /// Blends read the values from before the edit, so the order of entries is irrelevant.
    pub(crate) fn apply(&mut self, mesh: &LabeledMesh, edit: &Edit, applied: &Applied) {
        if self.dim == 0 {
            return;
        }
        let need = mesh.vertex_capacity() * self.dim;
        if self.values.len() < need {
            self.values.resize(need, 0.0);
        }
        let dim = self.dim;
        let blend = |values: &[f64], b: &Blend, out: &mut [f64]| {
            out.fill(0.0);
            for (id, w) in b.ids.iter().zip(b.weights) {
                if w != 0.0 {
                    for (o, x) in out
                        .iter_mut()
                        .zip(&values[id.idx() * dim..(id.idx() + 1) * dim])
                    {
                        *o += w * x;
                    }
                }
            }
        };
        // Staged so that every blend reads the values from before the edit. Edits are small:
        // the common sizes stay on the stack, only unusually large ones allocate.
        let len = dim * (edit.new_vertices.len() + edit.moves.len());
        let mut small = [0.0; STACK_VALUES];
        let mut large = Vec::new();
        let staged: &mut [f64] = if len <= STACK_VALUES {
            &mut small[..len]
        } else {
            large.resize(len, 0.0);
            &mut large
        };
        let mut chunks = staged.chunks_mut(dim);
        for nv in &edit.new_vertices {
            if let Some(out) = chunks.next() {
                blend(&self.values, &nv.blend, out);
            }
        }
        for m in &edit.moves {
            if let (Some(out), Some(b)) = (chunks.next(), m.blend.as_ref()) {
                blend(&self.values, b, out);
            }
        }
        let mut chunks = staged.chunks(dim);
        for &v in &applied.vertices {
            if let Some(src) = chunks.next() {
                self.get_mut(v).copy_from_slice(src);
            }
        }
        for m in &edit.moves {
            if let Some(src) = chunks.next()
                && m.blend.is_some()
            {
                self.get_mut(m.vertex).copy_from_slice(src);
            }
        }
    }
}
