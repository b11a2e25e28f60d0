//! `surftrack`: generate scenes, validate and convert meshes, run trackers.
//!
//! Exit codes: 0 success (and, for `validate`, a valid mesh), 1 an invalid mesh, 2 unreadable
//! input or a usage error.

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
