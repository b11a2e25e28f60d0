//! `surftrack bench implicit`: the animated implicit surface followed by our tracker vs
//! the same animation polygonized from scratch every frame by marching tetrahedra, at a
//! comparable triangle count (Nesme & Bouthors 2006 §5; `implicit_surface::compare`).

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context;
use clap::Args;
use implicit_surface::compare::{Comparison, compare};
use implicit_surface::scenes;
use serde::Serialize;

const EXAMPLES: &str = "\
Examples:
  surftrack bench implicit                          # crossing + swarm, 60 frames each
  surftrack bench implicit --frames 80 --out out/implicit --json

Output (in --out, default out/implicit): implicit.json (schema surftrack.implicit/1) and
report.md, one table per animation: ms per frame (mean, max), mean triangles, temporal
coherence (fraction of vertices persisting from the previous frame: for ours the same
vertex carried by the tracker, for marching tetrahedra a bit-identical position), final
component count, the largest |F|/|grad F| left on a vertex, and frames failing validation.";

/// Arguments of `surftrack bench implicit`.
#[derive(Debug, Args)]
#[command(after_long_help = EXAMPLES)]
pub struct ImplicitArgs {
    /// Frames per animation (over t ∈ [0, 1]; fewer frames = faster motion per frame).
    #[arg(long, default_value_t = 60)]
    pub frames: usize,
    /// Blobs in the swarm animation (0: skip it).
    #[arg(long, default_value_t = 12)]
    pub count: usize,
    /// Seed of the swarm.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Target edge length ℓ of the follower (also its tracker's cell size).
    #[arg(long, default_value_t = 0.12)]
    pub edge_length: f64,
    /// Output directory.
    #[arg(long, default_value = "out/implicit")]
    pub out: PathBuf,
    /// Print implicit.json on stdout instead of the tables.
    #[arg(long)]
    pub json: bool,
}

#[derive(Serialize)]
struct Record<'a> {
    schema: &'static str,
    frames: usize,
    comparisons: &'a [Comparison],
}

/// Runs the comparison and writes implicit.json and report.md.
pub fn run(args: &ImplicitArgs) -> anyhow::Result<ExitCode> {
    anyhow::ensure!(args.frames > 0, "--frames must be at least 1");
    anyhow::ensure!(
        args.edge_length.is_finite() && args.edge_length > 0.0,
        "--edge-length must be finite and > 0, got {}",
        args.edge_length
    );
    let mut animations = vec![scenes::crossing(1.1, args.edge_length, args.frames)?];
    if args.count > 0 {
        animations.push(scenes::swarm(
            args.count,
            args.seed,
            args.edge_length,
            args.frames,
        )?);
    }
    let mut results = Vec::new();
    for anim in &animations {
        tracing::info!(scene = anim.name, frames = args.frames, "comparing");
        results.push(
            compare(anim, args.frames, None, true)
                .with_context(|| format!("comparing on the `{}` animation", anim.name))?,
        );
    }
    let mut md = String::from(
        "# Animated implicit surface: following vs marching tetrahedra every frame\n\n",
    );
    for r in &results {
        md.push_str(&r.to_markdown());
        md.push('\n');
    }
    let record = Record {
        schema: "surftrack.implicit/1",
        frames: args.frames,
        comparisons: &results,
    };
    let json = serde_json::to_string_pretty(&record)?;
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    std::fs::write(args.out.join("implicit.json"), &json)
        .with_context(|| format!("writing {}", args.out.join("implicit.json").display()))?;
    std::fs::write(args.out.join("report.md"), &md)
        .with_context(|| format!("writing {}", args.out.join("report.md").display()))?;
    if args.json {
        println!("{json}");
    } else {
        print!("{md}");
        println!("record: {}", args.out.join("implicit.json").display());
    }
    let invalid: usize = results
        .iter()
        .flat_map(|r| &r.methods)
        .map(|m| m.invalid_frames)
        .sum();
    Ok(if invalid == 0 {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}
