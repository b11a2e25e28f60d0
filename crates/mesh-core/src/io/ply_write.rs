//! Writing PLY: `double` coordinates, `uchar`-counted index lists, integer label
//! properties, in ASCII or binary of either byte order.

use std::io::{BufWriter, Write};

use glam::DVec3;

use super::error::{Element, IoError, IoErrorKind, Location};
use crate::LabeledMesh;

/// The encoding of a PLY file to write.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PlyFormat {
    /// Text: readable and diffable, about 3× larger and slower than binary.
    Ascii,
    /// Packed binary, least significant byte first (the usual choice).
    #[default]
    BinaryLittleEndian,
    /// Packed binary, most significant byte first.
    BinaryBigEndian,
}

/// Writes the live part of `mesh`, densely renumbered, as PLY. Buffers internally; pass
/// `&mut Vec<u8>` to write to memory. Fails on non-finite positions before writing anything.
pub fn write_ply(mesh: &LabeledMesh, writer: impl Write, format: PlyFormat) -> Result<(), IoError> {
    let (positions, tris, labels) = mesh.to_raw();
    write_arrays(&positions, &tris, &labels, writer, format).map_err(IoError::memory)
}

/// Refuses positions that no reader (ours included) would accept back.
pub(crate) fn check_finite(positions: &[DVec3]) -> Result<(), IoErrorKind> {
    match positions.iter().position(|p| !p.is_finite()) {
        None => Ok(()),
        Some(i) => {
            let p = positions[i].to_array();
            let value = p.into_iter().find(|v| !v.is_finite()).unwrap_or(f64::NAN);
            Err(IoErrorKind::NonFinite {
                at: Location::element(Element::Vertex, i as u64, None),
                value,
            })
        }
    }
}

fn write_arrays(
    positions: &[DVec3],
    tris: &[[u32; 3]],
    labels: &[[u32; 2]],
    writer: impl Write,
    format: PlyFormat,
) -> Result<(), IoErrorKind> {
    check_finite(positions)?;
    let mut w = BufWriter::with_capacity(1 << 16, writer);
    // `int` unless a value does not fit it: what most tools expect, and still exact.
    let int_for = |max: u64| if max > i32::MAX as u64 { "uint" } else { "int" };
    let max_label = labels.iter().flatten().copied().max().unwrap_or(0);
    let index_type = int_for(positions.len().saturating_sub(1) as u64);
    let label_type = int_for(u64::from(max_label));
    let encoding = match format {
        PlyFormat::Ascii => "ascii",
        PlyFormat::BinaryLittleEndian => "binary_little_endian",
        PlyFormat::BinaryBigEndian => "binary_big_endian",
    };
    write!(
        w,
        "ply\nformat {encoding} 1.0\n\
         comment mesh-core labelled mesh: label_front is the material the right-hand normal points into\n\
         element vertex {nv}\nproperty double x\nproperty double y\nproperty double z\n\
         element face {nt}\nproperty list uchar {index_type} vertex_indices\n\
         property {label_type} label_front\nproperty {label_type} label_back\nend_header\n",
        nv = positions.len(),
        nt = tris.len(),
    )?;
    match format {
        PlyFormat::Ascii => {
            for p in positions {
                // `{:?}` is the shortest text that parses back to the same f64.
                writeln!(w, "{:?} {:?} {:?}", p.x, p.y, p.z)?;
            }
            for (t, l) in tris.iter().zip(labels) {
                writeln!(w, "3 {} {} {} {} {}", t[0], t[1], t[2], l[0], l[1])?;
            }
        }
        PlyFormat::BinaryLittleEndian | PlyFormat::BinaryBigEndian => {
            let big = format == PlyFormat::BinaryBigEndian;
            // Both `int` and `uint` are four bytes; the value is the same bit pattern
            // whenever the header says `int` (values <= i32::MAX).
            let u32_bytes = |v: u32| {
                if big {
                    v.to_be_bytes()
                } else {
                    v.to_le_bytes()
                }
            };
            let f64_bytes = |v: f64| {
                if big {
                    v.to_be_bytes()
                } else {
                    v.to_le_bytes()
                }
            };
            let mut vertex = [0u8; 24];
            for p in positions {
                for (k, v) in p.to_array().into_iter().enumerate() {
                    vertex[8 * k..8 * k + 8].copy_from_slice(&f64_bytes(v));
                }
                w.write_all(&vertex)?;
            }
            let mut face = [0u8; 21];
            face[0] = 3;
            for (t, l) in tris.iter().zip(labels) {
                for (k, &v) in t.iter().chain(l).enumerate() {
                    face[1 + 4 * k..5 + 4 * k].copy_from_slice(&u32_bytes(v));
                }
                w.write_all(&face)?;
            }
        }
    }
    w.flush()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::test_meshes::two_tets;

    #[test]
    fn ascii_output_is_the_documented_layout() {
        let mesh = LabeledMesh::from_raw(
            vec![DVec3::new(0.1, -0.0, 1e-7), DVec3::X, DVec3::Y],
            &[[0, 1, 2]],
            &[[1, 0]],
        )
        .unwrap();
        let mut buf = Vec::new();
        write_ply(&mesh, &mut buf, PlyFormat::Ascii).unwrap();
        let text = String::from_utf8(buf).unwrap();
        let body = text.split("end_header\n").nth(1).unwrap();
        assert_eq!(
            body,
            "0.1 -0.0 1e-7\n1.0 0.0 0.0\n0.0 1.0 0.0\n3 0 1 2 1 0\n"
        );
        assert!(
            text.contains("property list uchar int vertex_indices\nproperty int label_front\n")
        );
    }

    #[test]
    fn binary_sizes_match_the_header() {
        let mesh = two_tets();
        for format in [PlyFormat::BinaryLittleEndian, PlyFormat::BinaryBigEndian] {
            let mut buf = Vec::new();
            write_ply(&mesh, &mut buf, format).unwrap();
            let start = buf.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
            assert_eq!(buf.len() - start, 6 * 24 + 7 * 21);
        }
    }

    #[test]
    fn large_labels_switch_to_uint_and_survive() {
        let big = u32::MAX - 1;
        let mesh = LabeledMesh::from_raw(
            vec![DVec3::ZERO, DVec3::X, DVec3::Y],
            &[[0, 1, 2]],
            &[[big, 7]],
        )
        .unwrap();
        for format in [PlyFormat::Ascii, PlyFormat::BinaryLittleEndian] {
            let mut buf = Vec::new();
            write_ply(&mesh, &mut buf, format).unwrap();
            assert!(String::from_utf8_lossy(&buf).contains("property uint label_front"));
            let back = crate::io::read_ply(&buf[..], &Default::default()).unwrap();
            assert_eq!(back.to_raw().2, vec![[big, 7]]);
        }
    }

    #[test]
    fn non_finite_positions_are_refused_before_writing() {
        let mut mesh = two_tets();
        let v = mesh.vertices().nth(2).unwrap();
        mesh.set_position(v, DVec3::new(0.0, f64::INFINITY, 0.0));
        let mut buf = Vec::new();
        let e = write_ply(&mesh, &mut buf, PlyFormat::Ascii).unwrap_err();
        assert!(
            matches!(e.kind, IoErrorKind::NonFinite { at, value } if at.index == Some(2) && value == f64::INFINITY)
        );
        assert!(buf.is_empty());
    }

    #[test]
    fn write_errors_are_reported() {
        struct Full;
        impl Write for Full {
            fn write(&mut self, _: &[u8]) -> std::io::Result<usize> {
                Err(std::io::Error::new(
                    std::io::ErrorKind::StorageFull,
                    "disk full",
                ))
            }
            fn flush(&mut self) -> std::io::Result<()> {
                Ok(())
            }
        }
        let e = write_ply(&two_tets(), Full, PlyFormat::Ascii).unwrap_err();
        assert!(matches!(e.kind, IoErrorKind::Io(_)));
        assert!(e.to_string().contains("disk full"));
    }
}
