//! What the commands share about talking to the user: logs through `tracing` (filtered
//! by `RUST_LOG`, on stderr) and progress bars (indicatif, on stderr, only on a terminal
//! and never with `--quiet`), so stdout carries nothing but results and JSON.

use std::io::IsTerminal;
use std::time::Duration;

use indicatif::{ProgressBar, ProgressStyle};
use tracing_subscriber::filter::{LevelFilter, Targets};

/// Installs the global log subscriber once: `RUST_LOG` as `level` or `target=level,…`
/// (default `warn`). A malformed `RUST_LOG` falls back to the default with a note.
pub(super) fn init_logging() {
    let (filter, note) = match std::env::var("RUST_LOG") {
        Ok(spec) if !spec.trim().is_empty() => match spec.parse::<Targets>() {
            Ok(targets) => (targets, None),
            Err(e) => (
                Targets::new().with_default(LevelFilter::WARN),
                Some(format!("ignoring RUST_LOG={spec:?}: {e}")),
            ),
        },
        _ => (Targets::new().with_default(LevelFilter::WARN), None),
    };
    use tracing_subscriber::prelude::*;
    let layer = tracing_subscriber::fmt::layer()
        .with_writer(std::io::stderr)
        .with_ansi(std::io::stderr().is_terminal());
    // Fails only if a subscriber is already set (e.g. `run` called twice in tests).
    let _ = tracing_subscriber::registry()
        .with(layer.with_filter(filter))
        .try_init();
    if let Some(note) = note {
        tracing::warn!("{note}");
    }
}

/// A progress bar over `len` items, or a hidden one with `--quiet` or when stderr is not
/// a terminal (logs and CI output stay clean).
pub(super) fn progress_bar(quiet: bool, len: u64, prefix: &str) -> ProgressBar {
    if quiet || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(len);
    let style = ProgressStyle::with_template(
        "{prefix:>12} [{elapsed_precise}] {bar:30} {pos}/{len} (eta {eta}) {msg}",
    )
    .unwrap_or_else(|_| ProgressStyle::default_bar());
    bar.set_style(style);
    bar.set_prefix(prefix.to_string());
    bar.enable_steady_tick(Duration::from_millis(200));
    bar
}
