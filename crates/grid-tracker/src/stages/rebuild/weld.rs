//! Welding keyed triangles into an indexed mesh: equal keys become one vertex, exactly.
//!
//! The octant triangles of neighbouring cells and the boundary fans name shared vertices
//! by the same [`RebuildVertexKey`], so a hash map from key to index welds them with no
//! tolerance. [`Welder::alias`] implements the vertex sliding of §8.2: where a boundary
//! face meets an internal face, the octant vertex on their common grid edge slides onto
//! the cut point there (after §6.4 that edge carries at most one crossing), i.e. both keys
//! name one vertex, placed where the cut point is.

use glam::DVec3;
use mesh_core::{Label, LabeledMesh, MeshError};

use super::keys::{KeyMap, RebuildTriangle, RebuildVertexKey};

/// Why triangles could not be welded.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum WeldError {
    /// Both keys of an alias already name different vertices.
    #[error("cannot slide {from:?} onto {to:?}: both are already separate vertices")]
    AliasConflict {
        /// The sliding key.
        from: RebuildVertexKey,
        /// The key it should join.
        to: RebuildVertexKey,
    },
    /// Two corners of a triangle weld to one vertex (through aliases).
    #[error("triangle {verts:?} collapses: two of its keys are the same vertex")]
    Collapsed {
        /// The triangle's keys.
        verts: [RebuildVertexKey; 3],
    },
    /// More vertices than `u32` indices.
    #[error("more than u32::MAX welded vertices")]
    TooManyVertices,
    /// The placement gave no position for a key.
    #[error("no position for vertex {key:?}")]
    Unplaced {
        /// The key.
        key: RebuildVertexKey,
    },
    /// The mesh could not be built from the welded arrays.
    #[error("welded mesh rejected: {0}")]
    Mesh(#[from] MeshError),
}

/// Welds keyed triangles into indexed triangles: vertex `i` is `keys()[i]`, triangle `t`
/// is `triangles()[t]` with labels `labels()[t]`. Vertices are numbered in order of first
/// appearance, so the result is deterministic for a deterministic input order.
#[derive(Clone, Debug, Default)]
pub struct Welder {
    index: KeyMap<u32>,
    keys: Vec<RebuildVertexKey>,
    triangles: Vec<[u32; 3]>,
    labels: Vec<[Label; 2]>,
}

impl Welder {
    /// An empty welder.
    pub fn new() -> Self {
        Self::default()
    }

    /// Forgets everything, keeping the buffers.
    pub fn clear(&mut self) {
        self.index.clear();
        self.keys.clear();
        self.triangles.clear();
        self.labels.clear();
    }

    /// The vertex of `key`, if it has one yet.
    #[inline]
    pub fn get(&self, key: RebuildVertexKey) -> Option<u32> {
        self.index.get(&key).copied()
    }

    /// The vertex of `key`, created if new.
    pub fn vertex(&mut self, key: RebuildVertexKey) -> Result<u32, WeldError> {
        if let Some(&i) = self.index.get(&key) {
            return Ok(i);
        }
        let i = u32::try_from(self.keys.len()).map_err(|_| WeldError::TooManyVertices)?;
        self.keys.push(key);
        self.index.insert(key, i);
        Ok(i)
    }

    /// Makes `from` name the vertex of `to` (vertex sliding), in either order of first
    /// use: if only `from` has a vertex yet, that vertex becomes `to`'s and takes `to` as
    /// its key (so it is placed where `to` is). Fails if both already name different
    /// vertices. Returns the shared vertex.
    pub fn alias(
        &mut self,
        from: RebuildVertexKey,
        to: RebuildVertexKey,
    ) -> Result<u32, WeldError> {
        match (self.get(from), self.get(to)) {
            (Some(a), Some(b)) if a != b => Err(WeldError::AliasConflict { from, to }),
            (Some(a), Some(_)) => Ok(a),
            (Some(a), None) => {
                self.index.insert(to, a);
                self.keys[a as usize] = to;
                Ok(a)
            }
            (None, _) => {
                let b = self.vertex(to)?;
                self.index.insert(from, b);
                Ok(b)
            }
        }
    }

    /// Adds one triangle; returns its index. On error no triangle is added (keys seen for
    /// the first time keep their new vertices).
    pub fn add(&mut self, t: &RebuildTriangle) -> Result<usize, WeldError> {
        let [a, b, c] = t.verts;
        let v = [self.vertex(a)?, self.vertex(b)?, self.vertex(c)?];
        if v[0] == v[1] || v[1] == v[2] || v[0] == v[2] {
            return Err(WeldError::Collapsed { verts: t.verts });
        }
        self.triangles.push(v);
        self.labels.push(t.labels);
        Ok(self.triangles.len() - 1)
    }

    /// Adds every triangle of `ts`, stopping at the first error.
    pub fn add_all(&mut self, ts: &[RebuildTriangle]) -> Result<(), WeldError> {
        ts.iter().try_for_each(|t| self.add(t).map(|_| ()))
    }

    /// The key of every vertex (for an aliased vertex, the key it slid onto).
    #[inline]
    pub fn keys(&self) -> &[RebuildVertexKey] {
        &self.keys
    }

    /// The welded triangles.
    #[inline]
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// `[front, back]` of every triangle.
    #[inline]
    pub fn labels(&self) -> &[[Label; 2]] {
        &self.labels
    }

    /// A standalone mesh of the welded triangles, each vertex placed by `position` (called
    /// once per vertex with its key; `None` is an error naming the key).
    pub fn to_mesh(
        &self,
        mut position: impl FnMut(RebuildVertexKey) -> Option<DVec3>,
    ) -> Result<LabeledMesh, WeldError> {
        let positions = self
            .keys
            .iter()
            .map(|&key| position(key).ok_or(WeldError::Unplaced { key }))
            .collect::<Result<Vec<_>, _>>()?;
        let labels: Vec<[u32; 2]> = self.labels.iter().map(|l| l.map(Label::raw)).collect();
        Ok(LabeledMesh::from_raw(positions, &self.triangles, &labels)?)
    }
}

#[cfg(test)]
mod tests {
    use glam::IVec3;

    use super::*;

    fn cell(x: i32) -> RebuildVertexKey {
        RebuildVertexKey::Cell(IVec3::new(x, 0, 0))
    }

    #[test]
    fn equal_keys_weld_and_aliases_slide() {
        let mut w = Welder::new();
        let (l0, l1) = (Label::new(0), Label::new(1));
        let t = |a, b, c| RebuildTriangle {
            verts: [cell(a), cell(b), cell(c)],
            labels: [l1, l0],
        };
        assert_eq!(w.add(&t(0, 1, 2)), Ok(0));
        assert_eq!(w.add(&t(2, 1, 3)), Ok(1));
        assert_eq!(w.triangles(), &[[0, 1, 2], [2, 1, 3]]);
        // `from` known, `to` new: the vertex takes the new key.
        assert_eq!(w.alias(cell(3), RebuildVertexKey::Cut(7)), Ok(3));
        assert_eq!(w.keys()[3], RebuildVertexKey::Cut(7));
        // `from` new: it joins `to`.
        assert_eq!(w.alias(cell(9), cell(0)), Ok(0));
        assert_eq!(w.get(cell(9)), Some(0));
        assert_eq!(w.alias(cell(9), cell(0)), Ok(0));
        assert_eq!(
            w.alias(cell(1), cell(2)),
            Err(WeldError::AliasConflict {
                from: cell(1),
                to: cell(2)
            })
        );
        // A triangle whose keys alias to one vertex is refused, and nothing is added.
        assert!(matches!(
            w.add(&t(0, 9, 1)),
            Err(WeldError::Collapsed { .. })
        ));
        assert_eq!(w.triangles().len(), 2);
        // Placement must cover every vertex.
        let err = w.to_mesh(|k| (k != RebuildVertexKey::Cut(7)).then_some(DVec3::ZERO));
        assert!(matches!(
            err,
            Err(WeldError::Unplaced {
                key: RebuildVertexKey::Cut(7)
            })
        ));
        w.clear();
        assert!(w.keys().is_empty() && w.triangles().is_empty() && w.get(cell(0)).is_none());
    }
}
