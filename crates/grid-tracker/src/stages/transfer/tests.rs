//! Tests of §8.4: linear and constant fields through the grid.

use glam::{DVec3, IVec3};
use mesh_core::LabeledMesh;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::*;
use crate::stages::flaws::{FlawOptions, detect_flaws};
use crate::stages::grid::{GridOptions, build_grid};
use crate::stages::materials::{MaterialOptions, assign_materials};
use crate::test_util::sphere;

/// A flawed region that is exactly the `n³` block of cells from `lo` (relative to the
/// cell holding the origin), inside a large sphere (no mesh nearby, so growth adds
/// nothing), its grid, and `lo` in lattice coordinates.
fn block_region(lo: IVec3, n: i32) -> (Grid, FlawedRegion, IVec3) {
    let mesh = sphere(2, DVec3::ZERO, 4.0, 0, 1);
    let grid = build_grid(
        &mesh,
        0.25,
        &GridOptions {
            perturbation: 0.0,
            ..GridOptions::default()
        },
    )
    .unwrap();
    let mats = assign_materials(&mesh, &grid, &MaterialOptions::default()).unwrap();
    let mut region = detect_flaws(&mesh, &grid, &mats, &FlawOptions::default()).unwrap();
    assert!(region.is_empty());
    let l = grid.lattice();
    let lo = lo + IVec3::new(l.locate(0, 0.0), l.locate(1, 0.0), l.locate(2, 0.0));
    let mut block = Vec::new();
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                block.push(lo + IVec3::new(x, y, z));
            }
        }
    }
    region.grow(&mesh, &grid, &mats, &block);
    assert_eq!(region.len(), block.len(), "growth added cells");
    (grid, region, lo)
}

/// A mesh of isolated vertices at `points` (the transfer reads positions only).
fn points_mesh(points: &[DVec3]) -> LabeledMesh {
    let mut m = LabeledMesh::new();
    for &p in points {
        m.add_vertex(p).unwrap();
    }
    m
}

fn field(p: DVec3) -> [f64; 2] {
    [1.5 * p.x - 0.25 * p.y + 2.0 * p.z + 0.75, -3.0]
}

#[test]
fn linear_fields_are_reproduced_where_every_corner_saw_symmetric_data() {
    let (grid, region, lo) = block_region(IVec3::new(-2, -2, -2), 4);
    let lattice = *grid.lattice();
    // One old vertex at every cell centre: interior nodes average eight centres
    // symmetric about them, i.e. the field at the node.
    let old_points: Vec<DVec3> = region.cells().map(|c| lattice.cell_centre(c)).collect();
    let old_mesh = points_mesh(&old_points);
    let mut old_attrs = VertexAttributes::zeros(&old_mesh, 2);
    let old_ids: Vec<VertexId> = old_mesh.vertices().collect();
    for &v in &old_ids {
        old_attrs
            .get_mut(v)
            .copy_from_slice(&field(old_mesh.position(v)));
    }
    // New vertices at random points of the inner 2³ cells (all corners interior), and
    // some in the outer cells.
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    let inner_lo = lattice.node_position(lo + IVec3::ONE);
    let outer_lo = lattice.node_position(lo);
    let mut new_points: Vec<DVec3> = (0..200)
        .map(|_| inner_lo + 0.5 * DVec3::new(rng.random(), rng.random(), rng.random()))
        .collect();
    new_points.extend(
        (0..100).map(|_| outer_lo + 1.0 * DVec3::new(rng.random(), rng.random(), rng.random())),
    );
    let new_mesh = points_mesh(&new_points);
    let new_ids: Vec<VertexId> = new_mesh.vertices().collect();
    let mut attrs = VertexAttributes::zeros(&new_mesh, 2);
    let old = OldVertices {
        positions: old_mesh.positions(),
        attrs: &old_attrs,
        vertices: &old_ids,
    };
    let stats = transfer_pic(&old, &grid, &region, &new_mesh, &new_ids, &mut attrs).unwrap();
    assert_eq!(stats.nodes, 125);
    assert_eq!(stats.seeded_nodes, 125, "every node received data");
    assert_eq!((stats.flooded_nodes, stats.fallback_nodes), (0, 0));
    assert_eq!(stats.interpolated, 300);
    let range = old_ids
        .iter()
        .map(|&v| old_attrs.get(v)[0])
        .fold((f64::MAX, f64::MIN), |(a, b), x| (a.min(x), b.max(x)));
    for (k, &v) in new_ids.iter().enumerate() {
        let got = attrs.get(v);
        let want = field(new_mesh.position(v));
        assert!(
            (got[1] - want[1]).abs() < 1e-12,
            "constant component at {k}"
        );
        if k < 200 {
            assert!(
                (got[0] - want[0]).abs() < 1e-12,
                "vertex {k}: {} vs {}",
                got[0],
                want[0]
            );
        } else {
            // Near the block's border nodes average one-sidedly: bounded, not exact.
            assert!(got[0] >= range.0 - 1e-12 && got[0] <= range.1 + 1e-12);
        }
    }
}

#[test]
fn the_flood_fills_empty_cells_and_constants_stay_constant() {
    let (grid, region, lo) = block_region(IVec3::new(-3, -2, -2), 5);
    let lattice = *grid.lattice();
    // Old vertices only in the first layer of cells along x.
    let old_points: Vec<DVec3> = region
        .cells()
        .filter(|c| c.x == lo.x)
        .map(|c| lattice.cell_centre(c) + DVec3::new(0.01, -0.02, 0.03))
        .collect();
    let old_mesh = points_mesh(&old_points);
    let old_ids: Vec<VertexId> = old_mesh.vertices().collect();
    let mut old_attrs = VertexAttributes::zeros(&old_mesh, 3);
    for &v in &old_ids {
        old_attrs.get_mut(v).copy_from_slice(&[2.5, -1.0, 0.125]);
    }
    let new_points: Vec<DVec3> = region
        .cells()
        .map(|c| lattice.cell_centre(c) + DVec3::splat(0.07))
        .collect();
    let new_mesh = points_mesh(&new_points);
    let new_ids: Vec<VertexId> = new_mesh.vertices().collect();
    let mut attrs = VertexAttributes::zeros(&new_mesh, 3);
    let old = OldVertices {
        positions: old_mesh.positions(),
        attrs: &old_attrs,
        vertices: &old_ids,
    };
    let stats = transfer_pic(&old, &grid, &region, &new_mesh, &new_ids, &mut attrs).unwrap();
    // Two node layers seeded, four flooded, one per round.
    assert_eq!(stats.seeded_nodes, 2 * 36);
    assert_eq!(stats.flooded_nodes, 4 * 36);
    assert_eq!(
        stats.rounds, 5,
        "four filling rounds and one that finds nothing"
    );
    assert_eq!(stats.fallback_nodes, 0);
    for &v in &new_ids {
        for (g, w) in attrs.get(v).iter().zip([2.5, -1.0, 0.125]) {
            assert!((g - w).abs() < 1e-12);
        }
    }
}

#[test]
fn bad_inputs_are_errors() {
    let (grid, region, lo) = block_region(IVec3::ZERO, 2);
    let old_mesh = points_mesh(&[grid.lattice().cell_centre(lo)]);
    let old_ids: Vec<VertexId> = old_mesh.vertices().collect();
    let old_attrs = VertexAttributes::zeros(&old_mesh, 1);
    let old = OldVertices {
        positions: old_mesh.positions(),
        attrs: &old_attrs,
        vertices: &old_ids,
    };
    let far = points_mesh(&[DVec3::splat(-1.0)]);
    let ids: Vec<VertexId> = far.vertices().collect();
    let mut attrs = VertexAttributes::zeros(&far, 1);
    assert!(matches!(
        transfer_pic(&old, &grid, &region, &far, &ids, &mut attrs),
        Err(TransferError::OutsideRegion { .. })
    ));
    let mut wrong = VertexAttributes::zeros(&far, 2);
    assert_eq!(
        transfer_pic(&old, &grid, &region, &far, &ids, &mut wrong),
        Err(TransferError::DimensionMismatch { old: 1, new: 2 })
    );
    let none = OldVertices {
        vertices: &[],
        ..old
    };
    assert_eq!(
        transfer_pic(&none, &grid, &region, &far, &ids, &mut attrs),
        Err(TransferError::NoSource)
    );
    let stray = [VertexId::new(7)];
    let bad = OldVertices {
        vertices: &stray,
        ..old
    };
    assert!(matches!(
        transfer_pic(&bad, &grid, &region, &far, &ids, &mut attrs),
        Err(TransferError::NoOldPosition { .. })
    ));
}
