//! A field sampled on a regular grid (the paper's volume data, §5 and Fig. 13a), over a
//! sequence of time frames.
//!
//! Space: trilinear interpolation inside each cell; the gradient is the exact gradient
//! of that interpolant (continuous inside a cell, only C⁰ across cell faces — the case
//! the paper reports as harder for Newton projection; a fine grid keeps the jumps small).
//! Time: linear between the two frames around `t`, held before the first and after the
//! last. Outside the grid the field is the constant `outside` (negative: outside), with
//! zero gradient, so points that leave the grid are reported as quasi-critical rather
//! than projected somewhere arbitrary.

use glam::DVec3;
use rayon::prelude::*;

use super::ImplicitField;
use crate::error::{ImplicitError, invalid};

/// Largest number of grid points accepted (~1 GB of f64 per 2²⁷ points per frame).
pub const MAX_GRID_POINTS: usize = 1 << 27;

/// A sampled, animated field.
#[derive(Clone, Debug, PartialEq)]
pub struct GridField {
    origin: DVec3,
    spacing: f64,
    dims: [usize; 3],
    /// `(time, values)`, times strictly increasing; values x fastest, then y, then z.
    frames: Vec<(f64, Vec<f64>)>,
    outside: f64,
}

impl GridField {
    /// A field from raw frames: `dims` points per axis (each ≥ 2), spaced `spacing`
    /// from `origin`; every frame holds `dims[0]·dims[1]·dims[2]` finite values; frame
    /// times strictly increase; `outside` (finite, < 0) is the value off the grid.
    pub fn new(
        origin: DVec3,
        spacing: f64,
        dims: [usize; 3],
        frames: Vec<(f64, Vec<f64>)>,
        outside: f64,
    ) -> Result<Self, ImplicitError> {
        const WHAT: &str = "GridField";
        if !origin.is_finite() {
            return Err(invalid(WHAT, "origin", origin, "finite"));
        }
        if !(spacing.is_finite() && spacing > 0.0) {
            return Err(invalid(WHAT, "spacing", spacing, "finite and > 0"));
        }
        let n = dims.iter().try_fold(1usize, |acc, &d| acc.checked_mul(d));
        let n = match n {
            Some(n) if dims.iter().all(|&d| d >= 2) && n <= MAX_GRID_POINTS => n,
            _ => {
                return Err(invalid(
                    WHAT,
                    "dims",
                    format!("{dims:?}"),
                    "at least 2 points per axis, at most 2^27 in all",
                ));
            }
        };
        if !(outside.is_finite() && outside < 0.0) {
            return Err(invalid(WHAT, "outside", outside, "finite and < 0"));
        }
        if frames.is_empty() {
            return Err(invalid(WHAT, "frames", "[]", "at least one frame"));
        }
        for (i, (t, values)) in frames.iter().enumerate() {
            if !t.is_finite() || (i > 0 && *t <= frames[i - 1].0) {
                return Err(invalid(
                    WHAT,
                    "frames",
                    format!("time #{i} = {t}"),
                    "finite, strictly increasing times",
                ));
            }
            if values.len() != n {
                return Err(invalid(
                    WHAT,
                    "frames",
                    format!("frame #{i} has {} values", values.len()),
                    "one value per grid point",
                ));
            }
            if let Some(j) = values.iter().position(|v| !v.is_finite()) {
                return Err(invalid(
                    WHAT,
                    "frames",
                    format!("frame #{i}, value #{j} = {}", values[j]),
                    "finite values",
                ));
            }
        }
        Ok(Self {
            origin,
            spacing,
            dims,
            frames,
            outside,
        })
    }

    /// Samples `field` at the given times on a grid covering `bounds` with cells of size
    /// `spacing` (rounded so the grid covers the box; one extra cell of margin so the
    /// surface closes inside the grid). Sampling runs in parallel over z-slabs.
    pub fn sample(
        field: &(impl ImplicitField + ?Sized),
        bounds: [DVec3; 2],
        spacing: f64,
        times: &[f64],
        outside: f64,
    ) -> Result<Self, ImplicitError> {
        let [lo, hi] = bounds;
        if !(lo.is_finite() && hi.is_finite() && lo.cmple(hi).all()) {
            return Err(invalid(
                "GridField::sample",
                "bounds",
                format!("{lo}..{hi}"),
                "a finite, non-empty box",
            ));
        }
        if !(spacing.is_finite() && spacing > 0.0) {
            return Err(invalid(
                "GridField::sample",
                "spacing",
                spacing,
                "finite and > 0",
            ));
        }
        let origin = lo - DVec3::splat(spacing);
        let extent = (hi - lo) / spacing + 2.0;
        let dims = [extent.x, extent.y, extent.z].map(|e| (e.ceil() as usize).max(1) + 1);
        let n = dims.iter().try_fold(1usize, |acc, &d| acc.checked_mul(d));
        if n.is_none_or(|n| n > MAX_GRID_POINTS) {
            return Err(invalid(
                "GridField::sample",
                "spacing",
                spacing,
                "coarse enough for at most 2^27 grid points",
            ));
        }
        let mut frames = Vec::with_capacity(times.len());
        for &t in times {
            let mut values = vec![0.0; dims[0] * dims[1] * dims[2]];
            values
                .par_chunks_mut(dims[0] * dims[1])
                .enumerate()
                .for_each(|(k, slab)| {
                    for j in 0..dims[1] {
                        for i in 0..dims[0] {
                            let p = origin + DVec3::new(i as f64, j as f64, k as f64) * spacing;
                            slab[i + dims[0] * j] = field.value(p, t);
                        }
                    }
                });
            frames.push((t, values));
        }
        Self::new(origin, spacing, dims, frames, outside)
    }

    /// Points per axis.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// Value and gradient of frame `f` at `p`, or `None` off the grid.
    fn trilinear(&self, f: usize, p: DVec3) -> Option<(f64, DVec3)> {
        let g = (p - self.origin) / self.spacing;
        let [nx, ny, nz] = self.dims;
        let cell = |x: f64, n: usize| -> Option<(usize, f64)> {
            if !(x >= 0.0 && x <= (n - 1) as f64) {
                return None;
            }
            let i = (x.floor() as usize).min(n - 2);
            Some((i, x - i as f64))
        };
        let (i, u) = cell(g.x, nx)?;
        let (j, v) = cell(g.y, ny)?;
        let (k, w) = cell(g.z, nz)?;
        let vals = &self.frames[f].1;
        let at = |di: usize, dj: usize, dk: usize| vals[(i + di) + nx * ((j + dj) + ny * (k + dk))];
        let c = [
            at(0, 0, 0),
            at(1, 0, 0),
            at(0, 1, 0),
            at(1, 1, 0),
            at(0, 0, 1),
            at(1, 0, 1),
            at(0, 1, 1),
            at(1, 1, 1),
        ];
        // Interpolate along x, then y, then z, keeping the partial derivatives.
        let x00 = c[0] + (c[1] - c[0]) * u;
        let x10 = c[2] + (c[3] - c[2]) * u;
        let x01 = c[4] + (c[5] - c[4]) * u;
        let x11 = c[6] + (c[7] - c[6]) * u;
        let y0 = x00 + (x10 - x00) * v;
        let y1 = x01 + (x11 - x01) * v;
        let value = y0 + (y1 - y0) * w;
        let dx0 = (c[1] - c[0]) + ((c[3] - c[2]) - (c[1] - c[0])) * v;
        let dx1 = (c[5] - c[4]) + ((c[7] - c[6]) - (c[5] - c[4])) * v;
        let dx = dx0 + (dx1 - dx0) * w;
        let dy = (x10 - x00) + ((x11 - x01) - (x10 - x00)) * w;
        let dz = y1 - y0;
        Some((value, DVec3::new(dx, dy, dz) / self.spacing))
    }
}

impl ImplicitField for GridField {
    fn value(&self, p: DVec3, t: f64) -> f64 {
        self.value_and_gradient(p, t).0
    }

    fn gradient(&self, p: DVec3, t: f64) -> DVec3 {
        self.value_and_gradient(p, t).1
    }

    fn value_and_gradient(&self, p: DVec3, t: f64) -> (f64, DVec3) {
        let i = self.frames.partition_point(|(ft, _)| *ft <= t);
        let (f0, f1, s) = if i == 0 {
            (0, 0, 0.0)
        } else if i == self.frames.len() {
            (i - 1, i - 1, 0.0)
        } else {
            let (t0, t1) = (self.frames[i - 1].0, self.frames[i].0);
            (i - 1, i, (t - t0) / (t1 - t0))
        };
        let Some((v0, g0)) = self.trilinear(f0, p) else {
            return (self.outside, DVec3::ZERO);
        };
        if f1 == f0 || s == 0.0 {
            return (v0, g0);
        }
        let Some((v1, g1)) = self.trilinear(f1, p) else {
            return (self.outside, DVec3::ZERO);
        };
        (v0 + (v1 - v0) * s, g0 + (g1 - g0) * s)
    }

    fn bounds(&self, _t: f64) -> Option<[DVec3; 2]> {
        let n = DVec3::new(
            (self.dims[0] - 1) as f64,
            (self.dims[1] - 1) as f64,
            (self.dims[2] - 1) as f64,
        );
        Some([self.origin, self.origin + n * self.spacing])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::field::{SphereField, finite_difference_gradient};

    #[test]
    fn trilinear_gradient_matches_finite_differences_inside_cells() {
        let s = SphereField::new(DVec3::new(0.05, 0.0, -0.02), 0.6);
        let g = GridField::sample(&s, s.bounds(0.0).unwrap(), 0.1, &[0.0, 1.0], -1.0).unwrap();
        for i in 0..30 {
            let f = i as f64;
            // Points off the grid planes so the finite differences stay in one cell.
            let p = DVec3::new((f * 0.37).sin(), (f * 0.91).cos(), (f * 0.53).sin()) * 0.55
                + DVec3::splat(0.0123);
            let a = g.gradient(p, 0.5);
            let fd = finite_difference_gradient(&g, p, 0.5, 1e-7);
            assert!((a - fd).length() < 1e-5, "at {p}: {a} vs {fd}");
        }
    }

    #[test]
    fn samples_reproduce_the_field_at_grid_points_and_approximate_it_between() {
        let s = SphereField::new(DVec3::ZERO, 0.5);
        let g = GridField::sample(&s, s.bounds(0.0).unwrap(), 0.05, &[0.0], -1.0).unwrap();
        let p = DVec3::new(0.31, -0.12, 0.2);
        assert!((g.value(p, 0.0) - s.value(p, 0.0)).abs() < 0.01);
        assert_eq!(g.value(DVec3::splat(10.0), 0.0), -1.0);
        assert_eq!(g.gradient(DVec3::splat(10.0), 0.0), DVec3::ZERO);
    }

    #[test]
    fn frames_interpolate_linearly_in_time() {
        let a = SphereField::new(DVec3::ZERO, 0.3);
        let b = SphereField::new(DVec3::ZERO, 0.5);
        let box_ = [DVec3::splat(-0.6), DVec3::splat(0.6)];
        let ga = GridField::sample(&a, box_, 0.1, &[0.0], -1.0).unwrap();
        let gb = GridField::sample(&b, box_, 0.1, &[0.0], -1.0).unwrap();
        let both = GridField::new(
            ga.origin,
            ga.spacing,
            ga.dims,
            vec![(0.0, ga.frames[0].1.clone()), (2.0, gb.frames[0].1.clone())],
            -1.0,
        )
        .unwrap();
        let p = DVec3::new(0.2, 0.1, 0.0);
        let mid = both.value(p, 1.0);
        assert!((mid - 0.5 * (ga.value(p, 0.0) + gb.value(p, 0.0))).abs() < 1e-12);
    }

    #[test]
    fn bad_grids_are_typed_errors() {
        let ok = vec![(0.0, vec![0.0; 8])];
        assert!(GridField::new(DVec3::ZERO, 1.0, [2, 2, 2], ok.clone(), -1.0).is_ok());
        assert!(GridField::new(DVec3::ZERO, 0.0, [2, 2, 2], ok.clone(), -1.0).is_err());
        assert!(GridField::new(DVec3::ZERO, 1.0, [1, 2, 2], ok.clone(), -1.0).is_err());
        assert!(GridField::new(DVec3::ZERO, 1.0, [2, 2, 2], ok, 1.0).is_err());
        let nan = vec![(0.0, vec![f64::NAN; 8])];
        assert!(GridField::new(DVec3::ZERO, 1.0, [2, 2, 2], nan, -1.0).is_err());
    }
}
