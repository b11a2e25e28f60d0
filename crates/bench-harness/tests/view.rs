//! `surftrack view` and the report pictures end to end: the page of a small run in
//! headless Chromium (WebGL through SwiftShader, driven by Selenium: see
//! `tests/browser/view_page.py`), and the PNGs and pages that `run` and the benchmarks
//! write.
//!
//! The browser test needs Debian's `chromium`, `chromium-driver` and `python3-selenium`
//! (`.ci/run` installs them). Without them it fails under `CI=true` and otherwise skips
//! with a loud note on stderr.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::{json, surftrack, text};
use tiny_skia::Pixmap;

/// A Python that can import selenium (Debian's `python3-selenium` lives beside
/// `/usr/bin/python3`, which need not be the first `python3` on the PATH).
fn python_with_selenium() -> Option<PathBuf> {
    ["python3", "/usr/bin/python3"].into_iter().find_map(|p| {
        let ok = Command::new(p)
            .args(["-c", "import selenium"])
            .output()
            .is_ok_and(|o| o.status.success());
        ok.then(|| PathBuf::from(p))
    })
}

/// What the browser test is missing, if anything.
fn browser_missing() -> Option<String> {
    let chromium = ["/usr/bin/chromium", "/usr/bin/chromium-browser"]
        .iter()
        .any(|p| Path::new(p).exists());
    let driver = ["/usr/bin/chromedriver", "/usr/lib/chromium/chromedriver"]
        .iter()
        .any(|p| Path::new(p).exists());
    let mut missing = Vec::new();
    if !chromium {
        missing.push("chromium");
    }
    if !driver {
        missing.push("chromium-driver");
    }
    if python_with_selenium().is_none() {
        missing.push("python3-selenium");
    }
    (!missing.is_empty()).then(|| missing.join(", "))
}

/// A small run: two bubbles growing towards each other, three frames.
fn small_run(dir: &Path) -> PathBuf {
    let out = surftrack(
        &[
            "run",
            "double-bubble",
            "--steps",
            "6",
            "--every",
            "3",
            "--out",
            "db",
            "--quiet",
        ],
        dir,
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    dir.join("db")
}

#[test]
fn the_page_of_a_small_run_works_in_headless_chromium() {
    if let Some(missing) = browser_missing() {
        if std::env::var("CI").is_ok_and(|v| v == "true") {
            panic!("CI=true but the browser test lacks {missing} (.ci/run installs them)");
        }
        eprintln!(
            "\n*** SKIPPED the_page_of_a_small_run_works_in_headless_chromium: missing {missing}\n\
             *** apt-get install -y chromium chromium-driver python3-selenium to run it ***\n"
        );
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let run = small_run(dir.path());
    let out = surftrack(&["view", "db", "--out", "page.html"], dir.path());
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(
        text(&out.stdout).contains("page.html"),
        "{}",
        text(&out.stdout)
    );
    assert!(run.join("frame_0006.ply").exists());
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/browser/view_page.py");
    let result = Command::new(python_with_selenium().unwrap())
        .arg(&script)
        .args([
            dir.path().join("page.html").as_os_str(),
            "1".as_ref(),
            "2".as_ref(),
        ])
        .output()
        .expect("python runs");
    let report = format!("{}{}", text(&result.stdout), text(&result.stderr));
    println!("{report}");
    assert!(
        result.status.success(),
        "the browser checks failed:\n{report}"
    );
    assert!(report.contains("9 checks passed, 0 failed"), "{report}");
}

/// Pixels whose colour has the chromaticity of `colour` (shading scales all channels).
fn count_colour(pixmap: &Pixmap, colour: [u8; 3]) -> usize {
    let chroma = |c: [u8; 3]| {
        let s = c.iter().map(|&x| f64::from(x)).sum::<f64>() + 1e-9;
        [f64::from(c[0]) / s, f64::from(c[1]) / s]
    };
    let target = chroma(colour);
    pixmap
        .pixels()
        .iter()
        .map(|p| [p.red(), p.green(), p.blue()])
        .filter(|&c| c != [255, 255, 255])
        .filter(|&c| {
            let q = chroma(c);
            (q[0] - target[0]).hypot(q[1] - target[1]) < 0.02
        })
        .count()
}

/// The PNG files a report links, read.
fn linked_pictures(dir: &Path, report: &str) -> Vec<(String, Pixmap)> {
    report
        .split("](pictures/")
        .skip(1)
        .map(|rest| {
            let name = &rest[..rest.find(')').unwrap()];
            let pixmap = Pixmap::load_png(dir.join("pictures").join(name))
                .unwrap_or_else(|e| panic!("{name}: {e}"));
            (name.to_string(), pixmap)
        })
        .collect()
}

#[test]
fn run_writes_a_page_and_a_report_with_pictures_of_each_material() {
    let dir = tempfile::tempdir().unwrap();
    let out = surftrack(
        &[
            "run",
            "double-bubble",
            "--steps",
            "6",
            "--every",
            "3",
            "--out",
            "db",
        ],
        dir.path(),
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    let run = dir.path().join("db");
    assert!(
        stdout.contains(&format!(
            "view: {}",
            Path::new("db").join("view.html").display()
        )),
        "{stdout}"
    );
    let page = std::fs::read_to_string(run.join("view.html")).unwrap();
    assert!(
        page.contains("id=\"r0f2t\""),
        "all three frames in the page"
    );
    let report = std::fs::read_to_string(run.join("report.md")).unwrap();
    assert!(report.contains("[view.html](view.html)"), "{report}");
    let pictures = linked_pictures(&run, &report);
    assert_eq!(pictures.len(), 3, "first, last, cut-away: {report}");
    for (name, p) in &pictures {
        assert_eq!((p.width(), p.height()), (320, 240), "{name}");
        let blue = count_colour(p, [31, 119, 180]);
        let orange = count_colour(p, [255, 127, 14]);
        assert!(
            blue > 500 && orange > 500,
            "{name}: both bubbles show ({blue}, {orange})"
        );
    }
    // The last frame's bubbles are bigger: the same camera shows more of them.
    let area = |p: &Pixmap| count_colour(p, [31, 119, 180]) + count_colour(p, [255, 127, 14]);
    assert!(
        area(&pictures[1].1) > area(&pictures[0].1),
        "the bubbles grew"
    );
    // The same frames make the same pictures.
    let again = tempfile::tempdir().unwrap();
    let out = surftrack(
        &[
            "run",
            "double-bubble",
            "--steps",
            "6",
            "--every",
            "3",
            "--out",
            "db",
            "-q",
        ],
        again.path(),
    );
    assert!(out.status.success());
    for (name, _) in &pictures {
        let a = std::fs::read(run.join("pictures").join(name)).unwrap();
        let b = std::fs::read(again.path().join("db/pictures").join(name)).unwrap();
        assert_eq!(a, b, "{name} is deterministic");
    }
    // --no-view writes neither.
    let out = surftrack(
        &[
            "run",
            "double-bubble",
            "--steps",
            "1",
            "--out",
            "nv",
            "--no-view",
            "-q",
        ],
        dir.path(),
    );
    assert!(out.status.success());
    assert!(!dir.path().join("nv/view.html").exists() && !dir.path().join("nv/report.md").exists());
}

#[test]
fn compare_pictures_both_backends_with_one_camera_and_links_a_page() {
    let dir = tempfile::tempdir().unwrap();
    let out = surftrack(
        &[
            "bench",
            "compare",
            "double-bubble",
            "--steps",
            "2",
            "--out",
            "cmp",
            "-q",
        ],
        dir.path(),
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    let cmp = dir.path().join("cmp");
    let record = json(&cmp.join("compare.json"));
    let report = std::fs::read_to_string(cmp.join("compare.md")).unwrap();
    let pictures = linked_pictures(&cmp, &report);
    let ran = record["rows"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|r| r["run"]["initial_triangles"].as_u64() > Some(0))
        .count();
    assert!(ran >= 1);
    assert_eq!(pictures.len(), 3 * ran, "{report}");
    // One camera: the first frames (the same initial mesh) are the same picture.
    if ran == 2 {
        assert_eq!(
            pictures[0].1.data(),
            pictures[3].1.data(),
            "same camera, same mesh"
        );
    }
    assert!(report.contains("[view.html](view.html)"));
    let page = std::fs::read_to_string(cmp.join("view.html")).unwrap();
    assert_eq!(
        page.matches("type=\"application/octet-stream\" id=\"r")
            .count(),
        2 * 2 * ran
    );
    // The children kept only their first and last frames.
    let grid = json(&cmp.join("double-bubble-grid/run.json"));
    let steps: Vec<u64> = grid["frames"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["step"].as_u64().unwrap())
        .collect();
    assert_eq!(steps, [0, 2]);
}

#[test]
fn robustness_and_ablate_reports_show_pictures() {
    let dir = tempfile::tempdir().unwrap();
    let out = surftrack(
        &[
            "bench",
            "robustness",
            "--spheres",
            "2",
            "--seeds",
            "2",
            "--steps",
            "2",
            "-t",
            "grid",
            "--out",
            "rb",
            "-q",
        ],
        dir.path(),
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    let rb = dir.path().join("rb");
    let report = std::fs::read_to_string(rb.join("report.md")).unwrap();
    let pictures = linked_pictures(&rb, &report);
    assert_eq!(
        pictures.len(),
        3,
        "the first seed of the one backend: {report}"
    );
    assert!(
        pictures
            .iter()
            .all(|(_, p)| count_colour(p, [31, 119, 180]) > 100)
    );
    let out = surftrack(
        &[
            "bench",
            "ablate",
            "double-bubble",
            "--preset",
            "curve-smoothing",
            "--seeds",
            "1",
            "--steps",
            "2",
            "--out",
            "ab",
            "-q",
        ],
        dir.path(),
    );
    assert!(out.status.success(), "{}", text(&out.stderr));
    let ab = dir.path().join("ab");
    let report = std::fs::read_to_string(ab.join("report.md")).unwrap();
    assert_eq!(
        linked_pictures(&ab, &report).len(),
        6,
        "two variants: {report}"
    );
    let out = surftrack(
        &[
            "bench",
            "ablate",
            "double-bubble",
            "--preset",
            "curve-smoothing",
            "--seeds",
            "1",
            "--steps",
            "1",
            "--out",
            "np",
            "--no-pictures",
            "-q",
        ],
        dir.path(),
    );
    assert!(out.status.success());
    assert!(!dir.path().join("np/pictures").exists() && !dir.path().join("np/view.html").exists());
}
