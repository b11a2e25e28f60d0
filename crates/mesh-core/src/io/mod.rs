//! Reading and writing labelled meshes: PLY (ASCII and binary) and OBJ.
//!
//! Entry points: [`read_mesh`] / [`write_mesh`] pick the format from the file extension
//! (`.ply` or `.obj`, any case); [`read_ply`], [`write_ply`], [`read_obj`], [`write_obj`]
//! work on any reader or writer (in-memory buffers for tests and fuzzers). Errors are
//! [`IoError`]s naming the file and the element, index and line at fault; no input makes
//! these functions panic. Text (OBJ, ASCII PLY data, PLY headers) may end its lines with
//! `\n`, `\r\n` or a lone `\r`, mixed freely; line numbers count each ending once. A
//! leading UTF-8 byte-order mark is skipped.
//!
//! # Labels in PLY
//!
//! Faces carry two integer properties named exactly `label_front` and `label_back`
//! (any integer type on read, `int` on write — `uint` if a label exceeds `i32::MAX`):
//! `label_front` is the material on the side the right-hand normal `(v1−v0)×(v2−v0)` points
//! into. Vertices need `x y z` (any scalar type; written as `double`); faces need a list
//! `vertex_indices` (or `vertex_index`) of any integer types, with exactly three entries.
//! Other properties and elements are skipped, `comment` and `obj_info` lines ignored.
//! ASCII values that are read (integer-typed coordinates, list counts, indices, labels) must
//! fit their declared type ([`IoErrorKind::ValueOutOfType`]), as binary ones do by
//! construction; skipped scalar values are not parsed.
//! Binary big-endian is read and written too. Anything after the last element of an ASCII
//! file is ignored; leftover bytes after a binary file's last element are an error
//! ([`IoErrorKind::TrailingData`]), because they mean the header does not describe the data.
//!
//! # Labels in OBJ
//!
//! A run of consecutive triangles with label pair `[front, back]` is preceded by
//! `usemtl label_<front>_<back>` (e.g. `usemtl label_1_0`), so Blender and MeshLab show one
//! material per interface. The writer keeps triangle order (so ids survive a round trip)
//! and starts a new run whenever the pair changes; it writes no `.mtl` file and no `g`/`o`
//! lines. The reader assigns each face the pair of the last `usemtl label_F_B` before it;
//! material names starting with `label_` are reserved and must have that form. Other
//! material names, `g`, `o`, `s`, `vt`, `vn`, `mtllib` and unknown keywords are ignored,
//! as are extra numbers on `v` lines (`w`, colours; anything else there is an error) and
//! the texture/normal parts of face tokens (`v/vt/vn`). Negative (relative) indices are
//! resolved; faces must be triangles (`l` and `p` lines are rejected as non-triangular
//! faces). Line continuations (`\`) are not supported. Either every face has a label or
//! none has ([`IoErrorKind::MixedLabels`]). Unknown keywords are skipped, but no keyword
//! is a number: a line starting with one is an error ([`IoErrorKind::NotObjLine`]), and so
//! are data starting with the PLY magic `ply` ([`IoErrorKind::PlyInObj`]) and a file with
//! neither `v` nor `f` lines ([`IoErrorKind::NoGeometry`]), which would otherwise read as an
//! empty mesh. Vertices without faces are read (a point set).
//!
//! The OBJ reader is hand-written rather than `tobj`: `tobj` splits a file into one model
//! per material with vertices renumbered per model (so vertices shared by two label groups
//! come back as two unrelated vertices), drops unreferenced vertices, forgets `usemtl`
//! names unless an `.mtl` file defines them, reports no line numbers, and overflows on some
//! relative texture indices in debug builds. The tests use `tobj` to check that what we
//! write is ordinary OBJ.
//!
//! # Unlabelled files
//!
//! A PLY without label properties, or an OBJ without `label_` materials, is handled as
//! [`ReadOptions::unlabeled`] says; by default ([`Unlabeled::ClosedTwoMaterial`]) it must be
//! a closed, consistently oriented surface, and each connected component gets
//! `[front, back] = [0, 1]` (outward normals: inside is material 1) or `[1, 0]` if its
//! enclosed volume is negative (inward normals).
//!
//! # Coordinates
//!
//! Every finite `f64` is a valid coordinate, whatever its magnitude (1e15 and 1e-15
//! included): the readers keep the values bit for bit and leave scale to the consumer.
//! NaN and ±infinity (also decimal text that overflows to infinity, like `1e400`) are
//! [`IoErrorKind::NonFinite`] naming the vertex. Whether a tracker can work at a given
//! scale is its own typed decision (the grid backend refuses a cell size below the `f64`
//! spacing at the mesh's coordinates).
//!
//! # Writing
//!
//! Writers write the live mesh densely renumbered ([`LabeledMesh::to_raw`]). Positions are
//! written so that `f64` values read back bit-identical: binary PLY stores `double`, text
//! uses Rust's shortest round-trip formatting. Non-finite positions are refused.

mod error;
mod obj;
mod ply_header;
mod ply_read;
mod ply_write;
mod stitch;
mod text;
mod unlabeled;

#[cfg(test)]
mod fuzz_tests;
#[cfg(test)]
pub(crate) mod test_meshes;

use std::fs::File;
use std::io::{BufWriter, Read};
use std::path::Path;

use glam::DVec3;

pub use error::{EdgeProblem, Element, IoError, IoErrorKind, Location, MEMORY, TypeMismatch};
pub use obj::{read_obj, write_obj};
pub use ply_read::read_ply;
pub use ply_write::{PlyFormat, write_ply};

use crate::LabeledMesh;

/// What to do with a file that carries no labels.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Unlabeled {
    /// Require a closed, consistently oriented surface (every edge used by exactly two
    /// triangles in opposite directions; otherwise [`IoErrorKind::NotClosed`] names the
    /// first offending edge) and give each connected component `[0, 1]` if its normals point
    /// outwards, `[1, 0]` if inwards: a two-material mesh with label 1 inside.
    #[default]
    ClosedTwoMaterial,
    /// Give every triangle `[0, 1]` (normals assumed to point outwards) without any check —
    /// for inspecting open or broken surfaces; `validate` will report what is wrong.
    AssumeOutward,
    /// Refuse unlabelled files ([`IoErrorKind::Unlabeled`]).
    Error,
}

/// Options for the readers. `ReadOptions::default()` is what [`read_mesh`] uses.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ReadOptions {
    /// Treatment of files without labels.
    pub unlabeled: Unlabeled,
    /// Merge vertices at exactly the same position that lie on open edges (files that
    /// give every triangle its own vertices, as STL-style exporters do), before labels
    /// are settled, then split open edges at the open vertices lying on them, up to the
    /// rounding of stored coordinates (T-junctions, as CAD exporters leave them); a
    /// closed mesh is never changed. Off by
    /// default, so that a reader returns what the file says; the command line's repair and
    /// run commands turn it on. [`read_mesh_reported`] says how many vertices were merged
    /// and inserted.
    pub stitch: bool,
}

/// What reading changed besides parsing ([`read_mesh_reported`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ReadReport {
    /// Vertices merged into a coincident one on an open edge ([`ReadOptions::stitch`]).
    pub stitched_vertices: usize,
    /// Vertices inserted into open edges that ran past them (T-junctions, closed by
    /// splitting the edge's triangle; [`ReadOptions::stitch`]).
    pub t_junction_vertices: usize,
}

/// The file formats, chosen by extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshFormat {
    /// Stanford PLY (`.ply`).
    Ply,
    /// Wavefront OBJ (`.obj`).
    Obj,
}

impl MeshFormat {
    /// The format named by the extension of `path` (case-insensitive).
    pub fn from_path(path: &Path) -> Result<MeshFormat, IoError> {
        let extension = path
            .extension()
            .map(|e| e.to_string_lossy().into_owned())
            .unwrap_or_default();
        match extension.to_ascii_lowercase().as_str() {
            "ply" => Ok(MeshFormat::Ply),
            "obj" => Ok(MeshFormat::Obj),
            _ => Err(IoError::at_path(
                path,
                IoErrorKind::UnknownExtension { extension },
            )),
        }
    }
}

/// Reads a `.ply` or `.obj` file with default options (see [`read_mesh_with`]).
pub fn read_mesh(path: &Path) -> Result<LabeledMesh, IoError> {
    read_mesh_with(path, &ReadOptions::default())
}

/// Reads a `.ply` or `.obj` file (chosen by extension, case-insensitive). The path must
/// lead, symlinks followed, to a regular file ([`IoErrorKind::NotRegularFile`] otherwise).
pub fn read_mesh_with(path: &Path, options: &ReadOptions) -> Result<LabeledMesh, IoError> {
    read_mesh_reported(path, options).map(|(mesh, _)| mesh)
}

/// [`read_mesh_with`], also saying what reading changed (vertices stitched).
pub fn read_mesh_reported(
    path: &Path,
    options: &ReadOptions,
) -> Result<(LabeledMesh, ReadReport), IoError> {
    let format = MeshFormat::from_path(path)?;
    let bytes = read_regular_file(path)?;
    match format {
        MeshFormat::Ply => ply_read::parse_ply(&bytes),
        MeshFormat::Obj => obj::parse_obj(&bytes),
    }
    .and_then(|raw| raw.into_mesh(options))
    .map_err(|kind| IoError::at_path(path, kind))
}

/// Reads the whole file at `path`, refusing anything but a regular file (symlinks followed):
/// `/dev/zero` would fill memory without end, a FIFO or terminal could block forever. The
/// check comes before opening, because opening a FIFO already blocks until a writer appears,
/// and again on the opened handle, in case the path was replaced in between. There is no
/// size cap (real meshes run to several GB): a file memory cannot hold fails as an
/// out-of-memory I/O error when its size is reserved, before anything is read.
fn read_regular_file(path: &Path) -> Result<Vec<u8>, IoError> {
    let error = |kind| IoError::at_path(path, kind);
    let check = |meta: std::fs::Metadata| {
        if meta.is_dir() {
            Err(error(IoErrorKind::IsDirectory))
        } else if !meta.is_file() {
            Err(error(IoErrorKind::NotRegularFile))
        } else {
            Ok(meta.len())
        }
    };
    check(std::fs::metadata(path).map_err(|e| error(IoErrorKind::Io(e)))?)?;
    let mut file = File::open(path).map_err(|e| error(IoErrorKind::Io(e)))?;
    let len = check(file.metadata().map_err(|e| error(IoErrorKind::Io(e)))?)?;
    let mut bytes = Vec::new();
    bytes
        .try_reserve_exact(usize::try_from(len).unwrap_or(usize::MAX))
        .map_err(|_| error(IoErrorKind::Io(std::io::ErrorKind::OutOfMemory.into())))?;
    file.read_to_end(&mut bytes)
        .map_err(|e| error(IoErrorKind::Io(e)))?;
    Ok(bytes)
}

/// Writes a `.ply` (binary little-endian) or `.obj` file, chosen by extension.
/// The file is created or truncated.
pub fn write_mesh(mesh: &LabeledMesh, path: &Path) -> Result<(), IoError> {
    let format = MeshFormat::from_path(path)?;
    if path.is_dir() {
        return Err(IoError::at_path(path, IoErrorKind::IsDirectory));
    }
    let file = File::create(path).map_err(|e| IoError::at_path(path, IoErrorKind::Io(e)))?;
    let writer = BufWriter::with_capacity(1 << 16, file);
    match format {
        MeshFormat::Ply => write_ply(mesh, writer, PlyFormat::BinaryLittleEndian),
        MeshFormat::Obj => write_obj(mesh, writer),
    }
    .map_err(|e| e.with_path(path))
}

/// Plain arrays as read from a file, before labels are settled.
pub(crate) struct RawMesh {
    pub(crate) positions: Vec<DVec3>,
    pub(crate) tris: Vec<[u32; 3]>,
    /// `None` when the file has no labels.
    pub(crate) labels: Option<Vec<[u32; 2]>>,
}

impl RawMesh {
    /// Builds the mesh, stitching and settling missing labels as `options` say.
    pub(crate) fn into_mesh(
        mut self,
        options: &ReadOptions,
    ) -> Result<(LabeledMesh, ReadReport), IoErrorKind> {
        let (stitched_vertices, t_junction_vertices) = if options.stitch {
            match stitch::stitch_open_vertices(&mut self.positions, &mut self.tris) {
                None => (0, 0),
                Some(stitched) => (
                    stitched,
                    stitch::split_t_junctions(
                        &self.positions,
                        &mut self.tris,
                        self.labels.as_mut(),
                    ),
                ),
            }
        } else {
            (0, 0)
        };
        let check_closed =
            self.labels.is_none() && options.unlabeled == Unlabeled::ClosedTwoMaterial;
        let labels = match self.labels {
            Some(labels) => labels,
            None if options.unlabeled == Unlabeled::Error => return Err(IoErrorKind::Unlabeled),
            None => vec![[0, 1]; self.tris.len()],
        };
        let mut mesh = LabeledMesh::from_raw(self.positions, &self.tris, &labels)
            .map_err(IoErrorKind::Mesh)?;
        if check_closed {
            unlabeled::label_closed_components(&mut mesh)?;
        }
        Ok((
            mesh,
            ReadReport {
                stitched_vertices,
                t_junction_vertices,
            },
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::test_meshes::{assert_same_raw, two_tets};
    use super::*;

    fn tmp() -> tempfile::TempDir {
        tempfile::tempdir().unwrap()
    }

    #[test]
    fn round_trips_are_exact_in_every_format() {
        let mesh = two_tets();
        for format in [
            PlyFormat::Ascii,
            PlyFormat::BinaryLittleEndian,
            PlyFormat::BinaryBigEndian,
        ] {
            let mut buf = Vec::new();
            write_ply(&mesh, &mut buf, format).unwrap();
            let back = read_ply(&buf[..], &ReadOptions::default()).unwrap();
            assert_same_raw(&mesh, &back);
        }
        let mut buf = Vec::new();
        write_obj(&mesh, &mut buf).unwrap();
        let back = read_obj(&buf[..], &ReadOptions::default()).unwrap();
        assert_same_raw(&mesh, &back);
    }

    #[test]
    fn path_entry_points_dispatch_on_extension_case_insensitively() {
        let dir = tmp();
        let mesh = two_tets();
        for name in ["a.ply", "b.OBJ", "c.Ply"] {
            let path = dir.path().join(name);
            write_mesh(&mesh, &path).unwrap();
            assert_same_raw(&mesh, &read_mesh(&path).unwrap());
        }
        let head = std::fs::read(dir.path().join("a.ply")).unwrap();
        assert!(head.starts_with(b"ply\nformat binary_little_endian 1.0\n"));
    }

    #[test]
    fn path_errors_name_the_file() {
        let dir = tmp();
        let mesh = two_tets();
        let unknown = dir.path().join("mesh.stl");
        let e = write_mesh(&mesh, &unknown).unwrap_err();
        assert!(
            matches!(&e.kind, IoErrorKind::UnknownExtension { extension } if extension == "stl")
        );
        assert!(e.file.ends_with("mesh.stl"));
        let e = read_mesh(&dir.path().join("noext")).unwrap_err();
        assert!(
            matches!(&e.kind, IoErrorKind::UnknownExtension { extension } if extension.is_empty())
        );

        let as_dir = dir.path().join("folder.ply");
        std::fs::create_dir(&as_dir).unwrap();
        assert!(matches!(
            read_mesh(&as_dir).unwrap_err().kind,
            IoErrorKind::IsDirectory
        ));
        assert!(matches!(
            write_mesh(&mesh, &as_dir).unwrap_err().kind,
            IoErrorKind::IsDirectory
        ));

        // Devices are refused before reading (`/dev/zero` used to fill memory), by the path
        // a symlink points to.
        #[cfg(unix)]
        for (name, device) in [("null.ply", "/dev/null"), ("zero.obj", "/dev/zero")] {
            let link = dir.path().join(name);
            std::os::unix::fs::symlink(device, &link).unwrap();
            let e = read_mesh(&link).unwrap_err();
            assert!(matches!(e.kind, IoErrorKind::NotRegularFile), "{e}");
            assert!(e.to_string().contains(name), "{e}");
        }

        let missing = dir.path().join("nowhere").join("x.obj");
        let e = write_mesh(&mesh, &missing).unwrap_err();
        assert!(matches!(e.kind, IoErrorKind::Io(_)));
        assert!(e.to_string().contains("nowhere"));
        let e = read_mesh(&missing).unwrap_err();
        assert!(matches!(e.kind, IoErrorKind::Io(_)));

        let bad = dir.path().join("bad.ply");
        std::fs::write(
            &bad,
            b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n",
        )
        .unwrap();
        let e = read_mesh(&bad).unwrap_err();
        assert!(e.file.ends_with("bad.ply"), "{e}");
        assert!(matches!(e.kind, IoErrorKind::MissingProperty { .. }));
        let e = read_ply(&b""[..], &ReadOptions::default()).unwrap_err();
        assert_eq!(e.file, MEMORY);
        assert!(matches!(e.kind, IoErrorKind::Empty));
    }

    #[test]
    fn unlabeled_policies() {
        // A closed outward tetrahedron as PLY without labels.
        let ply = b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
element face 4\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n\
3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n";
        let closed = read_ply(&ply[..], &ReadOptions::default()).unwrap();
        assert_eq!(closed.to_raw().2, vec![[0, 1]; 4]);
        let error = ReadOptions {
            unlabeled: Unlabeled::Error,
            ..ReadOptions::default()
        };
        assert!(matches!(
            read_ply(&ply[..], &error).unwrap_err().kind,
            IoErrorKind::Unlabeled
        ));
        // Open (3 faces): an error by default, accepted as [0, 1] when asked.
        let open = &ply[..ply.len() - "3 0 3 2\n".len()];
        let open = String::from_utf8_lossy(open).replace("element face 4", "element face 3");
        let e = read_ply(open.as_bytes(), &ReadOptions::default()).unwrap_err();
        assert!(
            matches!(
                e.kind,
                IoErrorKind::NotClosed {
                    edge: [0, 2],
                    problem: EdgeProblem::Boundary
                }
            ),
            "{e}"
        );
        let assume = ReadOptions {
            unlabeled: Unlabeled::AssumeOutward,
            ..ReadOptions::default()
        };
        assert_eq!(
            read_ply(open.as_bytes(), &assume).unwrap().to_raw().2,
            vec![[0, 1]; 3]
        );
    }

    #[test]
    fn stitching_reads_a_triangle_soup_as_the_closed_solid() {
        // The outward tetrahedron of `unlabeled_policies`, every face on its own vertices
        // (as STL-style exporters write it), unlabelled OBJ.
        let corners = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ];
        let faces = [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]];
        let mut obj = String::new();
        for (k, f) in faces.iter().enumerate() {
            for &v in f {
                let [x, y, z] = corners[v];
                obj += &format!("v {x} {y} {z}\n");
            }
            obj += &format!("f {} {} {}\n", 3 * k + 1, 3 * k + 2, 3 * k + 3);
        }
        let dir = tmp();
        let path = dir.path().join("soup.obj");
        std::fs::write(&path, &obj).unwrap();
        // As written, every edge is open.
        let e = read_mesh(&path).unwrap_err();
        assert!(
            matches!(
                e.kind,
                IoErrorKind::NotClosed {
                    problem: EdgeProblem::Boundary,
                    ..
                }
            ),
            "{e}"
        );
        // Stitched: the closed tetrahedron, inside 1, with its 4 vertices.
        let stitch = ReadOptions {
            stitch: true,
            ..ReadOptions::default()
        };
        let (mesh, report) = read_mesh_reported(&path, &stitch).unwrap();
        assert_eq!(report.stitched_vertices, 12 - 4);
        let (positions, tris, labels) = mesh.to_raw();
        assert_eq!(positions.len(), 4);
        assert_eq!(labels, vec![[0, 1]; 4]);
        assert_eq!(tris, vec![[0, 1, 2], [0, 2, 3], [2, 1, 3], [0, 3, 1]]);
        assert!(crate::validate::validate(&mesh, &Default::default()).is_valid());
    }

    #[test]
    fn stitching_closes_a_t_junction_of_a_labelled_cad_style_file() {
        // The unit cube whose front face is a fan through the midpoint of its top edge,
        // which the top face's edge runs past (each face meshed on its own), labelled
        // PLY: the split triangle keeps its labels.
        let p = "0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n1 1 1\n0 1 1\n0.5 0 1\n";
        let faces = [
            [0, 2, 1],
            [0, 3, 2],
            [4, 5, 6],
            [4, 6, 7],
            [1, 2, 6],
            [1, 6, 5],
            [0, 7, 3],
            [0, 4, 7],
            [3, 7, 6],
            [3, 6, 2],
            [0, 1, 8],
            [1, 5, 8],
            [8, 4, 0],
        ];
        let mut ply = format!(
            "ply\nformat ascii 1.0\nelement vertex 9\nproperty double x\nproperty double y\n\
             property double z\nelement face {}\nproperty list uchar int vertex_indices\n\
             property int label_front\nproperty int label_back\nend_header\n{p}",
            faces.len()
        );
        for f in faces {
            ply += &format!("3 {} {} {} 0 2\n", f[0], f[1], f[2]);
        }
        let dir = tmp();
        let path = dir.path().join("tj.ply");
        std::fs::write(&path, &ply).unwrap();
        let as_written = read_mesh(&path).unwrap();
        assert_eq!(
            crate::validate::validate(&as_written, &Default::default())
                .boundary_edges
                .count,
            3
        );
        let stitch = ReadOptions {
            stitch: true,
            ..ReadOptions::default()
        };
        let (mesh, report) = read_mesh_reported(&path, &stitch).unwrap();
        assert_eq!(
            (report.stitched_vertices, report.t_junction_vertices),
            (0, 1)
        );
        assert_eq!(mesh.num_triangles(), 14);
        assert!(
            mesh.triangles()
                .all(|t| mesh.labels(t) == [crate::Label::OUTSIDE, crate::Label::new(2)])
        );
        assert!(crate::validate::validate(&mesh, &Default::default()).is_valid());
        let volume = crate::geometry::label_volumes(&mesh)[&crate::Label::new(2)];
        assert!((volume - 1.0).abs() < 1e-12, "{volume}");
    }
}
