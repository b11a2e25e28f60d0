//! Stage 1 (El Topo §3.8, first phase): proximity repulsion.
//!
//! Pairs of elements closer than the repulsion distance `ε_p` at the start of the step get
//! an impulse along their closest-point normal so that, integrated over the step, they end
//! at least `ε_p` apart: the relative normal velocity is raised to `(ε_p − d) / Δt`
//! (`Δt = 1`), nothing is done when it already is. Positions are not moved, only
//! velocities. This keeps the surfaces from grazing, which is where CCD is slow and
//! impulses oscillate, and removes most collisions before CCD runs.
//!
//! Distances are computed in parallel (positions do not change in this stage); the
//! impulses are then applied one pair at a time on the current velocities.

use std::time::Instant;

use glam::DVec3;
use rayon::prelude::*;

use super::impulses::Contact;
use super::{ResolveError, Resolver};
use crate::proximity::{Proximity, proximity_edge_edge, proximity_vertex_triangle};

impl Resolver {
    /// Applies repulsion impulses for every pair closer than
    /// [`super::ResolveOptions::proximity`] at `x0`, updating `u`.
    pub(super) fn repulsion(&mut self, x0: &[DVec3], u: &mut [DVec3]) -> Result<(), ResolveError> {
        let reach = self.options.proximity;
        if !(reach > 0.0 && reach.is_finite()) {
            return Ok(());
        }
        let clock = Instant::now();
        let broadphase = self.detector.broadphase_mut();
        broadphase.proximity_candidates(x0, reach)?;
        let elements = broadphase.elements();
        let candidates = broadphase.candidates();
        let close_pair = |quad: [u32; 4], proximity: Proximity| {
            (proximity.distance < reach).then_some((
                Contact {
                    vertices: quad,
                    weights: proximity.weights,
                    normal: proximity.normal,
                },
                proximity.distance,
            ))
        };
        let p = |v: u32| x0[v as usize];
        let mut close: Vec<(Contact, f64)> = candidates
            .vertex_triangle
            .par_iter()
            .with_min_len(256)
            .filter_map(|&pair| {
                let quad = elements.vertex_triangle_quad(pair).map(|v| v.raw());
                let proximity =
                    proximity_vertex_triangle(p(quad[0]), [p(quad[1]), p(quad[2]), p(quad[3])]);
                close_pair(quad, proximity)
            })
            .collect();
        close.par_extend(
            candidates
                .edge_edge
                .par_iter()
                .with_min_len(256)
                .filter_map(|&pair| {
                    let quad = elements.edge_edge_quad(pair).map(|v| v.raw());
                    let proximity =
                        proximity_edge_edge(p(quad[0]), p(quad[1]), p(quad[2]), p(quad[3]));
                    close_pair(quad, proximity)
                }),
        );
        for (contact, distance) in close {
            if contact.push_apart(
                u,
                &self.inverse_mass,
                reach - distance,
                self.options.friction,
            ) {
                self.report.repulsion_impulses += 1;
            }
        }
        self.report.seconds_proximity += clock.elapsed().as_secs_f64();
        Ok(())
    }
}
