//! Reading PLY data (ASCII, binary little- and big-endian) into plain arrays.
//!
//! The header is compiled into one [`Role`] per property; the data section is then read by
//! one generic loop over a [`Source`] — ASCII lines or a binary cursor — so both encodings
//! share every check (triangles only, indices in range, finite coordinates, labels in
//! range) and every unknown property or element is skipped by the same code. The whole
//! input is in memory, which makes "bytes left" known: declared counts the data cannot
//! hold are rejected before anything is allocated for them.

use std::io::Read;

use glam::DVec3;

use super::error::{Element, IoError, IoErrorKind, Location, TypeMismatch, shown};
use super::ply_header::{ElementDecl, Encoding, Header, PropKind, Property, Scalar, parse_header};
use super::text::{Lines, Tokens, is_blank, parse_float, parse_int, strip_bom};
use super::{RawMesh, ReadOptions};
use crate::LabeledMesh;
use crate::error::MeshError;
use crate::ids::MAX_INDEX;

/// Reads a PLY mesh (any encoding) from a reader. See the [module docs](super) for the
/// properties recognised and how unlabelled files are treated. Errors name `<memory>` as
/// the file; [`super::read_mesh`] names the path instead.
pub fn read_ply(mut reader: impl Read, options: &ReadOptions) -> Result<LabeledMesh, IoError> {
    let mut bytes = Vec::new();
    reader
        .read_to_end(&mut bytes)
        .map_err(|e| IoError::memory(IoErrorKind::Io(e)))?;
    ply_from_bytes(&bytes, options).map_err(IoError::memory)
}

/// Reads a PLY mesh from bytes in memory.
pub(crate) fn ply_from_bytes(
    bytes: &[u8],
    options: &ReadOptions,
) -> Result<LabeledMesh, IoErrorKind> {
    parse_ply(bytes)?.into_mesh(options).map(|(mesh, _)| mesh)
}

/// What a property means to us.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Role {
    Coord(usize),
    Indices,
    Front,
    Back,
    Skip,
}

/// What an element means to us.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Vertex,
    Face,
    Other,
}

/// A compiled element: its declaration and one role per property.
struct Plan<'h> {
    decl: &'h ElementDecl,
    kind: Kind,
    roles: Vec<Role>,
}

fn header_error(decl: &ElementDecl, reason: &str) -> IoErrorKind {
    IoErrorKind::BadHeader {
        at: Location::header(decl.line),
        reason: format!("element `{}`: {reason}", decl.name),
    }
}

/// Assigns roles and checks what the data will need: x/y/z, a vertex-index list, both or
/// neither label property, counts the data can hold.
fn compile(header: &Header, bytes_left: u64) -> Result<(Vec<Plan<'_>>, bool), IoErrorKind> {
    let mut plans = Vec::with_capacity(header.elements.len());
    let mut labelled = false;
    let mut needed: u64 = 0;
    for decl in &header.elements {
        let kind = match decl.name.as_str() {
            "vertex" => Kind::Vertex,
            "face" => Kind::Face,
            _ => Kind::Other,
        };
        let mut roles = vec![Role::Skip; decl.props.len()];
        let scalar_int = |i: usize, what: &str| match decl.props[i].kind {
            PropKind::Scalar(s) if s.is_int() => Ok(()),
            _ => Err(header_error(
                decl,
                &format!("property `{what}` must be a scalar integer"),
            )),
        };
        match kind {
            Kind::Vertex => {
                if decl.count > u64::from(MAX_INDEX) {
                    return Err(IoErrorKind::Mesh(MeshError::TooLarge {
                        what: "vertices",
                        count: usize::try_from(decl.count).unwrap_or(usize::MAX),
                    }));
                }
                for (axis, (name, what)) in [
                    ("x", "`vertex` property `x`"),
                    ("y", "`vertex` property `y`"),
                    ("z", "`vertex` property `z`"),
                ]
                .into_iter()
                .enumerate()
                {
                    let i = decl
                        .find(name)
                        .ok_or(IoErrorKind::MissingProperty { what })?;
                    if !matches!(decl.props[i].kind, PropKind::Scalar(_)) {
                        return Err(header_error(
                            decl,
                            &format!("property `{name}` must be a scalar"),
                        ));
                    }
                    roles[i] = Role::Coord(axis);
                }
            }
            Kind::Face => {
                let i = decl
                    .find("vertex_indices")
                    .or_else(|| decl.find("vertex_index"))
                    .ok_or(IoErrorKind::MissingProperty {
                        what: "`face` property `vertex_indices`",
                    })?;
                match decl.props[i].kind {
                    PropKind::List { item, .. } if item.is_int() => roles[i] = Role::Indices,
                    _ => {
                        return Err(header_error(
                            decl,
                            "`vertex_indices` must be a list of integers",
                        ));
                    }
                }
                match (decl.find("label_front"), decl.find("label_back")) {
                    (Some(f), Some(b)) => {
                        scalar_int(f, "label_front")?;
                        scalar_int(b, "label_back")?;
                        roles[f] = Role::Front;
                        roles[b] = Role::Back;
                        labelled = true;
                    }
                    (Some(_), None) => {
                        return Err(IoErrorKind::MissingLabelProperty {
                            present: "label_front",
                            missing: "label_back",
                        });
                    }
                    (None, Some(_)) => {
                        return Err(IoErrorKind::MissingLabelProperty {
                            present: "label_back",
                            missing: "label_front",
                        });
                    }
                    (None, None) => {}
                }
            }
            Kind::Other => {}
        }
        // Elements without properties occupy no data; they are skipped whatever their count.
        if !decl.props.is_empty() {
            needed =
                needed.saturating_add(decl.count.saturating_mul(decl.min_bytes(header.encoding)));
            // ASCII may omit the final newline.
            let slack = u64::from(header.encoding == Encoding::Ascii);
            if needed > bytes_left.saturating_add(slack) {
                return Err(IoErrorKind::DeclaredCountTooLarge {
                    element: decl.name.clone(),
                    declared: decl.count,
                    bytes_left,
                });
            }
        }
        plans.push(Plan { decl, kind, roles });
    }
    if !plans.iter().any(|p| p.kind == Kind::Vertex) {
        return Err(IoErrorKind::MissingProperty {
            what: "`vertex` element",
        });
    }
    Ok((plans, labelled))
}

/// Parses a whole PLY file into arrays.
pub(crate) fn parse_ply(bytes: &[u8]) -> Result<RawMesh, IoErrorKind> {
    // Offsets (`data_start`, binary positions) are relative to the text after the mark.
    let bytes = strip_bom(bytes);
    let header = parse_header(bytes)?;
    let bytes_left = (bytes.len() - header.data_start) as u64;
    let (plans, labelled) = compile(&header, bytes_left)?;
    // `compile` bounded every count by the data size, so these allocations are too.
    let count_of = |kind| {
        plans
            .iter()
            .find(|p| p.kind == kind)
            .map_or(0, |p| p.decl.count as usize)
    };
    let vertex_count = count_of(Kind::Vertex) as u64;
    let mut raw = RawMesh {
        positions: Vec::with_capacity(count_of(Kind::Vertex)),
        tris: Vec::with_capacity(count_of(Kind::Face)),
        labels: labelled.then(|| Vec::with_capacity(count_of(Kind::Face))),
    };
    match header.encoding {
        Encoding::Ascii => {
            let mut src = AsciiSource {
                lines: Lines::starting_at(bytes, header.data_start, header.data_line),
                tokens: Tokens::new(b""),
                line: header.data_line,
            };
            read_body(&mut src, &plans, vertex_count, &mut raw)?;
            // Anything after the last element (blank lines, tool footers) is ignored.
        }
        Encoding::BinaryLittleEndian | Encoding::BinaryBigEndian => {
            let mut src = BinarySource {
                bytes,
                pos: header.data_start,
                big_endian: header.encoding == Encoding::BinaryBigEndian,
            };
            read_body(&mut src, &plans, vertex_count, &mut raw)?;
            if src.pos < bytes.len() {
                return Err(IoErrorKind::TrailingData {
                    bytes: (bytes.len() - src.pos) as u64,
                });
            }
        }
    }
    Ok(raw)
}

/// Why one element could not be read; turned into an [`IoErrorKind`] with its location.
enum Fail {
    Truncated,
    Missing,
    Extra,
    Bad(String),
    NonFinite(f64),
    NonTriangle(i64),
    Index(i64),
    Label(i64),
    /// A text value that does not fit its integer type; `property` is filled in by
    /// [`Fail::of`] on the way out (empty until then, so nothing is allocated for it).
    Type {
        value: String,
        ty: Scalar,
        property: String,
    },
}

impl Fail {
    fn at(self, at: Location, vertex_count: u64) -> IoErrorKind {
        match self {
            Fail::Truncated => IoErrorKind::Truncated { at },
            Fail::Missing => IoErrorKind::MissingValues { at },
            Fail::Extra => IoErrorKind::ExtraValues { at },
            Fail::Bad(token) => IoErrorKind::BadValue { at, token },
            Fail::NonFinite(value) => IoErrorKind::NonFinite { at, value },
            Fail::NonTriangle(vertices) => IoErrorKind::NonTriangle { at, vertices },
            Fail::Index(index) => IoErrorKind::IndexOutOfRange {
                at,
                index,
                vertex_count,
            },
            Fail::Label(value) => IoErrorKind::LabelOutOfRange { at, value },
            Fail::Type {
                value,
                ty,
                property,
            } => IoErrorKind::ValueOutOfType(Box::new(TypeMismatch {
                at,
                property,
                ty: ty.name(),
                value,
            })),
        }
    }

    /// Names the property a type error was found in.
    #[cold]
    fn of(self, prop: &Property) -> Fail {
        match self {
            Fail::Type { value, ty, .. } => Fail::Type {
                value,
                ty,
                property: prop.name.clone(),
            },
            other => other,
        }
    }
}

/// Values of the data section, element by element.
trait Source {
    /// Starts the next element (ASCII: its line).
    fn begin(&mut self) -> Result<(), Fail>;
    /// One value of scalar type `s`, as a float.
    fn float(&mut self, s: Scalar) -> Result<f64, Fail>;
    /// One value of integer type `s`.
    fn int(&mut self, s: Scalar) -> Result<i64, Fail>;
    /// Skips `n` values of type `s`.
    fn skip(&mut self, s: Scalar, n: u64) -> Result<(), Fail>;
    /// Ends the element (ASCII: nothing may be left on the line).
    fn end(&mut self) -> Result<(), Fail>;
    /// Line of the current element, for text.
    fn line(&self) -> Option<u64>;
}

struct AsciiSource<'a> {
    lines: Lines<'a>,
    tokens: Tokens<'a>,
    line: u64,
}

impl AsciiSource<'_> {
    #[inline]
    fn token(&mut self) -> Result<&[u8], Fail> {
        self.tokens.next().ok_or(Fail::Missing)
    }
}

impl Source for AsciiSource<'_> {
    fn begin(&mut self) -> Result<(), Fail> {
        for (number, line) in self.lines.by_ref() {
            if !is_blank(line) {
                self.tokens = Tokens::new(line);
                self.line = number;
                return Ok(());
            }
        }
        // Name the line where the missing element should have been.
        self.line = self.lines.next_number();
        Err(Fail::Truncated)
    }

    #[inline]
    fn float(&mut self, s: Scalar) -> Result<f64, Fail> {
        if s.is_int() {
            // An integer-typed coordinate holds what its type holds, as in binary.
            return self.int(s).map(|v| v as f64);
        }
        let tok = self.token()?;
        parse_float(tok).ok_or_else(|| Fail::Bad(shown(tok)))
    }

    /// Text can say anything, so the value is checked against the type (binary values fit
    /// by construction): 257 in a `uchar` label, or a list count beyond its count type,
    /// would otherwise be taken as written.
    #[inline]
    fn int(&mut self, s: Scalar) -> Result<i64, Fail> {
        let tok = self.token()?;
        let type_error = |value| Fail::Type {
            value,
            ty: s,
            property: String::new(),
        };
        match (parse_int(tok), s.int_range()) {
            (Some(v), Some((min, max))) if v < min || v > max => Err(type_error(v.to_string())),
            (Some(v), _) => Ok(v),
            // A number, but not an integer (`2.5`, `1e3`).
            (None, _) if parse_float(tok).is_some() => Err(type_error(shown(tok))),
            (None, _) => Err(Fail::Bad(shown(tok))),
        }
    }

    fn skip(&mut self, _: Scalar, n: u64) -> Result<(), Fail> {
        // Terminates after at most (tokens on the line + 1) steps, whatever `n` is.
        for _ in 0..n {
            self.token()?;
        }
        Ok(())
    }

    fn end(&mut self) -> Result<(), Fail> {
        match self.tokens.next() {
            Some(_) => Err(Fail::Extra),
            None => Ok(()),
        }
    }

    fn line(&self) -> Option<u64> {
        Some(self.line)
    }
}

struct BinarySource<'a> {
    bytes: &'a [u8],
    pos: usize,
    big_endian: bool,
}

impl BinarySource<'_> {
    #[inline]
    fn take<const N: usize>(&mut self) -> Result<[u8; N], Fail> {
        let chunk = self
            .bytes
            .get(self.pos..self.pos.saturating_add(N))
            .and_then(|s| <[u8; N]>::try_from(s).ok())
            .ok_or(Fail::Truncated)?;
        self.pos += N;
        Ok(chunk)
    }
}

macro_rules! read_num {
    ($src:expr, $ty:ty) => {{
        let b = $src.take::<{ std::mem::size_of::<$ty>() }>()?;
        if $src.big_endian {
            <$ty>::from_be_bytes(b)
        } else {
            <$ty>::from_le_bytes(b)
        }
    }};
}

impl Source for BinarySource<'_> {
    #[inline]
    fn begin(&mut self) -> Result<(), Fail> {
        Ok(())
    }

    #[inline]
    fn float(&mut self, s: Scalar) -> Result<f64, Fail> {
        Ok(match s {
            Scalar::F32 => f64::from(read_num!(self, f32)),
            Scalar::F64 => read_num!(self, f64),
            _ => self.int(s)? as f64,
        })
    }

    #[inline]
    fn int(&mut self, s: Scalar) -> Result<i64, Fail> {
        Ok(match s {
            Scalar::I8 => i64::from(read_num!(self, i8)),
            Scalar::U8 => i64::from(read_num!(self, u8)),
            Scalar::I16 => i64::from(read_num!(self, i16)),
            Scalar::U16 => i64::from(read_num!(self, u16)),
            Scalar::I32 => i64::from(read_num!(self, i32)),
            Scalar::U32 => i64::from(read_num!(self, u32)),
            // The header only lets integer types reach here; a float would be truncated.
            Scalar::F32 | Scalar::F64 => self.float(s)? as i64,
        })
    }

    fn skip(&mut self, s: Scalar, n: u64) -> Result<(), Fail> {
        let end = usize::try_from(n)
            .ok()
            .and_then(|n| n.checked_mul(s.size()))
            .and_then(|len| self.pos.checked_add(len))
            .filter(|&end| end <= self.bytes.len())
            .ok_or(Fail::Truncated)?;
        self.pos = end;
        Ok(())
    }

    #[inline]
    fn end(&mut self) -> Result<(), Fail> {
        Ok(())
    }

    fn line(&self) -> Option<u64> {
        None
    }
}

fn read_body<S: Source>(
    src: &mut S,
    plans: &[Plan<'_>],
    vertex_count: u64,
    raw: &mut RawMesh,
) -> Result<(), IoErrorKind> {
    for plan in plans {
        if plan.decl.props.is_empty() {
            continue;
        }
        let element = match plan.kind {
            Kind::Vertex => Element::Vertex,
            Kind::Face => Element::Face,
            Kind::Other => Element::Other(plan.decl.name.clone()),
        };
        for i in 0..plan.decl.count {
            let result = match plan.kind {
                Kind::Vertex => read_vertex(src, plan).map(|p| raw.positions.push(p)),
                Kind::Face => read_face(src, plan, vertex_count).map(|(tri, labels)| {
                    raw.tris.push(tri);
                    if let Some(all) = &mut raw.labels {
                        all.push(labels);
                    }
                }),
                Kind::Other => skip_element(src, plan),
            };
            if let Err(fail) = result {
                return Err(fail.at(Location::element(element, i, src.line()), vertex_count));
            }
        }
    }
    Ok(())
}

/// Reads a list count; negative counts are malformed.
#[inline]
fn list_len<S: Source>(src: &mut S, count: Scalar) -> Result<i64, Fail> {
    let n = src.int(count)?;
    if n < 0 {
        Err(Fail::Bad(n.to_string()))
    } else {
        Ok(n)
    }
}

#[inline]
fn skip_property<S: Source>(src: &mut S, kind: PropKind) -> Result<(), Fail> {
    match kind {
        PropKind::Scalar(s) => src.skip(s, 1),
        PropKind::List { count, item } => {
            let n = list_len(src, count)?;
            src.skip(item, n as u64)
        }
    }
}

fn skip_element<S: Source>(src: &mut S, plan: &Plan<'_>) -> Result<(), Fail> {
    src.begin()?;
    for prop in &plan.decl.props {
        skip_property(src, prop.kind).map_err(|f| f.of(prop))?;
    }
    src.end()
}

#[inline]
fn read_vertex<S: Source>(src: &mut S, plan: &Plan<'_>) -> Result<DVec3, Fail> {
    src.begin()?;
    let mut p = [0.0; 3];
    for (prop, &role) in plan.decl.props.iter().zip(&plan.roles) {
        match (role, prop.kind) {
            (Role::Coord(axis), PropKind::Scalar(s)) => src.float(s).map(|v| p[axis] = v),
            (_, kind) => skip_property(src, kind),
        }
        .map_err(|f| f.of(prop))?;
    }
    src.end()?;
    if let Some(&bad) = p.iter().find(|v| !v.is_finite()) {
        return Err(Fail::NonFinite(bad));
    }
    Ok(DVec3::from_array(p))
}

/// The three entries of a `vertex_indices` list, as written.
#[inline]
fn read_indices<S: Source>(src: &mut S, count: Scalar, item: Scalar) -> Result<[i64; 3], Fail> {
    let n = src.int(count)?;
    if n != 3 {
        return Err(Fail::NonTriangle(n));
    }
    let mut indices = [0; 3];
    for index in &mut indices {
        *index = src.int(item)?;
    }
    Ok(indices)
}

#[inline]
fn read_face<S: Source>(
    src: &mut S,
    plan: &Plan<'_>,
    vertex_count: u64,
) -> Result<([u32; 3], [u32; 2]), Fail> {
    src.begin()?;
    let mut tri = [0u32; 3];
    let mut labels = [0u32; 2];
    for (prop, &role) in plan.decl.props.iter().zip(&plan.roles) {
        match (role, prop.kind) {
            (Role::Indices, PropKind::List { count, item }) => read_indices(src, count, item)
                .and_then(|t| {
                    // vertex_count <= MAX_INDEX (checked in `compile`), so an index fits u32.
                    for (slot, index) in tri.iter_mut().zip(t) {
                        match u32::try_from(index) {
                            Ok(v) if u64::from(v) < vertex_count => *slot = v,
                            _ => return Err(Fail::Index(index)),
                        }
                    }
                    Ok(())
                }),
            (Role::Front | Role::Back, PropKind::Scalar(s)) => src.int(s).and_then(|value| {
                let label = u32::try_from(value)
                    .ok()
                    .filter(|&l| l <= MAX_INDEX)
                    .ok_or(Fail::Label(value))?;
                labels[usize::from(role == Role::Back)] = label;
                Ok(())
            }),
            (_, kind) => skip_property(src, kind),
        }
        .map_err(|f| f.of(prop))?;
    }
    src.end()?;
    Ok((tri, labels))
}

#[cfg(test)]
#[path = "ply_read_tests.rs"]
mod tests;
