//! Tests of the PLY reader: accepted variants and every malformed-input error.

use glam::DVec3;

use super::*;
use crate::io::{EdgeProblem, Element, PlyFormat, TypeMismatch, Unlabeled, write_ply};

const HEAD: &str = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
element face 4\nproperty list uchar int vertex_indices\nproperty int label_front\nproperty int label_back\nend_header\n";
const VERTS: &str = "0 0 0\n1 0 0\n0 1 0\n0 0 1\n";
const FACES: &str = "3 0 2 1 0 1\n3 0 1 3 0 1\n3 1 2 3 0 1\n3 0 3 2 0 1\n";

fn read(bytes: &[u8]) -> Result<LabeledMesh, IoErrorKind> {
    ply_from_bytes(bytes, &ReadOptions::default())
}

fn err(bytes: &[u8]) -> IoErrorKind {
    match read(bytes) {
        Ok(_) => panic!("expected an error for {:?}", String::from_utf8_lossy(bytes)),
        Err(e) => e,
    }
}

fn ascii(head: &str, verts: &str, faces: &str) -> Vec<u8> {
    format!("{head}{verts}{faces}").into_bytes()
}

fn at(element: Element, index: u64, line: Option<u64>) -> Location {
    Location::element(element, index, line)
}

/// Binary little-endian writer for hand-made files.
#[derive(Default)]
struct Bin(Vec<u8>);
impl Bin {
    fn f32(mut self, v: f32) -> Self {
        self.0.extend(v.to_le_bytes());
        self
    }
    fn u8(mut self, v: u8) -> Self {
        self.0.push(v);
        self
    }
    fn i16(mut self, v: i16) -> Self {
        self.0.extend(v.to_le_bytes());
        self
    }
    fn u32(mut self, v: u32) -> Self {
        self.0.extend(v.to_le_bytes());
        self
    }
}

#[test]
fn reads_a_labelled_ascii_tetrahedron() {
    let mesh = read(&ascii(HEAD, VERTS, FACES)).unwrap();
    let (p, t, l) = mesh.to_raw();
    assert_eq!(p[3], DVec3::Z);
    assert_eq!(t[2], [1, 2, 3]);
    assert_eq!(l, vec![[0, 1]; 4]);
}

#[test]
fn skips_unknown_properties_and_elements_in_ascii() {
    let head = "ply\r\nformat ascii 1.0\r\ncomment made by hand\r\nobj_info whatever\r\n\
element vertex 4\nproperty uchar red\nproperty double z\nproperty list uchar float extra\nproperty double y\nproperty double x\n\
element material 2\nproperty list int uchar name\nproperty float shine\n\
element face 4\nproperty short flags\nproperty uchar label_back\nproperty list uint8 uint16 vertex_index\n\
property list uchar int texcoord\nproperty char label_front\nend_header\n";
    let verts = "255 0 2 1.5 -1 0 0\n0 0 0 0 1\n1 0 0 1 0\n7 1 2 2 3 0 0\n";
    let materials = "3 97 98 99 0.5\n\n0 1e3\n";
    let faces = "-1 1 3 0 2 1 0 0\n0 1 3 0 1 3 2 1 1 0\n0 1 3 1 2 3 0 0\n0 1 3 0 3 2 1 2 0\n";
    let mesh =
        read(format!("{head}{verts}{materials}{faces}\n\n trailing junk is ignored").as_bytes())
            .unwrap();
    let (p, t, l) = mesh.to_raw();
    assert_eq!(p, vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z]);
    assert_eq!(t, vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]]);
    assert_eq!(l, vec![[0, 1]; 4]);
}

#[test]
fn reads_every_line_ending_convention() {
    let text = ascii(HEAD, VERTS, FACES);
    let expected = read(&text).unwrap().to_raw();
    let text = String::from_utf8(text).unwrap();
    for ending in ["\r\n", "\r"] {
        let converted = text.replace('\n', ending);
        assert_eq!(read(converted.as_bytes()).unwrap().to_raw(), expected);
        // Line numbers stay right: the third face is line 18.
        let bad = converted.replace("3 1 2 3 0 1", "3 1 2 9 0 1");
        assert!(matches!(err(bad.as_bytes()),
            IoErrorKind::IndexOutOfRange { at: l, .. } if l == at(Element::Face, 2, Some(18))));
    }
    // A `\r`-only header before binary data whose first byte is 0x0A (`\n`): that byte is
    // data, not the end of a `\r\n`.
    let head = "ply\rformat binary_little_endian 1.0\relement vertex 3\rproperty uchar flags\r\
property float x\rproperty float y\rproperty float z\relement face 1\r\
property list uchar int vertex_indices\rend_header\r";
    let mut b = Bin(head.as_bytes().to_vec());
    for (x, y) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)] {
        b = b.u8(b'\n').f32(x).f32(y).f32(0.0);
    }
    let b = b.u8(3).u32(0).u32(1).u32(2);
    let assume = ReadOptions {
        unlabeled: Unlabeled::AssumeOutward,
        ..ReadOptions::default()
    };
    let (p, t, _) = ply_from_bytes(&b.0, &assume).unwrap().to_raw();
    assert_eq!(p, vec![DVec3::ZERO, DVec3::X, DVec3::Y]);
    assert_eq!(t, vec![[0, 1, 2]]);
}

#[test]
fn a_utf8_byte_order_mark_is_skipped() {
    // The mark used to hide the magic `ply`.
    let text = ascii(HEAD, VERTS, FACES);
    let expected = read(&text).unwrap().to_raw();
    let with_mark = [&b"\xEF\xBB\xBF"[..], &text].concat();
    assert_eq!(read(&with_mark).unwrap().to_raw(), expected);
    // Binary data is found where the header says, counted after the mark.
    let mut buf = b"\xEF\xBB\xBF".to_vec();
    let mesh = crate::io::test_meshes::two_tets();
    write_ply(&mesh, &mut buf, PlyFormat::BinaryLittleEndian).unwrap();
    crate::io::test_meshes::assert_same_raw(&mesh, &read(&buf).unwrap());
    assert!(matches!(err(b"\xEF\xBB\xBF"), IoErrorKind::Empty));
}

#[test]
fn skips_unknown_properties_and_elements_in_binary() {
    let head = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty list uchar short n\n\
property float y\nproperty float z\nelement edge 1\nproperty int a\nproperty list uchar uint b\n\
element face 1\nproperty uchar label_front\nproperty list uchar uint vertex_indices\nproperty short label_back\n\
element empty 1000000000\nend_header\n";
    let mut b = Bin(head.as_bytes().to_vec());
    for (x, y, z, n) in [(0.0, 0.0, 0.0, 2u8), (1.0, 0.0, 0.0, 0), (0.0, 1.0, 0.0, 1)] {
        b = b.f32(x).u8(n);
        for _ in 0..n {
            b = b.i16(-5);
        }
        b = b.f32(y).f32(z);
    }
    b = b.u32(9).u8(2).u32(1).u32(2); // edge
    b = b.u8(4).u8(3).u32(0).u32(1).u32(2).i16(0); // face, labels [4, 0]
    let mesh = ply_from_bytes(
        &b.0,
        &ReadOptions {
            unlabeled: Unlabeled::Error,
            ..ReadOptions::default()
        },
    )
    .unwrap();
    let (p, t, l) = mesh.to_raw();
    assert_eq!(p, vec![DVec3::ZERO, DVec3::X, DVec3::Y]);
    assert_eq!(t, vec![[0, 1, 2]]);
    assert_eq!(l, vec![[4, 0]]);

    // A cut inside the skipped `edge` element names it.
    let edge_start = b.0.len() - (1 + 1 + 12 + 2) - (4 + 1 + 8);
    match err(&b.0[..edge_start + 6]) {
        IoErrorKind::Truncated { at: l } => {
            assert_eq!(l, at(Element::Other("edge".into()), 0, None))
        }
        e => panic!("{e:?}"),
    }
    // One byte more is an error in binary: the header does not describe the data.
    let mut longer = b.0.clone();
    longer.push(0);
    assert!(matches!(
        err(&longer),
        IoErrorKind::TrailingData { bytes: 1 }
    ));
}

#[test]
fn reads_hand_made_big_endian() {
    let head = "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty float x\nproperty double y\n\
property short z\nelement face 1\nproperty list ushort uint vertex_indices\nproperty ushort label_front\n\
property int label_back\nend_header\n";
    let mut b = head.as_bytes().to_vec();
    for (x, y, z) in [(0.5f32, 0.25f64, -3i16), (1.0, 0.0, 0), (0.0, 1.0, 0)] {
        b.extend(x.to_be_bytes());
        b.extend(y.to_be_bytes());
        b.extend(z.to_be_bytes());
    }
    b.extend(3u16.to_be_bytes());
    for i in [2u32, 1, 0] {
        b.extend(i.to_be_bytes());
    }
    b.extend(258u16.to_be_bytes());
    b.extend(70000i32.to_be_bytes());
    let (p, t, l) = read(&b).unwrap().to_raw();
    assert_eq!(p, vec![DVec3::new(0.5, 0.25, -3.0), DVec3::X, DVec3::Y]);
    assert_eq!(t, vec![[2, 1, 0]]);
    assert_eq!(l, vec![[258, 70000]]);
}

#[test]
fn reads_big_endian_written_by_us() {
    let mesh = crate::io::test_meshes::two_tets();
    let mut buf = Vec::new();
    write_ply(&mesh, &mut buf, PlyFormat::BinaryBigEndian).unwrap();
    crate::io::test_meshes::assert_same_raw(&mesh, &read(&buf).unwrap());
}

#[test]
fn truncated_data_names_the_element() {
    // ASCII: the last face is missing, and a cut in the middle of a vertex line.
    let cut_faces = &FACES[..FACES.len() - "3 0 3 2 0 1\n".len()];
    assert_eq!(
        match err(&ascii(HEAD, VERTS, cut_faces)) {
            IoErrorKind::Truncated { at } => at,
            e => panic!("{e:?}"),
        },
        at(Element::Face, 3, Some(19))
    );
    let short_line = "0 0 0\n1 0 0\n0 1\n0 0 1\n";
    assert!(matches!(err(&ascii(HEAD, short_line, FACES)),
        IoErrorKind::MissingValues { at: l } if l == at(Element::Vertex, 2, Some(14))));
    // Binary: every proper prefix of the data fails with Truncated (or the header error).
    let mut buf = Vec::new();
    write_ply(
        &crate::io::test_meshes::two_tets(),
        &mut buf,
        PlyFormat::BinaryLittleEndian,
    )
    .unwrap();
    let start = buf.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    for cut in [start + 1, start + 24 * 6, buf.len() - 1] {
        match err(&buf[..cut]) {
            IoErrorKind::Truncated { at: l } => assert_eq!(l.line, None),
            IoErrorKind::DeclaredCountTooLarge { .. } => {}
            e => panic!("cut at {cut}: {e:?}"),
        }
    }
    match err(&buf[..buf.len() - 1]) {
        IoErrorKind::Truncated { at: l } => assert_eq!(l, at(Element::Face, 6, None)),
        e => panic!("{e:?}"),
    }
}

#[test]
fn line_value_counts_are_checked() {
    let extra = VERTS.replace("1 0 0\n", "1 0 0 5\n");
    assert!(matches!(err(&ascii(HEAD, &extra, FACES)),
        IoErrorKind::ExtraValues { at: l } if l == at(Element::Vertex, 1, Some(13))));
    let bad = VERTS.replace("0 1 0\n", "0 one 0\n");
    assert!(matches!(err(&ascii(HEAD, &bad, FACES)),
        IoErrorKind::BadValue { at: l, token } if l == at(Element::Vertex, 2, Some(14)) && token == "one"));
    let bad = FACES.replace("3 1 2 3 0 1", "3 1 2.0 3 0 1");
    assert!(matches!(
        err(&ascii(HEAD, VERTS, &bad)),
        IoErrorKind::ValueOutOfType(m) if m.ty == "int" && m.value == "2.0"
    ));
    let negative = FACES.replace("3 1 2 3 0 1", "-2 1 2 3 0 1");
    let signed_count = HEAD.replace("list uchar int", "list char int");
    assert!(matches!(
        err(&ascii(&signed_count, VERTS, &negative)),
        IoErrorKind::NonTriangle { vertices: -2, .. }
    ));
    assert!(matches!(
        err(&ascii(HEAD, VERTS, &negative)),
        IoErrorKind::ValueOutOfType(m) if m.ty == "uchar" && m.property == "vertex_indices"
    ));
}

#[test]
fn faces_must_be_triangles_with_indices_in_range() {
    let quad = FACES.replace("3 1 2 3 0 1", "4 1 2 3 0 0 1");
    assert!(matches!(err(&ascii(HEAD, VERTS, &quad)),
        IoErrorKind::NonTriangle { at: l, vertices: 4 } if l == at(Element::Face, 2, Some(18))));
    for (bad, index) in [
        ("3 1 2 4 0 1", 4),
        ("3 1 -1 3 0 1", -1),
        ("3 1 2 2147483647 0 1", 2147483647),
    ] {
        let faces = FACES.replace("3 1 2 3 0 1", bad);
        match err(&ascii(HEAD, VERTS, &faces)) {
            IoErrorKind::IndexOutOfRange {
                at: l,
                index: i,
                vertex_count: 4,
            } => {
                assert_eq!((l, i), (at(Element::Face, 2, Some(18)), index));
            }
            e => panic!("{bad}: {e:?}"),
        }
    }
    let head = HEAD.replace(
        "list uchar int vertex_indices",
        "list uchar float vertex_indices",
    );
    assert!(matches!(
        err(&ascii(&head, VERTS, FACES)),
        IoErrorKind::BadHeader { .. }
    ));
}

#[test]
fn ascii_values_must_fit_their_declared_type() {
    // 257 in a `uchar` label used to be read as label 257.
    let head = HEAD
        .replace("property int label_front", "property uchar label_front")
        .replace("property int label_back", "property char label_back")
        .replace("list uchar int", "list uchar ushort")
        .replace("property float z", "property short z");
    let fits = FACES.replace("3 1 2 3 0 1", "3 1 2 3 255 127");
    assert!(read(&ascii(&head, VERTS, &fits)).is_ok());
    let cases = [
        ("3 1 2 3 257 1", "label_front", "uchar", "257"),
        ("3 1 2 3 0 -129", "label_back", "char", "-129"),
        ("3 1 2 3 2.5 1", "label_front", "uchar", "2.5"),
        ("256 1 2 3 0 1", "vertex_indices", "uchar", "256"),
        ("3 1 2 65536 0 1", "vertex_indices", "ushort", "65536"),
    ];
    for (bad, property, ty, value) in cases {
        let faces = FACES.replace("3 1 2 3 0 1", bad);
        let e = err(&ascii(&head, VERTS, &faces));
        let expected = TypeMismatch {
            at: at(Element::Face, 2, Some(18)),
            property: property.into(),
            ty,
            value: value.into(),
        };
        assert!(
            matches!(&e, IoErrorKind::ValueOutOfType(m) if **m == expected),
            "{bad}: {e}"
        );
    }
    // An integer-typed coordinate, and the count of a list that is skipped.
    let verts = VERTS.replace("0 1 0\n", "0 1 40000\n");
    assert!(matches!(err(&ascii(&head, &verts, FACES)),
        IoErrorKind::ValueOutOfType(m) if m.at == at(Element::Vertex, 2, Some(14)) && m.property == "z"));
    let head = HEAD.replace(
        "end_header",
        "element extra 1\nproperty list uchar int stuff\nend_header",
    );
    assert!(
        matches!(err(&ascii(&head, VERTS, &format!("{FACES}256 0\n"))),
        IoErrorKind::ValueOutOfType(m) if m.at == at(Element::Other("extra".into()), 0, Some(22)) && m.property == "stuff")
    );
}

#[test]
fn coordinates_must_be_finite() {
    for bad in ["nan", "inf", "-infinity", "1e400"] {
        let verts = VERTS.replace("0 1 0\n", &format!("0 {bad} 0\n"));
        assert!(
            matches!(err(&ascii(HEAD, &verts, FACES)), IoErrorKind::NonFinite { at: l, .. } if l == at(Element::Vertex, 2, Some(14))),
            "{bad}"
        );
    }
    // Binary NaN.
    let head = "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
    let b = Bin(head.as_bytes().to_vec())
        .f32(0.0)
        .f32(f32::NAN)
        .f32(0.0);
    assert!(
        matches!(err(&b.0), IoErrorKind::NonFinite { at: l, value } if l == at(Element::Vertex, 0, None) && value.is_nan())
    );
}

#[test]
fn labels_must_be_both_present_and_in_range() {
    let only_front = HEAD.replace("property int label_back\n", "");
    assert!(matches!(
        err(&ascii(&only_front, VERTS, FACES)),
        IoErrorKind::MissingLabelProperty {
            present: "label_front",
            missing: "label_back"
        }
    ));
    let only_back = HEAD.replace("property int label_front\n", "");
    assert!(matches!(
        err(&ascii(&only_back, VERTS, FACES)),
        IoErrorKind::MissingLabelProperty {
            present: "label_back",
            missing: "label_front"
        }
    ));
    let float_label = HEAD.replace("property int label_back", "property float label_back");
    assert!(matches!(
        err(&ascii(&float_label, VERTS, FACES)),
        IoErrorKind::BadHeader { .. }
    ));
    let uint_back = HEAD.replace("property int label_back", "property uint label_back");
    for (bad, value) in [("3 1 2 3 -1 1", -1), ("3 1 2 3 0 4294967295", 4294967295)] {
        let faces = FACES.replace("3 1 2 3 0 1", bad);
        assert!(matches!(err(&ascii(&uint_back, VERTS, &faces)),
            IoErrorKind::LabelOutOfRange { at: l, value: v } if l == at(Element::Face, 2, Some(18)) && v == value));
    }
    // uint in binary: u32::MAX is out of range (it is no valid label id).
    let head = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
element face 1\nproperty list uchar int vertex_indices\nproperty uint label_front\nproperty uint label_back\nend_header\n";
    let mut b = Bin(head.as_bytes().to_vec());
    for _ in 0..9 {
        b = b.f32(0.0);
    }
    let b = b.u8(3).u32(0).u32(1).u32(2).u32(0).u32(u32::MAX);
    assert!(matches!(
        err(&b.0),
        IoErrorKind::LabelOutOfRange {
            value: 4294967295,
            ..
        }
    ));
}

#[test]
fn header_problems() {
    assert!(matches!(err(b""), IoErrorKind::Empty));
    assert!(matches!(err(b"OFF\n3 1 0\n"), IoErrorKind::BadMagic));
    let latin1 = b"ply\nformat ascii 1.0\ncomment caf\xe9\nend_header\n";
    assert!(matches!(err(latin1), IoErrorKind::NotUtf8 { at: l } if l == Location::header(3)));
    let no_vertex = "ply\nformat ascii 1.0\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n";
    assert!(matches!(
        err(no_vertex.as_bytes()),
        IoErrorKind::MissingProperty {
            what: "`vertex` element"
        }
    ));
    let no_z = HEAD.replace("property float z\n", "");
    assert!(matches!(
        err(&ascii(&no_z, VERTS, FACES)),
        IoErrorKind::MissingProperty {
            what: "`vertex` property `z`"
        }
    ));
    let no_list = HEAD.replace("property list uchar int vertex_indices\n", "");
    assert!(matches!(
        err(&ascii(&no_list, VERTS, FACES)),
        IoErrorKind::MissingProperty { .. }
    ));
    let list_x = HEAD.replace("property float x", "property list uchar float x");
    assert!(matches!(
        err(&ascii(&list_x, VERTS, FACES)),
        IoErrorKind::BadHeader { .. }
    ));
}

#[test]
fn absurd_counts_are_rejected_before_allocating() {
    for (encoding, count) in [
        ("ascii", "4000000000"),
        ("binary_little_endian", "4000000000"),
        ("ascii", "18446744073709551615"),
    ] {
        let head = format!(
            "ply\nformat {encoding} 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\n\
element face {count}\nproperty list uchar int vertex_indices\nend_header\n0 0 0 1 0 0 0 1 0\n"
        );
        match err(head.as_bytes()) {
            IoErrorKind::DeclaredCountTooLarge {
                element,
                declared,
                bytes_left,
            } => {
                assert_eq!(element, "face");
                assert_eq!(declared.to_string(), count);
                assert_eq!(bytes_left, 18);
            }
            e => panic!("{e:?}"),
        }
    }
    let huge_vertices = "ply\nformat ascii 1.0\nelement vertex 4294967295\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
    assert!(matches!(
        err(huge_vertices.as_bytes()),
        IoErrorKind::Mesh(crate::MeshError::TooLarge { .. })
    ));
}

#[test]
fn unlabelled_ply_reads_as_two_materials_or_names_the_bad_edge() {
    let head = HEAD.replace("property int label_front\nproperty int label_back\n", "");
    let faces = "3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n";
    assert_eq!(
        read(&ascii(&head, VERTS, faces)).unwrap().to_raw().2,
        vec![[0, 1]; 4]
    );
    let inward = "3 0 1 2\n3 0 3 1\n3 1 3 2\n3 0 2 3\n";
    assert_eq!(
        read(&ascii(&head, VERTS, inward)).unwrap().to_raw().2,
        vec![[1, 0]; 4]
    );
    let inconsistent = "3 0 1 2\n3 0 1 3\n3 1 2 3\n3 0 3 2\n";
    assert!(matches!(
        err(&ascii(&head, VERTS, inconsistent)),
        IoErrorKind::NotClosed {
            edge: [0, 1],
            problem: EdgeProblem::Inconsistent
        }
    ));
}
