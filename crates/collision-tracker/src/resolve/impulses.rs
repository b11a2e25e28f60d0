//! Stage 2 (El Topo §3.8, second phase): individual CCD impulses.
//!
//! A [`Detector`] runs continuous collision detection on every swept-box candidate of
//! the current motion in parallel. [`Resolver::impulse_sweeps`] then walks the hits in
//! order (Gauss–Seidel) and gives each the inelastic impulse that zeroes its relative
//! normal velocity, `I = −n · Σ wᵢ uᵢ` — the least change of kinetic energy that stops
//! the approach. A hit whose vertices were already pushed in this sweep is re-tested first
//! (its motion changed). One sweep can create new collisions, so El Topo runs three.
//!
//! Between passes only pairs with a *dirty* vertex (one whose motion changed since the
//! last pass, or one that collided) are tested again: the others have the same
//! trajectories as when they were last found collision-free, so skipping them is exact.
//! The broad phase of such a pass queries only the dirty elements
//! ([`Broadphase::swept_candidates_touching`]).

use std::time::Instant;

use glam::DVec3;
use rayon::prelude::*;

use super::{ResolveError, Resolver};
use crate::broadphase::{Broadphase, BroadphaseQueryError};
use crate::ccd::{CcdOptions, Impact, ccd_edge_edge_with, ccd_vertex_triangle_with};

/// A contact: four vertex slots with El Topo's signed weights and a unit normal (see the
/// [glossary](super)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Contact {
    /// Vertex slots, `[p, a, b, c]` or `[p0, p1, q0, q1]`.
    pub vertices: [u32; 4],
    /// Signed weights, summing to zero.
    pub weights: [f64; 4],
    /// Unit normal from the second element towards the first.
    pub normal: DVec3,
}

impl Contact {
    /// The contact of a CCD report.
    pub fn of_impact(vertices: [u32; 4], impact: &Impact) -> Contact {
        Contact {
            vertices,
            weights: impact.weights,
            normal: impact.normal,
        }
    }

    /// Relative velocity `Σ wᵢ uᵢ` of the two contact points.
    #[inline]
    pub fn relative_velocity(&self, u: &[DVec3]) -> DVec3 {
        (0..4)
            .map(|i| u[self.vertices[i] as usize] * self.weights[i])
            .sum()
    }

    /// The relative normal velocity a colliding pair is given so that it comes to rest
    /// `rest` apart: `min(0, rest − d₀)`, `d₀ = n · Σ wᵢ startᵢ` its separation along the
    /// normal at the start of the step. Zero (El Topo's inelastic impulse) when `rest` is
    /// zero or the pair starts closer than `rest`: it is never pushed apart here (that is
    /// repulsion's job), only allowed to come closer.
    pub fn rest_velocity(&self, start: &[DVec3], rest: f64) -> f64 {
        if rest.is_nan() || rest <= 0.0 {
            return 0.0;
        }
        let separation: DVec3 = (0..4)
            .map(|i| start[self.vertices[i] as usize] * self.weights[i])
            .sum();
        let target = rest - self.normal.dot(separation);
        if target.is_finite() {
            target.min(0.0)
        } else {
            0.0
        }
    }

    /// Applies the impulse that raises the relative normal velocity to `target` (nothing
    /// when it is already at least that), with Coulomb friction `friction` on the
    /// tangential part. Returns whether an impulse was applied.
    pub fn push_apart(
        &self,
        u: &mut [DVec3],
        inverse_mass: &[f64],
        target: f64,
        friction: f64,
    ) -> bool {
        let relative = self.relative_velocity(u);
        let normal_velocity = self.normal.dot(relative);
        // Also false for NaN: never push on a meaningless velocity.
        let approaching = normal_velocity < target;
        if !approaching {
            return false;
        }
        let change = target - normal_velocity;
        let mut delta = self.normal * change;
        if friction > 0.0 {
            let tangential = relative - self.normal * normal_velocity;
            let speed = tangential.length();
            if speed > 0.0 {
                delta -= tangential * (friction * change / speed).min(1.0);
            }
        }
        self.change_relative_velocity(u, inverse_mass, delta)
    }

    /// Changes the relative velocity by `delta` with the impulse of least kinetic energy:
    /// `uᵢ += wᵢ Δ / (mᵢ Σⱼ wⱼ²/mⱼ)`. False when every vertex is immovable.
    pub fn change_relative_velocity(
        &self,
        u: &mut [DVec3],
        inverse_mass: &[f64],
        delta: DVec3,
    ) -> bool {
        let denominator: f64 = (0..4)
            .map(|i| self.weights[i] * self.weights[i] * inverse_mass[self.vertices[i] as usize])
            .sum();
        if !(denominator > 0.0 && denominator.is_finite()) {
            return false;
        }
        let impulse = delta / denominator;
        for i in 0..4 {
            let v = self.vertices[i] as usize;
            u[v] += impulse * (self.weights[i] * inverse_mass[v]);
        }
        true
    }
}

/// Which kernel a contact came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(super) enum PairKind {
    /// Vertex `[0]` against triangle `[1, 2, 3]`.
    VertexTriangle,
    /// Edge `[0, 1]` against edge `[2, 3]`.
    EdgeEdge,
}

/// One collision found by a CCD pass.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Hit {
    /// Which kernel to rerun on it.
    pub kind: PairKind,
    /// Vertices, weights and normal at the (conservative) time of impact.
    pub contact: Contact,
}

impl Hit {
    /// Reruns the kernel on the pair's current motion.
    pub fn retest(&self, start: &[DVec3], u: &[DVec3], ccd: &CcdOptions) -> Option<Hit> {
        test(
            self.kind,
            self.contact.vertices,
            start,
            |v| start[v] + u[v],
            ccd,
        )
    }
}

/// CCD of one pair: `x0 = start`, `x1 = end(v)`.
#[inline]
fn test(
    kind: PairKind,
    vertices: [u32; 4],
    start: &[DVec3],
    end: impl Fn(usize) -> DVec3,
    ccd: &CcdOptions,
) -> Option<Hit> {
    let x0 = vertices.map(|v| start[v as usize]);
    let x1 = vertices.map(|v| end(v as usize));
    let impact = match kind {
        PairKind::VertexTriangle => ccd_vertex_triangle_with(x0, x1, ccd),
        PairKind::EdgeEdge => ccd_edge_edge_with(x0, x1, ccd),
    }?;
    Some(Hit {
        kind,
        contact: Contact::of_impact(vertices, &impact),
    })
}

/// Continuous collision detection over the whole mesh, with dirty-vertex filtering and
/// reused buffers (see the [module docs](self)).
pub(super) struct Detector {
    broadphase: Broadphase,
    /// Per vertex slot: its motion changed since the last pass (or it collided).
    dirty: Vec<bool>,
    /// Every vertex is dirty (skips the lookups).
    all_dirty: bool,
    hits: Vec<Hit>,
}

impl Detector {
    /// A detector over the broad phase's elements, for `slots` vertex slots.
    pub fn new(broadphase: Broadphase, slots: usize) -> Detector {
        Detector {
            broadphase,
            dirty: vec![true; slots],
            all_dirty: true,
            hits: Vec::new(),
        }
    }

    /// The broad phase (for the proximity queries of repulsion).
    pub fn broadphase_mut(&mut self) -> &mut Broadphase {
        &mut self.broadphase
    }

    /// True for the slot of a live vertex.
    pub fn is_live(&self, slot: usize) -> bool {
        self.broadphase.is_live_slot(slot)
    }

    /// The next pass tests every candidate.
    pub fn mark_all_dirty(&mut self) {
        self.all_dirty = true;
    }

    /// The next pass tests only pairs with a vertex marked after this call.
    pub fn clear_dirty(&mut self) {
        self.all_dirty = false;
        self.dirty.fill(false);
    }

    /// Marks a vertex slot for the next pass.
    #[inline]
    pub fn mark_dirty(&mut self, slot: u32) {
        self.dirty[slot as usize] = true;
    }

    /// The hits of the last pass, in candidate order.
    pub fn hits(&self) -> &[Hit] {
        &self.hits
    }

    /// One CCD pass over the straight lines from `start` to `end`: the swept-box
    /// candidates with a dirty vertex, tested in parallel; the hits replace the previous
    /// ones.
    pub fn detect(
        &mut self,
        start: &[DVec3],
        end: &[DVec3],
        ccd: &CcdOptions,
    ) -> Result<(), BroadphaseQueryError> {
        if self.all_dirty {
            self.broadphase.swept_candidates(start, end, 0.0)?;
        } else {
            self.broadphase
                .swept_candidates_touching(start, end, 0.0, &self.dirty)?;
        }
        let elements = self.broadphase.elements();
        let candidates = self.broadphase.candidates();
        let (dirty, all_dirty) = (&self.dirty, self.all_dirty);
        let wanted = |quad: &[u32; 4]| all_dirty || quad.iter().any(|&v| dirty[v as usize]);
        let run = |kind, quad: [u32; 4]| {
            if wanted(&quad) {
                test(kind, quad, start, |v| end[v], ccd)
            } else {
                None
            }
        };
        self.hits.clear();
        self.hits.par_extend(
            candidates
                .vertex_triangle
                .par_iter()
                .with_min_len(256)
                .filter_map(|&pair| {
                    let quad = elements.vertex_triangle_quad(pair).map(|v| v.raw());
                    run(PairKind::VertexTriangle, quad)
                }),
        );
        self.hits.par_extend(
            candidates
                .edge_edge
                .par_iter()
                .with_min_len(256)
                .filter_map(|&pair| {
                    let quad = elements.edge_edge_quad(pair).map(|v| v.raw());
                    run(PairKind::EdgeEdge, quad)
                }),
        );
        Ok(())
    }
}

impl Resolver {
    /// Runs [`super::ResolveOptions::impulse_sweeps`] sweeps of individual impulses on the
    /// motion `start + t u`, updating `u`. Returns whether collisions remain; the detector
    /// then holds them (the result of a pass after the last sweep).
    pub(super) fn impulse_sweeps(
        &mut self,
        start: &[DVec3],
        u: &mut [DVec3],
    ) -> Result<bool, ResolveError> {
        let clock = Instant::now();
        let mut end: Vec<DVec3> = start.iter().zip(u.iter()).map(|(s, v)| *s + *v).collect();
        let mut touched = vec![false; u.len()];
        self.detector.mark_all_dirty();
        let ccd = self.options.ccd;
        for _sweep in 0..self.options.impulse_sweeps {
            self.detector.detect(start, &end, &ccd)?;
            if self.detector.hits().is_empty() {
                self.report.seconds_ccd += clock.elapsed().as_secs_f64();
                return Ok(false);
            }
            touched.fill(false);
            for hit in self.detector.hits() {
                let vertices = hit.contact.vertices;
                let current = if vertices.iter().any(|&v| touched[v as usize]) {
                    match hit.retest(start, u, &ccd) {
                        Some(h) => h,
                        None => continue,
                    }
                } else {
                    *hit
                };
                let target = current
                    .contact
                    .rest_velocity(start, self.options.rest_distance);
                if current
                    .contact
                    .push_apart(u, &self.inverse_mass, target, self.options.friction)
                {
                    self.report.ccd_impulses += 1;
                    for v in vertices {
                        touched[v as usize] = true;
                        end[v as usize] = start[v as usize] + u[v as usize];
                    }
                }
            }
            // Next pass: pairs whose motion changed, and pairs that collided.
            let hit_vertices: Vec<u32> = self
                .detector
                .hits()
                .iter()
                .flat_map(|h| h.contact.vertices)
                .collect();
            self.detector.clear_dirty();
            for v in hit_vertices {
                self.detector.mark_dirty(v);
            }
            for (v, &t) in touched.iter().enumerate() {
                if t {
                    self.detector.mark_dirty(v as u32);
                }
            }
        }
        self.detector.detect(start, &end, &ccd)?;
        self.report.seconds_ccd += clock.elapsed().as_secs_f64();
        Ok(!self.detector.hits().is_empty())
    }
}
