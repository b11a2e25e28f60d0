//! The bad-input catalogue through the library API (issue 7, item 1): every malformed or
//! unsupported input gets a specific typed error naming what and where — never a panic,
//! never a silently wrong mesh. The same catalogue through the `surftrack` binary is in
//! `crates/bench-harness/tests/bad_input_cli.rs`.
//!
//! What is an error and what is valid:
//! - The readers accept any finite coordinate: magnitudes 1e15 and 1e-15 are valid meshes.
//!   Whether a tracker can work at that scale is the tracker's decision: it either tracks
//!   (a mesh scaled uniformly) or refuses with a typed error (a cell size below the `f64`
//!   resolution at the mesh's coordinates: `GridError::TooFine`, surfaced as
//!   `TrackError::InvalidInput` or `StageFailed { stage: "grid" }`).
//! - Labels equal on both sides, open meshes, inconsistent labels, duplicate and zero-area
//!   triangles are representable (the readers accept them, `validate` names them); the
//!   trackers refuse them at construction (`BackendError::InvalidInput`), and `fix`
//!   refuses what it cannot repair (open, duplicate, same-label) while repairing
//!   inconsistent wedges, zero-area triangles, overlaps and inversions.
//! - An ASCII PLY with fewer faces declared than present reads the declared faces (text
//!   after the last element is ignored by design, see `mesh_core::io`): the result is an
//!   open mesh, refused downstream as above; the binary equivalent is `TrailingData`.

use std::path::Path;

use surftrack::grid_tracker::{FixError, fix};
use surftrack::mesh_core::io::{
    EdgeProblem, Element, IoErrorKind, ReadOptions, Unlabeled, read_mesh, read_obj, read_ply,
    write_mesh,
};
use surftrack::mesh_core::validate::{ValidateOptions, validate};
use surftrack::mesh_core::{DVec3, LabeledMesh, VertexId};
use surftrack::{Backend, BackendError, TrackError, TrackerOptions, make_tracker_with};

const TET_V: [[f64; 3]; 4] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
];
const TET_F: [[u32; 3]; 4] = [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]];

/// An ASCII PLY with labels from explicit lines (vertex and face lines as given).
fn ply(nv: usize, nf: usize, verts: &[String], faces: &[String]) -> Vec<u8> {
    let mut s = format!(
        "ply\nformat ascii 1.0\nelement vertex {nv}\nproperty double x\nproperty double y\n\
property double z\nelement face {nf}\nproperty list uchar int vertex_indices\n\
property int label_front\nproperty int label_back\nend_header\n"
    );
    for l in verts.iter().chain(faces) {
        s.push_str(l);
        s.push('\n');
    }
    s.into_bytes()
}

fn tet_verts() -> Vec<String> {
    TET_V
        .iter()
        .map(|p| format!("{} {} {}", p[0], p[1], p[2]))
        .collect()
}

fn tet_faces() -> Vec<String> {
    TET_F
        .iter()
        .map(|f| format!("3 {} {} {} 0 1", f[0], f[1], f[2]))
        .collect()
}

fn tet_ply() -> Vec<u8> {
    ply(4, 4, &tet_verts(), &tet_faces())
}

fn read(bytes: &[u8]) -> Result<LabeledMesh, IoErrorKind> {
    read_ply(bytes, &ReadOptions::default()).map_err(|e| e.kind)
}

fn tet(scale: f64, offset: DVec3) -> LabeledMesh {
    let p = TET_V
        .iter()
        .map(|c| DVec3::from_array(*c) * scale + offset)
        .collect();
    LabeledMesh::from_raw(p, &TET_F, &[[0, 1]; 4]).unwrap()
}

/// A binary little-endian labelled tetrahedron, as bytes.
fn binary_tet() -> Vec<u8> {
    let mut buf = Vec::new();
    surftrack::mesh_core::io::write_ply(
        &tet(1.0, DVec3::ZERO),
        &mut buf,
        surftrack::mesh_core::io::PlyFormat::BinaryLittleEndian,
    )
    .unwrap();
    buf
}

/// The error both backends give for a mesh at construction.
fn construction_errors(mesh: &LabeledMesh) -> Vec<(Backend, TrackError)> {
    Backend::ALL
        .iter()
        .map(
            |&b| match make_tracker_with(b, mesh.clone(), &TrackerOptions::default()) {
                Err(BackendError::InvalidInput { error, .. }) => (b, error),
                Err(e) => panic!("{b}: expected InvalidInput, got {e}"),
                Ok(_) => panic!("{b}: accepted an invalid mesh"),
            },
        )
        .collect()
}

fn assert_refused(mesh: &LabeledMesh, needle: &str) {
    for (b, e) in construction_errors(mesh) {
        assert!(
            matches!(e, TrackError::InvalidInput(ref m) if m.contains(needle)),
            "{b}: {e} should mention {needle:?}"
        );
    }
}

#[test]
fn empty_input_is_empty_in_both_formats() {
    assert!(matches!(read(b""), Err(IoErrorKind::Empty)));
    assert!(matches!(read(b"  \n\n"), Err(IoErrorKind::Empty)));
    let e = read_obj(&b""[..], &ReadOptions::default()).unwrap_err();
    assert!(matches!(e.kind, IoErrorKind::Empty), "{e}");
}

#[test]
fn truncated_ascii_ply_names_the_element_cut() {
    let full = tet_ply();
    let text = String::from_utf8(full).unwrap();
    // Cut inside the third face line: face 2 is missing values, face 3 missing entirely.
    let cut = &text[..text.rfind("3 1 2 3").unwrap() + 3];
    match read(cut.as_bytes()) {
        Err(IoErrorKind::MissingValues { at }) | Err(IoErrorKind::Truncated { at }) => {
            assert_eq!(at.element, Element::Face);
            assert_eq!(at.index, Some(2));
        }
        other => panic!("expected a truncation at face 2, got {other:?}"),
    }
    // Cut after the vertices: the first face is missing.
    let cut = &text[..text.find("3 0 2 1").unwrap()];
    match read(cut.as_bytes()) {
        Err(IoErrorKind::Truncated { at }) => {
            assert_eq!((at.element, at.index), (Element::Face, Some(0)))
        }
        // Fewer bytes left than the declared faces could fit in: refused up front.
        Err(IoErrorKind::DeclaredCountTooLarge {
            element,
            declared: 4,
            ..
        }) => {
            assert_eq!(element, "face")
        }
        other => panic!("expected a truncation at face 0, got {other:?}"),
    }
}

#[test]
fn truncated_binary_ply_names_the_element_cut() {
    let full = binary_tet();
    let header = full.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    // Every cut inside the data is a Truncated error at the element being read.
    for cut in header..full.len() {
        let expected = if cut < header + 4 * 24 {
            Element::Vertex
        } else {
            Element::Face
        };
        match read(&full[..cut]) {
            Err(IoErrorKind::Truncated { at }) => assert_eq!(at.element, expected, "cut at {cut}"),
            // Too few bytes left for the declared count: refused before reading.
            Err(IoErrorKind::DeclaredCountTooLarge { element, .. }) => {
                assert_eq!(element, expected.to_string(), "cut at {cut}")
            }
            other => panic!("cut at byte {cut}: expected a truncation, got {other:?}"),
        }
    }
    // A cut inside the header is a header error, not a panic.
    for cut in 1..header {
        assert!(read(&full[..cut]).is_err(), "cut at byte {cut} accepted");
    }
}

#[test]
fn wrong_element_counts_are_errors_or_refused_downstream() {
    // More faces declared than present.
    assert!(matches!(
        read(&ply(4, 5, &tet_verts(), &tet_faces())),
        Err(IoErrorKind::Truncated { at }) if at.element == Element::Face && at.index == Some(4)
    ));
    // Fewer vertices declared than present: a face line parsed as a vertex.
    // Fewer vertices declared than present: the last vertex line is read as a face.
    assert!(matches!(
        read(&ply(3, 4, &tet_verts(), &tet_faces())),
        Err(IoErrorKind::NonTriangle { at, vertices: 0 }) if at.index == Some(0) && at.line == Some(15)
    ));
    // More vertices declared than present: a face line as a vertex, or the end.
    assert!(read(&ply(5, 4, &tet_verts(), &tet_faces())).is_err());
    // A count no file could hold is refused before anything is allocated.
    let huge = ply(4_000_000_000, 4, &tet_verts(), &tet_faces());
    assert!(matches!(
        read(&huge),
        Err(IoErrorKind::DeclaredCountTooLarge {
            declared: 4_000_000_000,
            ..
        })
    ));
    // Binary with fewer faces declared than stored: the leftover bytes are an error.
    let bin = binary_tet();
    let text = String::from_utf8_lossy(&bin).replace("element face 4", "element face 3");
    let fewer = [
        &text.as_bytes()[..text.find("end_header\n").unwrap() + 11],
        &bin[bin.windows(11).position(|w| w == b"end_header\n").unwrap() + 11..],
    ]
    .concat();
    assert!(matches!(read(&fewer), Err(IoErrorKind::TrailingData { bytes }) if bytes > 0));
    // ASCII with fewer faces declared: documented to read the declared ones; the open
    // result is refused by the trackers, naming the boundary.
    let open = read(&ply(4, 3, &tet_verts(), &tet_faces())).unwrap();
    assert_eq!(open.num_triangles(), 3);
    assert!(
        !validate(&open, &ValidateOptions::default())
            .boundary_edges
            .is_empty()
    );
    assert_refused(&open, "boundary");
}

#[test]
fn indices_out_of_range_name_face_and_index() {
    let mut faces = tet_faces();
    faces[2] = "3 1 2 4 0 1".into();
    match read(&ply(4, 4, &tet_verts(), &faces)) {
        Err(IoErrorKind::IndexOutOfRange {
            at,
            index: 4,
            vertex_count: 4,
        }) => assert_eq!(
            (at.element, at.index, at.line),
            (Element::Face, Some(2), Some(18))
        ),
        other => panic!("{other:?}"),
    }
    faces[2] = "3 1 2 -1 0 1".into();
    assert!(matches!(
        read(&ply(4, 4, &tet_verts(), &faces)),
        Err(IoErrorKind::IndexOutOfRange { index: -1, .. })
    ));
    let obj = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n";
    let e = read_obj(&obj[..], &ReadOptions::default()).unwrap_err();
    assert!(
        matches!(e.kind, IoErrorKind::IndexOutOfRange { index: 9, .. }),
        "{e}"
    );
    let e = read_obj(&b"v 0 0 0\nf 1 -2 1\n"[..], &ReadOptions::default()).unwrap_err();
    assert!(matches!(e.kind, IoErrorKind::IndexOutOfRange { .. }), "{e}");
}

#[test]
fn non_triangular_faces_are_refused() {
    let mut faces = tet_faces();
    faces[1] = "4 0 1 3 2 0 1".into();
    assert!(matches!(
        read(&ply(4, 4, &tet_verts(), &faces)),
        Err(IoErrorKind::NonTriangle { vertices: 4, at }) if at.index == Some(1)
    ));
    faces[1] = "2 0 1 0 1".into();
    assert!(matches!(
        read(&ply(4, 4, &tet_verts(), &faces)),
        Err(IoErrorKind::NonTriangle { vertices: 2, .. })
    ));
    for bad in [
        &b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 4 3\n"[..],
        b"v 0 0 0\nv 1 0 0\nl 1 2\n",
    ] {
        let e = read_obj(bad, &ReadOptions::default()).unwrap_err();
        assert!(matches!(e.kind, IoErrorKind::NonTriangle { .. }), "{e}");
    }
}

#[test]
fn non_finite_coordinates_name_the_vertex() {
    for bad in ["nan", "inf", "-inf", "NaN", "1e400"] {
        let mut v = tet_verts();
        v[2] = format!("0 {bad} 0");
        match read(&ply(4, 4, &v, &tet_faces())) {
            Err(IoErrorKind::NonFinite { at, .. }) => {
                assert_eq!((at.element, at.index), (Element::Vertex, Some(2)), "{bad}")
            }
            other => panic!("{bad}: {other:?}"),
        }
        let obj =
            format!("v 0 0 0\nv 1 0 0\nv 0 {bad} 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n");
        let e = read_obj(obj.as_bytes(), &ReadOptions::default()).unwrap_err();
        assert!(
            matches!(e.kind, IoErrorKind::NonFinite { .. }),
            "{bad}: {e}"
        );
    }
    // Binary NaN.
    let mut bin = binary_tet();
    let header = bin.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    bin[header + 8..header + 16].copy_from_slice(&f64::NAN.to_le_bytes());
    assert!(matches!(read(&bin), Err(IoErrorKind::NonFinite { at, .. }) if at.index == Some(0)));
    // A mesh built in memory with a NaN: refused by both trackers and by fix.
    let mut mesh = tet(1.0, DVec3::ZERO);
    mesh.set_position(VertexId::new(1), DVec3::new(f64::INFINITY, 0.0, 0.0));
    assert_refused(&mesh, "finite");
    assert!(matches!(fix(&mesh, None), Err(FixError::InvalidInput(_))));
}

#[test]
fn extreme_magnitudes_read_exactly_and_are_tracked_or_refused_with_a_type() {
    for scale in [1e15, 1e-15] {
        let v: Vec<String> = TET_V
            .iter()
            .map(|p| format!("{:e} {:e} {:e}", p[0] * scale, p[1] * scale, p[2] * scale))
            .collect();
        let mesh = read(&ply(4, 4, &v, &tet_faces())).unwrap();
        assert_eq!(mesh.position(VertexId::new(1)).x, scale);
        assert!(validate(&mesh, &ValidateOptions::with_intersections()).is_valid());
        // Uniformly scaled: a valid input; a step of zero motion keeps it valid.
        for b in Backend::ALL {
            let mut t = make_tracker_with(b, mesh.clone(), &TrackerOptions::default())
                .unwrap_or_else(|e| panic!("{b} at scale {scale}: {e}"));
            let p = t.mesh().positions().to_vec();
            match t.advance(&p) {
                Ok(_) => assert!(validate(t.mesh(), &ValidateOptions::default()).is_valid()),
                Err(e) => panic!("{b} at scale {scale}: identity step failed: {e}"),
            }
        }
    }
    // A unit tetrahedron far from the origin: ℓ below the f64 spacing there.
    let far = tet(1.0, DVec3::splat(1e15));
    match make_tracker_with(Backend::Grid, far.clone(), &TrackerOptions::default()) {
        Err(BackendError::InvalidInput { .. }) => {}
        Ok(mut t) => {
            let p = t.mesh().positions().to_vec();
            match t.advance(&p) {
                Err(TrackError::StageFailed { stage: "grid", .. }) => {}
                other => panic!("grid at 1e15 offset: expected a grid error, got {other:?}"),
            }
        }
        Err(e) => panic!("{e}"),
    }
    // The collision backend has no grid: it tracks there or refuses with a type, and a
    // failed step keeps the mesh.
    if let Ok(mut t) =
        make_tracker_with(Backend::Collision, far.clone(), &TrackerOptions::default())
    {
        let p: Vec<DVec3> = t
            .mesh()
            .positions()
            .iter()
            .map(|&q| q + DVec3::X * 0.125)
            .collect();
        let before = t.mesh().to_raw();
        match t.advance(&p) {
            Ok(_) => assert!(validate(t.mesh(), &ValidateOptions::default()).is_valid()),
            Err(e) => {
                println!("collision at 1e15 offset: {e}");
                assert_eq!(t.mesh().to_raw(), before);
            }
        }
    }
    // A clean input comes back untouched at any scale (issue 16), without the grid that
    // cannot be built at this offset; anything else must be the grid's typed error.
    match fix(&far, None) {
        Ok(out) => assert_eq!(out.to_raw(), far.to_raw(), "fix changed a clean input"),
        Err(FixError::Pipeline(p)) => assert_eq!(p.stage(), "grid"),
        other => panic!("fix at 1e15 offset: {other:?}"),
    }
}

#[test]
fn missing_label_properties() {
    let only_front = String::from_utf8(tet_ply())
        .unwrap()
        .replace("property int label_back\n", "");
    let faces = tet_faces()
        .iter()
        .map(|f| f[..f.len() - 2].to_string())
        .collect::<Vec<_>>();
    let only_front = only_front.split("end_header\n").next().unwrap().to_string()
        + "end_header\n"
        + &tet_verts().join("\n")
        + "\n"
        + &faces.join("\n");
    assert!(matches!(
        read(only_front.as_bytes()),
        Err(IoErrorKind::MissingLabelProperty {
            present: "label_front",
            missing: "label_back"
        })
    ));
    // No labels at all, where labels are required.
    let unlabeled =
        b"ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
property float z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n\
0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n";
    let strict = ReadOptions {
        unlabeled: Unlabeled::Error,
        ..ReadOptions::default()
    };
    assert!(matches!(
        read_ply(&unlabeled[..], &strict).unwrap_err().kind,
        IoErrorKind::Unlabeled
    ));
    let e = read_obj(&b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"[..], &strict).unwrap_err();
    assert!(matches!(e.kind, IoErrorKind::Unlabeled));
    // OBJ where some faces carry labels and others do not.
    let mixed = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nusemtl label_0_1\nf 1 2 4\n";
    let e = read_obj(&mixed[..], &ReadOptions::default()).unwrap_err();
    assert!(matches!(e.kind, IoErrorKind::MixedLabels { .. }), "{e}");
}

#[test]
fn front_equal_to_back_is_refused_by_trackers_and_fix() {
    let mut faces = tet_faces();
    faces[0] = "3 0 2 1 1 1".into();
    let mesh = read(&ply(4, 4, &tet_verts(), &faces)).unwrap();
    assert_eq!(
        validate(&mesh, &ValidateOptions::default())
            .same_label_triangles
            .count,
        1
    );
    assert_refused(&mesh, "label");
    assert!(matches!(fix(&mesh, None), Err(FixError::InvalidInput(_))));
}

#[test]
fn open_meshes() {
    // Unlabelled: the reader cannot tell inside from outside.
    let open = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\n";
    let e = read_obj(&open[..], &ReadOptions::default()).unwrap_err();
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
    // Labelled: read, then refused by the trackers and by fix.
    let mesh = LabeledMesh::from_raw(
        TET_V.iter().map(|p| DVec3::from_array(*p)).collect(),
        &TET_F[..3],
        &[[0, 1]; 3],
    )
    .unwrap();
    assert_refused(&mesh, "boundary");
    assert!(matches!(fix(&mesh, None), Err(FixError::InvalidInput(m)) if m.contains("boundary")));
}

#[test]
fn inconsistent_labels_are_refused_by_trackers_and_repaired_by_fix() {
    // Two labels meet inconsistently: one face says inside is 2, the others say 1.
    let mut mesh = tet(1.0, DVec3::ZERO);
    mesh.set_labels(
        surftrack::mesh_core::TriId::new(0),
        [
            surftrack::mesh_core::Label::new(0),
            surftrack::mesh_core::Label::new(2),
        ],
    );
    let report = validate(&mesh, &ValidateOptions::default());
    assert!(!report.inconsistent_edges.is_empty());
    assert_refused(&mesh, "inconsistent");
    // fix may repair it or refuse it with a type (a repair that would lose a material is
    // the loss error of issue 16); it never returns an invalid mesh.
    match fix(&mesh, Some(0.25)) {
        Ok(out) => assert!(validate(&out, &ValidateOptions::default()).is_valid()),
        Err(e) => assert!(
            matches!(
                e,
                FixError::Pipeline(_) | FixError::InvalidInput(_) | FixError::Loss(_)
            ),
            "{e}"
        ),
    }
    // Inconsistent orientation in an unlabelled file: a reader error at the edge.
    let flipped = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\nf 2 3 4\nf 1 4 3\n";
    let e = read_obj(&flipped[..], &ReadOptions::default()).unwrap_err();
    assert!(
        matches!(
            e.kind,
            IoErrorKind::NotClosed {
                problem: EdgeProblem::Inconsistent,
                ..
            }
        ),
        "{e}"
    );
}

#[test]
fn duplicate_and_zero_area_triangles() {
    // A duplicate face (same corners and labels twice).
    let mut faces = tet_faces();
    faces.push(faces[0].clone());
    let dup = read(&ply(4, 5, &tet_verts(), &faces)).unwrap();
    assert_eq!(
        validate(&dup, &ValidateOptions::default()).duplicates.count,
        1
    );
    assert_refused(&dup, "duplicate");
    assert!(matches!(fix(&dup, None), Err(FixError::InvalidInput(m)) if m.contains("duplicate")));
    // Zero area: the fourth corner on the edge between the first two.
    let mut v = tet_verts();
    v[3] = "0.5 0 0".into();
    let flat = read(&ply(4, 4, &v, &tet_faces())).unwrap();
    assert!(validate(&flat, &ValidateOptions::default()).zero_area.count > 0);
    assert_refused(&flat, "zero");
    // fix repairs zero-area triangles (or, for a mesh with no volume, refuses with a type:
    // a repair that would leave no triangles of its material is a loss).
    match fix(&flat, Some(0.25)) {
        Ok(out) => assert!(validate(&out, &ValidateOptions::default()).is_valid()),
        Err(e) => assert!(
            matches!(e, FixError::Pipeline(_) | FixError::Loss(_)),
            "{e}"
        ),
    }
    // A face repeating a vertex is degenerate (topology), refused everywhere.
    let mut faces = tet_faces();
    faces[0] = "3 0 0 1 0 1".into();
    let degenerate = read(&ply(4, 4, &tet_verts(), &faces)).unwrap();
    assert!(!validate(&degenerate, &ValidateOptions::default()).is_valid());
    construction_errors(&degenerate);
    assert!(matches!(
        fix(&degenerate, None),
        Err(FixError::InvalidInput(_))
    ));
}

#[test]
fn non_utf8_bytes_are_typed_errors() {
    let mut bytes = tet_ply();
    bytes[4] = 0xff; // inside `format`
    assert!(matches!(
        read(&bytes),
        Err(IoErrorKind::NotUtf8 { .. }) | Err(IoErrorKind::BadHeader { .. })
    ));
    let mut bytes = tet_ply();
    let v = bytes
        .windows(11)
        .position(|w| w == b"end_header\n")
        .unwrap()
        + 11;
    bytes[v] = 0xc3; // a stray byte in the first vertex value
    assert!(matches!(read(&bytes), Err(IoErrorKind::BadValue { at, .. }) if at.index == Some(0)));
    let e = read_obj(&b"v 0 \xff 0\n"[..], &ReadOptions::default()).unwrap_err();
    assert!(matches!(e.kind, IoErrorKind::BadValue { .. }), "{e}");
    // Unknown keywords in non-UTF-8 are ignored as OBJ allows; a `usemtl label_` with bad
    // bytes is a bad label name.
    let e = read_obj(
        &b"v 0 0 0\nusemtl label_\xff_1\nf 1 1 1\n"[..],
        &ReadOptions::default(),
    )
    .unwrap_err();
    assert!(matches!(e.kind, IoErrorKind::BadLabelName { .. }), "{e}");
}

#[test]
fn directories_and_unwritable_paths() {
    let dir = tempfile_dir();
    let as_dir = dir.join("d.ply");
    std::fs::create_dir_all(&as_dir).unwrap();
    let e = read_mesh(&as_dir).unwrap_err();
    assert!(
        matches!(e.kind, IoErrorKind::IsDirectory) && e.to_string().contains("d.ply"),
        "{e}"
    );
    let mesh = tet(1.0, DVec3::ZERO);
    assert!(matches!(
        write_mesh(&mesh, &as_dir).unwrap_err().kind,
        IoErrorKind::IsDirectory
    ));
    // Parent missing, and parent a file.
    let e = write_mesh(&mesh, &dir.join("missing/x.ply")).unwrap_err();
    assert!(
        matches!(e.kind, IoErrorKind::Io(_)) && e.to_string().contains("missing"),
        "{e}"
    );
    let file = dir.join("f.ply");
    write_mesh(&mesh, &file).unwrap();
    let e = write_mesh(&mesh, &file.join("x.obj")).unwrap_err();
    assert!(matches!(e.kind, IoErrorKind::Io(_)), "{e}");
    // Unknown extension.
    assert!(matches!(
        read_mesh(&dir.join("x.stl")).unwrap_err().kind,
        IoErrorKind::UnknownExtension { .. }
    ));
    // Missing file.
    let e = read_mesh(&dir.join("none.obj")).unwrap_err();
    assert!(matches!(e.kind, IoErrorKind::Io(_)) && e.to_string().contains("none.obj"));
    // A non-finite mesh cannot be written.
    let mut bad = mesh.clone();
    bad.set_position(VertexId::new(0), DVec3::NAN);
    let e = write_mesh(&bad, &dir.join("nan.ply")).unwrap_err();
    assert!(matches!(e.kind, IoErrorKind::NonFinite { .. }), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

/// A fresh directory under the target's tmp (no tempfile dependency in the root).
fn tempfile_dir() -> std::path::PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("reliability_bad_input_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn bad_proposals_are_refused_by_both_backends_without_touching_the_mesh() {
    for b in Backend::ALL {
        let mut t =
            make_tracker_with(b, tet(1.0, DVec3::ZERO), &TrackerOptions::default()).unwrap();
        let before = t.mesh().clone();
        let n = t.mesh().vertex_capacity();
        let good = t.mesh().positions().to_vec();
        for len in [0, n - 1, n + 1] {
            let p = vec![DVec3::ZERO; len];
            assert_eq!(
                t.advance(&p),
                Err(TrackError::ProposalLength {
                    expected: n,
                    got: len
                }),
                "{b}"
            );
        }
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            let mut p = good.clone();
            p[2].y = bad;
            match t.advance(&p) {
                Err(TrackError::NonFiniteProposal { vertex, .. }) => assert_eq!(vertex.idx(), 2),
                other => panic!("{b}: {bad}: {other:?}"),
            }
        }
        // Finite, but past the range where the exact predicates are exact.
        for bad in [1e31, -1e300] {
            let mut p = good.clone();
            p[3].z = bad;
            match t.advance(&p) {
                Err(TrackError::ProposalOutOfRange { vertex, .. }) => assert_eq!(vertex.idx(), 3),
                other => panic!("{b}: {bad}: {other:?}"),
            }
        }
        assert_eq!(t.mesh().to_raw().1, before.to_raw().1);
        let bits = |m: &LabeledMesh| {
            m.positions()
                .iter()
                .map(|p| p.to_array().map(f64::to_bits))
                .collect::<Vec<_>>()
        };
        assert_eq!(bits(t.mesh()), bits(&before), "{b}");
    }
}
