//! The page's data round-trips: what the browser decodes is the mesh that was read.

use super::*;
use mesh_core::generators::double_bubble;

/// The text of the element `<script … id="ID">…</script>` in `page`.
fn element<'a>(page: &'a str, id: &str) -> &'a str {
    let open = format!("id=\"{id}\">");
    let start = page
        .find(&open)
        .unwrap_or_else(|| panic!("no element {id}"))
        + open.len();
    let len = page[start..].find("</script>").unwrap();
    &page[start..start + len]
}

fn write_run(dir: &Path) -> LabeledMesh {
    let mesh = double_bubble(0.5, 12).unwrap();
    mesh_core::io::write_mesh(&mesh, &dir.join("frame_0000.ply")).unwrap();
    let mut moved = mesh.clone();
    for p in moved.positions_mut() {
        *p *= 1.5;
    }
    mesh_core::io::write_mesh(&moved, &dir.join("frame_0002.ply")).unwrap();
    std::fs::write(
        dir.join("run.json"),
        r#"{"scene":"double-bubble","tracker":"grid","steps":2,"steps_completed":2,"success":true,
            "failure":{"reason":"error","message":"</script><b>not markup</b>","step":null},
            "frames":[{"step":0,"file":"frame_0000.ply"},{"step":2,"file":"frame_0002.ply"}],
            "per_step":[]}"#,
    )
    .unwrap();
    std::fs::write(
        dir.join("plot.svg"),
        "<svg xmlns=\"http://www.w3.org/2000/svg\"/>",
    )
    .unwrap();
    mesh
}

#[test]
fn frames_group_triangles_by_pair_and_keep_every_triangle() {
    let mesh = double_bubble(0.5, 12).unwrap();
    let frame = encode_frame(&mesh);
    let (positions, tris, labels) = mesh.to_raw();
    assert_eq!(frame.positions.len(), positions.len() * 3);
    assert_eq!(frame.triangles.len(), tris.len() * 3);
    let mut covered = 0;
    for p in &frame.pairs {
        assert!(p.lo < p.hi);
        assert_eq!(p.first as usize, covered, "pairs are contiguous, in order");
        covered += p.count as usize;
        let expected = labels
            .iter()
            .filter(|l| (l[0].min(l[1]), l[0].max(l[1])) == (p.lo, p.hi))
            .count();
        assert_eq!(p.count as usize, expected, "pair {}|{}", p.lo, p.hi);
    }
    assert_eq!(covered, tris.len());
    // The same triangles, as sets of positions.
    let key = |t: &[u32], pos: &dyn Fn(u32) -> [f32; 3]| {
        let mut k: Vec<[u32; 3]> = t.iter().map(|&v| pos(v).map(f32::to_bits)).collect();
        k.sort();
        k
    };
    let mut ours: Vec<_> = frame
        .triangles
        .chunks(3)
        .map(|t| {
            key(t, &|v| {
                let i = v as usize * 3;
                [
                    frame.positions[i],
                    frame.positions[i + 1],
                    frame.positions[i + 2],
                ]
            })
        })
        .collect();
    let mut theirs: Vec<_> = tris
        .iter()
        .map(|t| key(t, &|v| positions[v as usize].to_array().map(|x| x as f32)))
        .collect();
    ours.sort();
    theirs.sort();
    assert_eq!(ours, theirs);
    assert!(frame.bounds[0][0] < frame.bounds[1][0]);
}

#[test]
fn the_page_carries_the_frames_the_record_and_three_js() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = write_run(dir.path());
    let source = ViewSource::open(dir.path()).unwrap();
    assert_eq!(
        source.frames.iter().map(|f| f.step).collect::<Vec<_>>(),
        [0, 2]
    );
    let mut page = Vec::new();
    let stats = write_page(&[source], &PageOptions::default(), &mut page).unwrap();
    let page = String::from_utf8(page).unwrap();
    assert_eq!(stats.bytes as usize, page.len());
    assert_eq!((stats.panels, stats.frames), (1, 2));
    assert_eq!(stats.max_triangles, mesh.num_triangles());
    // No network: nothing is fetched from anywhere.
    assert!(!page.contains("src=\"http") && !page.contains("https://unpkg"));
    assert!(page.contains("\"three\":\"data:text/javascript;base64,"));
    // The decoded arrays are the mesh's.
    let positions = BASE64.decode(element(&page, "r0f0p")).unwrap();
    let expected = encode_frame(&mesh);
    let floats: Vec<f32> = positions
        .chunks(4)
        .map(|b| f32::from_le_bytes(b.try_into().unwrap()))
        .collect();
    assert_eq!(floats, expected.positions);
    let tris = BASE64.decode(element(&page, "r0f1t")).unwrap();
    assert_eq!(tris.len(), mesh.num_triangles() * 12);
    // The record is there, and its text cannot close the script element.
    let meta: Value = serde_json::from_str(element(&page, "surftrack-meta")).unwrap();
    assert_eq!(meta["runs"][0]["record"]["scene"], "double-bubble");
    assert_eq!(
        meta["runs"][0]["record"]["failure"]["message"],
        "</script><b>not markup</b>"
    );
    assert_eq!(meta["runs"][0]["frames"][1]["step"], 2);
    assert_eq!(meta["runs"][0]["plots"][0]["name"], "plot.svg");
    assert_eq!(
        meta["pairs"][0][2],
        palette::hex(palette::pair_colour(0, 1))
    );
    assert!(page.matches("</script>").count() >= 2 * 2 + 3);
    assert!(!element(&page, "surftrack-meta").contains('<'));
}

#[test]
fn inputs_are_run_dirs_records_mesh_dirs_or_files() {
    let dir = tempfile::tempdir().unwrap();
    write_run(dir.path());
    let by_record = ViewSource::open(&dir.path().join("run.json")).unwrap();
    assert!(by_record.record.is_some() && by_record.title.starts_with("double-bubble · grid"));
    let file = ViewSource::open(&dir.path().join("frame_0002.ply")).unwrap();
    assert_eq!(file.frames.len(), 1);
    std::fs::remove_file(dir.path().join("run.json")).unwrap();
    let plain = ViewSource::open(dir.path()).unwrap();
    assert_eq!(plain.frames.len(), 2);
    assert!(plain.record.is_none());
    let empty = tempfile::tempdir().unwrap();
    assert!(matches!(
        ViewSource::open(empty.path()),
        Err(ViewError::NoFrames { .. })
    ));
    assert!(matches!(
        ViewSource::open(&empty.path().join("missing")),
        Err(ViewError::Input { .. })
    ));
    // A broken frame is an error naming it.
    std::fs::write(dir.path().join("frame_0002.ply"), "ply\nnot a header\n").unwrap();
    let broken = ViewSource::open(dir.path()).unwrap();
    let err = write_page(&[broken], &PageOptions::default(), std::io::sink()).unwrap_err();
    assert!(err.to_string().contains("frame_0002.ply"), "{err}");
}

#[test]
fn thinning_keeps_the_first_and_last_frames() {
    let mut source = ViewSource {
        title: String::new(),
        frames: (0..10)
            .map(|step| FrameFile {
                step,
                path: PathBuf::new(),
            })
            .collect(),
        record: None,
        plots: Vec::new(),
    };
    source.thin(4);
    let steps: Vec<usize> = source.frames.iter().map(|f| f.step).collect();
    assert_eq!(steps, [0, 4, 8, 9]);
}
