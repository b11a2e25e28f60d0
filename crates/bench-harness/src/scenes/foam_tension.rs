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
//! **Flow.** [`VolumePreservingTension`]: backward Euler mean curvature flow with tension
//! 1 over the union of all interface triangles, wall vertices held in the box faces,
//! every bubble's volume pulled back to its initial value each step. The Voronoi foam is
//! far from equilibrium (its triple curves do not meet at Plateau's 120°, its faces are
//! flat), so the films move, short edges and small faces shrink away and cells swap
//! neighbours (T1) or, where a small cell is squeezed by the constraints' compromise,
//! vanish (T2).
//!
//! **Time step.** `dt = DT_PER_H_SQUARED · h²` = `h²`. Backward Euler is stable for any
//! step, so stability sets no limit (forward Euler's bound is `~h²/4` on a regular mesh,
//! and ~10⁻⁸ on the refined Voronoi foam, whose cells have needles at their corners: the
//! explicit flow moved nothing in 20 steps). What limits the step is how far the tracker
//! should move the mesh per step: the grid tracker repairs whatever tangles, but every
//! cell a step tangles is cut out and rebuilt (volume error, lost detail), and the
//! collision tracker must resolve every trajectory by CCD, impulses and impact zones,
//! whose cost grows with the motion. Diffusive scaling keeps that motion a fixed fraction
//! of the edge length at any resolution: a kink of size `h` (the triple curves of the
//! Voronoi cells) spreads over `√(γ dt) = h` in one step, and a face of the cell spacing
//! `d = resolution · h` relaxes in `~d²/π²` (`3.6 h²` at the default resolution 6), so 20
//! steps span several relaxation times of every face — enough for the foam to rearrange
//! (T1 events start in the first steps). Measured at 100 bubbles, resolution 6, grid
//! backend, 20 steps: `h²` gives 13 contact changes with the last step's volume error at
//! most 0.5 %; `3.9 h²` gives 47 with 1.5 % (every bubble below 1 % needs `h²`). At 1000
//! bubbles (`h²`, 20 steps, release, 2 cores; `run foam-tension --count 1000 --steps 20`):
//! grid 5.1 s per step, 322k → 330k triangles, 328 T1 and 0 T2, every frame valid, volume
//! drift over the run median 0.03 %, largest 2.1 % (one bubble above 1 %); collision
//! 16.4 s per step, 2265 T1 (vertex separations) and 1 T2, every frame valid, median
//! 0.15 %, largest 2.5 % (18 bubbles above 1 %). The worst bubbles are the smallest (a
//! ninth of the mean volume, about two edges across): the trackers' resolution, not the
//! flow, whose proposal is volume-exact.
//!
//! The 2024 paper's Fig. 21–22 foam is not this flow: it couples the tracker to Ishida et
//! al.'s (2017) hyperbolic soap-film dynamics (second order in time, with inertia and
//! volume control) and does not state its step, only that it is 10× Los Topos' on the
//! same animation (the collision tracker's steps are limited by its trajectories). Here
//! the physics is first-order volume-preserving mean curvature flow (Los Topos' Fig. 17
//! foam, plus volume constraints and walls), so the step is chosen as above.

use glam::DVec3;
use mesh_core::LabeledMesh;
use mesh_core::generators;
use mesh_core::remesh::{ImproveParams, NoGuard, VertexAttributes, improve};

use super::{SceneError, SceneOptions};
use crate::flows::{McfScheme, MeanCurvatureFlow, VolumePreservingTension};

/// Default number of bubbles.
pub const DEFAULT_BUBBLES: usize = 64;
/// Default edges per mean cell spacing.
pub const DEFAULT_RESOLUTION: u32 = 6;
/// The time step in units of `h²` (see the module doc).
pub const DT_PER_H_SQUARED: f64 = 1.0;

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
    let mcf = MeanCurvatureFlow::new(1.0)?.with_scheme(McfScheme::BackwardEuler);
    let flow = VolumePreservingTension::new(&mesh, mcf, DVec3::ZERO, DVec3::ONE);
    Ok((mesh, flow, DT_PER_H_SQUARED * h * h))
}
