//! Snap-merging tests: two spheres facing each other across a gap below the merge
//! distance, with equal and with different labels; far spheres; misaligned meshes.

use glam::{DQuat, DVec3};
use mesh_core::generators::icosphere;
use mesh_core::validate::{ValidateOptions, validate};
use mesh_core::{Label, LabeledMesh, TriId};

use mesh_core::remesh::VertexAttributes;

use super::{MergeError, MergeOptions, MergeReport, snap_merge, snap_merge_with};
use crate::guard::CollisionGuard;
use crate::guard::tests::union;

/// A unit icosphere (labels `[0, la]`) and its mirror image (labels `[0, lb]`) across the
/// plane parallel to the face of largest z, `gap` beyond it: the two faces are parallel,
/// `gap` apart, vertex over vertex. The mirror is turned by `twist` radians about the
/// face normal (through the face centroid) to misalign the meshes.
fn facing_spheres(gap: f64, la: u32, lb: u32, twist: f64) -> (LabeledMesh, MergeOptions) {
    let a = icosphere(2, DVec3::ZERO, 1.0, [Label::OUTSIDE, Label::new(la)]).expect("sphere");
    let top = a
        .triangles()
        .max_by(|&s, &t| centroid(&a, s).z.total_cmp(&centroid(&a, t).z))
        .expect("faces");
    let x = a.tri_positions(top);
    let n = (x[1] - x[0]).cross(x[2] - x[0]).normalize();
    let c = centroid(&a, top);
    let plane = n.dot(c) + 0.5 * gap;
    let turn = DQuat::from_axis_angle(n, twist);
    let (p, t, _) = a.to_raw();
    let mirrored: Vec<DVec3> = p
        .iter()
        .map(|&q| {
            let m = q - 2.0 * (q.dot(n) - plane) * n;
            let foot = c + n * gap;
            foot + turn * (m - foot)
        })
        .collect();
    // A mirror reverses orientation: reverse each triangle to keep normals outward.
    let tris: Vec<[u32; 3]> = t.iter().map(|&[i, j, k]| [i, k, j]).collect();
    let b = LabeledMesh::from_raw(mirrored, &tris, &vec![[0, lb]; tris.len()]).expect("mirror");
    let options = MergeOptions::for_mesh(&a);
    (union(&[a, b]), options)
}

fn centroid(m: &LabeledMesh, t: TriId) -> DVec3 {
    m.tri_positions(t).iter().sum::<DVec3>() / 3.0
}

fn assert_valid_and_clean(m: &LabeledMesh) {
    let v = validate(m, &ValidateOptions::with_intersections());
    assert!(v.is_valid(), "{v:?}");
    assert_eq!(v.self_intersecting_pairs.map(|p| p.count), Some(0));
}

fn merge(m: &mut LabeledMesh, o: &MergeOptions) -> MergeReport {
    snap_merge(m, o, &mut CollisionGuard::new()).expect("merge")
}

#[test]
fn equal_labels_merge_into_one_region() {
    let (mut m, o) = facing_spheres(0.003, 1, 1, 0.0);
    assert!(0.003 < o.merge_distance, "{o:?}");
    assert_valid_and_clean(&m);
    assert_eq!(m.regions().bounded().count(), 2);
    let r = merge(&mut m, &o);
    assert_valid_and_clean(&m);
    assert_eq!(r.snaps, 3, "{r:?}");
    assert_eq!(r.degenerate.pairs_removed, 1, "{r:?}");
    assert_eq!((r.merges, r.new_interfaces), (1, 0), "{r:?}");
    let bounded: Vec<_> = m.regions().bounded().cloned().collect();
    assert_eq!(bounded.len(), 1);
    assert_eq!(bounded[0].label, Label::new(1));
}

#[test]
fn different_labels_get_a_shared_interface_and_a_triple_curve() {
    let (mut m, o) = facing_spheres(0.003, 1, 2, 0.0);
    let r = merge(&mut m, &o);
    assert_valid_and_clean(&m);
    assert_eq!(r.degenerate.pairs_relabelled, 1, "{r:?}");
    assert_eq!((r.merges, r.new_interfaces), (0, 1), "{r:?}");
    let shared: Vec<TriId> = m
        .triangles()
        .filter(|&t| {
            let [a, b] = m.labels(t);
            (a.raw().min(b.raw()), a.raw().max(b.raw())) == (1, 2)
        })
        .collect();
    assert_eq!(shared.len(), 1);
    let v = m.tri(shared[0]);
    for k in 0..3 {
        let n = m.edge_triangles(v[k], v[(k + 1) % 3]).count();
        assert_eq!(n, 3, "each edge of the interface is on the triple curve");
    }
    assert_eq!(m.regions().bounded().count(), 2);
}

#[test]
fn misaligned_meshes_split_and_snap_and_stay_clean() {
    let (mut m, o) = facing_spheres(0.003, 1, 1, 0.5);
    let r = merge(&mut m, &o);
    assert_valid_and_clean(&m);
    assert!(r.snaps > 0, "{r:?}");
    assert!(r.edge_splits + r.face_splits > 0, "{r:?}");
    // The two interiors are one region (a sliver of the outside may stay trapped between
    // the sheets as its own small region, for later T2 removal).
    assert_eq!(r.merges, 1, "{r:?}");
    let ones = m
        .regions()
        .bounded()
        .filter(|s| s.label == Label::new(1))
        .count();
    assert_eq!(ones, 1);
}

#[test]
fn far_spheres_are_untouched() {
    let (m0, o) = facing_spheres(0.1, 1, 2, 0.0);
    let mut m = m0.clone();
    let r = merge(&mut m, &o);
    assert_eq!(
        r,
        MergeReport {
            rounds: 1,
            ..MergeReport::default()
        }
    );
    assert_eq!(m.to_raw(), m0.to_raw());
    // A far third sphere next to a merging pair keeps every vertex and triangle.
    let (pair, o) = facing_spheres(0.003, 1, 2, 0.0);
    let far = icosphere(
        1,
        DVec3::new(5.0, 0.0, 0.0),
        1.0,
        [Label::OUTSIDE, Label::new(3)],
    )
    .expect("sphere");
    let first = pair.vertex_capacity() as u32;
    let first_tri = pair.triangle_capacity();
    let scene = union(&[pair, far.clone()]);
    let mut m = scene.clone();
    merge(&mut m, &o);
    for v in far.vertices() {
        let id = mesh_core::VertexId::new(first + v.raw());
        assert_eq!(m.position(id), far.position(v));
    }
    for t in far.triangles() {
        let id = TriId::new((first_tri + t.idx()) as u32);
        assert!(m.is_triangle_alive(id));
        assert_eq!(
            m.tri(id).map(|v| v.raw() - first),
            far.tri(t).map(|v| v.raw())
        );
    }
}

#[test]
fn invalid_distance_is_an_error() {
    let (mut m, mut o) = facing_spheres(0.003, 1, 1, 0.0);
    o.merge_distance = f64::NAN;
    let e = snap_merge(&mut m, &o, &mut CollisionGuard::new());
    assert!(matches!(e, Err(MergeError::InvalidOption { .. })));
}

/// The approach gate (`min_approach`): facing spheres within the merge distance merge only
/// when the displacement carried as attributes brings them together; at rest, or moving
/// apart, nothing changes.
#[test]
fn only_approaching_surfaces_merge_under_the_approach_gate() {
    let (m0, mut o) = facing_spheres(0.003, 1, 1, 0.0);
    o.min_approach = Some(1e-6);
    let half = m0.num_vertices() / 2;
    for (speed, merges) in [(0.0, false), (-0.01, false), (0.01, true)] {
        let mut m = m0.clone();
        let mut motion = VertexAttributes::zeros(&m, 3);
        let centre = |range: std::ops::Range<usize>| {
            range.clone().map(|i| m0.positions()[i]).sum::<DVec3>() / range.len() as f64
        };
        // Each sphere moves towards (speed > 0) or away from the other.
        let towards = (centre(half..2 * half) - centre(0..half)).normalize();
        for v in m.vertices() {
            let u = if v.idx() < half { towards } else { -towards } * speed;
            motion.get_mut(v).copy_from_slice(&u.to_array());
        }
        let r =
            snap_merge_with(&mut m, &mut motion, &o, &mut CollisionGuard::new()).expect("merge");
        assert_valid_and_clean(&m);
        assert_eq!(r.snaps > 0, merges, "speed {speed}: {r:?}");
        if !merges {
            assert!(r.not_approaching > 0, "{r:?}");
            assert_eq!(m.to_raw(), m0.to_raw());
        }
    }
}

/// Vetoes every snap (an edit that deletes a vertex onto another), allows the rest.
struct VetoSnaps;

impl mesh_core::remesh::EditGuard for VetoSnaps {
    fn check(
        &mut self,
        _m: &LabeledMesh,
        e: &mesh_core::remesh::Edit,
    ) -> Result<(), mesh_core::remesh::Veto> {
        if e.remove_vertices.is_empty() || e.moves.is_empty() {
            Ok(())
        } else {
            Err(mesh_core::remesh::Veto::Other("no snaps in this test"))
        }
    }
}

#[test]
fn splits_for_a_vetoed_snap_are_undone() {
    let (m0, o) = facing_spheres(0.003, 1, 1, 0.5);
    let mut m = m0.clone();
    let r = snap_merge(&mut m, &o, &mut VetoSnaps).expect("merge");
    assert_eq!(r.snaps, 0, "{r:?}");
    assert!(r.edge_splits + r.face_splits > 0, "{r:?}");
    assert_eq!(r.undone_splits, r.edge_splits + r.face_splits, "{r:?}");
    assert_eq!(m.num_vertices(), m0.num_vertices());
    assert_eq!(m.num_triangles(), m0.num_triangles());
    for v in m0.vertices() {
        assert_eq!(m.position(v), m0.position(v));
    }
    assert_valid_and_clean(&m);
}
