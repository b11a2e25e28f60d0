//! A built-in flow on the user's own mesh: `surftrack run --mesh FILE --flow
//! NAME[:key=value,…]`.
//!
//! The run's scene is named `mesh:<flow spec>` (so a record replays it with its
//! `scene_params.mesh`), and [`build`] makes the [`Scene`] from the mesh and the spec:
//!
//! | flow | keys (defaults) | time step |
//! |---|---|---|
//! | `normal` | `speed` (1: every material but 0 grows into 0), `A-B` (material A advances into B at this speed, per pair), `scheme` (`vertex_normals` / `face_offsetting`; default the `flow.normal_scheme` option) | 0.3 ℓ / fastest speed |
//! | `enright` | `period` (3) | period / 300 |
//! | `curl-noise` | `seed` (the run's), `modes` (16), `length` (0.5), `amplitude` (1) | 0.3 ℓ / amplitude |
//! | `rotation` | `axis` (`x`, `y`, `z`; z), `period` (1), centre `cx`, `cy`, `cz` (the mesh's bounding-box centre) | period / 100 |
//! | `mean-curvature` | `tension` (1) | 10⁻³, clamped to the flow's stability limit |
//!
//! ℓ is the mean edge length of the mesh the run starts from: the file's, split in four
//! until every material is at least [`EDGES_PER_THICKNESS`] edges thick ([`fit_mesh`];
//! `--resolution N` splits exactly N times instead). Forty steps by default (`--steps`,
//! `--dt` override).

use glam::DVec3;
use mesh_core::generators;
use mesh_core::predicates::{below_min_extent, within_max_coordinate};
use mesh_core::remesh::improve::mean_edge_length;
use mesh_core::validate::{ValidateOptions, validate};
use mesh_core::{Label, LabeledMesh};
use surftrack::grid_tracker::thinnest_shell;

use crate::flows::{
    CurlNoiseFlow, CurlNoiseParams, EnrightFlow, Flow, InterfaceSpeeds, MeanCurvatureFlow,
    NormalFlow, NormalScheme, RigidRotation,
};
use crate::options::FlowOptions;

use super::{Scene, SceneError, SceneOptions};

/// The prefix of a user-mesh scene's name.
pub const PREFIX: &str = "mesh:";

/// The scene name `surftrack run --mesh --flow` gives a run.
pub fn scene_name(flow_spec: &str) -> String {
    format!("{PREFIX}{flow_spec}")
}

/// Default number of steps of a user-mesh run.
pub const STEPS: usize = 40;

/// The flows by name, for messages.
pub const FLOWS: &[&str] = &[
    "normal",
    "enright",
    "curl-noise",
    "rotation",
    "mean-curvature",
];

/// How many mean edges thick (3·volume/area) every material must be before a run starts.
///
/// Why: both trackers take the mean edge length as ℓ and improve the mesh towards it, and
/// a collapse may change a material by up to 0.1 ℓ³. On a mesh coarser than its materials
/// that erases them under a motion that keeps every volume: a 252-triangle CAD cylinder
/// (radius 1, height 10, 3V/A = 1.36, mean edge 3.85) turned by `--flow rotation` for 20
/// steps kept 33 % (grid) and 42 % (collision) of its volume, every frame valid. Split
/// until its mean edge is at most 3V/A (2 splits) it keeps 90 % and 97 %; at most half of
/// it (3 splits), 97 % and 99.8 %. One edge is the compromise: a 943-triangle Voronoi foam
/// (thinnest cell 0.09, mean edge 0.19) keeps every cell's volume under `normal` flow
/// unsplit, and each split costs it 1.6-2x the run time.
pub const EDGES_PER_THICKNESS: f64 = 1.0;

/// Most times a run splits a `--mesh` in four on its own.
const MAX_SPLITS: u32 = 6;

/// Most triangles splitting may reach.
const MAX_TRIANGLES: usize = 4_000_000;

/// The mesh a user-mesh run starts from: `mesh` split `resolution` times if given, else
/// until its thinnest material is [`EDGES_PER_THICKNESS`] mean edges thick. A material
/// that stays thinner than one mean edge within [`MAX_SPLITS`] and [`MAX_TRIANGLES`] is
/// an error naming it: the run would erase it.
pub fn fit_mesh(mesh: LabeledMesh, resolution: Option<u32>) -> Result<LabeledMesh, String> {
    if let Some(n) = resolution {
        return generators::subdivide(&mesh, n).map_err(|e| e.to_string());
    }
    let Some((label, thickness)) = thinnest_shell(&mesh) else {
        return Ok(mesh);
    };
    let wanted = thickness / EDGES_PER_THICKNESS;
    let (fitted, mean) = super::split_until(mesh, wanted, 1, MAX_SPLITS, MAX_TRIANGLES)
        .map_err(|e| e.to_string())?;
    if mean > thickness {
        return Err(format!(
            "material {label} is {thickness:.4} thick (3·volume/area), less than the mean \
             edge {mean:.4} of the mesh split to {} triangles: the run would erase it. Give a \
             finer mesh, or `--resolution N` to split it N times and run anyway",
            fitted.num_triangles()
        ));
    }
    Ok(fitted)
}

/// `NAME[:key=value,…]` split into the name and its `(key, value)` pairs.
struct Spec<'a> {
    text: &'a str,
    name: &'a str,
    pairs: Vec<(&'a str, &'a str)>,
}

impl<'a> Spec<'a> {
    fn parse(text: &'a str) -> Result<Self, SceneError> {
        let (name, rest) = text.split_once(':').unwrap_or((text, ""));
        let mut pairs = Vec::new();
        for item in rest.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            let (k, v) = item.split_once('=').ok_or_else(|| SceneError::FlowSpec {
                spec: text.to_string(),
                message: format!("`{item}` is not key=value"),
            })?;
            pairs.push((k.trim(), v.trim()));
        }
        Ok(Spec {
            text,
            name: name.trim(),
            pairs,
        })
    }

    fn error(&self, message: String) -> SceneError {
        SceneError::FlowSpec {
            spec: self.text.to_string(),
            message,
        }
    }

    /// Refuses keys outside `known` (and, for `normal`, the `A-B` pair keys).
    fn check_keys(&self, known: &[&str], pair_keys: bool) -> Result<(), SceneError> {
        for (k, _) in &self.pairs {
            let is_pair = pair_keys && pair_key(k).is_some();
            if !(known.contains(k) || is_pair) {
                let extra = if pair_keys {
                    ", or A-B for a label pair"
                } else {
                    ""
                };
                return Err(self.error(format!(
                    "unknown key `{k}` for flow `{}`; known keys: {}{extra}",
                    self.name,
                    known.join(", ")
                )));
            }
        }
        Ok(())
    }

    fn number(&self, key: &str, default: f64) -> Result<f64, SceneError> {
        match self.pairs.iter().rev().find(|(k, _)| *k == key) {
            None => Ok(default),
            Some((_, v)) => v
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| self.error(format!("`{key}={v}`: expected a finite number"))),
        }
    }

    fn text_value(&self, key: &str) -> Option<&'a str> {
        self.pairs
            .iter()
            .rev()
            .find(|(k, _)| *k == key)
            .map(|(_, v)| *v)
    }
}

/// `A-B` as two labels.
fn pair_key(key: &str) -> Option<(Label, Label)> {
    let (a, b) = key.split_once('-')?;
    Some((Label::new(a.parse().ok()?), Label::new(b.parse().ok()?)))
}

/// Centre of the bounding box of the live vertices.
fn bbox_centre(mesh: &LabeledMesh) -> DVec3 {
    let (lo, hi) = mesh
        .vertices()
        .map(|v| mesh.position(v))
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p), hi.max(p))
        });
    if lo.is_finite() && hi.is_finite() {
        0.5 * (lo + hi)
    } else {
        DVec3::ZERO
    }
}

/// Refuses a mesh outside the coordinate range the library works in
/// ([`mesh_core::predicates::MAX_COORDINATE`], [`mesh_core::predicates::MIN_EXTENT`]),
/// naming the first vertex out of it. Why here: the flow's time step is derived from the
/// mean edge length, which such a mesh makes infinite or zero, and the run would then
/// stop on a time step the user never gave instead of on the mesh.
fn check_range(mesh: &LabeledMesh) -> Result<(), String> {
    if let Some(v) = mesh
        .vertices()
        .find(|&v| !within_max_coordinate(mesh.position(v)))
    {
        let p = mesh.position(v);
        return Err(format!(
            "the mesh's vertex {v} is at ({:e}, {:e}, {:e}): coordinates must be finite and at most 2^100 ≈ 1.3e30 \
             in magnitude (rescale the mesh)",
            p.x, p.y, p.z
        ));
    }
    let extent = mesh_core::validate::coordinate_extent(mesh);
    if below_min_extent(extent) {
        return Err(format!(
            "the mesh's largest coordinate magnitude is {extent:e}, below 2^-100 ≈ 7.9e-31 \
             (rescale the mesh)"
        ));
    }
    Ok(())
}

/// The scene of `spec` (the part after [`PREFIX`]) on `o.mesh`.
pub fn build(
    spec: &str,
    o: &SceneOptions,
    flow_options: &FlowOptions,
) -> Result<Scene, SceneError> {
    let spec = Spec::parse(spec)?;
    let mesh = o
        .mesh
        .clone()
        .ok_or_else(|| spec.error("a flow on a user mesh needs the mesh (`--mesh FILE`)".into()))?;
    if mesh.num_triangles() == 0 {
        return Err(spec.error("the mesh has no triangles".into()));
    }
    check_range(&mesh).map_err(|m| spec.error(m))?;
    // Layers 1–3 before placement, which assumes them: an open sheet or a flattened
    // solid was reported as "a part nested in another" with a remedy that cannot help.
    let structure = validate(
        &mesh,
        &ValidateOptions {
            placement: false,
            ..ValidateOptions::default()
        },
    );
    if !structure.is_valid() {
        return Err(spec.error(format!(
            "the mesh is not a valid labelled surface (`surftrack validate FILE` lists \
             every fault): {structure}"
        )));
    }
    // Before any splitting (up to millions of triangles): the trackers refuse a part
    // whose outside label is not the material it lies in, and `fix` is the remedy.
    if let Some(m) = mesh_core::placement::misplaced_shells(&mesh).first() {
        return Err(spec.error(format!(
            "{m}: a part nested in another with the wrong label outside it, or overlapping \
             it. `surftrack fix IN OUT` relabels nested parts and repairs overlaps; run on \
             its output"
        )));
    }
    let mesh = fit_mesh(mesh, o.resolution).map_err(|m| spec.error(m))?;
    let l = mean_edge_length(&mesh);
    let (flow, dt): (Box<dyn Flow>, f64) = match spec.name {
        "normal" => {
            spec.check_keys(&["speed", "scheme"], true)?;
            let speed = spec.number("speed", 1.0)?;
            let mut speeds = InterfaceSpeeds::grow_into(Label::OUTSIDE, speed);
            let mut fastest = speed.abs();
            for (k, _) in &spec.pairs {
                if let Some((a, b)) = pair_key(k) {
                    let s = spec.number(k, 0.0)?;
                    speeds = speeds.with_pair(a, b, s);
                    fastest = fastest.max(s.abs());
                }
            }
            let scheme = match spec.text_value("scheme") {
                None => flow_options.normal_scheme,
                Some("vertex_normals") => NormalScheme::VertexNormals,
                Some("face_offsetting") => NormalScheme::FaceOffsetting,
                Some(other) => {
                    return Err(spec.error(format!(
                        "`scheme={other}`: expected vertex_normals or face_offsetting"
                    )));
                }
            };
            let flow = NormalFlow::new(speeds, scheme)?;
            (Box::new(flow), 0.3 * l / fastest.max(f64::MIN_POSITIVE))
        }
        "enright" => {
            spec.check_keys(&["period"], false)?;
            let period = spec.number("period", EnrightFlow::DEFAULT_PERIOD)?;
            (Box::new(EnrightFlow::new(period)?), period / 300.0)
        }
        "curl-noise" => {
            spec.check_keys(&["seed", "modes", "length", "amplitude"], false)?;
            let defaults = CurlNoiseParams::default();
            let seed = spec.number("seed", o.seed as f64)?;
            let modes = spec.number("modes", defaults.modes as f64)?;
            let params = CurlNoiseParams {
                seed: seed.max(0.0) as u64,
                modes: modes.max(0.0) as usize,
                length_scale: spec.number("length", defaults.length_scale)?,
                amplitude: spec.number("amplitude", defaults.amplitude)?,
            };
            let dt = 0.3 * l / params.amplitude.abs().max(f64::MIN_POSITIVE);
            (Box::new(CurlNoiseFlow::new(params)?), dt)
        }
        "rotation" => {
            spec.check_keys(&["axis", "period", "cx", "cy", "cz"], false)?;
            let axis = match spec.text_value("axis").unwrap_or("z") {
                "x" => DVec3::X,
                "y" => DVec3::Y,
                "z" => DVec3::Z,
                other => return Err(spec.error(format!("`axis={other}`: expected x, y or z"))),
            };
            let period = spec.number("period", 1.0)?;
            if period <= 0.0 {
                return Err(spec.error(format!("`period={period}`: expected > 0")));
            }
            let c = bbox_centre(&mesh);
            let centre = DVec3::new(
                spec.number("cx", c.x)?,
                spec.number("cy", c.y)?,
                spec.number("cz", c.z)?,
            );
            let flow = RigidRotation::new(centre, axis, std::f64::consts::TAU / period)?;
            (Box::new(flow), period / 100.0)
        }
        "mean-curvature" => {
            spec.check_keys(&["tension"], false)?;
            let tension = spec.number("tension", 1.0)?;
            (Box::new(MeanCurvatureFlow::new(tension)?), 1e-3)
        }
        other => {
            return Err(spec.error(format!(
                "unknown flow `{other}`; known flows: {}",
                FLOWS.join(", ")
            )));
        }
    };
    Ok(Scene {
        name: "mesh",
        mesh,
        flow,
        dt,
        steps: STEPS,
        count: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use mesh_core::generators::{cuboid, double_bubble};

    /// Boxes `(lo, hi, label)` with outside 0, as one mesh.
    fn boxes(list: &[(DVec3, DVec3, u32)]) -> LabeledMesh {
        let (mut positions, mut tris, mut labels) = (Vec::new(), Vec::new(), Vec::new());
        for &(lo, hi, label) in list {
            let (p, t, l) = cuboid(lo, hi, [Label::OUTSIDE, Label::new(label)])
                .unwrap()
                .to_raw();
            let base = positions.len() as u32;
            positions.extend(p);
            tris.extend(t.iter().map(|t| t.map(|v| v + base)));
            labels.extend(l);
        }
        LabeledMesh::from_raw(positions, &tris, &labels).unwrap()
    }

    #[test]
    fn a_coarse_mesh_is_split_until_every_material_is_an_edge_thick() {
        // A 10 x 1 x 1 bar of 12 triangles: 3V/A = 0.71, mean edge about 5.
        let bar = boxes(&[(DVec3::ZERO, DVec3::new(10.0, 1.0, 1.0), 1)]);
        let (_, thickness) = thinnest_shell(&bar).unwrap();
        assert!(mean_edge_length(&bar) > thickness);
        let fitted = fit_mesh(bar.clone(), None).unwrap();
        assert!(mean_edge_length(&fitted) <= thickness / EDGES_PER_THICKNESS);
        assert!(fitted.num_triangles() > 12);
        // `--resolution N` splits exactly N times, even 0.
        assert_eq!(fit_mesh(bar.clone(), Some(0)).unwrap().num_triangles(), 12);
        assert_eq!(fit_mesh(bar, Some(1)).unwrap().num_triangles(), 48);
        // A fine enough mesh is kept as given.
        let n = fitted.num_triangles();
        assert_eq!(fit_mesh(fitted, None).unwrap().num_triangles(), n);
    }

    #[test]
    fn a_material_no_split_can_resolve_is_an_error_naming_it() {
        // A 0.01 cube beside a 10 cube: the splits stop at the triangle bound long before
        // the small cube is an edge thick.
        let mesh = boxes(&[
            (DVec3::ZERO, DVec3::splat(10.0), 1),
            (DVec3::new(12.0, 0.0, 0.0), DVec3::new(12.01, 0.01, 0.01), 2),
        ]);
        let message = fit_mesh(mesh.clone(), None).unwrap_err();
        assert!(message.contains("material L2"), "{message}");
        assert!(message.contains("--resolution"), "{message}");
        let o = SceneOptions {
            mesh: Some(mesh),
            ..SceneOptions::default()
        };
        assert!(build("rotation", &o, &FlowOptions::default()).is_err());
        let o = SceneOptions {
            resolution: Some(0),
            ..o
        };
        assert!(build("rotation", &o, &FlowOptions::default()).is_ok());
    }

    /// A part nested in another with 0 outside it: an error that names it and `fix`,
    /// before any splitting.
    #[test]
    fn a_nested_part_is_an_error_pointing_at_fix() {
        let l = |i| mesh_core::Label::new(i);
        let outer = mesh_core::generators::icosphere(1, DVec3::ZERO, 1.0, [l(0), l(1)]).unwrap();
        let inner = mesh_core::generators::icosphere(1, DVec3::ZERO, 0.5, [l(0), l(2)]).unwrap();
        let o = SceneOptions {
            mesh: Some(LabeledMesh::disjoint_union(&[outer, inner]).unwrap()),
            ..SceneOptions::default()
        };
        let message = build("normal", &o, &FlowOptions::default())
            .err()
            .expect("refused")
            .to_string();
        assert!(message.contains("lies in material 1"), "{message}");
        assert!(message.contains("surftrack fix"), "{message}");
    }

    /// A structurally broken mesh is refused with what validation finds (an open sheet's
    /// boundary edges, a flattened solid's zero-area triangles), not as "a part nested in
    /// another" from the placement check that assumes a valid surface.
    #[test]
    fn an_invalid_mesh_is_an_error_naming_its_faults_not_placement() {
        let l = |i| mesh_core::Label::new(i);
        let sheet = LabeledMesh::from_raw(
            vec![DVec3::ZERO, DVec3::X, DVec3::Y],
            &[[0, 1, 2]],
            &[[0, 1]],
        )
        .unwrap();
        let mut flat = mesh_core::generators::icosphere(1, DVec3::ZERO, 1.0, [l(0), l(1)]).unwrap();
        for v in flat.vertices().collect::<Vec<_>>() {
            let p = flat.position(v);
            flat.set_position(v, DVec3::new(p.x, p.y, 0.0));
        }
        for (mesh, expect) in [(sheet, "boundary edges"), (flat, "zero-area triangles")] {
            let o = SceneOptions {
                mesh: Some(mesh),
                ..SceneOptions::default()
            };
            let message = build("normal", &o, &FlowOptions::default())
                .err()
                .expect("refused")
                .to_string();
            assert!(message.contains(expect), "{message}");
            assert!(!message.contains("nested"), "{message}");
        }
    }

    /// A mesh too large or too small for the predicates is refused naming the mesh (its
    /// first vertex out of range, or its size), not the time step derived from it.
    #[test]
    fn a_mesh_out_of_range_is_an_error_naming_it_not_the_time_step() {
        for (scale, expect) in [
            (1e200, "the mesh's vertex v0 is at"),
            (f64::INFINITY, "the mesh's vertex v"),
            (1e-200, "largest coordinate magnitude is"),
        ] {
            let (p, t, l) = double_bubble(0.5, 4).unwrap().to_raw();
            let p: Vec<DVec3> = p.into_iter().map(|p| p * scale).collect();
            let o = SceneOptions {
                mesh: Some(LabeledMesh::from_raw(p, &t, &l).unwrap()),
                ..SceneOptions::default()
            };
            for flow in ["normal", "enright", "mean-curvature"] {
                let message = build(flow, &o, &FlowOptions::default())
                    .err()
                    .expect("refused")
                    .to_string();
                assert!(message.contains(expect), "{scale}: {message}");
                assert!(message.contains("rescale the mesh"), "{message}");
            }
        }
    }

    fn options() -> SceneOptions {
        SceneOptions {
            mesh: Some(double_bubble(0.5, 8).unwrap()),
            ..SceneOptions::default()
        }
    }

    #[test]
    fn every_flow_builds_on_a_user_mesh_and_proposes_motion() {
        let o = options();
        let mesh = o.mesh.clone().unwrap();
        for spec in [
            "normal",
            "normal:speed=0.5,1-2=0.3,scheme=face_offsetting",
            "enright:period=2",
            "curl-noise:modes=8,amplitude=0.5",
            "rotation:axis=x,period=2",
            "mean-curvature:tension=0.5",
        ] {
            let scene = build(spec, &o, &FlowOptions::default()).unwrap();
            assert!(scene.dt > 0.0 && scene.dt.is_finite(), "{spec}");
            let proposed = scene.flow.propose(&mesh, 0.0, scene.dt);
            let moved = mesh
                .vertices()
                .filter(|v| proposed[v.idx()] != mesh.position(*v))
                .count();
            assert!(moved > 0, "{spec} moved nothing");
        }
    }

    #[test]
    fn bad_specs_name_what_is_known() {
        let o = options();
        let err = |s: &str| {
            build(s, &o, &FlowOptions::default())
                .err()
                .unwrap()
                .to_string()
        };
        assert!(
            err("swirl").contains("known flows: normal, enright"),
            "{}",
            err("swirl")
        );
        assert!(err("enright:perio=2").contains("known keys: period"));
        assert!(err("normal:speed=fast").contains("finite number"));
        assert!(err("rotation:axis=w").contains("x, y or z"));
        assert!(err("normal:speed").contains("key=value"));
        let none = SceneOptions::default();
        assert!(build("normal", &none, &FlowOptions::default()).is_err());
    }
}
