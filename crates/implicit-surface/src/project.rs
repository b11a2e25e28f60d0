//! Stage 1 — projection onto the surface by Newton–Raphson along the gradient (paper
//! §2.2, eq. 2): `p_{k+1} = p_k − F(p_k) ∇F(p_k) / ‖∇F(p_k)‖²`.
//!
//! Bounded: at most [`ProjectParams::max_iterations`] steps, each clamped to
//! [`ProjectParams::max_step`] and the whole walk to [`ProjectParams::max_travel`], so a
//! point near a flat spot of the field cannot be thrown across the scene. Where the
//! iteration fails the point is *quasi-critical* (the paper's term: intuitively near a
//! critical point of `F`, e.g. the saddle between two blobs that just separated): the
//! result says why ([`Projection::outcome`]) and where the walk ended.

use glam::DVec3;

use crate::error::{ImplicitError, invalid};
use crate::field::ImplicitField;

/// Options of [`project_point`]; lengths are absolute (the follower derives them from
/// its target edge length).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProjectParams {
    /// Bound on Newton steps. Default 8 (the paper fixes a small maximum).
    pub max_iterations: usize,
    /// Converged when the Newton step `|F| / ‖∇F‖` (a first-order distance to the
    /// surface) is below this. Default 1e-6.
    pub tolerance: f64,
    /// Largest length of one step. Default 0.5.
    pub max_step: f64,
    /// Largest distance from the start the walk may reach. Default 2.0.
    pub max_travel: f64,
    /// `‖∇F‖` below this counts as a flat spot (a critical point): the walk stops there.
    /// Default 1e-9.
    pub min_gradient: f64,
}

impl Default for ProjectParams {
    fn default() -> Self {
        Self {
            max_iterations: 8,
            tolerance: 1e-6,
            max_step: 0.5,
            max_travel: 2.0,
            min_gradient: 1e-9,
        }
    }
}

impl ProjectParams {
    /// Checks every field, naming the bad one.
    pub fn check(&self) -> Result<(), ImplicitError> {
        const W: &str = "ProjectParams";
        if !(1..=1000).contains(&self.max_iterations) {
            return Err(invalid(
                W,
                "max_iterations",
                self.max_iterations,
                "in 1..=1000",
            ));
        }
        for (name, v) in [
            ("tolerance", self.tolerance),
            ("max_step", self.max_step),
            ("max_travel", self.max_travel),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(invalid(W, name, v, "finite and > 0"));
            }
        }
        if !(self.min_gradient.is_finite() && self.min_gradient >= 0.0) {
            return Err(invalid(
                W,
                "min_gradient",
                self.min_gradient,
                "finite and ≥ 0",
            ));
        }
        Ok(())
    }

    /// These parameters with the step lengths scaled for a mesh of edge length `h`:
    /// steps of at most `step_fraction · h`, a walk of at most `travel_fraction · h`,
    /// tolerance `1e-6 · h`.
    pub fn for_edge_length(h: f64, step_fraction: f64, travel_fraction: f64) -> Self {
        Self {
            tolerance: 1e-6 * h,
            max_step: step_fraction * h,
            max_travel: travel_fraction * h,
            ..Self::default()
        }
    }
}

/// How a projection ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ProjectionOutcome {
    /// `|F|/‖∇F‖ < tolerance` after this many steps (0: it already was).
    Converged {
        /// Newton steps taken.
        iterations: u32,
    },
    /// The gradient vanished (or the field was not finite): a critical point.
    FlatGradient,
    /// Out of iterations, or the walk hit `max_travel`: no surface within reach.
    NotConverged,
}

/// The result of one projection.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Projection {
    /// Where the walk ended (the surface point when converged).
    pub position: DVec3,
    /// `F` there.
    pub value: f64,
    /// Why it ended.
    pub outcome: ProjectionOutcome,
}

impl Projection {
    /// True when the point was not projected: the paper's quasi-critical point.
    pub fn is_quasi_critical(&self) -> bool {
        !matches!(self.outcome, ProjectionOutcome::Converged { .. })
    }
}

/// Projects `p` onto `F(·, t) = 0` by eq. 2 (see the module doc). Never panics: a
/// non-finite field ends the walk as [`ProjectionOutcome::FlatGradient`] at the last
/// finite position.
pub fn project_point(
    field: &(impl ImplicitField + ?Sized),
    p: DVec3,
    t: f64,
    params: &ProjectParams,
) -> Projection {
    let start = p;
    let mut p = p;
    let (mut f, mut g) = field.value_and_gradient(p, t);
    for k in 0..=params.max_iterations {
        if !(f.is_finite() && g.is_finite()) {
            return Projection {
                position: p,
                value: f,
                outcome: ProjectionOutcome::FlatGradient,
            };
        }
        let g2 = g.length_squared();
        let gl = g2.sqrt();
        if gl <= params.min_gradient {
            return Projection {
                position: p,
                value: f,
                outcome: ProjectionOutcome::FlatGradient,
            };
        }
        if f.abs() / gl < params.tolerance {
            return Projection {
                position: p,
                value: f,
                outcome: ProjectionOutcome::Converged {
                    iterations: k as u32,
                },
            };
        }
        if k == params.max_iterations {
            break;
        }
        let mut step = -g * (f / g2);
        let len = step.length();
        if len > params.max_step {
            step *= params.max_step / len;
        }
        let mut next = p + step;
        let off = next - start;
        if off.length() > params.max_travel {
            next = start + off * (params.max_travel / off.length());
            let (fn_, gn) = field.value_and_gradient(next, t);
            return Projection {
                position: next,
                value: fn_,
                outcome: if gn.length() <= params.min_gradient {
                    ProjectionOutcome::FlatGradient
                } else {
                    ProjectionOutcome::NotConverged
                },
            };
        }
        p = next;
        (f, g) = field.value_and_gradient(p, t);
    }
    Projection {
        position: p,
        value: f,
        outcome: ProjectionOutcome::NotConverged,
    }
}

/// Bound on bisection steps of [`project_point_oriented`]'s ray search: 60 halvings take
/// any bracket of at most `max_travel` below `1e-18 · max_travel`, past `tolerance`.
const MAX_BISECTIONS: usize = 60;

/// Projects the mesh vertex at `p`, whose own outward unit normal is `outward`, onto
/// `F(·, t) = 0` without leaving its own sheet: [`project_point`], unless its walk went
/// the wrong way along the vertex's own normal, in which case along the normal ray.
///
/// Why: where two surfaces overlap deeply within one frame, a vertex of one can start
/// inside the other (`F > 0` at its old position). Its own sheet moved *outward* there
/// (the inside grew over it), but Newton walks down `∇F`, and inside the blend `−∇F`
/// leads to the nearest point of the *other* sheet's surface, reached moving inward
/// (against `outward`). Landing there folds the sheet onto the union's surface with its
/// orientation reversed: the two sheets' windings cancel, so the exact ray casting of the
/// tracker (§5 of Heiss-Synak et al. 2024) finds material vectors that say *outside* in
/// the middle of the overlap, physical ones, and the tracker keeps the overlap as empty
/// space: the material vanishes. The tracker's labelling is right for the mesh it is
/// given; the fold is made here. So the rule is the level-set one: where `F(p) > 0` the
/// surface passed over `p` outward and the vertex must move along `+outward`; where
/// `F(p) < 0`, along `−outward`. A Newton result that breaks it is replaced by the first
/// root of `F` on that ray within `max_travel` (bracketed in steps of `max_step`, then
/// bisected); with no root in reach the vertex stops at `max_travel` on the ray, inside
/// the other body, and reports [`ProjectionOutcome::NotConverged`]: the overlap it makes
/// is non-physical (material vector 2 for one label), which the tracker merges.
///
/// `outward = 0` (no orientation known) is plain [`project_point`].
pub fn project_point_oriented(
    field: &(impl ImplicitField + ?Sized),
    p: DVec3,
    outward: DVec3,
    t: f64,
    params: &ProjectParams,
) -> Projection {
    let newton = project_point(field, p, t, params);
    if outward == DVec3::ZERO || !newton.position.is_finite() {
        return newton;
    }
    let f0 = field.value(p, t);
    if !f0.is_finite() || f0 == 0.0 {
        return newton;
    }
    let dir = if f0 > 0.0 { outward } else { -outward };
    if (newton.position - p).dot(dir) >= 0.0 {
        return newton;
    }
    project_along_ray(field, p, dir, f0, t, params)
}

/// The first root of `F(·, t)` on the ray `p + s·dir`, `0 < s ≤ max_travel` (see
/// [`project_point_oriented`]); `f0 = F(p)`, non-zero.
fn project_along_ray(
    field: &(impl ImplicitField + ?Sized),
    p: DVec3,
    dir: DVec3,
    f0: f64,
    t: f64,
    params: &ProjectParams,
) -> Projection {
    let steps = (params.max_travel / params.max_step).ceil().clamp(1.0, 1e6) as usize;
    let at = |s: f64| p + dir * s;
    let (mut lo, mut hi) = (0.0, None);
    for k in 1..=steps {
        let s = (k as f64 * params.max_step).min(params.max_travel);
        let f = field.value(at(s), t);
        if !f.is_finite() {
            break;
        }
        if (f > 0.0) != (f0 > 0.0) || f == 0.0 {
            hi = Some(s);
            break;
        }
        lo = s;
    }
    let Some(mut hi) = hi else {
        let q = at(lo);
        return Projection {
            position: q,
            value: field.value(q, t),
            outcome: ProjectionOutcome::NotConverged,
        };
    };
    for k in 0..MAX_BISECTIONS {
        if hi - lo <= params.tolerance {
            let q = at(0.5 * (lo + hi));
            return Projection {
                position: q,
                value: field.value(q, t),
                outcome: ProjectionOutcome::Converged {
                    iterations: k as u32,
                },
            };
        }
        let mid = 0.5 * (lo + hi);
        let f = field.value(at(mid), t);
        if (f > 0.0) == (f0 > 0.0) && f != 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let q = at(0.5 * (lo + hi));
    Projection {
        position: q,
        value: field.value(q, t),
        outcome: ProjectionOutcome::Converged {
            iterations: MAX_BISECTIONS as u32,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::{Path, SkeletonElement, SkeletonField, SphereField};

    #[test]
    fn newton_converges_onto_a_sphere_from_inside_and_outside() {
        let s = SphereField::new(DVec3::new(0.2, -0.1, 0.3), 0.7);
        let params = ProjectParams::default();
        for i in 0..50 {
            let f = i as f64;
            let dir = DVec3::new((f * 1.3).sin(), (f * 0.7).cos(), (f * 2.1).sin()).normalize();
            for r in [0.2, 0.69, 0.71, 1.5] {
                let p = s.centre + dir * r;
                let pr = project_point(&s, p, 0.0, &params);
                assert!(
                    matches!(pr.outcome, ProjectionOutcome::Converged { iterations } if iterations <= 3),
                    "{pr:?}"
                );
                assert!(((pr.position - s.centre).length() - 0.7).abs() < 1e-6);
                // It moved along the radius, not sideways.
                assert!((pr.position - s.centre).normalize().dot(dir) > 1.0 - 1e-9);
            }
        }
    }

    #[test]
    fn newton_converges_on_a_blob_and_quadratically() {
        let f = SkeletonField::new(
            vec![SkeletonElement::point(Path::fixed(DVec3::ZERO), 1.0)],
            0.5,
        )
        .unwrap();
        let pr = project_point(
            &f,
            DVec3::new(0.3, 0.2, 0.1),
            0.0,
            &ProjectParams::default(),
        );
        let ProjectionOutcome::Converged { iterations } = pr.outcome else {
            panic!("{pr:?}");
        };
        assert!(iterations <= 6, "{iterations}");
        assert!(f.value(pr.position, 0.0).abs() < 1e-6);
    }

    #[test]
    fn the_saddle_between_two_separated_blobs_is_quasi_critical() {
        // Two blobs whose kernels barely overlap: at the midpoint ∇F = 0 and F < 0.
        let f = SkeletonField::new(
            vec![
                SkeletonElement::point(Path::fixed(DVec3::new(-0.9, 0.0, 0.0)), 1.0),
                SkeletonElement::point(Path::fixed(DVec3::new(0.9, 0.0, 0.0)), 1.0),
            ],
            0.5,
        )
        .unwrap();
        assert!(f.value(DVec3::ZERO, 0.0) < 0.0);
        let pr = project_point(&f, DVec3::ZERO, 0.0, &ProjectParams::default());
        assert_eq!(pr.outcome, ProjectionOutcome::FlatGradient);
        assert!(pr.is_quasi_critical());
        // Far outside every kernel: flat, quasi-critical too.
        let far = project_point(&f, DVec3::splat(5.0), 0.0, &ProjectParams::default());
        assert!(far.is_quasi_critical());
    }

    #[test]
    fn an_oriented_projection_keeps_the_vertex_on_its_own_sheet() {
        // A vertex at x = 0.5 inside the unit sphere whose own sheet faces −x: the sphere
        // grew over it, so its sheet moved outward, to −x. Newton goes to the sphere's
        // nearest point (1, 0, 0), against the normal: a fold. The oriented projection
        // walks the normal ray to the far side instead.
        let s = SphereField::new(DVec3::ZERO, 1.0);
        let params = ProjectParams::default();
        let p = DVec3::new(0.5, 0.0, 0.0);
        let plain = project_point(&s, p, 0.0, &params);
        assert!((plain.position - DVec3::X).length() < 1e-6);
        let pr = project_point_oriented(&s, p, -DVec3::X, 0.0, &params);
        assert!(
            matches!(pr.outcome, ProjectionOutcome::Converged { .. }),
            "{pr:?}"
        );
        assert!((pr.position + DVec3::X).length() < 1e-5, "{pr:?}");
        // Out of reach: it stops on the ray at max_travel, inside, not converged.
        let short = ProjectParams {
            max_travel: 1.0,
            ..params
        };
        let pr = project_point_oriented(&s, p, -DVec3::X, 0.0, &short);
        assert_eq!(pr.outcome, ProjectionOutcome::NotConverged);
        assert!((pr.position - DVec3::new(-0.5, 0.0, 0.0)).length() < 1e-12);
        assert!(pr.value > 0.0);
        // Outside (F < 0) with the sheet facing −x: the surface receded from the vertex,
        // which must move inward (+x); Newton does, and its result is kept as it is.
        let q = DVec3::new(-1.5, 0.0, 0.0);
        assert_eq!(
            project_point_oriented(&s, q, -DVec3::X, 0.0, &params),
            project_point(&s, q, 0.0, &params)
        );
        // A consistent case and an unknown orientation are plain Newton.
        assert_eq!(project_point_oriented(&s, p, DVec3::X, 0.0, &params), plain);
        assert_eq!(
            project_point_oriented(&s, p, DVec3::ZERO, 0.0, &params),
            plain
        );
    }

    #[test]
    fn steps_are_clamped() {
        let s = SphereField::new(DVec3::ZERO, 1.0);
        let params = ProjectParams {
            max_step: 0.1,
            max_travel: 0.25,
            ..ProjectParams::default()
        };
        let pr = project_point(&s, DVec3::new(3.0, 0.0, 0.0), 0.0, &params);
        assert_eq!(pr.outcome, ProjectionOutcome::NotConverged);
        assert!((pr.position.x - 2.75).abs() < 1e-12);
        assert!(
            ProjectParams {
                max_step: -1.0,
                ..params
            }
            .check()
            .is_err()
        );
    }
}
