//! Skeleton-based fields (paper §5): `F(p, t) = Σᵢ wᵢ fᵢ(dᵢ(p, t)) − c`, where `dᵢ` is
//! the distance from `p` to skeleton element `i` (a point or a segment) measured in a
//! chosen [`Norm`], `fᵢ` a decreasing [`Falloff`] kernel, `wᵢ` a weight and `c` the
//! iso-value. Elements move along keyframed [`Path`]s, so the field is animated.
//!
//! Distances: the closest point `q` on the element is the Euclidean one (a clamped
//! projection onto the segment), and `d = ‖p − q‖` in the element's norm. For a segment
//! `∂q/∂p = u uᵀ` inside the segment (`u` its unit direction) and `0` past its ends, so
//! `∇d = (I − u uᵀ) ∇‖·‖(p − q)` inside and `∇‖·‖(p − q)` past the ends: the gradient
//! below is the exact derivative of the value below, which the tests check against finite
//! differences. With an Lₚ norm the level sets of one point are superellipsoids (p = 4,
//! 6: rounded cubes), of one segment rounded square tubes.

use glam::DVec3;

use super::ImplicitField;
use crate::error::{ImplicitError, invalid};

/// The norm distances are measured in (paper §5 uses L2, L4 and L0.6).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Norm {
    /// Euclidean distance: round blobs.
    Euclidean,
    /// `(|x|ᵖ + |y|ᵖ + |z|ᵖ)^(1/p)` for a finite `p ≥ 1`: `p > 2` gives rounded boxes
    /// (superellipsoids), `1 ≤ p < 2` octahedron-like shapes whose gradient is
    /// continuous only for `p > 1`. (`p < 1` is not a norm and its gradient blows up on
    /// the axes, which breaks Newton projection — the paper's Fig. 13b artefacts — so it
    /// is refused.)
    Lp(f64),
}

impl Norm {
    fn check(self) -> Result<(), ImplicitError> {
        match self {
            Norm::Euclidean => Ok(()),
            Norm::Lp(p) if p.is_finite() && (1.0..=64.0).contains(&p) => Ok(()),
            Norm::Lp(p) => Err(invalid("Norm::Lp", "p", p, "a finite exponent in [1, 64]")),
        }
    }

    /// `‖v‖` and its gradient with respect to `v` (zero at `v = 0`).
    pub fn length_and_gradient(self, v: DVec3) -> (f64, DVec3) {
        match self {
            Norm::Euclidean => {
                let l = v.length();
                (l, if l > 0.0 { v / l } else { DVec3::ZERO })
            }
            Norm::Lp(p) => {
                let a = v.abs();
                // Scale by the largest component so |x|^p neither overflows nor
                // underflows for p up to 64.
                let m = a.max_element();
                if m == 0.0 {
                    return (0.0, DVec3::ZERO);
                }
                let s = a / m;
                let pw = DVec3::new(s.x.powf(p), s.y.powf(p), s.z.powf(p));
                let sum = pw.x + pw.y + pw.z;
                let l = m * sum.powf(1.0 / p);
                // ∂‖v‖/∂vᵢ = sign(vᵢ) (|vᵢ| / ‖v‖)^(p−1).
                let r = a / l;
                let g = DVec3::new(r.x.powf(p - 1.0), r.y.powf(p - 1.0), r.z.powf(p - 1.0))
                    * v.signum();
                (l, g)
            }
        }
    }
}

/// The falloff kernel `f(d)`: 1 at the skeleton, decreasing with distance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Falloff {
    /// Wyvill-style compact polynomial `f(d) = (1 − d²/R²)³` for `d < R`, else 0: C²,
    /// zero beyond `R`, so far elements cost nothing and blends stay local.
    Wyvill {
        /// Radius of influence `R > 0`.
        radius: f64,
    },
    /// Softened inverse square `f(d) = 1 / (1 + (d/s)²)`: the paper's "1/d²-like"
    /// potential (`≈ s²/d²` far away) without the singularity at the skeleton. Not
    /// compact: every element influences the whole field.
    InverseSquare {
        /// Softening length `s > 0` (where `f = ½`).
        scale: f64,
    },
}

impl Falloff {
    fn check(self) -> Result<(), ImplicitError> {
        let (name, v) = match self {
            Falloff::Wyvill { radius } => ("radius", radius),
            Falloff::InverseSquare { scale } => ("scale", scale),
        };
        if v.is_finite() && v > 0.0 {
            Ok(())
        } else {
            Err(invalid("Falloff", name, v, "finite and > 0"))
        }
    }

    /// `f(d)` and `f′(d)`.
    pub fn value_and_derivative(self, d: f64) -> (f64, f64) {
        match self {
            Falloff::Wyvill { radius } => {
                let x = d * d / (radius * radius);
                if x >= 1.0 {
                    (0.0, 0.0)
                } else {
                    let u = 1.0 - x;
                    (u * u * u, -6.0 * d / (radius * radius) * u * u)
                }
            }
            Falloff::InverseSquare { scale } => {
                let x = d / scale;
                let den = 1.0 + x * x;
                (1.0 / den, -2.0 * x / (scale * den * den))
            }
        }
    }

    /// The distance beyond which `f(d) < level` (for `0 < level < 1`): used for bounds.
    fn reach(self, level: f64) -> f64 {
        match self {
            Falloff::Wyvill { radius } => radius,
            Falloff::InverseSquare { scale } => scale * (1.0 / level - 1.0).max(0.0).sqrt(),
        }
    }
}

/// A point moving through time: piecewise linear between keyframes, held constant
/// before the first and after the last.
#[derive(Clone, Debug, PartialEq)]
pub struct Path {
    keys: Vec<(f64, DVec3)>,
}

impl Path {
    /// A point that does not move.
    pub fn fixed(p: DVec3) -> Self {
        Self {
            keys: vec![(0.0, p)],
        }
    }

    /// Uniform motion `p₀ + v t` for every `t` (not held: extrapolated both ways).
    pub fn linear(p0: DVec3, velocity: DVec3) -> Self {
        // Two far keyframes give exact linear motion over any realistic time range.
        const T: f64 = 1e6;
        Self {
            keys: vec![(-T, p0 - velocity * T), (T, p0 + velocity * T)],
        }
    }

    /// Keyframes `(time, position)` with strictly increasing finite times and finite
    /// positions (at least one).
    pub fn keyframes(keys: Vec<(f64, DVec3)>) -> Result<Self, ImplicitError> {
        if keys.is_empty() {
            return Err(invalid(
                "Path::keyframes",
                "keys",
                "[]",
                "at least one keyframe",
            ));
        }
        for (i, &(t, p)) in keys.iter().enumerate() {
            if !t.is_finite() || !p.is_finite() {
                return Err(invalid(
                    "Path::keyframes",
                    "keys",
                    format!("#{i} = ({t}, {p})"),
                    "finite times and positions",
                ));
            }
            if i > 0 && t <= keys[i - 1].0 {
                return Err(invalid(
                    "Path::keyframes",
                    "keys",
                    format!("time #{i} = {t} after {}", keys[i - 1].0),
                    "strictly increasing times",
                ));
            }
        }
        Ok(Self { keys })
    }

    /// The position at time `t`.
    pub fn at(&self, t: f64) -> DVec3 {
        let k = &self.keys;
        let i = k.partition_point(|&(kt, _)| kt <= t);
        if i == 0 {
            return k[0].1;
        }
        if i == k.len() {
            return k[k.len() - 1].1;
        }
        let (t0, p0) = k[i - 1];
        let (t1, p1) = k[i];
        p0.lerp(p1, (t - t0) / (t1 - t0))
    }

    fn is_finite(&self) -> bool {
        self.keys
            .iter()
            .all(|(t, p)| t.is_finite() && p.is_finite())
    }
}

/// The geometric skeleton of one element.
#[derive(Clone, Debug, PartialEq)]
pub enum Skeleton {
    /// A point: round (or superellipsoidal) blobs.
    Point(Path),
    /// A segment between two moving end points: capsules.
    Segment(Path, Path),
}

/// One skeleton element with its kernel.
#[derive(Clone, Debug, PartialEq)]
pub struct SkeletonElement {
    /// Where the element is.
    pub skeleton: Skeleton,
    /// Weight `w` (may be negative: a carving element).
    pub weight: f64,
    /// The kernel.
    pub falloff: Falloff,
    /// The distance norm.
    pub norm: Norm,
}

impl SkeletonElement {
    /// A point element with the Wyvill kernel of radius `radius` and weight 1.
    pub fn point(path: Path, radius: f64) -> Self {
        Self {
            skeleton: Skeleton::Point(path),
            weight: 1.0,
            falloff: Falloff::Wyvill { radius },
            norm: Norm::Euclidean,
        }
    }

    /// A segment element with the Wyvill kernel of radius `radius` and weight 1.
    pub fn segment(a: Path, b: Path, radius: f64) -> Self {
        Self {
            skeleton: Skeleton::Segment(a, b),
            weight: 1.0,
            falloff: Falloff::Wyvill { radius },
            norm: Norm::Euclidean,
        }
    }

    /// The same element measured in another norm.
    pub fn with_norm(mut self, norm: Norm) -> Self {
        self.norm = norm;
        self
    }

    /// The same element with another kernel.
    pub fn with_falloff(mut self, falloff: Falloff) -> Self {
        self.falloff = falloff;
        self
    }

    /// The same element with another weight.
    pub fn with_weight(mut self, weight: f64) -> Self {
        self.weight = weight;
        self
    }

    /// `w f(d)` and its gradient at `p`.
    fn contribution(&self, p: DVec3, t: f64) -> (f64, DVec3) {
        let (v, jac_proj) = match &self.skeleton {
            Skeleton::Point(c) => (p - c.at(t), None),
            Skeleton::Segment(a, b) => {
                let (a, b) = (a.at(t), b.at(t));
                let ab = b - a;
                let len2 = ab.length_squared();
                if len2 == 0.0 {
                    (p - a, None)
                } else {
                    let s = (p - a).dot(ab) / len2;
                    if s <= 0.0 {
                        (p - a, None)
                    } else if s >= 1.0 {
                        (p - b, None)
                    } else {
                        (p - (a + ab * s), Some(ab / len2.sqrt()))
                    }
                }
            }
        };
        let (d, gn) = self.norm.length_and_gradient(v);
        let (f, df) = self.falloff.value_and_derivative(d);
        if df == 0.0 {
            return (self.weight * f, DVec3::ZERO);
        }
        // ∇d = (I − u uᵀ) ∇‖·‖ inside a segment (u uᵀ symmetric), ∇‖·‖ otherwise.
        let gd = match jac_proj {
            Some(u) => gn - u * u.dot(gn),
            None => gn,
        };
        (self.weight * f, gd * (self.weight * df))
    }

    /// Bounding box of the skeleton at `t`, grown by `margin`.
    fn bounds(&self, t: f64, margin: f64) -> [DVec3; 2] {
        let (lo, hi) = match &self.skeleton {
            Skeleton::Point(c) => (c.at(t), c.at(t)),
            Skeleton::Segment(a, b) => (a.at(t).min(b.at(t)), a.at(t).max(b.at(t))),
        };
        [lo - DVec3::splat(margin), hi + DVec3::splat(margin)]
    }
}

/// A blend (sum) of skeleton elements minus an iso-value: `F = Σ wᵢ fᵢ(dᵢ) − iso`.
#[derive(Clone, Debug, PartialEq)]
pub struct SkeletonField {
    elements: Vec<SkeletonElement>,
    iso: f64,
}

impl SkeletonField {
    /// The blend of `elements` at iso-value `iso ∈ (0, 1)` (kernels are 1 at the
    /// skeleton, so an iso-value of 1 or more leaves a lone element empty). Checks every
    /// element's parameters.
    pub fn new(elements: Vec<SkeletonElement>, iso: f64) -> Result<Self, ImplicitError> {
        if !(iso.is_finite() && iso > 0.0 && iso < 1.0) {
            return Err(invalid("SkeletonField", "iso", iso, "in (0, 1)"));
        }
        for (i, e) in elements.iter().enumerate() {
            e.norm.check()?;
            e.falloff.check()?;
            if !e.weight.is_finite() {
                return Err(invalid(
                    "SkeletonField",
                    "weight",
                    format!("element {i}: {}", e.weight),
                    "finite",
                ));
            }
            let paths_ok = match &e.skeleton {
                Skeleton::Point(c) => c.is_finite(),
                Skeleton::Segment(a, b) => a.is_finite() && b.is_finite(),
            };
            if !paths_ok {
                return Err(invalid(
                    "SkeletonField",
                    "skeleton",
                    format!("element {i}"),
                    "finite keyframes",
                ));
            }
        }
        Ok(Self { elements, iso })
    }

    /// The elements.
    pub fn elements(&self) -> &[SkeletonElement] {
        &self.elements
    }

    /// The iso-value.
    pub fn iso(&self) -> f64 {
        self.iso
    }
}

impl ImplicitField for SkeletonField {
    fn value(&self, p: DVec3, t: f64) -> f64 {
        self.value_and_gradient(p, t).0
    }

    fn gradient(&self, p: DVec3, t: f64) -> DVec3 {
        self.value_and_gradient(p, t).1
    }

    fn value_and_gradient(&self, p: DVec3, t: f64) -> (f64, DVec3) {
        let mut f = -self.iso;
        let mut g = DVec3::ZERO;
        for e in &self.elements {
            let (fi, gi) = e.contribution(p, t);
            f += fi;
            g += gi;
        }
        (f, g)
    }

    /// Where some element's kernel can still reach `iso / Σ|w|` (a necessary condition
    /// for `F ≥ 0`), grown by each element's reach in the Euclidean norm (every Lₚ norm
    /// with `p ≥ 1` is at least the L∞ norm, so the box is conservative).
    fn bounds(&self, t: f64) -> Option<[DVec3; 2]> {
        let total: f64 = self.elements.iter().map(|e| e.weight.abs()).sum();
        if total <= 0.0 {
            return None;
        }
        let level = (self.iso / total).min(1.0);
        self.elements
            .iter()
            .filter(|e| e.weight > 0.0)
            .map(|e| e.bounds(t, e.falloff.reach(level)))
            .reduce(|a, b| [a[0].min(b[0]), a[1].max(b[1])])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::finite_difference_gradient;

    fn check_gradient(field: &SkeletonField, points: &[DVec3], t: f64) {
        for &p in points {
            let g = field.gradient(p, t);
            let fd = finite_difference_gradient(field, p, t, 1e-6);
            let scale = g.length().max(1e-3);
            assert!(
                (g - fd).length() < 1e-5 * scale.max(1.0),
                "at {p}: analytic {g}, finite differences {fd}"
            );
        }
    }

    fn probe_points() -> Vec<DVec3> {
        (0..40)
            .map(|i| {
                let s = i as f64;
                DVec3::new(
                    (s * 0.731).sin() * 0.9,
                    (s * 1.377).cos() * 0.8,
                    (s * 0.913 + 0.4).sin() * 0.7,
                )
            })
            .collect()
    }

    #[test]
    fn gradients_match_finite_differences_for_every_norm_and_kernel() {
        let norms = [Norm::Euclidean, Norm::Lp(4.0), Norm::Lp(6.0), Norm::Lp(1.5)];
        let kernels = [
            Falloff::Wyvill { radius: 1.2 },
            Falloff::InverseSquare { scale: 0.4 },
        ];
        for norm in norms {
            for falloff in kernels {
                let a = Path::linear(DVec3::new(-0.3, 0.0, 0.1), DVec3::new(0.5, 0.1, 0.0));
                let b = Path::keyframes(vec![
                    (0.0, DVec3::new(0.2, 0.3, -0.1)),
                    (1.0, DVec3::new(0.4, -0.2, 0.2)),
                ])
                .unwrap();
                let field = SkeletonField::new(
                    vec![
                        SkeletonElement::point(a.clone(), 1.0)
                            .with_norm(norm)
                            .with_falloff(falloff),
                        SkeletonElement::segment(a, b, 1.0)
                            .with_norm(norm)
                            .with_falloff(falloff)
                            .with_weight(0.7),
                    ],
                    0.3,
                )
                .unwrap();
                check_gradient(&field, &probe_points(), 0.37);
            }
        }
    }

    #[test]
    fn lp_norm_levels_are_boxier_than_euclidean() {
        // At the same distance along an axis and a diagonal, L4 reads the diagonal as
        // nearer than L2 does: its unit ball reaches further into the corners.
        let d = DVec3::new(1.0, 1.0, 1.0).normalize();
        let (l2, _) = Norm::Euclidean.length_and_gradient(d);
        let (l4, _) = Norm::Lp(4.0).length_and_gradient(d);
        assert!((l2 - 1.0).abs() < 1e-12);
        assert!(l4 < 0.8, "L4 length of a unit diagonal = {l4}");
        let (ax, _) = Norm::Lp(4.0).length_and_gradient(DVec3::X);
        assert!((ax - 1.0).abs() < 1e-12);
    }

    #[test]
    fn bad_parameters_are_typed_errors() {
        let e = SkeletonElement::point(Path::fixed(DVec3::ZERO), 1.0);
        assert!(SkeletonField::new(vec![e.clone()], 1.5).is_err());
        assert!(SkeletonField::new(vec![e.clone().with_norm(Norm::Lp(0.6))], 0.5).is_err());
        assert!(
            SkeletonField::new(
                vec![e.with_falloff(Falloff::Wyvill { radius: f64::NAN })],
                0.5
            )
            .is_err()
        );
        assert!(Path::keyframes(vec![(1.0, DVec3::ZERO), (0.5, DVec3::ONE)]).is_err());
        assert!(Path::keyframes(vec![]).is_err());
    }

    #[test]
    fn keyframed_paths_interpolate_and_hold() {
        let p =
            Path::keyframes(vec![(0.0, DVec3::ZERO), (2.0, DVec3::new(2.0, 0.0, 0.0))]).unwrap();
        assert_eq!(p.at(-1.0), DVec3::ZERO);
        assert_eq!(p.at(1.0), DVec3::new(1.0, 0.0, 0.0));
        assert_eq!(p.at(5.0), DVec3::new(2.0, 0.0, 0.0));
    }

    #[test]
    fn bounds_contain_the_inside() {
        let field = SkeletonField::new(
            vec![
                SkeletonElement::point(Path::fixed(DVec3::ZERO), 1.0),
                SkeletonElement::point(Path::fixed(DVec3::X), 1.0)
                    .with_falloff(Falloff::InverseSquare { scale: 0.3 }),
            ],
            0.5,
        )
        .unwrap();
        let [lo, hi] = field.bounds(0.0).unwrap();
        for p in probe_points() {
            let q = p * 3.0;
            if field.value(q, 0.0) >= 0.0 {
                assert!(
                    q.cmpge(lo).all() && q.cmple(hi).all(),
                    "{q} outside {lo}..{hi}"
                );
            }
        }
    }
}
