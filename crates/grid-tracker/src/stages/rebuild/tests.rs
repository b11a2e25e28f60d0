//! Tests of the rebuild building blocks on blocks of cells: closedness, labels, volumes,
//! conformity across faces, boundary fans with vertex sliding, averaged placement.

use std::collections::BTreeMap;

use glam::{DVec3, IVec3};
use mesh_core::geometry::label_volumes;
use mesh_core::validate::{ValidateOptions, ValidationReport, validate};
use mesh_core::{Label, LabeledMesh};
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::*;
use crate::stages::grid::Lattice;
use crate::stages::grid::primitives::{GridFace, cell_faces, unit};

const UNIT: Lattice = Lattice {
    origin: DVec3::ZERO,
    cell_size: 1.0,
};

fn label(l: u32) -> Label {
    Label::new(l)
}

/// Labels on the nodes `0..=n` of an `n³` block of cells.
struct Block {
    n: i32,
    labels: Vec<Label>,
}

impl Block {
    /// Shell nodes get label 0, interior nodes `interior` in x-fastest order.
    fn with_interior(n: i32, interior: &[u32]) -> Block {
        let m = (n + 1) as usize;
        let mut labels = vec![label(0); m * m * m];
        let mut it = interior.iter();
        for z in 1..n {
            for y in 1..n {
                for x in 1..n {
                    labels[x as usize + m * (y as usize + m * z as usize)] =
                        label(*it.next().unwrap_or(&0));
                }
            }
        }
        Block { n, labels }
    }

    /// Any labelling `f(node)`.
    fn from_fn(n: i32, mut f: impl FnMut(IVec3) -> u32) -> Block {
        let m = (n + 1) as usize;
        let labels = (0..m * m * m)
            .map(|i| {
                label(f(IVec3::new(
                    (i % m) as i32,
                    ((i / m) % m) as i32,
                    (i / (m * m)) as i32,
                )))
            })
            .collect();
        Block { n, labels }
    }

    /// The label of node `p`; label 0 (the outside) beyond the block.
    fn node(&self, p: IVec3) -> Label {
        if p.min_element() < 0 || p.max_element() > self.n {
            return label(0);
        }
        let m = (self.n + 1) as usize;
        self.labels[p.x as usize + m * (p.y as usize + m * p.z as usize)]
    }

    fn corners(&self, c: IVec3) -> [Label; 8] {
        cell_corners(c).map(|p| self.node(p))
    }

    fn cells(&self) -> impl Iterator<Item = IVec3> + use<> {
        let n = self.n;
        (0..n * n * n).map(move |i| IVec3::new(i % n, (i / n) % n, i / (n * n)))
    }

    fn contains_cell(&self, c: IVec3) -> bool {
        c.min_element() >= 0 && c.max_element() < self.n
    }

    /// The octant surface of every cell.
    fn triangles(&self) -> Vec<RebuildTriangle> {
        let mut out = Vec::new();
        for c in self.cells() {
            triangulate_octants(c, &self.corners(c), FaceMask::ALL, &mut out);
        }
        out
    }

    /// Volume per label from counting: each node's dual cell, clipped to the block (the
    /// shell's share outside is the outside material, label 0).
    fn counted_volumes(&self) -> BTreeMap<Label, f64> {
        let mut out = BTreeMap::new();
        let mut total = 0.0;
        for (i, &l) in self.labels.iter().enumerate() {
            let m = (self.n + 1) as usize;
            let p = IVec3::new((i % m) as i32, ((i / m) % m) as i32, (i / (m * m)) as i32);
            if p.min_element() > 0 && p.max_element() < self.n && l != label(0) {
                *out.entry(l).or_insert(0.0) += 1.0;
                total += 1.0;
            }
        }
        out.insert(label(0), -total);
        out
    }
}

fn weld(tris: &[RebuildTriangle]) -> Welder {
    let mut w = Welder::new();
    w.add_all(tris).expect("octant triangles never collapse");
    w
}

fn midpoint_mesh(tris: &[RebuildTriangle]) -> LabeledMesh {
    weld(tris)
        .to_mesh(|k| midpoint_position(&UNIT, k))
        .expect("all keys are grid keys")
}

fn assert_valid(report: &ValidationReport, what: &str) {
    assert!(report.is_valid(), "{what}: {report:#?}");
    assert_eq!(
        report.self_intersecting_pairs.as_ref().map(|l| l.count),
        Some(0),
        "{what}"
    );
}

fn assert_volumes(mesh: &LabeledMesh, expected: &BTreeMap<Label, f64>) {
    let got = label_volumes(mesh);
    for l in got.keys().chain(expected.keys()) {
        let (g, e) = (
            got.get(l).copied().unwrap_or(0.0),
            expected.get(l).copied().unwrap_or(0.0),
        );
        assert!((g - e).abs() < 1e-9, "label {l}: volume {g}, counted {e}");
    }
}

/// `t` rotated so that its cell-centre vertex comes last (every octant and fan triangle
/// has exactly one), for comparing triangles up to rotation.
fn centre_last(t: &RebuildTriangle) -> RebuildTriangle {
    let k = t
        .verts
        .iter()
        .position(|v| matches!(v, RebuildVertexKey::Cell(_)))
        .expect("a centre vertex");
    let mut verts = t.verts;
    verts.rotate_left((k + 1) % 3);
    RebuildTriangle { verts, ..*t }
}

fn random_labels(rng: &mut ChaCha8Rng, k: u32) -> [Label; 8] {
    std::array::from_fn(|_| label(rng.random_range(0..k)))
}

#[test]
fn single_label_gives_no_triangles() {
    let mut out = Vec::new();
    for l in [0, 3] {
        let labels = [label(l); 8];
        assert_eq!(
            triangulate_octants(IVec3::new(4, -1, 2), &labels, FaceMask::ALL, &mut out),
            0
        );
        assert!(!has_interface(&labels));
    }
    assert!(out.is_empty());
    assert!(Block::from_fn(3, |_| 5).triangles().is_empty());
}

#[test]
fn a_plane_split_gives_a_flat_sheet() {
    for axis in 0..3 {
        // Nodes with coordinate ≤ 1 along `axis` are 1, the others 2: one sheet at 1.5.
        let block = Block::from_fn(3, |p| if p[axis] <= 1 { 1 } else { 2 });
        let tris = block.triangles();
        // 3×3 crossed cells, four crossing edges each, two triangles per quad.
        assert_eq!(tris.len(), 72);
        let mesh = midpoint_mesh(&tris);
        for t in mesh.triangles() {
            let p = mesh.tri_positions(t);
            assert!(p.iter().all(|q| q[axis] == 1.5), "off the plane: {p:?}");
            let n = (p[1] - p[0]).cross(p[2] - p[0]);
            assert!(n[axis] > 0.0, "normal {n} should point into label 2");
            assert_eq!(mesh.labels(t), [label(2), label(1)]);
        }
        assert!((mesh_core::geometry::total_area(&mesh) - 9.0).abs() < 1e-12);
        // Open only along the block's border: 4 sides × 3 cells × 2 segments.
        let report = validate(&mesh, &ValidateOptions::default());
        assert_eq!(report.boundary_edges.count, 24);
        assert_eq!(report.non_manifold_edges, 0);
        assert!(report.inconsistent_edges.is_empty() && report.degenerate.is_empty());
    }
}

#[test]
fn each_triangle_separates_the_octants_of_its_labels() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let c = IVec3::new(2, -3, 5);
    let mut out = Vec::new();
    for _ in 0..200 {
        let labels = random_labels(&mut rng, 4);
        out.clear();
        let count = triangulate_octants(c, &labels, FaceMask::ALL, &mut out);
        // Two triangles per edge with different end labels.
        let crossing = (0..12u8)
            .filter(|&i| {
                let e = edge_of_slot(c, i);
                let d = |p: IVec3| {
                    let o = p - c;
                    (o.x + 2 * o.y + 4 * o.z) as usize
                };
                labels[d(e.node)] != labels[d(e.end())]
            })
            .count();
        assert_eq!(count, 2 * crossing);
        for t in &out {
            let p = t
                .verts
                .map(|k| midpoint_position(&UNIT, k).expect("grid key"));
            let g = (p[0] + p[1] + p[2]) / 3.0;
            let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize();
            // The octant holding a point: bit k set when it is past the cell's mid-plane k.
            let octant = |q: DVec3| {
                let o = q - c.as_dvec3();
                usize::from(o.x > 0.5) + 2 * usize::from(o.y > 0.5) + 4 * usize::from(o.z > 0.5)
            };
            assert_eq!(
                t.labels,
                [labels[octant(g + 0.01 * n)], labels[octant(g - 0.01 * n)]],
                "{t:?}"
            );
        }
    }
}

#[test]
fn neighbouring_cells_conform_on_their_face() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    for round in 0..300 {
        let a = round % 3;
        let c0 = IVec3::new(1, 2, 3);
        let c1 = c0 + unit(mesh_core::predicates::Axis::from_index(a));
        // Random node labels around both cells, so they agree on the shared face.
        let block = Block::from_fn(6, |_| rng.random_range(0..3));
        let face = GridFace {
            node: c1,
            normal: mesh_core::predicates::Axis::from_index(a),
        };
        let on_face = |k: &RebuildVertexKey| match k {
            RebuildVertexKey::Edge(e) => face.edges().contains(e),
            RebuildVertexKey::Face(f) => *f == face,
            _ => false,
        };
        // The directed in-face edge of each triangle of each cell.
        let segments = |c: IVec3| {
            let mut out = Vec::new();
            triangulate_octants(c, &block.corners(c), FaceMask::ALL, &mut out);
            let mut segs: Vec<_> = out
                .iter()
                .map(centre_last)
                .filter(|t| on_face(&t.verts[0]) && on_face(&t.verts[1]))
                .map(|t| (t.verts[0], t.verts[1], t.labels))
                .collect();
            segs.sort_by_key(|s| format!("{s:?}"));
            segs
        };
        let (s0, s1) = (segments(c0), segments(c1));
        let mut reversed: Vec<_> = s1.iter().map(|&(p, q, l)| (q, p, l)).collect();
        reversed.sort_by_key(|s| format!("{s:?}"));
        assert_eq!(s0, reversed, "round {round}");
        let face_labels: Vec<Label> = (0..4)
            .map(|k| {
                let (b, cc) = face.normal.others();
                let mut p = face.node;
                p[b] += k & 1;
                p[cc] += k >> 1;
                block.node(p)
            })
            .collect();
        let crossing = [(0, 1), (2, 3), (0, 2), (1, 3)]
            .iter()
            .filter(|&&(i, j)| face_labels[i] != face_labels[j])
            .count();
        assert_eq!(s0.len(), crossing, "one segment per crossing face edge");
    }
}

#[test]
fn fans_of_the_neighbours_segments_equal_the_octant_triangles() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let mut scratch = Vec::new();
    for _ in 0..100 {
        let block = Block::from_fn(3, |_| rng.random_range(0..4));
        let cell = IVec3::ONE;
        for (j, (face, neighbour)) in cell_faces(cell).into_iter().enumerate() {
            // The neighbour's triangles belonging to the face, as clipped-mesh segments.
            scratch.clear();
            let jn = cell_face_index(neighbour, &face).expect("shared face");
            triangulate_octants(
                neighbour,
                &block.corners(neighbour),
                FaceMask::NONE.with(jn),
                &mut scratch,
            );
            let segs: Vec<BoundarySegment> = scratch
                .iter()
                .map(centre_last)
                .map(|t| BoundarySegment {
                    from: t.verts[0],
                    to: t.verts[1],
                    labels: t.labels,
                })
                .collect();
            let mut fans = Vec::new();
            assert_eq!(
                fan_boundary_face(cell, face, &segs, &mut fans),
                Ok(segs.len())
            );
            let mut own = Vec::new();
            triangulate_octants(
                cell,
                &block.corners(cell),
                FaceMask::NONE.with(j as u8),
                &mut own,
            );
            assert_eq!(fans.len(), own.len());
            for t in &own {
                assert!(
                    fans.iter().map(centre_last).any(|f| f == centre_last(t)),
                    "{t:?} not among the fans {fans:?}"
                );
            }
        }
    }
}

#[test]
fn fan_input_is_checked() {
    let cell = IVec3::new(0, 0, 0);
    let face = face_of_slot(cell, 1);
    let edge = RebuildVertexKey::Edge(face.edges()[0]);
    let seg = |from, to, labels: [u32; 2]| BoundarySegment {
        from,
        to,
        labels: labels.map(label),
    };
    let mut out = Vec::new();
    let good = seg(edge, RebuildVertexKey::Cut(4), [1, 0]);
    assert_eq!(fan_boundary_face(cell, face, &[good], &mut out), Ok(1));
    assert_eq!(
        out[0].verts,
        [RebuildVertexKey::Cut(4), edge, RebuildVertexKey::Cell(cell)]
    );
    assert_eq!(out[0].labels, [label(1), label(0)]);
    let far = face_of_slot(cell + IVec3::X, 1);
    assert_eq!(
        fan_boundary_face(cell, far, &[good], &mut out),
        Err(FanError::NotAFaceOfCell { cell, face: far })
    );
    let bad = [
        seg(edge, edge, [1, 0]),
        seg(edge, RebuildVertexKey::Cut(1), [2, 2]),
        seg(RebuildVertexKey::Cell(cell), edge, [1, 0]),
        seg(edge, RebuildVertexKey::Edge(far.edges()[0]), [1, 0]),
        seg(RebuildVertexKey::Face(far), edge, [1, 0]),
    ];
    for (i, b) in bad.iter().enumerate() {
        let r = fan_boundary_face(cell, face, &[good, *b], &mut out);
        assert!(
            matches!(r, Err(ref e) if format!("{e}").contains("segment 1")),
            "case {i}: {r:?}"
        );
    }
    assert_eq!(out.len(), 1, "nothing appended on error");
}

#[test]
fn averaged_face_points_agree_between_cells_and_lie_inside() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    for _ in 0..200 {
        let block = Block::from_fn(2, |_| rng.random_range(0..3));
        let (c0, c1) = (IVec3::ZERO, IVec3::X);
        let t = rng.random_range(0.1..0.9);
        let point = |e: crate::stages::grid::primitives::GridEdge| {
            UNIT.node_position(e.node).lerp(
                UNIT.node_position(e.end()),
                t + 0.01 * f64::from(e.node.y + e.node.z),
            )
        };
        let (p0, p1) = (
            average_cell_points(c0, &block.corners(c0), point),
            average_cell_points(c1, &block.corners(c1), point),
        );
        // Face 1 of cell 0 is face 0 of cell 1: identical bits.
        assert_eq!(
            p0.faces[1].map(|q| q.to_array().map(f64::to_bits)),
            p1.faces[0].map(|q| q.to_array().map(f64::to_bits))
        );
        for (c, p) in [(c0, p0), (c1, p1)] {
            assert_eq!(p.centre.is_some(), has_interface(&block.corners(c)));
            if let Some(q) = p.centre {
                let o = q - c.as_dvec3();
                assert!(
                    o.min_element() > 0.0 && o.max_element() < 1.0,
                    "centre {o} not inside"
                );
            }
            for (j, f) in p.faces.iter().enumerate() {
                if let Some(q) = f {
                    let face = face_of_slot(c, j as u8);
                    let o = *q - face.node.as_dvec3();
                    let (b, cc) = face.normal.others();
                    assert_eq!(o[face.normal.index()], 0.0);
                    assert!(
                        o[b] > 0.0 && o[b] < 1.0 && o[cc] > 0.0 && o[cc] < 1.0,
                        "face point {o} not inside"
                    );
                }
            }
        }
    }
}

/// Labels for a block: `(n, interior labels)` with 2–6 labels.
fn block_strategy() -> impl Strategy<Value = (i32, Vec<u32>)> {
    (2i32..=4, 2u32..=6).prop_flat_map(|(n, k)| {
        (
            Just(n),
            prop::collection::vec(0..k, ((n - 1) * (n - 1) * (n - 1)) as usize),
        )
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(40))]

    /// The welded octant surface of a block whose shell is one label is closed, label
    /// consistent, free of degenerate, duplicate and intersecting triangles, and bounds
    /// exactly the dual cells of each label's nodes.
    #[test]
    fn block_surface_is_closed_and_bounds_the_dual_cells((n, interior) in block_strategy()) {
        let block = Block::with_interior(n, &interior);
        let mesh = midpoint_mesh(&block.triangles());
        assert_valid(&validate(&mesh, &ValidateOptions::with_intersections()), "octant surface");
        assert_volumes(&mesh, &block.counted_volumes());
    }

    /// A random flawed region inside the block: flawed cells emit octant triangles for
    /// internal faces and fans for boundary faces; the intact cells' surface (standing in
    /// for the clipped mesh) has its boundary vertices renamed to cut points, and the
    /// flawed edge vertices slide onto them. The result is the same closed surface.
    #[test]
    fn fans_and_sliding_close_a_flawed_region((n, interior) in block_strategy(), picks in prop::collection::vec(any::<bool>(), 64)) {
        let block = Block::with_interior(n, &interior);
        let flawed = |c: IVec3| block.contains_cell(c) && picks[(c.x + 4 * c.y + 16 * c.z) as usize % 64];
        // Cut points: every vertex on a boundary face of the region.
        let mut cuts: KeyMap<u32> = KeyMap::default();
        let mut boundary: Vec<(IVec3, GridFace, IVec3)> = Vec::new();
        for c in block.cells().filter(|&c| flawed(c)) {
            for (face, nb) in cell_faces(c) {
                if !flawed(nb) {
                    boundary.push((c, face, nb));
                    let keys = face.edges().map(RebuildVertexKey::Edge);
                    for k in keys.into_iter().chain([RebuildVertexKey::Face(face)]) {
                        let id = cuts.len() as u32;
                        cuts.entry(k).or_insert(id);
                    }
                }
            }
        }
        let cut_of = |k: RebuildVertexKey| cuts.get(&k).map_or(k, |&i| RebuildVertexKey::Cut(i));
        let renamed = |t: &RebuildTriangle| RebuildTriangle { verts: t.verts.map(cut_of), ..*t };
        let mut tris = Vec::new();
        for c in block.cells() {
            let corners = block.corners(c);
            if !flawed(c) {
                let start = tris.len();
                triangulate_octants(c, &corners, FaceMask::ALL, &mut tris);
                for t in &mut tris[start..] {
                    *t = renamed(t);
                }
            } else {
                let internal = cell_faces(c)
                    .iter()
                    .enumerate()
                    .filter(|(_, (_, nb))| flawed(*nb))
                    .fold(FaceMask::NONE, |m, (j, _)| m.with(j as u8));
                triangulate_octants(c, &corners, internal, &mut tris);
            }
        }
        let mut scratch = Vec::new();
        for &(c, face, nb) in &boundary {
            scratch.clear();
            let j = cell_face_index(nb, &face).expect("shared face");
            triangulate_octants(nb, &block.corners(nb), FaceMask::NONE.with(j), &mut scratch);
            let segs: Vec<BoundarySegment> = scratch
                .iter()
                .map(|t| centre_last(&renamed(t)))
                .map(|t| BoundarySegment { from: t.verts[0], to: t.verts[1], labels: t.labels })
                .collect();
            prop_assert_eq!(fan_boundary_face(c, face, &segs, &mut tris), Ok(segs.len()));
        }
        let mut w = Welder::new();
        for (&k, &i) in &cuts {
            if matches!(k, RebuildVertexKey::Edge(_)) && tris.iter().any(|t| t.verts.contains(&k)) {
                w.alias(k, RebuildVertexKey::Cut(i)).expect("fresh aliases");
            }
        }
        w.add_all(&tris).expect("no collapse");
        let original: Vec<(RebuildVertexKey, u32)> = cuts.iter().map(|(&k, &i)| (k, i)).collect();
        let mesh = w
            .to_mesh(|k| match k {
                RebuildVertexKey::Cut(i) => original.iter().find(|o| o.1 == i).and_then(|o| midpoint_position(&UNIT, o.0)),
                k => midpoint_position(&UNIT, k),
            })
            .expect("placed");
        prop_assert_eq!(mesh.num_triangles(), block.triangles().len());
        assert_valid(&validate(&mesh, &ValidateOptions::with_intersections()), "fans and sliding");
        assert_volumes(&mesh, &block.counted_volumes());
    }

    /// §8.3's placement — edge vertices anywhere inside their edges, face and cell
    /// vertices at averages — keeps the surface valid and free of intersections: each
    /// cell's part is a cone from its centre over non-crossing segments on its boundary.
    #[test]
    fn averaged_placement_keeps_the_surface_valid((n, interior) in block_strategy(), seed in any::<u64>()) {
        let block = Block::with_interior(n, &interior);
        let tris = block.triangles();
        let w = weld(&tris);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut edge_points: KeyMap<DVec3> = KeyMap::default();
        for k in w.keys() {
            if let RebuildVertexKey::Edge(e) = *k {
                let t = rng.random_range(0.05..0.95);
                edge_points.insert(*k, UNIT.node_position(e.node).lerp(UNIT.node_position(e.end()), t));
            }
        }
        let mut placed = edge_points.clone();
        for c in block.cells() {
            let p = average_cell_points(c, &block.corners(c), |e| edge_points[&RebuildVertexKey::Edge(e)]);
            for (j, f) in p.faces.iter().enumerate() {
                if let Some(q) = *f {
                    let old = placed.insert(RebuildVertexKey::Face(face_of_slot(c, j as u8)), q);
                    prop_assert!(old.is_none_or(|o| o == q), "face vertices differ between cells");
                }
            }
            if let Some(q) = p.centre {
                placed.insert(RebuildVertexKey::Cell(c), q);
            }
        }
        let mesh = w.to_mesh(|k| placed.get(&k).copied()).expect("every vertex placed");
        let report = validate(&mesh, &ValidateOptions::with_intersections());
        prop_assert!(report.is_valid(), "{:#?}", report);
        prop_assert_eq!(report.self_intersecting_pairs.as_ref().map(|l| l.count), Some(0));
    }
}
