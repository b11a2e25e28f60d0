//! Errors of mesh reading and writing.
//!
//! Every error is an [`IoError`]: the file it concerns (its path, or `<memory>` for the
//! reader/writer-level functions) plus an [`IoErrorKind`] that says what went wrong and,
//! through a [`Location`], where — the element (`header`, `vertex`, `face`, or a skipped PLY
//! element), its 0-based index and, for text, its 1-based line. A user with a broken file
//! in a 10 GB data set should be able to open it at the right line from the message alone.

use std::fmt;
use std::path::Path;

use crate::error::MeshError;

/// The name used for data that did not come from a named file.
pub const MEMORY: &str = "<memory>";

/// The kind of record an error points at.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Element {
    /// The PLY header.
    Header,
    /// A vertex (PLY `vertex` element or OBJ `v` line).
    Vertex,
    /// A face (PLY `face` element or OBJ `f`/`l`/`p` line).
    Face,
    /// Any other line of a text file (OBJ keyword lines, `usemtl`).
    Line,
    /// A PLY element the reader skips, named as in the header.
    Other(String),
}

impl fmt::Display for Element {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Element::Header => f.write_str("header"),
            Element::Vertex => f.write_str("vertex"),
            Element::Face => f.write_str("face"),
            Element::Line => f.write_str("line"),
            Element::Other(name) => write!(f, "element `{name}`"),
        }
    }
}

/// Where in a file an error was found.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Location {
    /// What kind of record.
    pub element: Element,
    /// 0-based index among the records of that kind (`None` for header lines).
    pub index: Option<u64>,
    /// 1-based line number, for text data and headers (`None` in binary data).
    pub line: Option<u64>,
}

impl Location {
    /// A header line.
    pub fn header(line: u64) -> Self {
        Location {
            element: Element::Header,
            index: None,
            line: Some(line),
        }
    }

    /// An indexed element, with its line when the data is text.
    pub fn element(element: Element, index: u64, line: Option<u64>) -> Self {
        Location {
            element,
            index: Some(index),
            line,
        }
    }

    /// A text line that is neither a vertex nor a face.
    pub fn line(line: u64) -> Self {
        Location {
            element: Element::Line,
            index: None,
            line: Some(line),
        }
    }
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (&self.element, self.index, self.line) {
            (Element::Line, _, Some(line)) => write!(f, "line {line}"),
            (e, Some(i), Some(line)) => write!(f, "{e} {i} (line {line})"),
            (e, Some(i), None) => write!(f, "{e} {i}"),
            (e, None, Some(line)) => write!(f, "{e} line {line}"),
            (e, None, None) => write!(f, "{e}"),
        }
    }
}

/// Why an unlabelled mesh is not a closed, consistently oriented surface.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EdgeProblem {
    /// Only one triangle uses the edge: the surface is open.
    Boundary,
    /// More than two triangles use the edge: inside and outside are ambiguous.
    NonManifold {
        /// How many triangles use it.
        triangles: usize,
    },
    /// Both triangles traverse the edge in the same direction: their normals disagree.
    Inconsistent,
    /// The edge joins a vertex to itself (a triangle repeats a vertex).
    Degenerate,
}

impl fmt::Display for EdgeProblem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            EdgeProblem::Boundary => f.write_str("used by only one triangle (open surface)"),
            EdgeProblem::NonManifold { triangles } => {
                write!(f, "used by {triangles} triangles (not manifold)")
            }
            EdgeProblem::Inconsistent => f.write_str(
                "traversed in the same direction by both triangles (inconsistent orientation)",
            ),
            EdgeProblem::Degenerate => {
                f.write_str("joins a vertex to itself (degenerate triangle)")
            }
        }
    }
}

/// What went wrong reading or writing a mesh file (see [`IoError`] for the file name).
#[derive(Debug, thiserror::Error)]
pub enum IoErrorKind {
    /// The operating system refused or failed a read or write.
    #[error("I/O error: {0}")]
    Io(#[source] std::io::Error),
    /// A directory was given where a file was expected.
    #[error("is a directory, not a file")]
    IsDirectory,
    /// The path (symlinks followed) is a device, FIFO or socket, not a regular file: reading
    /// `/dev/zero` would fill memory without end, a FIFO could block forever.
    #[error("is not a regular file (a device, FIFO or socket)")]
    NotRegularFile,
    /// The file name does not end in `.ply` or `.obj` (case-insensitive).
    #[error("unknown mesh format extension {extension:?} (expected .ply or .obj)")]
    UnknownExtension {
        /// The extension found (empty if none).
        extension: String,
    },
    /// The input holds no data (or only whitespace).
    #[error("file is empty")]
    Empty,
    /// Data read as OBJ starts with the PLY magic line `ply`. Refused rather than read as
    /// PLY: the format follows the extension (or the reader called) everywhere, writing
    /// included, so a mislabelled file is a mix-up upstream that the user should see and
    /// fix by renaming, not a guess this reader should make.
    #[error("this is a PLY file (it starts with `ply`), not OBJ: rename it to .ply")]
    PlyInObj,
    /// An OBJ line starts with a number. Unknown OBJ keywords are ignored, but no keyword
    /// is a number: such a line means the data is not OBJ (or a line break went missing).
    #[error("{at}: starts with the number {token:?}, which is no OBJ keyword")]
    NotObjLine {
        /// The line.
        at: Location,
        /// The first token (shortened).
        token: String,
    },
    /// An OBJ file holds neither `v` nor `f` lines: whatever it is, it describes no mesh.
    #[error("no `v` or `f` lines: nothing to read as an OBJ mesh")]
    NoGeometry,
    /// The input does not start with the line `ply`.
    #[error("not a PLY file: the first line must be `ply`")]
    BadMagic,
    /// A header line is not valid UTF-8.
    #[error("{at}: header is not valid UTF-8")]
    NotUtf8 {
        /// The header line.
        at: Location,
    },
    /// The header is malformed or uses something this reader does not support.
    #[error("{at}: {reason}")]
    BadHeader {
        /// The header line.
        at: Location,
        /// What is wrong with it.
        reason: String,
    },
    /// A required PLY element or property is missing from the header.
    #[error("header has no {what}")]
    MissingProperty {
        /// E.g. "`vertex` property `x`".
        what: &'static str,
    },
    /// Only one of `label_front` / `label_back` is declared: labels would be half-known.
    #[error("header declares face property `{present}` but not `{missing}`")]
    MissingLabelProperty {
        /// The label property that is declared.
        present: &'static str,
        /// The one that is not.
        missing: &'static str,
    },
    /// The header declares more elements than the remaining bytes could possibly hold.
    #[error(
        "header declares {declared} `{element}` elements, but only {bytes_left} bytes of data follow"
    )]
    DeclaredCountTooLarge {
        /// The element name.
        element: String,
        /// The declared count.
        declared: u64,
        /// Bytes after the header.
        bytes_left: u64,
    },
    /// The data ends inside this element (fewer elements than declared, or a cut file).
    #[error("{at}: unexpected end of data")]
    Truncated {
        /// The element being read.
        at: Location,
    },
    /// A text line holds fewer values than its element's properties need.
    #[error("{at}: too few values on the line")]
    MissingValues {
        /// The element.
        at: Location,
    },
    /// A text line holds more values than its element's properties declare.
    #[error("{at}: more values on the line than the header declares")]
    ExtraValues {
        /// The element.
        at: Location,
    },
    /// Binary data continues after the last declared element: the header counts or types
    /// do not describe the data.
    #[error("{bytes} bytes of binary data follow the last declared element")]
    TrailingData {
        /// How many bytes are left over.
        bytes: u64,
    },
    /// A value is not a number of the expected kind.
    #[error("{at}: cannot parse {token:?} as a number")]
    BadValue {
        /// The element.
        at: Location,
        /// The offending text (shortened).
        token: String,
    },
    /// An ASCII PLY value does not fit the integer type its property declares (257 in a
    /// `uchar`, 2.5 in an `int`). Binary values fit by construction; text must too, or a
    /// file would mean something else once written back in binary.
    /// Boxed: it is the largest kind and rare, and every `Result` carrying an error pays for
    /// the largest one.
    #[error("{0}")]
    ValueOutOfType(Box<TypeMismatch>),
    /// A face does not have exactly three vertices.
    #[error("{at}: face has {vertices} vertices; only triangles are supported")]
    NonTriangle {
        /// The face.
        at: Location,
        /// Its vertex count as declared.
        vertices: i64,
    },
    /// A face refers to a vertex that does not exist.
    #[error("{at}: vertex index {index} out of range (the file has {vertex_count} vertices)")]
    IndexOutOfRange {
        /// The face.
        at: Location,
        /// The offending index as the file writes it: 0-based in PLY; in OBJ 1-based, or
        /// negative (counting back from the last vertex read).
        index: i64,
        /// The number of vertices.
        vertex_count: u64,
    },
    /// A coordinate is NaN or infinite (on read, or in a mesh being written).
    #[error("{at}: coordinate {value} is not finite")]
    NonFinite {
        /// The vertex.
        at: Location,
        /// The offending value.
        value: f64,
    },
    /// A label is negative or does not fit the `u32` label space.
    #[error("{at}: label {value} is out of range (0..=4294967294)")]
    LabelOutOfRange {
        /// The face, or the OBJ `usemtl` line.
        at: Location,
        /// The offending value.
        value: i64,
    },
    /// An OBJ material name starts with the reserved prefix `label_` but is not
    /// `label_<front>_<back>`.
    #[error("{at}: material name {name:?} starts with `label_` but is not `label_<front>_<back>`")]
    BadLabelName {
        /// The `usemtl` line.
        at: Location,
        /// The material name (shortened).
        name: String,
    },
    /// Some OBJ faces carry labels and this one does not.
    #[error("{at}: face has no `usemtl label_<front>_<back>` although other faces do")]
    MixedLabels {
        /// The first unlabelled face.
        at: Location,
    },
    /// The file carries no labels and the read options forbid unlabelled input.
    #[error("file carries no labels (ReadOptions::unlabeled is Unlabeled::Error)")]
    Unlabeled,
    /// An unlabelled file is not a closed, consistently oriented surface, so inside and
    /// outside cannot be told apart.
    #[error("unlabelled mesh: edge ({}, {}) is {problem}", edge[0], edge[1])]
    NotClosed {
        /// The first offending edge in `(lower, higher)` vertex-index order (0-based).
        edge: [u32; 2],
        /// What is wrong with it.
        problem: EdgeProblem,
    },
    /// The arrays read are not a valid [`crate::LabeledMesh`] (e.g. too many elements).
    #[error("{0}")]
    Mesh(#[source] MeshError),
}

/// A value that does not fit its declared PLY type ([`IoErrorKind::ValueOutOfType`]).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{at}: property `{property}` is declared {ty} but holds {value}, which does not fit")]
pub struct TypeMismatch {
    /// The element.
    pub at: Location,
    /// The property (for a list, its count or items).
    pub property: String,
    /// The declared type, as PLY names it (`uchar`, `int`, …).
    pub ty: &'static str,
    /// The value as written (shortened).
    pub value: String,
}

/// An error reading or writing a mesh: which file, and what went wrong where.
#[derive(Debug, thiserror::Error)]
#[error("{file}: {kind}")]
pub struct IoError {
    /// The file path, or `<memory>` for in-memory readers and writers.
    pub file: String,
    /// What went wrong, and where.
    pub kind: IoErrorKind,
}

impl IoError {
    /// An error about in-memory data.
    pub fn memory(kind: IoErrorKind) -> Self {
        IoError {
            file: MEMORY.to_owned(),
            kind,
        }
    }

    /// An error about the file at `path`.
    pub fn at_path(path: &Path, kind: IoErrorKind) -> Self {
        IoError {
            file: path.display().to_string(),
            kind,
        }
    }

    /// The same error, attributed to the file at `path` (used when a path-level entry point
    /// delegates to a reader-level one).
    pub fn with_path(self, path: &Path) -> Self {
        Self::at_path(path, self.kind)
    }
}

impl From<std::io::Error> for IoErrorKind {
    fn from(e: std::io::Error) -> Self {
        IoErrorKind::Io(e)
    }
}

/// Shortens untrusted text for an error message (lossy UTF-8, at most 40 characters), so a
/// megabyte-long garbage token cannot flood a log.
pub(crate) fn shown(bytes: &[u8]) -> String {
    const MAX: usize = 40;
    let text = String::from_utf8_lossy(&bytes[..bytes.len().min(MAX * 4)]);
    let mut out: String = text.chars().take(MAX).collect();
    if text.chars().count() > MAX || bytes.len() > MAX * 4 {
        out.push('…');
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_name_file_element_index_and_line() {
        let e = IoError::memory(IoErrorKind::NonFinite {
            at: Location::element(Element::Vertex, 3, Some(12)),
            value: f64::NAN,
        });
        assert_eq!(
            e.to_string(),
            "<memory>: vertex 3 (line 12): coordinate NaN is not finite"
        );
        let e = IoError::at_path(
            Path::new("a/b.ply"),
            IoErrorKind::Truncated {
                at: Location::element(Element::Face, 7, None),
            },
        );
        assert_eq!(e.to_string(), "a/b.ply: face 7: unexpected end of data");
        let e = IoError::memory(IoErrorKind::NotClosed {
            edge: [2, 5],
            problem: EdgeProblem::Boundary,
        });
        assert!(
            e.to_string()
                .contains("edge (2, 5) is used by only one triangle")
        );
        assert_eq!(Location::header(4).to_string(), "header line 4");
    }

    #[test]
    fn shown_truncates_long_garbage() {
        assert_eq!(shown(b"abc"), "abc");
        let long = vec![b'x'; 1000];
        let s = shown(&long);
        assert_eq!(s.chars().count(), 41);
        assert!(s.ends_with('…'));
        assert_eq!(shown(&[0xff, b'a']), "\u{fffd}a");
    }
}
