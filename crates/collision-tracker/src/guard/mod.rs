//! The collision-safe edit guard (El Topo §3.5, Los Topos §4.2 and §5 "Collision-Safety").
//!
//! Every remeshing and topology operation of [`mesh_core::remesh`] builds an atomic
//! [`Edit`] and asks an [`EditGuard`] before committing it. [`CollisionGuard`] is the guard
//! that keeps an intersection-free mesh intersection-free: it treats the edit as a
//! *pseudo-motion* over a fictitious step and refuses it when anything would pass through
//! anything else on the way, or when the end state would intersect.
//!
//! # What it checks, in order
//!
//! 1. **End state, exactly** — by composition with
//!    [`StaticIntersectionGuard`]: no added or moved triangle intersects any other triangle
//!    of the mesh after the edit (exact predicates; contact at shared vertices and edges
//!    allowed; exactly coincident triangles, which degenerate removal resolves, allowed).
//!    This is Los Topos §5's static test of the final positions of moved triangles against
//!    all edges and of moved edges against all triangles. Skipped for an edit that only
//!    moves vertices: from an intersection-free start, an intersecting end state needs a
//!    contact on the way, which step 2 finds (it has no false negatives) or step 3.
//! 2. **The sweep, by CCD** ([`crate::ccd`], no false negatives). The pseudo-motion is
//!    described in the guard's `motion` module: new vertices move from `start` to `end`,
//!    moved vertices from their current position to `end`, and the swept triangles are
//!    the kept triangles that move, the added triangles that move, and (for edge collapses
//!    and vertex snaps) the deleted fan of the vertex that merges away. Each swept
//!    triangle is tested against the static rest of the mesh (the live triangles the edit
//!    neither deletes nor moves): every static vertex against the moving triangle, every
//!    moving vertex against every static triangle, every moving edge against every static
//!    edge; and against the other swept triangles (vertex–triangle and edge–edge, when
//!    something moves). Pairs sharing a vertex are skipped — as are pairs that touch by
//!    construction: a vertex born at an existing vertex (separation, pinching) counts as
//!    that vertex, a vertex deleted onto a survivor (collapse, snap) counts as the
//!    survivor.
//! 3. **Tunnelling** (Los Topos §5): a swept triangle with one moving corner sweeps a
//!    tetrahedron; no vertex of the static rest and no vertex of the edit (at its end
//!    position) other than the triangle's own may lie strictly inside it (exact
//!    `orient3d`). This covers the pairs step 2 skips.
//! 4. **Flips** (El Topo §3.5.2): an edit that moves nothing and re-triangulates exactly
//!    four vertices bounds a tetrahedron between its old and new triangles; no vertex may
//!    lie strictly inside it. With step 1 (no edge crosses a new triangle) nothing passes
//!    through the flip.
//! 5. **Minimum distance** (optional, [`CollisionGuardOptions::min_distance`] `= Some(ε)`):
//!    no pair of non-adjacent elements involving a changed triangle (added or moved) may
//!    end closer than `ε` unless it already started at least that close. Only elements
//!    that existed before the edit get that allowance: a split vertex starts where it
//!    ends, and a flip's new diagonal (nothing moves) "starts" as close as it ends.
//!    Off by default: snap merging deliberately brings elements together. Steps 1–4
//!    cannot see the danger this covers: an edit that leaves two elements a rounding
//!    error apart without intersecting is collision-free, but every later motion of them
//!    starts in contact as far as continuous collision detection can tell.
//!
//! Candidates come from a BVH over the triangles plus a list of the triangles changed
//! since it was built (rebuilt when the list grows past a fraction of the mesh), kept
//! current through [`EditGuard::committed`]. If the mesh changes any other way, call
//! [`CollisionGuard::reset`].
//!
//! What it does not check: the operations' own geometric conditions (inversion, normal
//! rotation, volume change — the operations check those), and pairs of elements that both
//! stay still (an intersection-free mesh has none that collide).

mod motion;
mod sweep;
#[cfg(test)]
pub(crate) mod tests;

use mesh_core::LabeledMesh;
use mesh_core::remesh::{Applied, Edit, EditGuard, StaticIntersectionGuard, Veto};

use crate::ccd::CcdOptions;
use motion::Motion;
use sweep::{Hit, Scratch};

/// Options of [`CollisionGuard`]; the defaults are the fields' documented defaults.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CollisionGuardOptions {
    /// The CCD kernels' options. Default [`CcdOptions::default`] (near misses within about
    /// `10⁻¹²` of a query's size count as contacts).
    pub ccd: CcdOptions,
    /// Refuse edits that bring non-adjacent elements closer than this (see the module
    /// doc, step 5). Default `None`. A tracker typically sets a fraction of its
    /// proximity threshold so that remeshing does not undo collision resolution.
    pub min_distance: Option<f64>,
    /// Accept every edit unchecked: El Topo's `collision_safety = false`, for ablations
    /// only (remeshing may then make the mesh intersect itself). Default false.
    pub unchecked: bool,
}

/// What the guard did, for reports and tuning.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct GuardStats {
    /// Edits checked.
    pub checked: u64,
    /// Edits whose end state intersects the mesh (step 1).
    pub vetoed_end_state: u64,
    /// Edits whose sweep collides (step 2).
    pub vetoed_ccd: u64,
    /// Edits whose swept tetrahedra contain a vertex (step 3).
    pub vetoed_tunnel: u64,
    /// Flips whose tetrahedron contains a vertex (step 4).
    pub vetoed_flip: u64,
    /// Edits that bring elements too close (step 5).
    pub vetoed_proximity: u64,
    /// CCD kernel calls.
    pub ccd_queries: u64,
}

/// The collision-safe [`EditGuard`]: see the [module doc](self) for exactly what it checks.
#[derive(Debug, Default)]
pub struct CollisionGuard {
    options: CollisionGuardOptions,
    /// The end-state test (step 1); its triangle index is also the sweeps' broad phase.
    end_state: StaticIntersectionGuard,
    motion: Motion,
    scratch: Scratch,
    stats: GuardStats,
}

impl CollisionGuard {
    /// A guard with default options; its index is built on first use.
    pub fn new() -> Self {
        Self::default()
    }

    /// A guard with the given options.
    pub fn with_options(options: CollisionGuardOptions) -> Self {
        Self {
            options,
            ..Self::default()
        }
    }

    /// The options in use.
    pub fn options(&self) -> &CollisionGuardOptions {
        &self.options
    }

    /// Switches the minimum-distance check (step 5) on or off between stages, e.g. off for
    /// snap merging, which brings elements together on purpose, and on for the remeshing
    /// after it.
    pub fn set_min_distance(&mut self, min_distance: Option<f64>) {
        self.options.min_distance = min_distance;
    }

    /// Counts of checks and vetoes so far.
    pub fn stats(&self) -> GuardStats {
        GuardStats {
            ccd_queries: self.scratch.queries,
            ..self.stats
        }
    }

    /// Forgets the index, e.g. after the mesh was changed outside `apply_edit` (a time
    /// step moving every vertex).
    pub fn reset(&mut self) {
        self.end_state.reset();
    }

    /// A maker of fresh guards with this guard's options, one per block of
    /// `mesh_core::remesh::run_in_blocks` (each sees only its own block's mesh).
    pub fn maker(&self) -> impl Fn() -> Box<dyn EditGuard> + Sync + use<> {
        let options = self.options;
        move || -> Box<dyn EditGuard> { Box::new(CollisionGuard::with_options(options)) }
    }

    fn veto(&mut self, hit: Hit) -> Veto {
        match hit {
            Hit::VertexTriangle => {
                self.stats.vetoed_ccd += 1;
                Veto::SweepVertexTriangle
            }
            Hit::EdgeEdge => {
                self.stats.vetoed_ccd += 1;
                Veto::SweepEdgeEdge
            }
            Hit::Tunnel => {
                self.stats.vetoed_tunnel += 1;
                Veto::SweptVolume
            }
            Hit::FlipVolume => {
                self.stats.vetoed_flip += 1;
                Veto::FlipVolume
            }
            Hit::Proximity => {
                self.stats.vetoed_proximity += 1;
                Veto::TooClose
            }
        }
    }
}

impl CollisionGuard {
    /// Steps 2–5 of the module doc (everything after the end-state test) for `edit`.
    /// Runs after the end-state test, which brought the shared index up to date.
    fn sweep_checks(&mut self, mesh: &LabeledMesh, edit: &Edit) -> Result<(), Hit> {
        self.motion.build(mesh, edit);
        let index = self.end_state.index();
        let eps = self.options.min_distance.filter(|&e| e > 0.0);
        // An edit that only moves vertices sweeps exactly the triangles the proximity test
        // looks at, and the sweep runs that test itself (see `check_sweep`).
        let fused = eps.is_some()
            && edit.only_moves()
            && !self.motion.swept.is_empty()
            && self.motion.swept.len() == self.motion.moved_kept.len();
        let result = if self.motion.swept.is_empty() {
            sweep::check_retriangulation(&mut self.scratch, index, mesh, edit, &self.motion)
        } else {
            sweep::check_sweep(
                &mut self.scratch,
                index,
                mesh,
                edit,
                &self.motion,
                &self.options.ccd,
                eps.unwrap_or(0.0),
                fused,
            )
        };
        result.and_then(|()| match eps {
            Some(eps) if !fused => {
                sweep::check_proximity(&mut self.scratch, index, mesh, edit, &self.motion, eps)
            }
            _ => Ok(()),
        })
    }
}

impl EditGuard for CollisionGuard {
    fn check(&mut self, mesh: &LabeledMesh, edit: &Edit) -> Result<(), Veto> {
        if self.options.unchecked {
            return Ok(());
        }
        self.stats.checked += 1;
        if edit.only_moves() {
            // Moving vertices of an intersection-free mesh, the end state can only
            // intersect if something passed through something on the way, which the
            // sweep's CCD (no false negatives) and tunnelling test see; the exact
            // end-state test would repeat its verdict. Smoothing and wall relaxation are
            // such edits, one per move: 6 % of a packing foam's step went to that repeat.
            self.end_state.refresh_index(mesh);
        } else if let Err(reason) = self.end_state.check(mesh, edit) {
            self.stats.vetoed_end_state += 1;
            return Err(reason);
        }
        self.sweep_checks(mesh, edit).map_err(|hit| self.veto(hit))
    }

    /// Blames every move of a batch of more than one, so the caller commits each alone
    /// through [`Self::check`] (per-move CCD, as before batching).
    ///
    /// Why not one CCD pseudo-motion for the whole batch (El Topo's way): measured on the
    /// two-sphere scene, sweeping batches and bisecting the ones that collided made
    /// smoothing about 10× slower than checking each move, and a batched end-state test in
    /// front of per-move sweeps still cost 1.6×. Until batched CCD is made cheap, the
    /// collision backend keeps per-move checks, exactly as safe as before.
    fn offending_moves(&mut self, mesh: &LabeledMesh, edit: &Edit) -> Option<Vec<usize>> {
        if self.options.unchecked {
            return None;
        }
        if edit.moves.len() == 1 {
            return self.check(mesh, edit).err().map(|_| vec![0]);
        }
        Some((0..edit.moves.len()).collect())
    }

    fn committed(&mut self, mesh: &LabeledMesh, edit: &Edit, applied: &Applied) {
        self.end_state.committed(mesh, edit, applied);
    }
}
