//! Issue 16, item 4: sharp features. Flat faces and crease edges of the input that lie
//! outside the flawed cells come out of `fix` exactly as they went in; inside, the
//! rebuild (multi-material marching cubes, §8) can only chamfer them, by up to about ℓ
//! (see the `fix` module doc), so what is checked there is that the rebuilt surface stays
//! within a cell of the input's faces.

mod common;

use std::collections::{HashMap, HashSet};

use common::union;

use glam::DVec3;
use grid_tracker::{FixOptions, fix_with};
use mesh_core::LabeledMesh;

/// The box `[lo, hi]` with every face an `n × n` grid of quads (two triangles each),
/// outward normals, labels `[0, label]`: a CAD-like solid with flat faces and 12 crease
/// lines.
fn grid_box(lo: DVec3, hi: DVec3, n: i32, label: u32) -> LabeledMesh {
    let mut index: HashMap<[i32; 3], u32> = HashMap::new();
    let mut pos = Vec::new();
    let mut tris = Vec::new();
    let mut vid = |g: [i32; 3], pos: &mut Vec<DVec3>| {
        *index.entry(g).or_insert_with(|| {
            let f = |i: usize| lo[i] + (hi[i] - lo[i]) * f64::from(g[i]) / f64::from(n);
            pos.push(DVec3::new(f(0), f(1), f(2)));
            (pos.len() - 1) as u32
        })
    };
    for axis in 0..3 {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        for side in [0, n] {
            for i in 0..n {
                for j in 0..n {
                    let g = |di: i32, dj: i32| {
                        let mut c = [0; 3];
                        c[axis] = side;
                        c[u] = i + di;
                        c[v] = j + dj;
                        c
                    };
                    let q = [g(0, 0), g(1, 0), g(1, 1), g(0, 1)].map(|c| vid(c, &mut pos));
                    // (u, v, axis) is right-handed: counter-clockwise in (u, v) faces +axis.
                    let (a, b) = if side == n {
                        ([0, 1, 2], [0, 2, 3])
                    } else {
                        ([0, 2, 1], [0, 3, 2])
                    };
                    tris.push(a.map(|k| q[k]));
                    tris.push(b.map(|k| q[k]));
                }
            }
        }
    }
    let labels = vec![[0, label]; tris.len()];
    LabeledMesh::from_raw(pos, &tris, &labels).expect("grid box")
}

/// A triangle as exact corner positions (bit patterns, rotated to a canonical start) and
/// labels, to find it in another mesh.
fn key(m: &LabeledMesh, t: mesh_core::TriId) -> ([[u64; 3]; 3], [u32; 2]) {
    let p = m.tri_positions(t).map(|q| q.to_array().map(f64::to_bits));
    let k = (0..3).min_by_key(|&k| p[k]).unwrap();
    let l = m.labels(t).map(|l| l.raw());
    ([p[k], p[(k + 1) % 3], p[(k + 2) % 3]], l)
}

#[test]
fn flat_faces_and_creases_outside_flawed_cells_are_kept_exactly() {
    let a = grid_box(DVec3::ZERO, DVec3::ONE, 10, 1);
    let b = grid_box(DVec3::splat(0.7), DVec3::splat(1.3), 6, 2);
    assert!(
        mesh_core::validate::validate(&a, &Default::default()).is_valid(),
        "the box generator"
    );
    let m = union(&[a, b]);
    let out = fix_with(&m, &FixOptions::default()).expect("fix");
    let r = &out.report;
    assert!(r.validation.is_valid(), "{}", r.validation);
    assert!(r.vanished.is_empty());
    let ell = r.cell_size;
    let lattice = out.lattice.expect("a pass ran");
    let flawed: HashSet<[i32; 3]> = out.flawed_cells.iter().map(|c| c.to_array()).collect();
    let meets_flawed = |t| {
        let p = m.tri_positions(t);
        let [lo, hi] = lattice.cell_range(p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]));
        (lo.x..=hi.x)
            .any(|x| (lo.y..=hi.y).any(|y| (lo.z..=hi.z).any(|z| flawed.contains(&[x, y, z]))))
    };
    let output: HashSet<_> = out.mesh.triangles().map(|t| key(&out.mesh, t)).collect();
    let changed: HashSet<_> = out.changed_input.iter().copied().collect();
    // Every input triangle clear of the flawed cells is in the output, bit for bit.
    let mut kept_clear = 0;
    for t in m.triangles() {
        if !meets_flawed(t) {
            assert!(
                !changed.contains(&t),
                "triangle {t} clear of the region was changed"
            );
            assert!(
                output.contains(&key(&m, t)),
                "triangle {t} clear of the region is gone"
            );
            kept_clear += 1;
        }
    }
    assert!(
        kept_clear > m.num_triangles() / 2,
        "{kept_clear} of {}",
        m.num_triangles()
    );
    // The three faces of A away from B (x = 0, y = 0, z = 0) and the crease lines where
    // they meet are untouched: every triangle of theirs is in the output.
    for t in m.triangles() {
        let p = m.tri_positions(t);
        let on_far_face = (0..3).any(|i| p.iter().all(|q| q[i] == 0.0));
        if on_far_face {
            assert!(
                output.contains(&key(&m, t)),
                "far face triangle {t} changed"
            );
        }
    }
    // Inside the rebuilt cells the faces are approximated within about a cell: every
    // output vertex lies within √3·ℓ of one of the two boxes' surfaces.
    let dist_box = |p: DVec3, lo: DVec3, hi: DVec3| {
        let d = (lo - p).max(p - hi);
        if d.max_element() > 0.0 {
            d.max(DVec3::ZERO).length()
        } else {
            -d.max_element()
        }
    };
    for v in out.mesh.vertices() {
        let p = out.mesh.position(v);
        let d = dist_box(p, DVec3::ZERO, DVec3::ONE).min(dist_box(
            p,
            DVec3::splat(0.7),
            DVec3::splat(1.3),
        ));
        // Interior walls between the labels run through the overlap [0.7, 1]³.
        let in_overlap =
            p.cmpge(DVec3::splat(0.7 - ell)).all() && p.cmple(DVec3::splat(1.0 + ell)).all();
        assert!(
            in_overlap || d < 3f64.sqrt() * ell,
            "vertex {v} at {p} is {d} from the boxes (ℓ = {ell})"
        );
    }
}
