//! The `surftrack` command line: argument definitions and dispatch. Each subcommand lives
//! in its own module and returns the process exit code.
//!
//! Exit codes: 0 success; 1 an invalid mesh (`validate`) or a failed run (`run`); 2 a usage
//! or I/O error; 3 the requested backend is unavailable in this build (`run`).

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand};
use surftrack::Backend;

use crate::bench::{Shard, Simulate};

mod ablate;
mod bench;
mod convert;
mod fix;
mod generate;
mod implicit;
mod output;
mod run;
mod scaling;
mod scenes;
mod validate;
mod view;

pub use view::ViewArgs;

const MAIN_EXAMPLES: &str = "\
Examples:
  surftrack scenes                                     # what can be run
  surftrack run double-bubble --steps 60 --out out/db  # frames + run.json + plots in out/db
  surftrack run spheres --spheres 20 --seed 1 --steps 40 --tracker grid
  surftrack bench robustness --spheres 20 --seeds 10 --tracker grid --out out/rb
  surftrack bench compare double-bubble zalesak --steps 20
  surftrack validate out/db/frame_0060.ply --intersections

Logs: set RUST_LOG (error, warn, info, debug, trace; or per target, e.g.
RUST_LOG=bench_harness=debug) to see them on stderr. Progress bars show on a terminal
unless --quiet.

Exit codes: 0 success; 1 invalid mesh or failed run; 2 usage or I/O error; 3 backend
unavailable in this build.";

/// Multi-material surface tracking: run built-in scenes through a tracker backend,
/// benchmark the backends, generate, validate and convert labelled meshes.
///
/// Meshes are triangle meshes whose every triangle separates two materials
/// (`label_front`, `label_back`; 0 is the outside). PLY files carry the labels as face
/// properties; OBJ files as `usemtl label_<front>_<back>` groups.
#[derive(Debug, Parser)]
#[command(name = "surftrack", version, about, long_about = None, after_long_help = MAIN_EXAMPLES)]
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
    /// Run a built-in scene through a tracker: frames (PLY with labels), `run.json`, plots.
    ///
    /// Every step the scene's flow proposes new vertex positions, the tracker advances and
    /// the result is checked with `validate()`. The run stops at the first tracker error,
    /// panic, invalid mesh or triangle-cap excess and says which in `run.json`.
    Run(RunArgs),
    /// Benchmarks: robustness statistics (2024 paper §9.6), merging shards, comparing
    /// backends.
    Bench(BenchArgs),
    /// List the built-in scenes, one line each.
    Scenes(ScenesArgs),
    /// Repair a mesh, or unite overlapping labelled meshes, in one shot (grid backend).
    ///
    /// The input may overlap itself anywhere and by any amount (e.g. rotated copies of a
    /// mesh, each with its own label); the output is watertight, consistently labelled and
    /// free of self-intersections. Only triangles in flawed grid cells change.
    ///
    /// A clean input (valid, no self-intersections) is written back unchanged. A repair
    /// that would lose a material, or change the total volume beyond --volume-tolerance
    /// against the union of the input's materials, fails unless --allow-loss.
    ///
    /// Exit code 0 when the output is valid, 1 when the repair failed or would lose
    /// material, 2 when the input cannot be read.
    #[command(after_long_help = FIX_EXAMPLES)]
    Fix(FixArgs),
    /// Write one self-contained HTML page (WebGL, no network) showing the frames of one
    /// or more runs side by side: orbit camera, colours by material pair, toggles, a cut
    /// plane, a frame slider with the step's record and the run's plots.
    View(ViewArgs),
}

const FIX_EXAMPLES: &str = "\
Examples:
  surftrack generate copies --count 6 --out out/copies.ply
  surftrack fix out/copies.ply out/union.ply --json
  surftrack fix scan.obj scan_fixed.ply --cell 0.01

--json prints a record (schema surftrack.fix/1): input, output, valid, peak_rss_mib, and
the report:
stages [{stage, seconds}] (`reference` runs beside `improve`), seconds (the call's wall
time), cell_size, triangles_in, triangles_out, untouched_fraction, flawed_cells,
safety_rounds, subcell_rounds, subcell_pairs, improve_edits, improvement (per operation:
done, refused, vetoed; collapse refusals and guard vetoes per kind; null when improvement
did not run), validation, cell_size_choice {cell_size, rule, thinnest, reason},
clean_input, volumes [{label, before, after}], vanished, volume_check {reference, method,
spacing, output, relative_change, tolerance}, warnings.";

/// Arguments of `surftrack fix`.
#[derive(Debug, Args)]
pub struct FixArgs {
    /// Input mesh (.ply or .obj; unlabelled closed meshes are read as inside 1 / outside 0;
    /// vertices repeated at one position on open edges, as STL-style exports write them,
    /// are stitched first).
    pub input: PathBuf,
    /// Output mesh (.ply or .obj).
    pub output: PathBuf,
    /// Grid cell size ℓ: overlaps and features smaller than ℓ are resolved by remeshing.
    /// Default: the mean edge length of the input, or an eighth of the thinnest
    /// material's 3·volume/area where that is smaller, so every material is at least 8
    /// cells thick (the report's cell_size_choice says which rule decided).
    #[arg(long)]
    pub cell: Option<f64>,
    /// Accept a repair that loses a material or volume: write it, with a warning on
    /// stderr and in the record, instead of failing with exit code 1.
    #[arg(long)]
    pub allow_loss: bool,
    /// Largest accepted relative change of the total enclosed volume against the union
    /// of the input's materials.
    #[arg(long, default_value_t = 0.02)]
    pub volume_tolerance: f64,
    /// Print the JSON record instead of a summary.
    #[arg(long)]
    pub json: bool,
    /// Write binary PLY.
    #[arg(long)]
    pub binary: bool,
    /// Skip the exact self-intersection check of the output (faster on huge meshes).
    #[arg(long)]
    pub no_intersection_check: bool,
}

const RUN_EXAMPLES: &str = "\
Examples:
  surftrack run double-bubble --steps 60 --out out/db --json
  surftrack run spheres --spheres 20 --seed 1 --steps 40 --tracker grid
  surftrack run enright --resolution 16 --every 10 --tracker collision
  surftrack run copies --mesh bunny.ply --count 3
  surftrack run --mesh my.ply --flow normal:speed=0.5,1-2=0.2 --tracker collision
  surftrack run --mesh my.obj --flow enright:period=2 --steps 100 --every 10
  surftrack run rolling --set grid.resampling=global --set grid.improve_scope=changed
  surftrack run spheres --config scenario.toml --print-options
  surftrack run --from-record out/db/run.json --out out/db-replay

Output (in --out, default out/<scene>-<tracker>): frame_0000.ply (the initial mesh),
then every --every steps and the last step; run.json (schema surftrack.run/1:
scene, tracker, seed, steps, success, failure {reason, message, step}, wall_seconds,
peak_triangles, events, stage_seconds, per_step [...]); time_per_step.svg and
triangles_per_step.svg; unless --no-view, view.html (the frames in a browser, see
`surftrack view`) and report.md with pictures (pictures/*.png) of the first and last frame.

Failure reasons: unavailable, error, panic, invalid, memory (--max-triangles).
Exit codes: 0 success, 1 the run failed, 2 usage or I/O error, 3 backend unavailable.";

/// Scene parameters shared by `run` and the benchmarks; unset means the scene's default
/// (see `surftrack scenes --long`).
#[derive(Debug, Args, Clone, Default)]
pub struct SceneArgs {
    /// Spheres (`spheres`), cells (`foam`) or copies (`copies`).
    #[arg(long = "count", short = 'n', visible_alias = "spheres")]
    pub count: Option<usize>,
    /// Resolution; its meaning depends on the scene (`surftrack scenes --long`). With
    /// `--mesh` (`copies`, `run --flow`): split the mesh in four this many times (0: as
    /// given) instead of until its thinnest material is resolved.
    #[arg(long)]
    pub resolution: Option<u32>,
    /// Radius (`double-bubble`, `inversion`, `cyclic`).
    #[arg(long)]
    pub radius: Option<f64>,
    /// Input mesh for `copies`, or the mesh `run --flow` moves (.ply or .obj).
    #[arg(long)]
    pub mesh: Option<PathBuf>,
}

/// Options as data, shared by `run` and the benchmarks: a scenario file and `--set`
/// overrides of any backend or flow option (see `bench_harness::options`).
#[derive(Debug, Args, Clone, Default)]
pub struct OptionArgs {
    /// Scenario file (TOML) with tables `[grid]`, `[collision]`, `[flow]` overriding
    /// any option, e.g. `[grid]\nresampling = "global"`.
    #[arg(long, value_name = "FILE.toml")]
    pub config: Option<PathBuf>,
    /// Override one option, after the scenario file; repeatable. Paths are field paths
    /// (`grid.resampling=global`, `grid.flaws.deep_cell_test=false`,
    /// `collision.merge=false`, `flow.normal_scheme=face_offsetting`); `--print-options`
    /// lists them all.
    #[arg(long = "set", value_name = "PATH=VALUE")]
    pub set: Vec<String>,
}

/// Arguments of `surftrack run`.
#[derive(Debug, Args)]
#[command(after_long_help = RUN_EXAMPLES)]
pub struct RunArgs {
    /// The scene (`surftrack scenes` lists them); not needed with --from-record or --flow.
    #[arg(required_unless_present_any = ["from_record", "flow"], default_value = "")]
    pub scene: String,
    /// A built-in flow on your own mesh (`--mesh FILE`, labelled or a closed unlabelled
    /// surface) instead of a scene: `normal[:speed=S,A-B=S,scheme=face_offsetting]`,
    /// `enright[:period=T]`, `curl-noise[:seed=,modes=,length=,amplitude=]`,
    /// `rotation[:axis=z,period=T,cx=,cy=,cz=]`, `mean-curvature[:tension=K]`. Same frames,
    /// record and plots as a scene; 40 steps unless --steps.
    #[arg(
        long,
        value_name = "NAME[:key=value,...]",
        conflicts_with = "from_record"
    )]
    pub flow: Option<String>,
    /// Reproduce a run from its `run.json`: same scene, scene parameters, backend, seed,
    /// steps, time step and options (`--set`, `--config`, `--steps`, `--out` still apply).
    /// Bit-identical output for the same thread count (`RAYON_NUM_THREADS`).
    #[arg(long, value_name = "RUN_JSON")]
    pub from_record: Option<PathBuf>,
    /// Print the effective options (one `path = value` per line) and exit.
    #[arg(long)]
    pub print_options: bool,
    /// Scenario file and `--set` overrides.
    #[command(flatten)]
    pub option_args: OptionArgs,
    /// Tracker backend: `grid` (Heiss-Synak et al. 2024) or `collision` (Los Topos).
    #[arg(long, short = 't', default_value = "grid")]
    pub tracker: Backend,
    /// Number of steps (default: the scene's).
    #[arg(long)]
    pub steps: Option<usize>,
    /// Time step (default: the scene's).
    #[arg(long)]
    pub dt: Option<f64>,
    /// Random seed (sphere placement, noise, Voronoi sites, rotations).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output directory for frames, run.json and plots (default: `out/<scene>-<tracker>`).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Write a frame every N steps (plus the initial and the last); 0 writes none.
    #[arg(long, default_value_t = 1)]
    pub every: usize,
    /// Write ASCII PLY frames instead of binary.
    #[arg(long)]
    pub ascii: bool,
    /// Also check every step for exact self-intersections (slower).
    #[arg(long)]
    pub check_intersections: bool,
    /// Fail the run (reason `memory`) when a step leaves more triangles than this.
    #[arg(long)]
    pub max_triangles: Option<usize>,
    /// Print the run record as JSON on stdout instead of a summary.
    #[arg(long)]
    pub json: bool,
    /// No progress bar and no summary (errors still go to stderr).
    #[arg(long, short = 'q')]
    pub quiet: bool,
    /// Write neither view.html (`surftrack view` of the run) nor report.md with its
    /// pictures (the benchmarks' children run so; their reports picture them).
    #[arg(long)]
    pub no_view: bool,
    /// Scene parameters.
    #[command(flatten)]
    pub scene_args: SceneArgs,
    /// Test hook: misbehave instead of running (hang, panic).
    #[arg(long, hide = true)]
    pub simulate: Option<Simulate>,
}

/// Arguments of `surftrack bench`.
#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Which benchmark.
    #[command(subcommand)]
    pub command: BenchCommand,
}

/// The benchmarks.
#[derive(Debug, Subcommand)]
pub enum BenchCommand {
    /// The statistical robustness benchmark: N random spheres expanding under normal
    /// flow, M seeds, each run isolated in a child process with a time limit and a
    /// memory guard.
    ///
    /// Success per run (2024 paper §9.6): no panic, error, time-out or memory blow-up,
    /// and every step's mesh passes `validate()`.
    Robustness(RobustnessArgs),
    /// Merge the outputs of sharded `bench robustness` runs into one table.
    Merge(MergeArgs),
    /// Run scenes with every backend side by side and tabulate time, triangles and events.
    Compare(CompareArgs),
    /// Research ablations: the cross product of option variants on the same seeds, each
    /// run isolated; a table and plots per variant.
    Ablate(AblateArgs),
    /// An animated implicit surface (metaballs) followed by the grid tracker vs marching
    /// tetrahedra from scratch every frame: ms per frame, triangles, temporal coherence.
    Implicit(implicit::ImplicitArgs),
    /// Time and peak memory against size: `fix` on rotated copies from 100k to millions
    /// of triangles, and steps on sphere sets of increasing size; log–log slopes, plots.
    Scaling(scaling::ScalingArgs),
}

const ROBUSTNESS_EXAMPLES: &str = "\
Examples:
  surftrack bench robustness --spheres 20 --seeds 10 --tracker grid --out out/rb
  surftrack bench robustness --spheres 100 --seeds 10 --jobs 2 --json
  # on a cluster, one shard per array task, then merge:
  surftrack bench robustness --spheres 100 --seeds 100 --shard $TASK/10 --out out/rb/shard-$TASK
  surftrack bench merge out/rb/shard-* --out out/rb/all
  # or let surftrack write the Slurm job array and the dependent merge job:
  surftrack bench robustness --spheres 100 --seeds 100 --slurm out/rb-slurm --slurm-shards 10 --out out/rb
  sh out/rb-slurm/submit.sh        # merged table: out/rb/robustness.json

Output (in --out): robustness.json (schema surftrack.robustness/1: config, runs, summary
per tracker with runs, successes, success_rate, mean/median/max_seconds), report.md,
time_per_step.svg, triangles_per_step.svg, success_rate.svg, and runs/<tracker>-seed-<s>/
with each child's run.json and child.log.

Seeds are first-seed, first-seed+1, ...; shard I/N (0 <= I < N) takes the seeds at
positions I, I+N, I+2N, ... of that list. Times in the table are of successful runs.";

/// Arguments of `surftrack bench robustness`.
#[derive(Debug, Args)]
#[command(after_long_help = ROBUSTNESS_EXAMPLES)]
pub struct RobustnessArgs {
    /// Spheres per run.
    #[arg(long, default_value_t = 20)]
    pub spheres: usize,
    /// Number of seeds (runs per backend).
    #[arg(long, default_value_t = 10)]
    pub seeds: usize,
    /// First seed.
    #[arg(long, default_value_t = 1)]
    pub first_seed: u64,
    /// Backends to run (repeat or comma-separate; default: all).
    #[arg(long, short = 't', value_delimiter = ',')]
    pub tracker: Vec<Backend>,
    /// Steps per run.
    #[arg(long, default_value_t = 40)]
    pub steps: usize,
    /// Time limit per run, seconds (the child is killed after it).
    #[arg(long, default_value_t = 1800.0)]
    pub timeout: f64,
    /// Children running at once.
    #[arg(long, short = 'j', default_value_t = 1)]
    pub jobs: usize,
    /// Run only shard I of N (0-based), e.g. `--shard 0/4`.
    #[arg(long)]
    pub shard: Option<Shard>,
    /// Output directory (default: out/robustness, or out/robustness/shard-I with --shard).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Memory guard: a run whose mesh exceeds this many triangles fails with `memory`.
    #[arg(long, default_value_t = 2_000_000)]
    pub max_triangles: usize,
    /// Memory guard: a child above this resident memory (MiB, Linux) is killed; 0 = off.
    #[arg(long, default_value_t = 8192)]
    pub max_memory_mib: u64,
    /// Keep frames of every run, every N steps (0: only the first and last, for the
    /// report's pictures; none with --no-pictures).
    #[arg(long, default_value_t = 0)]
    pub every: usize,
    /// Print the per-backend summary as JSON instead of the table.
    #[arg(long)]
    pub json: bool,
    /// No progress bar.
    #[arg(long, short = 'q')]
    pub quiet: bool,
    /// No pictures in the report and no view.html (children then keep no frames unless
    /// --every asks).
    #[arg(long)]
    pub no_pictures: bool,
    /// Write Slurm scripts into DIR instead of running: a job array (one shard per task,
    /// each into OUT/shard-I), a merge job depending on it, and submit.sh to submit both.
    #[arg(long, value_name = "DIR", conflicts_with = "shard")]
    pub slurm: Option<PathBuf>,
    /// Array tasks (shards) of the --slurm scripts (default: one per seed).
    #[arg(long, value_name = "N", requires = "slurm")]
    pub slurm_shards: Option<usize>,
    /// Test hook passed to every child (hang, panic).
    #[arg(long, hide = true)]
    pub simulate: Option<Simulate>,
}

/// Arguments of `surftrack bench merge`.
#[derive(Debug, Args)]
#[command(
    after_long_help = "Example:\n  surftrack bench merge out/rb/shard-0 out/rb/shard-1 --out out/rb/all\n\nEach input is a directory holding robustness.json (or the file itself). The shards must come from the same benchmark parameters; a seed present twice is an error."
)]
pub struct MergeArgs {
    /// Shard output directories (or their robustness.json files).
    #[arg(required = true)]
    pub inputs: Vec<PathBuf>,
    /// Where the merged robustness.json, report.md and plots go.
    #[arg(long, default_value = "out/robustness-merged")]
    pub out: PathBuf,
    /// Print the per-backend summary as JSON instead of the table.
    #[arg(long)]
    pub json: bool,
}

/// Arguments of `surftrack bench compare`.
#[derive(Debug, Args)]
#[command(
    after_long_help = "Examples:\n  surftrack bench compare                       # every scene, default steps\n  surftrack bench compare double-bubble spheres --steps 10 --jobs 2\n\nOutput (in --out, default out/compare): compare.json (schema surftrack.compare/1), compare.md, and <scene>-<tracker>/ per run."
)]
pub struct CompareArgs {
    /// Scenes (default: every tracked scene).
    pub scenes: Vec<String>,
    /// Steps per scene (default: each scene's).
    #[arg(long)]
    pub steps: Option<usize>,
    /// Seed of every scene.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Count for scenes that have one (spheres, cells, copies).
    #[arg(long = "count", short = 'n', visible_alias = "spheres")]
    pub count: Option<usize>,
    /// Backends (repeat or comma-separate; default: all).
    #[arg(long, short = 't', value_delimiter = ',')]
    pub tracker: Vec<Backend>,
    /// Time limit per run, seconds.
    #[arg(long, default_value_t = 600.0)]
    pub timeout: f64,
    /// Children running at once.
    #[arg(long, short = 'j', default_value_t = 1)]
    pub jobs: usize,
    /// Output directory.
    #[arg(long, default_value = "out/compare")]
    pub out: PathBuf,
    /// Keep frames every N steps (0: only the first and last, for the pictures; none
    /// with --no-pictures).
    #[arg(long, default_value_t = 0)]
    pub every: usize,
    /// Memory guard: triangle cap per run.
    #[arg(long, default_value_t = 2_000_000)]
    pub max_triangles: usize,
    /// Memory guard: resident memory cap per child, MiB (Linux); 0 = off.
    #[arg(long, default_value_t = 8192)]
    pub max_memory_mib: u64,
    /// Print compare.json on stdout instead of the table.
    #[arg(long)]
    pub json: bool,
    /// No pictures in compare.md and no view.html (children then keep no frames unless
    /// --every asks).
    #[arg(long)]
    pub no_pictures: bool,
    /// No progress bar.
    #[arg(long, short = 'q')]
    pub quiet: bool,
}

const ABLATE_EXAMPLES: &str = "\
Examples:
  surftrack bench ablate rolling --preset resampling --seeds 3
  surftrack bench ablate spheres --vary grid.flaws.deep_cell_test=true,false --seeds 5
  surftrack bench ablate double-bubble --tracker collision --vary collision.merge=true,false \\
      --vary collision.t1=true,false --seeds 2 --steps 30 --json

Presets (each sets the backend, the varied options and fixed options; --vary adds more):
  resampling        grid: local vs global resampling (2024 Fig. 17b), local improvement
  deep-cells        grid: deep-cell test on/off (2024 Fig. 9)
  curve-smoothing   grid: non-manifold curve smoothing 10 steps vs off (2024 §8.3)
  label-correction  grid: nearest breaking point vs nearest grid vertex (§8.1)
  merging           collision: snap merging vs none (Los Topos §7)
  t1                collision: T1 vertex separation on/off (Los Topos §5)
  impact-zones      collision: impact zones (fail-safe) on/off (El Topo §3.8) [1]
  collision-safety  collision: El Topo's collision_safety on/off [1]
  normal-flow       both backends: vertex-normal vs face-offsetting normal flow (Los Topos §8.3)
  remeshing         both backends: mesh improvement on/off (El Topo Figs. 4.5-4.6)
  [1] the option is recorded; the collision backend does not act on it yet.

Output (in --out, default out/ablate-<scene>): ablate.json (schema surftrack.ablate/1),
report.md, plots (success_rate.svg, seconds_per_step.svg, untouched_fraction.svg,
triangles.svg, volume_drift.svg), runs/<variant>/seed-<s>/ with run.json and child.log.

Untouched fraction: the fraction of the final mesh's triangles that are an initial
triangle carried by the scene's rigid motion (rolling) or not moved at all (other
scenes), within 1e-9 of the scene size; see bench_harness::preservation.";

/// Arguments of `surftrack bench ablate`.
#[derive(Debug, Args)]
#[command(after_long_help = ABLATE_EXAMPLES)]
pub struct AblateArgs {
    /// The scene (`surftrack scenes`).
    pub scene: String,
    /// A named ablation (see below); its variants are crossed with any --vary.
    #[arg(long)]
    pub preset: Option<String>,
    /// An option and its values, `path=v1,v2,...`; repeatable (the cross product runs).
    #[arg(long, value_name = "PATH=V1,V2,...")]
    pub vary: Vec<String>,
    /// Backends (default: the preset's, else grid).
    #[arg(long, short = 't', value_delimiter = ',')]
    pub tracker: Vec<Backend>,
    /// Number of seeds (first-seed, first-seed+1, ...), the same for every variant.
    #[arg(long, default_value_t = 3)]
    pub seeds: usize,
    /// First seed.
    #[arg(long, default_value_t = 1)]
    pub first_seed: u64,
    /// Steps per run (default: the scene's).
    #[arg(long)]
    pub steps: Option<usize>,
    /// Scene parameters.
    #[command(flatten)]
    pub scene_args: SceneArgs,
    /// Scenario file and fixed `--set` overrides applied to every variant.
    #[command(flatten)]
    pub option_args: OptionArgs,
    /// Time limit per run, seconds.
    #[arg(long, default_value_t = 1800.0)]
    pub timeout: f64,
    /// Children running at once.
    #[arg(long, short = 'j', default_value_t = 1)]
    pub jobs: usize,
    /// Memory guard: triangle cap per run.
    #[arg(long, default_value_t = 2_000_000)]
    pub max_triangles: usize,
    /// Memory guard: resident memory cap per child, MiB (Linux); 0 = off.
    #[arg(long, default_value_t = 8192)]
    pub max_memory_mib: u64,
    /// Output directory (default: `out/ablate-<scene>`).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Print ablate.json on stdout instead of the table.
    #[arg(long)]
    pub json: bool,
    /// No pictures in report.md and no view.html (the children then keep no frames).
    #[arg(long)]
    pub no_pictures: bool,
    /// No progress bar.
    #[arg(long, short = 'q')]
    pub quiet: bool,
}

/// Arguments of `surftrack scenes`.
#[derive(Debug, Args)]
pub struct ScenesArgs {
    /// Also show each scene's default steps and parameters.
    #[arg(long)]
    pub long: bool,
}

/// Arguments of `surftrack generate`.
#[derive(Debug, Args)]
pub struct GenerateArgs {
    /// The scene: any of `surftrack scenes`, or `sphere`.
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
    /// Resolution: as `surftrack scenes --long` says, except `double-bubble`, written
    /// merged (two bubbles and their wall): segments around the triple curve (48).
    #[arg(long)]
    pub resolution: Option<u32>,
    /// Sphere radius (`sphere`, `double-bubble`, `inversion`, `cyclic`).
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

/// Reads a mesh a command is about to work on (`fix`, `run --mesh`, `generate --mesh`,
/// `bench scaling --mesh`): vertices repeated at the same position on open edges are
/// stitched and open edges split at the vertices lying on them
/// ([`mesh_core::io::ReadOptions::stitch`]: the per-face vertices of STL-style exports,
/// the T-junctions of CAD exports), and stderr says how many. `validate` and `convert`
/// read files as they are.
fn read_work_mesh(path: &std::path::Path) -> anyhow::Result<mesh_core::LabeledMesh> {
    let options = mesh_core::io::ReadOptions {
        stitch: true,
        ..Default::default()
    };
    let (mesh, report) = mesh_core::io::read_mesh_reported(path, &options)?;
    if report.stitched_vertices > 0 {
        eprintln!(
            "{}: stitched {} vertices that repeat another one's position on an open edge \
             (per-face vertices, as STL-style exporters write them)",
            path.display(),
            report.stitched_vertices
        );
    }
    if report.t_junction_vertices > 0 {
        eprintln!(
            "{}: split open edges at {} vertices lying on them (T-junctions, as CAD \
             exporters leave them)",
            path.display(),
            report.t_junction_vertices
        );
    }
    if let Some(refusal) = no_triangles(path, &mesh) {
        anyhow::bail!(refusal);
    }
    Ok(mesh)
}

/// The refusal of a file that read without error but holds no triangle: every command
/// works on surfaces, and such a file is almost always another format under the wrong
/// extension, or cut short, so `validate` calling it "valid" and `convert` writing an
/// empty mesh hid the mistake.
fn no_triangles(path: &std::path::Path, mesh: &mesh_core::LabeledMesh) -> Option<String> {
    (mesh.num_triangles() == 0).then(|| {
        format!(
            "{}: no triangles in the file ({} vertices read): not a surface mesh, or not in \
             the format its extension names",
            path.display(),
            mesh.num_vertices()
        )
    })
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

/// Runs a parsed command line, returning the exit code. Sets up logging (`RUST_LOG`) on
/// stderr first.
pub fn run(cli: Cli) -> anyhow::Result<ExitCode> {
    output::init_logging();
    match cli.command {
        Command::Generate(args) => generate::run(&args),
        Command::Validate(args) => validate::run(&args),
        Command::Convert(args) => convert::run(&args),
        Command::Run(args) => run::run(&args),
        Command::Bench(args) => match args.command {
            BenchCommand::Robustness(args) => bench::robustness(&args),
            BenchCommand::Merge(args) => bench::merge(&args),
            BenchCommand::Compare(args) => bench::compare(&args),
            BenchCommand::Ablate(args) => ablate::run(&args),
            BenchCommand::Implicit(args) => implicit::run(&args),
            BenchCommand::Scaling(args) => scaling::run(&args),
        },
        Command::Scenes(args) => scenes::run(&args),
        Command::Fix(args) => fix::run(&args),
        Command::View(args) => view::run(&args),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(args: &[&str]) -> Result<Cli, clap::Error> {
        Cli::try_parse_from(std::iter::once("surftrack").chain(args.iter().copied()))
    }

    #[test]
    fn run_has_documented_defaults_and_the_spheres_alias() {
        let Command::Run(run) = parse(&["run", "spheres", "--spheres", "20"])
            .unwrap()
            .command
        else {
            panic!("not run")
        };
        assert_eq!(run.tracker, Backend::Grid);
        assert_eq!((run.seed, run.every, run.steps), (1, 1, None));
        assert_eq!(run.scene_args.count, Some(20));
        assert!(!run.json && !run.quiet && run.simulate.is_none());
        let Command::Run(run) = parse(&[
            "run",
            "double-bubble",
            "-t",
            "collision",
            "--steps",
            "60",
            "--out",
            "o",
            "--json",
        ])
        .unwrap()
        .command
        else {
            panic!("not run")
        };
        assert_eq!(run.tracker, Backend::Collision);
        assert_eq!(run.steps, Some(60));
        assert_eq!(run.out, Some(PathBuf::from("o")));
        assert!(run.json);
        assert!(parse(&["run", "spheres", "--tracker", "levelset"]).is_err());
        assert!(parse(&["run"]).is_err());
    }

    #[test]
    fn bench_commands_parse_trackers_shards_and_inputs() {
        let cli = parse(&[
            "bench",
            "robustness",
            "--spheres",
            "100",
            "--seeds",
            "10",
            "--tracker",
            "grid,collision",
            "--shard",
            "1/4",
            "--jobs",
            "2",
            "--timeout",
            "60",
            "--json",
        ])
        .unwrap();
        let Command::Bench(BenchArgs {
            command: BenchCommand::Robustness(r),
        }) = cli.command
        else {
            panic!("not robustness")
        };
        assert_eq!((r.spheres, r.seeds, r.jobs, r.steps), (100, 10, 2, 40));
        assert_eq!(r.tracker, vec![Backend::Grid, Backend::Collision]);
        assert_eq!(r.shard, Some(Shard { index: 1, count: 4 }));
        assert_eq!(r.timeout, 60.0);
        assert!(r.json);
        assert!(parse(&["bench", "robustness", "--shard", "4/4"]).is_err());
        assert!(parse(&["bench", "merge"]).is_err(), "merge needs inputs");
        let Command::Bench(BenchArgs {
            command: BenchCommand::Merge(m),
        }) = parse(&["bench", "merge", "a", "b", "--out", "m"])
            .unwrap()
            .command
        else {
            panic!("not merge")
        };
        assert_eq!(m.inputs, vec![PathBuf::from("a"), PathBuf::from("b")]);
        let Command::Bench(BenchArgs {
            command: BenchCommand::Compare(c),
        }) = parse(&["bench", "compare", "zalesak", "cyclic", "--steps", "5"])
            .unwrap()
            .command
        else {
            panic!("not compare")
        };
        assert_eq!(c.scenes, vec!["zalesak", "cyclic"]);
        assert!(c.tracker.is_empty(), "default: every backend");
    }

    #[test]
    fn hidden_hooks_stay_out_of_the_help() {
        use clap::CommandFactory;
        let mut cmd = Cli::command();
        let run = cmd.find_subcommand_mut("run").unwrap();
        let help = run.render_long_help().to_string();
        assert!(help.contains("Examples:") && help.contains("--tracker"));
        assert!(!help.contains("simulate"));
        cmd.debug_assert();
    }
}
