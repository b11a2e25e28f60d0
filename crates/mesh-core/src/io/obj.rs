//! Wavefront OBJ with labels as `usemtl label_<front>_<back>` runs (see the
//! [module docs](super) for the convention and for why this reader is hand-written).

use std::io::{BufWriter, Read, Write};

use glam::DVec3;

use super::error::{Element, IoError, IoErrorKind, Location, shown};
use super::ply_write::check_finite;
use super::text::{Lines, Tokens, is_blank, parse_float, parse_int, strip_bom};
use super::{RawMesh, ReadOptions};
use crate::LabeledMesh;
use crate::ids::MAX_INDEX;

/// Reads an OBJ mesh from a reader. Errors name `<memory>` as the file;
/// [`super::read_mesh`] names the path instead.
pub fn read_obj(mut reader: impl Read, options: &ReadOptions) -> Result<LabeledMesh, IoError> {
    let mut bytes = Vec::new();
    reader
        .read_to_end(&mut bytes)
        .map_err(|e| IoError::memory(IoErrorKind::Io(e)))?;
    obj_from_bytes(&bytes, options).map_err(IoError::memory)
}

/// Reads an OBJ mesh from bytes in memory.
pub(crate) fn obj_from_bytes(
    bytes: &[u8],
    options: &ReadOptions,
) -> Result<LabeledMesh, IoErrorKind> {
    parse_obj(bytes)?.into_mesh(options).map(|(mesh, _)| mesh)
}

/// The label pair named by a `usemtl` material, `None` for a non-label material.
fn label_of_material(name: &[u8], line: u64) -> Result<Option<[u32; 2]>, IoErrorKind> {
    let Some(rest) = name.strip_prefix(b"label_") else {
        return Ok(None);
    };
    let bad = || IoErrorKind::BadLabelName {
        at: Location::line(line),
        name: shown(name),
    };
    let mut parts = rest.split(|&b| b == b'_');
    let (Some(front), Some(back), None) = (parts.next(), parts.next(), parts.next()) else {
        return Err(bad());
    };
    let mut pair = [0u32; 2];
    for (slot, text) in pair.iter_mut().zip([front, back]) {
        let value = parse_int(text).ok_or_else(bad)?;
        *slot = u32::try_from(value)
            .ok()
            .filter(|&l| l <= MAX_INDEX)
            .ok_or(IoErrorKind::LabelOutOfRange {
                at: Location::line(line),
                value,
            })?;
    }
    Ok(Some(pair))
}

/// Why a face token names no vertex.
enum BadCorner {
    /// Index 0, or a relative index before the first vertex (as written).
    Range(i64),
    /// Not a number (shortened text).
    Syntax(String),
}

/// Resolves one face token (`v`, `v/vt`, `v//vn`, `v/vt/vn`) to a 0-based vertex index,
/// relative indices against the `seen` vertices so far; returns it with the index as
/// written, which errors report (the user looks for what the file says). Indices past the
/// end are checked once the whole file is read (OBJ allows referring to later vertices).
fn vertex_of(token: &[u8], seen: usize) -> Result<(i64, i64), BadCorner> {
    let head = token.split(|&b| b == b'/').next().unwrap_or(token);
    let k = parse_int(head).ok_or_else(|| BadCorner::Syntax(shown(token)))?;
    let resolved = if k > 0 {
        k - 1
    } else {
        (seen as i64).saturating_add(k)
    };
    if k == 0 || resolved < 0 {
        Err(BadCorner::Range(k))
    } else {
        Ok((resolved, k))
    }
}

/// Parses a whole OBJ file into arrays.
pub(crate) fn parse_obj(bytes: &[u8]) -> Result<RawMesh, IoErrorKind> {
    let bytes = strip_bom(bytes);
    if is_blank(bytes) {
        return Err(IoErrorKind::Empty);
    }
    // Unknown keywords are skipped, so a PLY file would otherwise read as an empty mesh.
    let first = Lines::new(bytes)
        .map(|(_, text)| text)
        .find(|t| !is_blank(t));
    if first.is_some_and(|t| t.trim_ascii() == b"ply") {
        return Err(IoErrorKind::PlyInObj);
    }
    let mut geometry_lines = false;
    let mut positions: Vec<DVec3> = Vec::new();
    let mut tris: Vec<[u32; 3]> = Vec::new();
    let mut labels: Vec<[u32; 2]> = Vec::new();
    let mut current: Option<[u32; 2]> = None;
    let mut first_unlabelled: Option<Location> = None;
    let mut labelled = 0usize;
    for (line, text) in Lines::new(bytes) {
        let mut tokens = Tokens::new(text);
        let Some(keyword) = tokens.next() else {
            continue;
        };
        match keyword {
            b"v" => {
                geometry_lines = true;
                let at = || Location::element(Element::Vertex, positions.len() as u64, Some(line));
                let mut p = [0.0; 3];
                for value in &mut p {
                    let tok = tokens
                        .next()
                        .ok_or_else(|| IoErrorKind::MissingValues { at: at() })?;
                    *value = parse_float(tok).ok_or_else(|| IoErrorKind::BadValue {
                        at: at(),
                        token: shown(tok),
                    })?;
                    if !value.is_finite() {
                        return Err(IoErrorKind::NonFinite {
                            at: at(),
                            value: *value,
                        });
                    }
                }
                // Extra values (`w`, vertex colours) are ignored, but they must be numbers:
                // two records run together by a line ending the splitter missed (`v 0 0 0
                // v 1 0 0`) then fail here instead of losing the second. Their count is not
                // capped: exporters write 4 (`w`), 6 or 7 (colours) and some more, and a
                // missed ending always brings a keyword, which this check catches anyway.
                if let Some(tok) = tokens
                    .take_while(|t| !t.starts_with(b"#"))
                    .find(|t| parse_float(t).is_none())
                {
                    return Err(IoErrorKind::BadValue {
                        at: at(),
                        token: shown(tok),
                    });
                }
                positions.push(DVec3::from_array(p));
            }
            b"f" | b"l" | b"p" => {
                geometry_lines = true;
                let at = || Location::element(Element::Face, tris.len() as u64, Some(line));
                let corners = tokens.clone().take_while(|t| !t.starts_with(b"#"));
                let arity = corners.clone().count();
                if keyword != b"f" || arity != 3 {
                    return Err(IoErrorKind::NonTriangle {
                        at: at(),
                        vertices: arity as i64,
                    });
                }
                let mut tri = [0u32; 3];
                for (slot, tok) in tri.iter_mut().zip(corners) {
                    let (index, written) =
                        vertex_of(tok, positions.len()).map_err(|e| match e {
                            BadCorner::Range(index) => IoErrorKind::IndexOutOfRange {
                                at: at(),
                                index,
                                vertex_count: positions.len() as u64,
                            },
                            BadCorner::Syntax(token) => IoErrorKind::BadValue { at: at(), token },
                        })?;
                    // Indices past the last vertex read so far are checked at the end of the
                    // file; past MAX_INDEX they can never be valid.
                    *slot = u32::try_from(index)
                        .ok()
                        .filter(|&v| v <= MAX_INDEX)
                        .ok_or_else(|| IoErrorKind::IndexOutOfRange {
                            at: at(),
                            index: written,
                            vertex_count: positions.len() as u64,
                        })?;
                }
                match current {
                    Some(_) => labelled += 1,
                    None if first_unlabelled.is_none() => first_unlabelled = Some(at()),
                    None => {}
                }
                tris.push(tri);
                labels.push(current.unwrap_or([0, 0]));
            }
            b"usemtl" => {
                let name = tokens
                    .remainder()
                    .split(|&b| b == b'#')
                    .next()
                    .unwrap_or_default();
                current = label_of_material(name.trim_ascii_end(), line)?;
            }
            // No keyword is a number: ASCII PLY data, a point list, or a lost line break.
            [b'0'..=b'9' | b'+' | b'-' | b'.', ..] if parse_float(keyword).is_some() => {
                return Err(IoErrorKind::NotObjLine {
                    at: Location::line(line),
                    token: shown(keyword),
                });
            }
            // Comments, groups, objects, smoothing, texture/normal data, unknown keywords.
            _ => {}
        }
    }
    if !geometry_lines {
        return Err(IoErrorKind::NoGeometry);
    }
    let vertex_count = positions.len();
    if vertex_count > MAX_INDEX as usize {
        return Err(IoErrorKind::Mesh(crate::MeshError::TooLarge {
            what: "vertices",
            count: vertex_count,
        }));
    }
    if let Some((face, tri)) = tris
        .iter()
        .enumerate()
        .find(|(_, t)| t.iter().any(|&v| v as usize >= vertex_count))
    {
        let index = tri
            .iter()
            .copied()
            .find(|&v| v as usize >= vertex_count)
            .unwrap_or(u32::MAX);
        // Only a positive index can point past the end (a relative one is resolved against
        // vertices already read): as written, it is one more than the 0-based index.
        return Err(IoErrorKind::IndexOutOfRange {
            at: Location::element(Element::Face, face as u64, face_line(bytes, face)),
            index: i64::from(index) + 1,
            vertex_count: vertex_count as u64,
        });
    }
    let labels = match (labelled, first_unlabelled) {
        (0, _) => None,
        (_, Some(at)) => return Err(IoErrorKind::MixedLabels { at }),
        (_, None) => Some(labels),
    };
    Ok(RawMesh {
        positions,
        tris,
        labels,
    })
}

/// Line number of the `face`-th face line (only computed for an error message).
fn face_line(bytes: &[u8], face: usize) -> Option<u64> {
    Lines::new(bytes)
        .filter(|(_, text)| Tokens::new(text).next() == Some(b"f"))
        .nth(face)
        .map(|(line, _)| line)
}

/// Writes the live part of `mesh`, densely renumbered, as OBJ: `v` lines with shortest
/// round-trip coordinates, then the triangles in order, a `usemtl label_<front>_<back>`
/// line starting each run of equal label pairs. Buffers internally; pass `&mut Vec<u8>`
/// to write to memory. Fails on non-finite positions before writing anything.
pub fn write_obj(mesh: &LabeledMesh, writer: impl Write) -> Result<(), IoError> {
    let (positions, tris, labels) = mesh.to_raw();
    write_arrays(&positions, &tris, &labels, writer).map_err(IoError::memory)
}

fn write_arrays(
    positions: &[DVec3],
    tris: &[[u32; 3]],
    labels: &[[u32; 2]],
    writer: impl Write,
) -> Result<(), IoErrorKind> {
    check_finite(positions)?;
    let mut w = BufWriter::with_capacity(1 << 16, writer);
    writeln!(
        w,
        "# mesh-core labelled mesh: {} vertices, {} triangles",
        positions.len(),
        tris.len()
    )?;
    writeln!(
        w,
        "# usemtl label_<front>_<back>: front is the material the right-hand normal points into"
    )?;
    for p in positions {
        // `{:?}` is the shortest text that parses back to the same f64.
        writeln!(w, "v {:?} {:?} {:?}", p.x, p.y, p.z)?;
    }
    let mut current = None;
    for (t, &l) in tris.iter().zip(labels) {
        if current != Some(l) {
            writeln!(w, "usemtl label_{}_{}", l[0], l[1])?;
            current = Some(l);
        }
        writeln!(
            w,
            "f {} {} {}",
            u64::from(t[0]) + 1,
            u64::from(t[1]) + 1,
            u64::from(t[2]) + 1
        )?;
    }
    w.flush()?;
    Ok(())
}

#[cfg(test)]
#[path = "obj_tests.rs"]
mod tests;
