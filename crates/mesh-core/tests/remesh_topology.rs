//! Topology operations of issue 3 on hand-built configurations: vertex separation (T1,
//! Los Topos §5, Figs. 8–11), degenerate removal (T2, §6) and pinching (El Topo §3.6).
//!
//! Every scene is a watertight labelled mesh built by hand, checked valid (including the
//! exact self-intersection layer) before and after the operation, and checked with region
//! graphs: before, the named vertex is irregular; after, every vertex is regular.

use std::collections::BTreeMap;

use glam::{DMat3, DVec3};
use mesh_core::geometry::label_volumes;
use mesh_core::remesh::{
    AreaDecrease, Edit, EditGuard, NoGuard, RegionGraph, SeparationParams, VelocityDivergence,
    VertexAttributes, Veto, apply_edit, irregular_vertices, pinch_singular_vertices,
    remove_degenerate, separate_irregular_vertices,
};
use mesh_core::validate::{ValidateOptions, validate};
use mesh_core::{Label, LabeledMesh, VertexId};

/// The scenes shared with the library's own remesh unit tests.
#[path = "../src/remesh/fixtures.rs"]
mod fixtures;

// ----- scene construction ---------------------------------------------------------------

/// A triangle `tri` with `front` on the side towards `toward` and `back` on the other.
fn oriented(
    p: &[DVec3],
    tri: [u32; 3],
    front: u32,
    back: u32,
    toward: DVec3,
) -> ([u32; 3], [u32; 2]) {
    let [a, b, c] = tri.map(|i| p[i as usize]);
    let n = (b - a).cross(c - a);
    if n.dot(toward - (a + b + c) / 3.0) >= 0.0 {
        (tri, [front, back])
    } else {
        ([tri[0], tri[2], tri[1]], [front, back])
    }
}

fn build(p: Vec<DVec3>, faces: Vec<([u32; 3], [u32; 2])>) -> LabeledMesh {
    let (tris, labels): (Vec<_>, Vec<_>) = faces.into_iter().unzip();
    LabeledMesh::from_raw(p, &tris, &labels).expect("indices in range")
}

fn axis(k: usize) -> DVec3 {
    DVec3::AXES[k]
}

/// The octahedron `|x|+|y|+|z| ≤ 1` cut by the coordinate planes into eight octant cells,
/// cell labels from `label(signs)`, outside 0; faces between equal labels are omitted.
/// Vertices: 0 the centre, then `+x, −x, +y, −y, +z, −z` (1..=6).
fn octants(label: impl Fn([i32; 3]) -> u32) -> LabeledMesh {
    let mut p = vec![DVec3::ZERO];
    for k in 0..3 {
        p.push(axis(k));
        p.push(-axis(k));
    }
    let tip = |k: usize, s: i32| (1 + 2 * k + usize::from(s < 0)) as u32;
    let mut faces = Vec::new();
    for sx in [1, -1] {
        for sy in [1, -1] {
            for sz in [1, -1] {
                let tri = [tip(0, sx), tip(1, sy), tip(2, sz)];
                let out = DVec3::new(sx as f64, sy as f64, sz as f64);
                faces.push(oriented(&p, tri, 0, label([sx, sy, sz]), out));
            }
        }
    }
    for k in 0..3 {
        let (i, j) = ((k + 1) % 3, (k + 2) % 3);
        for si in [1, -1] {
            for sj in [1, -1] {
                let cell = |sk: i32| {
                    let mut s = [0; 3];
                    (s[i], s[j], s[k]) = (si, sj, sk);
                    label(s)
                };
                if cell(1) != cell(-1) {
                    let tri = [0, tip(i, si), tip(j, sj)];
                    let centroid = (axis(i) * si as f64 + axis(j) * sj as f64) / 3.0;
                    faces.push(oriented(&p, tri, cell(1), cell(-1), centroid + axis(k)));
                }
            }
        }
    }
    build(p, faces)
}

/// The cube `[−1, 1]³` cut into six pyramids from its centre (vertex 0) to its faces:
/// labels `+x, −x, +y, −y, +z, −z` = 1..=6, outside 0. Opposite pyramids meet only at the
/// centre: the 6-region irregular vertex of Los Topos Fig. 10.
fn cube_pyramids() -> LabeledMesh {
    let mut p = vec![DVec3::ZERO];
    for i in 0..8 {
        p.push(DVec3::new(sign(i & 1), sign(i & 2), sign(i & 4)));
    }
    let corner = |s: [i32; 3]| {
        (1 + usize::from(s[0] < 0) + 2 * usize::from(s[1] < 0) + 4 * usize::from(s[2] < 0)) as u32
    };
    let pyramid = |k: usize, s: i32| (1 + 2 * k + usize::from(s < 0)) as u32;
    let mut faces = Vec::new();
    for k in 0..3 {
        let (i, j) = ((k + 1) % 3, (k + 2) % 3);
        for s in [1, -1] {
            // Outer face x_k = s, as two triangles around its corners in cyclic order.
            let at = |a: i32, b: i32| {
                let mut c = [0; 3];
                (c[k], c[i], c[j]) = (s, a, b);
                corner(c)
            };
            let quad = [at(1, 1), at(-1, 1), at(-1, -1), at(1, -1)];
            let out = axis(k) * s as f64 * 2.0;
            faces.push(oriented(
                &p,
                [quad[0], quad[1], quad[2]],
                0,
                pyramid(k, s),
                out,
            ));
            faces.push(oriented(
                &p,
                [quad[0], quad[2], quad[3]],
                0,
                pyramid(k, s),
                out,
            ));
        }
        // Inner faces: through each cube edge parallel to axis k, between pyramids (i, si)
        // and (j, sj).
        for si in [1, -1] {
            for sj in [1, -1] {
                let end = |sk: i32| {
                    let mut c = [0; 3];
                    (c[i], c[j], c[k]) = (si, sj, sk);
                    corner(c)
                };
                let tri = [0, end(1), end(-1)];
                faces.push(oriented(
                    &p,
                    tri,
                    pyramid(i, si),
                    pyramid(j, sj),
                    axis(i) * si as f64,
                ));
            }
        }
    }
    build(p, faces)
}

fn sign(bit: usize) -> f64 {
    if bit == 0 { 1.0 } else { -1.0 }
}

/// Two tetrahedra on the base triangle `[1, 2, 3]` in the plane z = 0, apex 4 above (cell
/// `upper`) and apex 5 below (cell `lower`), outside 0; the base faces are `middle`
/// (none when the two cells are one material). Used for T2.
fn bipyramid(upper: u32, lower: u32, middle: &[([u32; 3], [u32; 2])]) -> LabeledMesh {
    let p = vec![
        DVec3::ZERO, // unused vertex 0 keeps indices readable; removed below
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(-0.5, 0.8, 0.0),
        DVec3::new(-0.5, -0.8, 0.0),
        DVec3::new(0.1, 0.05, 1.0),
        DVec3::new(-0.05, 0.1, -1.0),
    ];
    let mut faces = Vec::new();
    for (apex, label) in [(4, upper), (5, lower)] {
        let cell = (p[1] + p[2] + p[3] + p[apex as usize]) / 4.0;
        for (e0, e1) in [(1, 2), (2, 3), (3, 1)] {
            let face = (p[e0 as usize] + p[e1 as usize] + p[apex as usize]) / 3.0;
            faces.push(oriented(&p, [e0, e1, apex], 0, label, 2.0 * face - cell));
        }
    }
    faces.extend_from_slice(middle);
    let mut mesh = build(p, faces);
    mesh.remove_vertex(VertexId::new(0))
        .expect("vertex 0 is unused");
    mesh
}

/// Two tetrahedra of label 1 sharing only vertex 0 (the second mirrored through it).
fn bowtie() -> LabeledMesh {
    let (p, tris, labels) = fixtures::bowtie_raw();
    LabeledMesh::from_raw(p, &tris, &labels).expect("indices in range")
}

// ----- checks ---------------------------------------------------------------------------

fn assert_valid(mesh: &LabeledMesh, what: &str) {
    let report = validate(mesh, &ValidateOptions::with_intersections());
    assert!(report.is_valid(), "{what}: {report:?}");
}

fn missing_arc_labels(mesh: &LabeledMesh, v: VertexId) -> Vec<[u32; 2]> {
    let mut g = RegionGraph::new();
    g.build(mesh, v);
    let mut arcs: Vec<[u32; 2]> = g
        .missing_arcs()
        .map(|(a, b)| {
            let mut l = [g.node_label(a).raw(), g.node_label(b).raw()];
            l.sort_unstable();
            l
        })
        .collect();
    arcs.sort_unstable();
    arcs
}

/// Number of triangles separating the unordered label pair `{x, y}`.
fn interfaces(mesh: &LabeledMesh, x: u32, y: u32) -> usize {
    mesh.triangles()
        .filter(|&t| {
            let [f, b] = mesh.labels(t).map(Label::raw);
            (f, b) == (x, y) || (f, b) == (y, x)
        })
        .count()
}

/// Largest total area of the triangles at one vertex: each separation moves two copies of
/// a vertex by ε/2, sweeping at most `(ε/2)·area/3` per incident triangle.
fn max_vertex_star_area(mesh: &LabeledMesh) -> f64 {
    mesh.vertices()
        .map(|v| {
            mesh.vertex_triangles(v)
                .map(|t| mesh_core::geometry::triangle_area(&mesh.tri_positions(t)))
                .sum::<f64>()
        })
        .fold(0.0, f64::max)
}

fn assert_volumes_close(before: &BTreeMap<Label, f64>, after: &BTreeMap<Label, f64>, bound: f64) {
    assert_eq!(
        before.keys().collect::<Vec<_>>(),
        after.keys().collect::<Vec<_>>()
    );
    for (l, v) in before {
        let change = (after[l] - v).abs();
        assert!(
            change <= bound,
            "label {l}: volume {v} → {} (bound {bound})",
            after[l]
        );
    }
}

/// A guard that refuses everything.
struct VetoAll;

impl EditGuard for VetoAll {
    fn check(&mut self, _mesh: &LabeledMesh, _edit: &Edit) -> Result<(), Veto> {
        Err(Veto::Other("vetoed by test"))
    }
}

/// Refuses an edit whose end state fails validation, self-intersection layer included:
/// applies it to a copy and validates the copy. (The shipped `StaticIntersectionGuard`
/// is the cheap version of this; this one also catches label or pairing mistakes.)
struct EndStateGuard {
    checked: usize,
}

impl EditGuard for EndStateGuard {
    fn check(&mut self, mesh: &LabeledMesh, edit: &Edit) -> Result<(), Veto> {
        self.checked += 1;
        let mut copy = mesh.clone();
        apply_edit(&mut copy, &mut VertexAttributes::none(), &mut NoGuard, edit)
            .map_err(|_| Veto::Other("malformed"))?;
        let report = validate(&copy, &ValidateOptions::with_intersections());
        if report.is_valid() {
            Ok(())
        } else {
            eprintln!("end state invalid: {report:?}");
            Err(Veto::Other("end state invalid"))
        }
    }
}

/// Extension along (1, 1, 0), compression along (1, −1, 0), scaled by `s`.
fn shear(s: f64) -> VelocityDivergence<impl Fn(DVec3) -> DMat3 + Sync> {
    VelocityDivergence {
        gradient: move |_p: DVec3| DMat3::from_cols(DVec3::Y * s, DVec3::X * s, DVec3::ZERO),
    }
}

// ----- T1: vertex separation ------------------------------------------------------------

/// Los Topos Figs. 8–9: cells (+,+,+) = 1 and (−,−,−) = 2 touch only at the centre; the
/// other cells are 3 above z = 0 and 4 below. One missing arc, {1, 2}.
fn double_cone() -> LabeledMesh {
    octants(|s| match s {
        [1, 1, 1] => 1,
        [-1, -1, -1] => 2,
        [_, _, 1] => 3,
        _ => 4,
    })
}

#[test]
fn single_missing_arc_is_separated_with_a_gap_interface() {
    let mut mesh = double_cone();
    assert_valid(&mesh, "input");
    assert_eq!(irregular_vertices(&mesh), vec![VertexId::new(0)]);
    assert_eq!(missing_arc_labels(&mesh, VertexId::new(0)), vec![[1, 2]]);
    let volumes = label_volumes(&mesh);
    let bound = max_vertex_star_area(&mesh) * 0.1 / 6.0 * 1.5;
    let before_34 = interfaces(&mesh, 3, 4);

    let params = SeparationParams::default();
    let report = separate_irregular_vertices(
        &mut mesh,
        &mut VertexAttributes::none(),
        &mut NoGuard,
        &params,
        &AreaDecrease,
    );
    assert_eq!(report.separations, 1, "{report:?}");
    assert_eq!(report.irregular_remaining, 0);
    assert!(irregular_vertices(&mesh).is_empty());
    assert_valid(&mesh, "after separation");
    // Two gap triangles continue the 3 | 4 interface between the two pulled-apart copies.
    assert_eq!(interfaces(&mesh, 3, 4), before_34 + 2);
    assert_eq!(interfaces(&mesh, 1, 2), 0);
    assert_volumes_close(&volumes, &label_volumes(&mesh), bound);
}

/// The X of Los Topos Fig. 5/9 extruded: quadrant prisms 1 (+x+y), 2 (−x+y), 3 (−x−y),
/// 4 (+x−y). Diagonal quadrants share only the z axis, so the centre and both poles are
/// irregular with missing arcs {1, 3} and {2, 4}.
fn crossed_quadrants() -> LabeledMesh {
    octants(|s| match (s[0], s[1]) {
        (1, 1) => 1,
        (-1, 1) => 2,
        (-1, -1) => 3,
        _ => 4,
    })
}

#[test]
fn crossed_quadrants_separate_the_pair_the_flow_pulls_apart() {
    for (s, apart, joined) in [(1.0, [1, 3], [2, 4]), (-1.0, [2, 4], [1, 3])] {
        let mut mesh = crossed_quadrants();
        assert_valid(&mesh, "input");
        let poles_and_centre: Vec<VertexId> = [0, 5, 6].map(VertexId::new).to_vec();
        assert_eq!(irregular_vertices(&mesh), poles_and_centre);
        assert_eq!(
            missing_arc_labels(&mesh, VertexId::new(0)),
            vec![[1, 3], [2, 4]]
        );
        let volumes = label_volumes(&mesh);
        let bound = 3.0 * max_vertex_star_area(&mesh) * 0.1 / 6.0 * 1.5;
        let mut attrs = VertexAttributes::zeros(&mesh, 1);
        attrs.get_mut(VertexId::new(0))[0] = 7.0;

        let params = SeparationParams::default();
        let mut guard = EndStateGuard { checked: 0 };
        let report =
            separate_irregular_vertices(&mut mesh, &mut attrs, &mut guard, &params, &shear(s));
        assert_eq!(guard.checked, 3);
        // Centre and both poles separate once each (the T1 process along the z axis).
        assert_eq!(report.separations, 3, "s = {s}: {report:?}");
        assert_eq!(report.vetoed, 0);
        assert!(irregular_vertices(&mesh).is_empty(), "s = {s}");
        assert_valid(&mesh, "after separation");
        // The pair the flow pulls apart stays apart; the other pair gains an interface.
        assert_eq!(interfaces(&mesh, apart[0], apart[1]), 0, "s = {s}");
        assert!(interfaces(&mesh, joined[0], joined[1]) >= 2, "s = {s}");
        assert_volumes_close(&volumes, &label_volumes(&mesh), bound);
        // The centre's copy carries the centre's attributes.
        let copies = mesh.vertices().filter(|&v| attrs.get(v)[0] == 7.0).count();
        assert_eq!(copies, 2, "s = {s}");
    }
}

#[test]
fn six_regions_need_three_separations() {
    let mut mesh = cube_pyramids();
    assert_valid(&mesh, "input");
    assert_eq!(irregular_vertices(&mesh), vec![VertexId::new(0)]);
    assert_eq!(
        missing_arc_labels(&mesh, VertexId::new(0)),
        vec![[1, 2], [3, 4], [5, 6]]
    );
    let volumes = label_volumes(&mesh);
    let bound = 3.0 * max_vertex_star_area(&mesh) * 0.1 / 6.0 * 1.5;

    // Diverging most along x, then y: separate ±x first, then ±y at both copies.
    let flow = VelocityDivergence {
        gradient: |_p: DVec3| DMat3::from_diagonal(DVec3::new(3.0, 2.0, 1.0)),
    };
    let params = SeparationParams::default();
    let mut guard = EndStateGuard { checked: 0 };
    let report = separate_irregular_vertices(
        &mut mesh,
        &mut VertexAttributes::none(),
        &mut guard,
        &params,
        &flow,
    );
    assert_eq!(guard.checked, 3);
    assert_eq!(report.separations, 3, "{report:?}");
    assert_eq!(report.irregular_remaining, 0);
    assert!(irregular_vertices(&mesh).is_empty());
    assert_valid(&mesh, "after separation");
    assert_eq!(mesh.num_vertices(), 9 + 3);
    // ±x and ±y stay apart; the last pair, ±z, is joined by a new interface.
    assert_eq!(interfaces(&mesh, 1, 2), 0);
    assert_eq!(interfaces(&mesh, 3, 4), 0);
    assert!(interfaces(&mesh, 5, 6) >= 1);
    assert_volumes_close(&volumes, &label_volumes(&mesh), bound);
}

/// Moves every vertex by up to `amount` in each coordinate (seeded), so that no
/// configuration is symmetric by accident.
fn jitter(mesh: &mut LabeledMesh, seed: u64, amount: f64) {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let vertices: Vec<VertexId> = mesh.vertices().collect();
    for v in vertices {
        let d = DVec3::new(
            rng.random_range(-amount..amount),
            rng.random_range(-amount..amount),
            rng.random_range(-amount..amount),
        );
        mesh.set_position(v, mesh.position(v) + d);
    }
    // Rebuild the corner table for the moved geometry.
    let (p, t, l) = mesh.to_raw();
    *mesh = LabeledMesh::from_raw(p, &t, &l).expect("same indices");
}

#[test]
fn jittered_scenes_end_regular_and_valid() {
    let flow = VelocityDivergence {
        gradient: |_p: DVec3| DMat3::from_diagonal(DVec3::new(3.0, 2.0, 1.0)),
    };
    for seed in 0..8 {
        for (name, mut mesh) in [
            ("quadrants", crossed_quadrants()),
            ("pyramids", cube_pyramids()),
        ] {
            jitter(&mut mesh, seed, 0.15);
            assert_valid(&mesh, name);
            assert!(!irregular_vertices(&mesh).is_empty());
            let mut guard = EndStateGuard { checked: 0 };
            let params = SeparationParams::default();
            let strength: &dyn mesh_core::remesh::SeparationStrength = if name == "quadrants" {
                &shear(1.0)
            } else {
                &flow
            };
            let report = separate_irregular_vertices(
                &mut mesh,
                &mut VertexAttributes::none(),
                &mut guard,
                &params,
                strength,
            );
            assert_eq!(report.vetoed, 0, "{name} seed {seed}: {report:?}");
            assert_eq!(report.separations, 3, "{name} seed {seed}: {report:?}");
            assert_eq!(
                report.irregular_remaining, 0,
                "{name} seed {seed}: {report:?}"
            );
            assert!(irregular_vertices(&mesh).is_empty());
            assert_valid(&mesh, name);
        }
    }
}

#[test]
fn separation_passes_are_bounded() {
    // One pass resolves the centre into two 5-region vertices and one of them further; the
    // last separation needs a second pass, which is not allowed here.
    let mut mesh = cube_pyramids();
    let flow = VelocityDivergence {
        gradient: |_p: DVec3| DMat3::from_diagonal(DVec3::new(3.0, 2.0, 1.0)),
    };
    let params = SeparationParams {
        max_iterations: 1,
        ..SeparationParams::default()
    };
    let report = separate_irregular_vertices(
        &mut mesh,
        &mut VertexAttributes::none(),
        &mut NoGuard,
        &params,
        &flow,
    );
    assert_eq!(
        (
            report.iterations,
            report.separations,
            report.irregular_remaining
        ),
        (1, 2, 1),
        "{report:?}"
    );
    assert_valid(&mesh, "after one pass");
    let params = SeparationParams::default();
    let report = separate_irregular_vertices(
        &mut mesh,
        &mut VertexAttributes::none(),
        &mut NoGuard,
        &params,
        &flow,
    );
    assert_eq!(
        (report.separations, report.irregular_remaining),
        (1, 0),
        "{report:?}"
    );
}

#[test]
fn separation_waits_for_a_positive_strength() {
    let mut mesh = cube_pyramids();
    let before = mesh.to_raw();
    let converging = VelocityDivergence {
        gradient: |_p: DVec3| -DMat3::IDENTITY,
    };
    let params = SeparationParams::default();
    let report = separate_irregular_vertices(
        &mut mesh,
        &mut VertexAttributes::none(),
        &mut NoGuard,
        &params,
        &converging,
    );
    assert_eq!(report.separations, 0);
    assert_eq!(report.irregular_remaining, 1);
    assert_eq!(mesh.to_raw(), before);
}

// ----- T2: degenerate removal -----------------------------------------------------------

#[test]
fn collapsed_region_between_two_materials_leaves_one_interface() {
    // The flattened region 3 between the upper cell 1 and the lower cell 2, as two
    // coincident triangles in either order and orientation, plus a collapsed triangle.
    let upper_side = ([1, 2, 3], [1, 3]); // normal +z: front faces cell 1
    let lower_side = ([1, 3, 2], [2, 3]); // normal −z: front faces cell 2
    for middle in [vec![upper_side, lower_side], vec![lower_side, upper_side]] {
        let mut middle = middle;
        middle.push(([1, 1, 4], [0, 1]));
        let mut mesh = bipyramid(1, 2, &middle);
        assert!(!validate(&mesh, &ValidateOptions::default()).is_valid());
        let report = remove_degenerate(&mut mesh, &mut VertexAttributes::none(), &mut NoGuard);
        assert_eq!(
            (
                report.collapsed_removed,
                report.pairs_relabelled,
                report.pairs_removed
            ),
            (1, 1, 0),
            "{report:?}"
        );
        assert_valid(&mesh, "after T2");
        let base: Vec<_> = mesh
            .triangles()
            .filter(|&t| mesh.tri(t).iter().all(|v| (1..=3).contains(&v.raw())))
            .collect();
        assert_eq!(base.len(), 1);
        let t = base[0];
        let [a, b, c] = mesh.tri_positions(t);
        let up = (b - a).cross(c - a).z > 0.0;
        // Cell 1 lies above the base, cell 2 below, whichever way the triangle turns.
        let expect = if up { [1, 2] } else { [2, 1] };
        assert_eq!(mesh.labels(t).map(Label::raw), expect);
        assert!(!mesh.label_set().contains(&Label::new(3)));
    }
}

#[test]
fn collapsed_region_inside_one_material_disappears_and_the_material_merges() {
    let middle = [([1, 2, 3], [1, 3]), ([1, 3, 2], [1, 3])];
    let mut mesh = bipyramid(1, 1, &middle);
    let report = remove_degenerate(&mut mesh, &mut VertexAttributes::none(), &mut NoGuard);
    assert_eq!(
        (report.pairs_relabelled, report.pairs_removed),
        (0, 1),
        "{report:?}"
    );
    assert_valid(&mesh, "after T2");
    assert_eq!(mesh.num_triangles(), 6);
    // One region of material 1 now fills both cells.
    let ones: Vec<_> = mesh
        .regions()
        .bounded()
        .filter(|s| s.label == Label::new(1))
        .cloned()
        .collect();
    assert_eq!(ones.len(), 1);
    let total = label_volumes(&mesh)[&Label::new(1)];
    assert!(
        (ones[0].volume - total).abs() < 1e-12 && total > 0.5,
        "{ones:?} vs {total}"
    );
    assert_eq!(mesh.label_set(), vec![Label::new(0), Label::new(1)]);
}

// ----- pinching ---------------------------------------------------------------------------

#[test]
fn touching_tetrahedra_are_pinched_apart() {
    let mut mesh = bowtie();
    assert_eq!(irregular_vertices(&mesh), vec![VertexId::new(0)]);
    let mut guard = EndStateGuard { checked: 0 };
    let pinched = pinch_singular_vertices(&mut mesh, &mut VertexAttributes::none(), &mut guard);
    assert_eq!(guard.checked, 1);
    assert_eq!(pinched, 1);
    assert_eq!(mesh.num_vertices(), 8);
    assert_valid(&mesh, "after pinch");
    assert!(irregular_vertices(&mesh).is_empty());
    // Each copy of the centre is used by exactly one tetrahedron's three triangles.
    for v in [VertexId::new(0), VertexId::new(7)] {
        let mut others: Vec<u32> = mesh
            .vertex_triangles(v)
            .flat_map(|t| mesh.tri(t))
            .map(|w| w.raw())
            .collect();
        others.sort_unstable();
        others.dedup();
        assert_eq!(mesh.vertex_triangles(v).count(), 3);
        assert!(
            others == [0, 1, 2, 3] || others == [4, 5, 6, 7],
            "{v}: {others:?}"
        );
    }
}

// ----- vetoes -----------------------------------------------------------------------------

#[test]
fn vetoed_operations_leave_the_mesh_bit_identical() {
    let mut attrs = VertexAttributes::none();
    let params = SeparationParams::default();

    let mut mesh = crossed_quadrants();
    let before = mesh.to_raw();
    let report =
        separate_irregular_vertices(&mut mesh, &mut attrs, &mut VetoAll, &params, &shear(1.0));
    assert_eq!(report.separations, 0);
    assert_eq!(report.vetoed, 3, "{report:?}");
    assert_eq!(mesh.to_raw(), before);

    let middle = [
        ([1, 2, 3], [1, 3]),
        ([1, 3, 2], [2, 3]),
        ([1, 1, 4], [0, 1]),
    ];
    let mut mesh = bipyramid(1, 2, &middle);
    let before = mesh.to_raw();
    let report = remove_degenerate(&mut mesh, &mut attrs, &mut VetoAll);
    assert_eq!(report.vetoed, 2, "{report:?}");
    assert_eq!(mesh.to_raw(), before);

    let mut mesh = bowtie();
    let before = mesh.to_raw();
    assert_eq!(
        pinch_singular_vertices(&mut mesh, &mut attrs, &mut VetoAll),
        0
    );
    assert_eq!(mesh.to_raw(), before);
}
