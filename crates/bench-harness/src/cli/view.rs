//! `surftrack view DIR|FILE… [--out page.html] [--open]`: the frames of one or more runs
//! in one self-contained page ([`crate::view`]).

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::Context;
use clap::Args;

use crate::view::{PageOptions, PageStats, ViewSource, write_page};

pub(super) const VIEW_EXAMPLES: &str = "\
Examples:
  surftrack view out/db                              # one run: out/db/view.html
  surftrack view out/db-grid out/db-collision --out both.html   # side by side, one camera
  surftrack view out/ablate-rolling/runs/*/seed-1 --out variants.html
  surftrack view out/foam.ply --open                 # one mesh file

Inputs: a run directory (its run.json lists the frames; its record and SVG plots show
beside the picture), a run.json, a directory of .ply/.obj files, or one mesh file.
The page needs no network: three.js and every frame are inside it. Colours are by
material pair (the outer surface of material m in m's colour, a wall between two
materials in the mean of theirs); the legend's boxes hide materials or pairs.";

/// Arguments of `surftrack view`.
#[derive(Debug, Args)]
#[command(after_long_help = VIEW_EXAMPLES)]
pub struct ViewArgs {
    /// Run directories, run.json files, directories of meshes or mesh files; one panel
    /// each, side by side with a linked camera.
    #[arg(required = true)]
    pub inputs: Vec<PathBuf>,
    /// The page to write (default: view.html inside the only input directory, else
    /// ./view.html).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Keep every N-th frame of each run (and always the first and last).
    #[arg(long, default_value_t = 1)]
    pub every: usize,
    /// Open the page in the desktop's browser afterwards (xdg-open / open).
    #[arg(long)]
    pub open: bool,
}

/// Writes the page of `sources` to `out`; the directory is created if missing.
pub(crate) fn write_page_file(sources: &[ViewSource], out: &Path) -> anyhow::Result<PageStats> {
    if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let file = std::fs::File::create(out).with_context(|| format!("writing {}", out.display()))?;
    write_page(sources, &PageOptions::default(), file)
        .with_context(|| format!("writing {}", out.display()))
}

pub(super) fn run(args: &ViewArgs) -> anyhow::Result<ExitCode> {
    let start = Instant::now();
    let mut sources = Vec::with_capacity(args.inputs.len());
    for input in &args.inputs {
        let mut source = ViewSource::open(input)?;
        source.thin(args.every);
        sources.push(source);
    }
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| match args.inputs.as_slice() {
            [only] if only.is_dir() => only.join("view.html"),
            _ => PathBuf::from("view.html"),
        });
    let stats = write_page_file(&sources, &out)?;
    println!(
        "view: {} ({} panel(s), {} frame(s), largest {} triangles, {:.1} MB, {:.2} s)",
        out.display(),
        stats.panels,
        stats.frames,
        stats.max_triangles,
        stats.bytes as f64 / 1e6,
        start.elapsed().as_secs_f64()
    );
    if args.open {
        open_in_browser(&out);
    }
    Ok(ExitCode::SUCCESS)
}

/// Hands the page to the desktop; a missing opener is a note, not an error (the page is
/// written and its path printed).
fn open_in_browser(page: &Path) {
    let opener = if cfg!(target_os = "macos") {
        "open"
    } else {
        "xdg-open"
    };
    if let Err(e) = std::process::Command::new(opener).arg(page).spawn() {
        eprintln!(
            "note: cannot run {opener} ({e}); open {} yourself",
            page.display()
        );
    }
}

/// The `--every` the benchmarks give their children so that each keeps only its initial
/// and last frame, what the report pictures: no step is a multiple of it.
pub(crate) const ENDS_ONLY: usize = usize::MAX;

/// For a benchmark's report: pictures of `runs` (first and last frame, cut-away, one
/// camera) and `view.html` showing them side by side, both in `out`; returns the
/// markdown to append. A failure here is a warning in the report and on stderr, never a
/// lost benchmark: the records are written before.
pub(crate) fn bench_pictures(runs: &[crate::report::picture::PicturedRun], out: &Path) -> String {
    let pictures = match crate::report::picture::pictures_section(runs, out) {
        Ok(md) => md,
        Err(e) => {
            eprintln!("warning: no pictures in the report: {e}");
            return format!("\n(no pictures: {e})\n");
        }
    };
    if pictures.is_empty() {
        return pictures;
    }
    let sources: Vec<ViewSource> = runs
        .iter()
        .filter_map(|r| {
            let mut s = ViewSource::open(&r.dir).ok()?;
            s.title = format!("{} · {}", r.label, s.title);
            Some(s)
        })
        .collect();
    let page = out.join("view.html");
    match write_page_file(&sources, &page) {
        Ok(_) => format!(
            "{pictures}\nThese runs side by side in a browser, one camera: [view.html](view.html) \
             (`surftrack view DIR…` for any runs).\n"
        ),
        Err(e) => {
            eprintln!("warning: no view.html: {e:#}");
            pictures
        }
    }
}
