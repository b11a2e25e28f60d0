//! The enclosed volume of the union of a (possibly self-overlapping) mesh's materials,
//! measured independently of the grid pipeline: the reference [`crate::fix_with`] checks
//! its output against.
//!
//! Why not the input's own per-label volumes: on an overlapping input the divergence
//! theorem integrates each material's winding number, so an overlap of two materials is
//! counted twice and their sum exceeds the union. Why not the output's: that is what is
//! being checked.
//!
//! Method: a lattice of lines along one axis (the bounding box's shortest, so that flat
//! parts are crossed, not grazed), spaced `h` apart at cell centres. Along each line the
//! crossings with the mesh are exact ([`cross_axis_line_triangle`], with the
//! Simulation-of-Simplicity perturbation of the material stage, so a line through an edge
//! or a vertex counts once); walking them in order keeps the winding count of the
//! outside material 0, which is 1 outside every material and less inside at least one
//! (inside two overlapping materials it is −1). The union's length along the line is the
//! total length where it is below 1 — exact up to rounding. The volume is `h²` times the
//! sum of lengths: midpoint quadrature over the lattice, whose error comes only from the
//! silhouette, at most about `h / 2` times the silhouette's length relative to the
//! projected area (0.4 % for a unit square at the default 2¹⁷ lines).

use glam::{DVec2, DVec3};
use mesh_core::predicates::{Axis, cross_axis_line_triangle};
use mesh_core::{Label, LabeledMesh};
use rayon::prelude::*;

/// Lines cast by [`union_volume`] (about; the lattice follows the box's aspect ratio).
pub const UNION_LINES: usize = 1 << 17;

/// Lines per bin along the second lattice axis: small enough that a line tests few
/// triangles it cannot meet, large enough that a triangle lands in few bins.
const BLOCK: usize = 8;

/// What [`union_volume`] measured.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct UnionVolume {
    /// The enclosed volume of the union of all materials other than 0.
    pub volume: f64,
    /// Line spacing `h`.
    pub spacing: f64,
    /// Lines cast.
    pub lines: usize,
}

/// Measures the union volume of `mesh`'s materials (see the module doc). `None` for an
/// empty mesh or one without extent in two axes.
pub fn union_volume(mesh: &LabeledMesh) -> Option<UnionVolume> {
    let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    for v in mesh.vertices() {
        let p = mesh.position(v);
        lo = lo.min(p);
        hi = hi.max(p);
    }
    let ext = hi - lo;
    if !ext.is_finite() {
        return None;
    }
    let a = if ext.x <= ext.y && ext.x <= ext.z {
        0
    } else if ext.y <= ext.z {
        1
    } else {
        2
    };
    let axis = Axis::from_index(a);
    let (b, c) = axis.others();
    let (eb, ec) = (ext[b], ext[c]);
    if !(eb > 0.0 && ec > 0.0) {
        return None;
    }
    let h = (eb * ec / UNION_LINES as f64).sqrt();
    let (nb, nc) = ((eb / h).ceil() as usize, (ec / h).ceil() as usize);
    let line_at =
        |i: usize, j: usize| DVec2::new(lo[b] + (i as f64 + 0.5) * h, lo[c] + (j as f64 + 0.5) * h);
    // Triangles binned by the blocks of lines (one row along `b`, BLOCK lines along `c`)
    // their projection may meet, one line of slack each way.
    let nblk = nc.div_ceil(BLOCK);
    let mut bins: Vec<Vec<u32>> = vec![Vec::new(); nb * nblk];
    let index = |x: f64, o: f64, n: usize| ((x - o) / h - 0.5).clamp(0.0, (n - 1) as f64);
    let labels = mesh.label_pairs();
    for t in mesh.triangles() {
        let p = mesh.tri_positions(t);
        let (mn, mx) = (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]));
        let (i0, i1) = (
            index(mn[b], lo[b], nb).floor() as usize,
            index(mx[b], lo[b], nb).ceil() as usize,
        );
        let (k0, k1) = (
            index(mn[c], lo[c], nc).floor() as usize / BLOCK,
            index(mx[c], lo[c], nc).ceil() as usize / BLOCK,
        );
        for i in i0..=i1 {
            for bin in &mut bins[i * nblk + k0..=i * nblk + k1] {
                bin.push(t.raw());
            }
        }
    }
    let outside = Label::OUTSIDE;
    // Per row, then summed in row order: a parallel float sum would round differently for
    // each way rayon splits the rows, so the reference would depend on the thread count.
    let rows: Vec<f64> = (0..nb)
        .into_par_iter()
        .map_init(Vec::<(f64, i32)>::new, |hits, i| {
            let mut row_len = 0.0;
            for j in 0..nc {
                let q = line_at(i, j);
                hits.clear();
                for &t in &bins[i * nblk + j / BLOCK] {
                    let t = mesh_core::TriId::new(t);
                    let Some(x) = cross_axis_line_triangle(axis, q, mesh.tri_positions(t)) else {
                        continue;
                    };
                    let [front, back] = labels[t.idx()];
                    // +1: leaves `back`, enters `front` (towards +axis).
                    let (from, to) = if x.direction > 0 {
                        (back, front)
                    } else {
                        (front, back)
                    };
                    let d = i32::from(to == outside) - i32::from(from == outside);
                    if d != 0 {
                        hits.push((x.coordinate, d));
                    }
                }
                hits.sort_unstable_by(|u, v| u.0.total_cmp(&v.0));
                let mut w = 1;
                let mut start = 0.0;
                for &(x, d) in hits.iter() {
                    let was_in = w < 1;
                    w += d;
                    match (was_in, w < 1) {
                        (false, true) => start = x,
                        (true, false) => row_len += x - start,
                        _ => {}
                    }
                }
            }
            row_len
        })
        .collect();
    let total: f64 = rows.iter().sum();
    Some(UnionVolume {
        volume: total * h * h,
        spacing: h,
        lines: nb * nc,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_util::{cube, sphere, union};

    #[test]
    fn a_box_and_two_overlapping_boxes() {
        let a = cube(DVec3::ZERO, DVec3::new(1.0, 0.7, 0.4), 0, 1);
        let v = union_volume(&a).expect("volume").volume;
        assert!((v - 0.28).abs() < 0.28 * 0.005, "{v}");
        let b = cube(DVec3::new(0.5, 0.2, 0.1), DVec3::new(1.5, 0.9, 0.6), 0, 2);
        // |A ∪ B| = 0.28 + 0.35 − 0.5·0.5·0.3
        let exact = 0.28 + 0.35 - 0.075;
        let v = union_volume(&union(&[a, b])).expect("volume").volume;
        assert!((v - exact).abs() < exact * 0.005, "{v} vs {exact}");
    }

    #[test]
    fn a_sphere_inside_a_sphere_counts_once() {
        let big = sphere(4, DVec3::ZERO, 1.0, 0, 1);
        let inner = sphere(2, DVec3::new(0.2, 0.0, 0.0), 0.3, 0, 2);
        let exact = mesh_core::geometry::label_volumes(&big)[&Label::new(1)];
        let v = union_volume(&union(&[big, inner])).expect("volume").volume;
        assert!((v - exact).abs() < exact * 0.005, "{v} vs {exact}");
    }
}
