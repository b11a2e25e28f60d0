//! Running one `surftrack run` in a child process under a watchdog, so that a run which
//! crashes, hangs or eats all memory cannot take the benchmark down with it (the issue's
//! "each run isolated"; the 2024 paper's success criterion counts exactly those).
//!
//! The child is the current executable ([`std::env::current_exe`]) with a `run` command
//! line that writes `run.json` into its own directory; its stdout and stderr go to
//! `child.log` there. The watchdog polls the child every [`POLL`]: past the time limit it
//! kills it (failure `timeout`); on Linux it also reads the child's resident set size from
//! `/proc/<pid>/status` and kills it above the memory cap (failure `memory`). A child that
//! exits without a record died of a panic or a signal (failure `panic` or `crash`).

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};

use tracing::{debug, warn};

use crate::record::{Failure, FailureReason, RunRecord, RunSummary};

/// How often the watchdog looks at a child.
pub const POLL: Duration = Duration::from_millis(50);

/// Exit code of `surftrack run` when the run failed (tracker error, invalid frame, caught
/// panic, triangle cap).
pub const EXIT_RUN_FAILED: u8 = 1;
/// Exit code for usage and I/O errors.
pub const EXIT_USAGE: u8 = 2;
/// Exit code when the requested backend is not available in this build.
pub const EXIT_UNAVAILABLE: u8 = 3;
/// Exit code of a Rust process that panicked outside any `catch_unwind`.
const EXIT_RUST_PANIC: i32 = 101;

/// Limits the watchdog enforces.
#[derive(Clone, Copy, Debug)]
pub struct Limits {
    /// Wall-clock limit.
    pub timeout: Duration,
    /// Resident memory cap in bytes (Linux only; `None` = unlimited).
    pub max_rss_bytes: Option<u64>,
}

/// One child run: the `run` arguments (without the executable) and its directory.
#[derive(Clone, Debug)]
pub struct ChildRun {
    /// Backend name, for the record of a run that leaves none.
    pub tracker: String,
    /// Seed, likewise.
    pub seed: u64,
    /// Arguments after the executable, e.g. `["run", "spheres", …]`; must make the child
    /// write `run.json` into `dir`.
    pub args: Vec<OsString>,
    /// The run's directory (created if missing).
    pub dir: PathBuf,
}

/// How the watchdog ended.
enum Ending {
    Exited(ExitStatus),
    Killed(FailureReason, String),
}

/// Resident set size of a process, from `/proc/<pid>/status` (`VmRSS: <n> kB`); `None`
/// where there is no such file (not Linux, or the process is gone).
fn resident_bytes(pid: u32) -> Option<u64> {
    status_kib(&format!("/proc/{pid}/status"), "VmRSS:").map(|kib| kib * 1024)
}

/// Peak resident set of this process (`VmHWM` in `/proc/self/status`); `None` where
/// there is no such file.
pub fn own_peak_resident_bytes() -> Option<u64> {
    status_kib("/proc/self/status", "VmHWM:").map(|kib| kib * 1024)
}

fn status_kib(path: &str, key: &str) -> Option<u64> {
    let status = std::fs::read_to_string(path).ok()?;
    let line = status.lines().find(|l| l.starts_with(key))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

/// Waits for the child within the limits, killing it when one is exceeded. The loop is
/// bounded by the time limit (plus one poll).
fn watch(child: &mut Child, limits: &Limits, peak: &mut u64) -> Result<Ending, std::io::Error> {
    let start = Instant::now();
    loop {
        if let Some(status) = child.try_wait()? {
            return Ok(Ending::Exited(status));
        }
        let elapsed = start.elapsed();
        let killed = if elapsed >= limits.timeout {
            Some((
                FailureReason::Timeout,
                format!("killed after {:.1} s (time limit)", elapsed.as_secs_f64()),
            ))
        } else {
            let rss = resident_bytes(child.id());
            *peak = (*peak).max(rss.unwrap_or(0));
            limits.max_rss_bytes.and_then(|cap| {
                let rss = rss?;
                (rss > cap).then(|| {
                    (
                        FailureReason::Memory,
                        format!(
                            "killed at {} MiB resident (cap {} MiB)",
                            rss >> 20,
                            cap >> 20
                        ),
                    )
                })
            })
        };
        if let Some((reason, message)) = killed {
            // The child may exit between the check and the kill; either way reap it.
            if let Err(e) = child.kill() {
                debug!("kill: {e}");
            }
            child.wait()?;
            return Ok(Ending::Killed(reason, message));
        }
        std::thread::sleep(
            POLL.min(limits.timeout.saturating_sub(elapsed))
                .max(Duration::from_millis(1)),
        );
    }
}

/// "was killed by signal N" where the platform says which.
fn signal_description(status: &ExitStatus) -> String {
    #[cfg(unix)]
    {
        use std::os::unix::process::ExitStatusExt;
        if let Some(signal) = status.signal() {
            return format!("was killed by signal {signal}");
        }
    }
    format!("ended without an exit code ({status})")
}

/// Reads `run.json` from a run directory.
pub fn read_run_record(dir: &Path) -> Option<RunRecord> {
    let text = std::fs::read_to_string(dir.join("run.json")).ok()?;
    serde_json::from_str(&text).ok()
}

/// How a child started by [`run_watched`] ended.
#[derive(Debug)]
pub enum WatchedEnding {
    /// It exited by itself, with this code (`None`: killed by a signal).
    Exited(Option<i32>),
    /// The watchdog killed it (time-out or memory cap), with what it said.
    Killed(FailureReason, String),
    /// It could not be started or waited for.
    Failed(String),
}

/// A child run under the watchdog, for commands other than `run` (the scaling
/// benchmark's `fix` children).
#[derive(Debug)]
pub struct Watched {
    /// How it ended.
    pub ending: WatchedEnding,
    /// Wall time, seconds.
    pub wall_seconds: f64,
    /// Largest resident set the watchdog sampled, bytes (0 where unknown).
    pub sampled_peak_rss_bytes: u64,
}

/// Runs `exe args…` with stdout into `stdout` and stderr into `log`, under `limits`.
pub fn run_watched(
    exe: &Path,
    args: &[OsString],
    stdout: &Path,
    log: &Path,
    limits: &Limits,
) -> Watched {
    let start = Instant::now();
    let done = |ending, peak| Watched {
        ending,
        wall_seconds: start.elapsed().as_secs_f64(),
        sampled_peak_rss_bytes: peak,
    };
    let open = |path: &Path| {
        std::fs::File::create(path).map_err(|e| format!("cannot create {}: {e}", path.display()))
    };
    let (out, err) = match (open(stdout), open(log)) {
        (Ok(o), Ok(e)) => (o, e),
        (Err(m), _) | (_, Err(m)) => return done(WatchedEnding::Failed(m), 0),
    };
    let spawned = Command::new(exe)
        .args(args)
        .stdin(Stdio::null())
        .stdout(Stdio::from(out))
        .stderr(Stdio::from(err))
        .spawn();
    let mut child = match spawned {
        Ok(child) => child,
        Err(e) => {
            let message = format!("cannot start {}: {e}", exe.display());
            return done(WatchedEnding::Failed(message), 0);
        }
    };
    let mut peak = 0;
    let ending = match watch(&mut child, limits, &mut peak) {
        Ok(Ending::Exited(status)) => WatchedEnding::Exited(status.code()),
        Ok(Ending::Killed(reason, message)) => WatchedEnding::Killed(reason, message),
        Err(e) => WatchedEnding::Failed(format!("waiting for the child: {e}")),
    };
    done(ending, peak)
}

/// Runs `run` in a child of `exe` under `limits` and summarises it. Never fails: a child
/// that cannot even be started is a failed run (`crash`) with the reason in its message.
pub fn run_isolated(exe: &Path, run: &ChildRun, limits: &Limits) -> RunSummary {
    let start = Instant::now();
    let failed = |reason, message: String| {
        let failure = Failure {
            reason,
            message,
            step: None,
        };
        RunSummary::failed(
            &run.tracker,
            run.seed,
            failure,
            start.elapsed().as_secs_f64(),
        )
    };
    if let Err(e) = std::fs::create_dir_all(&run.dir) {
        return failed(
            FailureReason::Crash,
            format!("cannot create {}: {e}", run.dir.display()),
        );
    }
    // A stale record from an earlier benchmark in the same directory must not be read.
    let _ = std::fs::remove_file(run.dir.join("run.json"));
    let log_path = run.dir.join("child.log");
    let log = match std::fs::File::create(&log_path) {
        Ok(log) => log,
        Err(e) => {
            return failed(
                FailureReason::Crash,
                format!("cannot create {}: {e}", log_path.display()),
            );
        }
    };
    let log_err = match log.try_clone() {
        Ok(l) => Stdio::from(l),
        Err(_) => Stdio::null(),
    };
    let spawned = Command::new(exe)
        .args(&run.args)
        .stdin(Stdio::null())
        .stdout(Stdio::from(log))
        .stderr(log_err)
        .spawn();
    let mut child = match spawned {
        Ok(child) => child,
        Err(e) => {
            return failed(
                FailureReason::Crash,
                format!("cannot start {}: {e}", exe.display()),
            );
        }
    };
    let mut peak = 0;
    let ending = watch(&mut child, limits, &mut peak);
    let watched_mib = (peak > 0).then(|| crate::record::bytes_to_mib(peak));
    let wall = start.elapsed().as_secs_f64();
    let see_log = format!("see {}", log_path.display());
    match ending {
        Err(e) => failed(FailureReason::Crash, format!("waiting for the child: {e}")),
        Ok(Ending::Killed(reason, message)) => {
            warn!(tracker = %run.tracker, seed = run.seed, "{message}");
            let mut summary = failed(reason, format!("{message}; {see_log}"));
            summary.peak_rss_mib = watched_mib;
            summary
        }
        Ok(Ending::Exited(status)) => match read_run_record(&run.dir) {
            Some(record) => RunSummary::from_record(&record, wall),
            None => {
                let (reason, what) = match status.code() {
                    Some(EXIT_RUST_PANIC) => (FailureReason::Panic, "panicked".to_string()),
                    Some(code) => (FailureReason::Crash, format!("exited with code {code}")),
                    None => (FailureReason::Crash, signal_description(&status)),
                };
                failed(reason, format!("child {what} without a record; {see_log}"))
            }
        },
    }
}
