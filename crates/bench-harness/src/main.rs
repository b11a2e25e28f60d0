//! `surftrack`: run built-in scenes through the tracker backends, benchmark them,
//! generate, validate and convert meshes.
//!
//! Exit codes: 0 success (and, for `validate`, a valid mesh), 1 an invalid mesh or a failed
//! run, 2 unreadable input or a usage error, 3 the requested backend is unavailable.

use std::process::ExitCode;

use clap::Parser;

use bench_harness::cli::{Cli, run};

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli) {
        Ok(code) => code,
        Err(err) => {
            eprintln!("error: {err:#}");
            ExitCode::from(2)
        }
    }
}
