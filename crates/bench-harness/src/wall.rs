//! How clean an interface wall is (issue 15): the wall between two labels — e.g. the disc
//! two merged spheres share — measured against its best-fit plane.
//!
//! ```text
//! wall_quality(mesh, a, b):
//!     triangles with labels {a, b}                   the wall
//!     centroid and covariance of the triangles,      best-fit plane (normal = the
//!       area-weighted                                 covariance's smallest eigenvector)
//!     rms distance of the wall's vertices to the plane, relative to the wall's radius
//!       (√(projected area / π), the radius of a flat disc of that area)
//!     area fraction of triangles whose normal is > 30° from the plane's
//!
//!
//! open_contact(mesh, a, b):
//!     vertices on a's sheet facing the outside (not on the wall, not on b's sheet) that
//!     lie within OPEN_CONTACT_REACH × mean edge length of b's sheet facing the outside
//! ```
//!
//! A smooth membrane between two pressed-together spheres is a flat disc: RMS ≈ 0, tilted
//! fraction ≈ 0. A merge that completes leaves no open contact but the few vertices next
//! to the triple curve, where the two outer sheets meet at the contact angle; channels and
//! holes of the outside left between the sheets (a ragged rim, a wall with holes) show as
//! many. Fins and spikes show in both numbers, and its area exceeds what the
//! geometry implies (compare [`WallQuality::area`] with the grid backend's wall on the same
//! run). `cargo run --release -p bench-harness --example wall -- FRAME.ply…` prints them.

use collision_tracker::proximity::proximity_vertex_triangle;
use glam::DVec3;
use mesh_core::broadphase::{Aabb, Bvh};
use mesh_core::{Label, LabeledMesh, TriId};
use nalgebra::{Matrix3, SymmetricEigen};

/// Tilt beyond which a wall triangle counts as folded (the issue's 30°).
pub const TILT_DEGREES: f64 = 30.0;

/// Reach of [`open_contact`], in mean edge lengths: one step of the `spheres` scene's flow
/// moves a sheet about this far, so two sheets this close that face each other would have
/// met within the step.
pub const OPEN_CONTACT_REACH: f64 = 0.2;

/// The measurements of one wall (see the module doc).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WallQuality {
    /// Wall triangles.
    pub triangles: usize,
    /// Total area of the wall.
    pub area: f64,
    /// Radius of a flat disc of the wall's area projected onto its plane.
    pub radius: f64,
    /// RMS distance of the wall's vertices to the best-fit plane, divided by `radius`.
    pub rms_over_radius: f64,
    /// Fraction of the wall's area in triangles tilted more than [`TILT_DEGREES`].
    pub tilted_fraction: f64,
}

/// The wall between labels `a` and `b` of `mesh`, or `None` when they share no triangle.
pub fn wall_quality(mesh: &LabeledMesh, a: Label, b: Label) -> Option<WallQuality> {
    let wall: Vec<_> = mesh
        .triangles()
        .filter(|&t| {
            let l = mesh.labels(t);
            (l[0] == a && l[1] == b) || (l[0] == b && l[1] == a)
        })
        .collect();
    let area_vector = |t| {
        let [p, q, r] = mesh.tri_positions(t);
        0.5 * (q - p).cross(r - p)
    };
    let area: f64 = wall.iter().map(|&t| area_vector(t).length()).sum();
    if wall.is_empty() || area <= 0.0 {
        return None;
    }
    // Area-weighted centroid and covariance (each triangle by its centroid, plus its own
    // second moment so a single coarse triangle still has a plane).
    let centroid = wall
        .iter()
        .map(|&t| {
            let [p, q, r] = mesh.tri_positions(t);
            (p + q + r) / 3.0 * area_vector(t).length()
        })
        .sum::<DVec3>()
        / area;
    let mut cov = Matrix3::<f64>::zeros();
    for &t in &wall {
        let w = area_vector(t).length() / 3.0;
        for p in mesh.tri_positions(t) {
            let d = p - centroid;
            let v = nalgebra::Vector3::new(d.x, d.y, d.z);
            cov += v * v.transpose() * w;
        }
    }
    let eig = SymmetricEigen::new(cov);
    let k = eig.eigenvalues.imin();
    let n = eig.eigenvectors.column(k);
    let normal = DVec3::new(n[0], n[1], n[2]).normalize();
    let mut vertices: Vec<_> = wall.iter().flat_map(|&t| mesh.tri(t)).collect();
    vertices.sort_unstable();
    vertices.dedup();
    let rms = (vertices
        .iter()
        .map(|&v| (mesh.position(v) - centroid).dot(normal).powi(2))
        .sum::<f64>()
        / vertices.len() as f64)
        .sqrt();
    let cos_limit = TILT_DEGREES.to_radians().cos();
    let (mut projected, mut tilted) = (0.0, 0.0);
    for &t in &wall {
        let v = area_vector(t);
        let len = v.length();
        projected += v.dot(normal).abs();
        if len > 0.0 && v.dot(normal).abs() / len < cos_limit {
            tilted += len;
        }
    }
    let radius = (projected / std::f64::consts::PI).sqrt();
    Some(WallQuality {
        triangles: wall.len(),
        area,
        radius,
        rms_over_radius: if radius > 0.0 { rms / radius } else { 0.0 },
        tilted_fraction: tilted / area,
    })
}

/// Vertices of `a`'s sheet facing [`Label::OUTSIDE`] that are on neither the `a`|`b` wall
/// nor `b`'s outer sheet and lie closer than [`OPEN_CONTACT_REACH`] mean edge lengths to
/// `b`'s outer sheet: contact between the two bodies that the merge has not (yet) turned
/// into wall (see the module doc).
pub fn open_contact(mesh: &LabeledMesh, a: Label, b: Label) -> usize {
    let outer = |t: TriId, x: Label| {
        let l = mesh.labels(t);
        l.contains(&x) && l.contains(&Label::OUTSIDE)
    };
    let sheet_b: Vec<TriId> = mesh.triangles().filter(|&t| outer(t, b)).collect();
    let boxes: Vec<Aabb> = sheet_b
        .iter()
        .map(|&t| Aabb::from_points(&mesh.tri_positions(t)))
        .collect();
    let ids: Vec<u32> = sheet_b.iter().map(|t| t.raw()).collect();
    let Ok(bvh) = Bvh::build_with_ids(&boxes, &ids) else {
        return 0;
    };
    let reach = OPEN_CONTACT_REACH * mesh_core::remesh::improve::mean_edge_length(mesh);
    let mut excluded = vec![false; mesh.vertex_capacity()];
    let mut candidates = Vec::new();
    for t in mesh.triangles() {
        let l = mesh.labels(t);
        let on_b = l.contains(&b);
        for v in mesh.tri(t) {
            excluded[v.idx()] |= on_b;
            if outer(t, a) {
                candidates.push(v);
            }
        }
    }
    candidates.sort_unstable();
    candidates.dedup();
    candidates
        .into_iter()
        .filter(|&v| !excluded[v.idx()])
        .filter(|&v| {
            let p = mesh.position(v);
            let mut near = false;
            bvh.query(&Aabb::new(p, p), reach, |u| {
                let tri = mesh.tri_positions(TriId::new(u));
                near |= proximity_vertex_triangle(p, tri).distance < reach;
            });
            near
        })
        .count()
}

#[cfg(test)]
mod tests {
    use super::*;
    use mesh_core::generators::double_bubble;

    #[test]
    fn a_double_bubble_wall_is_a_flat_disc() {
        let mesh = double_bubble(0.5, 12).unwrap();
        let labels: Vec<_> = mesh.triangles().map(|t| mesh.labels(t)).collect();
        let inner = labels
            .iter()
            .find(|l| l[0] != Label::OUTSIDE && l[1] != Label::OUTSIDE)
            .expect("a double bubble has an inner wall");
        let q = wall_quality(&mesh, inner[0], inner[1]).unwrap();
        assert!(q.rms_over_radius < 1e-6, "{q:?}");
        assert!(q.tilted_fraction < 1e-9, "{q:?}");
        assert!((q.area - std::f64::consts::PI * q.radius * q.radius).abs() < 1e-9 * q.area);
    }

    /// A finished wall has no open contact; two spheres resting a tenth of an edge apart
    /// without a wall have it at their facing vertices, and none an edge apart.
    #[test]
    fn open_contact_counts_facing_sheets_not_a_finished_wall() {
        let mesh = double_bubble(0.5, 12).unwrap();
        assert_eq!(open_contact(&mesh, Label::new(1), Label::new(2)), 0);
        let apart = |gap_in_edges: f64| {
            let unit = mesh_core::generators::spheres_mesh(
                &[mesh_core::generators::PlacedSphere {
                    centre: DVec3::ZERO,
                    radius: 1.0,
                    label: Label::new(1),
                }],
                3,
            )
            .unwrap();
            let l = mesh_core::remesh::improve::mean_edge_length(&unit);
            let spheres = [(DVec3::ZERO, 1), (DVec3::X * (2.0 + gap_in_edges * l), 2)].map(
                |(centre, label)| mesh_core::generators::PlacedSphere {
                    centre,
                    radius: 1.0,
                    label: Label::new(label),
                },
            );
            let mesh = mesh_core::generators::spheres_mesh(&spheres, 3).unwrap();
            open_contact(&mesh, Label::new(1), Label::new(2))
        };
        assert!(apart(0.1) >= 1, "the touching vertex of each icosphere");
        assert_eq!(apart(1.0), 0);
    }

    #[test]
    fn a_crumpled_wall_reads_as_tilted() {
        // Outer sheets of a double bubble are spherical caps: measured as a "wall" they are
        // far from flat.
        let mesh = double_bubble(0.5, 12).unwrap();
        let t = mesh
            .triangles()
            .find(|&t| mesh.labels(t).contains(&Label::OUTSIDE));
        let l = mesh.labels(t.unwrap());
        let q = wall_quality(&mesh, l[0], l[1]).unwrap();
        assert!(q.rms_over_radius > 0.05 && q.tilted_fraction > 0.2, "{q:?}");
        assert_eq!(wall_quality(&mesh, Label::new(7), Label::new(8)), None);
    }
}
