//! `surftrack view`: one self-contained HTML page showing the frames of one or more runs
//! side by side — WebGL through the vendored three.js (`assets/three/`, MIT), an orbit
//! camera shared by every panel, colour by material pair ([`palette`]), toggles per
//! material and pair, a cut plane, a frame slider with play/pause, the step's record and
//! the run's plots.
//!
//! The page needs no network and no server: three.js, the viewer script and every
//! frame are inside the file. Frames travel as base64 little-endian typed arrays
//! (positions `Float32Array`, triangles `Uint32Array` sorted by material pair, with a
//! `[lo, hi, first, count]` range per pair), decoded only when shown, so a large frame
//! costs one `atob` and no parsing. three.js is an ES module that imports its core by a
//! relative path; the page maps both through an import map of `data:` URLs, the vendored
//! files otherwise untouched.
//!
//! Entry points: [`ViewSource::open`] (a run directory, a `run.json`, or a mesh file) and
//! [`write_page`].

pub mod palette;

use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};

use base64::Engine;
use base64::engine::general_purpose::STANDARD as BASE64;
use mesh_core::LabeledMesh;
use serde::Serialize;
use serde_json::Value;

/// three.js, vendored from the npm package `three` (see `assets/three/README.md`).
const THREE_MODULE: &str = include_str!("../../assets/three/three.module.js");
const THREE_CORE: &str = include_str!("../../assets/three/three.core.js");
const ORBIT_CONTROLS: &str = include_str!("../../assets/three/OrbitControls.js");
/// The viewer itself and the page around it.
const APP_JS: &str = include_str!("app.js");
const PAGE_HTML: &str = include_str!("page.html");

/// Why a page could not be made, naming the file involved.
#[derive(Debug, thiserror::Error)]
pub enum ViewError {
    /// A frame could not be read.
    #[error("cannot read frame {path}: {source}")]
    Frame {
        /// The frame file.
        path: PathBuf,
        /// What mesh-core's reader said.
        source: Box<mesh_core::io::IoError>,
    },
    /// A run record or directory could not be read.
    #[error("cannot read {path}: {message}")]
    Input {
        /// The file or directory.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// A directory holds no frames.
    #[error("{path} holds no frames (frame_*.ply, or any .ply/.obj)")]
    NoFrames {
        /// The directory.
        path: PathBuf,
    },
    /// Writing the page failed.
    #[error("cannot write the page: {0}")]
    Write(#[from] std::io::Error),
}

/// One frame of a source: the step it shows and its mesh file.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameFile {
    /// Step after which the frame was written (0: the initial mesh).
    pub step: usize,
    /// The mesh file (.ply or .obj).
    pub path: PathBuf,
}

/// What one panel of the page shows: a run's frames, its record and plots, or a lone
/// mesh file.
#[derive(Clone, Debug)]
pub struct ViewSource {
    /// Panel title (the run's scene and tracker, or the path).
    pub title: String,
    /// Frames in step order.
    pub frames: Vec<FrameFile>,
    /// The run's `run.json`, when there is one (shown per step beside the picture).
    pub record: Option<Value>,
    /// The run's SVG plots: `(file name, contents)`.
    pub plots: Vec<(String, String)>,
}

impl ViewSource {
    /// Opens a run directory (with `run.json`: its frames, record and plots; without:
    /// every `.ply`/`.obj` in name order), a `run.json`, or one mesh file.
    pub fn open(path: &Path) -> Result<ViewSource, ViewError> {
        let input_error = |message: String| ViewError::Input {
            path: path.to_path_buf(),
            message,
        };
        if path.is_file() {
            if path.file_name().is_some_and(|n| n == "run.json") {
                let dir = path.parent().unwrap_or(Path::new("."));
                return ViewSource::open_run(dir, path);
            }
            return Ok(ViewSource {
                title: path.display().to_string(),
                frames: vec![FrameFile {
                    step: 0,
                    path: path.to_path_buf(),
                }],
                record: None,
                plots: Vec::new(),
            });
        }
        if !path.is_dir() {
            return Err(input_error("no such file or directory".into()));
        }
        let record = path.join("run.json");
        if record.is_file() {
            return ViewSource::open_run(path, &record);
        }
        let mut files: Vec<PathBuf> = std::fs::read_dir(path)
            .map_err(|e| input_error(e.to_string()))?
            .filter_map(|entry| entry.ok().map(|e| e.path()))
            .filter(|p| {
                p.is_file()
                    && p.extension().is_some_and(|e| {
                        e.eq_ignore_ascii_case("ply") || e.eq_ignore_ascii_case("obj")
                    })
            })
            .collect();
        if files.is_empty() {
            return Err(ViewError::NoFrames {
                path: path.to_path_buf(),
            });
        }
        files.sort();
        Ok(ViewSource {
            title: path.display().to_string(),
            frames: files
                .into_iter()
                .enumerate()
                .map(|(step, path)| FrameFile { step, path })
                .collect(),
            record: None,
            plots: svg_plots(path),
        })
    }

    /// A run directory with its record: the frames the record lists.
    fn open_run(dir: &Path, record_path: &Path) -> Result<ViewSource, ViewError> {
        let input_error = |message: String| ViewError::Input {
            path: record_path.to_path_buf(),
            message,
        };
        let text = std::fs::read_to_string(record_path).map_err(|e| input_error(e.to_string()))?;
        let record: Value = serde_json::from_str(&text).map_err(|e| input_error(e.to_string()))?;
        let frames: Vec<FrameFile> = record["frames"]
            .as_array()
            .map(|list| {
                list.iter()
                    .filter_map(|f| {
                        Some(FrameFile {
                            step: usize::try_from(f["step"].as_u64()?).ok()?,
                            path: dir.join(f["file"].as_str()?),
                        })
                    })
                    .collect()
            })
            .unwrap_or_default();
        if frames.is_empty() {
            return Err(ViewError::NoFrames {
                path: dir.to_path_buf(),
            });
        }
        let title = match (record["scene"].as_str(), record["tracker"].as_str()) {
            (Some(scene), Some(tracker)) => format!("{scene} · {tracker} · {}", dir.display()),
            _ => dir.display().to_string(),
        };
        Ok(ViewSource {
            title,
            frames,
            record: Some(record),
            plots: svg_plots(dir),
        })
    }

    /// Keeps every `k`-th frame, always with the first and the last (k = 0 or 1: all).
    pub fn thin(&mut self, k: usize) {
        if k <= 1 || self.frames.len() <= 2 {
            return;
        }
        let last = self.frames.len() - 1;
        let mut i = 0;
        self.frames.retain(|_| {
            let keep = i % k == 0 || i == last;
            i += 1;
            keep
        });
    }
}

/// The `.svg` files of a directory, in name order (unreadable ones skipped: plots are
/// decoration, never a reason to refuse the page).
fn svg_plots(dir: &Path) -> Vec<(String, String)> {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut plots: Vec<(String, String)> = entries
        .filter_map(|e| e.ok())
        .filter(|e| e.path().extension().is_some_and(|x| x == "svg"))
        .filter_map(|e| {
            let text = std::fs::read_to_string(e.path()).ok()?;
            Some((e.file_name().to_string_lossy().into_owned(), text))
        })
        .collect();
    plots.sort();
    plots
}

/// A frame as the page receives it: f32 positions, triangles grouped by material pair.
#[derive(Clone, Debug, PartialEq)]
pub struct EncodedFrame {
    /// `x, y, z` per vertex.
    pub positions: Vec<f32>,
    /// Three vertex indices per triangle, triangles of one pair contiguous.
    pub triangles: Vec<u32>,
    /// `(lo, hi)` label pair → `(first triangle, triangle count)`, pairs ascending.
    pub pairs: Vec<PairRange>,
    /// Lower and upper corner of the frame's box.
    pub bounds: [[f64; 3]; 2],
}

/// The triangles of one material pair in an [`EncodedFrame`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct PairRange {
    /// Smaller label.
    pub lo: u32,
    /// Larger label.
    pub hi: u32,
    /// Index of the pair's first triangle.
    pub first: u32,
    /// Triangles of the pair.
    pub count: u32,
}

/// Packs a mesh for the page: live elements densely renumbered, triangles grouped by
/// unordered label pair (one draw call and one toggle per pair).
pub fn encode_frame(mesh: &LabeledMesh) -> EncodedFrame {
    let (positions, tris, labels) = mesh.to_raw();
    let mut by_pair: BTreeMap<(u32, u32), Vec<[u32; 3]>> = BTreeMap::new();
    for (t, [a, b]) in tris.iter().zip(&labels) {
        by_pair.entry((*a.min(b), *a.max(b))).or_default().push(*t);
    }
    let mut triangles = Vec::with_capacity(tris.len() * 3);
    let mut pairs = Vec::with_capacity(by_pair.len());
    for ((lo, hi), list) in by_pair {
        pairs.push(PairRange {
            lo,
            hi,
            first: (triangles.len() / 3) as u32,
            count: list.len() as u32,
        });
        triangles.extend(list.iter().flatten());
    }
    let mut bounds = [[f64::INFINITY; 3], [f64::NEG_INFINITY; 3]];
    for p in &positions {
        for (i, x) in p.to_array().into_iter().enumerate() {
            bounds[0][i] = bounds[0][i].min(x);
            bounds[1][i] = bounds[1][i].max(x);
        }
    }
    EncodedFrame {
        positions: positions
            .iter()
            .flat_map(|p| p.to_array().map(|x| x as f32))
            .collect(),
        triangles,
        pairs,
        bounds,
    }
}

/// Options of [`write_page`].
#[derive(Clone, Debug, Default)]
pub struct PageOptions {
    /// Title of the page (default: the first source's).
    pub title: Option<String>,
}

/// What a written page holds.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PageStats {
    /// Panels (sources).
    pub panels: usize,
    /// Frames over all panels.
    pub frames: usize,
    /// Triangles of the largest frame.
    pub max_triangles: usize,
    /// Bytes written.
    pub bytes: u64,
}

/// The page's description of one frame (its arrays are in the data elements).
#[derive(Serialize)]
struct FrameMeta {
    step: usize,
    file: String,
    vertices: usize,
    triangles: usize,
    pairs: Vec<PairRange>,
    bounds: [[f64; 3]; 2],
}

#[derive(Serialize)]
struct PlotMeta {
    name: String,
    /// `data:image/svg+xml;base64,…`
    src: String,
}

#[derive(Serialize)]
struct RunMeta<'a> {
    title: &'a str,
    frames: Vec<FrameMeta>,
    record: Option<&'a Value>,
    plots: Vec<PlotMeta>,
}

#[derive(Serialize)]
struct PageMeta<'a> {
    schema: &'static str,
    title: &'a str,
    runs: Vec<RunMeta<'a>>,
    /// Every pair in any frame: `[lo, hi, "#rrggbb"]`.
    pairs: Vec<(u32, u32, String)>,
    /// Every material in any frame: `[label, "#rrggbb"]`.
    materials: Vec<(u32, String)>,
}

/// Writes the page for `sources` (one panel each) to `out`, reading and encoding one
/// frame at a time so a long run never sits in memory whole.
pub fn write_page(
    sources: &[ViewSource],
    options: &PageOptions,
    out: impl Write,
) -> Result<PageStats, ViewError> {
    let mut out = CountingWriter {
        inner: std::io::BufWriter::new(out),
        bytes: 0,
    };
    let title = options
        .title
        .clone()
        .or_else(|| sources.first().map(|s| s.title.clone()))
        .unwrap_or_else(|| "surftrack view".into());
    let (head, rest) = PAGE_HTML
        .split_once("{{DATA}}")
        .expect("page.html has a {{DATA}} marker");
    let (middle, tail) = rest
        .split_once("{{META}}")
        .expect("page.html has a {{META}} marker");
    let (middle, app_tail) = middle
        .split_once("{{APP}}")
        .map_or((middle, ""), |(a, b)| (a, b));
    let head = head
        .replace("{{TITLE}}", &html_escape(&title))
        .replace("{{IMPORTMAP}}", &import_map());
    out.write_all(head.as_bytes())?;

    let mut stats = PageStats {
        panels: sources.len(),
        ..PageStats::default()
    };
    let mut pair_set = BTreeMap::new();
    let mut runs = Vec::with_capacity(sources.len());
    for (r, source) in sources.iter().enumerate() {
        let mut frames = Vec::with_capacity(source.frames.len());
        for (f, frame) in source.frames.iter().enumerate() {
            let mesh =
                mesh_core::io::read_mesh(&frame.path).map_err(|source| ViewError::Frame {
                    path: frame.path.clone(),
                    source: Box::new(source),
                })?;
            let encoded = encode_frame(&mesh);
            drop(mesh);
            write_array(
                &mut out,
                &format!("r{r}f{f}p"),
                le_bytes_f32(&encoded.positions),
            )?;
            write_array(
                &mut out,
                &format!("r{r}f{f}t"),
                le_bytes_u32(&encoded.triangles),
            )?;
            for p in &encoded.pairs {
                pair_set.insert((p.lo, p.hi), ());
            }
            let triangles = encoded.triangles.len() / 3;
            stats.frames += 1;
            stats.max_triangles = stats.max_triangles.max(triangles);
            frames.push(FrameMeta {
                step: frame.step,
                file: frame.path.display().to_string(),
                vertices: encoded.positions.len() / 3,
                triangles,
                pairs: encoded.pairs,
                bounds: encoded.bounds,
            });
        }
        runs.push(RunMeta {
            title: &source.title,
            frames,
            record: source.record.as_ref(),
            plots: source
                .plots
                .iter()
                .map(|(name, svg)| PlotMeta {
                    name: name.clone(),
                    src: format!("data:image/svg+xml;base64,{}", BASE64.encode(svg)),
                })
                .collect(),
        });
    }
    let mut materials: Vec<u32> = pair_set.keys().flat_map(|&(a, b)| [a, b]).collect();
    materials.sort_unstable();
    materials.dedup();
    let meta = PageMeta {
        schema: "surftrack.view/1",
        title: &title,
        runs,
        pairs: pair_set
            .keys()
            .map(|&(a, b)| (a, b, palette::hex(palette::pair_colour(a, b))))
            .collect(),
        materials: materials
            .into_iter()
            .map(|m| (m, palette::hex(palette::material_colour(m))))
            .collect(),
    };
    out.write_all(middle.as_bytes())?;
    out.write_all(APP_JS.as_bytes())?;
    out.write_all(app_tail.as_bytes())?;
    // `<` only occurs inside JSON strings, where `\u003c` means the same: the record's
    // messages can never close the script element.
    let json = serde_json::to_string(&meta)
        .map_err(std::io::Error::other)?
        .replace('<', "\\u003c");
    out.write_all(json.as_bytes())?;
    out.write_all(tail.as_bytes())?;
    out.inner.flush()?;
    stats.bytes = out.bytes;
    Ok(stats)
}

/// The import map that lets the untouched three.js modules find each other and the
/// viewer find them, all from `data:` URLs.
fn import_map() -> String {
    let url = |js: &str| format!("data:text/javascript;base64,{}", BASE64.encode(js));
    let module = THREE_MODULE.replace("'./three.core.js'", "'three-core'");
    let map = serde_json::json!({
        "imports": {
            "three": url(&module),
            "three-core": url(THREE_CORE),
            "three-orbit-controls": url(ORBIT_CONTROLS),
        }
    });
    map.to_string()
}

/// One array as an inert script element holding base64.
fn write_array(out: &mut impl Write, id: &str, bytes: Vec<u8>) -> std::io::Result<()> {
    write!(
        out,
        "<script type=\"application/octet-stream\" id=\"{id}\">"
    )?;
    out.write_all(BASE64.encode(bytes).as_bytes())?;
    out.write_all(b"</script>\n")
}

fn le_bytes_f32(values: &[f32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

fn le_bytes_u32(values: &[u32]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// Text for HTML element content and attribute values.
fn html_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Counts what passes through, for [`PageStats::bytes`].
struct CountingWriter<W: Write> {
    inner: W,
    bytes: u64,
}

impl<W: Write> Write for CountingWriter<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = self.inner.write(buf)?;
        self.bytes += n as u64;
        Ok(n)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

#[cfg(test)]
mod tests;
