//! Helpers shared by the integration tests that drive the built `surftrack` binary.
// Each test crate includes this module and uses only some of it.
#![allow(dead_code)]

use std::path::Path;
use std::process::{Command, Output};

use serde_json::Value;

/// Runs `surftrack args…` in `dir` (logs off) and returns its output.
pub fn surftrack(args: &[&str], dir: &Path) -> Output {
    surftrack_with_env(args, dir, &[])
}

/// As [`surftrack`], with extra environment variables (e.g. a fixed thread count for
/// bit-identical replays).
pub fn surftrack_with_env(args: &[&str], dir: &Path, env: &[(&str, &str)]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_surftrack"))
        .args(args)
        .current_dir(dir)
        .env_remove("RUST_LOG")
        .envs(env.iter().copied())
        .output()
        .expect("the surftrack binary runs")
}

/// A JSON file, parsed.
pub fn json(path: &Path) -> Value {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap()
}

/// Output bytes as text.
pub fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// Everything of a robustness record that does not depend on timing or memory.
pub fn without_times(record: &Value) -> Value {
    let mut r = record.clone();
    for run in r["runs"].as_array_mut().unwrap() {
        for key in [
            "wall_seconds",
            "step_seconds",
            "stage_seconds",
            "peak_rss_mib",
            "mib_per_million_triangles",
        ] {
            run[key] = Value::Null;
        }
        if let Some(f) = run.get_mut("failure").and_then(|f| f.as_object_mut()) {
            f.remove("message"); // names the run directory
        }
    }
    for s in r["summary"].as_array_mut().unwrap() {
        for key in [
            "mean_seconds",
            "median_seconds",
            "max_seconds",
            "mean_stage_seconds",
            "max_peak_rss_mib",
            "max_mib_per_million_triangles",
        ] {
            s[key] = Value::Null;
        }
    }
    r
}
