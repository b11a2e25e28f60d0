use std::collections::{BTreeMap, BTreeSet};

use glam::{DVec3, IVec3};
use mesh_core::{LabeledMesh, TriId};

use super::*;
use crate::test_util::{sphere, union};

fn key(c: IVec3) -> [i32; 3] {
    c.to_array()
}

/// Brute force: cell → triangles from every triangle's exact box range.
fn expected_cells(mesh: &LabeledMesh, grid: &Grid) -> BTreeMap<[i32; 3], Vec<TriId>> {
    let mut out: BTreeMap<[i32; 3], Vec<TriId>> = BTreeMap::new();
    for t in mesh.triangles() {
        let [a, b, c] = mesh.tri_positions(t);
        let [lo, hi] = grid.lattice().cell_range(a.min(b).min(c), a.max(b).max(c));
        for z in lo.z..=hi.z {
            for y in lo.y..=hi.y {
                for x in lo.x..=hi.x {
                    out.entry([x, y, z]).or_default().push(t);
                }
            }
        }
    }
    out
}

fn scene() -> LabeledMesh {
    union(&[
        sphere(2, DVec3::new(0.1, 0.2, -0.1), 1.0, 0, 1),
        sphere(1, DVec3::new(2.5, -1.0, 0.3), 0.6, 0, 2),
    ])
}

#[test]
fn cells_list_exactly_the_triangles_whose_box_meets_them() {
    let mesh = scene();
    for (seed, ell) in [(1u64, 0.37), (2, 0.21), (3, 0.9)] {
        let opts = GridOptions {
            seed,
            ..GridOptions::default()
        };
        let grid = build_grid(&mesh, ell, &opts).unwrap();
        let expected = expected_cells(&mesh, &grid);
        assert_eq!(grid.num_cells(), expected.len());
        for c in grid.cells() {
            let coord = grid.cell_coord(c);
            assert_eq!(grid.cell_id(coord), Some(c));
            assert_eq!(
                grid.cell_triangles(c),
                expected[&key(coord)].as_slice(),
                "cell {coord}"
            );
        }
        // Nodes are exactly the corners of allocated cells.
        let corners: BTreeSet<[i32; 3]> = expected
            .keys()
            .flat_map(|&[x, y, z]| {
                (0..8).map(move |d| [x + (d & 1), y + ((d >> 1) & 1), z + (d >> 2)])
            })
            .collect();
        assert_eq!(grid.num_nodes(), corners.len());
        for n in grid.nodes() {
            let coord = grid.node_coord(n);
            assert!(corners.contains(&key(coord)));
            assert_eq!(grid.node_id(coord), Some(n));
        }
        // Unallocated lookups.
        assert_eq!(grid.cell_id(IVec3::splat(10_000)), None);
        let stats = grid.stats();
        assert_eq!(
            stats.entries,
            expected.values().map(Vec::len).sum::<usize>()
        );
        assert!(stats.heap_bytes > 0);
    }
}

#[test]
fn nearest_node_below_along_x_matches_a_scan() {
    let mesh = scene();
    let grid = build_grid(&mesh, 0.3, &GridOptions::default()).unwrap();
    let nodes: BTreeSet<[i32; 3]> = grid.nodes().map(|n| key(grid.node_coord(n))).collect();
    let lo = nodes.iter().map(|k| k[0]).min().unwrap();
    for y in -8..8 {
        for z in -8..8 {
            for x in (lo - 20)..(lo + 40) {
                let want = (lo - 1..=x).rev().find(|&xx| nodes.contains(&[xx, y, z]));
                let got = grid
                    .node_at_or_below_x(IVec3::new(x, y, z))
                    .map(|n| grid.node_coord(n).x);
                assert_eq!(got, want, "at ({x}, {y}, {z})");
            }
        }
    }
}

#[test]
fn zero_perturbation_puts_planes_on_multiples_of_the_cell_size() {
    let mesh = sphere(1, DVec3::new(0.3, 0.3, 0.3), 1.0, 0, 1);
    let opts = GridOptions {
        perturbation: 0.0,
        ..GridOptions::default()
    };
    let grid = build_grid(&mesh, 0.25, &opts).unwrap();
    for a in 0..3 {
        let o = grid.lattice().origin[a];
        assert_eq!((o / 0.25).round() * 0.25, o);
    }
    // A different seed moves the origin by at most the perturbation.
    let g1 = build_grid(&mesh, 0.25, &GridOptions::default()).unwrap();
    let g2 = build_grid(
        &mesh,
        0.25,
        &GridOptions {
            seed: 9,
            ..GridOptions::default()
        },
    )
    .unwrap();
    assert_ne!(g1.lattice().origin, g2.lattice().origin);
    assert!(
        (g1.lattice().origin - grid.lattice().origin)
            .abs()
            .max_element()
            <= 0.1 * 0.25
    );
}

#[test]
fn bad_input_is_a_typed_error() {
    let mesh = sphere(1, DVec3::ZERO, 1.0, 0, 1);
    let o = GridOptions::default();
    for ell in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(matches!(
            build_grid(&mesh, ell, &o),
            Err(GridError::BadCellSize(_))
        ));
    }
    let bad = GridOptions {
        perturbation: 0.7,
        ..o.clone()
    };
    assert!(matches!(
        build_grid(&mesh, 0.1, &bad),
        Err(GridError::BadOption { .. })
    ));
    // A tiny ℓ on a unit sphere would need billions of cells.
    assert!(matches!(
        build_grid(&mesh, 1e-5, &o),
        Err(GridError::TooManyCells { .. })
    ));
    let fine = build_grid(&mesh, 1e-12, &o).unwrap_err();
    assert!(matches!(fine, GridError::TooFine { .. }));
    assert!(fine.to_string().contains("cells per axis"), "{fine}");
    // A unit sphere 10¹² from the origin: ℓ = 0.35 is below what f64 resolves there, and
    // the remedy is to move the mesh, which the message says.
    let mut far = mesh.clone();
    for v in mesh.vertices() {
        far.set_position(v, mesh.position(v) + DVec3::new(1e12, 0.0, 0.0));
    }
    let far = build_grid(&far, 0.35, &o).unwrap_err();
    assert!(matches!(far, GridError::TooFine { .. }));
    assert!(
        far.to_string().contains("move the mesh towards the origin"),
        "{far}"
    );
    let mut nan = mesh.clone();
    nan.set_position(mesh_core::VertexId::new(3), DVec3::new(f64::NAN, 0.0, 0.0));
    match build_grid(&nan, 0.1, &o) {
        Err(GridError::NonFinite { vertex, .. }) => assert_eq!(vertex, 3),
        other => panic!("expected NonFinite, got {other:?}"),
    }
}

#[test]
fn empty_mesh_gives_an_empty_grid() {
    let grid = build_grid(&LabeledMesh::new(), 1.0, &GridOptions::default()).unwrap();
    assert_eq!(grid.num_cells(), 0);
    assert_eq!(grid.num_nodes(), 0);
    assert_eq!(grid.node_at_or_below_x(IVec3::ZERO), None);
}
