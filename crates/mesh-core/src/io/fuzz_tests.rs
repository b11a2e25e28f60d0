//! Property tests: no input makes a reader panic, and whatever a reader accepts writes and
//! reads back identically.

use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};

use super::test_meshes::{assert_same_raw, two_tets};
use super::*;

/// Valid files to mutate: the labelled fixture in every encoding, an unlabelled OBJ, and an
/// ASCII PLY whose skipped lists and elements exercise the skipping paths.
fn seeds() -> Vec<(bool, Vec<u8>)> {
    let mesh = two_tets();
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
    out.push((
        false,
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1/1 2//3 4\nf -3 -2 -1\nf 1 4 3\n"
            .to_vec(),
    ));
    let ply = "ply\nformat ascii 1.0\ncomment c\nelement vertex 3\nproperty list uchar float n\nproperty float x\n\
property float y\nproperty float z\nelement junk 1\nproperty list int uchar s\nelement face 1\n\
property list uchar int vertex_indices\nproperty uchar label_front\nproperty int label_back\nend_header\n\
2 0.5 0.5 0 0 0\n0 1 0 0\n1 7 0 1 0\n3 1 2 3\n3 0 1 2 1 0\n";
    out.push((true, ply.as_bytes().to_vec()));
    out
}

fn read_any(is_ply: bool, bytes: &[u8]) -> Result<LabeledMesh, IoError> {
    if is_ply {
        read_ply(bytes, &ReadOptions::default())
    } else {
        read_obj(bytes, &ReadOptions::default())
    }
}

/// Reading must not panic; an accepted mesh must survive a binary PLY round trip.
fn check(is_ply: bool, bytes: &[u8]) {
    if let Ok(mesh) = read_any(is_ply, bytes) {
        let mut buf = Vec::new();
        write_ply(&mesh, &mut buf, PlyFormat::BinaryLittleEndian).unwrap();
        assert_same_raw(&mesh, &read_ply(&buf[..], &ReadOptions::default()).unwrap());
    }
}

#[derive(Clone, Debug)]
enum Mutation {
    Truncate(usize),
    Flip(usize, u8),
    Insert(usize, Vec<u8>),
    Delete(usize, usize),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        any::<usize>().prop_map(Mutation::Truncate),
        (any::<usize>(), 1..=255u8).prop_map(|(i, x)| Mutation::Flip(i, x)),
        (any::<usize>(), prop::collection::vec(any::<u8>(), 1..8))
            .prop_map(|(i, b)| Mutation::Insert(i, b)),
        (any::<usize>(), 1..16usize).prop_map(|(i, n)| Mutation::Delete(i, n)),
    ]
}

fn apply(bytes: &mut Vec<u8>, m: &Mutation) {
    let at = |i: usize, len: usize| if len == 0 { 0 } else { i % (len + 1) };
    match m {
        Mutation::Truncate(i) => bytes.truncate(at(*i, bytes.len())),
        Mutation::Flip(i, x) if !bytes.is_empty() => {
            let i = i % bytes.len();
            bytes[i] ^= x;
        }
        Mutation::Flip(..) => {}
        Mutation::Insert(i, b) => {
            let i = at(*i, bytes.len());
            bytes.splice(i..i, b.iter().copied());
        }
        Mutation::Delete(i, n) => {
            let i = at(*i, bytes.len());
            let end = (i + n).min(bytes.len());
            bytes.drain(i..end);
        }
    }
}

fn config() -> Config {
    Config {
        cases: 512,
        rng_seed: RngSeed::Fixed(0x5EED),
        failure_persistence: None,
        ..Config::default()
    }
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn random_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..512)) {
        check(true, &bytes);
        check(false, &bytes);
        // Random bytes behind a plausible header reach the data parsers.
        for head in [&b"ply\nformat ascii 1.0\n"[..], b"ply\nformat binary_little_endian 1.0\n"] {
            let mut with_head = head.to_vec();
            with_head.extend_from_slice(&bytes);
            check(true, &with_head);
        }
    }

    #[test]
    fn mutated_valid_files_never_panic(
        seed in 0..6usize,
        mutations in prop::collection::vec(mutation(), 1..6),
    ) {
        let (is_ply, mut bytes) = seeds().swap_remove(seed);
        for m in &mutations {
            apply(&mut bytes, m);
        }
        check(is_ply, &bytes);
    }
}

#[test]
fn every_prefix_of_every_seed_is_handled() {
    for (is_ply, bytes) in seeds() {
        assert!(read_any(is_ply, &bytes).is_ok());
        for cut in 0..bytes.len() {
            check(is_ply, &bytes[..cut]);
        }
    }
}
