//! Tests of §8.1 on real scenes: clean spheres keep their physical labels, overlaps take
//! the label of the nearest breaking point.

use glam::{DVec3, IVec3};
use mesh_core::LabeledMesh;

use super::*;
use crate::stages::flaws::{FlawOptions, detect_flaws};
use crate::stages::grid::{GridOptions, build_grid};
use crate::stages::materials::{MaterialOptions, assign_materials};
use crate::stages::rebuild::cell_corners;
use crate::test_util::{sphere, union};

/// The stages up to §6 on one mesh (shared with the rebuild tests).
pub(crate) struct Run {
    pub grid: Grid,
    pub mats: Materials,
    pub region: FlawedRegion,
}

/// Grid, materials and flaws of `mesh`; with `everything`, the region is grown to a box
/// of cells one layer beyond the band.
pub(crate) fn run(mesh: &LabeledMesh, ell: f64, everything: bool) -> Run {
    let grid = build_grid(mesh, ell, &GridOptions::default()).unwrap();
    let mats = assign_materials(mesh, &grid, &MaterialOptions::default()).unwrap();
    let mut region = detect_flaws(mesh, &grid, &mats, &FlawOptions::default()).unwrap();
    if everything {
        let [lo, hi] = grid.cell_bounds().unwrap();
        let (lo, hi) = (lo - IVec3::ONE, hi + IVec3::ONE);
        let mut all = Vec::new();
        for z in lo.z..=hi.z {
            for y in lo.y..=hi.y {
                for x in lo.x..=hi.x {
                    all.push(IVec3::new(x, y, z));
                }
            }
        }
        region.grow(mesh, &grid, &mats, &all);
    }
    Run { grid, mats, region }
}

#[test]
fn clean_sphere_nodes_keep_their_physical_labels() {
    let c = DVec3::new(0.03, -0.02, 0.01);
    let mesh = sphere(3, c, 1.0, 0, 1);
    let r = run(&mesh, 0.3, true);
    let labels = correct_labels(&mesh, &r.grid, &r.mats, &r.region).unwrap();
    let s = labels.stats();
    assert!(s.nodes > 500, "{s:?}");
    assert_eq!(s.physical_nodes, s.nodes);
    assert_eq!(s.breaking_points, 0);
    assert!(s.scanned_edges > 0, "edges crossing the sphere are walked");
    let lattice = r.grid.lattice();
    for (n, l) in labels.nodes() {
        assert!(labels.is_physical(n) && labels.breaking_point(n).is_none());
        let d = lattice.node_position(n).distance(c);
        if d < 0.95 {
            assert_eq!(l, Label::new(1), "node {n} at distance {d}");
        } else if d > 1.0 {
            assert_eq!(l, Label::new(0), "node {n} at distance {d}");
        }
    }
    // Every corner of every flawed cell has a label; nothing beyond.
    for cell in r.region.cells() {
        for n in cell_corners(cell) {
            assert!(labels.label(n).is_some());
        }
    }
    assert_eq!(labels.label(IVec3::splat(1000)), None);
    // Edges crossed once carry the crossing as first and last.
    let crossed = r
        .region
        .cells()
        .flat_map(crate::stages::grid::primitives::cell_edges);
    let mut seen = 0;
    for e in crossed {
        if let Some(t) = labels.edge_transitions(&e) {
            let (first, last) = (t.first_crossing.unwrap(), t.last_crossing.unwrap());
            let axis = e.axis.index();
            let (lo, hi) = (
                lattice.plane(axis, e.node[axis]),
                lattice.plane(axis, e.node[axis] + 1),
            );
            assert!(lo <= first && first <= last && last <= hi);
            assert!(t.lower_breaking.is_none() && t.upper_breaking.is_none());
            seen += 1;
        }
    }
    assert!(seen > 0);
}

/// Two spheres of labels 1 (left, centre x = −0.5) and 2 (right, x = +0.5), radius 1:
/// the lens between them is non-physical. A lens node nearer the lens' left face (the
/// right sphere's surface, beyond which only sphere 1 remains) takes label 1, and
/// symmetrically.
#[test]
fn overlap_nodes_take_the_label_beyond_the_nearest_face() {
    let (cl, cr) = (DVec3::new(-0.5, 0.01, 0.02), DVec3::new(0.5, 0.01, 0.02));
    let mesh = union(&[sphere(3, cl, 1.0, 0, 1), sphere(3, cr, 1.0, 0, 2)]);
    let ell = 0.2;
    let r = run(&mesh, ell, false);
    let labels = correct_labels(&mesh, &r.grid, &r.mats, &r.region).unwrap();
    let s = labels.stats();
    assert!(s.nodes > 0 && s.breaking_points > 0, "{s:?}");
    assert!(
        s.physical_nodes < s.nodes,
        "the lens has non-physical nodes"
    );
    assert_eq!((s.fallback_nodes, s.unreached_nodes), (0, 0), "{s:?}");
    let lattice = r.grid.lattice();
    let bps = labels.breaking_points();
    let mut checked = 0;
    for (n, l) in labels.nodes() {
        if labels.is_physical(n) {
            continue;
        }
        let p = lattice.node_position(n);
        assert!(l == Label::new(1) || l == Label::new(2), "node {n}: {l}");
        // Its breaking point is (nearly) the nearest of all: closest-point propagation is
        // approximate (measured here: within 0.1ℓ).
        let bp = labels.breaking_point(n).expect("marched");
        let nearest = bps
            .iter()
            .map(|b| b.position.distance(p))
            .fold(f64::MAX, f64::min);
        assert!(
            bp.distance(p) <= nearest + 0.15 * ell,
            "node {n}: {} vs nearest {nearest}",
            bp.distance(p)
        );
        assert!(bps.iter().any(|b| b.position == bp && b.label == l));
        let (to_left_face, to_right_face) = (1.0 - p.distance(cr), 1.0 - p.distance(cl));
        if to_left_face + ell < to_right_face {
            assert_eq!(l, Label::new(1), "node {n} at {p}");
            checked += 1;
        } else if to_right_face + ell < to_left_face {
            assert_eq!(l, Label::new(2), "node {n} at {p}");
            checked += 1;
        }
    }
    assert!(checked > 10, "only {checked} nodes decisively placed");
    // Breaking points lie on grid edges: two coordinates on grid planes.
    for b in bps {
        let on_plane = (0..3)
            .filter(|&a| lattice.plane(a, lattice.locate(a, b.position[a])) == b.position[a])
            .count();
        assert!(on_plane >= 2, "{b:?}");
    }
}

#[test]
fn mismatched_inputs_are_errors() {
    let mesh = sphere(2, DVec3::ZERO, 1.0, 0, 1);
    let r = run(&mesh, 0.4, false);
    let other = sphere(1, DVec3::ZERO, 1.0, 0, 1);
    assert!(matches!(
        correct_labels(&other, &r.grid, &r.mats, &r.region),
        Err(LabelError::Mismatch(_))
    ));
    // A clean sphere has an empty region and an empty labelling.
    let labels = correct_labels(&mesh, &r.grid, &r.mats, &r.region).unwrap();
    assert!(labels.is_empty() && labels.nodes().next().is_none());
}

#[test]
fn marching_takes_the_nearest_point_along_a_chain() {
    // Seven nodes on a line, x = 0..6, all open; breaking points at x = −0.5 (label 1)
    // and x = 6.2 (label 2).
    let positions: Vec<DVec3> = (0..7).map(|i| DVec3::new(f64::from(i), 0.0, 0.0)).collect();
    let open = vec![true; 7];
    let neighbours = |i: u32, out: &mut [u32; march::STENCIL]| {
        let mut k = 0;
        if i > 0 {
            out[k] = i - 1;
            k += 1;
        }
        if i < 6 {
            out[k] = i + 1;
            k += 1;
        }
        k
    };
    let bp = |x: f64, l: u32| BreakingPoint {
        position: DVec3::new(x, 0.0, 0.0),
        label: Label::new(l),
    };
    let mut best = vec![None; 7];
    let seeds = [(0u32, bp(-0.5, 1)), (6u32, bp(6.2, 2))];
    march::march(&positions, &open, &neighbours, seeds.into_iter(), &mut best);
    let got: Vec<u32> = best.iter().map(|b| b.unwrap().point.label.raw()).collect();
    // Midpoint 2.85: nodes 0..=2 are nearer −0.5, nodes 3..=6 nearer 6.2.
    assert_eq!(got, [1, 1, 1, 2, 2, 2, 2]);
    for (i, b) in best.iter().enumerate() {
        let b = b.unwrap();
        assert!((b.distance - b.point.position.distance(positions[i])).abs() < 1e-15);
    }
    // A closed node blocks the propagation.
    let mut best = vec![None; 7];
    let mut open = vec![true; 7];
    open[3] = false;
    march::march(
        &positions,
        &open,
        &neighbours,
        [(0u32, bp(-0.5, 1))].into_iter(),
        &mut best,
    );
    assert!(best[..3].iter().all(Option::is_some) && best[3..].iter().all(Option::is_none));
}

/// One overlap of two spheres (its region takes the dense node index), and two such
/// overlaps 30 apart (much sparser than its bounding box: the hashed index), with whether
/// the index is dense.
fn near_and_far_overlaps() -> [(LabeledMesh, bool); 2] {
    let pair = |x: f64, l: u32| {
        [
            sphere(2, DVec3::new(x - 0.4, 0.0, 0.0), 0.6, 0, l),
            sphere(2, DVec3::new(x + 0.4, 0.0, 0.0), 0.6, 0, l + 1),
        ]
    };
    let near = union(&pair(0.0, 1));
    let far = union(&[pair(0.0, 1), pair(30.0, 3)].concat());
    [(near, true), (far, false)]
}

/// Two overlaps far apart: a region much sparser than its bounding box takes the hashed
/// index, a single overlap the dense one; both list exactly the sorted corners.
#[test]
fn region_nodes_are_the_sorted_corners_dense_or_sparse() {
    for (mesh, dense) in near_and_far_overlaps() {
        let r = run(&mesh, 0.2, false);
        let (nodes, index) = region_nodes(&r.region).unwrap();
        assert_eq!(matches!(index, NodeIndex::Dense { .. }), dense);
        let mut want: Vec<IVec3> = r.region.cells().flat_map(cell_corners).collect();
        want.sort_unstable_by_key(|n| [n.z, n.y, n.x]);
        want.dedup();
        assert_eq!(nodes, want);
        for (i, &n) in nodes.iter().enumerate() {
            assert_eq!(index.get(n), Some(i as u32));
            assert_eq!(index.get(n + IVec3::new(0, 0, 1000)), None);
        }
        let labels = correct_labels(&mesh, &r.grid, &r.mats, &r.region).unwrap();
        assert_eq!(labels.len(), nodes.len());
        assert_eq!(labels.stats().unreached_nodes, 0);
    }
}

/// The marching's view of the region: for a dense index (interior nodes through fixed
/// box offsets) and a sparse one, every node's neighbours and positions are exactly what
/// the lattice and the index give, in stencil order.
#[test]
fn region_nodes_list_the_stencil_neighbours_in_order() {
    use march::Nodes;
    for (mesh, dense) in near_and_far_overlaps() {
        let r = run(&mesh, 0.2, false);
        let (nodes, index) = region_nodes(&r.region).unwrap();
        assert_eq!(matches!(index, NodeIndex::Dense { .. }), dense);
        let lattice = *r.grid.lattice();
        let view = RegionNodes::new(&nodes, &index, &lattice, 1);
        assert_eq!(view.len(), nodes.len());
        let mut interior = 0;
        for (i, &p) in nodes.iter().enumerate() {
            let mut got = Vec::new();
            view.for_each_neighbour(i as u32, |j, at| got.push((j, at)));
            let want: Vec<(u32, DVec3)> = march::OFFSETS
                .iter()
                .filter_map(|&d| index.get(p + d).map(|j| (j, lattice.node_position(p + d))))
                .collect();
            assert_eq!(got, want, "node {p}");
            assert_eq!(view.position(i as u32), lattice.node_position(p));
            interior += usize::from(got.len() == march::STENCIL);
        }
        assert!(interior > 0, "some nodes have all 26 neighbours");
    }
}

/// Every node of the box `[0, n)³`, in lattice order, with its dense index.
fn solid_block(n: i32) -> (Vec<IVec3>, NodeIndex) {
    let mut nodes = Vec::new();
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                nodes.push(IVec3::new(x, y, z));
            }
        }
    }
    let index = NodeIndex::Dense {
        lo: IVec3::ZERO,
        dims: IVec3::splat(n),
        index: (0..nodes.len() as u32).collect(),
    };
    (nodes, index)
}

/// The nearest of `points` to `at` by looking at every one: its id (the lowest among
/// equally near ones) and distance.
fn exact_nearest(points: &[BreakingPoint], at: DVec3) -> (u32, f64) {
    exact_nearest_of(points, at, |_| true)
}

/// [`exact_nearest`] among the points `keep` accepts, squared distances compared (as
/// the stage does, so that points whose distances round to one value still tie to the
/// nearer).
fn exact_nearest_of(
    points: &[BreakingPoint],
    at: DVec3,
    keep: impl Fn(usize) -> bool,
) -> (u32, f64) {
    let mut best = (u32::MAX, f64::INFINITY);
    for (k, b) in points.iter().enumerate() {
        let d2 = (b.position - at).length_squared();
        if keep(k) && d2 < best.1 {
            best = (k as u32, d2);
        }
    }
    (best.0, best.1.sqrt())
}

/// The nearest points of the stage (exact in the band, the far-field march beyond)
/// against the plain march and against looking at every point, on a solid block of 41³
/// nodes whose six faces are breaking points of six labels (the inside of an overlap,
/// seen from its surfaces): nodes within the band get exactly the nearest point (the
/// lowest id among equally near ones), never farther than the plain march's; beyond it
/// every node is reached, its point is within 0.45ℓ of the nearest (0.41ℓ measured; the
/// fill and refine steps the gather replaced gave 0.46ℓ), and it takes another
/// label than the plain march only where both labels are equally near (on the diagonal
/// planes between two faces).
#[test]
fn nearest_points_are_exact_in_the_band_and_near_beyond() {
    let n = 41;
    let lattice = crate::stages::grid::Lattice {
        origin: DVec3::new(0.3, -0.2, 0.1),
        cell_size: 0.5,
    };
    let ell = lattice.cell_size;
    let (nodes, index) = solid_block(n);
    // Face k's nodes carry breaking points of label k + 1, half a cell outside the face.
    let mut points = Vec::new();
    let mut seeds = Vec::new();
    for (i, &p) in nodes.iter().enumerate() {
        for axis in 0..3 {
            for (side, at) in [(0, 0), (1, n - 1)] {
                if p[axis] == at {
                    let mut position = lattice.node_position(p);
                    position[axis] += if side == 0 { -0.5 } else { 0.5 } * ell;
                    let label = Label::new(1 + 2 * axis as u32 + side);
                    points.push(BreakingPoint { position, label });
                    seeds.push((i as u32, points.len() as u32 - 1));
                }
            }
        }
    }
    let fine = RegionNodes::new(&nodes, &index, &lattice, 1);
    let mut plain = vec![march::Slot::OPEN; nodes.len()];
    march::march_over(&fine, &points, seeds.iter().copied(), &mut plain);
    let band = FAR_FIELD_BAND_CELLS * ell;
    let seed_of: Vec<usize> = seeds.iter().map(|&(i, _)| i as usize).collect();
    let (far, stats) = nearest_points(&nodes, &index, &lattice, &points, |k| Some(seed_of[k]));
    assert!(stats.far_nodes > 10_000, "{stats:?}");
    assert_eq!(stats.rest_nodes, 0, "{stats:?}");
    let nearest_of = |at: DVec3, label: Option<Label>| {
        points
            .iter()
            .filter(|b| label.is_none_or(|l| b.label == l))
            .map(|b| b.position.distance(at))
            .fold(f64::INFINITY, f64::min)
    };
    let mut relabelled = 0;
    for (i, (p, f)) in plain.iter().zip(&far).enumerate() {
        assert!(f.point < march::Slot::CLOSED, "node {i} unreached");
        let at = lattice.node_position(nodes[i]);
        let nearest = nearest_of(at, None);
        if nearest <= band {
            assert_eq!(
                (f.point, f.distance),
                exact_nearest(&points, at),
                "band node {i}"
            );
            assert!(f.distance <= p.distance, "band node {i}");
            continue;
        }
        assert!(
            f.distance <= nearest + 0.45 * ell,
            "node {i}: {} vs {nearest}",
            f.distance
        );
        let (lp, lf) = (
            points[p.point as usize].label,
            points[f.point as usize].label,
        );
        if lp != lf {
            relabelled += 1;
            let gap = (nearest_of(at, Some(lp)) - nearest_of(at, Some(lf))).abs();
            assert!(gap <= 1e-9 * ell, "node {i}: labels {lp} / {lf}, gap {gap}");
        }
    }
    assert!(
        relabelled < nodes.len() / 50,
        "{relabelled} nodes relabelled"
    );
}

/// A node takes points of its own part of the region only, as a march over the region's
/// nodes would: of two blocks two cells apart, the one without breaking points is
/// reached by none, in the band or beyond (its nodes are left to the fallback), though
/// every node of it is well within the band of the other's point and its far field's
/// candidates hold that point. The far field used to take it across parts.
#[test]
fn band_points_stay_in_their_part_of_the_region() {
    let lattice = crate::stages::grid::Lattice {
        origin: DVec3::ZERO,
        cell_size: 1.0,
    };
    let mut nodes = Vec::new();
    for z in 0..4 {
        for y in 0..4 {
            for x in (0..4).chain(6..10) {
                nodes.push(IVec3::new(x, y, z));
            }
        }
    }
    nodes.sort_by_key(|p| [p.z, p.y, p.x]);
    let index = NodeIndex::Sparse(
        nodes
            .iter()
            .enumerate()
            .map(|(i, &p)| (p, i as u32))
            .collect(),
    );
    // One breaking point just outside the first block's far face.
    let seed = index.get(IVec3::new(3, 1, 1)).unwrap() as usize;
    let points = [BreakingPoint {
        position: DVec3::new(3.5, 1.0, 1.0),
        label: Label::new(1),
    }];
    let (slots, stats) = nearest_points(&nodes, &index, &lattice, &points, |_| Some(seed));
    assert_eq!(stats.far_nodes, nodes.len() / 2, "{stats:?}");
    assert_eq!(stats.rest_nodes, nodes.len() / 2, "{stats:?}");
    for (i, p) in nodes.iter().enumerate() {
        if p.x < 4 {
            let exact = points[0].position.distance(lattice.node_position(*p));
            assert_eq!((slots[i].point, slots[i].distance), (0, exact), "node {p}");
        } else {
            assert_eq!(slots[i].point, march::Slot::NONE, "node {p}");
        }
    }
}

/// Every node within the band of scattered breaking points gets exactly the nearest one
/// (the lowest id among equally near ones) and no other node is in the band, wherever
/// the points lie against the far field's blocks: the check that lets one query answer
/// for a whole block deep inside must not skip a node whose nearest point is within the
/// band.
#[test]
fn band_nodes_get_the_exact_nearest_of_scattered_points() {
    let n = 30;
    let lattice = crate::stages::grid::Lattice {
        origin: DVec3::new(-0.1, 0.2, 0.05),
        cell_size: 1.0,
    };
    let (nodes, index) = solid_block(n);
    // A few points at pseudo-random spots (a fixed linear congruential sequence), each
    // seeded at the node below it.
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let points: Vec<BreakingPoint> = (0..6)
        .map(|k| BreakingPoint {
            position: lattice.origin
                + DVec3::new(next(), next(), next()) * (n - 1) as f64 * lattice.cell_size,
            label: Label::new(1 + k % 2),
        })
        .collect();
    let seed_of: Vec<usize> = points
        .iter()
        .map(|b| {
            let p = ((b.position - lattice.origin) / lattice.cell_size)
                .floor()
                .as_ivec3();
            index.get(p).unwrap() as usize
        })
        .collect();
    let (slots, stats) = nearest_points(&nodes, &index, &lattice, &points, |k| Some(seed_of[k]));
    let band = FAR_FIELD_BAND_CELLS * lattice.cell_size;
    let mut in_band = 0;
    for (i, &p) in nodes.iter().enumerate() {
        let at = lattice.node_position(p);
        let want = exact_nearest(&points, at);
        if want.1 <= band {
            in_band += 1;
            assert_eq!((slots[i].point, slots[i].distance), want, "node {p}");
        }
    }
    // Every node beyond the band, and only those, was left to the far field.
    assert_eq!(stats.far_nodes, nodes.len() - in_band, "{stats:?}");
    assert!(
        in_band > 1000 && stats.far_nodes > 1000,
        "{in_band} in the band, {stats:?}"
    );
}

proptest::proptest! {
    /// The band's per-block candidate lists against looking at every point of the node's
    /// part, on two slabs of nodes one missing layer apart (two parts, and blocks that
    /// straddle both, which ask the tree per node) with points on a half-cell lattice (so
    /// that exact ties are everywhere): every node whose nearest point of its part is
    /// within the band gets exactly it (the lowest id among equally near ones), and no
    /// other node gets any.
    #[test]
    fn band_candidates_give_the_exact_nearest_of_the_part(
        raw in proptest::collection::vec((0i32..27, 0i32..19, 0i32..19), 1..40),
    ) {
        let lattice = crate::stages::grid::Lattice {
            origin: DVec3::new(0.25, -0.5, 0.125),
            cell_size: 0.5,
        };
        // x in 0..=5 and 7..=13: the gap at x = 6 parts them (26-neighbours are one apart).
        let mut nodes = Vec::new();
        for z in 0..10 {
            for y in 0..10 {
                for x in (0..14).filter(|&x| x != 6) {
                    nodes.push(IVec3::new(x, y, z));
                }
            }
        }
        let index = NodeIndex::Sparse(
            nodes.iter().enumerate().map(|(i, &p)| (p, i as u32)).collect(),
        );
        // Points on the half-cell lattice, each seeded at the node at or below it.
        let points: Vec<BreakingPoint> = raw
            .iter()
            .map(|&(x, y, z)| BreakingPoint {
                position: lattice.origin + DVec3::new(x as f64, y as f64, z as f64) * 0.5 * lattice.cell_size,
                label: Label::new(1 + (x % 3) as u32),
            })
            .collect();
        let seed_of: Vec<Option<usize>> = raw
            .iter()
            .map(|&(x, y, z)| {
                let p = IVec3::new(x.div_euclid(2), y.div_euclid(2), z.div_euclid(2));
                index.get(p).map(|i| i as usize)
            })
            .collect();
        let part_of = |p: IVec3| p.x > 6;
        let (slots, _) = nearest_points(&nodes, &index, &lattice, &points, |k| seed_of[k]);
        let band = FAR_FIELD_BAND_CELLS * lattice.cell_size;
        for (i, &p) in nodes.iter().enumerate() {
            let at = lattice.node_position(p);
            let same_part = |k: usize| seed_of[k].is_some_and(|j| part_of(nodes[j]) == part_of(p));
            let want = exact_nearest_of(&points, at, same_part);
            if want.1 <= band {
                proptest::prop_assert_eq!((slots[i].point, slots[i].distance), want, "node {}", p);
            } else {
                // Beyond the band: the far field's, but never a point of the other part.
                let k = slots[i].point as usize;
                proptest::prop_assert!(k >= points.len() || same_part(k), "node {}", p);
            }
        }
    }

    /// The region's parts by runs against union–find over every node and its 26
    /// neighbours, on random sparse node sets (thin diagonal contacts are common): the
    /// same part, named by its smallest node, for every node.
    #[test]
    fn parts_by_runs_match_parts_by_nodes(
        cells in proptest::collection::vec(proptest::bool::weighted(0.3), 7 * 6 * 5),
    ) {
        let nodes: Vec<IVec3> = (0..7 * 6 * 5)
            .filter(|&k| cells[k as usize])
            .map(|k| IVec3::new(k % 7, (k / 7) % 6, k / 42))
            .collect();
        let index = NodeIndex::Sparse(
            nodes.iter().enumerate().map(|(i, &p)| (p, i as u32)).collect(),
        );
        let mut parent: Vec<u32> = (0..nodes.len() as u32).collect();
        for (i, &p) in nodes.iter().enumerate() {
            for d in march::OFFSETS {
                if let Some(j) = index.get(p + d) {
                    mesh_core::union_find::union(&mut parent, i as u32, j);
                }
            }
        }
        let want: Vec<u32> = (0..nodes.len() as u32)
            .map(|i| mesh_core::union_find::find(&mut parent, i))
            .collect();
        proptest::prop_assert_eq!(components(&nodes), want);
    }
}

/// The status carried along runs of x neighbours against looking each node up on its
/// own ([`Materials::material_at`] walks back to the surface): the same id and label for
/// every node of the half of the overlaps' box beyond their centre, whose rows start deep
/// inside a solid (so a run must not take over the end of the row before, outside).
#[test]
fn status_carried_along_runs_matches_the_walk_per_node() {
    for (mesh, _) in near_and_far_overlaps() {
        let r = run(&mesh, 0.1, false);
        let [lo, hi] = r.grid.cell_bounds().unwrap();
        let mut nodes = Vec::new();
        for z in lo.z..=hi.z + 1 {
            for y in lo.y..=hi.y + 1 {
                for x in (lo.x + hi.x) / 2 - 3..=hi.x + 1 {
                    nodes.push(IVec3::new(x, y, z));
                }
            }
        }
        let (ids, status) = physical_status(&r.grid, &r.mats, &nodes);
        let mut inside = 0;
        for (i, &p) in nodes.iter().enumerate() {
            let id = r.grid.node_id(p);
            let want = match id {
                Some(n) => r.mats.physical_label(n),
                None => r.mats.material_at(&r.grid, p).label(),
            };
            inside += usize::from(id.is_none() && want != Some(Label::OUTSIDE));
            assert_eq!((ids[i], status[i]), (id, want), "node {p}");
        }
        assert!(inside > 100, "{inside} unallocated nodes inside");
    }
}
