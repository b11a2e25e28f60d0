//! [`Tracker`]: a backend plus named per-vertex attributes (velocities, temperatures, …)
//! that follow the mesh through every step, topology changes included, whichever backend
//! runs.
//!
//! A backend that carries attributes itself ([`SurfaceTracker::attributes`]: the grid
//! backend, by its edits' blends and PIC transfer, §8.4 of Heiss-Synak et al. 2024) gets
//! them handed over and does the work. For one that does not (the collision backend keeps
//! only its own motion attribute), the tracker carries them: after each step every vertex
//! of the new mesh takes the values of the nearest vertex of the old mesh moved to its
//! proposed positions. Survivors of a step stay where they were proposed (up to collision
//! impulses), so they keep their own values; vertices made by merges, splits and
//! remeshing take those of the closest old vertex.

use std::collections::HashMap;

use mesh_core::remesh::VertexAttributes;
use mesh_core::{DVec3, LabeledMesh, StepReport, SurfaceTracker, TrackError, VertexId};

use crate::{Backend, BackendError, BackendOptions, make_tracker_from};

/// Why an attribute could not be set.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AttributeError {
    /// The values are not `dim` per vertex slot.
    #[error(
        "attribute `{name}`: expected {expected} values ({dim} per vertex slot × {slots} slots), got {got}"
    )]
    Length {
        /// The attribute.
        name: String,
        /// Values per vertex.
        dim: usize,
        /// Vertex slots of the mesh.
        slots: usize,
        /// `dim × slots`.
        expected: usize,
        /// The length given.
        got: usize,
    },
    /// An attribute needs at least one value per vertex.
    #[error("attribute `{0}`: dimension must be at least 1")]
    ZeroDim(String),
}

/// A tracker of either backend with named per-vertex attributes carried through steps.
///
/// ```
/// use surftrack::{Backend, BackendOptions, Tracker};
/// use surftrack::mesh_core::generators::double_bubble;
///
/// let mesh = double_bubble(0.5, 12)?;
/// let mut tracker = Tracker::new(Backend::Grid, mesh, &BackendOptions::default())?;
/// let slots = tracker.mesh().vertex_capacity();
/// tracker.set_attribute("temperature", 1, &vec![20.0; slots])?;
/// let proposed = tracker.mesh().positions().to_vec();
/// tracker.advance(&proposed)?;
/// let (dim, values) = tracker.attribute("temperature").unwrap();
/// assert_eq!((dim, values.len()), (1, tracker.mesh().vertex_capacity()));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub struct Tracker {
    inner: Box<dyn SurfaceTracker>,
    /// Attribute names and widths, in column order of the combined attributes.
    columns: Vec<(String, usize)>,
    /// The combined attributes when the backend does not carry them.
    own: Option<VertexAttributes>,
}

impl Tracker {
    /// A tracker of `backend` around `mesh` with every option from `options`
    /// (see [`make_tracker_from`]).
    pub fn new(
        backend: Backend,
        mesh: LabeledMesh,
        options: &BackendOptions,
    ) -> Result<Self, BackendError> {
        Ok(Self::from_boxed(make_tracker_from(backend, mesh, options)?))
    }

    /// Wraps an existing backend (which must not carry attributes of its own yet).
    pub fn from_boxed(inner: Box<dyn SurfaceTracker>) -> Self {
        Self {
            inner,
            columns: Vec::new(),
            own: None,
        }
    }

    /// The backend's name.
    pub fn name(&self) -> &str {
        self.inner.name()
    }

    /// The current mesh.
    pub fn mesh(&self) -> &LabeledMesh {
        self.inner.mesh()
    }

    /// The backend, e.g. to downcast-free inspect its mesh or call trait methods.
    pub fn backend(&self) -> &dyn SurfaceTracker {
        self.inner.as_ref()
    }

    /// One step (see [`SurfaceTracker::advance`]); the attributes follow. On error the
    /// mesh and the attributes are unchanged.
    pub fn advance(&mut self, proposed: &[DVec3]) -> Result<StepReport, TrackError> {
        let Some(attrs) = &self.own else {
            return self.inner.advance(proposed);
        };
        // The old vertices where the motion takes them: what the new mesh is compared to.
        // `advance` checks the proposal first, so only a successful step reads this.
        let old = self.inner.mesh();
        let sources: Vec<(VertexId, DVec3)> = old
            .vertices()
            .filter_map(|v| proposed.get(v.idx()).map(|&p| (v, p)))
            .collect();
        let report = self.inner.advance(proposed)?;
        let carried = transfer_nearest(&sources, attrs, self.inner.mesh());
        self.own = Some(carried);
        Ok(report)
    }

    /// Names and widths of the attributes, in the order they were first set.
    pub fn attribute_names(&self) -> Vec<(&str, usize)> {
        self.columns.iter().map(|(n, d)| (n.as_str(), *d)).collect()
    }

    /// The combined attributes (every column, in [`Self::attribute_names`] order).
    fn combined(&self) -> Option<&VertexAttributes> {
        match &self.own {
            Some(a) => Some(a),
            None => self.inner.attributes(),
        }
    }

    /// Column offset and width of `name`.
    fn column(&self, name: &str) -> Option<(usize, usize)> {
        let mut offset = 0;
        for (n, d) in &self.columns {
            if n == name {
                return Some((offset, *d));
            }
            offset += d;
        }
        None
    }

    /// The values of attribute `name`: its width and `width` values per vertex slot of
    /// [`Self::mesh`] (dead slots hold zeros).
    pub fn attribute(&self, name: &str) -> Option<(usize, Vec<f64>)> {
        let (offset, dim) = self.column(name)?;
        let attrs = self.combined()?;
        let mesh = self.mesh();
        let mut out = vec![0.0; dim * mesh.vertex_capacity()];
        for v in mesh.vertices() {
            let row = attrs.get(v);
            out[v.idx() * dim..(v.idx() + 1) * dim].copy_from_slice(&row[offset..offset + dim]);
        }
        Some((dim, out))
    }

    /// Sets (or replaces) attribute `name`: `dim` values per vertex slot of
    /// [`Self::mesh`], slot by slot (values of dead slots are ignored).
    pub fn set_attribute(
        &mut self,
        name: &str,
        dim: usize,
        values: &[f64],
    ) -> Result<(), AttributeError> {
        let mesh = self.mesh();
        let slots = mesh.vertex_capacity();
        if dim == 0 {
            return Err(AttributeError::ZeroDim(name.to_string()));
        }
        if values.len() != dim * slots {
            return Err(AttributeError::Length {
                name: name.to_string(),
                dim,
                slots,
                expected: dim * slots,
                got: values.len(),
            });
        }
        let mut columns = self.columns.clone();
        match columns.iter_mut().find(|(n, _)| n == name) {
            Some(col) => col.1 = dim,
            None => columns.push((name.to_string(), dim)),
        }
        let total: usize = columns.iter().map(|(_, d)| d).sum();
        let mut attrs = VertexAttributes::zeros(mesh, total);
        for v in mesh.vertices() {
            let row = attrs.get_mut(v);
            let mut offset = 0;
            for (n, d) in &columns {
                let dst = &mut row[offset..offset + d];
                if n == name {
                    dst.copy_from_slice(&values[v.idx() * d..(v.idx() + 1) * d]);
                } else if let (Some((old, _)), Some(current)) = (self.column(n), self.combined()) {
                    dst.copy_from_slice(&current.get(v)[old..old + d]);
                }
                offset += d;
            }
        }
        self.columns = columns;
        self.install(attrs);
        Ok(())
    }

    /// Removes attribute `name`; `false` if there was none.
    pub fn remove_attribute(&mut self, name: &str) -> bool {
        let Some((offset, dim)) = self.column(name) else {
            return false;
        };
        let mesh = self.mesh();
        let total: usize = self.columns.iter().map(|(_, d)| d).sum::<usize>() - dim;
        let mut attrs = VertexAttributes::zeros(mesh, total);
        if let Some(current) = self.combined() {
            for v in mesh.vertices() {
                let row = current.get(v);
                let kept: Vec<f64> = row[..offset]
                    .iter()
                    .chain(&row[offset + dim..])
                    .copied()
                    .collect();
                attrs.get_mut(v).copy_from_slice(&kept);
            }
        }
        self.columns.retain(|(n, _)| n != name);
        self.install(attrs);
        true
    }

    /// Gives the combined attributes to the backend, or keeps them if it carries none.
    fn install(&mut self, attrs: VertexAttributes) {
        // Handed back (`Err`) when the backend carries none: then they are ours.
        self.own = self.inner.set_attributes(attrs).err();
    }
}

/// Nearest-point lookups over a fixed point set: a uniform hash grid searched in
/// Chebyshev shells of cells, each point bucketed once.
struct PointGrid {
    cell: f64,
    cells: HashMap<[i64; 3], Vec<usize>>,
    points: Vec<DVec3>,
    /// Bounds of the occupied cells, which bound every search.
    lo: [i64; 3],
    hi: [i64; 3],
}

impl PointGrid {
    fn new(points: Vec<DVec3>) -> Self {
        let (mut min, mut max) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for p in &points {
            min = min.min(*p);
            max = max.max(*p);
        }
        let extent = (max - min).max_element();
        // About one point per cell for a surface sample spread over a box.
        let n = points.len().max(1) as f64;
        let cell = if extent.is_finite() && extent > 0.0 {
            (extent / n.sqrt()).max(extent * 1e-6)
        } else {
            1.0
        };
        let mut grid = Self {
            cell,
            cells: HashMap::new(),
            points: Vec::new(),
            lo: [i64::MAX; 3],
            hi: [i64::MIN; 3],
        };
        for (i, p) in points.iter().enumerate() {
            let c = grid.key(*p);
            for (k, &ck) in c.iter().enumerate() {
                grid.lo[k] = grid.lo[k].min(ck);
                grid.hi[k] = grid.hi[k].max(ck);
            }
            grid.cells.entry(c).or_default().push(i);
        }
        grid.points = points;
        grid
    }

    fn key(&self, p: DVec3) -> [i64; 3] {
        // Saturating float→int casts keep far-away or non-finite points in range.
        (p / self.cell).floor().to_array().map(|x| x as i64)
    }

    /// The index of the point nearest to `p`; `None` only for an empty set.
    fn nearest(&self, p: DVec3) -> Option<usize> {
        if self.points.is_empty() {
            return None;
        }
        let c = self.key(p);
        // Every occupied cell lies within this Chebyshev distance of `c`.
        let max_ring = (0..3)
            .map(|k| (c[k].saturating_sub(self.lo[k])).max(self.hi[k].saturating_sub(c[k])))
            .max()
            .unwrap_or(0)
            .max(0);
        let mut best: Option<(f64, usize)> = None;
        for r in 0..=max_ring {
            for dx in -r..=r {
                for dy in -r..=r {
                    for dz in -r..=r {
                        if dx.abs().max(dy.abs()).max(dz.abs()) != r {
                            continue;
                        }
                        let key = [c[0] + dx, c[1] + dy, c[2] + dz];
                        for &i in self.cells.get(&key).into_iter().flatten() {
                            let d = self.points[i].distance_squared(p);
                            if best.is_none_or(|(b, _)| d < b) {
                                best = Some((d, i));
                            }
                        }
                    }
                }
            }
            // Cells beyond ring r are at least r·cell away from `p`.
            if let Some((d, _)) = best
                && d.sqrt() <= r as f64 * self.cell
            {
                break;
            }
        }
        best.map(|(_, i)| i)
    }
}

/// The attributes of `new`'s vertices, each copied from the nearest of `sources` (old
/// vertex ids at their proposed positions, reading `attrs`).
fn transfer_nearest(
    sources: &[(VertexId, DVec3)],
    attrs: &VertexAttributes,
    new: &LabeledMesh,
) -> VertexAttributes {
    let mut out = VertexAttributes::zeros(new, attrs.dim());
    let grid = PointGrid::new(sources.iter().map(|(_, p)| *p).collect());
    for v in new.vertices() {
        if let Some(i) = grid.nearest(new.position(v)) {
            out.get_mut(v).copy_from_slice(attrs.get(sources[i].0));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use mesh_core::generators::double_bubble;

    #[test]
    fn point_grid_finds_the_true_nearest_point() {
        let points: Vec<DVec3> = (0..500)
            .map(|i| {
                let t = i as f64 * 0.37;
                DVec3::new(t.sin() * 3.0, (t * 1.7).cos(), (t * 0.3).sin() * 5.0)
            })
            .collect();
        let grid = PointGrid::new(points.clone());
        for q in [
            DVec3::ZERO,
            DVec3::new(10.0, -4.0, 2.0),
            DVec3::new(0.3, 0.2, -4.9),
        ] {
            let brute = (0..points.len())
                .min_by(|&a, &b| points[a].distance(q).total_cmp(&points[b].distance(q)))
                .unwrap();
            let found = grid.nearest(q).unwrap();
            assert_eq!(points[found].distance(q), points[brute].distance(q), "{q}");
        }
        assert!(PointGrid::new(Vec::new()).nearest(DVec3::ZERO).is_none());
    }

    /// Both backends carry a named attribute (here each vertex's own x coordinate, which
    /// a static step must keep within the shape) through a step that remeshes.
    #[test]
    fn attributes_follow_both_backends_and_are_checked() {
        for backend in Backend::ALL {
            let mesh = double_bubble(0.5, 10).unwrap();
            let mut tracker = Tracker::new(backend, mesh, &BackendOptions::default()).unwrap();
            let slots = tracker.mesh().vertex_capacity();
            let xs: Vec<f64> = tracker.mesh().positions().iter().map(|p| p.x).collect();
            tracker.set_attribute("x", 1, &xs).unwrap();
            tracker
                .set_attribute("tag", 2, &vec![7.0; 2 * slots])
                .unwrap();
            assert!(matches!(
                tracker.set_attribute("bad", 3, &[1.0]),
                Err(AttributeError::Length { .. })
            ));
            let proposed: Vec<DVec3> = tracker
                .mesh()
                .positions()
                .iter()
                .map(|p| *p * 1.05)
                .collect();
            tracker.advance(&proposed).unwrap();
            let mesh = tracker.mesh();
            let (dim, x) = tracker.attribute("x").unwrap();
            let (_, tag) = tracker.attribute("tag").unwrap();
            assert_eq!(dim, 1);
            assert_eq!(x.len(), mesh.vertex_capacity());
            for v in mesh.vertices() {
                // Scaled by 1.05: the carried value is the old x, about x/1.05.
                let expect = mesh.position(v).x / 1.05;
                assert!((x[v.idx()] - expect).abs() < 0.2, "{backend}: {v}");
                assert_eq!(&tag[2 * v.idx()..2 * v.idx() + 2], &[7.0, 7.0]);
            }
            assert!(tracker.remove_attribute("x"));
            assert!(tracker.attribute("x").is_none());
            assert_eq!(tracker.attribute("tag").unwrap().1, tag);
            assert_eq!(tracker.attribute_names(), vec![("tag", 2)]);
        }
    }
}
