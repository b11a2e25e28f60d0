//! Slurm job arrays for the robustness benchmark: `surftrack bench robustness …
//! --slurm DIR` writes, instead of running, the scripts that spread the sweep over a
//! cluster.
//!
//! The 2024 paper's tables (100 spheres × 100 seeds, 1000 spheres × 50 seeds) need many
//! machines. Seeds are already dealt round-robin to shards (`--shard I/N`, see
//! [`crate::bench::shard_seeds`]) and shard records are joined by `bench merge`
//! ([`crate::record::merge_records`]); this module only writes the scheduler's side:
//!
//! | file | what |
//! |---|---|
//! | `robustness-array.sbatch` | a job array `0..N-1`; task `I` runs shard `I/N` into `OUT/shard-I/` |
//! | `robustness-merge.sbatch` | `bench merge OUT/shard-0 … OUT/shard-(N-1) --out OUT` |
//! | `submit.sh` | submits the array, then the merge with `--dependency=afterany:<array>` |
//! | `logs/` | one log per array task and one for the merge |
//!
//! The merge depends on the array with `afterany`, not `afterok`: a task that Slurm kills
//! (time limit, node failure) must still lead to a merge job whose log says which shard
//! is missing, rather than to a merge that waits forever on a dependency that can never
//! be met. Every path in the scripts is absolute, so they run from any working directory
//! on any node that shares the file system.
//!
//! The generated scripts are plain `bash` and can be run without Slurm, one task at a time
//! (`SLURM_ARRAY_TASK_ID=0 bash robustness-array.sbatch`), which is how the tests check
//! them; `scripts/slurm/check.sh` runs them on a real single-node Slurm.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Name of the job-array script in the Slurm directory.
pub const ARRAY_SCRIPT: &str = "robustness-array.sbatch";
/// Name of the merge script in the Slurm directory.
pub const MERGE_SCRIPT: &str = "robustness-merge.sbatch";
/// Name of the submitting script in the Slurm directory.
pub const SUBMIT_SCRIPT: &str = "submit.sh";
/// Sub-directory of the Slurm directory for the jobs' logs.
pub const LOG_DIR: &str = "logs";

/// Minutes added to every task's time limit on top of its runs' time-outs: start-up,
/// the report's pictures, a loaded file system.
const SLACK_MINUTES: u64 = 10;
/// Time limit of the merge job, minutes (it reads JSON and writes a table).
const MERGE_MINUTES: u64 = 15;
/// Memory asked for on top of the children's caps (the parent, the report), MiB.
const PARENT_MIB: u64 = 1024;

/// Everything the scripts depend on.
#[derive(Clone, Debug)]
pub struct SlurmPlan {
    /// The `surftrack` executable the tasks run (absolute).
    pub exe: PathBuf,
    /// Where the scripts and logs go (absolute).
    pub dir: PathBuf,
    /// The benchmark's output: shards in `out/shard-I/`, the merged table in `out/`
    /// (absolute).
    pub out: PathBuf,
    /// Array tasks = shards.
    pub shards: usize,
    /// The `bench robustness` arguments every task shares (no `--shard`, `--out`,
    /// `--slurm`).
    pub bench_args: Vec<String>,
    /// Seeds of the whole sweep.
    pub seeds: usize,
    /// Backends each seed runs with.
    pub trackers: usize,
    /// Children a task runs at once (`--jobs`): its CPUs.
    pub jobs: usize,
    /// Time limit of one run, seconds.
    pub run_timeout_seconds: f64,
    /// Resident-memory cap of one child, MiB (0: none, then no `--mem` is asked for).
    pub child_memory_mib: u64,
    /// `--job-name` of the array (the merge job appends `-merge`).
    pub job_name: String,
}

/// Why no scripts can be written.
#[derive(Debug, thiserror::Error)]
pub enum SlurmError {
    /// More shards than seeds leaves some tasks nothing to do.
    #[error("{shards} shards for {seeds} seeds: every array task needs at least one seed")]
    TooManyShards {
        /// Shards asked for.
        shards: usize,
        /// Seeds of the sweep.
        seeds: usize,
    },
    /// Zero shards.
    #[error("--slurm-shards must be at least 1")]
    NoShards,
    /// A path that a shell script cannot carry (not UTF-8).
    #[error("path {0} is not valid UTF-8 and cannot be written into a shell script")]
    Path(PathBuf),
    /// Writing a file.
    #[error("writing {path}: {source}")]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// What went wrong.
        source: std::io::Error,
    },
}

/// The three scripts, as text.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SlurmScripts {
    /// `robustness-array.sbatch`.
    pub array: String,
    /// `robustness-merge.sbatch`.
    pub merge: String,
    /// `submit.sh`.
    pub submit: String,
}

/// Quotes a word for `bash`: bare when it is made of safe characters, else in single
/// quotes with every `'` written as `'\''`.
pub fn shell_quote(word: &str) -> String {
    let safe = !word.is_empty()
        && word
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_./=,:+@%".contains(c));
    if safe {
        word.to_string()
    } else {
        format!("'{}'", word.replace('\'', r"'\''"))
    }
}

fn utf8(path: &Path) -> Result<&str, SlurmError> {
    path.to_str()
        .ok_or_else(|| SlurmError::Path(path.to_path_buf()))
}

/// The number of seeds of the largest of `shards` round-robin shards of `seeds` seeds.
pub fn largest_shard(seeds: usize, shards: usize) -> usize {
    seeds.div_ceil(shards.max(1))
}

/// Task time limit in minutes: the shard's runs, `jobs` at a time, each up to its
/// time-out, plus slack.
fn task_minutes(plan: &SlurmPlan) -> u64 {
    let runs = largest_shard(plan.seeds, plan.shards) * plan.trackers.max(1);
    let rounds = runs.div_ceil(plan.jobs.max(1)) as f64;
    (rounds * plan.run_timeout_seconds / 60.0).ceil() as u64 + SLACK_MINUTES
}

/// Writes the `#SBATCH` header common to both jobs.
fn header(s: &mut String, name: &str, minutes: u64, log: &str) {
    let _ = writeln!(s, "#!/bin/bash");
    let _ = writeln!(s, "#SBATCH --job-name={}", shell_quote(name));
    let _ = writeln!(s, "#SBATCH --time={minutes}");
    let _ = writeln!(s, "#SBATCH --output={}", shell_quote(log));
}

/// The scripts of a plan (pure: nothing is written).
pub fn slurm_scripts(plan: &SlurmPlan) -> Result<SlurmScripts, SlurmError> {
    if plan.shards == 0 {
        return Err(SlurmError::NoShards);
    }
    if plan.shards > plan.seeds {
        return Err(SlurmError::TooManyShards {
            shards: plan.shards,
            seeds: plan.seeds,
        });
    }
    let exe = shell_quote(utf8(&plan.exe)?);
    let out = utf8(&plan.out)?;
    let logs = plan.dir.join(LOG_DIR);
    let logs = utf8(&logs)?;
    let n = plan.shards;
    let shared: Vec<String> = plan.bench_args.iter().map(|a| shell_quote(a)).collect();

    let mut array = String::new();
    header(
        &mut array,
        &plan.job_name,
        task_minutes(plan),
        &format!("{logs}/shard-%a.log"),
    );
    let _ = writeln!(array, "#SBATCH --array=0-{}", n - 1);
    let _ = writeln!(array, "#SBATCH --ntasks=1");
    let _ = writeln!(array, "#SBATCH --cpus-per-task={}", plan.jobs.max(1));
    if plan.child_memory_mib > 0 {
        let mib = plan.child_memory_mib * plan.jobs.max(1) as u64 + PARENT_MIB;
        let _ = writeln!(array, "#SBATCH --mem={mib}M");
    }
    let _ = writeln!(
        array,
        "# Written by `surftrack bench robustness --slurm`: array task I runs shard I/{n} of\n\
         # the sweep into {out}/shard-I/; {MERGE_SCRIPT} joins them."
    );
    let _ = writeln!(array, "set -euo pipefail");
    let _ = writeln!(
        array,
        ": \"${{SLURM_ARRAY_TASK_ID:?not set: submit this as a job array (sbatch), or set it by hand}}\""
    );
    let _ = writeln!(array, "task=$SLURM_ARRAY_TASK_ID");
    let _ = writeln!(
        array,
        "exec {exe} bench robustness {} --shard \"$task/{n}\" --out {}\"/shard-$task\" --quiet",
        shared.join(" "),
        shell_quote(out)
    );

    let mut merge = String::new();
    header(
        &mut merge,
        &format!("{}-merge", plan.job_name),
        MERGE_MINUTES,
        &format!("{logs}/merge-%j.log"),
    );
    let _ = writeln!(merge, "#SBATCH --ntasks=1");
    let _ = writeln!(merge, "#SBATCH --cpus-per-task=1");
    let _ = writeln!(
        merge,
        "# Written by `surftrack bench robustness --slurm`: joins the {n} shards of\n\
         # {ARRAY_SCRIPT} into {out}/robustness.json (a missing shard is an error here)."
    );
    let _ = writeln!(merge, "set -euo pipefail");
    let shard_dirs: Vec<String> = (0..n)
        .map(|i| shell_quote(&format!("{out}/shard-{i}")))
        .collect();
    let _ = writeln!(
        merge,
        "exec {exe} bench merge {} --out {}",
        shard_dirs.join(" "),
        shell_quote(out)
    );

    let dir = utf8(&plan.dir)?;
    let mut submit = String::new();
    let _ = writeln!(submit, "#!/bin/sh");
    let _ = writeln!(
        submit,
        "# Submits the robustness sweep: the job array, then the merge after it (afterany:\n\
         # the merge runs even when a task failed, and its log names the missing shard).\n\
         # Prints `array=<id> merge=<id>` on its last line."
    );
    let _ = writeln!(submit, "set -eu");
    let _ = writeln!(
        submit,
        "array=$(sbatch --parsable {})",
        shell_quote(&format!("{dir}/{ARRAY_SCRIPT}"))
    );
    // `--parsable` prints `id` or `id;cluster`.
    let _ = writeln!(submit, "array=${{array%%;*}}");
    let _ = writeln!(
        submit,
        "merge=$(sbatch --parsable --dependency=afterany:\"$array\" {})",
        shell_quote(&format!("{dir}/{MERGE_SCRIPT}"))
    );
    let _ = writeln!(submit, "merge=${{merge%%;*}}");
    let _ = writeln!(
        submit,
        "echo \"submitted: {n} array tasks, merged table in {}/robustness.json\"",
        out.replace('"', "\\\"")
    );
    let _ = writeln!(submit, "echo \"array=$array merge=$merge\"");
    Ok(SlurmScripts {
        array,
        merge,
        submit,
    })
}

/// Writes the scripts (executable) and the log directory into `plan.dir`; returns the
/// paths written.
pub fn write_slurm_scripts(plan: &SlurmPlan) -> Result<Vec<PathBuf>, SlurmError> {
    let scripts = slurm_scripts(plan)?;
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |source| SlurmError::Io { path, source }
    };
    let logs = plan.dir.join(LOG_DIR);
    std::fs::create_dir_all(&logs).map_err(io(&logs))?;
    let mut written = Vec::new();
    for (name, text) in [
        (ARRAY_SCRIPT, &scripts.array),
        (MERGE_SCRIPT, &scripts.merge),
        (SUBMIT_SCRIPT, &scripts.submit),
    ] {
        let path = plan.dir.join(name);
        std::fs::write(&path, text).map_err(io(&path))?;
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o755))
                .map_err(io(&path))?;
        }
        written.push(path);
    }
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plan() -> SlurmPlan {
        SlurmPlan {
            exe: PathBuf::from("/opt/st/surftrack"),
            dir: PathBuf::from("/scratch/rb slurm"),
            out: PathBuf::from("/scratch/rb"),
            shards: 4,
            bench_args: vec![
                "--spheres".into(),
                "100".into(),
                "--seeds".into(),
                "10".into(),
            ],
            seeds: 10,
            trackers: 2,
            jobs: 2,
            run_timeout_seconds: 600.0,
            child_memory_mib: 4096,
            job_name: "surftrack-rb".into(),
        }
    }

    #[test]
    fn shell_quoting_keeps_words_whole() {
        assert_eq!(shell_quote("--spheres"), "--spheres");
        assert_eq!(shell_quote("a b"), "'a b'");
        assert_eq!(shell_quote("it's"), r"'it'\''s'");
        assert_eq!(shell_quote(""), "''");
        assert_eq!(shell_quote("$HOME"), "'$HOME'");
    }

    #[test]
    fn the_array_has_one_task_per_shard_and_writes_shard_dirs() {
        let s = slurm_scripts(&plan()).unwrap();
        assert!(s.array.starts_with("#!/bin/bash\n"));
        assert!(s.array.contains("\n#SBATCH --array=0-3\n"), "{}", s.array);
        assert!(s.array.contains("\n#SBATCH --cpus-per-task=2\n"));
        // 3 seeds × 2 backends = 6 runs, 2 at a time, 10 minutes each: 30 minutes plus slack.
        assert!(
            s.array
                .contains(&format!("\n#SBATCH --time={}\n", 30 + SLACK_MINUTES))
        );
        assert!(
            s.array
                .contains(&format!("\n#SBATCH --mem={}M\n", 2 * 4096 + PARENT_MIB))
        );
        assert!(
            s.array
                .contains("--output='/scratch/rb slurm/logs/shard-%a.log'")
        );
        assert!(s.array.contains(
            "exec /opt/st/surftrack bench robustness --spheres 100 --seeds 10 \
             --shard \"$task/4\" --out /scratch/rb\"/shard-$task\" --quiet"
        ));
        // The #SBATCH lines come before any command (sbatch stops reading them there).
        let first_command = s.array.find("\nset -euo").unwrap();
        assert!(s.array.rfind("#SBATCH").unwrap() < first_command);
    }

    #[test]
    fn the_merge_joins_every_shard_and_depends_on_the_array() {
        let s = slurm_scripts(&plan()).unwrap();
        assert!(s.merge.contains(
            "exec /opt/st/surftrack bench merge /scratch/rb/shard-0 /scratch/rb/shard-1 \
             /scratch/rb/shard-2 /scratch/rb/shard-3 --out /scratch/rb\n"
        ));
        assert!(!s.merge.contains("--array"));
        assert!(
            s.submit
                .contains("array=$(sbatch --parsable '/scratch/rb slurm/robustness-array.sbatch')")
        );
        assert!(s.submit.contains(
            "merge=$(sbatch --parsable --dependency=afterany:\"$array\" '/scratch/rb slurm/robustness-merge.sbatch')"
        ));
        let no_cap = SlurmPlan {
            child_memory_mib: 0,
            ..plan()
        };
        assert!(!slurm_scripts(&no_cap).unwrap().array.contains("--mem"));
    }

    #[test]
    fn empty_shards_are_refused() {
        let p = SlurmPlan {
            shards: 0,
            ..plan()
        };
        assert!(matches!(slurm_scripts(&p), Err(SlurmError::NoShards)));
        let p = SlurmPlan {
            shards: 11,
            ..plan()
        };
        assert!(matches!(
            slurm_scripts(&p),
            Err(SlurmError::TooManyShards {
                shards: 11,
                seeds: 10
            })
        ));
        assert_eq!(largest_shard(10, 4), 3);
        assert_eq!(largest_shard(8, 4), 2);
    }
}
