//! The first three stages (grid, materials, flaws) through the public API, on scenes
//! whose answers are known independently.

mod common;

use common::{cube, inverted, mean_edge, sphere, stages, union, vector};
use glam::{DVec3, IVec3};
use grid_tracker::{FaceScratch, GridOptions, intersect_face};
use mesh_core::LabeledMesh;
use proptest::prelude::*;

/// Distance-based classification against an icosphere of radius `r` about `c`: inside
/// the inscribed ball, outside the circumscribed one, `None` in the thin shell between.
fn ball_side(p: DVec3, c: DVec3, r: f64, r_in: f64) -> Option<bool> {
    let d = (p - c).length();
    if d < r_in * (1.0 - 1e-9) {
        Some(true)
    } else if d > r * (1.0 + 1e-9) {
        Some(false)
    } else {
        None
    }
}

/// Smallest distance from `c` to a face plane of `m`: the inscribed radius.
fn inscribed(m: &LabeledMesh, c: DVec3) -> f64 {
    m.triangles()
        .map(|t| {
            let [a, b, d] = m.tri_positions(t);
            ((b - a).cross(d - a).normalize()).dot(a - c).abs()
        })
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn clean_icosphere_is_physical_everywhere_with_no_flawed_cell() {
    let c = DVec3::new(0.3, -0.2, 0.1);
    let s = sphere(4, c, 1.0, 0, 1);
    let r_in = inscribed(&s, c);
    let ell = mean_edge(&s);
    let st = stages(&s, ell, &GridOptions::default());
    assert!(st.materials.flawed_nodes().is_empty());
    let (mut ins, mut outs) = (0, 0);
    for n in st.grid.nodes() {
        let p = st.grid.lattice().node_position(st.grid.node_coord(n));
        let v = vector(&st, n);
        match ball_side(p, c, 1.0, r_in) {
            Some(true) => {
                ins += 1;
                assert_eq!(v, [(1, 1)]);
            }
            Some(false) => {
                outs += 1;
                assert_eq!(v, [(0, 1)]);
            }
            None => assert!(v == [(0, 1)] || v == [(1, 1)]),
        }
    }
    assert!(ins > 1000 && outs > 1000, "{ins} {outs}");
    assert!(st.flaws.is_empty(), "{:?}", st.flaws.stats());
}

#[test]
fn overlapping_spheres_are_non_physical_exactly_in_the_overlap_and_flawed_there() {
    let (ca, cb) = (DVec3::new(-0.45, 0.0, 0.0), DVec3::new(0.5, 0.03, -0.02));
    let (a, b) = (sphere(4, ca, 1.0, 0, 1), sphere(4, cb, 0.8, 0, 2));
    let (ra, rb) = (inscribed(&a, ca), inscribed(&b, cb));
    let mesh = union(&[a, b]);
    let st = stages(
        &mesh,
        0.06,
        &GridOptions {
            seed: 11,
            ..GridOptions::default()
        },
    );
    let mut overlap = 0;
    for n in st.grid.nodes() {
        let p = st.grid.lattice().node_position(st.grid.node_coord(n));
        let (Some(ia), Some(ib)) = (ball_side(p, ca, 1.0, ra), ball_side(p, cb, 0.8, rb)) else {
            continue;
        };
        let want: &[(u32, i32)] = match (ia, ib) {
            (true, true) => &[(0, -1), (1, 1), (2, 1)],
            (true, false) => &[(1, 1)],
            (false, true) => &[(2, 1)],
            (false, false) => &[(0, 1)],
        };
        assert_eq!(vector(&st, n), want);
        if ia && ib {
            overlap += 1;
            for d in 0..8 {
                let cell = st.grid.node_coord(n) - IVec3::new(d & 1, (d >> 1) & 1, d >> 2);
                assert!(st.flaws.is_flawed(cell));
            }
        }
    }
    assert!(overlap > 200);
    // The lens interior is unallocated and flawed as well.
    let mid = (ca + cb) * 0.5;
    let lat = st.grid.lattice();
    let cell = IVec3::new(
        lat.locate(0, mid.x),
        lat.locate(1, mid.y),
        lat.locate(2, mid.z),
    );
    assert!(st.grid.cell_id(cell).is_none() && st.flaws.is_flawed(cell));
    // §6.4: the boundary is free of complex edges and faces.
    let mut scratch = FaceScratch::new();
    for bf in st.flaws.boundary_faces() {
        for e in bf.face.edges() {
            let k = st
                .grid
                .node_id(e.node)
                .map_or(0, |id| st.materials.edge_crossing_count(id, e.axis));
            assert!(k <= 1);
        }
        let r = intersect_face(&mesh, &st.grid, &st.materials, bf.face, &mut scratch);
        assert!(!r.cycle && !r.inconsistent);
    }
}

#[test]
fn inside_out_sphere_has_negative_entries() {
    let c = DVec3::new(0.1, 0.1, 0.1);
    let s = sphere(3, c, 1.0, 0, 1);
    let r_in = inscribed(&s, c);
    let st = stages(&inverted(&s), 0.15, &GridOptions::default());
    let mut inside = 0;
    for n in st.grid.nodes() {
        let p = st.grid.lattice().node_position(st.grid.node_coord(n));
        if ball_side(p, c, 1.0, r_in) == Some(true) {
            inside += 1;
            assert_eq!(vector(&st, n), [(0, 2), (1, -1)]);
        }
    }
    assert!(inside > 50);
    assert!(st.flaws.stats().non_physical_cells > 0);
}

#[test]
fn box_on_grid_planes_is_consistent_on_all_axes() {
    // Faces on grid planes and corners on grid nodes: every ray through it runs along
    // faces, edges and vertices.
    let m = cube(DVec3::splat(0.5), DVec3::splat(2.0), 0, 1);
    let st = stages(
        &m,
        0.5,
        &GridOptions {
            perturbation: 0.0,
            ..GridOptions::default()
        },
    );
    assert!(st.materials.flawed_nodes().is_empty());
    for n in st.grid.nodes() {
        let v = vector(&st, n);
        assert!(v == [(0, 1)] || v == [(1, 1)], "{v:?}");
    }
    assert!(st.flaws.is_empty(), "{:?}", st.flaws.stats());
}

fn double_bubble() -> LabeledMesh {
    mesh_core::generators::double_bubble(1.0, 24).expect("double bubble")
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(16))]

    /// A clean three-material mesh: for any perturbation and cell size, the three ray
    /// axes agree at every node, every vector is physical, and nothing is flawed except
    /// where the triple curve makes edges deep.
    #[test]
    fn double_bubble_is_consistent_for_any_grid(seed in 0u64..10_000, ell in 0.08f64..0.4, pert in 0.0f64..0.5) {
        let m = double_bubble();
        let st = stages(&m, ell, &GridOptions { seed, perturbation: pert, ..GridOptions::default() });
        prop_assert!(st.materials.flawed_nodes().is_empty());
        for n in st.grid.nodes() {
            prop_assert!(st.materials.node_material(n).is_physical());
        }
        prop_assert_eq!(st.flaws.stats().non_physical_cells, 0);
    }
}
