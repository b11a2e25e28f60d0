//! Short property-test versions of the fuzz targets in `fuzz/` (issue 7, item 3), run on
//! every `cargo test`, plus the replay of every kept fuzz input.
//!
//! The fuzz crate's checks are compiled in here from `fuzz/src/lib.rs` (it depends on
//! nothing but this package), so a proptest case and a libFuzzer input are decoded and
//! judged by the same code. Kept inputs live in `tests/data/regressions/<target>/`, one
//! file per crash the fuzzers found, and are replayed by [`kept_fuzz_inputs_replay_clean`];
//! the named regression tests that go with them are at the end of this file.

#[allow(dead_code)]
#[path = "../fuzz/src/lib.rs"]
mod fuzz_checks;

use std::path::Path;

use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};
use surftrack::mesh_core::io::{PlyFormat, write_obj, write_ply};
use surftrack::mesh_core::{DVec3, LabeledMesh};

/// A fixed seed and a small case count: the same few seconds every run.
fn config(cases: u32) -> Config {
    Config {
        cases,
        rng_seed: RngSeed::Fixed(0x005e_ed07),
        failure_persistence: None,
        ..Config::default()
    }
}

/// A labelled two-tetrahedra mesh in every format, as seeds to mutate.
fn seed_files() -> Vec<(bool, Vec<u8>)> {
    let p = vec![
        DVec3::ZERO,
        DVec3::X,
        DVec3::Y,
        DVec3::Z,
        DVec3::new(2.0, 0.0, 0.0),
        DVec3::new(3.0, 0.0, 0.0),
        DVec3::new(2.0, 1.0, 0.0),
        DVec3::new(2.0, 0.0, 1.0),
    ];
    let f = [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]];
    let tris: Vec<[u32; 3]> = f
        .iter()
        .chain(f.iter())
        .enumerate()
        .map(|(i, t)| t.map(|v| v + if i < 4 { 0 } else { 4 }))
        .collect();
    let labels: Vec<[u32; 2]> = (0..8).map(|i| [0, if i < 4 { 1 } else { 2 }]).collect();
    let mesh = LabeledMesh::from_raw(p, &tris, &labels).unwrap();
    let mut out = Vec::new();
    for format in [
        PlyFormat::Ascii,
        PlyFormat::BinaryLittleEndian,
        PlyFormat::BinaryBigEndian,
    ] {
        let mut buf = Vec::new();
        write_ply(&mesh, &mut buf, format).unwrap();
        out.push((true, buf));
    }
    let mut buf = Vec::new();
    write_obj(&mesh, &mut buf).unwrap();
    out.push((false, buf));
    out
}

/// A seed with up to four byte edits (overwrite, insert, delete) and an optional cut.
fn mutated() -> impl Strategy<Value = (bool, Vec<u8>)> {
    let seeds = seed_files();
    let n = seeds.len();
    (
        0..n,
        prop::collection::vec((any::<prop::sample::Index>(), any::<u8>(), 0u8..3), 0..4),
        prop::option::of(any::<prop::sample::Index>()),
    )
        .prop_map(move |(which, edits, cut)| {
            let (is_ply, mut bytes) = seeds[which].clone();
            for (at, byte, kind) in edits {
                let i = at.index(bytes.len().max(1)).min(bytes.len());
                match kind {
                    0 if i < bytes.len() => bytes[i] = byte,
                    1 => bytes.insert(i, byte),
                    _ if i < bytes.len() => {
                        bytes.remove(i);
                    }
                    _ => {}
                }
            }
            if let Some(cut) = cut {
                let len = cut.index(bytes.len() + 1);
                bytes.truncate(len);
            }
            (is_ply, bytes)
        })
}

proptest! {
    #![proptest_config(config(256))]

    /// Fuzz targets `ply` and `obj`: no panic, exact round trips of whatever is accepted.
    #[test]
    fn readers_never_panic_on_mutated_files((is_ply, bytes) in mutated()) {
        if is_ply {
            fuzz_checks::check_ply(&bytes);
        } else {
            fuzz_checks::check_obj(&bytes);
        }
    }

    /// Both readers on arbitrary bytes.
    #[test]
    fn readers_never_panic_on_arbitrary_bytes(bytes in prop::collection::vec(any::<u8>(), 0..256)) {
        fuzz_checks::check_ply(&bytes);
        fuzz_checks::check_obj(&bytes);
    }
}

proptest! {
    #![proptest_config(config(64))]

    /// Fuzz target `fix`: no panic; `Ok` is a valid mesh.
    #[test]
    fn fix_on_small_arbitrary_meshes(bytes in prop::collection::vec(any::<u8>(), 0..96)) {
        fuzz_checks::check_fix(&bytes);
    }

    /// Fuzz target `advance`, both backends: `Ok` is valid, `Err` leaves the mesh as it was.
    #[test]
    fn advance_on_small_arbitrary_meshes(bytes in prop::collection::vec(any::<u8>(), 0..160)) {
        fuzz_checks::check_advance(&bytes);
    }
}

/// The decoder produces meshes both backends accept, so the `advance` properties above
/// exercise real steps and not only the construction checks.
#[test]
fn decoded_meshes_are_often_valid_tracker_inputs() {
    use surftrack::mesh_core::validate::{ValidateOptions, validate};
    let mut valid = 0;
    for k in 0..64u8 {
        let bytes: Vec<u8> = (0..64)
            .map(|i: u8| i.wrapping_mul(37).wrapping_add(k.wrapping_mul(11)))
            .collect();
        let mut b = fuzz_checks::Bytes::new(&bytes);
        if let Some(m) = fuzz_checks::decode_mesh(&mut b)
            && validate(&m, &ValidateOptions::default()).is_valid()
        {
            valid += 1;
        }
    }
    println!("{valid} of 64 decoded meshes are valid");
    assert!(valid >= 8, "only {valid} of 64 decoded meshes are valid");
}

/// Every kept fuzz input, replayed through its target's check.
#[test]
fn kept_fuzz_inputs_replay_clean() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/regressions");
    type Check = fn(&[u8]);
    let targets: [(&str, Check); 4] = [
        ("ply", fuzz_checks::check_ply),
        ("obj", fuzz_checks::check_obj),
        ("fix", fuzz_checks::check_fix),
        ("advance", fuzz_checks::check_advance),
    ];
    for (target, check) in targets {
        let Ok(dir) = std::fs::read_dir(root.join(target)) else {
            continue;
        };
        for entry in dir.flatten() {
            let bytes = std::fs::read(entry.path()).unwrap();
            println!("replaying {}", entry.path().display());
            check(&bytes);
        }
    }
}

/// Reads a kept fuzz input.
fn kept(target: &str, name: &str) -> Vec<u8> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/regressions")
        .join(target)
        .join(name);
    std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// `fix` fuzzing (ASan build) flagged this input as its slowest unit (11 s): three
/// overlapping cells decoded from mostly identical bytes, so their corners coincide in
/// many places. In an ordinary build it must stay well inside the resource bounds.
#[test]
fn fix_slow_unit_overlapping_cells_stays_bounded() {
    let bytes = kept("fix", "slow_unit_overlapping_cells.bin");
    let mut b = fuzz_checks::Bytes::new(&bytes);
    let mesh = fuzz_checks::decode_mesh(&mut b).expect("decodes");
    let start = std::time::Instant::now();
    fuzz_checks::check_fix(&bytes);
    let elapsed = start.elapsed();
    println!(
        "{} triangles: fix checked in {elapsed:?}",
        mesh.num_triangles()
    );
    assert!(elapsed < std::time::Duration::from_secs(10), "{elapsed:?}");
}
