//! The `surftrack` command line: argument definitions and dispatch. Each subcommand lives
//! in its own module and returns the process exit code.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand};

mod convert;
mod generate;
mod validate;

/// Multi-material surface tracking: generate scenes, validate and convert labelled meshes.
///
/// Meshes are triangle meshes whose every triangle separates two materials
/// (`label_front`, `label_back`; 0 is the outside). PLY files carry the labels as face
/// properties; OBJ files as `usemtl label_<front>_<back>` groups.
#[derive(Debug, Parser)]
#[command(name = "surftrack", version, about, long_about = None)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Write a built-in scene to a mesh file (PLY or OBJ, by extension).
    ///
    /// Example: `surftrack generate double-bubble --out db.ply`
    Generate(GenerateArgs),
    /// Check a mesh file against the invariants (watertight, consistently labelled, no
    /// degenerate or duplicate triangles, finite; with --intersections, no self-intersections).
    ///
    /// Exit code 0 when valid, 1 when invalid, 2 when the file cannot be read.
    Validate(ValidateArgs),
    /// Convert between PLY (ASCII or binary) and OBJ, keeping labels.
    Convert(ConvertArgs),
}

/// Arguments of `surftrack generate`.
#[derive(Debug, Args)]
pub struct GenerateArgs {
    /// The scene: sphere, spheres, double-bubble, zalesak, foam, copies.
    pub scene: String,
    /// Output file (.ply or .obj).
    #[arg(long)]
    pub out: PathBuf,
    /// Random seed for scenes with random placement (spheres, foam, copies).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Number of spheres (`spheres`), cells (`foam`) or copies (`copies`).
    #[arg(long, short = 'n')]
    pub count: Option<usize>,
    /// Resolution: icosphere subdivisions (`sphere`, `spheres`), segments around the triple
    /// curve (`double-bubble`), grid cells per axis (`zalesak`).
    #[arg(long)]
    pub resolution: Option<u32>,
    /// Sphere radius (`sphere`, `double-bubble`).
    #[arg(long)]
    pub radius: Option<f64>,
    /// Input mesh for `copies`.
    #[arg(long)]
    pub mesh: Option<PathBuf>,
    /// Write binary PLY instead of ASCII.
    #[arg(long)]
    pub binary: bool,
}

/// Arguments of `surftrack validate`.
#[derive(Debug, Args)]
pub struct ValidateArgs {
    /// The mesh file (.ply or .obj).
    pub file: PathBuf,
    /// Also run the exact self-intersection check (slower).
    #[arg(long)]
    pub intersections: bool,
    /// Print one JSON object instead of a human summary.
    #[arg(long)]
    pub json: bool,
}

/// Arguments of `surftrack convert`.
#[derive(Debug, Args)]
pub struct ConvertArgs {
    /// Input mesh (.ply or .obj).
    pub input: PathBuf,
    /// Output mesh (.ply or .obj).
    pub output: PathBuf,
    /// Write binary PLY instead of ASCII.
    #[arg(long)]
    pub binary: bool,
}

/// Writes a mesh by extension; PLY is ASCII unless `binary`.
fn write_mesh_file(
    mesh: &mesh_core::LabeledMesh,
    path: &std::path::Path,
    binary: bool,
) -> anyhow::Result<()> {
    use mesh_core::io::{MeshFormat, PlyFormat, write_ply};
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .map_err(|e| anyhow::anyhow!("cannot create directory {}: {e}", dir.display()))?;
    }
    match MeshFormat::from_path(path)? {
        MeshFormat::Ply if !binary => {
            let file = std::fs::File::create(path)
                .map_err(|e| anyhow::anyhow!("cannot write {}: {e}", path.display()))?;
            write_ply(mesh, std::io::BufWriter::new(file), PlyFormat::Ascii)
                .map_err(|e| e.with_path(path))?;
        }
        _ => mesh_core::io::write_mesh(mesh, path)?,
    }
    Ok(())
}

/// Runs a parsed command line, returning the exit code.
pub fn run(cli: Cli) -> anyhow::Result<ExitCode> {
    match cli.command {
        Command::Generate(args) => generate::run(&args),
        Command::Validate(args) => validate::run(&args),
        Command::Convert(args) => convert::run(&args),
    }
}
