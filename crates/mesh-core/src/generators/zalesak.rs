//! Zalesak's notched sphere, the classic rigid-rotation test of interface trackers.
//!
//! The 3D version of Zalesak's slotted disk (Enright et al. 2002): a sphere of radius 0.15
//! centred at `(0.5, 0.75, 0.5)` in the unit box, with a slot of width 0.05 (along x)
//! cut up from the bottom of the sphere to a depth of 0.25 (along y), through the whole
//! sphere along z. The material left above the slot joins the two halves. The mesh is the
//! zero set of an implicit function (sphere distance `max` minus slot distance), meshed by
//! [`mesh_implicit`]: watertight, with the slot's sharp edges chamfered at grid scale.

use glam::{DVec2, DVec3};

use super::error::{GeneratorError, check_finite, check_positive, invalid};
use super::implicit::{MAX_CELLS_PER_AXIS, mesh_implicit};
use crate::ids::Label;
use crate::mesh::LabeledMesh;

/// A sphere with a rectangular slot cut from its bottom (−y side) towards its top.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NotchedSphere {
    /// Sphere centre.
    pub centre: DVec3,
    /// Sphere radius.
    pub radius: f64,
    /// Slot width along x, centred on the sphere; `0 < width < 2·radius`.
    pub slot_width: f64,
    /// Slot depth along y, measured from the bottom of the sphere; `0 < depth ≤ 2·radius`.
    pub slot_depth: f64,
}

impl Default for NotchedSphere {
    /// The classic test: centre `(0.5, 0.75, 0.5)`, radius 0.15, slot 0.05 wide and 0.25 deep.
    fn default() -> Self {
        NotchedSphere {
            centre: DVec3::new(0.5, 0.75, 0.5),
            radius: 0.15,
            slot_width: 0.05,
            slot_depth: 0.25,
        }
    }
}

impl NotchedSphere {
    /// Height of the slot's top face above the centre (negative: below the centre).
    fn slot_top(&self) -> f64 {
        self.slot_depth - self.radius
    }

    /// Checks the parameters (see the field docs).
    pub fn validate(&self) -> Result<(), GeneratorError> {
        const NAME: &str = "zalesak";
        check_finite(NAME, "centre", self.centre)?;
        check_positive(NAME, "radius", self.radius)?;
        check_positive(NAME, "slot width", self.slot_width)?;
        check_positive(NAME, "slot depth", self.slot_depth)?;
        if self.slot_width >= 2.0 * self.radius {
            return Err(invalid(
                NAME,
                "slot width",
                self.slot_width,
                "less than the diameter",
            ));
        }
        if self.slot_depth > 2.0 * self.radius {
            return Err(invalid(
                NAME,
                "slot depth",
                self.slot_depth,
                "at most the diameter",
            ));
        }
        Ok(())
    }

    /// Negative inside, positive outside, zero on the surface; 1-Lipschitz. It is the exact
    /// distance away from the slot's edges (where the `max` of two distances underestimates).
    pub fn signed_distance(&self, p: DVec3) -> f64 {
        let q = p - self.centre;
        let sphere = q.length() - self.radius;
        // The slot {|x| ≤ w/2, y ≤ top} (infinite along z and downwards): a 2D box distance.
        let d = DVec2::new(q.x.abs() - self.slot_width / 2.0, q.y - self.slot_top());
        let slot = d.max(DVec2::ZERO).length() + d.max_element().min(0.0);
        sphere.max(-slot)
    }

    /// Exact enclosed volume: the ball minus the part of it inside the slot,
    /// `∫ A(√(r² − x²)) dx` over `|x| ≤ w/2`, where `A(ρ)` is the area of a disk of radius ρ
    /// below the slot top. The integrand is smooth, so composite Simpson with 2048
    /// intervals is exact to rounding for all practical purposes.
    pub fn volume(&self) -> f64 {
        let r = self.radius;
        let top = self.slot_top();
        let below = |x: f64| {
            let rho = (r * r - x * x).max(0.0).sqrt();
            if top >= rho {
                std::f64::consts::PI * rho * rho
            } else if top <= -rho {
                0.0
            } else {
                rho * rho * (std::f64::consts::PI - (top / rho).acos())
                    + top * (rho * rho - top * top).sqrt()
            }
        };
        const INTERVALS: usize = 2048;
        let a = self.slot_width / 2.0;
        let h = 2.0 * a / INTERVALS as f64;
        let mut sum = below(-a) + below(a);
        for i in 1..INTERVALS {
            sum += below(-a + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
        }
        4.0 / 3.0 * std::f64::consts::PI * r.powi(3) - sum * h / 3.0
    }

    /// Meshes the notched sphere with `resolution` grid cells across its diameter (plus a
    /// two-cell margin on every side), labels `[0 outside, 1 inside]`. Resolving the slot
    /// needs cells well below `slot_width`, i.e. a resolution of about
    /// `4·radius/slot_width` (12 for the classic sphere) or more.
    pub fn mesh(&self, resolution: usize) -> Result<LabeledMesh, GeneratorError> {
        self.validate()?;
        if !(2..=MAX_CELLS_PER_AXIS - 4).contains(&resolution) {
            return Err(invalid(
                "zalesak",
                "resolution",
                resolution,
                "between 2 and 508",
            ));
        }
        let h = 2.0 * self.radius / resolution as f64;
        let half = DVec3::splat(self.radius + 2.0 * h);
        let bounds = [self.centre - half, self.centre + half];
        mesh_implicit(
            |p| self.signed_distance(p),
            bounds,
            resolution + 4,
            [Label::new(0), Label::new(1)],
        )
    }
}

/// The classic Zalesak notched sphere ([`NotchedSphere::default`]) with `resolution`
/// grid cells across its diameter; labels 0 outside, 1 inside.
pub fn zalesak(resolution: usize) -> Result<LabeledMesh, GeneratorError> {
    NotchedSphere::default().mesh(resolution)
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI;

    use super::*;
    use crate::generators::checks::{assert_well_formed, bounded_volumes};

    #[test]
    fn analytic_volume_matches_closed_forms() {
        let r: f64 = 0.15;
        let w: f64 = 0.05;
        let a = w / 2.0;
        let ball = 4.0 / 3.0 * PI * r.powi(3);
        // The slab |x| ≤ a of the ball: π(2a r² − 2a³/3).
        let slab = PI * (2.0 * a * r * r - 2.0 * a.powi(3) / 3.0);
        let through = NotchedSphere {
            slot_depth: 2.0 * r,
            ..Default::default()
        };
        assert!((through.volume() - (ball - slab)).abs() < 1e-14);
        let half = NotchedSphere {
            slot_depth: r,
            ..Default::default()
        };
        assert!((half.volume() - (ball - slab / 2.0)).abs() < 1e-14);
        let classic = NotchedSphere::default().volume();
        assert!(classic > ball - slab && classic < ball - slab / 2.0);
    }

    #[test]
    fn signed_distance_has_the_right_signs() {
        let z = NotchedSphere::default();
        let c = z.centre;
        assert!(
            z.signed_distance(c + DVec3::new(0.0, 0.12, 0.0)) < 0.0,
            "above the slot"
        );
        assert!(
            z.signed_distance(c + DVec3::new(0.05, 0.0, 0.0)) < 0.0,
            "beside the slot"
        );
        assert!(z.signed_distance(c) > 0.0, "in the slot");
        assert!(
            z.signed_distance(c + DVec3::new(0.0, -0.1, 0.1)) > 0.0,
            "in the slot, off-centre in z"
        );
        assert!(
            z.signed_distance(c + DVec3::new(0.2, 0.0, 0.0)) > 0.0,
            "outside the sphere"
        );
    }

    #[test]
    fn mesh_is_well_formed_and_has_the_notched_volume() {
        let exact = NotchedSphere::default().volume();
        let mut errors = Vec::new();
        for resolution in [16, 32, 48] {
            let m = zalesak(resolution).unwrap();
            assert_well_formed(&m);
            let vols = bounded_volumes(&m);
            assert_eq!(vols.len(), 1, "one connected body");
            errors.push(((vols[0].1 - exact) / exact).abs());
        }
        assert!(errors[2] < 0.02, "relative volume errors {errors:?}");
        assert!(errors[2] < errors[0], "relative volume errors {errors:?}");
    }

    #[test]
    fn bad_parameters_are_refused() {
        assert!(zalesak(1).is_err());
        assert!(zalesak(600).is_err());
        let bad = [
            NotchedSphere {
                radius: -1.0,
                ..Default::default()
            },
            NotchedSphere {
                slot_width: 0.3,
                ..Default::default()
            },
            NotchedSphere {
                slot_depth: 0.31,
                ..Default::default()
            },
            NotchedSphere {
                slot_depth: f64::NAN,
                ..Default::default()
            },
            NotchedSphere {
                centre: DVec3::NAN,
                ..Default::default()
            },
        ];
        for z in bad {
            assert!(z.mesh(8).is_err(), "{z:?}");
        }
    }
}
