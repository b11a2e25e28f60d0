//! The same run gives the same mesh for any thread count and from run to run, on both
//! backends: the double bubble through its merge and first T1 (25 steps), with 1, 2
//! and 4 threads, twice each, must leave one `final_digest` per backend.
//!
//! Improvement by blocks is switched on from 64 vertices of work (default 1024), so
//! that every step of this small scene runs the parallel block passes whose commits
//! must come out in one order whatever the threads do.

mod common;

use std::collections::BTreeSet;

use common::{json, surftrack_with_env, text};

/// Thread counts tried; 4 is more than this machine's cores, which shuffles the order
/// in which rayon's tasks finish the most.
const THREADS: [&str; 3] = ["1", "2", "4"];

#[test]
fn both_backends_give_one_final_mesh_for_any_thread_count_and_run() {
    let dir = tempfile::tempdir().unwrap();
    for backend in surftrack::Backend::ALL {
        let name = backend.name();
        let blocks = format!("{name}.improve_blocks.min_work=64");
        let mut digests = BTreeSet::new();
        let mut events = BTreeSet::new();
        for threads in THREADS {
            for attempt in 0..2 {
                let out_dir = format!("{name}-{threads}-{attempt}");
                let args = [
                    "run",
                    "double-bubble",
                    "--tracker",
                    name,
                    "--steps",
                    "25",
                    "--set",
                    &blocks,
                    "--out",
                    &out_dir,
                ];
                let out = surftrack_with_env(&args, dir.path(), &[("RAYON_NUM_THREADS", threads)]);
                if out.status.code() == Some(3) {
                    println!("{name}: unavailable, skipped");
                    break;
                }
                assert!(
                    out.status.success(),
                    "{name}, {threads} threads: {}",
                    text(&out.stderr)
                );
                let record = json(&dir.path().join(&out_dir).join("run.json"));
                assert_eq!(record["success"], true, "{name}: {}", record["failure"]);
                assert!(
                    record["events"]["merges"].as_u64().unwrap() >= 1,
                    "{name}: the scene must change topology to test anything: {}",
                    record["events"]
                );
                let last = record["per_step"].as_array().unwrap().last().unwrap();
                assert!(
                    last["triangles"].as_u64().unwrap() > 1000,
                    "{name}: an empty final mesh would make equal digests meaningless"
                );
                digests.insert(record["final_digest"].as_str().unwrap().to_string());
                events.insert(record["events"].to_string());
            }
        }
        println!("{name}: digests {digests:?}, events {events:?}");
        assert!(
            digests.len() <= 1,
            "{name}: final meshes differ between thread counts or runs: {digests:?}"
        );
        assert!(events.len() <= 1, "{name}: event counts differ: {events:?}");
    }
}
