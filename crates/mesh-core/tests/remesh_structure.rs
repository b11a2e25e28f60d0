//! Edit sequences and batches that would break a mesh if the per-edit structural check or
//! the batch guard were wrong.
//!
//! - Random edits (vertex moves of up to an edge length, splits, flips, collapses) on a
//!   double bubble, whose triple curve makes non-manifold edges a fold can reorder: after
//!   every committed edit the mesh validates (labels and radial order included). Without
//!   `apply_edit`'s structural check the moves next to the triple curve leave
//!   inconsistent wedges within a few dozen edits.
//! - Batches of random moves on two nearly touching spheres through
//!   `StaticIntersectionGuard::offending_moves`: once the guard clears what is left of a
//!   batch, its end state is exactly intersection-free, and every move committed alone
//!   after a per-move `check` is too.

use glam::DVec3;
use mesh_core::generators::{double_bubble, icosphere};
use mesh_core::remesh::{
    CollapseParams, Edit, EditGuard, FlipParams, NoGuard, SplitPlacement, StaticIntersectionGuard,
    VertexAttributes, VertexMove, apply_edit, collapse_edge, flip_edge, split_edge,
};
use mesh_core::validate::{ValidateOptions, validate};
use mesh_core::{Label, LabeledMesh, VertexId};

/// A small deterministic generator (SplitMix64): seeded cases, no dependency.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }

    fn vector(&mut self) -> DVec3 {
        DVec3::new(
            2.0 * self.unit() - 1.0,
            2.0 * self.unit() - 1.0,
            2.0 * self.unit() - 1.0,
        )
    }
}

fn mean_edge(mesh: &LabeledMesh) -> f64 {
    mesh_core::remesh::improve::mean_edge_length(mesh)
}

/// A random edge `(a, b)` of a random live triangle.
fn random_edge(mesh: &LabeledMesh, rng: &mut Rng) -> (VertexId, VertexId) {
    let tris: Vec<_> = mesh.triangles().collect();
    let t = tris[rng.below(tris.len())];
    let [a, b, c] = mesh.tri(t);
    match rng.below(3) {
        0 => (a, b),
        1 => (b, c),
        _ => (c, a),
    }
}

#[test]
fn random_edit_sequences_keep_a_multi_material_mesh_valid_after_every_edit() {
    // Layers 1–3: without a guard, moves pass sheets through each other, and placement
    // (layer 4) is only defined for meshes that do not intersect themselves.
    let layers = ValidateOptions {
        placement: false,
        ..ValidateOptions::default()
    };
    let mut committed_moves = 0;
    let mut refused = 0;
    for seed in 0..6u64 {
        let mut mesh = double_bubble(0.5, 10).expect("double bubble");
        assert!(validate(&mesh, &layers).is_valid());
        let mut rng = Rng(seed);
        let scale = mean_edge(&mesh);
        let mut attrs = VertexAttributes::none();
        for step in 0..300 {
            let before = mesh.to_raw();
            let ok = match rng.below(5) {
                // Moves dominate: they are what folds a sheet past its neighbour.
                0 | 1 => {
                    let live: Vec<VertexId> = mesh.vertices().collect();
                    let v = live[rng.below(live.len())];
                    let edit = Edit {
                        moves: vec![VertexMove {
                            vertex: v,
                            end: mesh.position(v) + rng.vector() * scale,
                            blend: None,
                        }],
                        ..Edit::default()
                    };
                    let ok = apply_edit(&mut mesh, &mut attrs, &mut NoGuard, &edit).is_ok();
                    committed_moves += usize::from(ok);
                    ok
                }
                2 => {
                    let (a, b) = random_edge(&mesh, &mut rng);
                    split_edge(
                        &mut mesh,
                        &mut attrs,
                        &mut NoGuard,
                        a,
                        b,
                        SplitPlacement::Midpoint,
                    )
                    .is_ok()
                }
                3 => {
                    let (a, b) = random_edge(&mesh, &mut rng);
                    flip_edge(
                        &mut mesh,
                        &mut attrs,
                        &mut NoGuard,
                        a,
                        b,
                        &FlipParams::default(),
                    )
                    .is_ok()
                }
                _ => {
                    let (a, b) = random_edge(&mesh, &mut rng);
                    collapse_edge(
                        &mut mesh,
                        &mut attrs,
                        &mut NoGuard,
                        a,
                        b,
                        &CollapseParams::default(),
                    )
                    .is_ok()
                }
            };
            if !ok {
                refused += 1;
                assert_eq!(mesh.to_raw(), before, "a refused edit changed the mesh");
                continue;
            }
            let report = validate(&mesh, &layers);
            assert!(
                report.is_valid(),
                "seed {seed}, edit {step}: the mesh is invalid after a committed edit: {report}"
            );
        }
    }
    // The sequences did something, and the check did refuse edits.
    assert!(
        committed_moves > 300 && refused > 0,
        "{committed_moves} moves, {refused} refused"
    );
}

/// Two spheres of different materials, a tenth of an edge apart.
fn touching_spheres() -> LabeledMesh {
    let a = icosphere(3, DVec3::ZERO, 1.0, [Label::new(0), Label::new(1)]).expect("sphere");
    let gap = 0.1 * mean_edge(&a);
    let b = icosphere(
        3,
        DVec3::new(2.0 + gap, 0.0, 0.0),
        1.0,
        [Label::new(0), Label::new(2)],
    )
    .expect("sphere");
    let (mut p, mut t, mut l) = a.to_raw();
    let (pb, tb, lb) = b.to_raw();
    let base = p.len() as u32;
    p.extend(pb);
    t.extend(tb.iter().map(|tri| tri.map(|v| v + base)));
    l.extend(lb);
    LabeledMesh::from_raw(p, &t, &l).expect("two spheres")
}

/// An independent set of random moves (no two share a triangle), up to `n` of them.
fn random_batch(mesh: &LabeledMesh, rng: &mut Rng, n: usize, reach: f64) -> Edit {
    let mut claimed = vec![false; mesh.triangle_capacity()];
    let live: Vec<VertexId> = mesh.vertices().collect();
    let mut edit = Edit::default();
    for _ in 0..4 * n {
        let v = live[rng.below(live.len())];
        if edit.moves.len() == n || mesh.vertex_triangles(v).any(|t| claimed[t.idx()]) {
            continue;
        }
        mesh.vertex_triangles(v)
            .for_each(|t| claimed[t.idx()] = true);
        edit.moves.push(VertexMove {
            vertex: v,
            end: mesh.position(v) + rng.vector() * reach,
            blend: None,
        });
    }
    edit
}

#[test]
fn batched_guard_checks_never_clear_an_intersecting_state() {
    let exact = ValidateOptions::with_intersections();
    let mut mesh = touching_spheres();
    assert!(validate(&mesh, &exact).is_valid());
    let reach = 0.6 * mean_edge(&mesh);
    let mut guard = StaticIntersectionGuard::new();
    let mut attrs = VertexAttributes::none();
    let mut rng = Rng(11);
    let (mut batched, mut alone, mut blamed_total, mut intersecting_batches) = (0, 0, 0, 0);
    for round in 0..40 {
        let mut edit = random_batch(&mesh, &mut rng, 64, reach);
        // Would the whole batch intersect? (It must, sometimes, or the test shows nothing.)
        let mut probe = mesh.clone();
        apply_edit(
            &mut probe,
            &mut VertexAttributes::none(),
            &mut NoGuard,
            &edit,
        )
        .ok();
        if !validate(&probe, &exact).is_valid() {
            intersecting_batches += 1;
        }
        let mut blamed_moves = Vec::new();
        let mut cleared = false;
        for _ in 0..8 {
            match guard.offending_moves(&mesh, &edit) {
                None => {
                    cleared = true;
                    break;
                }
                Some(blamed) => {
                    assert!(
                        !blamed.is_empty(),
                        "a verdict against a batch must blame a move"
                    );
                    blamed_total += blamed.len();
                    let mut i = 0;
                    edit.moves.retain(|m| {
                        let keep = blamed.binary_search(&i).is_err();
                        if !keep {
                            blamed_moves.push(*m);
                        }
                        i += 1;
                        keep
                    });
                }
            }
        }
        if cleared && !edit.moves.is_empty() {
            apply_edit(&mut mesh, &mut attrs, &mut guard, &edit).expect("a cleared batch commits");
            batched += edit.moves.len();
            let report = validate(&mesh, &exact);
            assert!(
                report.is_valid(),
                "round {round}: a cleared batch intersects: {report}"
            );
        }
        // The blamed moves, one at a time through the ordinary per-move check.
        for m in blamed_moves {
            if !mesh.is_vertex_alive(m.vertex) {
                continue;
            }
            let single = Edit {
                moves: vec![m],
                ..Edit::default()
            };
            if apply_edit(&mut mesh, &mut attrs, &mut guard, &single).is_ok() {
                alone += 1;
            }
        }
        let report = validate(&mesh, &exact);
        assert!(
            report.is_valid(),
            "round {round}: a move committed alone intersects: {report}"
        );
    }
    assert!(
        intersecting_batches > 5 && blamed_total > 5 && batched > 500,
        "{intersecting_batches} intersecting batches, {blamed_total} blamed, {batched} batched, {alone} alone"
    );
}
