//! Animations used by the harness scene `metaballs`, the comparison and the tests.
//!
//! - [`crossing`]: the paper's Fig. 1 — two skeleton segments crossing each other:
//!   apart, blended into one surface while they overlap, split again after;
//! - [`triple`]: three blobs meeting at one point and leaving again (the case the paper
//!   cannot weld: three surfaces blending in one place);
//! - [`swarm`]: `n` blobs on seeded keyframed paths in a box, blending and splitting in
//!   several places at once.
//!
//! Every element uses the Wyvill kernel of radius `R = 1` at iso-value ½, so a lone
//! point is a sphere of radius `√(1 − ½^⅓) ≈ 0.454` and two elements interact within 2.

use glam::DVec3;

use crate::error::ImplicitError;
use crate::field::{Path, SkeletonElement, SkeletonField};

/// An animated field with its time range and suggested resolution.
#[derive(Clone, Debug)]
pub struct Animation {
    /// Short name.
    pub name: &'static str,
    /// The field.
    pub field: SkeletonField,
    /// Start time.
    pub t0: f64,
    /// End time.
    pub t1: f64,
    /// Default number of frames (steps from `t0` to `t1`).
    pub frames: usize,
    /// Suggested target edge length ℓ.
    pub edge_length: f64,
}

impl Animation {
    /// The time of frame `k` of `frames` (frame 0 is `t0`, frame `frames` is `t1`).
    pub fn time(&self, k: usize, frames: usize) -> f64 {
        self.t0 + (self.t1 - self.t0) * k as f64 / frames.max(1) as f64
    }
}

const ISO: f64 = 0.5;

/// The paper's Fig. 1: segment A (along y) moves +x, segment B (along z) moves −x; they
/// start `2·gap` apart (no interaction for `gap ≥ 1`), cross at `t = ½` and end swapped.
/// `edge_length` sets ℓ (default scene: 0.12, 40 frames).
pub fn crossing(gap: f64, edge_length: f64, frames: usize) -> Result<Animation, ImplicitError> {
    let seg = |x0: f64, x1: f64, axis: DVec3| -> Result<SkeletonElement, ImplicitError> {
        let a = Path::keyframes(vec![
            (0.0, DVec3::X * x0 - axis * 0.5),
            (1.0, DVec3::X * x1 - axis * 0.5),
        ])?;
        let b = Path::keyframes(vec![
            (0.0, DVec3::X * x0 + axis * 0.5),
            (1.0, DVec3::X * x1 + axis * 0.5),
        ])?;
        Ok(SkeletonElement::segment(a, b, 1.0))
    };
    let field = SkeletonField::new(
        vec![seg(-gap, gap, DVec3::Y)?, seg(gap, -gap, DVec3::Z)?],
        ISO,
    )?;
    Ok(Animation {
        name: "crossing",
        field,
        t0: 0.0,
        t1: 1.0,
        frames,
        edge_length,
    })
}

/// Three blobs at 120° in the xy plane, `reach` from the centre, meet in the middle at
/// `t = ½` and go back out by `t = 1`.
pub fn triple(reach: f64, edge_length: f64, frames: usize) -> Result<Animation, ImplicitError> {
    let mut elements = Vec::new();
    for k in 0..3 {
        let a = std::f64::consts::TAU * k as f64 / 3.0;
        let dir = DVec3::new(a.cos(), a.sin(), 0.0);
        let path = Path::keyframes(vec![
            (0.0, dir * reach),
            (0.5, dir * 0.15),
            (1.0, dir * reach),
        ])?;
        elements.push(SkeletonElement::point(path, 1.0));
    }
    Ok(Animation {
        name: "triple",
        field: SkeletonField::new(elements, ISO)?,
        t0: 0.0,
        t1: 1.0,
        frames,
        edge_length,
    })
}

/// SplitMix64: a seeded stream without a dependency.
fn splitmix(state: &mut u64) -> f64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 53) as f64
}

/// `n` blobs (weights 0.8–1.2) in a box of side `1.2·n^⅓ + 1`, each on a path through
/// four seeded keyframes over `[0, 1]`: the box is small enough that several pairs
/// (and sometimes triples) blend and split during the run.
pub fn swarm(
    n: usize,
    seed: u64,
    edge_length: f64,
    frames: usize,
) -> Result<Animation, ImplicitError> {
    if n == 0 {
        return Err(crate::error::invalid("swarm", "n", n, "at least 1"));
    }
    let mut s = seed ^ 0x5EED;
    let half = 0.5 * (1.2 * (n as f64).cbrt() + 1.0);
    let point = |s: &mut u64| {
        DVec3::new(splitmix(s), splitmix(s), splitmix(s)) * (2.0 * half) - DVec3::splat(half)
    };
    let mut elements = Vec::with_capacity(n);
    for _ in 0..n {
        let keys = (0..4).map(|k| (k as f64 / 3.0, point(&mut s))).collect();
        let w = 0.8 + 0.4 * splitmix(&mut s);
        elements.push(SkeletonElement::point(Path::keyframes(keys)?, 1.0).with_weight(w));
    }
    Ok(Animation {
        name: "swarm",
        field: SkeletonField::new(elements, ISO)?,
        t0: 0.0,
        t1: 1.0,
        frames,
        edge_length,
    })
}
