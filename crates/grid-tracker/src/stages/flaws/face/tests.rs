use glam::{DVec3, IVec3};
use mesh_core::predicates::{Axis, cross_axis_segment_triangle};
use proptest::prelude::*;

use super::*;
use crate::stages::grid::{GridOptions, build_grid};
use crate::stages::materials::{MaterialOptions, assign_materials};
use crate::test_util::{sphere, union};

/// End points of triangle `tri` in face `face` of the unit lattice at the origin:
/// face-edge crossings plus piercing triangle edges.
fn end_points(face: GridFace, tri: [DVec3; 3]) -> usize {
    let lattice = Lattice {
        origin: DVec3::ZERO,
        cell_size: 1.0,
    };
    let boundary = face
        .edges()
        .iter()
        .filter(|e| {
            let from = lattice.node_position(e.node);
            let to = lattice.plane(e.axis.index(), e.node[e.axis.index()] + 1);
            cross_axis_segment_triangle(e.axis, from, to, tri).is_some()
        })
        .count();
    let pierced = (0..3)
        .filter(|&k| segment_pierces_face(&lattice, face, tri[k], tri[(k + 1) % 3]))
        .count();
    boundary + pierced
}

fn point() -> impl Strategy<Value = DVec3> {
    // Half-integers in [-1, 2]: vertices on nodes, edges and planes of the face often.
    (-2i32..=4, -2i32..=4, -2i32..=4)
        .prop_map(|(x, y, z)| DVec3::new(f64::from(x), f64::from(y), f64::from(z)) * 0.5)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(3000))]

    /// Fig. 8 by construction: under the one perturbation shared with the grid-line
    /// crossings, every triangle meets a face in exactly zero or two points, even when
    /// its vertices sit on the face's nodes, edges and plane.
    #[test]
    fn a_triangle_meets_a_face_in_zero_or_two_points(
        a in point(), b in point(), c in point(), axis in 0usize..3,
    ) {
        let face = GridFace { node: IVec3::ZERO, normal: Axis::from_index(axis) };
        let n = end_points(face, [a, b, c]);
        prop_assert!(n == 0 || n == 2, "{n} end points");
    }
}

#[test]
fn a_small_sphere_across_a_face_is_a_cycle() {
    // Sphere centred on the face x = 1 of cell (0, 0, 0), well inside it.
    let s = sphere(2, DVec3::new(1.0, 0.5, 0.5), 0.2, 0, 1);
    let opts = GridOptions {
        perturbation: 0.0,
        ..GridOptions::default()
    };
    let grid = build_grid(&s, 1.0, &opts).unwrap();
    let mats = assign_materials(&s, &grid, &MaterialOptions::default()).unwrap();
    let o = grid.lattice().origin;
    let node = IVec3::new(
        grid.lattice().locate(0, 1.0),
        grid.lattice().locate(1, 0.5),
        grid.lattice().locate(2, 0.5),
    );
    assert_eq!(grid.lattice().plane(0, node.x), 1.0, "origin {o}");
    let mut scratch = FaceScratch::new();
    let face = GridFace {
        node,
        normal: Axis::X,
    };
    let r = intersect_face(&s, &grid, &mats, face, &mut scratch);
    assert!(r.touched && r.cycle && !r.inconsistent, "{r:?}");
    assert!(scratch.segments().len() >= 8);
    assert!(
        scratch
            .segments()
            .iter()
            .all(|s| s.ends.iter().all(|p| matches!(p, FacePoint::MeshEdge(..))))
    );
    // A face the sphere does not reach.
    let far = GridFace {
        node: node + IVec3::new(0, 1, 0),
        normal: Axis::X,
    };
    assert_eq!(
        intersect_face(&s, &grid, &mats, far, &mut scratch),
        FaceReport::default()
    );
}

#[test]
fn faces_of_closed_meshes_are_never_inconsistent() {
    let mesh = union(&[
        sphere(2, DVec3::ZERO, 1.0, 0, 1),
        sphere(2, DVec3::new(0.7, 0.2, 0.1), 0.6, 0, 2),
    ]);
    for (seed, ell) in [(1, 0.17), (2, 0.3)] {
        let grid = build_grid(
            &mesh,
            ell,
            &GridOptions {
                seed,
                ..GridOptions::default()
            },
        )
        .unwrap();
        let mats = assign_materials(&mesh, &grid, &MaterialOptions::default()).unwrap();
        let mut scratch = FaceScratch::new();
        let mut touched = 0;
        for c in grid.cells() {
            for axis in Axis::ALL {
                let face = GridFace {
                    node: grid.cell_coord(c),
                    normal: axis,
                };
                let r = intersect_face(&mesh, &grid, &mats, face, &mut scratch);
                assert!(!r.inconsistent, "face {face:?}");
                touched += usize::from(r.touched);
                // Every segment's triangle touches the face's cells.
                for s in scratch.segments() {
                    assert!(
                        grid.cell_triangles(grid.cell_id(face.node).unwrap())
                            .contains(&s.tri)
                    );
                }
            }
        }
        assert!(touched > 100);
    }
}
