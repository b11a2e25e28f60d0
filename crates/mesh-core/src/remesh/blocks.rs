//! [`improve_in_blocks`]: mesh improvement on every core, by blocks of space; and
//! [`run_in_blocks`], the same for any stage whose edits go through an [`EditGuard`] (the
//! collision backend's wall relaxation).
//!
//! Why: [`improve_in`] commits its edits one at a time, each checked against the mesh as it
//! stands, so it runs on one core; on large changed regions (`fix` of scanned meshes, a
//! tracking step where many bodies press into each other) it is most of the run. Edits far
//! apart do not interact, so space is cut into cubic blocks of side `block_edges · ℓ` and
//! every block with work is improved on its own:
//!
//! 1. **Copy out.** A block's mesh is every triangle whose box meets the block's box. The
//!    triangles with all three vertices strictly inside the box may change (and the ones
//!    their edits create); the others are fenced ([`FenceGuard`]), and so is any vertex an
//!    edit would move or create outside the box.
//! 2. **Improve** with the usual driver and the caller's guard, on its own thread. The
//!    check is exact against the whole mesh: every triangle an edit creates lies inside
//!    the box (its vertices do, and the box is convex), so every triangle it could meet
//!    has a box meeting the block's box, and was copied out.
//! 3. **Write back**, block after block in a fixed order. Blocks improved side by side
//!    cannot disturb each other: what one changes lies strictly inside its box, which no
//!    other block's box meets, so no other block copied it out or could have placed
//!    anything against it.
//!
//! Edits refused only because of a block's border are handed on: a second pass on blocks
//! shifted by half a side takes them (a border of the first is the middle of a block of
//! the second), and a last serial pass over the whole mesh takes what is left. So is the
//! work of a block that stopped at its sweep limit ([`BlockJob::unfinished`]).
//!
//! Deterministic: the blocks, what each copies out, the order in which each is improved and
//! the order of write-back depend on the mesh only, so the result is the same for any
//! number of threads. It is not the mesh serial improvement makes (edits happen in another
//! order), which is why the caller picks a work size below which it stays serial.

use glam::DVec3;
use rayon::iter::Either;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::broadphase::Aabb;
use crate::ids::{Label, TriId, VertexId};
use crate::mesh::LabeledMesh;

use super::attributes::VertexAttributes;
use super::features;
use super::fence::FenceGuard;
use super::guard::EditGuard;
use super::improve::{
    ImproveParams, ImproveRegion, ImproveReport, improve_part, initial_work, live_sorted,
    mean_edge_length,
};
use super::separate::AreaDecrease;

/// Options of [`improve_in_blocks`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct BlockParams {
    /// Block passes before the serial pass over what they left. Default 2 (the second on
    /// blocks shifted by half a side); 0 improves serially.
    pub passes: usize,
    /// Block side in target edge lengths ℓ. Default 24: a vertex within about one edge of
    /// a border waits for the next pass, so smaller blocks leave more to it, and larger
    /// ones leave fewer blocks to share among the cores. Measured on the grid backend's
    /// `spheres --spheres 20` (40 steps, 2 threads), improvement took 8.7 s with blocks of
    /// 10, 8.2 s with 16 and 7.2 s with 24 edges; `fix` of six bunnies is the same at 16
    /// and 24.
    pub block_edges: f64,
    /// A pass runs on blocks only when its work list has at least this many vertices;
    /// below, copying blocks out costs more than the cores save. Default 1024.
    pub min_work: usize,
    /// Distance that edits on the two sides of a border must keep from each other: each
    /// block may change only what lies at least `margin / 2` inside its box, and copies
    /// out everything within `margin` of it. Default 0, enough for an intersection
    /// guard; a guard that refuses elements closer than `d` (the collision guard's
    /// minimum distance) needs `d`, or two blocks could each place an element `d / 2`
    /// from their shared face without either seeing the other's.
    pub margin: f64,
}

impl BlockParams {
    /// True when blocks of side `side` can run at all: at least one pass, a usable side,
    /// and a margin that leaves a block something it may change (under half a side).
    pub fn runs(&self, side: f64) -> bool {
        let margin = self.margin.max(0.0);
        self.passes > 0
            && side.is_finite()
            && side > 0.0
            && margin.is_finite()
            && 2.0 * margin < side
    }
}

impl Default for BlockParams {
    fn default() -> Self {
        Self {
            passes: 2,
            block_edges: 24.0,
            min_work: 1024,
            margin: 0.0,
        }
    }
}

/// [`improve_in`] on blocks of space, in parallel (see the module doc), with the
/// separation strength [`AreaDecrease`] (a block's mesh has its own vertex ids, so a
/// strength that looks up data by id could not be used).
///
/// `editable`: the caller's fence (slot `t` may change when `editable[t]`; see
/// [`FenceGuard::new`]), or `None`. `make_guard` makes the guard of one block, or of the
/// final serial pass; it is called on the thread that uses it, and each guard sees only
/// its own block's mesh.
pub fn improve_in_blocks(
    mesh: &mut LabeledMesh,
    params: &ImproveParams,
    region: ImproveRegion<'_>,
    mut editable: Option<Vec<bool>>,
    attrs: &mut VertexAttributes,
    blocks: &BlockParams,
    make_guard: &(dyn Fn() -> Box<dyn EditGuard> + Sync),
) -> ImproveReport {
    let target = params
        .target_edge_length
        .unwrap_or_else(|| mean_edge_length(mesh));
    let params = ImproveParams {
        target_edge_length: Some(target),
        max_volume_change: Some(
            params
                .max_volume_change
                .unwrap_or(0.1 * target * target * target),
        ),
        ..params.clone()
    };
    let mut report = ImproveReport {
        converged: true,
        ..Default::default()
    };
    let side = blocks.block_edges * target;
    let caps = features::material_caps(mesh, params.max_material_share);
    // The serial pass's work: what the block passes left, or the region when none ran.
    let mut left: Option<Vec<VertexId>> = None;
    if blocks.runs(side) {
        let stage = |job: BlockJob<'_>| {
            let r = improve_part(
                job.mesh,
                &params,
                ImproveRegion::Vertices(job.work),
                job.attrs,
                job.guard,
                &AreaDecrease,
                false,
                Some(job.unfinished),
                &caps,
            );
            let edits = r.edits();
            (r, edits)
        };
        let work = first_work(mesh, &params, target, region);
        let (reports, rest) = run_in_blocks(
            mesh,
            attrs,
            &mut editable,
            work,
            side,
            blocks,
            make_guard,
            &stage,
        );
        report.blocks = reports.len();
        for r in &reports {
            report.absorb(r);
        }
        left = Some(rest);
    }
    let region = match &left {
        Some(w) => ImproveRegion::Vertices(w),
        None => region,
    };
    let t0 = std::time::Instant::now();
    let mut inner = make_guard();
    let serial = |mesh: &mut LabeledMesh, attrs: &mut VertexAttributes, g: &mut dyn EditGuard| {
        improve_part(
            mesh,
            &params,
            region,
            attrs,
            g,
            &AreaDecrease,
            true,
            None,
            &caps,
        )
    };
    let last = match editable {
        Some(e) => serial(mesh, attrs, &mut FenceGuard::new(inner.as_mut(), e)),
        None => serial(mesh, attrs, inner.as_mut()),
    };
    tracing::debug!(
        edits = last.edits(),
        seconds = t0.elapsed().as_secs_f64(),
        "improve: serial pass"
    );
    report.absorb(&last);
    // A block stopped at the sweep limit handed its unfinished work on, so the passes
    // converged when the last one did.
    report.converged = last.converged;
    report.target_edge_length = last.target_edge_length;
    report.max_volume_change = last.max_volume_change;
    report.edges = last.edges;
    report.edges_in_range = last.edges_in_range;
    report
}

/// The work list `region` starts from, as vertices.
fn first_work(
    mesh: &LabeledMesh,
    params: &ImproveParams,
    target: f64,
    region: ImproveRegion<'_>,
) -> Vec<VertexId> {
    let range = (
        params.min_edge_factor * target,
        params.max_edge_factor * target,
    );
    let mut work = match region {
        ImproveRegion::Whole => mesh.vertices().collect(),
        ImproveRegion::Around { seeds, degraded } => {
            initial_work(mesh, params, range, seeds, degraded)
        }
        ImproveRegion::Vertices(v) => v.to_vec(),
    };
    live_sorted(mesh, &mut work);
    work
}

/// Integer block coordinates of a point: `floor((p − origin) / side)`.
type Key = [i64; 3];

/// The block lattice of one pass: side and origin.
#[derive(Clone, Copy)]
struct Lattice {
    origin: DVec3,
    side: f64,
}

impl Lattice {
    fn key(&self, p: DVec3) -> Key {
        let q = ((p - self.origin) / self.side).floor();
        [q.x as i64, q.y as i64, q.z as i64]
    }

    /// The block's box. Neighbours compute their shared face from the same expression, so
    /// the open boxes of two blocks never overlap.
    fn bounds(&self, k: Key) -> Aabb {
        let corner =
            |k: Key| self.origin + DVec3::new(k[0] as f64, k[1] as f64, k[2] as f64) * self.side;
        Aabb::new(corner(k), corner([k[0] + 1, k[1] + 1, k[2] + 1]))
    }
}

/// One block's job: the box its edits must stay strictly inside (its lattice box shrunk
/// by half the margin), the triangles it copies out and its work, all global ids in
/// increasing order.
struct Block {
    bounds: Aabb,
    tris: Vec<TriId>,
    work: Vec<VertexId>,
}

/// What a stage gets to work on in one block: the block's own copy of its part of the
/// mesh (local ids), the attributes, the work (local ids, increasing), the global id of
/// every copied vertex (`globals[i]` is local vertex `i`; vertices a stage creates have
/// none) and the block's fenced guard, which every edit must go through.
pub struct BlockJob<'a> {
    /// The block's mesh.
    pub mesh: &'a mut LabeledMesh,
    /// Its vertices' attributes.
    pub attrs: &'a mut VertexAttributes,
    /// The vertices to work on.
    pub work: &'a [VertexId],
    /// Global id of each copied vertex.
    pub globals: &'a [VertexId],
    /// The block's guard: the caller's, behind the block's fence.
    pub guard: &'a mut dyn EditGuard,
    /// Where the stage puts vertices (local ids) whose work it left undone, e.g. when it
    /// stopped at a sweep limit: they are handed on like those the border held back.
    pub unfinished: &'a mut Vec<VertexId>,
}

/// Runs `stage` on blocks of space, in parallel, pass after pass (see the module doc;
/// every pass after the first works on blocks shifted by half a side and takes what the
/// previous one's borders held back), and writes every block back in a fixed order.
/// `stage` returns its report and the number of edits it committed.
///
/// Returns the blocks' reports in write-back order, and the work left for the caller's
/// serial pass: what the last pass's borders held back, or all of `work` when it has fewer
/// than [`BlockParams::min_work`] vertices (or [`BlockParams::runs`] is false). `editable`
/// is the caller's fence, as in [`improve_in_blocks`]; triangles the blocks create are
/// added to it.
#[allow(clippy::too_many_arguments)]
pub fn run_in_blocks<R: Send>(
    mesh: &mut LabeledMesh,
    attrs: &mut VertexAttributes,
    editable: &mut Option<Vec<bool>>,
    mut work: Vec<VertexId>,
    side: f64,
    blocks: &BlockParams,
    make_guard: &(dyn Fn() -> Box<dyn EditGuard> + Sync),
    stage: &(dyn Fn(BlockJob<'_>) -> (R, usize) + Sync),
) -> (Vec<R>, Vec<VertexId>) {
    let mut reports = Vec::new();
    if !blocks.runs(side) {
        return (reports, work);
    }
    let margin = blocks.margin.max(0.0);
    for pass in 0..blocks.passes {
        if work.len() < blocks.min_work {
            break;
        }
        let shift = if pass % 2 == 0 { 0.0 } else { 0.5 * side };
        let t0 = std::time::Instant::now();
        let before = reports.len();
        let (edits, next) = block_pass(
            mesh,
            &work,
            editable,
            attrs,
            (side, shift, margin),
            make_guard,
            stage,
            &mut reports,
        );
        tracing::debug!(
            pass,
            blocks = reports.len() - before,
            work = work.len(),
            left = next.len(),
            edits,
            seconds = t0.elapsed().as_secs_f64(),
            "blocks: pass"
        );
        work = next;
    }
    (reports, work)
}

/// A block after its stage ran, with what write-back needs to map it onto the mesh.
struct Worked {
    /// Global id of each vertex the block copied out (its local id is the index).
    verts: Vec<VertexId>,
    /// Global id of each triangle it copied out (likewise).
    tris: Vec<TriId>,
    /// Per copied triangle: it was free to change.
    editable: Vec<bool>,
    /// Per copied vertex: strictly inside the box (only such vertices can move).
    inner: Vec<bool>,
    mesh: LabeledMesh,
    attrs: VertexAttributes,
    /// Local ids of the vertices of edits refused only because of the border, and of the
    /// work the stage left unfinished.
    deferred: Vec<VertexId>,
    /// Edits the stage committed.
    edits: usize,
}

/// One pass over the blocks of a lattice shifted by `shift`: the stage runs on every block
/// with work in parallel, then the blocks are written back in block order and their
/// reports appended to `reports`. Returns the edits and the next pass's work (global ids
/// of what the borders held back).
#[allow(clippy::too_many_arguments)]
fn block_pass<R: Send>(
    mesh: &mut LabeledMesh,
    work: &[VertexId],
    editable: &mut Option<Vec<bool>>,
    attrs: &mut VertexAttributes,
    (side, shift, margin): (f64, f64, f64),
    make_guard: &(dyn Fn() -> Box<dyn EditGuard> + Sync),
    stage: &(dyn Fn(BlockJob<'_>) -> (R, usize) + Sync),
    reports: &mut Vec<R>,
) -> (usize, Vec<VertexId>) {
    let low = mesh
        .vertices()
        .fold(DVec3::INFINITY, |m, v| m.min(mesh.position(v)));
    let lattice = Lattice {
        origin: (low / side).floor() * side - DVec3::splat(shift),
        side,
    };
    let blocks = cut_into_blocks(mesh, work, &lattice, margin);
    // Largest blocks first: one block can hold several times the mean work (six bunnies:
    // 13k vertices against a mean of 3.3k), and started last it leaves the other cores
    // idle while it runs. The order of running does not touch the result: each block
    // reads only the mesh as the pass found it, and write-back stays in key order.
    let mut order: Vec<usize> = (0..blocks.len()).collect();
    order.sort_by_key(|&i| std::cmp::Reverse(blocks[i].work.len() + blocks[i].tris.len()));
    let mut ran: Vec<(usize, (Worked, R))> = order
        .par_iter()
        .with_max_len(1)
        .map(|&i| {
            let b = &blocks[i];
            (
                i,
                run_block(mesh, attrs, editable.as_deref(), b, make_guard, stage),
            )
        })
        .collect();
    ran.sort_unstable_by_key(|&(i, _)| i);
    let worked = ran.into_iter().map(|(_, w)| w);
    let mut next = Vec::new();
    let mut edits = 0;
    for (block, report) in worked {
        edits += block.edits;
        reports.push(report);
        write_back(mesh, attrs, editable, block, &mut next);
    }
    live_sorted(mesh, &mut next);
    (edits, next)
}

/// The blocks that hold work, in key order, each with every triangle whose box comes
/// within `margin` of its lattice box (boxes grown by a further millionth of a side, so
/// that rounding in the keys can only add triangles: an extra one is fenced and harmless,
/// a missing one could hide an intersection).
fn cut_into_blocks(
    mesh: &LabeledMesh,
    work: &[VertexId],
    lattice: &Lattice,
    margin: f64,
) -> Vec<Block> {
    let mut keyed: Vec<(Key, VertexId)> = work
        .iter()
        .map(|&v| (lattice.key(mesh.position(v)), v))
        .collect();
    keyed.sort_unstable();
    // One block per distinct key, in increasing key order: `keys[i]` is block `i`'s.
    let mut blocks: Vec<Block> = Vec::new();
    let mut keys: Vec<Key> = Vec::new();
    for (k, v) in keyed {
        if keys.last() != Some(&k) {
            let b = lattice.bounds(k);
            keys.push(k);
            blocks.push(Block {
                bounds: Aabb::new(b.min + 0.5 * margin, b.max - 0.5 * margin),
                tris: Vec::new(),
                work: Vec::new(),
            });
        }
        blocks.last_mut().expect("pushed above").work.push(v);
    }
    // Which blocks each triangle reaches, found for all triangles in parallel (a serial
    // pass with a hashed lookup per spanned block was most of the serial time of a block
    // pass); collected in triangle order, so every block lists its triangles in
    // increasing order whatever the thread count.
    let slack = 1e-6 * lattice.side + margin;
    let alive = mesh.tri_alive_flags();
    let keys = &keys[..];
    let reached: Vec<(u32, TriId)> = (0..mesh.triangle_capacity())
        .into_par_iter()
        .with_min_len(4096)
        .filter(|&t| alive[t])
        .flat_map_iter(|t| {
            let t = TriId::new(t as u32);
            let b = Aabb::from_points(&mesh.tri_positions(t)).inflated(slack);
            let (lo, hi) = (lattice.key(b.min), lattice.key(b.max));
            let inside = move |k: &Key| (0..3).all(|a| lo[a] <= k[a] && k[a] <= hi[a]);
            let span = (0..3).fold(1i128, |n, k| n * (hi[k] as i128 - lo[k] as i128 + 1));
            let found = if span > keys.len() as i128 {
                // A triangle larger than the blocks with work (coarse input, a tiny ℓ):
                // ask each of those blocks instead of each block the triangle spans.
                Either::Left((0..keys.len()).filter(move |&i| inside(&keys[i])))
            } else {
                Either::Right((lo[0]..=hi[0]).flat_map(move |x| {
                    (lo[1]..=hi[1]).flat_map(move |y| {
                        (lo[2]..=hi[2]).filter_map(move |z| keys.binary_search(&[x, y, z]).ok())
                    })
                }))
            };
            found.map(move |i| (i as u32, t))
        })
        .collect();
    for (i, t) in reached {
        blocks[i as usize].tris.push(t);
    }
    blocks
}

/// Copies one block out and runs the stage on it.
fn run_block<R>(
    mesh: &LabeledMesh,
    attrs: &VertexAttributes,
    region: Option<&[bool]>,
    block: &Block,
    make_guard: &(dyn Fn() -> Box<dyn EditGuard> + Sync),
    stage: &(dyn Fn(BlockJob<'_>) -> (R, usize) + Sync),
) -> (Worked, R) {
    let mut verts: Vec<VertexId> = block.tris.iter().flat_map(|&t| mesh.tri(t)).collect();
    verts.sort_unstable();
    verts.dedup();
    let local = |v: VertexId| verts.binary_search(&v).ok().map(|i| i as u32);
    let positions: Vec<DVec3> = verts.iter().map(|&v| mesh.position(v)).collect();
    let tris: Vec<[u32; 3]> = block
        .tris
        .iter()
        .map(|&t| {
            mesh.tri(t)
                .map(|v| local(v).expect("a copied triangle's vertex"))
        })
        .collect();
    let labels: Vec<[u32; 2]> = block
        .tris
        .iter()
        .map(|&t| mesh.labels(t).map(Label::raw))
        .collect();
    let inner: Vec<bool> = positions
        .iter()
        .map(|&p| block.bounds.contains_strictly(p))
        .collect();
    let in_region = |t: TriId| region.is_none_or(|r| r.get(t.idx()).copied().unwrap_or(false));
    let all_inner: Vec<bool> = tris
        .iter()
        .map(|tri| tri.iter().all(|&i| inner[i as usize]))
        .collect();
    let editable: Vec<bool> = block
        .tris
        .iter()
        .zip(&all_inner)
        .map(|(&t, &a)| a && in_region(t))
        .collect();
    let held: Vec<bool> = block
        .tris
        .iter()
        .zip(&all_inner)
        .map(|(&t, &a)| !a && in_region(t))
        .collect();
    let mut sub = LabeledMesh::from_raw(positions, &tris, &labels)
        .expect("a block has fewer vertices and triangles than the mesh it is cut from");
    let mut sub_attrs = VertexAttributes::zeros(&sub, attrs.dim());
    if attrs.dim() > 0 {
        for (i, &v) in verts.iter().enumerate() {
            sub_attrs
                .get_mut(VertexId::new(i as u32))
                .copy_from_slice(attrs.get(v));
        }
    }
    let work: Vec<VertexId> = block
        .work
        .iter()
        .filter_map(|&v| local(v).map(VertexId::new))
        .collect();
    let mut inner_guard = make_guard();
    let mut fence = FenceGuard::block(inner_guard.as_mut(), editable.clone(), held, block.bounds);
    let mut unfinished = Vec::new();
    let (report, edits) = stage(BlockJob {
        mesh: &mut sub,
        attrs: &mut sub_attrs,
        work: &work,
        globals: &verts,
        guard: &mut fence,
        unfinished: &mut unfinished,
    });
    let mut deferred = fence.deferred().to_vec();
    deferred.append(&mut unfinished);
    let worked = Worked {
        verts,
        tris: block.tris.clone(),
        editable,
        inner,
        mesh: sub,
        attrs: sub_attrs,
        deferred,
        edits,
    };
    (worked, report)
}

/// Writes a worked block into the mesh (the same steps as committing one edit: moves,
/// removals, new vertices, new triangles, each touched edge re-paired once, then the edges
/// around moved vertices) and adds the global ids of its deferred vertices to `next`.
fn write_back(
    mesh: &mut LabeledMesh,
    attrs: &mut VertexAttributes,
    editable: &mut Option<Vec<bool>>,
    block: Worked,
    next: &mut Vec<VertexId>,
) {
    let Worked {
        verts,
        tris,
        editable: free,
        inner,
        mesh: sub,
        attrs: sub_attrs,
        deferred,
        edits,
    } = block;
    let (n_verts, n_tris) = (verts.len(), tris.len());
    if edits == 0 {
        next.extend(deferred.iter().map(|v| verts[v.idx()]));
        return;
    }
    // A copied triangle that was free to change is kept when its slot still holds it.
    let kept = |s: usize| -> bool {
        let st = TriId::new(s as u32);
        !free[s]
            || (sub.is_triangle_alive(st)
                && sub.tri(st).map(|v| verts.get(v.idx()).copied()) == mesh.tri(tris[s]).map(Some)
                && sub.labels(st) == mesh.labels(tris[s]))
    };
    let kept: Vec<bool> = (0..n_tris).map(kept).collect();
    let mut moved = Vec::new();
    for (i, &v) in verts.iter().enumerate() {
        let sv = VertexId::new(i as u32);
        if inner[i] && sub.is_vertex_alive(sv) && sub.position(sv) != mesh.position(v) {
            mesh.set_position(v, sub.position(sv));
            moved.push(v);
        }
    }
    let mut edges = Vec::new();
    for (s, &t) in tris.iter().enumerate() {
        if !kept[s] {
            let v = mesh
                .remove_triangle_unpaired(t)
                .expect("a block removes only live triangles it copied");
            edges.extend([[v[0], v[1]], [v[1], v[2]], [v[2], v[0]]]);
        }
    }
    let mut map = verts.clone();
    for i in n_verts..sub.vertex_capacity() {
        let sv = VertexId::new(i as u32);
        map.push(if sub.is_vertex_alive(sv) {
            mesh.add_vertex(sub.position(sv))
                .expect("room for a block's new vertices")
        } else {
            VertexId::new(0)
        });
    }
    for st in sub.triangles() {
        if st.idx() < n_tris && kept[st.idx()] {
            continue;
        }
        let v = sub.tri(st).map(|sv| map[sv.idx()]);
        let t = mesh
            .add_triangle_unpaired(v, sub.labels(st))
            .expect("room for a block's new triangles");
        edges.extend([[v[0], v[1]], [v[1], v[2]], [v[2], v[0]]]);
        if let Some(e) = editable {
            if t.idx() >= e.len() {
                e.resize(t.idx() + 1, false);
            }
            e[t.idx()] = true;
        }
    }
    mesh.relink_edges(&mut edges);
    for (i, &v) in verts.iter().enumerate() {
        if !sub.is_vertex_alive(VertexId::new(i as u32)) {
            mesh.remove_vertex(v)
                .expect("a vertex a block removed has no triangles left");
        }
    }
    for &v in &moved {
        mesh.relink_around(v);
    }
    if attrs.dim() > 0 {
        attrs.fit(mesh);
        for (i, &g) in map.iter().enumerate() {
            let sv = VertexId::new(i as u32);
            if sub.is_vertex_alive(sv) && (i >= n_verts || inner[i]) {
                attrs.get_mut(g).copy_from_slice(sub_attrs.get(sv));
            }
        }
    }
    next.extend(deferred.iter().map(|v| map[v.idx()]));
}
