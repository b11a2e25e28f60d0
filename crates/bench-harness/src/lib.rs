//! # bench-harness
//!
//! How users meet the project: built-in scenes, flows that propose vertex motion, the
//! statistical robustness benchmark, and the `surftrack` command line (`src/main.rs`,
//! defined in [`cli`]).
//!
//! | module | what |
//! |---|---|
//! | [`flows`] | vertex proposals: normal, Enright, curl noise, rotation, mean curvature, cyclic, one-shot |
//! | [`scenes`] | built-in scenes: initial mesh + flow + time step ([`scenes::build_tracked`]) |
//! | [`driver`] | one scene through one backend in this process ([`driver::run_scene`]) |
//! | [`isolate`] | the same in a child process under a watchdog (time-out, memory cap) |
//! | [`options`] | every backend and flow option as data: scenario files, `--set`, records |
//! | [`preservation`] | untouched fraction and feature distance (2024 paper Fig. 17) |
//! | [`bench`](mod@bench) | the robustness benchmark (2024 paper §9.6) and the backend comparison |
//! | [`ablate`] | research ablations: option variants × seeds, isolated, summarised per variant |
//! | [`record`] | the JSON records (`run.json`, `robustness.json`, `compare.json`) and shard merging |
//! | [`report`] | markdown tables, SVG plots and PNG pictures of frames |
//! | [`scaling`] | `bench scaling`: time and peak memory against size, `fix` and steps, log–log slopes |
//! | [`slurm`] | `bench robustness --slurm DIR`: a job array of shards and a dependent merge job |
//! | [`view`] | `surftrack view`: a self-contained WebGL page of runs' frames |
#![warn(missing_docs)]
#![forbid(unsafe_code)]

pub mod ablate;
pub mod bench;
pub mod cli;
pub mod driver;
pub mod flows;
pub mod isolate;
pub mod options;
pub mod preservation;
pub mod quality;
pub mod record;
pub mod report;
pub mod scaling;
pub mod scenes;
pub mod slurm;
pub mod view;
pub mod wall;
