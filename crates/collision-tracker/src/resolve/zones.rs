//! Stages 3 and 5 (El Topo §3.8, fail-safe; Harmon et al. 2008): impact zones.
//!
//! **Inelastic projection** ([`Resolver::impact_zones`]). The collisions left after the
//! sweeps become *constraints* `n · Σ wᵢ u'ᵢ = 0` (zero relative normal velocity, with the
//! weights and normal of the report), one per colliding pair: a pair found again replaces
//! its earlier contact. Constraints sharing a vertex belong to one *impact zone*
//! (union–find over vertices; zones only grow within a substep). Each zone that received
//! a new constraint is solved at once for the velocities closest to the current ones in
//! the mass norm:
//!
//! ```text
//! min ‖u' − u‖²_M  subject to  C u' = 0,
//! ```
//!
//! `C` having one row per constraint with the 3-blocks `wᵥ nᵀ`: `u'` is the projection of
//! `u` onto the null space of `C`, computed as the residual of a least-squares problem by
//! conjugate gradients (CGLS, see [`project_zone`] for why not the normal equations).
//! Zones are independent and solved in parallel. Then CCD runs again on the changed
//! vertices and the new collisions join the constraints, until CCD finds nothing or the
//! iteration bound is reached.
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

use std::collections::HashMap;
use std::collections::hash_map::Entry;

use super::impulses::{Contact, PairKind};
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
        // One constraint per colliding pair: a pair found again replaces its contact (the
        // newer normal and weights). Keeping both adds a nearly dependent row — the same
        // pair, a turned normal — and pairs of nearly touching sheets are found again and
        // again (up to 23 rows for one edge pair, measured on two merging spheres): such
        // zones grew to ~1300 rows that neither CG nor CGLS solved (relative residuals of
        // 5 % to over 100 % after 2m iterations), every zone round found a few new hits,
        // and the stage ran to its bound and halved the step (seed 2 of two spheres, side
        // by side: 532 s with 462 s in zones before, 31 s with 0.35 s after).
        let mut constraints: Vec<Contact> = Vec::new();
        let mut row_of: HashMap<(PairKind, [u32; 4]), usize> = HashMap::new();
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
                match row_of.entry((hit.kind, hit.contact.vertices)) {
                    Entry::Occupied(row) => constraints[*row.get()] = hit.contact,
                    Entry::Vacant(row) => {
                        row.insert(constraints.len());
                        constraints.push(hit.contact);
                    }
                }
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
///
/// Solved as the least-squares problem it is, not through the normal equations: with
/// `y = M^{1/2} u` and `K = C M^{-1/2}` (rows scaled to unit length), `u' = M^{-1/2} y'`
/// where `y' = y − Kᵀ μ` is the residual of `min_μ ‖y − Kᵀ μ‖`, i.e. the projection of `y`
/// onto the null space of `K`. The problem is feasible for any set of constraints
/// (`u' = 0` satisfies all of them) and CGLS keeps the projected velocities themselves as
/// its iterate, so dependent rows need no special care. It is also cheaper than CG on
/// `C M⁻¹ Cᵀ λ = C u`: that matrix has to be assembled and has ~120 entries per row on the
/// contact zone of two pressed sheets, where `K` has 12.
fn project_zone(group: &[(u32, Contact)], u: &[DVec3], inverse_mass: &[f64]) -> Vec<(u32, DVec3)> {
    // Zone vertices, and each row's four local vertex indices and scaled weights.
    let mut vertices: Vec<u32> = group.iter().flat_map(|(_, c)| c.vertices).collect();
    vertices.sort_unstable();
    vertices.dedup();
    let local = |v: u32| vertices.binary_search(&v).expect("a zone vertex") as u32;
    let scale: Vec<f64> = vertices
        .iter()
        .map(|&v| inverse_mass[v as usize].max(0.0).sqrt())
        .collect();
    let rows: Vec<Row> = group
        .iter()
        .map(|(_, c)| {
            let at = c.vertices.map(local);
            let mut coefficients = [0.0; 4];
            for i in 0..4 {
                coefficients[i] = c.weights[i] * scale[at[i] as usize];
            }
            let norm = coefficients.iter().map(|w| w * w).sum::<f64>().sqrt();
            if norm > 0.0 && norm.is_finite() {
                coefficients.iter_mut().for_each(|w| *w /= norm);
            } else {
                coefficients = [0.0; 4];
            }
            Row {
                at,
                coefficients,
                normal: c.normal,
            }
        })
        .collect();
    // y = M^{1/2} u (an immovable vertex, `1/m = 0`, takes no part: its columns are 0).
    let y: Vec<DVec3> = vertices
        .iter()
        .zip(&scale)
        .map(|(&v, &s)| {
            if s > 0.0 {
                u[v as usize] / s
            } else {
                DVec3::ZERO
            }
        })
        .collect();
    let projected = null_space_projection(&rows, y);
    vertices
        .iter()
        .zip(&scale)
        .zip(projected)
        .map(|((&v, &s), y)| (v, if s > 0.0 { y * s } else { u[v as usize] }))
        .collect()
}

/// One constraint row of `K`: `Σᵢ coefficientsᵢ (normal · y[atᵢ]) = 0`.
struct Row {
    at: [u32; 4],
    coefficients: [f64; 4],
    normal: DVec3,
}

/// The residual `y − Kᵀ μ` of `min_μ ‖y − Kᵀ μ‖` by CGLS (conjugate gradients on the
/// least-squares problem, keeping the residual itself as the iterate): stops when
/// `‖K r‖` — the remaining constraint violation — is `10⁻¹²` of its start, or after
/// `2m + 20` iterations (`m` rows; exact arithmetic needs at most `m`).
///
/// Every exact CGLS step shortens `r` (by `α γ`), so the result is never longer than `y`
/// (a projection). Past convergence the steps run on rounding noise, where `α` can be
/// anything: a four-vertex zone whose velocities already nearly met its one contact came
/// back 10⁷ times longer, and in a 15k-vertex zone of two crossing cylinders turned
/// rigidly (collision backend) velocities of 10⁹⁷ and ∞ made every pair a CCD candidate
/// and the process was killed at 24 GB. So the iteration also stops when `‖K r‖²` is
/// down to the rounding of `K r` itself (about `ε ‖y‖∞` per row), and, as a backstop,
/// when a step would lengthen `r` (by more than 10⁻⁶ of it: nearly dependent contacts
/// converge through steps that round to no change).
fn null_space_projection(rows: &[Row], y: Vec<DVec3>) -> Vec<DVec3> {
    let apply = |r: &[DVec3], out: &mut [f64]| {
        for (row, o) in rows.iter().zip(out.iter_mut()) {
            *o = (0..4)
                .map(|i| row.coefficients[i] * row.normal.dot(r[row.at[i] as usize]))
                .sum();
        }
    };
    let apply_transposed = |p: &[f64], out: &mut [DVec3]| {
        out.fill(DVec3::ZERO);
        for (row, &p) in rows.iter().zip(p) {
            for i in 0..4 {
                out[row.at[i] as usize] += row.normal * (row.coefficients[i] * p);
            }
        }
    };
    let dot = |a: &[f64], b: &[f64]| -> f64 { a.iter().zip(b).map(|(x, y)| x * y).sum() };
    let m = rows.len();
    let mut r = y;
    let mut length: f64 = r.iter().map(|v| v.length_squared()).sum();
    let mut s = vec![0.0; m];
    apply(&r, &mut s);
    let mut gamma = dot(&s, &s);
    let largest = r.iter().map(|v| v.abs().max_element()).fold(0.0, f64::max);
    let rounding = 64.0 * f64::EPSILON * largest;
    let stop = (1e-24 * gamma).max(m as f64 * rounding * rounding);
    let mut p = s.clone();
    let mut q = vec![DVec3::ZERO; r.len()];
    let mut candidate = vec![DVec3::ZERO; r.len()];
    for _ in 0..2 * m + 20 {
        if gamma <= stop || gamma.is_nan() {
            break;
        }
        apply_transposed(&p, &mut q);
        let qq: f64 = q.iter().map(|v| v.length_squared()).sum();
        if !(qq > 0.0 && qq.is_finite()) {
            break;
        }
        let alpha = gamma / qq;
        // The step is taken into `candidate` and its length summed in the same pass; it
        // replaces `r` only if it is not longer.
        let mut next_length = 0.0;
        for ((c, r), q) in candidate.iter_mut().zip(&r).zip(&q) {
            *c = *r - *q * alpha;
            next_length += c.length_squared();
        }
        let diverging = next_length.is_nan() || next_length > length * (1.0 + 1e-6);
        if diverging {
            break; // keep the shorter iterate
        }
        length = next_length;
        std::mem::swap(&mut r, &mut candidate);
        apply(&r, &mut s);
        let next = dot(&s, &s);
        let beta = next / gamma;
        gamma = next;
        for (p, s) in p.iter_mut().zip(&s) {
            *p = *s + beta * *p;
        }
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A zone the crossing-cylinders run met (rotation, collision backend): four vertices,
    /// one contact their velocities already nearly satisfy. One CGLS step projects exactly;
    /// the iterations after it ran on rounding noise and returned velocities 10⁷ times
    /// longer (and, in larger zones, ∞).
    #[test]
    fn a_nearly_satisfied_contact_is_projected_not_blown_up() {
        let y = vec![
            DVec3::new(
                -5.014539531590734e-2,
                3.726361529960431e-2,
                3.3964870477843548e-6,
            ),
            DVec3::new(
                -5.0373245935596e-2,
                3.710896176587623e-2,
                1.4746749144790542e-6,
            ),
            DVec3::new(
                -5.045314459547197e-2,
                3.6762666237971045e-2,
                5.2624065868130955e-6,
            ),
            DVec3::new(
                -5.044349564783362e-2,
                3.698518417095564e-2,
                3.136003807484728e-6,
            ),
        ];
        let row = Row {
            at: [0, 3, 1, 2],
            coefficients: [
                1.3786266456696433e-1,
                7.171479371810949e-1,
                -6.52417680885233e-1,
                -2.0259292086282618e-1,
            ],
            normal: DVec3::new(
                8.485318300313349e-1,
                -5.287011444383718e-1,
                2.165255858390793e-2,
            ),
        };
        let violation = |v: &[DVec3]| -> f64 {
            (0..4)
                .map(|i| row.coefficients[i] * row.normal.dot(v[row.at[i] as usize]))
                .sum()
        };
        let length = |v: &[DVec3]| -> f64 { v.iter().map(|v| v.length_squared()).sum() };
        let r = null_space_projection(std::slice::from_ref(&row), y.clone());
        assert!(length(&r) <= length(&y), "{} > {}", length(&r), length(&y));
        assert!(violation(&r).abs() <= 1e-15, "violation {}", violation(&r));
    }

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

    /// Two curved sheets pressed together, ~480 rows sharing vertices: every vertex of
    /// the upper sheet in a vertex–triangle and an edge–edge contact with the lower one,
    /// each contact `copies` times with its normal turned by up to `tilt` more per copy
    /// (as CCD finds a pair again). The upper sheet moves down onto the lower one, with
    /// some tangential noise.
    fn pressed_sheets(copies: u32, tilt: f64) -> (Vec<(u32, Contact)>, Vec<DVec3>) {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let side = 12u32;
        let sheet = side * side;
        let id = |sheet_index: u32, i: u32, j: u32| sheet_index * sheet + i * side + j;
        let mut group = Vec::new();
        for i in 0..side - 1 {
            for j in 0..side - 1 {
                let bend = 0.05 * DVec3::new(f64::from(i) - 5.5, f64::from(j) - 5.5, 0.0) / 5.5;
                let normal = (DVec3::Z + bend).normalize();
                let (a, b) = (rng.random_range(0.1..0.4), rng.random_range(0.1..0.4));
                let vertex_triangle = Contact {
                    vertices: [id(1, i, j), id(0, i, j), id(0, i + 1, j), id(0, i, j + 1)],
                    weights: [1.0, -(1.0 - a - b), -a, -b],
                    normal,
                };
                let (s, t) = (rng.random_range(0.2..0.8), rng.random_range(0.2..0.8));
                let edge_edge = Contact {
                    vertices: [
                        id(1, i, j),
                        id(1, i + 1, j + 1),
                        id(0, i + 1, j),
                        id(0, i, j + 1),
                    ],
                    weights: [1.0 - s, s, -(1.0 - t), -t],
                    normal,
                };
                for copy in 0..copies {
                    for contact in [vertex_triangle, edge_edge] {
                        let turn = DVec3::new(
                            rng.random_range(-tilt..=tilt),
                            rng.random_range(-tilt..=tilt),
                            0.0,
                        );
                        let normal = (contact.normal + turn * f64::from(copy)).normalize();
                        group.push((0, Contact { normal, ..contact }));
                    }
                }
            }
        }
        let u = (0..2 * sheet)
            .map(|v| {
                let down = if v >= sheet { -1e-3 } else { 0.0 };
                let noise = 1e-4;
                DVec3::new(
                    rng.random_range(-noise..noise),
                    rng.random_range(-noise..noise),
                    down,
                )
            })
            .collect();
        (group, u)
    }

    fn fastest_approach(group: &[(u32, Contact)], u: &[DVec3]) -> f64 {
        group
            .iter()
            .map(|(_, c)| c.normal.dot(c.relative_velocity(u)).abs())
            .fold(0.0, f64::max)
    }

    fn project(group: &[(u32, Contact)], u: &[DVec3]) -> Vec<DVec3> {
        let mut out = u.to_vec();
        for (v, w) in project_zone(group, u, &vec![1.0; u.len()]) {
            out[v as usize] = w;
        }
        out
    }

    /// Exactly repeated rows (dependent, consistent): every row satisfied, momentum kept.
    #[test]
    fn projection_of_a_dependent_sheet_contact_satisfies_every_row() {
        let (group, u) = pressed_sheets(2, 0.0);
        let projected = project(&group, &u);
        let worst = fastest_approach(&group, &projected);
        assert!(worst < 1e-12, "largest remaining approach speed {worst:e}");
        let (before, after): (DVec3, DVec3) = (u.iter().sum(), projected.iter().sum());
        assert!(
            (after - before).length() < 1e-12,
            "momentum {before} → {after}"
        );
    }

    /// Nearly dependent rows — the same pairs with normals turned by ~10⁻⁶, as repeated
    /// pairs gave before they replaced their rows — make the system nearly singular. The
    /// projection must still be one: no velocity grows in the mass norm, and every
    /// approach slows by orders of magnitude.
    #[test]
    fn projection_with_nearly_dependent_rows_stays_a_projection() {
        let (group, u) = pressed_sheets(3, 1e-6);
        let projected = project(&group, &u);
        let norm = |u: &[DVec3]| u.iter().map(|v| v.length_squared()).sum::<f64>().sqrt();
        assert!(norm(&projected) <= norm(&u) * (1.0 + 1e-12));
        let (before, after) = (
            fastest_approach(&group, &u),
            fastest_approach(&group, &projected),
        );
        assert!(after < 1e-3 * before, "approach {before:e} → {after:e}");
    }
}
