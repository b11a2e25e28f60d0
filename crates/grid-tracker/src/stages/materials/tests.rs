use glam::{DVec3, IVec3};
use mesh_core::predicates::{Axis, Sign, cross_axis_segment_triangle, orient3d};
use mesh_core::{Label, LabeledMesh};
use proptest::prelude::*;

use super::*;
use crate::stages::grid::{GridOptions, build_grid};
use crate::test_util::{cube, inverted, sphere, union};

fn l(i: u32) -> Label {
    Label::new(i)
}

/// Exact point-in-convex-polyhedron: `Some(true)` strictly inside (behind every face),
/// `Some(false)` strictly outside, `None` on a face plane (left to SoS).
fn inside_convex(m: &LabeledMesh, p: DVec3) -> Option<bool> {
    let mut on = false;
    for t in m.triangles() {
        let [a, b, c] = m.tri_positions(t);
        match orient3d(a, b, c, p) {
            Sign::Positive => return Some(false),
            Sign::Zero => on = true,
            Sign::Negative => {}
        }
    }
    (!on).then_some(true)
}

fn run(mesh: &LabeledMesh, ell: f64, opts: &GridOptions) -> (Grid, Materials) {
    let grid = build_grid(mesh, ell, opts).unwrap();
    let mats = assign_materials(mesh, &grid, &MaterialOptions::default()).unwrap();
    (grid, mats)
}

fn vector(m: &Materials, n: NodeId) -> Vec<(u32, i32)> {
    m.node_vector(n)
        .to_vector()
        .entries()
        .iter()
        .map(|&(l, c)| (l.raw(), c))
        .collect()
}

#[test]
fn clean_sphere_is_physical_and_matches_point_in_sphere() {
    let s = sphere(3, DVec3::new(0.05, -0.1, 0.2), 1.0, 0, 1);
    for (seed, ell) in [(0, 0.13), (5, 0.29)] {
        let (grid, mats) = run(
            &s,
            ell,
            &GridOptions {
                seed,
                ..GridOptions::default()
            },
        );
        assert!(mats.flawed_nodes().is_empty());
        let (mut ins, mut outs) = (0, 0);
        for n in grid.nodes() {
            let p = grid.lattice().node_position(grid.node_coord(n));
            let want = match inside_convex(&s, p) {
                Some(true) => vec![(1, 1)],
                Some(false) => vec![(0, 1)],
                None => continue,
            };
            ins += usize::from(want[0].0 == 1);
            outs += usize::from(want[0].0 == 0);
            assert_eq!(vector(&mats, n), want, "node {}", grid.node_coord(n));
            assert_eq!(mats.physical_label(n), Some(l(want[0].0)));
        }
        assert!(ins > 50 && outs > 50, "{ins} inside, {outs} outside");
        // Unallocated nodes deep inside and far outside.
        let centre = IVec3::new(
            grid.lattice().locate(0, 0.05),
            grid.lattice().locate(1, -0.1),
            grid.lattice().locate(2, 0.2),
        );
        assert_eq!(
            grid.node_id(centre),
            None,
            "the centre should be unallocated"
        );
        assert_eq!(mats.material_at(&grid, centre).label(), Some(l(1)));
        assert_eq!(
            mats.material_at(&grid, centre + IVec3::new(0, 100, 0))
                .label(),
            Some(l(0))
        );
    }
}

#[test]
fn crossings_match_brute_force_segment_tests() {
    let s = union(&[
        sphere(2, DVec3::ZERO, 1.0, 0, 1),
        sphere(1, DVec3::new(0.8, 0.1, 0.0), 0.7, 0, 2),
    ]);
    let (grid, mats) = run(&s, 0.23, &GridOptions::default());
    let mut total = 0;
    for n in grid.nodes() {
        let c = grid.node_coord(n);
        let p = grid.lattice().node_position(c);
        for axis in Axis::ALL {
            let a = axis.index();
            let end = grid.lattice().plane(a, c[a] + 1);
            let mut want: Vec<u32> = s
                .triangles()
                .filter(|&t| {
                    cross_axis_segment_triangle(axis, p, end, s.tri_positions(t)).is_some()
                })
                .map(|t| t.raw())
                .collect();
            want.sort_unstable();
            let mut got: Vec<u32> = mats
                .edge_crossings(n, axis)
                .iter()
                .map(|x| x.tri.raw())
                .collect();
            let coords: Vec<f64> = mats
                .edge_crossings(n, axis)
                .iter()
                .map(|x| x.coordinate)
                .collect();
            assert!(
                coords.windows(2).all(|w| w[0] <= w[1] + 1e-12),
                "crossings sorted along the edge"
            );
            got.sort_unstable();
            assert_eq!(got, want, "edge {c} axis {a}");
            total += got.len();
        }
    }
    assert_eq!(
        total,
        mats.stats().crossings,
        "every crossing lies on an allocated edge"
    );
}

#[test]
fn overlapping_spheres_are_non_physical_exactly_in_the_overlap() {
    let a = sphere(3, DVec3::new(-0.4, 0.0, 0.0), 1.0, 0, 1);
    let b = sphere(3, DVec3::new(0.45, 0.05, 0.0), 0.9, 0, 2);
    let mesh = union(&[a.clone(), b.clone()]);
    let (grid, mats) = run(&mesh, 0.15, &GridOptions::default());
    assert!(mats.flawed_nodes().is_empty());
    let mut overlap = 0;
    for n in grid.nodes() {
        let p = grid.lattice().node_position(grid.node_coord(n));
        let (Some(ia), Some(ib)) = (inside_convex(&a, p), inside_convex(&b, p)) else {
            continue;
        };
        let want = match (ia, ib) {
            (true, true) => vec![(0, -1), (1, 1), (2, 1)],
            (true, false) => vec![(1, 1)],
            (false, true) => vec![(2, 1)],
            (false, false) => vec![(0, 1)],
        };
        overlap += usize::from(ia && ib);
        assert_eq!(vector(&mats, n), want);
    }
    assert!(overlap > 20, "only {overlap} overlap nodes");
    assert_eq!(
        mats.stats().mixed_nodes,
        overlap + count_on_planes_mixed(&grid, &mats, &a, &b)
    );
}

/// Mixed nodes lying exactly on a face plane of either sphere (skipped above).
fn count_on_planes_mixed(grid: &Grid, mats: &Materials, a: &LabeledMesh, b: &LabeledMesh) -> usize {
    grid.nodes()
        .filter(|&n| {
            let p = grid.lattice().node_position(grid.node_coord(n));
            (inside_convex(a, p).is_none() || inside_convex(b, p).is_none())
                && !mats.node_material(n).is_physical()
        })
        .count()
}

#[test]
fn inverted_sphere_gives_negative_entries_inside() {
    let s = sphere(2, DVec3::new(0.1, 0.0, -0.05), 1.0, 0, 1);
    let inv = inverted(&s);
    let (grid, mats) = run(&inv, 0.21, &GridOptions::default());
    assert!(mats.flawed_nodes().is_empty());
    let mut inside = 0;
    for n in grid.nodes() {
        let p = grid.lattice().node_position(grid.node_coord(n));
        match inside_convex(&s, p) {
            Some(true) => {
                inside += 1;
                assert_eq!(vector(&mats, n), vec![(0, 2), (1, -1)]);
            }
            Some(false) => assert_eq!(vector(&mats, n), vec![(0, 1)]),
            None => {}
        }
    }
    assert!(inside > 10);
}

#[test]
fn box_on_grid_nodes_is_consistent_thanks_to_sos() {
    // Faces on grid planes, vertices on grid nodes: every ray hits edges and vertices.
    let b = cube(DVec3::splat(0.25), DVec3::splat(1.0), 0, 1);
    let opts = GridOptions {
        perturbation: 0.0,
        ..GridOptions::default()
    };
    let (grid, mats) = run(&b, 0.25, &opts);
    assert_eq!(grid.lattice().origin, DVec3::splat(0.25));
    assert!(
        mats.flawed_nodes().is_empty(),
        "axes disagree at {:?}",
        mats.flawed_nodes()
    );
    for n in grid.nodes() {
        let p = grid.lattice().node_position(grid.node_coord(n));
        let v = vector(&mats, n);
        assert!(v == [(0, 1)] || v == [(1, 1)], "non-physical {v:?} at {p}");
        let strictly_inside = p.cmpgt(DVec3::splat(0.25)).all() && p.cmplt(DVec3::splat(1.0)).all();
        let strictly_outside =
            p.cmplt(DVec3::splat(0.25)).any() || p.cmpgt(DVec3::splat(1.0)).any();
        if strictly_inside {
            assert_eq!(v, [(1, 1)]);
        }
        if strictly_outside {
            assert_eq!(v, [(0, 1)]);
        }
    }
    // The perturbed node p + (ε, ε², ε³) is inside exactly for p in [0.25, 1)³.
    let on_low_corner = grid.node_id(IVec3::ZERO).unwrap();
    assert_eq!(vector(&mats, on_low_corner), vec![(1, 1)]);
    let on_high_corner = grid.node_id(IVec3::splat(3)).unwrap();
    assert_eq!(vector(&mats, on_high_corner), vec![(0, 1)]);
}

#[test]
fn a_hole_makes_the_axes_disagree() {
    let s = sphere(2, DVec3::ZERO, 1.0, 0, 1);
    let (p, t, lab) = s.to_raw();
    let holed = LabeledMesh::from_raw(p, &t[1..], &lab[1..]).unwrap();
    let (_, mats) = run(&holed, 0.1, &GridOptions::default());
    assert!(
        !mats.flawed_nodes().is_empty(),
        "a missing triangle must show up"
    );
    let (_, unchecked) = {
        let grid = build_grid(&holed, 0.1, &GridOptions::default()).unwrap();
        let m = assign_materials(
            &holed,
            &grid,
            &MaterialOptions {
                check_all_axes: false,
            },
        )
        .unwrap();
        (grid, m)
    };
    assert!(unchecked.flawed_nodes().is_empty());
}

#[test]
fn mismatched_grid_is_refused() {
    let s = sphere(1, DVec3::ZERO, 1.0, 0, 1);
    let grid = build_grid(&s, 0.3, &GridOptions::default()).unwrap();
    let other = sphere(2, DVec3::ZERO, 1.0, 0, 1);
    assert!(matches!(
        assign_materials(&other, &grid, &MaterialOptions::default()),
        Err(MaterialError::GridMismatch { .. })
    ));
}

/// A closed but tangled surface: an icosphere with every vertex pushed by a random amount.
fn tangled_sphere(seed: u64, amount: f64) -> LabeledMesh {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let s = sphere(2, DVec3::ZERO, 1.0, 0, 1);
    let (mut p, t, lab) = s.to_raw();
    for q in &mut p {
        *q += DVec3::new(
            rng.random::<f64>() - 0.5,
            rng.random::<f64>() - 0.5,
            rng.random::<f64>() - 0.5,
        ) * amount;
    }
    LabeledMesh::from_raw(p, &t, &lab).unwrap()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// On a closed mesh — even a self-intersecting one — rays along x, y and z agree at
    /// every node, and vectors always sum to 1.
    #[test]
    fn three_axes_agree_on_closed_meshes(seed in 0u64..1000, ell in 0.07f64..0.5, pert in 0.0f64..0.5, amount in 0.0f64..0.6) {
        let mesh = union(&[tangled_sphere(seed, amount), sphere(1, DVec3::new(0.5, 0.2, 0.1), 0.6, 0, 2)]);
        let opts = GridOptions { perturbation: pert, seed, ..GridOptions::default() };
        let (grid, mats) = run(&mesh, ell, &opts);
        prop_assert!(mats.flawed_nodes().is_empty(), "{} flawed nodes", mats.flawed_nodes().len());
        for n in grid.nodes() {
            let v = mats.node_vector(n).to_vector();
            prop_assert_eq!(v.entries().iter().map(|e| e.1).sum::<i32>(), 1);
        }
    }
}
