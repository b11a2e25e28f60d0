//! The comparison of §5: the same animation meshed by following (this crate) and from
//! scratch every frame by marching tetrahedra, at comparable triangle counts.
//!
//! Figures per method, over the frames after the first:
//! - **ms per frame**: ours = proposal (relaxation + Newton) + tracker step + final
//!   re-projection ([`crate::FrameReport::seconds`]); marching tetrahedra = sampling the
//!   field on the grid + extraction into index/vertex buffers ([`crate::polygonize()`]);
//! - **triangles**: mean live triangles;
//! - **coherence**: mean over frames of the fraction of vertices that persist from the
//!   previous frame. Ours: the same particle, carried by the tracker (not created,
//!   collapsed or rebuilt by it; identity tags ride on the tracker's vertex attributes).
//!   Marching tetrahedra has no identity, so a vertex persists only if it lies at a
//!   bit-identical position in the previous frame (essentially never while anything moves);
//! - **components** at the end and, for ours, the largest distance `|F|/‖∇F‖` left on a
//!   vertex and the number of frames whose output failed validation (should be 0).
//!
//! The marching-tetrahedra cell size is chosen by two secant steps on the triangle count
//! (∝ 1/cell²) to match ours at the first frame.

use std::collections::HashSet;
use std::time::Instant;

use mesh_core::validate::{ValidateOptions, validate};
use serde::Serialize;

use crate::error::{ImplicitError, invalid};
use crate::field::ImplicitField;
use crate::follow::{FollowParams, Follower};
use crate::polygonize::polygonize;
use crate::scenes::Animation;

/// One method's figures.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MethodFigures {
    /// Method name.
    pub method: String,
    /// Frames measured.
    pub frames: usize,
    /// Mean wall milliseconds per frame.
    pub ms_per_frame: f64,
    /// Slowest frame, ms.
    pub ms_max: f64,
    /// Mean triangles per frame.
    pub triangles: f64,
    /// Mean fraction of vertices persisting from the previous frame.
    pub coherence: f64,
    /// Surface components in the last frame.
    pub final_components: usize,
    /// Largest `|F|/‖∇F‖` on an output vertex over all frames (ours), or the grid's
    /// interpolation error bound (none: 0) for marching tetrahedra.
    pub max_residual: f64,
    /// Frames whose output mesh failed `mesh_core::validate` (layers 1–3).
    pub invalid_frames: usize,
}

/// The comparison of one animation.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Comparison {
    /// Animation name.
    pub scene: String,
    /// Target edge length ℓ of the follower.
    pub edge_length: f64,
    /// Cell size chosen for marching tetrahedra.
    pub mt_cell: f64,
    /// Ours, then marching tetrahedra.
    pub methods: Vec<MethodFigures>,
    /// Component count per frame (ours), to see the blend and split.
    pub components: Vec<usize>,
}

impl Comparison {
    /// A markdown table of the figures.
    pub fn to_markdown(&self) -> String {
        let mut s = format!(
            "### `{}` (ℓ = {}, marching-tetrahedra cell = {:.4})\n\n",
            self.scene, self.edge_length, self.mt_cell
        );
        s.push_str("| method | frames | ms/frame (mean) | ms/frame (max) | triangles (mean) | coherence | final components | max \\|F\\|/\\|∇F\\| | invalid frames |\n");
        s.push_str("|---|---:|---:|---:|---:|---:|---:|---:|---:|\n");
        for m in &self.methods {
            s.push_str(&format!(
                "| {} | {} | {:.2} | {:.2} | {:.0} | {:.3} | {} | {:.1e} | {} |\n",
                m.method,
                m.frames,
                m.ms_per_frame,
                m.ms_max,
                m.triangles,
                m.coherence,
                m.final_components,
                m.max_residual,
                m.invalid_frames
            ));
        }
        s
    }
}

fn bounds_of(field: &impl ImplicitField, t: f64) -> Result<[glam::DVec3; 2], ImplicitError> {
    field
        .bounds(t)
        .ok_or_else(|| invalid("compare", "field", "unbounded", "a field with bounds"))
}

/// Runs both methods over `frames` frames of `anim` (see the module doc). `validate`
/// checks every output mesh of ours (costs time, not counted in ms/frame).
pub fn compare(
    anim: &Animation,
    frames: usize,
    params: Option<FollowParams>,
    validate_frames: bool,
) -> Result<Comparison, ImplicitError> {
    if frames == 0 {
        return Err(invalid("compare", "frames", frames, "at least 1"));
    }
    let params = params.unwrap_or_else(|| FollowParams::new(anim.edge_length));
    let field = &anim.field;
    // Ours.
    let mut follower = Follower::new(field.clone(), anim.t0, None, params.clone())?;
    let mut times = Vec::with_capacity(frames);
    let (mut tris, mut coherence, mut residual, mut invalid_frames) = (0.0, 0.0, 0.0f64, 0);
    let mut components = Vec::with_capacity(frames);
    let mut first_tris = None;
    for k in 1..=frames {
        let prev_vertices = follower.mesh().num_vertices();
        let r = follower.advance_to(anim.time(k, frames))?;
        times.push(r.seconds * 1e3);
        tris += r.triangles as f64;
        coherence += r.persisted as f64 / r.vertices.max(prev_vertices).max(1) as f64;
        residual = residual.max(r.max_residual);
        components.push(r.components);
        first_tris.get_or_insert(r.triangles);
        if validate_frames && !validate(follower.mesh(), &ValidateOptions::default()).is_valid() {
            invalid_frames += 1;
        }
    }
    let n = frames as f64;
    let ours = MethodFigures {
        method: "follow + grid tracker (ours)".into(),
        frames,
        ms_per_frame: times.iter().sum::<f64>() / n,
        ms_max: times.iter().copied().fold(0.0, f64::max),
        triangles: tris / n,
        coherence: coherence / n,
        final_components: components.last().copied().unwrap_or(0),
        max_residual: residual,
        invalid_frames,
    };
    // Marching tetrahedra at a matching triangle count (two secant steps).
    let target = first_tris.unwrap_or(1).max(1) as f64;
    let t1 = anim.time(1, frames);
    let mut cell = anim.edge_length;
    for _ in 0..2 {
        let count = polygonize(field, t1, bounds_of(field, t1)?, cell)?
            .triangles
            .len()
            .max(1);
        cell *= (count as f64 / target).sqrt();
    }
    let mut prev: HashSet<[u64; 3]> = HashSet::new();
    let mut mt_times = Vec::with_capacity(frames);
    let (mut mt_tris, mut mt_coh, mut mt_comp) = (0.0, 0.0, 0);
    for k in 1..=frames {
        let t = anim.time(k, frames);
        let start = Instant::now();
        let p = polygonize(field, t, bounds_of(field, t)?, cell)?;
        mt_times.push(start.elapsed().as_secs_f64() * 1e3);
        mt_tris += p.triangles.len() as f64;
        let keys: HashSet<[u64; 3]> = p
            .positions
            .iter()
            .map(|q| q.to_array().map(f64::to_bits))
            .collect();
        if k > 1 {
            let same = keys.iter().filter(|q| prev.contains(*q)).count();
            mt_coh += same as f64 / keys.len().max(1) as f64;
        }
        if k == frames {
            mt_comp = p.components();
        }
        prev = keys;
    }
    let mt = MethodFigures {
        method: "marching tetrahedra from scratch".into(),
        frames,
        ms_per_frame: mt_times.iter().sum::<f64>() / n,
        ms_max: mt_times.iter().copied().fold(0.0, f64::max),
        triangles: mt_tris / n,
        coherence: if frames > 1 { mt_coh / (n - 1.0) } else { 0.0 },
        final_components: mt_comp,
        max_residual: 0.0,
        invalid_frames: 0,
    };
    Ok(Comparison {
        scene: anim.name.into(),
        edge_length: params.edge_length,
        mt_cell: cell,
        methods: vec![ours, mt],
        components,
    })
}
