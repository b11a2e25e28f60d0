//! Collision resolution (El Topo §3.8, Los Topos Algorithm 1 "resolve interpenetrations"):
//! move the mesh from its current positions towards proposed ones without ever passing
//! through a collision.
//!
//! Entry point: [`resolve_step`] with [`ResolveOptions`], returning [`Resolved`] or a
//! [`ResolveError`].
//!
//! # Glossary
//!
//! - **step**: straight-line motion `x(t) = x⁰ + t u`, `t ∈ [0, 1]`, from the current
//!   positions `x⁰` with the *velocity* `u = proposed − x⁰` (the time step is 1: velocities
//!   are displacements over the step).
//! - **masses**: every vertex has mass 1 (El Topo's unit weighting `M = I` for surfaces
//!   without a natural mass); the stages are written with inverse masses so that per-vertex
//!   masses can be added later.
//! - **contact**: four vertices with El Topo's signed weights `w` (positive on the vertex /
//!   first edge, negative on the triangle / second edge, see [`crate::proximity`]) and a
//!   unit normal `n` from the second element towards the first. Its **relative normal
//!   velocity** is `n · Σ wᵢ uᵢ` (negative = approaching). An **impulse** changing the
//!   relative velocity by `Δ` adds `wᵢ Δ / (mᵢ Σⱼ wⱼ²/mⱼ)` to each `uᵢ`: momentum is
//!   conserved because the weights sum to zero.
//!
//! # The stages (one module each, in the paper's order)
//!
//! 1. `repulsion.rs`: pairs closer than [`ResolveOptions::proximity`] at `x⁰` get an impulse
//!    so that they separate to at least that distance over the step (or keep separating
//!    faster) — this keeps later CCD away from degenerate grazing contacts.
//! 2. `impulses.rs`: `impulse_sweeps` Gauss–Seidel sweeps: CCD finds the colliding pairs of
//!    the current motion (in parallel), each hit in turn gets the inelastic impulse that
//!    zeroes its relative normal velocity — or, with a [`ResolveOptions::rest_distance`]
//!    `ε_r > 0`, the impulse that sets it to `ε_r − d₀` when the pair starts at a normal
//!    separation `d₀ > ε_r`, so that it comes to rest about `ε_r` apart (linearised: if
//!    the turning of the normal makes it collide anyway, the next sweep or the impact
//!    zones catch it, and certification checks the result in any case).
//! 3. `zones.rs`: the remaining collisions are grouped into *impact zones* (vertex sets
//!    merged by shared vertices, Harmon et al. 2008) and each zone is solved at once by
//!    *inelastic projection*: the smallest change of velocity (in the mass norm) with zero
//!    relative normal velocity at every contact of the zone, `C M⁻¹ Cᵀ λ = C u`,
//!    `u ← u − M⁻¹ Cᵀ λ` (sparse, conjugate gradients). Repeated, adding the new
//!    collisions, until CCD finds nothing or [`ResolveOptions::max_zone_iterations`].
//! 4. **Step halving** (this module): if the zones do not converge, the substep is split
//!    in two halves of the proposed motion, resolved in turn (at most
//!    [`ResolveOptions::max_halvings`] levels deep).
//! 5. **Rigid impact zones** (`zones.rs`, the last resort of El Topo / Harmon et al.): at the
//!    deepest level every zone moves as one rigid translation (its mean velocity); zones
//!    hit by new collisions merge, so in the worst case the colliding part of the mesh
//!    translates as a whole, which cannot collide. Can be disabled
//!    ([`ResolveOptions::rigid_fallback`]).
//! 6. **Certification**: a full CCD pass over the straight-line motion from `x⁰` to the
//!    result. `Ok` only when it finds nothing — so `Ok` means collision-free; a substepped
//!    path whose end point is not reachable on a straight line is resolved once more on
//!    that straight line (projection, then rigid zones) before giving up.
//!
//! CCD reports touching and near misses closer than about `10⁻¹²` of a pair's size as
//! collisions (see [`crate::ccd`]), so `Ok` also means no pair came closer than that. A
//! mesh whose elements already touch at `x⁰` cannot be resolved: the result is an error
//! naming them.

mod impulses;
mod repulsion;
mod zones;

#[cfg(test)]
mod tests;

use std::time::Instant;

use glam::DVec3;
use mesh_core::{LabeledMesh, VertexId};

use crate::broadphase::{Broadphase, BroadphaseQueryError};
use crate::ccd::CcdOptions;
use impulses::Detector;

/// Knobs of [`resolve_step`]. One struct for every stage; see the [module docs](self).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ResolveOptions {
    /// Repulsion distance `ε_p` (El Topo §3.4): pairs closer than this at the start of the
    /// step are pushed apart to at least this distance over the step. Absolute length.
    pub proximity: f64,
    /// Gauss–Seidel sweeps of individual CCD impulses before impact zones (El Topo: 3).
    pub impulse_sweeps: usize,
    /// Rest distance `ε_r` of the individual CCD impulses: a colliding pair that starts
    /// the (sub)step farther apart than this, along the impact normal, may still approach
    /// to this distance instead of being stopped where it started. Absolute length.
    /// Default 0: El Topo's inelastic impulse (zero relative normal velocity), which
    /// freezes a colliding pair at its start distance — anywhere between 0 and one step's
    /// approach. A tracker that merges surfaces sets it below its merge distance, so that
    /// colliding surfaces come to rest where merging sees them (see the
    /// [module docs](self), stage 2). Impact zones and rigid zones (the fail-safes) still
    /// use zero relative normal velocity.
    pub rest_distance: f64,
    /// Detect–merge–solve rounds of the impact-zone stage before the step is halved.
    pub max_zone_iterations: usize,
    /// Levels of step halving (at most `2^max_halvings` substeps).
    pub max_halvings: u32,
    /// Coulomb friction coefficient of the repulsion and CCD impulses: the tangential
    /// relative velocity is reduced by `friction ×` the normal velocity change (never
    /// reversed). 0 = frictionless, as El Topo. Impact-zone projections are frictionless.
    pub friction: f64,
    /// Use rigid impact zones when halving is exhausted (the last resort). Without it
    /// such a step is an error.
    pub rigid_fallback: bool,
    /// Options of the CCD kernels.
    pub ccd: CcdOptions,
}

impl ResolveOptions {
    /// Repulsion distance as a fraction of the mean edge length in
    /// [`ResolveOptions::for_length`]: well below the 0.02 merge distance of Los Topos, so
    /// repulsion never keeps surfaces out of merge range, and well above the CCD's
    /// near-miss tolerance (`10⁻¹²`), so grazing contacts are pushed out of its way.
    pub const PROXIMITY_FRACTION: f64 = 1e-3;

    /// Options for a mesh of mean edge length `mean_edge_length`: repulsion distance
    /// [`Self::PROXIMITY_FRACTION`] `× mean_edge_length`, the other values as
    /// [`Default`]. A non-finite or non-positive length gives the defaults.
    pub fn for_length(mean_edge_length: f64) -> ResolveOptions {
        let mut options = ResolveOptions::default();
        if mean_edge_length.is_finite() && mean_edge_length > 0.0 {
            options.proximity = Self::PROXIMITY_FRACTION * mean_edge_length;
        }
        options
    }
}

impl Default for ResolveOptions {
    /// `proximity = 1e-4` (a mean edge length of 0.1, the scale of the unit-box test
    /// scenes), 3 impulse sweeps (El Topo), rest distance 0 (El Topo), 50 zone iterations, 4 halvings (16
    /// substeps), no friction, rigid fallback on, default CCD options.
    fn default() -> Self {
        ResolveOptions {
            proximity: 1e-4,
            impulse_sweeps: 3,
            rest_distance: 0.0,
            max_zone_iterations: 50,
            max_halvings: 4,
            friction: 0.0,
            rigid_fallback: true,
            ccd: CcdOptions::default(),
        }
    }
}

/// What [`resolve_step`] did, for step reports and benchmarks.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ResolveReport {
    /// Substeps the step was resolved in (1 without halving).
    pub substeps: u32,
    /// Repulsion impulses applied.
    pub repulsion_impulses: usize,
    /// Individual CCD impulses applied in the sweeps.
    pub ccd_impulses: usize,
    /// Impact zones solved (counted once per zone per solve).
    pub impact_zones: usize,
    /// Detect–merge–solve rounds of the zone stage, summed over substeps.
    pub zone_iterations: usize,
    /// Rigid impact zones in the last round of the last resort (0 unless it ran).
    pub rigid_zones: usize,
    /// Seconds in continuous collision detection (swept broad phase + CCD kernels +
    /// impulse sweeps + the certification pass).
    pub seconds_ccd: f64,
    /// Seconds in impact-zone solves (inelastic projection and rigid zones).
    pub seconds_zones: f64,
    /// Seconds in the proximity broad phase, proximity queries and repulsion.
    pub seconds_proximity: f64,
}

/// The result of [`resolve_step`]: collision-free end positions.
#[derive(Clone, Debug)]
pub struct Resolved {
    /// End positions by vertex slot (dead slots keep their proposed value). The straight
    /// line from the mesh's positions to these is certified collision-free.
    pub positions: Vec<DVec3>,
    /// What was done.
    pub report: ResolveReport,
}

/// Which bound of [`resolve_step`] was exhausted.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ExhaustedBound {
    /// Zone iterations failed at the deepest halving level and the rigid fallback is off.
    #[error("impact zones did not converge after {max_halvings} halvings (rigid fallback off)")]
    Halvings {
        /// The halving bound.
        max_halvings: u32,
    },
    /// Rigid zones could not separate a collision inside one zone: its elements touch
    /// already at the start of the step.
    #[error("rigid impact zones: elements touch at the start of the step")]
    TouchingAtStart,
    /// The rigid-zone loop hit its iteration bound.
    #[error("rigid impact zones: iteration bound {iterations} reached")]
    RigidIterations {
        /// The bound.
        iterations: usize,
    },
}

/// Why [`resolve_step`] failed. The mesh is never modified, so a failed step leaves the
/// caller's state intact.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ResolveError {
    /// `proposed` does not have one position per vertex slot.
    #[error("resolve: {got} proposed positions for {expected} vertex slots")]
    ProposalLength {
        /// Vertex slots of the mesh.
        expected: usize,
        /// Positions given.
        got: usize,
    },
    /// A live vertex has a non-finite current or proposed position.
    #[error(
        "resolve: vertex {vertex} has a non-finite position (current {current:?}, proposed {proposed:?})"
    )]
    NonFinite {
        /// The vertex.
        vertex: VertexId,
        /// Its current position.
        current: [f64; 3],
        /// Its proposed position.
        proposed: [f64; 3],
    },
    /// Collisions remain after the named bound was exhausted.
    #[error(
        "resolve: {remaining} collisions remain ({bound}); vertices involved include {vertices:?}"
    )]
    Unresolved {
        /// The bound that was exhausted.
        bound: ExhaustedBound,
        /// Colliding pairs found by the last CCD pass.
        remaining: usize,
        /// Vertices of the remaining collisions (sorted, at most 32 listed).
        vertices: Vec<VertexId>,
    },
    /// The broad phase failed (too many elements).
    #[error(transparent)]
    Broadphase(#[from] BroadphaseQueryError),
}

/// How many vertices an [`ResolveError::Unresolved`] lists.
const MAX_LISTED: usize = 32;

/// Moves from the mesh's current positions towards `proposed` (one per vertex slot) without
/// ever passing through a collision: proximity repulsion, [`ResolveOptions::impulse_sweeps`]
/// sweeps of CCD impulses, then impact zones merged by adjacency and solved together by
/// inelastic projection (sparse `C M⁻¹ Cᵀ λ = C u`, conjugate gradients), repeated until CCD
/// finds nothing; if that fails, the step is halved (proposed positions part-way) and the
/// halves resolved in turn, at most [`ResolveOptions::max_halvings`] deep, with rigid impact
/// zones as the last resort.
///
/// On `Ok`, the straight-line motion from the current positions to
/// [`Resolved::positions`] is collision-free, certified by a final full CCD pass with no
/// hits. Velocities are `proposed − current`, masses 1. Vertices that do not move still
/// take part in every contact. The mesh is not modified.
pub fn resolve_step(
    mesh: &LabeledMesh,
    proposed: &[DVec3],
    options: &ResolveOptions,
) -> Result<Resolved, ResolveError> {
    let x0 = mesh.positions();
    check_input(mesh, proposed)?;
    let mut state = Resolver {
        options: *options,
        inverse_mass: vec![1.0; x0.len()],
        detector: Detector::new(Broadphase::new(mesh), x0.len()),
        report: ResolveReport::default(),
    };

    // Stage 1: repulsion, once, on the whole step.
    let mut u: Vec<DVec3> = proposed.iter().zip(x0).map(|(p, x)| *p - *x).collect();
    state.repulsion(x0, &mut u)?;
    let target: Vec<DVec3> = x0.iter().zip(&u).map(|(x, v)| *x + *v).collect();

    // Stages 2–5: sweeps and zones, halving when needed.
    let end = state.advance(x0, &target, 0)?;

    // Stage 6: certification of the straight line to the returned positions. Vertices
    // that ended where the unmodified step puts them return the proposal bit for bit.
    let mut positions: Vec<DVec3> = (0..x0.len())
        .map(|i| {
            let untouched = end[i] == x0[i] + (proposed[i] - x0[i]);
            if untouched || !state.detector.is_live(i) {
                proposed[i]
            } else {
                end[i]
            }
        })
        .collect();
    // A substepped path may bend: its end point is then resolved once more on the
    // straight line (projection, then rigid zones).
    for attempt in 0..2 {
        if state.detect_all(x0, &positions)?.is_empty() {
            return Ok(Resolved {
                positions,
                report: state.report,
            });
        }
        if attempt == 1 {
            break;
        }
        let mut u: Vec<DVec3> = positions.iter().zip(x0).map(|(p, x)| *p - *x).collect();
        if !state.substep(x0, &mut u)? {
            state.rigid_zones(x0, &mut u)?;
        }
        for (i, p) in positions.iter_mut().enumerate() {
            if state.detector.is_live(i) {
                *p = x0[i] + u[i];
            }
        }
    }
    Err(state.unresolved(ExhaustedBound::TouchingAtStart))
}

/// Checks lengths and finiteness before anything runs.
fn check_input(mesh: &LabeledMesh, proposed: &[DVec3]) -> Result<(), ResolveError> {
    if proposed.len() != mesh.vertex_capacity() {
        return Err(ResolveError::ProposalLength {
            expected: mesh.vertex_capacity(),
            got: proposed.len(),
        });
    }
    for v in mesh.vertices() {
        let (current, proposed) = (mesh.position(v), proposed[v.idx()]);
        if !(current.is_finite() && proposed.is_finite()) {
            return Err(ResolveError::NonFinite {
                vertex: v,
                current: current.to_array(),
                proposed: proposed.to_array(),
            });
        }
    }
    Ok(())
}

/// Working state of one [`resolve_step`].
struct Resolver {
    options: ResolveOptions,
    /// `1 / mᵢ` per vertex slot (all 1 for now).
    inverse_mass: Vec<f64>,
    detector: Detector,
    report: ResolveReport,
}

impl Resolver {
    /// Resolves the motion from `start` to `target`, halving on failure; returns the end
    /// positions. `depth` is the current halving level.
    fn advance(
        &mut self,
        start: &[DVec3],
        target: &[DVec3],
        depth: u32,
    ) -> Result<Vec<DVec3>, ResolveError> {
        let mut u: Vec<DVec3> = target.iter().zip(start).map(|(t, s)| *t - *s).collect();
        if !self.substep(start, &mut u)? {
            if depth < self.options.max_halvings {
                let half: Vec<DVec3> = start
                    .iter()
                    .zip(target)
                    .map(|(s, t)| *s + (*t - *s) * 0.5)
                    .collect();
                let middle = self.advance(start, &half, depth + 1)?;
                return self.advance(&middle, target, depth + 1);
            }
            if !self.options.rigid_fallback {
                return Err(self.unresolved(ExhaustedBound::Halvings {
                    max_halvings: self.options.max_halvings,
                }));
            }
            self.rigid_zones(start, &mut u)?;
        }
        self.report.substeps += 1;
        Ok(start.iter().zip(&u).map(|(s, v)| *s + *v).collect())
    }

    /// Sweeps of individual impulses, then impact zones, on the motion `start + t u`.
    /// `Ok(false)` when collisions remain (the detector keeps the last ones found).
    fn substep(&mut self, start: &[DVec3], u: &mut [DVec3]) -> Result<bool, ResolveError> {
        if !self.impulse_sweeps(start, u)? {
            return Ok(true);
        }
        self.impact_zones(start, u)
    }

    /// A full CCD pass (every candidate) on the straight lines from `start` to `end`,
    /// timed.
    fn detect_all(
        &mut self,
        start: &[DVec3],
        end: &[DVec3],
    ) -> Result<&[impulses::Hit], ResolveError> {
        let clock = Instant::now();
        self.detector.mark_all_dirty();
        let found = self.detector.detect(start, end, &self.options.ccd);
        self.report.seconds_ccd += clock.elapsed().as_secs_f64();
        found?;
        Ok(self.detector.hits())
    }

    /// The error for the collisions of the last detection pass.
    fn unresolved(&self, bound: ExhaustedBound) -> ResolveError {
        let hits = self.detector.hits();
        let mut vertices: Vec<VertexId> = hits
            .iter()
            .flat_map(|h| h.contact.vertices)
            .map(VertexId::new)
            .collect();
        vertices.sort_unstable();
        vertices.dedup();
        vertices.truncate(MAX_LISTED);
        ResolveError::Unresolved {
            bound,
            remaining: hits.len(),
            vertices,
        }
    }
}
