//! Built-in scenes by name: the initial meshes of `surftrack generate` (and, later, of the
//! tracked scenes of `surftrack run`).

use glam::DVec3;
use mesh_core::generators::{self, GeneratorError, place_random_spheres, spheres_mesh};
use mesh_core::{Label, LabeledMesh};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Names and one-line descriptions of the built-in scenes.
pub const SCENES: &[(&str, &str)] = &[
    (
        "sphere",
        "an icosphere, label 1 inside, 0 outside (--resolution = subdivisions, --radius)",
    ),
    (
        "spheres",
        "N random non-overlapping spheres with labels 1..=N (-n, --resolution, --seed)",
    ),
    (
        "double-bubble",
        "two bubbles sharing a wall: 3 labels and a triple curve (--resolution, --radius)",
    ),
    (
        "zalesak",
        "Zalesak's notched sphere (--resolution = grid cells per axis)",
    ),
    (
        "foam",
        "a Voronoi foam of N cells in the unit cube, labels 1..=N (-n, --seed)",
    ),
    (
        "copies",
        "k rotated, overlapping copies of --mesh FILE (default: the notched sphere), distinct labels (-n, --seed)",
    ),
];

/// Parameters shared by the scene builders; `None` means the scene's default.
#[derive(Debug, Default)]
pub struct SceneOptions {
    /// Random seed.
    pub seed: u64,
    /// Spheres, foam cells or copies.
    pub count: Option<usize>,
    /// Resolution (meaning depends on the scene).
    pub resolution: Option<u32>,
    /// Radius.
    pub radius: Option<f64>,
    /// Input mesh for `copies`.
    pub mesh: Option<LabeledMesh>,
}

/// Why a scene could not be built.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// No scene has this name.
    #[error("unknown scene `{0}`; known scenes: {known}", known = SCENES.iter().map(|s| s.0).collect::<Vec<_>>().join(", "))]
    Unknown(String),
    /// The generator refused the parameters.
    #[error(transparent)]
    Generator(#[from] GeneratorError),
}

/// Builds the initial mesh of a named scene.
pub fn build_scene(name: &str, o: &SceneOptions) -> Result<LabeledMesh, SceneError> {
    let resolution = |default: u32| o.resolution.unwrap_or(default);
    let mesh = match name {
        "sphere" => generators::icosphere(
            resolution(4),
            DVec3::ZERO,
            o.radius.unwrap_or(1.0),
            [Label::OUTSIDE, Label::new(1)],
        )?,
        "spheres" => generators::random_spheres(
            o.count.unwrap_or(20),
            DVec3::ZERO,
            DVec3::ONE,
            [0.03, 0.08],
            resolution(2),
            o.seed,
        )?,
        "double-bubble" => {
            generators::double_bubble(o.radius.unwrap_or(1.0), resolution(48) as usize)?
        }
        "zalesak" => generators::zalesak(resolution(64) as usize)?,
        "foam" => generators::voronoi_foam(o.count.unwrap_or(16), o.seed, DVec3::ZERO, DVec3::ONE)?,
        "copies" => {
            let base = match &o.mesh {
                Some(mesh) => mesh.clone(),
                None => generators::zalesak(resolution(40) as usize)?,
            };
            generators::copies(&base, o.count.unwrap_or(6), o.seed)?
        }
        other => return Err(SceneError::Unknown(other.to_string())),
    };
    Ok(mesh)
}

/// The remeshing benchmark's scene (`benches/remesh.rs`, `examples/remesh.rs`):
/// 40 spheres of 5120 triangles each (~205k triangles) with radii varying threefold, so one
/// target edge length makes the small ones collapse and the large ones split; every vertex
/// is pushed radially from its sphere's centre by up to ±20 % of that sphere's edge length,
/// so flips and smoothing have work too. Still intersection-free: each sphere stays
/// star-shaped about its centre, and the jitter stays below half the smallest gap.
pub fn noisy_spheres() -> Result<LabeledMesh, GeneratorError> {
    let spheres = place_random_spheres(40, DVec3::ZERO, DVec3::ONE, [0.03, 0.09], 7)?;
    let mut mesh = spheres_mesh(&spheres, 4)?;
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let vertices: Vec<_> = mesh.vertices().collect();
    for v in vertices {
        let p = mesh.position(v);
        let Some(sphere) = spheres.iter().min_by(|a, b| {
            (a.centre.distance(p) - a.radius)
                .abs()
                .total_cmp(&(b.centre.distance(p) - b.radius).abs())
        }) else {
            continue;
        };
        // An icosphere of 4 subdivisions has edges of about 0.066 radius.
        let jitter = rng.random_range(-1.0..1.0) * 0.2 * 0.066 * sphere.radius;
        mesh.set_position(v, p + (p - sphere.centre).normalize_or_zero() * jitter);
    }
    Ok(mesh)
}
