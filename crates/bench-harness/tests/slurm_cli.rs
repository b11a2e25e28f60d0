//! `bench robustness --slurm DIR`: the scripts it writes, checked by running them the way
//! Slurm would — each array task with its `SLURM_ARRAY_TASK_ID`, then the merge — without
//! a scheduler (`scripts/slurm/check.sh` runs them on a real single-node Slurm).

mod common;

use std::path::Path;
use std::process::Command;

use common::{json, surftrack, text, without_times};

/// Runs `bash script` with `SLURM_ARRAY_TASK_ID` set (or not), from another directory
/// than the one the scripts were written from (the paths inside must be absolute).
fn bash(script: &Path, task: Option<usize>) -> std::process::Output {
    let mut cmd = Command::new("bash");
    cmd.arg(script).current_dir(std::env::temp_dir());
    cmd.env_remove("SLURM_ARRAY_TASK_ID");
    if let Some(t) = task {
        cmd.env("SLURM_ARRAY_TASK_ID", t.to_string());
    }
    cmd.output().expect("bash runs")
}

#[test]
fn slurm_scripts_run_as_a_job_array_merge_to_the_unsharded_table() {
    let dir = tempfile::tempdir().unwrap();
    // Panicking children are cheap and deterministic whatever backends this build has.
    let sweep = [
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
        "--no-pictures",
        "--quiet",
    ];
    let with = |extra: &[&str]| -> Vec<String> {
        sweep.iter().chain(extra).map(|s| s.to_string()).collect()
    };
    let run = |args: Vec<String>| {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let out = surftrack(&args, dir.path());
        assert!(out.status.success(), "{}", text(&out.stderr));
        out
    };
    run(with(&["--out", "whole"]));
    run(with(&[
        "--slurm",
        "jobs",
        "--slurm-shards",
        "3",
        "--out",
        "sharded",
    ]));
    let jobs = dir.path().join("jobs");
    let array_script = jobs.join("robustness-array.sbatch");
    let array = std::fs::read_to_string(&array_script).unwrap();
    let merge = std::fs::read_to_string(jobs.join("robustness-merge.sbatch")).unwrap();
    let submit = std::fs::read_to_string(jobs.join("submit.sh")).unwrap();
    assert!(array.contains("#SBATCH --array=0-2\n"), "{array}");
    let sharded = dir.path().canonicalize().unwrap().join("sharded");
    let logs = jobs.canonicalize().unwrap().join("logs");
    assert!(logs.is_dir());
    assert!(array.contains(&format!("#SBATCH --output={}/shard-%a.log", logs.display())));
    assert!(array.contains(&format!("--out {}\"/shard-$task\"", sharded.display())));
    assert!(array.contains(&format!(
        "exec {} bench robustness",
        std::path::absolute(env!("CARGO_BIN_EXE_surftrack"))
            .unwrap()
            .display()
    )));
    assert!(merge.contains(&format!(
        "bench merge {0}/shard-0 {0}/shard-1 {0}/shard-2 --out {0}\n",
        sharded.display()
    )));
    assert!(
        submit.contains("--dependency=afterany:\"$array\""),
        "{submit}"
    );
    // Outside a job array the task script refuses to guess its shard.
    let bare = bash(&array_script, None);
    assert!(!bare.status.success());
    assert!(text(&bare.stderr).contains("SLURM_ARRAY_TASK_ID"));
    // The tasks in any order, then the merge: the unsharded table.
    for task in [2, 0, 1] {
        let out = bash(&array_script, Some(task));
        assert!(out.status.success(), "task {task}: {}", text(&out.stderr));
        let shard = json(&sharded.join(format!("shard-{task}/robustness.json")));
        assert_eq!(shard["config"]["shard"], serde_json::json!([task, 3]));
    }
    let merged = bash(&jobs.join("robustness-merge.sbatch"), None);
    assert!(merged.status.success(), "{}", text(&merged.stderr));
    let whole = json(&dir.path().join("whole/robustness.json"));
    let merged = json(&sharded.join("robustness.json"));
    assert_eq!(without_times(&merged), without_times(&whole));
}

#[test]
fn slurm_options_are_checked() {
    let dir = tempfile::tempdir().unwrap();
    let more_shards_than_seeds = surftrack(
        &[
            "bench",
            "robustness",
            "--seeds",
            "2",
            "--slurm",
            "j",
            "--slurm-shards",
            "3",
        ],
        dir.path(),
    );
    assert_eq!(more_shards_than_seeds.status.code(), Some(2));
    assert!(text(&more_shards_than_seeds.stderr).contains("3 shards for 2 seeds"));
    let with_shard = surftrack(
        &["bench", "robustness", "--slurm", "j", "--shard", "0/2"],
        dir.path(),
    );
    assert_eq!(with_shard.status.code(), Some(2));
    let shards_alone = surftrack(&["bench", "robustness", "--slurm-shards", "2"], dir.path());
    assert_eq!(shards_alone.status.code(), Some(2));
    assert!(
        !dir.path().join("j").exists(),
        "nothing written on a usage error"
    );
}
