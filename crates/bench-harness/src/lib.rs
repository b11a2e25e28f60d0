//! # bench-harness
//!
//! How users meet the project: built-in scenes, flows that propose vertex motion, the
//! statistical robustness benchmark, and the `surftrack` command line (`src/main.rs`,
//! defined in [`cli`]).
#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod cli;
pub mod flows;
pub mod scenes;
