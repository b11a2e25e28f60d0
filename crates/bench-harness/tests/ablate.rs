//! Research ablations end to end: options as data (`--set`, `--config`, the record),
//! replays from a record, and every `bench ablate` preset on a small scene.
//!
//! Sizes are the smallest that still exercise each stage (icosphere subdivision 2, two
//! spheres, a few steps), so the whole file stays well under a minute in the test profile.

mod common;

use std::path::Path;
use std::process::Output;

use serde_json::Value;

use common::{json, text};

/// Bit-identical replays need the same thread count.
fn surftrack(args: &[&str], dir: &Path) -> Output {
    common::surftrack_with_env(args, dir, &[("RAYON_NUM_THREADS", "2")])
}

#[test]
fn options_reach_the_record_and_bad_paths_are_usage_errors() {
    let dir = tempfile::tempdir().unwrap();
    let scenario = dir.path().join("scenario.toml");
    std::fs::write(
        &scenario,
        "[grid]\nresampling = \"global\"\n[grid.rebuild]\ncurve_smoothing_steps = 3\n",
    )
    .unwrap();
    let out = surftrack(
        &[
            "run",
            "rolling",
            "--resolution",
            "2",
            "--steps",
            "2",
            "--every",
            "0",
            "--out",
            "r",
            "--quiet",
            "--config",
            "scenario.toml",
            "--set",
            "grid.flaws.deep_cell_test=false",
        ],
        dir.path(),
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    let record = json(&dir.path().join("r/run.json"));
    let grid = &record["options"]["grid"];
    assert_eq!(grid["resampling"], "global");
    assert_eq!(grid["rebuild"]["curve_smoothing_steps"], 3);
    assert_eq!(grid["flaws"]["deep_cell_test"], false);
    // The run's seed drives the grid shifts unless set explicitly.
    assert_eq!(grid["seed"], 1);
    assert_eq!(record["scene_params"]["resolution"], 2);
    assert!(record["final_digest"].is_string());
    // Global resampling rebuilt everything: nothing of the original is left.
    assert_eq!(record["preservation"]["untouched_triangles"], 0);

    let out = surftrack(
        &["run", "rolling", "--set", "grid.resampel=global"],
        dir.path(),
    );
    assert_eq!(out.status.code(), Some(2));
    assert!(
        text(&out.stderr).contains("resampling"),
        "{}",
        text(&out.stderr)
    );
    let out = surftrack(
        &["run", "rolling", "--set", "grid.resampling=sideways"],
        dir.path(),
    );
    assert_eq!(out.status.code(), Some(2));

    let out = surftrack(&["run", "spheres", "--print-options"], dir.path());
    assert!(out.status.success());
    let listing = text(&out.stdout);
    for path in [
        "grid.resampling = \"local\"",
        "grid.flaws.deep_cell_test = true",
        "grid.label_correction = \"fast_marching\"",
        "collision.merge = true",
        "collision.impact_zones = true",
        "flow.normal_scheme = \"vertex_normals\"",
    ] {
        assert!(listing.contains(path), "{path} missing from:\n{listing}");
    }
}

#[test]
fn a_record_replays_to_the_same_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let first = surftrack(
        &[
            "run",
            "rolling",
            "--resolution",
            "2",
            "--steps",
            "6",
            "--every",
            "6",
            "--out",
            "a",
            "--quiet",
            "--seed",
            "5",
            "--set",
            "grid.improve_scope=changed",
        ],
        dir.path(),
    );
    assert!(first.status.success(), "{}", text(&first.stderr));
    let replay = surftrack(
        &[
            "run",
            "--from-record",
            "a/run.json",
            "--every",
            "6",
            "--out",
            "b",
            "--quiet",
        ],
        dir.path(),
    );
    assert!(replay.status.success(), "{}", text(&replay.stderr));
    let (a, b) = (
        json(&dir.path().join("a/run.json")),
        json(&dir.path().join("b/run.json")),
    );
    for key in [
        "scene",
        "tracker",
        "seed",
        "steps",
        "dt",
        "options",
        "scene_params",
        "final_digest",
    ] {
        assert_eq!(a[key], b[key], "{key}");
    }
    assert_eq!(a["steps_completed"], 6);
    let fa = std::fs::read(dir.path().join("a/frame_0006.ply")).unwrap();
    let fb = std::fs::read(dir.path().join("b/frame_0006.ply")).unwrap();
    assert!(fa == fb, "the replayed final frame differs");
    // A different grid seed is a different run (the digest sees it).
    let other = surftrack(
        &[
            "run",
            "--from-record",
            "a/run.json",
            "--every",
            "0",
            "--out",
            "c",
            "--quiet",
            "--set",
            "grid.seed=99",
        ],
        dir.path(),
    );
    assert!(other.status.success(), "{}", text(&other.stderr));
    let c = json(&dir.path().join("c/run.json"));
    assert_eq!(c["options"]["grid"]["seed"], 99);
}

/// Runs one ablation and returns its record, checking that every variant ran every seed
/// to a record (no crash, no time-out) and that the table names every variant.
fn ablate(dir: &Path, args: &[&str]) -> Value {
    let out_dir = format!("ab-{}", args.join("-").replace(['/', '=', ','], "_"));
    let mut full = vec!["bench", "ablate"];
    full.extend_from_slice(args);
    full.extend_from_slice(&[
        "--seeds",
        "1",
        "--timeout",
        "60",
        "--jobs",
        "2",
        "--quiet",
        "--out",
    ]);
    full.push(&out_dir);
    let out = surftrack(&full, dir);
    assert!(out.status.success(), "{args:?}: {}", text(&out.stderr));
    let record = json(&dir.join(&out_dir).join("ablate.json"));
    let table = text(&out.stdout);
    for v in record["variants"].as_array().unwrap() {
        assert_eq!(v["runs"], 1, "{args:?}");
        let name = v["variant"]["name"].as_str().unwrap();
        assert!(table.contains(name), "{name} not in\n{table}");
    }
    for r in record["runs"].as_array().unwrap() {
        let reason = r["run"]["failure"]["reason"].as_str().unwrap_or("ok");
        assert!(
            !["crash", "timeout", "panic"].contains(&reason),
            "{args:?}: {r}"
        );
        assert!(
            dir.join(&out_dir)
                .join(r["dir"].as_str().unwrap())
                .join("run.json")
                .exists()
        );
    }
    for plot in [
        "success_rate.svg",
        "untouched_fraction.svg",
        "seconds_per_step.svg",
    ] {
        assert!(dir.join(&out_dir).join(plot).exists());
    }
    record
}

fn variant<'a>(record: &'a Value, name: &str) -> &'a Value {
    record["variants"]
        .as_array()
        .unwrap()
        .iter()
        .find(|v| v["variant"]["name"] == name)
        .unwrap_or_else(|| panic!("no variant {name}"))
}

#[test]
fn grid_presets_run_and_local_resampling_keeps_the_surface() {
    let dir = tempfile::tempdir().unwrap();
    let small = ["--resolution", "2", "--steps", "4"];
    let mut args = vec!["rolling", "--preset", "resampling"];
    args.extend_from_slice(&small);
    let record = ablate(dir.path(), &args);
    let local = variant(&record, "local");
    let global = variant(&record, "global");
    assert_eq!(local["success_rate"], 1.0);
    let (l, g) = (
        local["untouched_fraction"].as_f64().unwrap(),
        global["untouched_fraction"].as_f64().unwrap_or(0.0),
    );
    assert!(l > 0.5 && g < 0.05, "local {l}, global {g}");
    for preset in ["deep-cells", "curve-smoothing", "label-correction"] {
        let mut args = vec!["rolling", "--preset", preset];
        args.extend_from_slice(&small);
        let record = ablate(dir.path(), &args);
        assert_eq!(record["variants"].as_array().unwrap().len(), 2, "{preset}");
    }
}

#[test]
fn collision_and_flow_presets_run_on_two_spheres() {
    let dir = tempfile::tempdir().unwrap();
    let small = ["--count", "2", "--resolution", "1", "--steps", "3"];
    for preset in [
        "merging",
        "t1",
        "impact-zones",
        "collision-safety",
        "normal-flow",
        "remeshing",
    ] {
        let mut args = vec!["spheres", "--preset", preset];
        args.extend_from_slice(&small);
        let record = ablate(dir.path(), &args);
        let n = record["variants"].as_array().unwrap().len();
        let both = ["normal-flow", "remeshing"].contains(&preset);
        assert_eq!(n, if both { 4 } else { 2 }, "{preset}");
    }
    // Face offsetting moves the vertices differently from vertex normals.
    let record = ablate(
        dir.path(),
        &[
            "spheres",
            "--preset",
            "normal-flow",
            "--tracker",
            "grid",
            "--count",
            "2",
            "--resolution",
            "1",
            "--steps",
            "2",
        ],
    );
    let a = variant(&record, "vertex-normals");
    let b = variant(&record, "face-offsetting");
    assert!(a["success_rate"] == 1.0 && b["success_rate"] == 1.0);
    assert_ne!(
        a["volume_drift"], b["volume_drift"],
        "the scheme had no effect"
    );
    // --vary crosses with the preset.
    let record = ablate(
        dir.path(),
        &[
            "spheres",
            "--preset",
            "t1",
            "--vary",
            "collision.merge=true,false",
            "--count",
            "2",
            "--resolution",
            "1",
            "--steps",
            "2",
        ],
    );
    assert_eq!(record["variants"].as_array().unwrap().len(), 4);
}
