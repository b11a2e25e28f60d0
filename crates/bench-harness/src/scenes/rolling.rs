//! The `rolling` scene (Heiss-Synak et al. 2024, Fig. 17, "rolling stones"): two decorated
//! spheres roll into each other, merge, and roll apart again. Every motion is rigid, so
//! wherever the tracker did not resample the surface, the final mesh *is* the rigidly
//! moved original: the scene measures feature preservation ([`RollingMotion`] gives the
//! exact rigid motion of each sphere at any time; [`crate::preservation`] compares).
//!
//! **Geometry.** Sphere A (centre `(−c, 0, 0)`) and sphere B (`(+c, 0, 0)`), radius `r`,
//! both of material 1 (so they merge into one region, then split), a gap of `0.3 r`.
//! Each carries [`BUMPS`] Gaussian bumps at Fibonacci-spiral directions, of height
//! [`BUMP_HEIGHT`]` · r` and angular width [`BUMP_WIDTH`] — with the default resolution
//! (icosphere subdivision 4, edges ≈ 0.066 r, which is the grid cell ℓ) a bump is about
//! 2ℓ high and 3ℓ wide, well above the grid scale, so the local tracker can keep it.
//!
//! **Motion.** For `t ∈ [0, 1]` each sphere rolls towards the other on the floor `y = −r`
//! (velocity `±v`, angular velocity `up × v / r`) while spinning about its direction of
//! travel; they meet, press `0.3 r` into each other (total) and merge. For `t ∈ [1, 2]`
//! they roll back (rolling reverses, the spin does not), tear the merged neck apart and
//! end where they started, turned by the spin. A vertex follows the sphere on its side
//! of the plane `x = 0`. Rigid motions alone would stretch the merged neck into a tube
//! that never thins, so in the second phase vertices within [`NECK_BAND`]` · r` of that
//! plane are also drawn towards the line of centres, which pinches the neck off; the
//! band lies inside the contact zone that the feature-distance measure skips.

use glam::{DMat3, DVec3};
use mesh_core::generators::{PlacedSphere, spheres_mesh};
use mesh_core::{Label, LabeledMesh};

use crate::flows::Flow;

use super::{SceneError, SceneOptions};

/// Bumps per sphere.
pub const BUMPS: usize = 24;
/// Bump height as a fraction of the radius.
pub const BUMP_HEIGHT: f64 = 0.12;
/// Bump angular width σ (radians): height `exp(−θ²/(2σ²))` at angle θ from its centre.
pub const BUMP_WIDTH: f64 = 0.2;
/// Default radius.
pub const RADIUS: f64 = 0.3;
/// Duration of the scene (two phases of length 1).
pub const DURATION: f64 = 2.0;
/// Half-width of the band around `x = 0`, as a fraction of the radius, in which the
/// second phase draws the merged neck towards the line of centres.
pub const NECK_BAND: f64 = 0.15;
/// Rate of that contraction at `x = 0` (per unit time): the neck's radius shrinks by
/// `e^{-NECK_RATE · t}`, below a grid cell well before the end.
const NECK_RATE: f64 = 8.0;
/// Total spin about the travel axis over the run (radians).
const SPIN: f64 = std::f64::consts::FRAC_PI_2;

/// The rigid motion of both spheres: where every initial point of either sphere is at
/// time `t`.
#[derive(Clone, Copy, Debug)]
pub struct RollingMotion {
    /// Radius.
    pub radius: f64,
    /// Initial centres (A on −x, B on +x).
    pub centres: [DVec3; 2],
    /// Speed along x (both spheres).
    pub speed: f64,
}

impl RollingMotion {
    /// The motion for radius `r`.
    pub fn new(r: f64) -> Self {
        let gap = 0.3 * r;
        let c = r + 0.5 * gap;
        // Each travels half the gap plus 0.15 r: 0.3 r of overlap in total at t = 1.
        let travel = 0.5 * gap + 0.15 * r;
        RollingMotion {
            radius: r,
            centres: [DVec3::new(-c, 0.0, 0.0), DVec3::new(c, 0.0, 0.0)],
            speed: travel,
        }
    }

    /// Direction of travel of sphere `i` in phase 1 (towards the other).
    fn direction(i: usize) -> DVec3 {
        if i == 0 { DVec3::X } else { DVec3::NEG_X }
    }

    /// Angular velocity of sphere `i` in phase `phase` (0 or 1): rolling on the floor
    /// (`up × velocity / r`) plus the spin about the direction of travel.
    fn omega(&self, i: usize, phase: usize) -> DVec3 {
        let d = Self::direction(i);
        let velocity = if phase == 0 { d } else { -d } * self.speed;
        let rolling = DVec3::Y.cross(velocity) / self.radius;
        rolling + d * (SPIN / DURATION)
    }

    /// Time spent in each phase up to `t`.
    fn phase_times(t: f64) -> [f64; 2] {
        let t = t.clamp(0.0, DURATION);
        [t.min(1.0), (t - 1.0).max(0.0)]
    }

    /// Centre of sphere `i` at time `t`.
    pub fn centre(&self, i: usize, t: f64) -> DVec3 {
        let [a, b] = Self::phase_times(t);
        self.centres[i] + Self::direction(i) * self.speed * (a - b)
    }

    /// Rotation of sphere `i` from time 0 to `t`.
    pub fn rotation(&self, i: usize, t: f64) -> DMat3 {
        let [a, b] = Self::phase_times(t);
        let rot = |w: DVec3, tau: f64| {
            let angle = w.length() * tau;
            if angle == 0.0 {
                DMat3::IDENTITY
            } else {
                DMat3::from_axis_angle(w.normalize(), angle)
            }
        };
        rot(self.omega(i, 1), b) * rot(self.omega(i, 0), a)
    }

    /// Which sphere an initial point belongs to (by side of `x = 0`).
    pub fn sphere_of(p: DVec3) -> usize {
        usize::from(p.x > 0.0)
    }

    /// Where the initial point `p0` of sphere `i` is at time `t`.
    pub fn place(&self, i: usize, p0: DVec3, t: f64) -> DVec3 {
        self.centre(i, t) + self.rotation(i, t) * (p0 - self.centres[i])
    }

    /// Whether the initial point `p0` ever comes within `margin` of the plane `x = 0`
    /// where the spheres touch (sampled at 200 times; the contact zone, excluded from
    /// the feature-preservation distance).
    pub fn in_contact_zone(&self, p0: DVec3, margin: f64) -> bool {
        let i = Self::sphere_of(p0);
        (0..=200).any(|k| {
            let t = DURATION * k as f64 / 200.0;
            self.place(i, p0, t).x.abs() < margin
        })
    }
}

/// Moves every vertex rigidly with the sphere on its side of `x = 0`.
pub struct RollingFlow {
    motion: RollingMotion,
}

impl Flow for RollingFlow {
    fn name(&self) -> &str {
        "rolling"
    }

    fn propose(&self, mesh: &LabeledMesh, t: f64, dt: f64) -> Vec<DVec3> {
        let m = &self.motion;
        let step: [(DVec3, DMat3, DVec3); 2] = [0, 1].map(|i| {
            let r = m.rotation(i, t + dt) * m.rotation(i, t).transpose();
            (m.centre(i, t), r, m.centre(i, t + dt))
        });
        let band = NECK_BAND * m.radius;
        let pinch = t >= 1.0;
        let mut out = mesh.positions().to_vec();
        for v in mesh.vertices() {
            let p = mesh.position(v);
            let (c0, r, c1) = step[RollingMotion::sphere_of(p)];
            let mut q = c1 + r * (p - c0);
            if pinch && p.x.abs() < band {
                // Draw the neck towards the line of centres so that it thins and tears.
                let k = (-NECK_RATE * dt * (1.0 - p.x.abs() / band)).exp();
                q.y *= k;
                q.z *= k;
            }
            out[v.idx()] = q;
        }
        out
    }
}

/// Unit Fibonacci-spiral directions: evenly spread bump centres, no randomness.
fn bump_directions(n: usize) -> Vec<DVec3> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|k| {
            let y = 1.0 - 2.0 * (k as f64 + 0.5) / n as f64;
            let rho = (1.0 - y * y).max(0.0).sqrt();
            let phi = golden * k as f64;
            DVec3::new(rho * phi.cos(), y, rho * phi.sin())
        })
        .collect()
}

/// The decorated radius factor in direction `u` (unit).
fn decoration(u: DVec3, bumps: &[DVec3]) -> f64 {
    let s2 = 2.0 * BUMP_WIDTH * BUMP_WIDTH;
    1.0 + BUMP_HEIGHT
        * bumps
            .iter()
            .map(|d| {
                let theta = u.dot(*d).clamp(-1.0, 1.0).acos();
                (-theta * theta / s2).exp()
            })
            .sum::<f64>()
}

/// Builds the scene: mesh, flow and time step for `steps` steps over [`DURATION`].
/// `--resolution` = icosphere subdivisions (default 4), `--radius` (default 0.3).
pub fn build(
    o: &SceneOptions,
    steps: usize,
) -> Result<(LabeledMesh, RollingFlow, f64), SceneError> {
    let r = o.radius.unwrap_or(RADIUS);
    let motion = RollingMotion::new(r);
    let spheres = motion.centres.map(|centre| PlacedSphere {
        centre,
        radius: r,
        label: Label::new(1),
    });
    let mut mesh = spheres_mesh(&spheres, o.resolution.unwrap_or(4))?;
    // B's bumps are A's turned about y, so the spheres meet bump against bump unevenly.
    let bumps_a = bump_directions(BUMPS);
    let turn = DMat3::from_rotation_y(0.7);
    let bumps_b: Vec<DVec3> = bumps_a.iter().map(|d| turn * *d).collect();
    let vertices: Vec<_> = mesh.vertices().collect();
    for v in vertices {
        let p = mesh.position(v);
        let i = RollingMotion::sphere_of(p);
        let c = motion.centres[i];
        let u = (p - c).normalize_or_zero();
        let bumps = if i == 0 { &bumps_a } else { &bumps_b };
        mesh.set_position(v, c + u * r * decoration(u, bumps));
    }
    let dt = DURATION / steps.max(1) as f64;
    Ok((mesh, RollingFlow { motion }, dt))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_motion_is_rigid_meets_in_the_middle_and_returns() {
        let m = RollingMotion::new(0.3);
        let p = m.centres[0] + DVec3::new(0.1, 0.2, -0.05);
        let q = m.centres[0] + DVec3::new(-0.2, 0.0, 0.1);
        for t in [0.0, 0.3, 1.0, 1.7, 2.0] {
            let d = m.place(0, p, t).distance(m.place(0, q, t));
            assert!((d - p.distance(q)).abs() < 1e-12);
        }
        // At t = 1 the spheres overlap by 0.3 r in total; at the end the centres are back.
        let gap = m.centre(1, 1.0).x - m.centre(0, 1.0).x;
        assert!((gap - 1.7 * 0.3).abs() < 1e-12, "{gap}");
        assert!(m.centre(0, 2.0).distance(m.centres[0]) < 1e-12);
        // ...but turned by the spin.
        assert!(m.place(0, p, 2.0).distance(p) > 1e-3);
    }

    #[test]
    fn stepping_the_flow_follows_the_rigid_motion() {
        let o = SceneOptions {
            resolution: Some(2),
            ..SceneOptions::default()
        };
        let (mut mesh, flow, dt) = build(&o, 10).unwrap();
        let start = mesh.clone();
        let m = RollingMotion::new(RADIUS);
        let mut t = 0.0;
        // Phase 1 only (t = 0.8).
        for _ in 0..4 {
            let next = flow.propose(&mesh, t, dt);
            let vs: Vec<_> = mesh.vertices().collect();
            for v in vs {
                mesh.set_position(v, next[v.idx()]);
            }
            t += dt;
        }
        // Away from the plane x = 0 (where a bump may cross to the other side before the
        // spheres meet) every vertex is where the rigid motion puts it.
        let mut checked = 0;
        for v in start.vertices() {
            let p0 = start.position(v);
            if p0.x.abs() < 0.2 {
                continue;
            }
            let want = m.place(RollingMotion::sphere_of(p0), p0, t);
            assert!(mesh.position(v).distance(want) < 1e-12);
            checked += 1;
        }
        assert!(checked > start.num_vertices() / 2);
    }
}
