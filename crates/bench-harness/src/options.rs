//! Options as data: every stage option of both backends and of the flows in one
//! serde struct ([`RunOptions`]), overridable from a TOML scenario file and from
//! `--set path.to.option=value`, and written into every run record so that the record
//! alone reproduces the run.
//!
//! # Paths
//!
//! An option's path is its field path in [`RunOptions`] serialised: `grid.resampling`,
//! `grid.flaws.deep_cell_test`, `grid.rebuild.curve_smoothing_steps`,
//! `grid.label_correction`, `grid.improve` (a table, or `none` for off),
//! `grid.improve.max_sweeps`, `collision.merge`, `collision.t1`, `collision.improve`,
//! `collision.impact_zones`, `collision.collision_safety`, `flow.normal_scheme`, … —
//! `surftrack run SCENE --print-options` lists them all with their defaults.
//!
//! # Values
//!
//! A `--set` value is read as a TOML value (`true`, `3`, `0.5`, `"text"`, `[1, 2]`,
//! `{ max_sweeps = 2 }`); a bare word that is not TOML (`global`, `fast_marching`) is a
//! string; `none` and `null` mean "off"/"default" for optional fields. Enum variants are
//! snake case.
//!
//! # Layering
//!
//! Defaults, then the scenario file (`--config file.toml`, tables `[grid]`, `[collision]`,
//! `[flow]`), then every `--set` in order. Unknown paths are errors that list the known
//! keys at that level.

use std::path::Path;

use serde::{Deserialize, Serialize};
use serde_json::{Map, Value};
use surftrack::BackendOptions;
use surftrack::collision_tracker::CollisionParams;
use surftrack::grid_tracker::GridParams;

use crate::flows::NormalScheme;

/// Options of the flows the scenes build (the geometric ones: normal flow).
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FlowOptions {
    /// How constant-speed normal flow moves vertices: `vertex_normals` (the naive flow of
    /// the 2024 paper's §9.6) or `face_offsetting` (Jiao 2007, Los Topos §8.2). Default
    /// `vertex_normals`. Used by every scene whose motion is normal flow (`spheres`,
    /// `double-bubble`, `curl-noise`).
    pub normal_scheme: NormalScheme,
}

/// Every option of a run besides the scene: both backends' parameters and the flows'.
/// Only the chosen backend's table is used; both are recorded, so a record names every
/// default in force when it was written.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RunOptions {
    /// [`GridParams`] of the grid backend.
    pub grid: GridParams,
    /// [`CollisionParams`] of the collision backend.
    pub collision: CollisionParams,
    /// [`FlowOptions`].
    pub flow: FlowOptions,
}

/// Equal when their serialised forms are (the collision backend's ambient flow, a
/// closure, is not compared: it is not data).
impl PartialEq for RunOptions {
    fn eq(&self, other: &Self) -> bool {
        to_tree(self) == to_tree(other)
    }
}

impl RunOptions {
    /// The backends' part, for [`surftrack::make_tracker_from`].
    pub fn backend_options(&self) -> BackendOptions {
        BackendOptions {
            grid: self.grid.clone(),
            collision: self.collision.clone(),
        }
    }
}

/// Why options could not be read or set.
#[derive(Debug, thiserror::Error)]
pub enum OptionsError {
    /// The scenario file could not be read.
    #[error("cannot read scenario file {path}: {message}")]
    Read {
        /// The file.
        path: String,
        /// The I/O error.
        message: String,
    },
    /// The scenario file is not valid TOML.
    #[error("scenario file {path} is not valid TOML: {message}")]
    Toml {
        /// The file.
        path: String,
        /// The parser's message.
        message: String,
    },
    /// A `--set` argument is not `path=value`.
    #[error("`--set {0}`: expected path.to.option=value, e.g. grid.resampling=global")]
    Syntax(String),
    /// No option has this path.
    #[error("unknown option `{path}`: `{key}` is not one of {known}")]
    UnknownPath {
        /// The full path.
        path: String,
        /// The key that was not found.
        key: String,
        /// The keys known at that level.
        known: String,
    },
    /// The value does not fit the option's type.
    #[error("invalid value for `{path}`: {message}")]
    Value {
        /// The option (or `config` for a whole file).
        path: String,
        /// serde's message.
        message: String,
    },
}

/// The options as a JSON tree (the form paths are resolved in).
fn to_tree(options: &RunOptions) -> Value {
    // Serialising plain structs of numbers, bools and strings cannot fail.
    serde_json::to_value(options).unwrap_or(Value::Null)
}

/// Reads the tree back, with `path` naming the culprit on error.
fn from_tree(tree: Value, path: &str) -> Result<RunOptions, OptionsError> {
    serde_json::from_value(tree).map_err(|e| OptionsError::Value {
        path: path.to_string(),
        message: e.to_string(),
    })
}

/// A TOML value as JSON (datetimes as strings: no option is a date).
fn toml_to_json(value: toml::Value) -> Value {
    match value {
        toml::Value::String(s) => Value::String(s),
        toml::Value::Integer(i) => Value::from(i),
        toml::Value::Float(f) => serde_json::Number::from_f64(f)
            .map(Value::Number)
            .unwrap_or(Value::Null),
        toml::Value::Boolean(b) => Value::Bool(b),
        toml::Value::Datetime(d) => Value::String(d.to_string()),
        toml::Value::Array(a) => Value::Array(a.into_iter().map(toml_to_json).collect()),
        toml::Value::Table(t) => Value::Object(
            t.into_iter()
                .map(|(k, v)| (k, toml_to_json(v)))
                .collect::<Map<String, Value>>(),
        ),
    }
}

/// Parses the value part of `--set path=value` (see the module doc).
pub fn parse_value(text: &str) -> Value {
    let text = text.trim();
    if text.eq_ignore_ascii_case("none") || text.eq_ignore_ascii_case("null") {
        return Value::Null;
    }
    match format!("v = {text}").parse::<toml::Table>() {
        Ok(mut table) => table
            .remove("v")
            .map(toml_to_json)
            .unwrap_or_else(|| Value::String(text.to_string())),
        Err(_) => Value::String(text.to_string()),
    }
}

/// Sets `path` (dot separated) in `tree` to `value`. Every key but the last must exist
/// and be a table; the last must exist too, except inside a table that is `null` in the
/// defaults (an optional struct switched off), which the value then switches on.
fn set_path(tree: &mut Value, path: &str, value: Value) -> Result<(), OptionsError> {
    let keys: Vec<&str> = path.split('.').collect();
    let mut node = tree;
    for (i, key) in keys.iter().enumerate() {
        let last = i + 1 == keys.len();
        let Value::Object(map) = node else {
            return Err(OptionsError::UnknownPath {
                path: path.to_string(),
                key: key.to_string(),
                known: "(not a table)".to_string(),
            });
        };
        if !map.contains_key(*key) {
            let known = map.keys().cloned().collect::<Vec<_>>().join(", ");
            return Err(OptionsError::UnknownPath {
                path: path.to_string(),
                key: key.to_string(),
                known,
            });
        }
        let slot = map
            .get_mut(*key)
            .ok_or_else(|| OptionsError::Syntax(path.into()))?;
        if last {
            *slot = value;
            return Ok(());
        }
        if slot.is_null() {
            return Err(OptionsError::Value {
                path: path.to_string(),
                message: format!(
                    "`{}` is off (none); set it to a table first, e.g. `{}={{}}`",
                    keys[..=i].join("."),
                    keys[..=i].join(".")
                ),
            });
        }
        node = slot;
    }
    Err(OptionsError::Syntax(path.to_string()))
}

/// Merges `patch` into `tree`, key by key, checking that every key exists.
fn merge_tree(tree: &mut Value, patch: Value, prefix: &str) -> Result<(), OptionsError> {
    match patch {
        Value::Object(map) => {
            for (k, v) in map {
                let path = if prefix.is_empty() {
                    k.clone()
                } else {
                    format!("{prefix}.{k}")
                };
                let target_is_table = matches!(
                    tree.pointer(&format!("/{}", path.replace('.', "/"))),
                    Some(Value::Object(_))
                );
                if v.is_object() && target_is_table {
                    merge_tree(tree, v, &path)?;
                } else {
                    set_path(tree, &path, v)?;
                }
            }
            Ok(())
        }
        other => set_path(tree, prefix, other),
    }
}

/// Builds options in layers and remembers which paths were set explicitly.
#[derive(Clone, Debug)]
pub struct OptionsBuilder {
    tree: Value,
    set: Vec<String>,
}

impl Default for OptionsBuilder {
    fn default() -> Self {
        Self::new(&RunOptions::default())
    }
}

impl OptionsBuilder {
    /// Starts from `base` (the defaults, or a record's options).
    pub fn new(base: &RunOptions) -> Self {
        OptionsBuilder {
            tree: to_tree(base),
            set: Vec::new(),
        }
    }

    /// Layers a TOML scenario file over the options.
    pub fn config_file(&mut self, path: &Path) -> Result<&mut Self, OptionsError> {
        let text = std::fs::read_to_string(path).map_err(|e| OptionsError::Read {
            path: path.display().to_string(),
            message: e.to_string(),
        })?;
        self.config_text(&text, &path.display().to_string())
    }

    /// Layers TOML text (a scenario file's contents; `name` for messages).
    pub fn config_text(&mut self, text: &str, name: &str) -> Result<&mut Self, OptionsError> {
        let table: toml::Table = text
            .parse()
            .map_err(|e: toml::de::Error| OptionsError::Toml {
                path: name.to_string(),
                message: e.to_string(),
            })?;
        let patch = toml_to_json(toml::Value::Table(table));
        let mut paths = Vec::new();
        leaf_paths(&patch, "", &mut paths);
        merge_tree(&mut self.tree, patch, "")?;
        self.set.extend(paths);
        from_tree(self.tree.clone(), name)?;
        Ok(self)
    }

    /// Applies one `path=value`.
    pub fn set(&mut self, assignment: &str) -> Result<&mut Self, OptionsError> {
        let (path, value) = assignment
            .split_once('=')
            .ok_or_else(|| OptionsError::Syntax(assignment.to_string()))?;
        let path = path.trim();
        if path.is_empty() {
            return Err(OptionsError::Syntax(assignment.to_string()));
        }
        self.set_value(path, parse_value(value))
    }

    /// Sets `path` to an already parsed value: `--set` without the text, for callers
    /// whose values come typed (the Python bindings' keyword options).
    pub fn set_value(&mut self, path: &str, value: Value) -> Result<&mut Self, OptionsError> {
        set_path(&mut self.tree, path, value)?;
        from_tree(self.tree.clone(), path)?;
        self.set.push(path.to_string());
        Ok(self)
    }

    /// Whether `path` (or an option inside it) was set by a file or `--set`.
    pub fn was_set(&self, path: &str) -> bool {
        self.set
            .iter()
            .any(|p| p == path || p.starts_with(&format!("{path}.")))
    }

    /// The options.
    pub fn build(&self) -> Result<RunOptions, OptionsError> {
        from_tree(self.tree.clone(), "options")
    }
}

/// Dot paths of every leaf of a tree (tables recursed into).
fn leaf_paths(tree: &Value, prefix: &str, out: &mut Vec<String>) {
    if let Value::Object(map) = tree {
        for (k, v) in map {
            let path = if prefix.is_empty() {
                k.clone()
            } else {
                format!("{prefix}.{k}")
            };
            if v.is_object() {
                leaf_paths(v, &path, out);
            } else {
                out.push(path);
            }
        }
    }
}

/// Every option as `path = value` lines (for `--print-options` and reports).
pub fn option_lines(options: &RunOptions) -> Vec<String> {
    let tree = to_tree(options);
    let mut paths = Vec::new();
    leaf_paths(&tree, "", &mut paths);
    paths
        .into_iter()
        .map(|p| {
            let v = tree
                .pointer(&format!("/{}", p.replace('.', "/")))
                .cloned()
                .unwrap_or(Value::Null);
            format!("{p} = {v}")
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use surftrack::grid_tracker::ImproveScope;
    use surftrack::grid_tracker::stages::flaws::Resampling;

    #[test]
    fn defaults_round_trip_through_json_and_toml_shaped_values() {
        let o = RunOptions::default();
        let back: RunOptions = serde_json::from_value(to_tree(&o)).unwrap();
        assert_eq!(back.grid, o.grid);
        assert_eq!(back.flow, o.flow);
        assert_eq!(
            serde_json::to_string(&back.collision).unwrap(),
            serde_json::to_string(&o.collision).unwrap()
        );
    }

    #[test]
    fn set_and_config_override_nested_options_and_reject_unknown_paths() {
        let mut b = OptionsBuilder::default();
        b.set("grid.resampling=global").unwrap();
        b.set("grid.flaws.deep_cell_test=false").unwrap();
        b.set("collision.merge = false").unwrap();
        b.set("grid.improve.max_sweeps=3").unwrap();
        b.config_text(
            "[grid]\nimprove_scope = \"changed\"\n[flow]\nnormal_scheme = \"face_offsetting\"\n",
            "test.toml",
        )
        .unwrap();
        let o = b.build().unwrap();
        assert_eq!(o.grid.resampling, Resampling::Global);
        assert!(!o.grid.flaws.deep_cell_test);
        assert!(!o.collision.merge);
        assert_eq!(o.grid.improve.as_ref().unwrap().max_sweeps, 3);
        assert_eq!(o.grid.improve_scope, ImproveScope::Changed);
        assert_eq!(o.flow.normal_scheme, NormalScheme::FaceOffsetting);
        assert!(b.was_set("grid.flaws") && b.was_set("grid.improve_scope"));
        assert!(!b.was_set("grid.seed"));
        b.set("grid.improve=none").unwrap();
        assert!(b.build().unwrap().grid.improve.is_none());

        let err = OptionsBuilder::default()
            .set("grid.resampel=global")
            .unwrap_err();
        assert!(err.to_string().contains("resampling"), "{err}");
        let err = OptionsBuilder::default()
            .set("grid.resampling=sideways")
            .unwrap_err();
        assert!(matches!(err, OptionsError::Value { .. }), "{err}");
        assert!(OptionsBuilder::default().set("novalue").is_err());

        // Volume conservation by kind, by path or by one bool (the form of older records).
        use mesh_core::remesh::ConserveVolume;
        let conserve = |sets: &[&str], config: &str| {
            let mut b = OptionsBuilder::default();
            for s in sets {
                b.set(s)?;
            }
            b.config_text(config, "t")?;
            b.build().map(|o| o.collision.conserve_volume)
        };
        let default = RunOptions::default().collision.conserve_volume;
        assert!(default.flips && default.collapses && !default.smoothing);
        let with_smoothing = ConserveVolume {
            smoothing: true,
            ..default
        };
        assert_eq!(
            conserve(&["collision.conserve_volume.smoothing=true"], "").unwrap(),
            with_smoothing
        );
        assert_eq!(
            conserve(&[], "[collision.conserve_volume]\nsmoothing = true\n").unwrap(),
            with_smoothing
        );
        assert_eq!(
            conserve(&["collision.conserve_volume=true"], "").unwrap(),
            ConserveVolume::ALL
        );
        assert_eq!(
            conserve(&["collision.conserve_volume=false"], "").unwrap(),
            ConserveVolume::OFF
        );
        assert!(conserve(&["collision.conserve_volume={ flips = true }"], "").is_err());
        assert!(conserve(&["collision.conserve_volume.shifts=true"], "").is_err());
        assert!(
            OptionsBuilder::default()
                .config_text("[grid]\nnope = 1\n", "t")
                .is_err()
        );
    }
}
