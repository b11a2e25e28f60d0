//! Pictures of frames for the reports: PNGs drawn off-screen, without a browser, by
//! tiny-skia (filled triangles sorted back to front: the painter's algorithm), coloured
//! by material pair as in `surftrack view` ([`crate::view::palette`]).
//!
//! Every picture of one report uses one [`Camera`], fitted to all the frames it shows, so
//! variants compare at a glance: the same direction ([`VIEW_DIRECTION`], the page's
//! initial view too), the same scale. A cut-away drops the triangles above the plane
//! z = box centre (the half nearer the camera), showing interior walls.
//!
//! Output is deterministic: a stable sort with an index tie-break and no anti-aliasing,
//! so the same frames make the same bytes (the tests compare them).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use glam::DVec3;
use mesh_core::LabeledMesh;
use mesh_core::broadphase::Aabb;
use tiny_skia::{Color, FillRule, Paint, PathBuilder, Pixmap, Transform};

use crate::record::RunRecord;
use crate::view::palette::pair_colour;

/// From the scene towards the camera (y up), shared with the page's initial view.
pub const VIEW_DIRECTION: DVec3 = DVec3::new(1.0, 0.8, 1.6);

/// Size of a report picture, pixels.
pub const PICTURE_SIZE: (u32, u32) = (320, 240);

/// The background, white as the page's.
const BACKGROUND: [u8; 3] = [255, 255, 255];

/// Why a picture could not be made.
#[derive(Debug, thiserror::Error)]
pub enum PictureError {
    /// Zero or absurd width or height.
    #[error("cannot make a {width}×{height} picture")]
    Size {
        /// Requested width.
        width: u32,
        /// Requested height.
        height: u32,
    },
    /// PNG encoding failed.
    #[error("cannot encode the PNG: {0}")]
    Encode(String),
    /// A frame could not be read.
    #[error("cannot read frame {path}: {source}")]
    Frame {
        /// The frame.
        path: PathBuf,
        /// mesh-core's error.
        source: Box<mesh_core::io::IoError>,
    },
    /// A picture could not be written.
    #[error("cannot write {path}: {source}")]
    Write {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
}

/// An orthographic camera looking along −[`VIEW_DIRECTION`] at a box's centre, framing
/// the box's bounding sphere whatever its orientation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    centre: DVec3,
    radius: f64,
    right: DVec3,
    up: DVec3,
    towards: DVec3,
}

impl Camera {
    /// Frames `bounds` (an empty or non-finite box frames the unit cube).
    pub fn fit(bounds: Aabb) -> Camera {
        Camera::fit_looking(bounds, VIEW_DIRECTION)
    }

    /// [`Camera::fit`] seen from `direction` (from the scene towards the camera) instead
    /// of [`VIEW_DIRECTION`]; a zero, non-finite or vertical direction falls back to it.
    pub fn fit_looking(bounds: Aabb, direction: DVec3) -> Camera {
        let ok =
            bounds.min.is_finite() && bounds.max.is_finite() && bounds.min.cmple(bounds.max).all();
        let (min, max) = if ok {
            (bounds.min, bounds.max)
        } else {
            (DVec3::splat(-1.0), DVec3::splat(1.0))
        };
        let towards = direction.normalize_or_zero();
        let towards = if towards.is_finite() && towards.cross(DVec3::Y).length() > 1e-6 {
            towards
        } else {
            VIEW_DIRECTION.normalize()
        };
        let right = DVec3::Y.cross(towards).normalize();
        let up = towards.cross(right);
        Camera {
            centre: (min + max) / 2.0,
            radius: ((max - min).length() / 2.0).max(1e-12),
            right,
            up,
            towards,
        }
    }

    /// Whether `p` lies in the half [`render`]'s cut-away drops.
    fn beyond_cut(&self, p: DVec3) -> bool {
        let axis = self.towards.abs().max_position();
        (p[axis] - self.centre[axis]) * self.towards[axis].signum() > 0.0
    }

    /// Pixel coordinates and depth (larger: nearer the camera) of `p`.
    fn project(&self, p: DVec3, width: u32, height: u32) -> (f32, f32, f64) {
        let d = p - self.centre;
        let scale = f64::from(width.min(height)) / (2.1 * self.radius);
        let x = f64::from(width) / 2.0 + d.dot(self.right) * scale;
        let y = f64::from(height) / 2.0 - d.dot(self.up) * scale;
        (x as f32, y as f32, d.dot(self.towards))
    }
}

/// The box around the live vertices of `meshes`.
pub fn bounds_of<'a>(meshes: impl IntoIterator<Item = &'a LabeledMesh>) -> Aabb {
    meshes.into_iter().fold(Aabb::EMPTY, |b, m| {
        m.vertices().fold(b, |b, v| b.including(m.position(v)))
    })
}

/// Renders `mesh` seen by `camera`; with `cut_away`, the half nearer the camera is left
/// out: the triangles beyond the plane through the centre across the view direction's
/// dominant axis (z = centre for [`VIEW_DIRECTION`] — the page's default cut plane too).
pub fn render(
    mesh: &LabeledMesh,
    camera: &Camera,
    width: u32,
    height: u32,
    cut_away: bool,
) -> Result<Pixmap, PictureError> {
    if width == 0 || height == 0 || width > 8192 || height > 8192 {
        return Err(PictureError::Size { width, height });
    }
    let mut pixmap = Pixmap::new(width, height).ok_or(PictureError::Size { width, height })?;
    pixmap.fill(Color::from_rgba8(
        BACKGROUND[0],
        BACKGROUND[1],
        BACKGROUND[2],
        255,
    ));
    let light = (camera.towards + 0.4 * camera.up + 0.2 * camera.right).normalize();
    // (depth, triangle index, screen corners, colour): sorted far to near.
    type Face = (f64, usize, [(f32, f32); 3], [u8; 3]);
    let mut faces: Vec<Face> = Vec::new();
    for (i, t) in mesh.triangles().enumerate() {
        let p = mesh.tri_positions(t);
        let centroid = (p[0] + p[1] + p[2]) / 3.0;
        if !centroid.is_finite() || (cut_away && camera.beyond_cut(centroid)) {
            continue;
        }
        let corners = p.map(|q| camera.project(q, width, height));
        let xs = corners.map(|c| c.0);
        let ys = corners.map(|c| c.1);
        let span = |v: [f32; 3]| {
            v.iter().fold(f32::MIN, |a, &b| a.max(b)) - v.iter().fold(f32::MAX, |a, &b| a.min(b))
        };
        // Edge-on triangles cover no pixel; tiny-skia would refuse them with a warning.
        if span(xs) < 1e-3 || span(ys) < 1e-3 {
            continue;
        }
        let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
        let shade = 0.35 + 0.65 * n.dot(light).abs();
        let [a, b] = mesh.labels(t).map(|l| l.raw());
        let colour =
            pair_colour(a, b).map(|c| (f64::from(c) * shade).round().clamp(0.0, 255.0) as u8);
        let depth = corners.iter().map(|c| c.2).sum::<f64>() / 3.0;
        faces.push((depth, i, corners.map(|c| (c.0, c.1)), colour));
    }
    faces.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    let mut paint = Paint {
        anti_alias: false,
        ..Paint::default()
    };
    for (_, _, c, colour) in &faces {
        let mut path = PathBuilder::new();
        path.move_to(c[0].0, c[0].1);
        path.line_to(c[1].0, c[1].1);
        path.line_to(c[2].0, c[2].1);
        path.close();
        if let Some(path) = path.finish() {
            paint.set_color_rgba8(colour[0], colour[1], colour[2], 255);
            pixmap.fill_path(
                &path,
                &paint,
                FillRule::Winding,
                Transform::identity(),
                None,
            );
        }
    }
    Ok(pixmap)
}

/// [`render`], encoded as PNG.
pub fn render_png(
    mesh: &LabeledMesh,
    camera: &Camera,
    width: u32,
    height: u32,
    cut_away: bool,
) -> Result<Vec<u8>, PictureError> {
    render(mesh, camera, width, height, cut_away)?
        .encode_png()
        .map_err(|e| PictureError::Encode(e.to_string()))
}

/// One run to picture in a report: a label for its row and its directory (with
/// `run.json`).
#[derive(Clone, Debug)]
pub struct PicturedRun {
    /// Row label (variant, tracker, scene …).
    pub label: String,
    /// The run's directory.
    pub dir: PathBuf,
}

/// The first and last frames a run's record lists, read; `None` when it has none.
fn end_frames(dir: &Path) -> Result<Option<[(usize, LabeledMesh); 2]>, PictureError> {
    let Ok(text) = std::fs::read_to_string(dir.join("run.json")) else {
        return Ok(None);
    };
    let Ok(record) = serde_json::from_str::<RunRecord>(&text) else {
        return Ok(None);
    };
    let (Some(first), Some(last)) = (record.frames.first(), record.frames.last()) else {
        return Ok(None);
    };
    let read = |file: &str| {
        let path = dir.join(file);
        mesh_core::io::read_mesh(&path).map_err(|source| PictureError::Frame {
            path,
            source: Box::new(source),
        })
    };
    Ok(Some([
        (first.step, read(&first.file)?),
        (last.step, read(&last.file)?),
    ]))
}

/// Renders the first frame, the last and a cut-away of the last of every run into
/// `out/pictures/`, all with one camera, and returns the markdown section showing them
/// (empty when no run has frames). Runs without frames get a row saying so.
pub fn pictures_section(runs: &[PicturedRun], out: &Path) -> Result<String, PictureError> {
    let mut loaded = Vec::with_capacity(runs.len());
    for run in runs {
        loaded.push((run, end_frames(&run.dir)?));
    }
    if loaded.iter().all(|(_, f)| f.is_none()) {
        return Ok(String::new());
    }
    let camera = Camera::fit(bounds_of(
        loaded
            .iter()
            .filter_map(|(_, f)| f.as_ref())
            .flat_map(|[a, b]| [&a.1, &b.1]),
    ));
    let dir = out.join("pictures");
    std::fs::create_dir_all(&dir).map_err(|source| PictureError::Write {
        path: dir.clone(),
        source,
    })?;
    let (w, h) = PICTURE_SIZE;
    let mut md = String::from(
        "\n## Pictures\n\nFirst and last frame and a cut-away of the last (everything above the \
         box centre's z removed), one camera for all; colours by material pair as in `surftrack view`.\n\n\
         | run | first | last | cut-away |\n|---|---|---|---|\n",
    );
    for (i, (run, frames)) in loaded.iter().enumerate() {
        let Some([(s0, first), (s1, last)]) = frames else {
            let _ = writeln!(md, "| {} | no frames | | |", run.label);
            continue;
        };
        let mut cells = Vec::with_capacity(3);
        for (name, mesh, cut, step) in [
            ("first", first, false, s0),
            ("last", last, false, s1),
            ("cut", last, true, s1),
        ] {
            let file = format!("{i:02}-{}-{name}.png", slug(&run.label));
            let png = render_png(mesh, &camera, w, h, cut)?;
            let path = dir.join(&file);
            std::fs::write(&path, png).map_err(|source| PictureError::Write {
                path: path.clone(),
                source,
            })?;
            cells.push(format!(
                "![{} {name}, step {step}](pictures/{file})",
                run.label
            ));
        }
        let _ = writeln!(md, "| {} | {} |", run.label, cells.join(" | "));
    }
    Ok(md)
}

/// A file-name piece: `[A-Za-z0-9._-]` kept, everything else `_`.
fn slug(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        let c = if c.is_ascii_alphanumeric() || ".-".contains(c) {
            c
        } else {
            '_'
        };
        if !(c == '_' && out.ends_with('_')) {
            out.push(c);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use mesh_core::generators::double_bubble;

    /// Pixels of `pixmap` whose chromaticity is nearest that of `colour`, among the
    /// pair colours of a two-bubble scene and the background.
    fn count_colour(pixmap: &Pixmap, colour: [u8; 3]) -> usize {
        let chroma = |c: [u8; 3]| {
            let s = f64::from(c[0]) + f64::from(c[1]) + f64::from(c[2]) + 1e-9;
            [f64::from(c[0]) / s, f64::from(c[1]) / s]
        };
        let target = chroma(colour);
        pixmap
            .pixels()
            .iter()
            .filter(|p| {
                let c = chroma([p.red(), p.green(), p.blue()]);
                [p.red(), p.green(), p.blue()] != BACKGROUND
                    && (c[0] - target[0]).hypot(c[1] - target[1]) < 0.02
            })
            .count()
    }

    fn bubbles() -> LabeledMesh {
        double_bubble(0.5, 16).unwrap()
    }

    #[test]
    fn a_picture_shows_each_material_colour_and_is_deterministic() {
        let mesh = bubbles();
        let camera = Camera::fit(bounds_of([&mesh]));
        let pixmap = render(&mesh, &camera, 320, 240, false).unwrap();
        let total = (320 * 240) as usize;
        let background = pixmap
            .pixels()
            .iter()
            .filter(|p| [p.red(), p.green(), p.blue()] == BACKGROUND)
            .count();
        assert!(
            background < total * 9 / 10 && background > total / 10,
            "the mesh covers part of the picture: {background} of {total} background"
        );
        let one = count_colour(&pixmap, pair_colour(0, 1));
        let two = count_colour(&pixmap, pair_colour(0, 2));
        assert!(
            one > total / 50 && two > total / 50,
            "materials 1 and 2 show: {one}, {two}"
        );
        let png = render_png(&mesh, &camera, 320, 240, false).unwrap();
        assert_eq!(&png[1..4], b"PNG");
        assert_eq!(u32::from_be_bytes(png[16..20].try_into().unwrap()), 320);
        assert_eq!(u32::from_be_bytes(png[20..24].try_into().unwrap()), 240);
        assert_eq!(png, render_png(&mesh, &camera, 320, 240, false).unwrap());
    }

    #[test]
    fn a_cut_away_reveals_the_wall_between_the_bubbles() {
        let mesh = bubbles();
        let camera = Camera::fit(bounds_of([&mesh]));
        let whole = render(&mesh, &camera, 320, 240, false).unwrap();
        let cut = render(&mesh, &camera, 320, 240, true).unwrap();
        let wall = pair_colour(1, 2);
        assert!(
            count_colour(&cut, wall) > 4 * count_colour(&whole, wall).max(50),
            "the interior wall shows in the cut-away: {} vs {}",
            count_colour(&cut, wall),
            count_colour(&whole, wall)
        );
    }

    #[test]
    fn one_camera_keeps_scale_across_frames() {
        let small = bubbles();
        let mut big = small.clone();
        for p in big.positions_mut() {
            *p *= 2.0;
        }
        let camera = Camera::fit(bounds_of([&small, &big]));
        let covered = |m: &LabeledMesh| {
            let pixmap = render(m, &camera, 200, 200, false).unwrap();
            pixmap
                .pixels()
                .iter()
                .filter(|p| [p.red(), p.green(), p.blue()] != BACKGROUND)
                .count() as f64
        };
        let ratio = covered(&big) / covered(&small);
        assert!(
            (3.0..5.0).contains(&ratio),
            "twice the size, four times the area: {ratio}"
        );
        assert!(matches!(
            render(&small, &camera, 0, 10, false),
            Err(PictureError::Size { .. })
        ));
    }
}
