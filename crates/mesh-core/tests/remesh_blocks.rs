//! `remesh::improve_in_blocks`, improvement by blocks of space on every core: on a foam
//! (walls, triple curves, corners) cut into many small blocks, so that most edits have a
//! block border nearby, the result validates with the exact intersection layer, label
//! volumes move by no more than the per-edit bound, attributes follow, a caller's fence
//! holds, quality matches serial improvement, and the mesh is the same for 1, 2 and 4
//! threads.

mod common;

use common::{assert_valid, assert_volumes};
use glam::DVec3;
use mesh_core::geometry::label_volumes;
use mesh_core::remesh::{
    BlockJob, BlockParams, EditGuard, ImproveParams, ImproveRegion, ImproveReport,
    StaticIntersectionGuard, VertexAttributes, improve_in, improve_in_blocks, run_in_blocks,
};
use mesh_core::{LabeledMesh, TriId, VertexId, generators};

/// A five-cell foam in the unit cube: label walls, triple curves and the corners where
/// they meet, all of which a block border can cut through.
fn foam() -> LabeledMesh {
    generators::voronoi_foam(5, 3, DVec3::ZERO, DVec3::ONE).expect("foam")
}

/// Refinement to a fifth of the foam's edges: every triangle needs work.
fn params() -> ImproveParams {
    ImproveParams {
        target_edge_length: Some(0.07),
        ..ImproveParams::default()
    }
}

/// Blocks of four target edges, each pass on blocks whatever the work's size.
fn small_blocks() -> BlockParams {
    BlockParams {
        block_edges: 4.0,
        min_work: 0,
        ..BlockParams::default()
    }
}

fn exact() -> Box<dyn EditGuard> {
    Box::new(StaticIntersectionGuard::new())
}

/// Improves the foam by blocks in a pool of `threads`, with the position as a 3-value
/// attribute.
fn by_blocks(threads: usize) -> (LabeledMesh, VertexAttributes, ImproveReport) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("pool");
    pool.install(|| {
        let mut m = foam();
        let mut attrs = VertexAttributes::zeros(&m, 3);
        for v in m.vertices().collect::<Vec<_>>() {
            let p = m.position(v);
            attrs.get_mut(v).copy_from_slice(&[p.x, p.y, p.z]);
        }
        let r = improve_in_blocks(
            &mut m,
            &params(),
            ImproveRegion::Whole,
            None,
            &mut attrs,
            &small_blocks(),
            &exact,
        );
        (m, attrs, r)
    })
}

/// Fraction of triangles with an angle under 10°.
fn sliver_share(mesh: &LabeledMesh) -> f64 {
    let n = mesh.num_triangles().max(1);
    let slivers = mesh
        .triangles()
        .filter(|&t| {
            mesh_core::geometry::triangle_min_angle(&mesh.tri_positions(t)) < 10f64.to_radians()
        })
        .count();
    slivers as f64 / n as f64
}

#[test]
fn blocks_give_a_valid_mesh_the_same_for_any_thread_count() {
    let before = label_volumes(&foam());
    let (m1, a1, r1) = by_blocks(1);
    eprintln!("blocks: {r1:?}");
    assert!(
        r1.blocks > 20,
        "the foam was cut into blocks: {}",
        r1.blocks
    );
    assert_valid(&m1, "after improvement by blocks");
    assert_volumes(&before, &m1, &r1);
    for threads in [2, 4] {
        let (m, _, r) = by_blocks(threads);
        assert_eq!(m.to_raw(), m1.to_raw(), "{threads} threads");
        assert_eq!(r, r1, "{threads} threads");
    }
    // Attributes started as positions: splits interpolate and collapses average, and
    // smoothing moves a vertex less than an edge without changing its attribute, so each
    // stays within about an edge of its vertex (one left behind in a block, or zeroed,
    // would be far off).
    for v in m1.vertices() {
        let a = a1.get(v);
        let d = DVec3::new(a[0], a[1], a[2]).distance(m1.position(v));
        assert!(
            d < 1.5 * 0.07,
            "vertex {v}: attribute {a:?} far from {}",
            m1.position(v)
        );
    }
    // As good as serial improvement of the same foam.
    let mut serial = foam();
    let rs = improve_in(
        &mut serial,
        &params(),
        ImproveRegion::Whole,
        &mut VertexAttributes::none(),
        exact().as_mut(),
        &mesh_core::remesh::AreaDecrease,
    );
    eprintln!(
        "in range: blocks {} serial {}; slivers: blocks {} serial {}",
        r1.edges_in_range,
        rs.edges_in_range,
        sliver_share(&m1),
        sliver_share(&serial)
    );
    assert!(r1.edges_in_range >= rs.edges_in_range - 0.02);
    assert!(sliver_share(&m1) <= sliver_share(&serial) + 0.01);
}

#[test]
fn a_callers_fence_holds_across_blocks() {
    let mut m = foam();
    // Fence off every triangle with its centroid at x > 0.6.
    let fenced = |m: &LabeledMesh, t: TriId| {
        let p = m.tri_positions(t);
        (p[0].x + p[1].x + p[2].x) / 3.0 > 0.6
    };
    let editable: Vec<bool> = (0..m.triangle_capacity())
        .map(|t| {
            let t = TriId::new(t as u32);
            m.is_triangle_alive(t) && !fenced(&m, t)
        })
        .collect();
    let snapshot = |m: &LabeledMesh, keep: &dyn Fn(TriId) -> bool| {
        let mut tris: Vec<String> = m
            .triangles()
            .filter(|&t| keep(t))
            .map(|t| format!("{:?} {:?}", m.tri_positions(t), m.labels(t)))
            .collect();
        tris.sort();
        tris
    };
    let before: Vec<String> = snapshot(&m, &|t| !editable[t.idx()]);
    let seeds: Vec<TriId> = m.triangles().filter(|&t| editable[t.idx()]).collect();
    let r = improve_in_blocks(
        &mut m,
        &params(),
        ImproveRegion::Around {
            seeds: &seeds,
            degraded: false,
        },
        Some(editable),
        &mut VertexAttributes::none(),
        &small_blocks(),
        &exact,
    );
    assert!(r.blocks > 10 && r.edits() > 100, "{r:?}");
    assert_valid(&m, "after fenced improvement by blocks");
    // Every fenced triangle is still there, exactly: same corners, same labels.
    let all = snapshot(&m, &|_| true);
    for tri in &before {
        assert!(
            all.binary_search(tri).is_ok(),
            "fenced triangle changed: {tri}"
        );
    }
}

/// Work a block's stage leaves unfinished (here: all of it, as a stage stopped at its
/// sweep limit before doing anything would) comes back to the caller with the work the
/// borders held back, as global ids: dropping it would leave those places unimproved
/// while the report says the passes converged.
#[test]
fn a_blocks_unfinished_work_is_handed_on() {
    let mut m = foam();
    let work: Vec<VertexId> = m.vertices().collect();
    let stage = |job: BlockJob<'_>| {
        job.unfinished.extend_from_slice(job.work);
        ((), 0)
    };
    let blocks = BlockParams {
        passes: 1,
        ..small_blocks()
    };
    let (reports, mut left) = run_in_blocks(
        &mut m,
        &mut VertexAttributes::none(),
        &mut None,
        work.clone(),
        4.0 * 0.07,
        &blocks,
        &exact,
        &stage,
    );
    assert!(reports.len() > 20, "blocks: {}", reports.len());
    left.sort_unstable();
    left.dedup();
    assert_eq!(left, work);
}
