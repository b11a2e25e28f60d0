//! Issue 14's triangle-quality bars, measured on one mesh: the fraction of triangles with a
//! minimum interior angle under 10° and the spread of edge lengths (the 1st and 99th
//! percentiles of the distinct edges). `min_angle_deg` and the edge extremes of
//! [`mesh_core::geometry::quality`] answer "how bad is the worst triangle"; these answer
//! "how much of the mesh is bad", which is what a simulator feeding the mesh to a solver
//! cares about.

use mesh_core::LabeledMesh;
use mesh_core::geometry::triangle_min_angle;
use rayon::prelude::*;

/// Minimum angle below which a triangle counts as a sliver (the 10°).
pub const SLIVER_DEGREES: f64 = 10.0;

/// See the [module doc](self).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleQuality {
    /// Live triangles measured.
    pub triangles: usize,
    /// Fraction of them with a minimum angle under [`SLIVER_DEGREES`].
    pub below_10_deg: f64,
    /// 1st percentile of the distinct edges' lengths.
    pub edge_p1: f64,
    /// 99th percentile of the distinct edges' lengths.
    pub edge_p99: f64,
}

/// The quality figures of `mesh` (see the [module doc](self)). Deterministic: counts and
/// order statistics only.
pub fn triangle_quality(mesh: &LabeledMesh) -> TriangleQuality {
    let tris: Vec<_> = mesh.triangles().collect();
    let limit = SLIVER_DEGREES.to_radians();
    let slivers = tris
        .par_iter()
        .filter(|&&t| triangle_min_angle(&mesh.tri_positions(t)) < limit)
        .count();
    let mut edges: Vec<(u32, u32)> = tris
        .iter()
        .flat_map(|&t| {
            let v = mesh.tri(t).map(|v| v.raw());
            (0..3).map(move |k| {
                let (a, b) = (v[k], v[(k + 1) % 3]);
                (a.min(b), a.max(b))
            })
        })
        .collect();
    edges.par_sort_unstable();
    edges.dedup();
    let mut lengths: Vec<f64> = edges
        .par_iter()
        .map(|&(a, b)| {
            let p = |v| mesh.position(mesh_core::VertexId::new(v));
            p(a).distance(p(b))
        })
        .collect();
    lengths.par_sort_unstable_by(f64::total_cmp);
    let at = |q: f64| {
        if lengths.is_empty() {
            return f64::NAN;
        }
        lengths[((lengths.len() - 1) as f64 * q).round() as usize]
    };
    TriangleQuality {
        triangles: tris.len(),
        below_10_deg: if tris.is_empty() {
            0.0
        } else {
            slivers as f64 / tris.len() as f64
        },
        edge_p1: at(0.01),
        edge_p99: at(0.99),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;
    use mesh_core::Label;
    use mesh_core::generators::icosphere;

    /// A regular icosphere has no slivers and nearly equal edges; squashing it flat makes
    /// every triangle a sliver and spreads the edge lengths.
    #[test]
    fn slivers_and_spread_are_counted() {
        let mut mesh = icosphere(2, DVec3::ZERO, 1.0, [Label::OUTSIDE, Label::new(1)]).unwrap();
        let q = triangle_quality(&mesh);
        assert_eq!(q.triangles, 320);
        assert_eq!(q.below_10_deg, 0.0);
        assert!(q.edge_p99 / q.edge_p1 < 1.5, "{q:?}");
        let vertices: Vec<_> = mesh.vertices().collect();
        for v in vertices {
            let p = mesh.position(v);
            mesh.set_position(v, DVec3::new(p.x, p.y, 0.01 * p.z));
        }
        let q = triangle_quality(&mesh);
        assert!(q.below_10_deg > 0.1, "{q:?}");
        assert!(q.edge_p99 / q.edge_p1 > 3.0, "{q:?}");
    }
}
