//! Stages 3 and 5 (El Topo §3.8, fail-safe; Harmon et al. 2008): impact zones.
//!
//! **Inelastic projection** ([`Resolver::impact_zones`]). The collisions left after the
//! sweeps become *constraints* `n · Σ wᵢ u'ᵢ = 0` (zero relative normal velocity, with the
//! weights and normal of the report). Constraints sharing a vertex belong to one *impact
//! zone* (union–find over vertices; zones only grow within a substep). Each zone that
//! received a new constraint is solved at once for the velocities closest to the current
//! ones in the mass norm:
//!
//! ```text
//! min ‖u' − u‖²_M  subject to  C u' = 0   ⇒   C M⁻¹ Cᵀ λ = C u,   u' = u − M⁻¹ Cᵀ λ,
//! ```
//!
//! `C` having one row per constraint with the 3-blocks `wᵥ nᵀ`. The matrix is assembled
//! with sprs (entries `Σ_v wᵣᵥ wₛᵥ (nᵣ · nₛ) / m_v` over shared vertices) and solved by
//! Jacobi-preconditioned conjugate gradients, which also handles the singular but
//! consistent systems of repeated or dependent constraints. Zones are independent and
//! solved in parallel. Then CCD runs again on the changed vertices and the new collisions
//! join the constraints, until CCD finds nothing or the iteration bound is reached.
//!
//! **Rigid impact zones** ([`Resolver::rigid_zones`], the last resort). Every colliding
//! pair's vertices join a zone; each zone moves by one common translation, the
//! mass-weighted mean of its velocities (momentum is conserved). A translation cannot make
//! a zone collide with itself, so new collisions involve another zone or a free vertex and
//! merge them: every round either succeeds or merges, so the loop ends within the vertex
//! count. A collision inside one zone means the elements touch at the start of the step.
//! (Only translations: an interpolated rotation is not rigid along a straight line.)

use std::time::Instant;

use glam::DVec3;
use rayon::prelude::*;
use sprs::TriMat;

use super::impulses::Contact;
use super::{ExhaustedBound, ResolveError, Resolver};

/// Disjoint sets over vertex slots (path halving, union by size).
struct UnionFind {
    parent: Vec<u32>,
    size: Vec<u32>,
}

impl UnionFind {
    fn new(n: usize) -> UnionFind {
        UnionFind {
            parent: (0..n as u32).collect(),
            size: vec![1; n],
        }
    }

    fn find(&mut self, mut v: u32) -> u32 {
        while self.parent[v as usize] != v {
            let grand = self.parent[self.parent[v as usize] as usize];
            self.parent[v as usize] = grand;
            v = grand;
        }
        v
    }

    /// Joins the sets of `a` and `b`; true when they were different.
    fn union(&mut self, a: u32, b: u32) -> bool {
        let (mut a, mut b) = (self.find(a), self.find(b));
        if a == b {
            return false;
        }
        if self.size[a as usize] < self.size[b as usize] {
            std::mem::swap(&mut a, &mut b);
        }
        self.parent[b as usize] = a;
        self.size[a as usize] += self.size[b as usize];
        true
    }
}

impl Resolver {
    /// The inelastic-projection stage on the motion `start + t u`, starting from the hits
    /// the detector holds. Returns whether CCD ended with no collision.
    pub(super) fn impact_zones(
        &mut self,
        start: &[DVec3],
        u: &mut [DVec3],
    ) -> Result<bool, ResolveError> {
        let mut zones = UnionFind::new(u.len());
        let mut constraints: Vec<Contact> = Vec::new();
        let mut end: Vec<DVec3> = start.iter().zip(u.iter()).map(|(s, v)| *s + *v).collect();
        let mut fresh = vec![false; u.len()];
        let ccd = self.options.ccd;
        for _ in 0..self.options.max_zone_iterations {
            if self.detector.hits().is_empty() {
                return Ok(true);
            }
            let clock = Instant::now();
            self.report.zone_iterations += 1;
            for hit in self.detector.hits() {
                let [a, b, c, d] = hit.contact.vertices;
                zones.union(a, b);
                zones.union(a, c);
                zones.union(a, d);
                constraints.push(hit.contact);
            }
            // Zones with a new constraint are solved again (the others are satisfied).
            fresh.fill(false);
            for hit in self.detector.hits() {
                let root = zones.find(hit.contact.vertices[0]);
                fresh[root as usize] = true;
            }
            let mut grouped: Vec<(u32, Contact)> = constraints
                .iter()
                .map(|c| (zones.find(c.vertices[0]), *c))
                .filter(|(root, _)| fresh[*root as usize])
                .collect();
            grouped.sort_by_key(|(root, _)| *root);
            let groups: Vec<&[(u32, Contact)]> = grouped.chunk_by(|a, b| a.0 == b.0).collect();
            self.report.impact_zones += groups.len();
            let current: &[DVec3] = u;
            let inverse_mass = &self.inverse_mass;
            let updates: Vec<Vec<(u32, DVec3)>> = groups
                .par_iter()
                .map(|group| project_zone(group, current, inverse_mass))
                .collect();
            self.detector.clear_dirty();
            for (v, velocity) in updates.into_iter().flatten() {
                u[v as usize] = velocity;
                end[v as usize] = start[v as usize] + velocity;
                self.detector.mark_dirty(v);
            }
            self.report.seconds_zones += clock.elapsed().as_secs_f64();

            let clock = Instant::now();
            self.detector.detect(start, &end, &ccd)?;
            self.report.seconds_ccd += clock.elapsed().as_secs_f64();
        }
        Ok(self.detector.hits().is_empty())
    }

    /// The rigid-impact-zone last resort on the motion `start + t u`: colliding vertices
    /// are grouped into zones, each translated by its mean velocity, merged until CCD finds
    /// nothing. Errors when a collision lies inside one zone (touching at the start).
    pub(super) fn rigid_zones(
        &mut self,
        start: &[DVec3],
        u: &mut [DVec3],
    ) -> Result<(), ResolveError> {
        let velocities = u.to_vec();
        let mut zones = UnionFind::new(u.len());
        let mut members: Vec<u32> = Vec::new();
        let mut end: Vec<DVec3> = start.iter().zip(u.iter()).map(|(s, v)| *s + *v).collect();
        self.detect_all(start, &end)?;
        let bound = self.detector.hits().len() + u.len() + 1;
        let ccd = self.options.ccd;
        for _ in 0..bound {
            if self.detector.hits().is_empty() {
                return Ok(());
            }
            let clock = Instant::now();
            let mut merged = false;
            for hit in self.detector.hits() {
                let [a, b, c, d] = hit.contact.vertices;
                merged |= zones.union(a, b) | zones.union(a, c) | zones.union(a, d);
                members.extend_from_slice(&hit.contact.vertices);
            }
            if !merged {
                return Err(self.unresolved(ExhaustedBound::TouchingAtStart));
            }
            members.sort_unstable();
            members.dedup();
            let mut by_zone: Vec<(u32, u32)> =
                members.iter().map(|&v| (zones.find(v), v)).collect();
            by_zone.sort_unstable();
            self.detector.clear_dirty();
            let mut count = 0;
            for zone in by_zone.chunk_by(|a, b| a.0 == b.0) {
                count += 1;
                let (mut momentum, mut mass) = (DVec3::ZERO, 0.0);
                for &(_, v) in zone {
                    let m = 1.0 / self.inverse_mass[v as usize];
                    momentum += velocities[v as usize] * m;
                    mass += m;
                }
                let common = if mass > 0.0 && mass.is_finite() {
                    momentum / mass
                } else {
                    DVec3::ZERO
                };
                for &(_, v) in zone {
                    u[v as usize] = common;
                    end[v as usize] = start[v as usize] + common;
                    self.detector.mark_dirty(v);
                }
            }
            self.report.rigid_zones = count;
            self.report.seconds_zones += clock.elapsed().as_secs_f64();

            let clock = Instant::now();
            self.detector.detect(start, &end, &ccd)?;
            self.report.seconds_ccd += clock.elapsed().as_secs_f64();
        }
        Err(self.unresolved(ExhaustedBound::RigidIterations { iterations: bound }))
    }
}

/// Inelastic projection of one zone: the new velocities of its vertices.
fn project_zone(group: &[(u32, Contact)], u: &[DVec3], inverse_mass: &[f64]) -> Vec<(u32, DVec3)> {
    let rows = group.len();
    // Entries (vertex, row, weight), grouped by vertex to find the rows sharing one.
    let mut entries: Vec<(u32, u32, f64)> = group
        .iter()
        .enumerate()
        .flat_map(|(r, (_, c))| (0..4).map(move |i| (c.vertices[i], r as u32, c.weights[i])))
        .collect();
    entries.sort_unstable_by_key(|&(v, r, _)| (v, r));
    let mut matrix = TriMat::new((rows, rows));
    for shared in entries.chunk_by(|a, b| a.0 == b.0) {
        let inv_m = inverse_mass[shared[0].0 as usize];
        for &(_, r, wr) in shared {
            for &(_, s, ws) in shared {
                let (nr, ns) = (group[r as usize].1.normal, group[s as usize].1.normal);
                matrix.add_triplet(r as usize, s as usize, wr * ws * inv_m * nr.dot(ns));
            }
        }
    }
    let matrix = matrix.to_csr::<usize>();
    let rhs: Vec<f64> = group
        .iter()
        .map(|(_, c)| c.normal.dot(c.relative_velocity(u)))
        .collect();
    let lambda = conjugate_gradients(&matrix, &rhs);

    // u' = u − M⁻¹ Cᵀ λ, vertex by vertex.
    let mut out: Vec<(u32, DVec3)> = Vec::new();
    for shared in entries.chunk_by(|a, b| a.0 == b.0) {
        let v = shared[0].0;
        let change: DVec3 = shared
            .iter()
            .map(|&(_, r, w)| group[r as usize].1.normal * (w * lambda[r as usize]))
            .sum();
        out.push((v, u[v as usize] - change * inverse_mass[v as usize]));
    }
    out
}

/// Solves `A λ = b` (`b` in the range of `A`) by mesh-core's Jacobi-preconditioned
/// conjugate gradients, to a relative residual of `1e-13` or `2n + 20` iterations (exact
/// arithmetic needs at most `n`).
fn conjugate_gradients(a: &sprs::CsMat<f64>, b: &[f64]) -> Vec<f64> {
    let n = b.len();
    let inverse_diagonal: Vec<f64> = (0..n)
        .map(|i| match a.get(i, i) {
            Some(&d) if d > 0.0 => 1.0 / d,
            _ => 1.0,
        })
        .collect();
    let multiply = |x: &[f64], y: &mut [f64]| {
        for (i, row) in a.outer_iterator().enumerate() {
            y[i] = row.iter().map(|(j, &v)| v * x[j]).sum();
        }
    };
    mesh_core::solve::conjugate_gradients(b, &inverse_diagonal, 1e-13, 2 * n + 20, multiply, |_| {})
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn union_find_merges_and_reports_changes() {
        let mut uf = UnionFind::new(5);
        assert!(uf.union(0, 1));
        assert!(uf.union(3, 4));
        assert!(!uf.union(1, 0));
        assert!(uf.union(1, 4));
        assert_eq!(uf.find(0), uf.find(3));
        assert_ne!(uf.find(2), uf.find(0));
    }

    #[test]
    fn projection_zeroes_every_constraint_of_a_zone() {
        // A vertex squeezed between two triangles: two constraints sharing vertex 0.
        let c1 = Contact {
            vertices: [0, 1, 2, 3],
            weights: [1.0, -0.2, -0.3, -0.5],
            normal: DVec3::Z,
        };
        let c2 = Contact {
            vertices: [0, 4, 5, 6],
            weights: [1.0, -0.6, -0.2, -0.2],
            normal: -DVec3::Z,
        };
        let mut u = vec![DVec3::ZERO; 7];
        u[0] = DVec3::new(0.3, 0.0, -1.0);
        u[4] = DVec3::new(0.0, 0.0, -0.5);
        let group = [(0, c1), (0, c2)];
        for (v, w) in project_zone(&group, &u, &[1.0; 7]) {
            u[v as usize] = w;
        }
        for c in [c1, c2] {
            assert!(c.normal.dot(c.relative_velocity(&u)).abs() < 1e-12);
        }
        // Momentum is conserved.
        let total: DVec3 = u.iter().copied().sum();
        assert!((total - DVec3::new(0.3, 0.0, -1.5)).length() < 1e-12);
    }
}
