//! Built-in scenes: an initial mesh, a flow, a time step and a default number of steps —
//! everything `surftrack run` needs, no input files. [`build_tracked`] makes a tracked
//! scene; [`build_scene`] the mesh `surftrack generate` writes.
//!
//! | scene | what it tests (paper) |
//! |---|---|
//! | `double-bubble` | two spheres expand, merge into a double bubble, reverse, separate and vanish (2024 §9.6, Fig. 18) |
//! | `spheres` | N random non-overlapping spheres under naive normal flow: the robustness benchmark (2024 §9.6) |
//! | `zalesak` | the notched sphere turned once about an outside point (Los Topos §8.1) |
//! | `enright` | a sphere of four materials through the Enright field, there and back (Los Topos Fig. 14) |
//! | `curl-noise` | four spheres under alternating normal flow and curl noise (Los Topos Fig. 15) |
//! | `foam` | Voronoi cells under mean curvature flow (Los Topos Fig. 17) |
//! | `foam-tension` | N bubbles in a box with fixed walls under volume-preserving surface tension (2024 Fig. 21–22) |
//! | `inversion` | a double bubble thrown into self-intersection by strong smooth noise, fixed in one step (2024 Fig. 15) |
//! | `copies` | k rotated copies of a mesh teleported onto each other, one step (2024 Fig. 16) |
//! | `cyclic` | cyclical normal flow a→b→c→a around a still triple curve (Los Topos Fig. 16) |
//! | `rolling` | two decorated spheres roll into each other, merge and roll apart: feature preservation (2024 Fig. 17) |
//! | `metaballs` | an animated implicit surface followed by Newton projection: two skeleton segments cross, blend, split (Nesme & Bouthors 2006, Fig. 1) |
//!
//! `mesh:<flow>` runs a built-in flow on the user's mesh ([`user`]).
//!
//! Sizes default to a few thousand triangles so a run takes seconds to minutes; the
//! options of [`SceneOptions`] scale them.

pub mod foam_tension;
pub mod metaballs;
mod quadrant_sphere;
pub mod rolling;
pub mod user;

use glam::DVec3;
use mesh_core::generators::{
    self, GeneratorError, PlacedSphere, place_random_spheres, spheres_mesh,
};
use mesh_core::remesh::improve::mean_edge_length;
use mesh_core::{Label, LabeledMesh};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use surftrack::grid_tracker::default_cell_size;

use crate::flows::{
    CurlNoiseFlow, CurlNoiseParams, EnrightFlow, Flow, FlowError, Integrator, InterfaceSpeeds,
    MeanCurvatureFlow, NormalFlow, OneShot, RigidRotation, Schedule, TargetPositions,
    cyclic_normal_flow,
};
use crate::options::FlowOptions;

pub use quadrant_sphere::{MAX_RESOLUTION as QUADRANT_MAX_RESOLUTION, quadrant_sphere};

/// One entry of the scene table.
#[derive(Clone, Copy, Debug)]
pub struct SceneInfo {
    /// Name on the command line.
    pub name: &'static str,
    /// One line for `surftrack scenes`.
    pub summary: &'static str,
    /// Default number of steps (0: a mesh for `generate` only, not a tracked scene).
    pub steps: usize,
    /// What `--count` and `--resolution` mean for it.
    pub knobs: &'static str,
}

/// Every built-in scene, tracked ones first.
pub const SCENES: &[SceneInfo] = &[
    SceneInfo {
        name: "double-bubble",
        summary: "two spheres expand, merge into a double bubble, reverse, separate and vanish (2024 paper Fig. 18)",
        steps: 60,
        knobs: "--radius (0.3), --resolution = icosphere subdivisions (3)",
    },
    SceneInfo {
        name: "spheres",
        summary: "N random non-overlapping spheres expanding under naive normal flow: the robustness benchmark (2024 paper §9.6)",
        steps: 40,
        knobs: "--count/--spheres N (20), --resolution = icosphere subdivisions (2), --seed",
    },
    SceneInfo {
        name: "zalesak",
        summary: "Zalesak's notched sphere rotated once about an outside point (Los Topos §8.1)",
        steps: 100,
        knobs: "--resolution = grid cells across the sphere (32)",
    },
    SceneInfo {
        name: "enright",
        summary: "a sphere of 4 materials stretched by the Enright field and brought back at t = 3 (Los Topos Fig. 14)",
        steps: 300,
        knobs: "--resolution = segments per quarter great circle (12)",
    },
    SceneInfo {
        name: "curl-noise",
        summary: "4 spheres under alternating normal flow and seeded curl noise (Los Topos Fig. 15)",
        steps: 200,
        knobs: "--resolution = icosphere subdivisions (3), --seed",
    },
    SceneInfo {
        name: "foam",
        summary: "Voronoi cells in the unit cube under mean curvature flow (Los Topos Fig. 17)",
        steps: 100,
        knobs: "--count N cells (16), --seed",
    },
    SceneInfo {
        name: "foam-tension",
        summary: "N Voronoi bubbles filling a box with fixed walls under volume-preserving surface tension; T1/T2 as they rearrange (2024 paper Fig. 21-22)",
        steps: 20,
        knobs: "--count N bubbles (64), --resolution = edges per cell spacing (6), --seed",
    },
    SceneInfo {
        name: "inversion",
        summary: "a double bubble deformed by strong smooth noise into self-intersection, fixed in one step (2024 paper Fig. 15)",
        steps: 1,
        knobs: "--resolution = segments around the triple circle (32), --seed",
    },
    SceneInfo {
        name: "copies",
        summary: "k rotated copies of a mesh (--mesh FILE or the notched sphere) teleported onto each other, one step (2024 paper Fig. 16)",
        steps: 1,
        knobs: "--count k (4), --mesh FILE, --resolution = notched sphere cells (16), or with --mesh times each triangle is split in four (default: until edges are no longer than the cell size `fix` would pick), --seed",
    },
    SceneInfo {
        name: "cyclic",
        summary: "two bubbles under cyclical normal flow a->b->c->a, curling around a still triple curve (Los Topos Fig. 16)",
        steps: 100,
        knobs: "--radius (1), --resolution = segments around the triple circle (32)",
    },
    SceneInfo {
        name: "rolling",
        summary: "two decorated spheres roll into each other, merge and roll apart: feature preservation (2024 paper Fig. 17)",
        steps: 40,
        knobs: "--resolution = icosphere subdivisions (4), --radius (0.3)",
    },
    SceneInfo {
        name: "metaballs",
        summary: "an animated implicit surface followed by Newton projection: two skeleton segments cross, blend and split (Nesme & Bouthors 2006, Fig. 1)",
        steps: metaballs::STEPS,
        knobs: "--resolution = edges per unit length (8), --count N = a swarm of N blobs instead (more --steps), --seed",
    },
    SceneInfo {
        name: "sphere",
        summary: "(generate only) an icosphere, label 1 inside, 0 outside",
        steps: 0,
        knobs: "--resolution = subdivisions (4), --radius (1)",
    },
];

/// The entry of a scene, if it exists.
pub fn scene_info(name: &str) -> Option<&'static SceneInfo> {
    SCENES.iter().find(|s| s.name == name)
}

/// Parameters shared by the scene builders; `None` means the scene's default.
#[derive(Debug, Default, Clone)]
pub struct SceneOptions {
    /// Random seed.
    pub seed: u64,
    /// Spheres, foam cells or copies.
    pub count: Option<usize>,
    /// Resolution (meaning depends on the scene, see [`SceneInfo::knobs`]).
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
    #[error("unknown scene `{0}`; known scenes: {known}", known = SCENES.iter().map(|s| s.name).collect::<Vec<_>>().join(", "))]
    Unknown(String),
    /// The scene exists as a mesh but has no motion.
    #[error("scene `{0}` is a mesh for `generate` only; tracked scenes: {known}", known = SCENES.iter().filter(|s| s.steps > 0).map(|s| s.name).collect::<Vec<_>>().join(", "))]
    NotTracked(String),
    /// The generator refused the parameters.
    #[error(transparent)]
    Generator(#[from] GeneratorError),
    /// The flow refused its parameters.
    #[error(transparent)]
    Flow(#[from] FlowError),
    /// A `--flow NAME[:key=value,…]` on a user mesh could not be read.
    #[error("--flow {spec}: {message}")]
    FlowSpec {
        /// The spec as given.
        spec: String,
        /// What is wrong, naming what is known.
        message: String,
    },
}

/// A tracked scene: where it starts, how it moves, and for how long by default.
pub struct Scene {
    /// Scene name.
    pub name: &'static str,
    /// The initial mesh (valid, and intersection-free, so either backend can start).
    pub mesh: LabeledMesh,
    /// What proposes the vertex motion.
    pub flow: Box<dyn Flow>,
    /// Time step; a flow with a stability limit may be stepped more finely.
    pub dt: f64,
    /// Default number of steps.
    pub steps: usize,
    /// Spheres, cells or copies, for scenes with a count.
    pub count: Option<usize>,
}

/// `n` spheres of subdivision `s` as one mesh (labels from the [`PlacedSphere`]s).
fn sphere_set(spheres: &[PlacedSphere], subdivisions: u32) -> Result<LabeledMesh, SceneError> {
    Ok(spheres_mesh(spheres, subdivisions)?)
}

/// Normal flow (naive vertex normals unless `flow` says face offsetting): every material
/// but 0 grows at `speed`.
fn expand(speed: f64, flow: &FlowOptions) -> Result<NormalFlow, FlowError> {
    NormalFlow::new(
        InterfaceSpeeds::grow_into(Label::OUTSIDE, speed),
        flow.normal_scheme,
    )
}

/// Largest sphere radius of the `spheres` scene for `n` spheres in the unit cube: keeps
/// the packing fraction near 5 % for any `n`, so placement never struggles and the
/// spheres have room to grow into each other.
fn spheres_radius(n: usize) -> f64 {
    (0.3 * (n.max(1) as f64).powf(-1.0 / 3.0)).min(0.2)
}

/// Builds a tracked scene by name, with the default flow options.
pub fn build_tracked(name: &str, o: &SceneOptions) -> Result<Scene, SceneError> {
    build_tracked_with(name, o, &FlowOptions::default())
}

/// Builds a tracked scene by name, its flows configured by `flow` (the normal-flow
/// scheme of the `normal-flow` ablation).
pub fn build_tracked_with(
    name: &str,
    o: &SceneOptions,
    flow_options: &FlowOptions,
) -> Result<Scene, SceneError> {
    if let Some(spec) = name.strip_prefix(user::PREFIX) {
        return user::build(spec, o, flow_options);
    }
    let info = scene_info(name).ok_or_else(|| SceneError::Unknown(name.to_string()))?;
    if info.steps == 0 {
        return Err(SceneError::NotTracked(name.to_string()));
    }
    let resolution = |default: u32| o.resolution.unwrap_or(default);
    let label = Label::new;
    let (mesh, flow, dt, count): (LabeledMesh, Box<dyn Flow>, f64, Option<usize>) = match name {
        "double-bubble" => {
            // Gap of half a radius; they touch at t = r/4 and have a wide shared wall by
            // t = 0.6 r, when the flow reverses; at t = 2.6 r both have shrunk to nothing.
            let r = o.radius.unwrap_or(0.3);
            let spheres = [-1.0, 1.0].map(|side: f64| PlacedSphere {
                centre: DVec3::new(side * 1.25 * r, 0.0, 0.0),
                radius: r,
                label: label(if side < 0.0 { 1 } else { 2 }),
            });
            let mesh = sphere_set(&spheres, resolution(3))?;
            let flow = Schedule::new(
                vec![
                    (
                        0.6 * r,
                        Box::new(expand(1.0, flow_options)?) as Box<dyn Flow>,
                    ),
                    (2.0 * r, Box::new(expand(-1.0, flow_options)?)),
                ],
                false,
            )?;
            (mesh, Box::new(flow), 2.6 * r / 60.0, None)
        }
        "spheres" => {
            // Speed and step: every vertex moves ~0.3 of the smallest spheres' edge per
            // step, and over 40 steps the spheres grow by half their typical spacing.
            // The 2024 paper (§9.6, Fig. 19) gives neither a placement density nor a
            // speed for its 100- and 1000-sphere runs, only "randomized, non-intersecting"
            // placement and "constant speed"; we keep the packing fraction (~5 %, see
            // `spheres_radius`), the growth relative to the spacing and the triangles per
            // sphere the same for every N, so `--spheres 1000` is the 100-sphere run
            // scaled down tenfold in volume per sphere (~320k triangles at N = 1000).
            let n = o.count.unwrap_or(20);
            let r_max = spheres_radius(n);
            let spheres =
                place_random_spheres(n, DVec3::ZERO, DVec3::ONE, [0.5 * r_max, r_max], o.seed)?;
            let mesh = sphere_set(&spheres, resolution(2))?;
            let speed = 0.5 * (n.max(1) as f64).powf(-1.0 / 3.0);
            (
                mesh,
                Box::new(expand(speed, flow_options)?),
                1.0 / 40.0,
                Some(n),
            )
        }
        "zalesak" => {
            let mesh = generators::zalesak(resolution(32) as usize)?;
            let flow = RigidRotation::zalesak(DVec3::new(0.5, 0.5, 0.5), 1.0)?;
            (mesh, Box::new(flow), 1.0 / 100.0, None)
        }
        "enright" => {
            let mesh = quadrant_sphere(DVec3::splat(0.35), 0.15, resolution(12))?;
            let flow = EnrightFlow::new(EnrightFlow::DEFAULT_PERIOD)?;
            (
                mesh,
                Box::new(flow),
                EnrightFlow::DEFAULT_PERIOD / 300.0,
                None,
            )
        }
        "curl-noise" => {
            // Four spheres of radius 0.2 at the corners of a regular tetrahedron, 0.49
            // apart; normal flow and curl noise take turns, one step each.
            let corners = [
                [1.0, 1.0, 1.0],
                [1.0, -1.0, -1.0],
                [-1.0, 1.0, -1.0],
                [-1.0, -1.0, 1.0],
            ];
            let spheres: Vec<PlacedSphere> = corners
                .iter()
                .enumerate()
                .map(|(i, c)| PlacedSphere {
                    centre: DVec3::from_array(*c).normalize() * 0.3,
                    radius: 0.2,
                    label: label(i as u32 + 1),
                })
                .collect();
            let mesh = sphere_set(&spheres, resolution(3))?;
            let dt = 0.01;
            let noise = CurlNoiseFlow::new(CurlNoiseParams {
                seed: o.seed,
                modes: 16,
                length_scale: 0.5,
                amplitude: 0.5,
            })?;
            let flow = Schedule::new(
                vec![
                    (dt, Box::new(expand(0.5, flow_options)?) as Box<dyn Flow>),
                    (dt, Box::new(noise)),
                ],
                true,
            )?;
            (mesh, Box::new(flow), dt, None)
        }
        "foam" => {
            let n = o.count.unwrap_or(16);
            let mesh = generators::voronoi_foam(n, o.seed, DVec3::ZERO, DVec3::ONE)?;
            (mesh, Box::new(MeanCurvatureFlow::new(1.0)?), 1e-3, Some(n))
        }
        "inversion" => {
            // Noise of rms amplitude half the radius at a wavelength of 0.8 radius, one
            // forward Euler step of length 1: the bubble walls fold through each other.
            let r = o.radius.unwrap_or(1.0);
            let mesh = generators::double_bubble(r, resolution(32) as usize)?;
            let noise = CurlNoiseFlow::new(CurlNoiseParams {
                seed: o.seed,
                modes: 32,
                length_scale: 0.8 * r,
                amplitude: 0.5 * r,
            })?
            .with_integrator(Integrator::ForwardEuler);
            (
                mesh,
                Box::new(OneShot::new("inversion-noise", Box::new(noise))),
                1.0,
                None,
            )
        }
        "copies" => {
            // The copies start side by side along x, apart; the single step teleports them
            // onto their rotated, overlapping positions.
            let k = o.count.unwrap_or(4);
            let base = tracked_copies_base(o, k)?;
            let target = generators::copies(&base, k, o.seed)?;
            let per_copy = base.to_raw().0.len().max(1);
            let (lo, hi) = target
                .vertices()
                .map(|v| target.position(v))
                .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
                    (lo.min(p), hi.max(p))
                });
            let spacing = 1.5 * (hi - lo).max_element().max(f64::MIN_POSITIVE);
            let mut mesh = target.clone();
            for v in target.vertices() {
                let copy = (v.idx() / per_copy) as f64;
                mesh.set_position(v, target.position(v) + DVec3::X * spacing * copy);
            }
            let flow = TargetPositions::new(target.positions().to_vec());
            (mesh, Box::new(flow), 1.0, Some(k))
        }
        "cyclic" => {
            let r = o.radius.unwrap_or(1.0);
            let mesh = generators::double_bubble(r, resolution(32) as usize)?;
            let flow = cyclic_normal_flow(label(1), label(2), Label::OUTSIDE, 1.0)?;
            (mesh, Box::new(flow), 0.01 * r, None)
        }
        "rolling" => {
            let (mesh, flow, dt) = rolling::build(o, info.steps)?;
            (mesh, Box::new(flow), dt, None)
        }
        "foam-tension" => {
            let (mesh, flow, dt) = foam_tension::build(o)?;
            let n = o.count.unwrap_or(foam_tension::DEFAULT_BUBBLES);
            (mesh, Box::new(flow), dt, Some(n))
        }
        "metaballs" => {
            let (mesh, flow, dt) = metaballs::build(o)?;
            (mesh, Box::new(flow), dt, o.count)
        }
        other => return Err(SceneError::Unknown(other.to_string())),
    };
    Ok(Scene {
        name: info.name,
        mesh,
        flow,
        dt,
        steps: info.steps,
        count,
    })
}

/// Builds the mesh `surftrack generate` writes for a scene: the tracked scene's initial
/// mesh, except for `double-bubble`, which writes the merged double bubble (two bubbles,
/// a shared wall and a triple curve: the scene's middle), `copies`, which writes the
/// overlapping union (what the tracker is asked to repair), and `sphere`, one icosphere.
pub fn build_scene(name: &str, o: &SceneOptions) -> Result<LabeledMesh, SceneError> {
    match name {
        "double-bubble" => Ok(generators::double_bubble(
            o.radius.unwrap_or(1.0),
            o.resolution.unwrap_or(48) as usize,
        )?),
        "sphere" => Ok(generators::icosphere(
            o.resolution.unwrap_or(4),
            DVec3::ZERO,
            o.radius.unwrap_or(1.0),
            [Label::OUTSIDE, Label::new(1)],
        )?),
        "copies" => Ok(generators::copies(
            &copies_base(o)?,
            o.count.unwrap_or(4),
            o.seed,
        )?),
        _ => Ok(build_tracked(name, o)?.mesh),
    }
}

/// The mesh `copies` copies: `--mesh` split in four `--resolution` times (none by
/// default; the same surface, finer, so a scan can be copied at any size), or the notched
/// sphere at that resolution.
fn copies_base(o: &SceneOptions) -> Result<LabeledMesh, GeneratorError> {
    match &o.mesh {
        Some(mesh) => generators::subdivide(mesh, o.resolution.unwrap_or(0)),
        None => generators::zalesak(o.resolution.unwrap_or(16) as usize),
    }
}

/// Most times `copies` splits a `--mesh` in four on its own (4⁶ = 4096 times the
/// triangles).
const MAX_COPIES_SPLITS: u32 = 6;

/// Most triangles of all copies together that splitting may reach.
const MAX_COPIES_TRIANGLES: usize = 4_000_000;

/// [`copies_base`] for a run: a `--mesh` without `--resolution` is split in four until its
/// mean edge is no longer than the cell size `fix` would pick for it (an eighth of its
/// thinnest material's 3·volume/area, [`default_cell_size`]), within
/// [`MAX_COPIES_SPLITS`] and [`MAX_COPIES_TRIANGLES`].
///
/// Why: the single step is a repair of the overlapping union, and the grid tracker takes
/// the mean edge length as ℓ; a coarse CAD-like mesh (a 12-triangle cube: edges 1.1 for a
/// unit of thickness) is then about one cell thick, every overlapping material is rebuilt
/// from nodes that miss it, and all of them vanished in the first step. `generate copies`
/// keeps the mesh as given: `fix` chooses its own ℓ.
fn tracked_copies_base(o: &SceneOptions, k: usize) -> Result<LabeledMesh, GeneratorError> {
    let base = copies_base(o)?;
    if o.mesh.is_none() || o.resolution.is_some() {
        return Ok(base);
    }
    let wanted = default_cell_size(&base).cell_size;
    Ok(split_until(base, wanted, k, MAX_COPIES_SPLITS, MAX_COPIES_TRIANGLES)?.0)
}

/// `mesh` split in four ([`generators::subdivide`]) until its mean edge is at most
/// `edge`, at most `max_splits` times and while `copies` copies of it stay within
/// `max_triangles`; also the mean edge reached.
pub(crate) fn split_until(
    mut mesh: LabeledMesh,
    edge: f64,
    copies: usize,
    max_splits: u32,
    max_triangles: usize,
) -> Result<(LabeledMesh, f64), GeneratorError> {
    let mut mean = mean_edge_length(&mesh);
    for _ in 0..max_splits {
        let fine_enough = mean <= edge * (1.0 + 1e-9);
        if fine_enough || 4 * mesh.num_triangles() * copies.max(1) > max_triangles {
            break;
        }
        mesh = generators::subdivide(&mesh, 1)?;
        mean = mean_edge_length(&mesh);
    }
    Ok((mesh, mean))
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

/// The smallest sensible size of each scene (a few hundred to a few thousand
/// triangles): for smoke tests and CI, where every scene must run through every backend
/// in seconds. Unknown names get the defaults.
pub fn smoke_options(name: &str) -> SceneOptions {
    let (count, resolution) = match name {
        "double-bubble" | "curl-noise" => (None, Some(2)),
        "spheres" => (Some(4), Some(2)),
        "zalesak" => (None, Some(10)),
        "enright" => (None, Some(4)),
        "foam" => (Some(4), None),
        "foam-tension" => (Some(4), Some(3)),
        "inversion" | "cyclic" => (None, Some(8)),
        "rolling" => (None, Some(2)),
        "metaballs" => (None, Some(5)),
        "copies" => (Some(2), Some(8)),
        _ => (None, None),
    };
    SceneOptions {
        seed: 3,
        count,
        resolution,
        ..SceneOptions::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use mesh_core::validate::{ValidateOptions, validate};

    #[test]
    fn every_tracked_scene_starts_valid_and_intersection_free_with_a_full_proposal() {
        for info in SCENES.iter().filter(|s| s.steps > 0) {
            let scene = build_tracked(info.name, &smoke_options(info.name))
                .unwrap_or_else(|e| panic!("{}: {e}", info.name));
            let report = validate(&scene.mesh, &ValidateOptions::with_intersections());
            assert!(report.is_valid(), "{}: {report}", info.name);
            assert!(scene.mesh.num_triangles() > 0 && scene.dt > 0.0 && scene.steps > 0);
            let proposed = scene.flow.propose(&scene.mesh, 0.0, scene.dt);
            assert_eq!(
                proposed.len(),
                scene.mesh.vertex_capacity(),
                "{}",
                info.name
            );
            assert!(proposed.iter().all(|p| p.is_finite()), "{}", info.name);
            // Every scene moves something in its first step.
            let moved = scene
                .mesh
                .vertices()
                .any(|v| proposed[v.idx()] != scene.mesh.position(v));
            assert!(moved, "{} proposes no motion", info.name);
        }
    }

    #[test]
    fn copies_start_apart_and_are_sent_onto_the_overlapping_union() {
        let o = smoke_options("copies");
        let scene = build_tracked("copies", &o).unwrap();
        let union = build_scene("copies", &o).unwrap();
        let proposed = scene.flow.propose(&scene.mesh, 0.0, scene.dt);
        assert_eq!(proposed, union.positions());
        // The first copy does not move; the second is shifted along x only.
        let half = scene.mesh.vertex_capacity() / 2;
        let first = mesh_core::VertexId::new(0);
        let second = mesh_core::VertexId::new(half as u32);
        assert_eq!(scene.mesh.position(first), union.position(first));
        let shift = scene.mesh.position(second) - union.position(second);
        assert!(shift.x > 0.0 && shift.y == 0.0 && shift.z == 0.0);
    }

    /// A coarse CAD-like mesh (a 12-triangle unit cube) copied onto itself: the run's
    /// copies are split until their edges fit the cell size `fix` would pick (1/16), so
    /// the grid tracker's one step keeps every material, where at the cube's own edges
    /// (ℓ ≈ 1.1) all of them vanished. `generate copies` keeps the cube as given.
    #[test]
    fn copies_of_a_coarse_mesh_are_refined_so_that_no_material_vanishes() {
        use mesh_core::SurfaceTracker;
        let cube =
            generators::cuboid(DVec3::ZERO, DVec3::ONE, [Label::OUTSIDE, Label::new(1)]).unwrap();
        let o = SceneOptions {
            count: Some(3),
            mesh: Some(cube),
            ..SceneOptions::default()
        };
        assert_eq!(build_scene("copies", &o).unwrap().num_triangles(), 3 * 12);
        let scene = build_tracked("copies", &o).unwrap();
        assert_eq!(scene.mesh.num_triangles(), 3 * 12 * 4usize.pow(5));
        let mut tracker = surftrack::grid_tracker::GridTracker::new(
            scene.mesh.clone(),
            surftrack::grid_tracker::GridParams::default(),
        )
        .unwrap();
        let proposed = scene.flow.propose(&scene.mesh, 0.0, scene.dt);
        let report = tracker.advance(&proposed).unwrap();
        assert!(report.events.vanished.is_empty(), "{:?}", report.events);
        for v in &report.volumes {
            assert!(v.after > 0.1 * v.before, "{v:?}");
        }
    }

    /// With `--mesh`, `--resolution` splits the given mesh's triangles in four that many
    /// times (none by default) instead of naming a notched-sphere size; the union covers the
    /// same volume either way.
    #[test]
    fn copies_of_a_given_mesh_are_subdivided_by_the_resolution() {
        let given = generators::zalesak(6).unwrap();
        let with = |resolution| SceneOptions {
            count: Some(2),
            resolution,
            mesh: Some(given.clone()),
            ..SceneOptions::default()
        };
        let plain = build_scene("copies", &with(None)).unwrap();
        let finer = build_scene("copies", &with(Some(1))).unwrap();
        assert_eq!(plain.num_triangles(), 2 * given.num_triangles());
        assert_eq!(finer.num_triangles(), 4 * plain.num_triangles());
        let (a, b) = (
            mesh_core::geometry::label_volumes(&plain),
            mesh_core::geometry::label_volumes(&finer),
        );
        for (label, volume) in &a {
            assert!((volume - b[label]).abs() < 1e-9, "label {label}");
        }
        let tracked = build_tracked("copies", &with(Some(1))).unwrap();
        assert_eq!(tracked.mesh.num_triangles(), finer.num_triangles());
    }

    #[test]
    fn unknown_and_untracked_scenes_are_errors() {
        let o = SceneOptions::default();
        assert!(matches!(
            build_tracked("nope", &o),
            Err(SceneError::Unknown(_))
        ));
        assert!(matches!(
            build_tracked("sphere", &o),
            Err(SceneError::NotTracked(_))
        ));
        assert!(build_scene("sphere", &o).is_ok());
        let bad = SceneOptions {
            count: Some(0),
            ..SceneOptions::default()
        };
        assert!(matches!(
            build_tracked("spheres", &bad),
            Err(SceneError::Generator(_))
        ));
    }

    #[test]
    fn spheres_are_seeded() {
        let o = |seed| SceneOptions {
            seed,
            ..smoke_options("spheres")
        };
        let a = build_tracked("spheres", &o(1)).unwrap().mesh;
        let b = build_tracked("spheres", &o(1)).unwrap().mesh;
        let c = build_tracked("spheres", &o(2)).unwrap().mesh;
        assert_eq!(a.positions(), b.positions());
        assert_ne!(a.positions(), c.positions());
    }
}
