//! The `surftrack` binary end to end: exit codes, records on disk, the robustness
//! driver's handling of children that fail, hang or panic, and shard merging.
//!
//! Children misbehave through the hidden `--simulate` hook, so these tests are cheap and
//! do not depend on which backends exist; the one test that runs a tracker accepts
//! "unavailable" (exit 3) for a backend this build lacks.

mod common;

use std::time::{Duration, Instant};

use serde_json::Value;

use common::{json, surftrack, text, without_times};

/// Reasons of every run in a robustness record, in record order.
fn reasons(record: &Value) -> Vec<(String, u64, String)> {
    record["runs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| {
            let reason = r["failure"]["reason"].as_str().unwrap_or("ok").to_string();
            (
                r["tracker"].as_str().unwrap().to_string(),
                r["seed"].as_u64().unwrap(),
                reason,
            )
        })
        .collect()
}

#[test]
fn scenes_lists_every_scene_on_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let out = surftrack(&["scenes"], dir.path());
    assert!(out.status.success());
    let listing = text(&out.stdout);
    for scene in bench_harness::scenes::SCENES {
        let lines: Vec<_> = listing
            .lines()
            .filter(|l| l.starts_with(scene.name))
            .collect();
        assert!(!lines.is_empty(), "{} missing from:\n{listing}", scene.name);
    }
    assert_eq!(listing.lines().count(), bench_harness::scenes::SCENES.len());
}

#[test]
fn run_writes_a_record_and_valid_frames_or_reports_the_backend_unavailable() {
    let dir = tempfile::tempdir().unwrap();
    for backend in surftrack::Backend::ALL {
        let out_dir = format!("db-{backend}");
        let out = surftrack(
            &[
                "run",
                "double-bubble",
                "--tracker",
                backend.name(),
                "--steps",
                "2",
                "--resolution",
                "2",
                "--out",
                &out_dir,
            ],
            dir.path(),
        );
        let record = json(&dir.path().join(&out_dir).join("run.json"));
        assert_eq!(record["schema"], "surftrack.run/1");
        assert_eq!(record["tracker"], backend.name());
        match out.status.code() {
            Some(3) => {
                assert_eq!(record["failure"]["reason"], "unavailable");
                assert_eq!(record["success"], false);
                println!("{backend}: unavailable, skipped");
            }
            Some(0) => {
                assert_eq!(record["success"], true);
                assert_eq!(record["steps_completed"], 2);
                let frames = record["frames"].as_array().unwrap();
                assert_eq!(frames.len(), 3, "initial + 2 steps");
                for frame in frames {
                    let path = dir
                        .path()
                        .join(&out_dir)
                        .join(frame["file"].as_str().unwrap());
                    // Checked by a separate process, as a user would.
                    let check = surftrack(&["validate", path.to_str().unwrap()], dir.path());
                    assert!(
                        check.status.success(),
                        "{}: {}",
                        path.display(),
                        text(&check.stdout)
                    );
                }
                assert!(text(&out.stdout).contains("record:"));
            }
            other => panic!(
                "{backend}: exit {other:?}, failure {}\nstderr: {}",
                record["failure"],
                text(&out.stderr)
            ),
        }
    }
}

#[test]
fn usage_errors_exit_with_2() {
    let dir = tempfile::tempdir().unwrap();
    let unknown = surftrack(&["run", "no-such-scene"], dir.path());
    assert_eq!(unknown.status.code(), Some(2));
    assert!(text(&unknown.stderr).contains("unknown scene"));
    let bad_shard = surftrack(&["bench", "robustness", "--shard", "2/2"], dir.path());
    assert_eq!(bad_shard.status.code(), Some(2));
    let bad_compare = surftrack(&["bench", "compare", "sphere"], dir.path());
    assert_eq!(bad_compare.status.code(), Some(2));
}

#[test]
fn the_watchdog_kills_hanging_children_and_records_a_timeout() {
    let dir = tempfile::tempdir().unwrap();
    let start = Instant::now();
    let out = surftrack(
        &[
            "bench",
            "robustness",
            "--spheres",
            "2",
            "--seeds",
            "2",
            "--steps",
            "1",
            "--tracker",
            "grid",
            "--timeout",
            "0.4",
            "--jobs",
            "2",
            "--simulate",
            "hang",
            "--out",
            "rb",
            "--json",
        ],
        dir.path(),
    );
    let elapsed = start.elapsed();
    assert!(out.status.success(), "{}", text(&out.stderr));
    // Two children in parallel, each killed at 0.4 s (the hang would last 10 minutes).
    assert!(elapsed < Duration::from_secs(20), "took {elapsed:?}");
    let record = json(&dir.path().join("rb/robustness.json"));
    assert_eq!(
        reasons(&record),
        vec![
            ("grid".into(), 1, "timeout".into()),
            ("grid".into(), 2, "timeout".into())
        ]
    );
    // --json prints the per-backend summary with the documented fields.
    let printed: Value = serde_json::from_slice(&out.stdout).unwrap();
    let grid = &printed["summary"][0];
    for field in [
        "runs",
        "successes",
        "success_rate",
        "mean_seconds",
        "median_seconds",
        "max_seconds",
    ] {
        assert!(grid.get(field).is_some(), "{field} missing from {grid}");
    }
    assert_eq!(grid["runs"], 2);
    assert_eq!(grid["successes"], 0);
    assert_eq!(grid["failures"]["timeout"], 2);
}

#[test]
fn children_that_panic_are_recorded_and_the_report_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let out = surftrack(
        &[
            "bench",
            "robustness",
            "--spheres",
            "2",
            "--seeds",
            "2",
            "--steps",
            "1",
            "--simulate",
            "panic",
            "--out",
            "rb",
        ],
        dir.path(),
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    let record = json(&dir.path().join("rb/robustness.json"));
    let all = reasons(&record);
    assert_eq!(all.len(), 2 * surftrack::Backend::ALL.len());
    assert!(all.iter().all(|r| r.2 == "panic"), "{all:?}");
    let stdout = text(&out.stdout);
    assert!(
        stdout.contains("| tracker | runs | successes | success rate |"),
        "{stdout}"
    );
    for file in [
        "report.md",
        "time_per_step.svg",
        "triangles_per_step.svg",
        "success_rate.svg",
    ] {
        assert!(dir.path().join("rb").join(file).is_file(), "{file} missing");
    }
    // Each child left its log, with the panic message in it.
    let log = std::fs::read_to_string(dir.path().join("rb/runs/grid-seed-0001/child.log")).unwrap();
    assert!(log.contains("simulated panic"), "{log}");
}

#[test]
fn sharded_runs_merged_equal_the_unsharded_run() {
    let dir = tempfile::tempdir().unwrap();
    // Panicking children are deterministic and cheap whatever backends this build has.
    let common = [
        "bench",
        "robustness",
        "--spheres",
        "2",
        "--seeds",
        "5",
        "--first-seed",
        "3",
        "--steps",
        "1",
        "--simulate",
        "panic",
        "--jobs",
        "2",
        "--quiet",
    ];
    let run = |extra: &[&str]| {
        let args: Vec<&str> = common.iter().chain(extra).copied().collect();
        let out = surftrack(&args, dir.path());
        assert!(out.status.success(), "{}", text(&out.stderr));
    };
    run(&["--out", "whole"]);
    run(&["--shard", "0/2", "--out", "s0"]);
    run(&["--shard", "1/2", "--out", "s1"]);
    let merged = surftrack(
        &[
            "bench",
            "merge",
            "s1",
            "s0/robustness.json",
            "--out",
            "merged",
        ],
        dir.path(),
    );
    assert!(merged.status.success(), "{}", text(&merged.stderr));
    let whole = json(&dir.path().join("whole/robustness.json"));
    let shard0 = json(&dir.path().join("s0/robustness.json"));
    assert_eq!(shard0["config"]["shard"], serde_json::json!([0, 2]));
    assert_eq!(
        shard0["runs"].as_array().unwrap().len(),
        3 * surftrack::Backend::ALL.len()
    );
    let merged = json(&dir.path().join("merged/robustness.json"));
    assert_eq!(without_times(&merged), without_times(&whole));
    // Merging a shard with itself is refused.
    let twice = surftrack(&["bench", "merge", "s0", "s0"], dir.path());
    assert_eq!(twice.status.code(), Some(2));
    assert!(text(&twice.stderr).contains("more than one record"));
}

#[test]
fn help_teaches_with_examples() {
    let dir = tempfile::tempdir().unwrap();
    for args in [
        vec!["--help"],
        vec!["run", "--help"],
        vec!["bench", "robustness", "--help"],
        vec!["bench", "merge", "--help"],
        vec!["bench", "compare", "--help"],
    ] {
        let out = surftrack(&args, dir.path());
        assert!(out.status.success());
        let help = text(&out.stdout);
        assert!(help.contains("Example"), "{args:?}:\n{help}");
        assert!(help.contains("surftrack "), "{args:?}");
    }
}

/// `run --mesh FILE --flow NAME:…` moves the user's own mesh with a built-in flow through
/// either backend: a labelled PLY (a double bubble) under per-pair normal flow, and an
/// unlabelled OBJ (a plain closed sphere, read as inside 1) under the Enright field. Each
/// run's record names the flow, and its frames pass `validate` in a separate process.
#[test]
fn run_moves_a_user_mesh_with_a_named_flow_on_both_backends() {
    use mesh_core::generators::{double_bubble, icosphere};
    use mesh_core::{DVec3, Label};
    let dir = tempfile::tempdir().unwrap();
    let labelled = dir.path().join("bubbles.ply");
    mesh_core::io::write_mesh(&double_bubble(0.3, 6).unwrap(), &labelled).unwrap();
    // An OBJ without usemtl groups: no labels at all.
    let sphere = icosphere(2, DVec3::splat(0.35), 0.15, [Label::OUTSIDE, Label::new(1)]).unwrap();
    let (positions, tris, _) = sphere.to_raw();
    let mut obj = String::new();
    for p in &positions {
        obj.push_str(&format!("v {} {} {}\n", p.x, p.y, p.z));
    }
    for t in &tris {
        obj.push_str(&format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1));
    }
    let unlabelled = dir.path().join("sphere.obj");
    std::fs::write(&unlabelled, obj).unwrap();

    for backend in surftrack::Backend::ALL {
        for (mesh, flow) in [
            (&labelled, "normal:speed=0.2,1-2=0.1"),
            (&unlabelled, "enright:period=2"),
        ] {
            let out_dir = format!("user-{backend}-{}", flow.split(':').next().unwrap());
            let out = surftrack(
                &[
                    "run",
                    "--mesh",
                    mesh.to_str().unwrap(),
                    "--flow",
                    flow,
                    "--tracker",
                    backend.name(),
                    "--steps",
                    "3",
                    "--out",
                    &out_dir,
                ],
                dir.path(),
            );
            if out.status.code() == Some(3) {
                println!("{backend}: unavailable, skipped");
                continue;
            }
            let record = json(&dir.path().join(&out_dir).join("run.json"));
            assert_eq!(
                out.status.code(),
                Some(0),
                "{backend} {flow}: {}\n{}",
                record["failure"],
                text(&out.stderr)
            );
            assert_eq!(record["scene"], format!("mesh:{flow}"));
            assert_eq!(record["steps_completed"], 3);
            assert_eq!(record["scene_params"]["mesh"], mesh.to_str().unwrap());
            let frames = record["frames"].as_array().unwrap();
            assert_eq!(frames.len(), 4, "initial + 3 steps");
            let first = dir
                .path()
                .join(&out_dir)
                .join(frames[0]["file"].as_str().unwrap());
            let last = dir
                .path()
                .join(&out_dir)
                .join(frames[3]["file"].as_str().unwrap());
            for path in [&first, &last] {
                let check = surftrack(&["validate", path.to_str().unwrap()], dir.path());
                assert!(
                    check.status.success(),
                    "{}: {}",
                    path.display(),
                    text(&check.stdout)
                );
            }
            // The flow moved the mesh.
            let a = mesh_core::io::read_mesh(&first).unwrap();
            let b = mesh_core::io::read_mesh(&last).unwrap();
            assert_ne!(
                a.positions(),
                b.positions(),
                "{backend} {flow} did not move"
            );
            assert!(dir.path().join(&out_dir).join("time_per_step.svg").exists());
        }
    }

    // Unknown flows and keys are usage errors naming what exists; --flow needs --mesh.
    let bad = surftrack(
        &[
            "run",
            "--mesh",
            labelled.to_str().unwrap(),
            "--flow",
            "swirl",
            "--out",
            "bad",
        ],
        dir.path(),
    );
    assert_eq!(bad.status.code(), Some(2));
    assert!(
        text(&bad.stderr).contains("known flows: normal, enright"),
        "{}",
        text(&bad.stderr)
    );
    let bad = surftrack(
        &[
            "run",
            "--mesh",
            labelled.to_str().unwrap(),
            "--flow",
            "enright:speed=1",
            "--out",
            "bad",
        ],
        dir.path(),
    );
    assert!(
        text(&bad.stderr).contains("known keys: period"),
        "{}",
        text(&bad.stderr)
    );
    let bad = surftrack(&["run", "--flow", "enright", "--out", "bad"], dir.path());
    assert_eq!(bad.status.code(), Some(2));
    assert!(
        text(&bad.stderr).contains("--mesh"),
        "{}",
        text(&bad.stderr)
    );
}
