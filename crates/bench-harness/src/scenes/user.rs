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
//! ℓ is the mesh's mean edge length. Forty steps by default (`--steps`, `--dt` override).

use glam::DVec3;
use mesh_core::remesh::improve::mean_edge_length;
use mesh_core::{Label, LabeledMesh};

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
    use mesh_core::generators::double_bubble;

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
