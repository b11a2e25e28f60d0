//! Guard tests. The tunnelling scenes are built so that the end state is clean (the static
//! guard accepts them, which each test asserts): only the sweep can catch them, so every
//! test here fails if the CCD part of the guard is removed.

use glam::DVec3;
use mesh_core::generators::icosphere;
use mesh_core::remesh::{
    Blend, Edit, EditError, EditGuard, FeatureParams, ImproveParams, ImproveReport, NewVertex,
    NoGuard, StaticIntersectionGuard, VertexAttributes, VertexMove, VertexRef, apply_edit, improve,
};
use mesh_core::validate::{ValidateOptions, validate};
use mesh_core::{Label, LabeledMesh, TriId, VertexId};

use super::{CollisionGuard, CollisionGuardOptions};

/// The union of several meshes (vertex and triangle ids offset in order).
pub(crate) fn union(parts: &[LabeledMesh]) -> LabeledMesh {
    LabeledMesh::disjoint_union(parts).expect("union of valid meshes")
}

fn sphere(sub: u32, c: DVec3, r: f64, labels: [u32; 2]) -> LabeledMesh {
    icosphere(sub, c, r, labels.map(Label::new)).expect("icosphere")
}

fn intersections(mesh: &LabeledMesh) -> usize {
    validate(mesh, &ValidateOptions::with_intersections())
        .self_intersecting_pairs
        .map_or(0, |p| p.count)
}

/// Applies `edit` to a copy of `mesh` under each guard; returns (static ok, collision ok,
/// unguarded result intersects).
fn outcomes(mesh: &LabeledMesh, edit: &Edit) -> (bool, bool, bool) {
    let run = |g: &mut dyn EditGuard| {
        let mut m = mesh.clone();
        let r = apply_edit(&mut m, &mut VertexAttributes::none(), g, edit);
        (r, m)
    };
    let (stat, _) = run(&mut StaticIntersectionGuard::new());
    let (coll, _) = run(&mut CollisionGuard::new());
    let (free, m) = run(&mut NoGuard);
    assert!(free.is_ok());
    (stat.is_ok(), coll.is_ok(), intersections(&m) > 0)
}

/// The top vertex of a sphere (largest z).
fn top(mesh: &LabeledMesh) -> VertexId {
    mesh.vertices()
        .max_by(|a, b| mesh.position(*a).z.total_cmp(&mesh.position(*b).z))
        .expect("vertices")
}

fn move_edit(v: VertexId, end: DVec3) -> Edit {
    Edit {
        moves: vec![VertexMove {
            vertex: v,
            end,
            blend: None,
        }],
        ..Edit::default()
    }
}

#[test]
fn smoothing_move_through_a_small_sphere_is_vetoed() {
    let big = sphere(2, DVec3::ZERO, 1.0, [0, 1]);
    let v = top(&big);
    let p = big.position(v);
    // A small sphere just outside the vertex; the move pushes the fan past it, so that it
    // ends inside the big sphere without touching anything.
    let mesh = union(&[big, sphere(0, p * 1.03, 0.008, [0, 2])]);
    let (stat, coll, _) = outcomes(&mesh, &move_edit(v, p * 1.08));
    assert!(
        stat,
        "the end state is clean: only the sweep sees the collision"
    );
    assert!(!coll, "the sweep passes through the small sphere");
    // A small move that stops short of it is fine.
    let (_, coll, _) = outcomes(&mesh, &move_edit(v, p * 1.01));
    assert!(coll);
}

#[test]
fn smoothing_move_through_a_sheet_is_vetoed() {
    let a = sphere(2, DVec3::ZERO, 1.0, [0, 1]);
    let v = top(&a);
    let p = a.position(v);
    let mesh = union(&[a, sphere(2, DVec3::new(0.0, 0.0, 2.05), 1.0, [0, 2])]);
    let (stat, coll, crossed) = outcomes(&mesh, &move_edit(v, p * 1.2));
    assert!(crossed && !stat && !coll);
}

/// Split of edge `{a, b}` with the new vertex moving from the midpoint to `end`.
fn split_edit(mesh: &LabeledMesh, a: VertexId, b: VertexId, end: DVec3) -> Edit {
    let mid = (mesh.position(a) + mesh.position(b)) * 0.5;
    let mut edit = Edit {
        new_vertices: vec![NewVertex {
            start: mid,
            end,
            blend: Blend::lerp(a, b, 0.5),
        }],
        ..Edit::default()
    };
    for t in mesh.edge_triangles(a, b).collect::<Vec<_>>() {
        edit.remove_tris.push(t);
        let tri = mesh.tri(t).map(VertexRef::Old);
        for r in [a, b] {
            let half = tri.map(|x| {
                if x == VertexRef::Old(r) {
                    VertexRef::New(0)
                } else {
                    x
                }
            });
            edit.add_tris.push((half, mesh.labels(t)));
        }
    }
    edit
}

fn neighbour(mesh: &LabeledMesh, v: VertexId) -> VertexId {
    mesh.vertex_triangles(v)
        .flat_map(|t| mesh.tri(t))
        .find(|&w| w != v)
        .expect("neighbour")
}

#[test]
fn split_vertex_pushed_through_a_small_sphere_is_vetoed() {
    let big = sphere(2, DVec3::ZERO, 1.0, [0, 1]);
    let a = top(&big);
    let b = neighbour(&big, a);
    let mid = (big.position(a) + big.position(b)) * 0.5;
    let dir = mid.normalize();
    let mesh = union(&[big, sphere(0, dir * 1.02, 0.006, [0, 2])]);
    let (stat, coll, _) = outcomes(&mesh, &split_edit(&mesh, a, b, dir * 1.06));
    assert!(stat && !coll);
    // The midpoint split is always safe.
    let (_, coll, _) = outcomes(&mesh, &split_edit(&mesh, a, b, mid));
    assert!(coll);
}

/// Collapse of `b` onto `a`'s position.
fn collapse_edit(mesh: &LabeledMesh, a: VertexId, b: VertexId) -> Edit {
    let mut edit = Edit::default();
    for t in mesh.vertex_triangles(b).collect::<Vec<_>>() {
        edit.remove_tris.push(t);
        let tri = mesh.tri(t);
        if !tri.contains(&a) {
            edit.add_tris.push((
                tri.map(|w| VertexRef::Old(if w == b { a } else { w })),
                mesh.labels(t),
            ));
        }
    }
    edit.moves.push(VertexMove {
        vertex: b,
        end: mesh.position(a),
        blend: None,
    });
    edit.remove_vertices.push(b);
    edit
}

#[test]
fn collapse_sweeping_over_a_small_sphere_is_vetoed() {
    let big = sphere(2, DVec3::ZERO, 1.0, [0, 1]);
    let b = top(&big);
    let a = neighbour(&big, b);
    let pb = big.position(b);
    // Just under b, inside the big sphere: after the collapse the flatter fan passes below
    // it, leaving it outside.
    let small = sphere(0, pb * 0.988, 0.004, [1, 2]);
    let mesh = union(&[big, small]);
    let edit = collapse_edit(&mesh, a, b);
    let (stat, coll, _) = outcomes(&mesh, &edit);
    assert!(stat, "the end state is clean");
    assert!(!coll, "b's fan sweeps over the small sphere");
    // Without the small sphere the same collapse passes.
    let alone = sphere(2, DVec3::ZERO, 1.0, [0, 1]);
    let (_, coll, _) = outcomes(&alone, &collapse_edit(&alone, a, b));
    assert!(coll);
}

#[test]
fn flip_over_a_small_sphere_is_vetoed() {
    let big = sphere(1, DVec3::ZERO, 1.0, [0, 1]);
    let a = top(&big);
    let b = neighbour(&big, a);
    let tris: Vec<TriId> = big.edge_triangles(a, b).collect();
    let far = |t: TriId| {
        big.tri(t)
            .into_iter()
            .find(|&w| w != a && w != b)
            .expect("third vertex")
    };
    let (x, y) = (far(tris[0]), far(tris[1]));
    let corners = [a, b, x, y].map(|v| big.position(v));
    let centroid = corners.iter().sum::<DVec3>() / 4.0;
    let small = sphere(0, centroid, 0.002, [1, 2]);
    let mesh = union(&[big.clone(), small]);
    // The flip, oriented like the old triangles.
    let mut edit = Edit::default();
    edit.remove_tris.extend(&tris);
    let labels = mesh.labels(tris[0]);
    let t0 = mesh.tri(tris[0]);
    let k = t0.iter().position(|&w| w == x).expect("x on t0");
    let (p, q) = (t0[(k + 1) % 3], t0[(k + 2) % 3]);
    edit.add_tris.push(([x, p, y].map(VertexRef::Old), labels));
    edit.add_tris.push(([y, q, x].map(VertexRef::Old), labels));
    let (stat, coll, _) = outcomes(&mesh, &edit);
    assert!(stat && !coll);
    let (_, coll, _) = outcomes(&big, &edit);
    assert!(coll, "the same flip without the small sphere passes");
}

#[test]
fn minimum_distance_option_refuses_close_approaches() {
    let a = sphere(2, DVec3::ZERO, 1.0, [0, 1]);
    let v = top(&a);
    let p = a.position(v);
    let mesh = union(&[a, sphere(2, DVec3::new(0.0, 0.0, 2.1), 1.0, [0, 2])]);
    // Ends 0.02 below the other sphere's bottom vertex.
    let edit = move_edit(v, p * 1.08);
    let mut plain = CollisionGuard::new();
    assert!(plain.check(&mesh, &edit).is_ok());
    let mut strict = CollisionGuard::with_options(CollisionGuardOptions {
        min_distance: Some(0.05),
        ..CollisionGuardOptions::default()
    });
    assert!(strict.check(&mesh, &edit).is_err());
    assert_eq!(strict.stats().vetoed_proximity, 1);
    // Moving away is fine even when already close.
    assert!(strict.check(&mesh, &move_edit(v, p * 0.99)).is_ok());
}

/// A split vertex starts where it ends, so "it started at least that close" cannot excuse
/// it: a split whose new vertex lands within the minimum distance of another surface is
/// refused (the state the next step's CCD would find in contact), and allowed without the
/// option.
#[test]
fn minimum_distance_refuses_a_split_vertex_born_next_to_another_surface() {
    let big = sphere(1, DVec3::ZERO, 1.0, [0, 1]);
    let a = top(&big);
    let b = neighbour(&big, a);
    let mid = (big.position(a) + big.position(b)) * 0.5;
    let n = mid.normalize();
    // A small tetrahedron with one corner 1e-5 outside the chord's midpoint.
    let tip = mid + n * 1e-5;
    let (u, w) = (
        n.any_orthonormal_vector(),
        n.cross(n.any_orthonormal_vector()),
    );
    let tet = LabeledMesh::from_raw(
        vec![
            tip,
            tip + n * 0.1 + u * 0.05,
            tip + n * 0.1 - u * 0.03 + w * 0.05,
            tip + n * 0.1 - u * 0.03 - w * 0.05,
        ],
        &[[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]],
        &[[0, 2]; 4],
    )
    .expect("tet");
    let mesh = union(&[big, tet]);
    assert_eq!(intersections(&mesh), 0);
    let split = |guard: &mut CollisionGuard| {
        let mut m = mesh.clone();
        mesh_core::remesh::split_edge_at(&mut m, &mut VertexAttributes::none(), guard, a, b, 0.5)
    };
    assert!(split(&mut CollisionGuard::new()).is_ok());
    let mut strict = CollisionGuard::with_options(CollisionGuardOptions {
        min_distance: Some(1e-3),
        ..CollisionGuardOptions::default()
    });
    assert!(split(&mut strict).is_err());
    assert_eq!(strict.stats().vetoed_proximity, 1);
}

/// The same for a flip: nothing moves, so the new diagonal would "start" as close as it
/// ends. A flip whose new diagonal passes 1e-5 from another surface's edge (which is
/// farther from the two old triangles) is refused with the minimum distance.
#[test]
fn minimum_distance_refuses_a_flip_diagonal_next_to_another_surface() {
    let big = sphere(2, DVec3::ZERO, 1.0, [0, 1]);
    let a = top(&big);
    let c = neighbour(&big, a);
    let fan: Vec<TriId> = big.edge_triangles(a, c).collect();
    assert_eq!(fan.len(), 2);
    // Rotate each triangle to start at the edge's first end along its orientation.
    let rotated = |t: TriId| {
        let v = big.tri(t);
        let k = (0..3)
            .find(|&k| (v[k] == a || v[k] == c) && (v[(k + 1) % 3] == a || v[(k + 1) % 3] == c))
            .expect("edge in triangle");
        [v[k], v[(k + 1) % 3], v[(k + 2) % 3]]
    };
    let ([p, q, b], [_, _, d]) = (rotated(fan[0]), rotated(fan[1]));
    let labels = big.labels(fan[0]);
    let (xb, xd) = (big.position(b), big.position(d));
    let m = (xb + xd) * 0.5;
    let n = -m.normalize();
    let e = (xd - xb).normalize();
    let w = e.cross(n).normalize();
    // A small tetrahedron inside the sphere, one edge 1e-5 under the new diagonal.
    let o = m + n * 1e-5;
    let pts = vec![
        o - w * 0.01,
        o + w * 0.01,
        m + n * 0.05,
        m + n * 0.05 + e * 0.02,
    ];
    let faces = [[0u32, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]];
    let flipped: Vec<[u32; 3]> = faces.iter().map(|&[i, j, k]| [i, k, j]).collect();
    let tet = [faces.to_vec(), flipped]
        .into_iter()
        .filter_map(|f| LabeledMesh::from_raw(pts.clone(), &f, &[[1, 2]; 4]).ok())
        .map(|t| union(&[big.clone(), t]))
        .find(|m| validate(m, &ValidateOptions::with_intersections()).is_valid())
        .expect("a valid union with the tetrahedron inside");
    let edit = Edit {
        remove_tris: fan.clone(),
        // Edge p→q of the first triangle becomes b→d: [b, p, d] and [d, q, b].
        add_tris: vec![
            ([b, p, d].map(VertexRef::Old), labels),
            ([d, q, b].map(VertexRef::Old), labels),
        ],
        ..Edit::default()
    };
    assert!(CollisionGuard::new().check(&tet, &edit).is_ok());
    let mut strict = CollisionGuard::with_options(CollisionGuardOptions {
        min_distance: Some(1e-3),
        ..CollisionGuardOptions::default()
    });
    assert!(strict.check(&tet, &edit).is_err());
    assert_eq!(strict.stats().vetoed_proximity, 1);
}

/// A coarse sphere and a small one hovering over an edge midpoint, in the gap between the
/// coarse sphere's chord and the round surface the butterfly split restores: unguarded,
/// improvement pushes the split vertex into the small sphere; guarded, the split falls
/// back to the midpoint and the result is valid and exactly intersection-free.
#[test]
fn improve_next_to_a_close_sphere_stays_intersection_free() {
    let big = sphere(1, DVec3::ZERO, 1.0, [0, 1]);
    let a = top(&big);
    let b = neighbour(&big, a);
    let dir = ((big.position(a) + big.position(b)) * 0.5).normalize();
    let mesh = union(&[big, sphere(1, dir * 1.06, 0.1, [0, 2])]);
    assert_eq!(intersections(&mesh), 0);
    let params = ImproveParams {
        target_edge_length: Some(0.3),
        max_volume_change: Some(1.0),
        collapse: false,
        max_sweeps: 2,
        // Read the coarse sphere as smooth, so that splits take the butterfly position.
        features: FeatureParams {
            rank_ratio: 0.5,
            ..FeatureParams::default()
        },
        ..ImproveParams::default()
    };
    let mut free = mesh.clone();
    improve(
        &mut free,
        &params,
        &mut VertexAttributes::none(),
        &mut NoGuard,
    );
    assert!(
        intersections(&free) > 0,
        "the scene must provoke a collision"
    );

    let mut guarded = mesh.clone();
    let mut guard = CollisionGuard::new();
    let report = improve(
        &mut guarded,
        &params,
        &mut VertexAttributes::none(),
        &mut guard,
    );
    assert!(report.split.done > 50, "{report:?}");
    let stats = guard.stats();
    assert!(stats.vetoed_ccd + stats.vetoed_end_state > 0, "{stats:?}");
    let v = validate(&guarded, &ValidateOptions::with_intersections());
    assert!(v.is_valid(), "{v:?}");
}

/// On a lone sphere nothing can collide: the guard refuses no improvement edit, and the
/// index stays current through hundreds of committed edits.
#[test]
fn safe_edits_pass() {
    let mut mesh = sphere(2, DVec3::ZERO, 1.0, [0, 1]);
    let params = ImproveParams {
        target_edge_length: Some(0.12),
        ..ImproveParams::default()
    };
    let mut guard = CollisionGuard::new();
    let report = improve(
        &mut mesh,
        &params,
        &mut VertexAttributes::none(),
        &mut guard,
    );
    let stats = guard.stats();
    assert!(stats.checked > 300, "{stats:?}");
    let vetoed = report.split.vetoed + report.collapse.vetoed + report.flip.vetoed;
    assert!(
        vetoed * 50 <= stats.checked as usize,
        "at most 2 % vetoed on a lone sphere: {report:?} {stats:?}"
    );
    assert!(validate(&mesh, &ValidateOptions::with_intersections()).is_valid());
}

#[test]
fn vetoed_edit_leaves_mesh_unchanged() {
    let a = sphere(2, DVec3::ZERO, 1.0, [0, 1]);
    let v = top(&a);
    let p = a.position(v);
    let mesh = union(&[a, sphere(0, p * 1.03, 0.008, [0, 2])]);
    let mut m = mesh.clone();
    let r = apply_edit(
        &mut m,
        &mut VertexAttributes::none(),
        &mut CollisionGuard::new(),
        &move_edit(v, p * 1.08),
    );
    assert!(matches!(r, Err(EditError::Vetoed(_))));
    assert_eq!(m.to_raw(), mesh.to_raw());
}

/// A Voronoi foam (non-manifold triple curves and quadruple points) coarsened with every
/// operation under the guard: nothing can collide there, so the guard refuses nothing the
/// unguarded run does, and the result is valid and intersection-free.
#[test]
fn foam_coarsening_passes_the_guard_unchanged() {
    let foam = mesh_core::generators::voronoi_foam(6, 3, DVec3::ZERO, DVec3::ONE).expect("foam");
    let params = ImproveParams {
        target_edge_length: Some(0.35),
        max_sweeps: 4,
        ..ImproveParams::default()
    };
    let mut free = foam.clone();
    let unguarded = improve(
        &mut free,
        &params,
        &mut VertexAttributes::none(),
        &mut NoGuard,
    );
    let mut m = foam.clone();
    let mut guard = CollisionGuard::new();
    let guarded = improve(&mut m, &params, &mut VertexAttributes::none(), &mut guard);
    assert!(
        guarded.collapse.done > 0 && guarded.flip.done > 0,
        "{guarded:?}"
    );
    assert_eq!(m.to_raw(), free.to_raw());
    // Same mesh, same counts. The volume bound is a sum along the path: a smoothing move
    // the guard checks alone (it blames every move of a multi-move batch) measures its
    // volume change against neighbours the rest of its batch has already moved, where
    // the unguarded batch measured all of them against the old positions.
    let bound = (guarded.volume_change_bound, unguarded.volume_change_bound);
    assert!((bound.0 - bound.1).abs() <= 0.01 * bound.1, "{bound:?}");
    let same_bound = ImproveReport {
        volume_change_bound: unguarded.volume_change_bound,
        ..guarded
    };
    assert_eq!(same_bound, unguarded);
    let v = validate(&m, &ValidateOptions::with_intersections());
    assert!(v.is_valid(), "{v:?}");
}

/// Two tetrahedra touching at a vertex (the bowtie): vertex separation (T1) and pinching
/// create a vertex at the touching vertex and pull the copies apart — pairs incident at
/// the start, which the guard must hand to the static checks instead of vetoing.
fn bowtie() -> LabeledMesh {
    let p = vec![
        DVec3::ZERO,
        DVec3::X,
        DVec3::Y,
        DVec3::Z,
        -DVec3::X,
        -DVec3::Y,
        -DVec3::Z,
    ];
    let tris = [
        [0, 2, 1],
        [0, 1, 3],
        [0, 3, 2],
        [1, 2, 3],
        [0, 4, 5],
        [0, 6, 4],
        [0, 5, 6],
        [4, 6, 5],
    ];
    LabeledMesh::from_raw(p, &tris, &[[0, 1]; 8]).expect("bowtie")
}

#[test]
fn separation_and_pinching_pass_the_guard() {
    use mesh_core::remesh::{
        AreaDecrease, SeparationParams, pinch_singular_vertices, separate_irregular_vertices,
    };
    let mut m = bowtie();
    let r = separate_irregular_vertices(
        &mut m,
        &mut VertexAttributes::none(),
        &mut CollisionGuard::new(),
        &SeparationParams::default(),
        &AreaDecrease,
    );
    assert_eq!((r.separations, r.vetoed), (1, 0), "{r:?}");
    assert!(validate(&m, &ValidateOptions::with_intersections()).is_valid());

    let mut m = bowtie();
    let pinched = pinch_singular_vertices(
        &mut m,
        &mut VertexAttributes::none(),
        &mut CollisionGuard::new(),
    );
    assert_eq!(pinched, 1);
    assert_eq!(m.num_vertices(), 8);
    assert!(validate(&m, &ValidateOptions::with_intersections()).is_valid());
}

/// Improvement by blocks under the collision guard, with a block border running through
/// the gap between two close spheres (refined to half their edge length, so hundreds of
/// splits and moves happen next to the border): the result is exactly intersection-free
/// and no vertex of one sphere comes closer than the guard's minimum distance to a
/// triangle of the other. (This scene does not push the two sides towards each other, so
/// it passes with a zero margin too; what the margin adds is argued in `blocks`' doc.)
#[test]
fn blocks_next_to_a_close_surface_stay_intersection_free_and_apart() {
    use crate::proximity::proximity_vertex_triangle;
    use mesh_core::remesh::{BlockParams, ImproveRegion, improve_in_blocks};

    let (gap, d) = (0.02, 0.01);
    let c = 1.0 + 0.5 * gap;
    let mesh = union(&[
        sphere(3, DVec3::new(-c, 0.0, 0.0), 1.0, [0, 1]),
        sphere(3, DVec3::new(c, 0.0, 0.0), 1.0, [0, 2]),
    ]);
    let params = ImproveParams {
        target_edge_length: Some(0.08),
        max_sweeps: 2,
        ..ImproveParams::default()
    };
    // Blocks of 0.32: the lattice starts at x = −2.24, so a border lies at x = 0, in the
    // gap.
    let blocks = BlockParams {
        block_edges: 4.0,
        min_work: 0,
        margin: d,
        ..BlockParams::default()
    };
    let options = CollisionGuardOptions {
        min_distance: Some(d),
        ..CollisionGuardOptions::default()
    };
    let make_guard =
        move || -> Box<dyn EditGuard> { Box::new(CollisionGuard::with_options(options)) };
    let mut m = mesh.clone();
    let r = improve_in_blocks(
        &mut m,
        &params,
        ImproveRegion::Whole,
        None,
        &mut VertexAttributes::none(),
        &blocks,
        &make_guard,
    );
    assert!(r.blocks > 10 && r.split.done > 100, "{r:?}");
    let v = validate(&m, &ValidateOptions::with_intersections());
    assert!(v.is_valid(), "{v:?}");
    // Vertices near the gap against the other sphere's triangles near it.
    let near = |t: TriId| m.tri_positions(t).iter().all(|p| p.x.abs() < 0.3);
    let side = |t: TriId| m.labels(t)[1].raw();
    let mut closest = f64::INFINITY;
    for t in m.triangles().filter(|&t| near(t)) {
        for u in m.triangles().filter(|&u| near(u) && side(u) != side(t)) {
            for p in m.tri_positions(u) {
                closest = closest.min(proximity_vertex_triangle(p, m.tri_positions(t)).distance);
            }
        }
    }
    assert!(
        closest >= d * (1.0 - 1e-9),
        "a vertex {closest} from the other sphere"
    );
}
