//! Tests of the OBJ reader and writer.

use super::*;
use crate::io::test_meshes::two_tets;
use crate::io::{EdgeProblem, Element, Unlabeled};

const TET: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n";
const OUTWARD: &str = "f 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n";
const INWARD: &str = "f 1 2 3\nf 1 4 2\nf 2 4 3\nf 1 3 4\n";

fn read(text: &str) -> Result<LabeledMesh, IoErrorKind> {
    obj_from_bytes(text.as_bytes(), &ReadOptions::default())
}

fn err(text: &str) -> IoErrorKind {
    match read(text) {
        Ok(_) => panic!("expected an error for {text:?}"),
        Err(e) => e,
    }
}

fn face(index: u64, line: u64) -> Location {
    Location::element(Element::Face, index, Some(line))
}

#[test]
fn unlabelled_closed_tetrahedra_get_inside_one() {
    assert_eq!(
        read(&format!("{TET}{OUTWARD}")).unwrap().to_raw().2,
        vec![[0, 1]; 4]
    );
    assert_eq!(
        read(&format!("{TET}{INWARD}")).unwrap().to_raw().2,
        vec![[1, 0]; 4]
    );
    // Two components, one of each orientation, in one file (the second with relative indices).
    let second =
        "v 5 5 5\nv 6 5 5\nv 5 6 5\nv 5 5 6\nf -4 -3 -2\nf -4 -1 -3\nf -3 -1 -2\nf -4 -2 -1\n";
    let labels = read(&format!("{TET}{OUTWARD}{second}")).unwrap().to_raw().2;
    assert_eq!(&labels[..4], &[[0, 1]; 4]);
    assert_eq!(&labels[4..], &[[1, 0]; 4]);
}

#[test]
fn open_or_inconsistent_unlabelled_obj_is_a_typed_error() {
    let open = format!("{TET}f 1 3 2\nf 1 2 4\nf 2 3 4\n");
    assert!(matches!(
        err(&open),
        IoErrorKind::NotClosed {
            edge: [0, 2],
            problem: EdgeProblem::Boundary
        }
    ));
    let flipped = format!("{TET}f 1 2 3\nf 1 2 4\nf 2 3 4\nf 1 4 3\n");
    assert!(matches!(
        err(&flipped),
        IoErrorKind::NotClosed {
            edge: [0, 1],
            problem: EdgeProblem::Inconsistent
        }
    ));
    let assume = ReadOptions {
        unlabeled: Unlabeled::AssumeOutward,
        ..ReadOptions::default()
    };
    assert_eq!(
        obj_from_bytes(open.as_bytes(), &assume).unwrap().to_raw().2,
        vec![[0, 1]; 3]
    );
}

#[test]
fn accepts_common_obj_variants() {
    let text = "# made by hand \u{e9}\nmtllib scene.mtl\no thing\ng part\ns 1\n\
v 0 0 0 1.0\nv 1 0 0 0.5 0.5 0.5\nvt 0 0\nvn 0 0 1\nv 0 1 0\r\nv 0 0 1\n\
usemtl label_2_0\nf 1/1/1 3//1 2/1 # a comment\nf -4/1 -3 -1\nusemtl label_2_0\nf 2 3 4\n  usemtl   label_0_2  # trailing comment\nf 1 4 3\n";
    let (p, t, l) = read(text).unwrap().to_raw();
    assert_eq!(p.len(), 4);
    assert_eq!(p[1], glam::DVec3::X);
    assert_eq!(t, vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]]);
    assert_eq!(l, vec![[2, 0], [2, 0], [2, 0], [0, 2]]);
    // Latin-1 in a comment is harmless; other material names mean "no label".
    let plain = format!("# caf\u{e9}\nusemtl Material.001\n{TET}{OUTWARD}");
    assert_eq!(read(&plain).unwrap().to_raw().2, vec![[0, 1]; 4]);
    let mut latin1 = b"# caf\xe9\n".to_vec();
    latin1.extend_from_slice(format!("{TET}{OUTWARD}").as_bytes());
    assert!(obj_from_bytes(&latin1, &ReadOptions::default()).is_ok());
    // Faces may refer to vertices defined later.
    let forward = format!("{OUTWARD}{TET}");
    assert_eq!(read(&forward).unwrap().num_triangles(), 4);
}

#[test]
fn every_line_ending_convention_reads_the_same_mesh() {
    // A lone `\r` (old Mac) used to end no line: the whole file was one `v` line.
    let text = format!("{TET}usemtl label_0_1\n{OUTWARD}");
    let expected = read(&text).unwrap().to_raw();
    for ending in ["\r\n", "\r"] {
        let converted = text.replace('\n', ending);
        assert_eq!(read(&converted).unwrap().to_raw(), expected, "{ending:?}");
    }
    // Line numbers in errors count each ending once, whatever the mix.
    let mixed = "v 0 0 0\rv 1 0 0\r\nv 0 1 0\n\rf 1 2 x\r";
    assert!(
        matches!(err(mixed), IoErrorKind::BadValue { at, .. } if at == face(0, 5)),
        "{:?}",
        err(mixed)
    );
}

#[test]
fn a_utf8_byte_order_mark_is_skipped() {
    // The mark used to hide the first `v`, so a face later pointed past the last vertex.
    let text = format!("{TET}usemtl label_0_1\n{OUTWARD}");
    let expected = read(&text).unwrap().to_raw();
    assert_eq!(read(&format!("\u{feff}{text}")).unwrap().to_raw(), expected);
    // A mark alone is an empty file.
    assert!(matches!(err("\u{feff}"), IoErrorKind::Empty));
}

#[test]
fn what_is_not_obj_is_refused_not_read_as_empty() {
    // A PLY file given to the OBJ reader used to read as 0 vertices and 0 triangles.
    let ply = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
property float z\nend_header\n0 0 0\n";
    assert!(matches!(err(ply), IoErrorKind::PlyInObj));
    assert!(matches!(
        err(&format!("\u{feff}\r\n  ply \r{TET}")),
        IoErrorKind::PlyInObj
    ));
    // A line starting with a number is no OBJ, even among known keywords.
    for (text, line, token) in [
        ("0 0 0\n", 1, "0"),
        ("v 0 0 0\n\n-1.5e3 x\n", 3, "-1.5e3"),
        ("# c\n.5\n", 2, ".5"),
    ] {
        match err(text) {
            IoErrorKind::NotObjLine { at, token: t } => {
                assert_eq!((at, t.as_str()), (Location::line(line), token), "{text:?}")
            }
            e => panic!("{text:?} gave {e:?}"),
        }
    }
    // Nothing geometric at all is an error; vertices without faces (a point set) are not,
    // nor are unknown keywords that are words.
    for text in ["# nothing\n# here\n", "mtllib a.mtl\no x\nvt 0 0\n"] {
        assert!(matches!(err(text), IoErrorKind::NoGeometry), "{text:?}");
    }
    let assume = ReadOptions {
        unlabeled: Unlabeled::AssumeOutward,
        ..ReadOptions::default()
    };
    let points = obj_from_bytes(b"v 0 0 0\ncstype bezier\nv 1 0 0\n", &assume).unwrap();
    assert_eq!((points.num_vertices(), points.num_triangles()), (2, 0));
}

#[test]
fn malformed_obj_errors_name_the_line() {
    assert!(matches!(err(""), IoErrorKind::Empty));
    assert!(matches!(err("  \n\t\n"), IoErrorKind::Empty));
    type Check = fn(&IoErrorKind) -> bool;
    let cases: &[(&str, Check)] = &[
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 4 3\n",
            |e| matches!(e, IoErrorKind::NonTriangle { at, vertices: 4 } if *at == face(0, 5)),
        ),
        (
            "v 0 0 0\nv 1 0 0\nl 1 2\n",
            |e| matches!(e, IoErrorKind::NonTriangle { at, vertices: 2 } if *at == face(0, 3)),
        ),
        ("v 0 0 0\nf 1 1\n", |e| {
            matches!(e, IoErrorKind::NonTriangle { vertices: 2, .. })
        }),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n",
            |e| matches!(e, IoErrorKind::IndexOutOfRange { at, index: 0, vertex_count: 3 } if *at == face(0, 4)),
        ),
        ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -4 1 2\n", |e| {
            matches!(e, IoErrorKind::IndexOutOfRange { index: -4, .. })
        }),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n# gap\nf 1 2 5\n",
            |e| matches!(e, IoErrorKind::IndexOutOfRange { at, index: 5, vertex_count: 3 } if *at == face(1, 6)),
        ),
        ("v 0 0 0\nf 1 2 99999999999\n", |e| {
            matches!(
                e,
                IoErrorKind::IndexOutOfRange {
                    index: 99999999999,
                    ..
                }
            )
        }),
        (
            "v 0 0 0\nf 1 2 x\n",
            |e| matches!(e, IoErrorKind::BadValue { token, .. } if token == "x"),
        ),
        (
            "v 0 0\n",
            |e| matches!(e, IoErrorKind::MissingValues { at } if *at == Location::element(Element::Vertex, 0, Some(1))),
        ),
        (
            "v 0 0 0\nv 0 y 0\n",
            |e| matches!(e, IoErrorKind::BadValue { at, .. } if *at == Location::element(Element::Vertex, 1, Some(2))),
        ),
        // Two records on one line (a line ending lost) must not pass as extra values.
        (
            "v 0 0 0 1 # w\nv 0 0 0 1 0 0 v 1 1 1\n",
            |e| matches!(e, IoErrorKind::BadValue { at, token } if *at == Location::element(Element::Vertex, 1, Some(2)) && token == "v"),
        ),
        (
            "v 0 0 0\nv 0 NaN 0\n",
            |e| matches!(e, IoErrorKind::NonFinite { value, .. } if value.is_nan()),
        ),
        ("v 0 0 inf\n", |e| {
            matches!(e, IoErrorKind::NonFinite { .. })
        }),
        (
            "usemtl label_1\n",
            |e| matches!(e, IoErrorKind::BadLabelName { at, .. } if *at == Location::line(1)),
        ),
        ("usemtl label_a_b\n", |e| {
            matches!(e, IoErrorKind::BadLabelName { .. })
        }),
        ("usemtl label_1_2_3\n", |e| {
            matches!(e, IoErrorKind::BadLabelName { .. })
        }),
        (
            "\nusemtl label_-1_0\n",
            |e| matches!(e, IoErrorKind::LabelOutOfRange { at, value: -1 } if *at == Location::line(2)),
        ),
        ("usemtl label_0_4294967295\n", |e| {
            matches!(
                e,
                IoErrorKind::LabelOutOfRange {
                    value: 4294967295,
                    ..
                }
            )
        }),
    ];
    for (text, check) in cases {
        let e = err(text);
        assert!(check(&e), "{text:?} gave {e:?}");
    }
    let mixed =
        format!("{TET}usemtl label_1_0\nf 1 3 2\nf 1 2 4\nusemtl glass\nf 2 3 4\nf 1 4 3\n");
    assert!(matches!(err(&mixed), IoErrorKind::MixedLabels { at } if at == face(2, 9)));
}

#[test]
fn writer_starts_a_usemtl_run_per_label_change() {
    let mut buf = Vec::new();
    write_obj(&two_tets(), &mut buf).unwrap();
    let text = String::from_utf8(buf).unwrap();
    let runs: Vec<&str> = text.lines().filter(|l| l.starts_with("usemtl")).collect();
    assert_eq!(
        runs,
        vec!["usemtl label_1_2", "usemtl label_0_1", "usemtl label_0_2"]
    );
    assert!(text.contains("v 1e300 -5e-324 -0.0\n"), "{text}");
    assert_eq!(text.lines().filter(|l| l.starts_with("f ")).count(), 7);
}

#[test]
fn tobj_reads_what_we_write_with_the_same_geometry() {
    let mesh = two_tets();
    let mut buf = Vec::new();
    write_obj(&mesh, &mut buf).unwrap();
    let options = tobj::LoadOptions {
        triangulate: false,
        single_index: false,
        ..Default::default()
    };
    let (models, _) = tobj::load_obj_buf(&mut &buf[..], &options, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .unwrap();
    // Without an .mtl file tobj keeps one model; compare corner positions bit for bit.
    assert_eq!(models.len(), 1);
    let m = &models[0].mesh;
    let (positions, tris, _) = mesh.to_raw();
    assert_eq!(m.indices.len(), 3 * tris.len());
    for (k, &i) in m.indices.iter().enumerate() {
        let ours = positions[tris[k / 3][k % 3] as usize].to_array();
        let theirs = [0, 1, 2].map(|a| m.positions[3 * i as usize + a]);
        assert_eq!(ours.map(f64::to_bits), theirs.map(f64::to_bits));
    }
}
