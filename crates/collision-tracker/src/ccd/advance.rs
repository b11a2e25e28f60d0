//! The advancement loop shared by both kernels: certify `[t, t + h]`, advance, repeat.
//!
//! Invariant: `[0, t]` is proven contact-free. The loop returns `None` only after
//! certifying an interval that ends at 1, so every contact is reported (see the
//! [module docs](super) for the argument, the step policy and what a report means).
//! Everything that is not a certificate (closest points, the choice of direction and of
//! interval ends) is a heuristic: it affects speed only, never the answer `None`.

use glam::DVec3;

use super::certify::{U, coplanarity_excluded, separated_along, separated_on_axis};
use super::{CcdOptions, Impact};
use crate::proximity::{Proximity, off_line, unit};

/// Coordinates beyond this magnitude (`2²⁰⁰`) could overflow the certificates (the side
/// certificates multiply four coordinate differences); such input is reported
/// conservatively. Overflow could never make a certificate pass (it yields infinities or
/// NaN, which fail every comparison), it would only make them useless.
const MAX_COORD: f64 = f64::from_bits((1023u64 + 200) << 52);

/// Distances below `NOISE_FACTOR · u · max|x|` are not resolvable from computed positions
/// (their error is about `10 u max|x|`): they count as touching and give no direction.
const NOISE_FACTOR: f64 = 128.0;

/// Fraction of the guaranteed separation time taken by a conservative-advancement step,
/// leaving a margin (1 % of the gap) for the certificate's error bound: each step of a
/// straight approach gains two decades of distance.
const ADVANCE_FRACTION: f64 = 0.99;

/// What a kernel tells the shared loop about its pair of elements. Both elements are
/// given by four points `x = [first…, second…]` in the kernel's argument order.
pub(crate) trait PairGeometry {
    /// The vertex-pair differences (first minus second); the convex hull of the four
    /// (vertex–triangle repeats one) is the set of vectors between the elements.
    fn differences(x: &[DVec3; 4]) -> [DVec3; 4];
    /// The three vectors whose determinant vanishes at every contact.
    fn coplanarity(x: &[DVec3; 4]) -> [DVec3; 3];
    /// Closest points at one instant.
    fn proximity(x: &[DVec3; 4]) -> Proximity;
    /// A "side" certificate for the interval between the configurations `xa` and `xb`:
    /// true when a quantity that must lie in a range at any contact provably does not
    /// (see the kernels). Complements the coplanarity cubic in coplanar motion.
    fn outside(xa: &[DVec3; 4], xb: &[DVec3; 4], m: DVec3) -> bool;
    /// The (unnormalised) geometric normal: triangle normal, or edge cross product.
    fn geometric_normal(x: &[DVec3; 4]) -> DVec3;
    /// Weights reported when nothing is known (invalid input).
    const NEUTRAL_WEIGHTS: [f64; 4];
    /// How many of the four points belong to the first element (1 or 2).
    const FIRST_LEN: usize;
    /// Edges of the polytope spanned by the differences (index pairs); its vertices are
    /// the differences and, for both kinds, `(D₁ − D₀) × (D₂ − D₀)` is its face normal.
    const HULL_EDGES: &'static [(usize, usize)];
}

/// Magnitudes that set the error bounds and the tolerance of one query.
struct Scale {
    /// Per-axis bound on `|x|` over all eight input points.
    m: DVec3,
    /// Distances at or below this are reported as contact.
    delta: f64,
    /// Distances at or below this give no usable direction.
    noise: f64,
}

impl Scale {
    /// `None` for non-finite or out-of-range input.
    fn of(x0: &[DVec3; 4], x1: &[DVec3; 4], tolerance: f64) -> Option<Scale> {
        let mut m = DVec3::ZERO;
        let mut lo = DVec3::INFINITY;
        let mut hi = DVec3::NEG_INFINITY;
        for x in x0.iter().chain(x1) {
            // `max_element` ignores NaN, hence the explicit finiteness test.
            if !(x.is_finite() && x.abs().max_element() <= MAX_COORD) {
                return None;
            }
            m = m.max(x.abs());
            lo = lo.min(*x);
            hi = hi.max(*x);
        }
        let noise = NOISE_FACTOR * U * m.max_element();
        let extent = (hi - lo).max_element();
        let delta = (tolerance * extent).max(noise);
        Some(Scale { m, delta, noise })
    }
}

/// Positions at time `t` (exactly `x1` at `t = 1`); error per axis `≤ 5.001 u M`.
#[inline]
fn positions(x0: &[DVec3; 4], x1: &[DVec3; 4], t: f64) -> [DVec3; 4] {
    if t >= 1.0 {
        return *x1;
    }
    std::array::from_fn(|i| x0[i] + (x1[i] - x0[i]) * t)
}

/// The pair differences at both ends of an interval.
#[inline]
fn end_differences<P: PairGeometry>(xa: &[DVec3; 4], xb: &[DVec3; 4]) -> [DVec3; 8] {
    let (a, b) = (P::differences(xa), P::differences(xb));
    [a[0], a[1], a[2], a[3], b[0], b[1], b[2], b[3]]
}

/// The direction-free certificates: axes and the coplanarity cubic, and — when `sides` —
/// the kernel's side certificates (several times dearer; they matter for tangential
/// contacts in coplanar motion, where the cubic vanishes).
#[inline]
fn certify_static<P: PairGeometry>(
    xa: &[DVec3; 4],
    xb: &[DVec3; 4],
    d: &[DVec3; 8],
    m: DVec3,
    sides: bool,
) -> bool {
    separated_on_axis(d, m)
        || coplanarity_excluded(&P::coplanarity(xa), &P::coplanarity(xb), m)
        || (sides && P::outside(xa, xb, m))
}

/// True when the swept bounding boxes of the two elements are disjoint on some axis: the
/// exact fast rejection (comparisons of input coordinates only, no rounding).
#[inline]
fn swept_boxes_disjoint<P: PairGeometry>(x0: &[DVec3; 4], x1: &[DVec3; 4]) -> bool {
    let (mut lo_a, mut hi_a) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    let (mut lo_b, mut hi_b) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
    // `min`/`max` skip NaN: non-finite input must not be judged here.
    if !x0.iter().chain(x1).all(|x| x.is_finite()) {
        return false;
    }
    for i in 0..4 {
        let (lo, hi) = if i < P::FIRST_LEN {
            (&mut lo_a, &mut hi_a)
        } else {
            (&mut lo_b, &mut hi_b)
        };
        *lo = lo.min(x0[i]).min(x1[i]);
        *hi = hi.max(x0[i]).max(x1[i]);
    }
    hi_a.cmplt(lo_b).any() || hi_b.cmplt(lo_a).any()
}

/// The best separating direction at one instant among the closest-feature directions of
/// the polytope spanned by the differences `d` (each vertex, each edge with the edge
/// direction projected out, the face normal) and `hint`.
///
/// Why not just the closest-point direction from the proximity query: near a Voronoi
/// boundary of the closest features (a vertex approaching another element's vertex along
/// one of its edges, say) rounding can pick the wrong feature, and that direction leaves
/// some difference with zero margin. Every candidate is a valid direction; scoring them by
/// their margin `min_j n̂ · Dⱼ` (a lower bound on the distance, equal to it for the true
/// closest feature) picks one that works.
fn best_direction<P: PairGeometry>(d: &[DVec3; 4], hint: DVec3, distance: f64) -> DVec3 {
    // The margin of a candidate, in its better orientation.
    let scored = |n: DVec3| -> Option<(f64, DVec3)> {
        let n = unit(n)?;
        let (lo, hi) = d
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                let g = n.dot(*v);
                (lo.min(g), hi.max(g))
            });
        Some(if lo >= -hi { (lo, n) } else { (-hi, -n) })
    };
    let mut best = scored(hint).unwrap_or((f64::NEG_INFINITY, hint));
    // The margin is at most the distance; when the hint nearly attains it, keep it.
    if best.0 >= 0.5 * distance {
        return best.1;
    }
    let edges = P::HULL_EDGES
        .iter()
        .map(|&(i, j)| off_line(d[i], d[j] - d[i]));
    let face = (d[1] - d[0]).cross(d[2] - d[0]);
    for n in d.iter().copied().chain(edges).chain(std::iter::once(face)) {
        if let Some(c) = scored(n).filter(|c| c.0 > best.0) {
            best = c;
        }
    }
    best.1
}

/// How far past `t` the direction `n` keeps separating the elements (exact for linear
/// motion, computed in floating point — a proposal only, certified afterwards).
fn advancement<P: PairGeometry>(
    x0: &[DVec3; 4],
    x1: &[DVec3; 4],
    xt: &[DVec3; 4],
    n: DVec3,
) -> f64 {
    let (d0, d1, dt) = (P::differences(x0), P::differences(x1), P::differences(xt));
    let mut tau = f64::INFINITY;
    for j in 0..4 {
        let gap = n.dot(dt[j]);
        if gap.is_nan() || gap <= 0.0 {
            return 0.0;
        }
        let rate = n.dot(d1[j] - d0[j]);
        if rate < 0.0 {
            tau = tau.min(gap / -rate);
        }
    }
    tau
}

/// Why a pair was reported (the tests check that false positives are near misses).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Reason {
    /// The elements came within the tolerance `δ`.
    Close,
    /// The iteration budget ran out, or `t` could not advance.
    Budget,
    /// Non-finite or out-of-range input.
    Invalid,
}

/// Runs the advancement loop for one pair; see the module docs.
pub(crate) fn advance<P: PairGeometry>(
    x0: &[DVec3; 4],
    x1: &[DVec3; 4],
    opts: &CcdOptions,
) -> Option<(Impact, Reason)> {
    advance_counted::<P>(x0, x1, opts).0
}

/// [`advance`], also returning the number of iterations used (for the tests' statistics).
pub(crate) fn advance_counted<P: PairGeometry>(
    x0: &[DVec3; 4],
    x1: &[DVec3; 4],
    opts: &CcdOptions,
) -> (Option<(Impact, Reason)>, u32) {
    if swept_boxes_disjoint::<P>(x0, x1) {
        return (None, 0);
    }
    let Some(scale) = Scale::of(x0, x1, opts.tolerance) else {
        let impact = Impact {
            time: 0.0,
            normal: DVec3::Z,
            weights: P::NEUTRAL_WEIGHTS,
            relative_normal_velocity: 0.0,
        };
        return (Some((impact, Reason::Invalid)), 0);
    };
    let m = scale.m;
    let mut t = 0.0f64;
    let mut xt = *x0;
    let mut h = 1.0f64;
    // The last resolvable closest-point direction: the direction of approach.
    let mut approach: Option<DVec3> = None;
    // Set after an advancement step: the contact is probably just ahead, so the
    // direction-free test of the doubled trial interval would be wasted.
    let mut approaching = false;
    let mut last_advance = f64::INFINITY;
    // Separating direction first (cheap), then — unless `quick` — the direction-free
    // certificates including the sides.
    let certify = |xa: &[DVec3; 4], xb: &[DVec3; 4], n: DVec3, quick: bool| {
        let d = end_differences::<P>(xa, xb);
        separated_along(&d, m, n) || (!quick && certify_static::<P>(xa, xb, &d, m, true))
    };

    let mut iterations = 0;
    'step: while iterations < opts.max_iterations {
        iterations += 1;
        // Try the whole trial interval [t, t + h] with the cheap direction-free certificates.
        let tb = if t + h >= 1.0 { 1.0 } else { t + h };
        let xb = positions(x0, x1, tb);
        if !approaching && certify_static::<P>(&xt, &xb, &end_differences::<P>(&xt, &xb), m, false)
        {
            if tb >= 1.0 {
                return (None, iterations);
            }
            (t, xt) = (tb, xb);
            h *= 2.0;
            continue;
        }
        let prox = P::proximity(&xt);
        if prox.distance.is_nan() || prox.distance <= scale.delta {
            let hit = impact::<P>(x0, x1, t, &xt, &prox, approach, &scale);
            return (Some((hit, Reason::Close)), iterations);
        }
        if prox.distance > scale.noise {
            approach = Some(prox.normal);
        }
        let n = best_direction::<P>(&P::differences(&xt), prox.normal, prox.distance);
        // Candidate ends: the trial end again (now with the separating direction, which
        // is cheap), the conservative-advancement step along `n` (one cheap test, and the
        // fast way through a transversal approach), and half the trial (with every
        // certificate: the way through tangential contacts, where the direction-free
        // certificates work up to the contact while advancement crawls). While
        // approaching, advancement goes first; otherwise the longer of the two.
        let tc = t + ADVANCE_FRACTION * advancement::<P>(x0, x1, &xt, n);
        let half = t + 0.5 * (tb - t);
        let order = if approaching || tc > half {
            [tb, tc, half]
        } else {
            [tb, half, tc]
        };
        let mut shortest = tb;
        for (k, end) in order.into_iter().enumerate() {
            if !(end > t && (k == 0 || end < tb)) {
                continue;
            }
            shortest = shortest.min(end);
            let xe = if k == 0 { xb } else { positions(x0, x1, end) };
            // The trial interval already failed the direction-free certificates (or skipped
            // them while approaching), and an advancement step needs only its direction.
            let quick = k == 0 || end == tc;
            if certify(&xt, &xe, n, quick) {
                if end >= 1.0 {
                    return (None, iterations);
                }
                // Approaching: advancement steps shrink geometrically towards a
                // contact. Steps that do not shrink mean a crawl (tangential contact).
                approaching = end == tc && (end - t) <= 0.5 * last_advance;
                last_advance = if end == tc { end - t } else { f64::INFINITY };
                h = 2.0 * (end - t);
                (t, xt) = (end, xe);
                continue 'step;
            }
        }
        // Everything failed: retry below the shortest interval tried.
        approaching = false;
        h = 0.5 * (shortest - t);
        if h.is_nan() || t + h <= t {
            break; // no representable progress: report at `t`
        }
    }
    let prox = P::proximity(&xt);
    (
        Some((
            impact::<P>(x0, x1, t, &xt, &prox, approach, &scale),
            Reason::Budget,
        )),
        iterations,
    )
}

/// Builds the report at time `t` (see "Impact fields" in the module docs).
fn impact<P: PairGeometry>(
    x0: &[DVec3; 4],
    x1: &[DVec3; 4],
    t: f64,
    xt: &[DVec3; 4],
    prox: &Proximity,
    approach: Option<DVec3>,
    scale: &Scale,
) -> Impact {
    let w = prox.weights;
    let disp: DVec3 = (0..4).map(|i| (x1[i] - x0[i]) * w[i]).sum();
    let normal = if prox.distance > scale.noise {
        prox.normal
    } else if let Some(n) = approach {
        n
    } else {
        // Touching since the search began: orient the geometric normal against the
        // relative motion so that the resolver sees an approach.
        match unit(P::geometric_normal(xt)) {
            Some(n) if n.dot(disp) > 0.0 => -n,
            Some(n) => n,
            None => unit(-disp).unwrap_or(prox.normal),
        }
    };
    Impact {
        time: t,
        normal,
        weights: w,
        relative_normal_velocity: normal.dot(disp),
    }
}
