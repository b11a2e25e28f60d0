//! `surftrack scenes [--long]`: the built-in scenes, one line each.

use std::process::ExitCode;

use crate::scenes::SCENES;

use super::ScenesArgs;

pub(super) fn run(args: &ScenesArgs) -> anyhow::Result<ExitCode> {
    let width = SCENES.iter().map(|s| s.name.len()).max().unwrap_or(0);
    for s in SCENES {
        println!("{:width$}  {}", s.name, s.summary);
        if args.long {
            if s.steps > 0 {
                println!("{:width$}  default steps: {}; {}", "", s.steps, s.knobs);
            } else {
                println!("{:width$}  {}", "", s.knobs);
            }
        }
    }
    Ok(ExitCode::SUCCESS)
}
