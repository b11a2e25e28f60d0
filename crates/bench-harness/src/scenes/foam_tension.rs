//! `foam-tension`: N soap bubbles filling a box, under volume-preserving surface tension
//! (2024 paper §9.5, Fig. 21–22: a 1000-bubble foam of ~625k triangles; Los Topos' foam
//! scene under mean curvature flow).
//!
//! **Initial mesh.** The Voronoi cells of N seeded sites in the unit cube
//! ([`generators::voronoi_foam`]: label `i + 1` per cell, 0 outside the cube), refined to
//! a target edge length `h = d / resolution`, `d = N^{-1/3}` the mean cell spacing, by
//! mesh-core's improvement with midpoint splits, collapses and Delaunay flips only (no
//! smoothing, no butterfly placement, so the flat Voronoi faces and the box walls stay
//! exactly flat and the cells keep their volumes exactly).
//!
//! **Flow.** [`VolumePreservingTension`]: mean curvature flow with tension 1, wall
//! vertices held in the box faces, every bubble's volume pulled back to its initial value
//! each step. The Voronoi foam is far from equilibrium (Plateau's 120° angles), so the
//! faces move, short edges collapse and cells swap neighbours (T1) or, where a small
//! cell is squeezed by the constraints' compromise, vanish (T2).
//!
//! **Time step.** `0.25 h²`, the scale of forward Euler's stability bound for mean
//! curvature flow; the driver shrinks it further when the mesh's own bound is smaller
//! ([`crate::flows::Flow::max_stable_dt`]).

use glam::DVec3;
use mesh_core::LabeledMesh;
use mesh_core::generators;
use mesh_core::remesh::{ImproveParams, NoGuard, VertexAttributes, improve};

use super::{SceneError, SceneOptions};
use crate::flows::VolumePreservingTension;

/// Default number of bubbles.
pub const DEFAULT_BUBBLES: usize = 64;
/// Default edges per mean cell spacing.
pub const DEFAULT_RESOLUTION: u32 = 6;

/// The refined foam of `n` bubbles at `resolution` edges per cell spacing, and `h`.
pub fn foam_mesh(n: usize, resolution: u32, seed: u64) -> Result<(LabeledMesh, f64), SceneError> {
    let mut mesh = generators::voronoi_foam(n, seed, DVec3::ZERO, DVec3::ONE)?;
    let h = (n.max(1) as f64).powf(-1.0 / 3.0) / f64::from(resolution.max(1));
    let params = ImproveParams {
        target_edge_length: Some(h),
        butterfly: false,
        smooth: false,
        separate: false,
        pinch: false,
        max_sweeps: 16,
        // Only edits that keep every cell's volume (flat faces): no corner cutting.
        max_volume_change: Some(1e-12 * h * h * h),
        ..ImproveParams::default()
    };
    improve(
        &mut mesh,
        &params,
        &mut VertexAttributes::none(),
        &mut NoGuard,
    );
    mesh.compact();
    Ok((mesh, h))
}

/// Mesh, flow and time step of the scene.
pub fn build(o: &SceneOptions) -> Result<(LabeledMesh, VolumePreservingTension, f64), SceneError> {
    let n = o.count.unwrap_or(DEFAULT_BUBBLES);
    let (mesh, h) = foam_mesh(n, o.resolution.unwrap_or(DEFAULT_RESOLUTION), o.seed)?;
    let flow = VolumePreservingTension::new(&mesh, 1.0, DVec3::ZERO, DVec3::ONE)?;
    Ok((mesh, flow, 0.25 * h * h))
}
