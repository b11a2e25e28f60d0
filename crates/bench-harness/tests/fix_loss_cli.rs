//! `surftrack fix` never loses a material silently (issue 16): a repair that would is exit
//! code 1 with a message naming the material and its volumes, `--allow-loss` writes it
//! with a warning on stderr, and the JSON record carries every label's volumes.

mod common;

use std::path::Path;

use common::{surftrack, text};
use glam::DVec3;
use mesh_core::LabeledMesh;
use serde_json::Value;

/// The box `[lo, hi]`, 12 outward triangles, labels `[0, inside]`, appended to the lists.
fn push_box(
    lo: DVec3,
    hi: DVec3,
    inside: u32,
    p: &mut Vec<DVec3>,
    t: &mut Vec<[u32; 3]>,
    l: &mut Vec<[u32; 2]>,
) {
    let o = p.len() as u32;
    p.extend((0..8).map(|i| {
        DVec3::new(
            if i & 1 == 0 { lo.x } else { hi.x },
            if i & 2 == 0 { lo.y } else { hi.y },
            if i & 4 == 0 { lo.z } else { hi.z },
        )
    }));
    for [a, b, c, d] in [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ] {
        t.push([o + a, o + b, o + c]);
        t.push([o + a, o + c, o + d]);
        l.extend([[0, inside]; 2]);
    }
}

/// Two overlapping unit boxes (labels 1, 2) and a small box of label 3 poking into box 1,
/// with no grid node inside it at ℓ = 0.5.
fn write_scene(dir: &Path) {
    let (mut p, mut t, mut l) = (Vec::new(), Vec::new(), Vec::new());
    push_box(DVec3::ZERO, DVec3::ONE, 1, &mut p, &mut t, &mut l);
    push_box(
        DVec3::splat(0.4),
        DVec3::splat(1.4),
        2,
        &mut p,
        &mut t,
        &mut l,
    );
    push_box(
        DVec3::new(-0.12, 0.13, 0.17),
        DVec3::new(0.08, 0.29, 0.33),
        3,
        &mut p,
        &mut t,
        &mut l,
    );
    let m = LabeledMesh::from_raw(p, &t, &l).expect("boxes");
    mesh_core::io::write_mesh(&m, &dir.join("boxes.ply")).expect("write");
}

#[test]
fn fix_exits_1_naming_a_lost_material_and_allow_loss_warns() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_scene(d);
    let out = surftrack(&["fix", "boxes.ply", "out.ply", "--cell", "0.5"], d);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("material 3 vanished (volume 0.005120"),
        "{err}"
    );
    assert!(
        !d.join("out.ply").exists(),
        "a lossy repair must not be written"
    );

    let out = surftrack(
        &[
            "fix",
            "boxes.ply",
            "out.ply",
            "--cell",
            "0.5",
            "--allow-loss",
            "--json",
        ],
        d,
    );
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{err}");
    assert!(
        err.contains("warning: accepted loss: material 3 vanished"),
        "{err}"
    );
    let record: Value = serde_json::from_slice(&out.stdout).expect("JSON record");
    let report = &record["report"];
    assert_eq!(report["vanished"], serde_json::json!([3]));
    let volumes = report["volumes"].as_array().expect("volumes");
    let labels: Vec<u64> = volumes
        .iter()
        .map(|v| v["label"].as_u64().unwrap())
        .collect();
    assert_eq!(labels, [1, 2, 3]);
    assert_eq!(volumes[2]["after"].as_f64(), Some(0.0));
    assert!((volumes[0]["before"].as_f64().unwrap() - 1.0).abs() < 1e-9);
    assert!(report["volume_check"]["reference"].as_f64().unwrap() > 1.7);
    // The improvement's own report: its committed edits are the report's count.
    let improvement = &report["improvement"];
    let done = |op: &str| improvement[op]["done"].as_u64().expect("counts");
    let edits = done("split") + done("collapse") + done("flip") + done("smooth");
    let edits = edits + improvement["separations"].as_u64().unwrap();
    let edits = edits + improvement["pinched"].as_u64().unwrap();
    assert_eq!(report["improve_edits"].as_u64(), Some(edits));
    assert!(improvement["vetoes"].is_object());
    // The wall time, not more than the stages (the reference overlaps improvement).
    let seconds = report["seconds"].as_f64().unwrap();
    let stages: f64 = report["stages"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["seconds"].as_f64().unwrap())
        .sum();
    assert!(
        seconds > 0.0 && seconds <= stages + 0.05,
        "{seconds} vs {stages}"
    );
    assert!(d.join("out.ply").exists());
}

#[test]
fn fix_returns_a_clean_coarse_cube_unchanged() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (mut p, mut t, mut l) = (Vec::new(), Vec::new(), Vec::new());
    push_box(DVec3::ZERO, DVec3::ONE, 1, &mut p, &mut t, &mut l);
    let m = LabeledMesh::from_raw(p, &t, &l).expect("cube");
    mesh_core::io::write_mesh(&m, &d.join("cube.ply")).expect("write");
    let out = surftrack(&["fix", "cube.ply", "out.ply", "--json"], d);
    assert_eq!(out.status.code(), Some(0), "{}", text(&out.stderr));
    let record: Value = serde_json::from_slice(&out.stdout).expect("JSON record");
    assert_eq!(record["report"]["clean_input"], Value::Bool(true));
    assert_eq!(record["report"]["triangles_out"].as_u64(), Some(12));
    assert!(record["report"]["improvement"].is_null());
    let back = mesh_core::io::read_mesh(&d.join("out.ply")).expect("read");
    assert_eq!(back.to_raw(), m.to_raw());
}
