//! `bench scaling` end to end at toy sizes: every point runs, the record, report and
//! plots are written, and the slopes cover every stage.

mod common;

use common::{json, surftrack, text};

#[test]
fn scaling_runs_fix_and_step_points_and_fits_slopes() {
    let dir = tempfile::tempdir().unwrap();
    let out = surftrack(
        &[
            "bench",
            "scaling",
            "--fix-triangles",
            "4000,1500",
            "--copies",
            "2",
            "--spheres",
            "2,3",
            "--steps",
            "1",
            "--tracker",
            "grid",
            "--quiet",
            "--out",
            "sc",
        ],
        dir.path(),
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    let record = json(&dir.path().join("sc/scaling.json"));
    assert_eq!(record["schema"], "surftrack.scaling/1");
    let fix = record["fix"].as_array().unwrap();
    assert_eq!(fix.len(), 2);
    // Smallest first, and the input sizes follow the request.
    let sizes: Vec<u64> = fix
        .iter()
        .map(|p| p["triangles_in"].as_u64().unwrap())
        .collect();
    assert!(sizes[0] < sizes[1], "{sizes:?}");
    for (p, target) in fix.iter().zip([1500.0, 4000.0]) {
        assert_eq!(p["success"], true, "{p}");
        let n = p["triangles_in"].as_f64().unwrap();
        assert!((n / target - 1.0).abs() < 0.5, "{n} for {target}");
        assert!(!p["stages"].as_array().unwrap().is_empty());
        if cfg!(target_os = "linux") {
            assert!(p["peak_rss_mib"].as_f64().unwrap() > 1.0);
            assert!(p["mib_per_million_triangles"].as_f64().is_some());
        }
    }
    let steps = record["steps"].as_array().unwrap();
    assert_eq!(steps.len(), 2);
    assert!(steps.iter().all(|p| p["tracker"] == "grid"));
    let slopes = record["slopes"].as_array().unwrap();
    let what: Vec<&str> = slopes.iter().map(|s| s["what"].as_str().unwrap()).collect();
    for stage in fix[0]["stages"].as_array().unwrap() {
        let name = format!("fix: {}", stage["stage"].as_str().unwrap());
        assert!(what.contains(&name.as_str()), "{name} not in {what:?}");
    }
    assert!(what.contains(&"fix: total") && what.contains(&"grid: seconds per step"));
    for file in ["report.md", "fix_scaling.svg", "steps_scaling.svg"] {
        assert!(dir.path().join("sc").join(file).is_file(), "{file}");
    }
    let bad = surftrack(&["bench", "scaling", "--copies", "0"], dir.path());
    assert_eq!(bad.status.code(), Some(2));
}

/// With `--mesh`, the fix series copies that mesh split in four as often as comes nearest
/// each count: targets that round to one level run once, the next level has four times
/// the triangles, and the report names the mesh.
#[test]
fn scaling_copies_a_given_mesh_at_subdivision_levels() {
    let dir = tempfile::tempdir().unwrap();
    let generated = surftrack(
        &[
            "generate",
            "zalesak",
            "--resolution",
            "6",
            "--out",
            "base.ply",
        ],
        dir.path(),
    );
    assert!(generated.status.success(), "{}", text(&generated.stderr));
    let base = mesh_core::io::read_mesh(&dir.path().join("base.ply"))
        .unwrap()
        .num_triangles();
    let (one, four) = (2 * base, 8 * base);
    let targets = format!("{one},{},{four}", one + 10);
    let out = surftrack(
        &[
            "bench",
            "scaling",
            "--mesh",
            "base.ply",
            "--fix-triangles",
            &targets,
            "--copies",
            "2",
            "--spheres",
            "0",
            "--quiet",
            "--out",
            "sc",
        ],
        dir.path(),
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    let record = json(&dir.path().join("sc/scaling.json"));
    assert_eq!(record["base_mesh"], "base.ply");
    let fix = record["fix"].as_array().unwrap();
    let sizes: Vec<(u64, u64)> = fix
        .iter()
        .map(|p| {
            assert_eq!(p["success"], true, "{p}");
            (
                p["resolution"].as_u64().unwrap(),
                p["triangles_in"].as_u64().unwrap(),
            )
        })
        .collect();
    assert_eq!(sizes, [(0, one as u64), (1, four as u64)]);
    let report = std::fs::read_to_string(dir.path().join("sc/report.md")).unwrap();
    assert!(report.contains("copies of base.ply"), "{report}");
}
