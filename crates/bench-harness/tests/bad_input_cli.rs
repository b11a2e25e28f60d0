//! The bad-input catalogue through the `surftrack` binary (issue 7, item 1): every broken
//! input gives exit code 2 (unreadable input, unwritable output) or 1 (a readable mesh
//! that is invalid, or a repair that failed), never a panic (101), with a message on
//! stderr — or in the `--json` record — naming the file and the problem.
//! The library-level catalogue is `tests/reliability_bad_input.rs` in the root package.

mod common;

use std::path::{Path, PathBuf};
use std::process::Output;

use common::{surftrack, text};

/// Asserts the exit code and that stderr (or stdout, for JSON records) mentions every
/// needle, case-insensitively.
fn expect(out: &Output, code: i32, needles: &[&str], what: &str) {
    let all = format!("{}{}", text(&out.stderr), text(&out.stdout)).to_lowercase();
    assert_eq!(
        out.status.code(),
        Some(code),
        "{what}: exit code; output:\n{all}"
    );
    for n in needles {
        assert!(
            all.contains(&n.to_lowercase()),
            "{what}: output does not mention {n:?}:\n{all}"
        );
    }
    assert!(!all.contains("panicked"), "{what}: panicked:\n{all}");
}

const HEADER: &str = "ply\nformat ascii 1.0\nelement vertex 4\nproperty double x\n\
property double y\nproperty double z\nelement face 4\nproperty list uchar int vertex_indices\n\
property int label_front\nproperty int label_back\nend_header\n";
const VERTS: &str = "0 0 0\n1 0 0\n0 1 0\n0 0 1\n";
const FACES: &str = "3 0 2 1 0 1\n3 0 1 3 0 1\n3 1 2 3 0 1\n3 0 3 2 0 1\n";

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

/// Files that cannot be read: `validate`, `convert` and `fix` all exit 2 naming the file
/// and the problem.
#[test]
fn unreadable_inputs_exit_2_with_the_problem_named() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let truncated_binary = {
        let mut mesh_bytes = HEADER.replace("ascii", "binary_little_endian").into_bytes();
        mesh_bytes.extend_from_slice(&1.0f64.to_le_bytes()); // half a vertex
        mesh_bytes
    };
    let cases: Vec<(&str, Vec<u8>, Vec<&str>)> = vec![
        ("empty.ply", vec![], vec!["empty"]),
        ("empty.obj", vec![], vec!["empty"]),
        (
            "truncated.ply",
            format!("{HEADER}{VERTS}3 0 2 1 0 1\n3 0 1").into_bytes(),
            vec!["face"],
        ),
        ("truncated_bin.ply", truncated_binary, vec!["vertex"]),
        (
            "count.ply",
            format!("{}{VERTS}{FACES}", HEADER.replace("face 4", "face 5")).into_bytes(),
            vec!["face 4", "end of data"],
        ),
        (
            "range.ply",
            format!("{HEADER}{VERTS}{}", FACES.replace("3 1 2 3", "3 1 2 9")).into_bytes(),
            vec!["face 2", "index 9", "out of range"],
        ),
        (
            "quad.ply",
            format!("{HEADER}{VERTS}{}", FACES.replace("3 0 1 3", "4 0 1 3 2")).into_bytes(),
            vec!["face 1", "only triangles"],
        ),
        (
            "nan.ply",
            format!("{HEADER}{}{FACES}", VERTS.replace("0 1 0", "0 nan 0")).into_bytes(),
            vec!["vertex 2", "not finite"],
        ),
        (
            "inf.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 -inf 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n".to_vec(),
            vec!["line 3", "not finite"],
        ),
        (
            "half_labels.ply",
            format!(
                "{}{VERTS}3 0 2 1 0\n3 0 1 3 0\n3 1 2 3 0\n3 0 3 2 0\n",
                HEADER.replace("property int label_back\n", "")
            )
            .into_bytes(),
            vec!["label_back"],
        ),
        (
            "open.obj",
            b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\n".to_vec(),
            vec!["open surface"],
        ),
        (
            "utf8.ply",
            {
                let mut b = format!("{HEADER}{VERTS}{FACES}").into_bytes();
                b[10] = 0xff;
                b
            },
            vec!["utf-8"],
        ),
        (
            "utf8.obj",
            b"v 0 \xff\xfe 0\n".to_vec(),
            vec!["line 1", "cannot parse"],
        ),
        // Files that read without error but hold no triangle: validate called them valid
        // and convert wrote an empty mesh.
        (
            "points.obj",
            b"# a point cloud\nv 0 0 0\nv 1 0 0\nv 0 1 0\n".to_vec(),
            vec!["no triangles", "3 vertices"],
        ),
        (
            "no_faces.ply",
            format!("{}{VERTS}", HEADER.replace("face 4", "face 0")).into_bytes(),
            vec!["no triangles", "4 vertices"],
        ),
    ];
    for (name, bytes, needles) in &cases {
        let path = write(d, name, bytes);
        let p = path.to_str().unwrap();
        let mut needles = needles.clone();
        needles.push(name);
        expect(
            &surftrack(&["validate", p], d),
            2,
            &needles,
            &format!("validate {name}"),
        );
        expect(
            &surftrack(&["convert", p, "out.obj"], d),
            2,
            &needles,
            &format!("convert {name}"),
        );
        expect(
            &surftrack(&["fix", p, "out.ply"], d),
            2,
            &needles,
            &format!("fix {name}"),
        );
        let json = surftrack(&["validate", p, "--json"], d);
        expect(&json, 2, &needles, &format!("validate --json {name}"));
        let record: serde_json::Value = serde_json::from_slice(&json.stdout).unwrap();
        assert_eq!(record["valid"], false);
    }
    // A directory given as the input file, and a missing file.
    std::fs::create_dir(d.join("dir.ply")).unwrap();
    for cmd in [
        vec!["validate", "dir.ply"],
        vec!["convert", "dir.ply", "o.obj"],
        vec!["fix", "dir.ply", "o.ply"],
    ] {
        expect(
            &surftrack(&cmd, d),
            2,
            &["dir.ply", "directory"],
            &cmd.join(" "),
        );
    }
    expect(
        &surftrack(&["validate", "missing.obj"], d),
        2,
        &["missing.obj"],
        "missing",
    );
    expect(
        &surftrack(&["validate", "mesh.stl"], d),
        2,
        &["stl"],
        "extension",
    );
}

/// Readable meshes that break an invariant: `validate` exits 1 naming it, `fix` exits 1
/// for what it cannot repair.
#[test]
fn invalid_meshes_exit_1_with_the_defect_named() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cases = [
        (
            "same_label.ply",
            format!(
                "{HEADER}{VERTS}{}",
                FACES.replacen("3 0 2 1 0 1", "3 0 2 1 1 1", 1)
            ),
            "label",
        ),
        (
            "open.ply",
            format!(
                "{}{VERTS}{}",
                HEADER.replace("face 4", "face 3"),
                &FACES[..FACES.len() - 12]
            ),
            "boundary",
        ),
        (
            "duplicate.ply",
            format!(
                "{}{VERTS}{FACES}3 0 2 1 0 1\n",
                HEADER.replace("face 4", "face 5")
            ),
            "duplicate",
        ),
    ];
    for (name, body, needle) in cases {
        let path = write(d, name, body.as_bytes());
        let p = path.to_str().unwrap();
        expect(
            &surftrack(&["validate", p], d),
            1,
            &[needle, "invalid"],
            &format!("validate {name}"),
        );
        expect(
            &surftrack(&["fix", p, "out.ply"], d),
            1,
            &[needle],
            &format!("fix {name}"),
        );
        let out = surftrack(&["fix", p, "out.ply", "--json"], d);
        expect(&out, 1, &[needle], &format!("fix --json {name}"));
        let record: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(record["valid"], false);
        assert!(record["error"].as_str().is_some());
    }
    // Inconsistent labels: invalid for validate, repaired by fix.
    let inconsistent = write(
        d,
        "inconsistent.ply",
        format!(
            "{HEADER}{VERTS}{}",
            FACES.replacen("3 0 2 1 0 1", "3 0 2 1 0 2", 1)
        )
        .as_bytes(),
    );
    let p = inconsistent.to_str().unwrap();
    expect(
        &surftrack(&["validate", p], d),
        1,
        &["inconsistent"],
        "validate inconsistent",
    );
    let out = surftrack(&["fix", p, "fixed.ply", "--cell", "0.25"], d);
    assert!(
        matches!(out.status.code(), Some(0 | 1)),
        "{}",
        text(&out.stderr)
    );
    if out.status.success() {
        expect(
            &surftrack(&["validate", "fixed.ply"], d),
            0,
            &["valid"],
            "validate fixed",
        );
    }
}

/// Outputs that cannot be written: exit 2 naming the path, for every writing command.
#[test]
fn unwritable_outputs_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let input = write(d, "tet.ply", format!("{HEADER}{VERTS}{FACES}").as_bytes());
    let p = input.to_str().unwrap();
    std::fs::create_dir(d.join("taken.ply")).unwrap();
    std::fs::write(d.join("file"), b"x").unwrap();
    for out_path in ["taken.ply", "file/sub/out.ply", "out.xyz"] {
        let needle = if out_path.ends_with("xyz") {
            "xyz"
        } else {
            out_path.split('/').next().unwrap()
        };
        expect(
            &surftrack(&["convert", p, out_path], d),
            2,
            &[needle],
            &format!("convert -> {out_path}"),
        );
        expect(
            &surftrack(&["convert", p, out_path, "--binary"], d),
            2,
            &[needle],
            &format!("convert --binary -> {out_path}"),
        );
        expect(
            &surftrack(&["fix", p, out_path], d),
            2,
            &[needle],
            &format!("fix -> {out_path}"),
        );
        expect(
            &surftrack(
                &[
                    "generate",
                    "double-bubble",
                    "--resolution",
                    "3",
                    "--out",
                    out_path,
                ],
                d,
            ),
            2,
            &[needle],
            &format!("generate -> {out_path}"),
        );
    }
    // The good paths still work.
    expect(
        &surftrack(&["convert", p, "ok.obj"], d),
        0,
        &["ok.obj"],
        "convert ok",
    );
    expect(
        &surftrack(&["validate", "ok.obj"], d),
        0,
        &["valid"],
        "validate ok",
    );
}

/// A triangle soup (every face on its own vertices, as STL-style exporters write it):
/// `validate` reports the file as written and hints at stitching; `fix` and `run --mesh`
/// stitch it into the closed solid, labelled or not, and say so.
#[test]
fn triangle_soups_are_stitched_by_the_working_commands() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let corners = ["0 0 0", "1 0 0", "0 1 0", "0 0 1"];
    let faces = [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]];
    let (mut ply_verts, mut ply_faces, mut obj) = (String::new(), String::new(), String::new());
    for (k, f) in faces.iter().enumerate() {
        for &v in f {
            ply_verts += &format!("{}\n", corners[v]);
            obj += &format!("v {}\n", corners[v]);
        }
        ply_faces += &format!("3 {} {} {} 0 1\n", 3 * k, 3 * k + 1, 3 * k + 2);
        obj += &format!("f {} {} {}\n", 3 * k + 1, 3 * k + 2, 3 * k + 3);
    }
    let header = HEADER.replace("vertex 4", "vertex 12");
    let labelled = write(
        d,
        "soup.ply",
        format!("{header}{ply_verts}{ply_faces}").as_bytes(),
    );
    let unlabelled = write(d, "soup.obj", obj.as_bytes());
    for (path, code) in [(&labelled, 1), (&unlabelled, 2)] {
        let p = path.to_str().unwrap();
        expect(
            &surftrack(&["validate", p], d),
            code,
            &["8 vertices repeat", "stitch"],
            &format!("validate {p}"),
        );
        let out = surftrack(&["fix", p, "fixed.ply"], d);
        expect(&out, 0, &["stitched 8 vertices"], &format!("fix {p}"));
        let out = surftrack(&["validate", "fixed.ply", "--json"], d);
        expect(&out, 0, &[], "validate fixed");
        let record: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(record["vertices"], 4, "{record}");
        assert_eq!(record["triangles"], 4, "{record}");
        assert_eq!(record["stitchable_vertices"], 0, "{record}");
        let out = surftrack(
            &[
                "run",
                "--mesh",
                p,
                "--flow",
                "rotation",
                "--tracker",
                "collision",
                "--steps",
                "2",
            ],
            d,
        );
        expect(
            &out,
            0,
            &["stitched 8 vertices"],
            &format!("run --mesh {p}"),
        );
    }
}
