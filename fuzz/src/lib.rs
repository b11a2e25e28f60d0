//! What the fuzz targets check, as plain functions of the fuzzer's bytes, so that the root
//! integration tests (`tests/reliability_fuzz_props.rs`, the regression replays) run the
//! very same decoding and checks on kept inputs and on proptest's bytes.
//!
//! Each `check_*` panics exactly when a reliability property is violated:
//!
//! - a reader panics, or accepts a file whose binary PLY round trip is not bit-identical;
//! - `grid_tracker::fix` panics, or returns `Ok` with a mesh failing layers 1–3 of
//!   `validate()`;
//! - a backend's `advance` panics, returns `Ok` with an invalid mesh, or returns `Err`
//!   after changing the mesh (positions compared bitwise, triangles and labels exactly).
//!
//! Meshes are decoded from bytes by [`decode_mesh`]: either a few closed cells (tetrahedra
//! and octahedra with jittered corners, possibly overlapping or inside out — what `fix` and
//! the trackers must handle) or a raw triangle soup (what their input checks must refuse).
//! Coordinates are quantised to multiples of 1/64 so that exact coincidences — vertices on
//! grid planes, coplanar and duplicate triangles — are common rather than measure zero.

use surftrack::mesh_core::io::{PlyFormat, ReadOptions, Unlabeled, read_obj, read_ply, write_ply};
use surftrack::mesh_core::validate::{ValidateOptions, validate};
use surftrack::mesh_core::{DVec3, LabeledMesh};
use surftrack::{Backend, TrackerOptions, make_tracker_with};

/// Reads bytes one at a time, yielding zeros once the input is used up, so every input
/// decodes to something.
pub struct Bytes<'a> {
    data: &'a [u8],
    at: usize,
}

impl<'a> Bytes<'a> {
    /// A reader over `data`.
    pub fn new(data: &'a [u8]) -> Self {
        Bytes { data, at: 0 }
    }

    /// The next byte (0 past the end).
    pub fn byte(&mut self) -> u8 {
        let b = self.data.get(self.at).copied().unwrap_or(0);
        self.at += 1;
        b
    }

    /// A value in `lo..=hi` (`hi >= lo`).
    pub fn range(&mut self, lo: usize, hi: usize) -> usize {
        lo + self.byte() as usize % (hi - lo + 1)
    }

    /// A signed coordinate step: a multiple of 1/64 in [-2, 2).
    pub fn coord(&mut self) -> f64 {
        (self.byte() as i8) as f64 / 64.0
    }
}

/// Corners and outward-oriented faces of a unit tetrahedron.
const TET: ([[f64; 3]; 4], [[u32; 3]; 4]) = (
    [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, 0.0, 1.0],
    ],
    [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
);

/// Corners and outward-oriented faces of an octahedron of radius 1.
const OCT: ([[f64; 3]; 6], [[u32; 3]; 8]) = (
    [
        [1.0, 0.0, 0.0],
        [-1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, -1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.0, 0.0, -1.0],
    ],
    [
        [0, 2, 4],
        [2, 1, 4],
        [1, 3, 4],
        [3, 0, 4],
        [2, 0, 5],
        [1, 2, 5],
        [3, 1, 5],
        [0, 3, 5],
    ],
);

/// A small mesh from bytes (see the module doc). `None` when the arrays are not even a
/// mesh (`LabeledMesh::from_raw` refuses them), which cannot happen for the closed-cell
/// mode and is itself checked not to panic.
pub fn decode_mesh(b: &mut Bytes<'_>) -> Option<LabeledMesh> {
    let mut positions = Vec::new();
    let mut tris = Vec::new();
    let mut labels = Vec::new();
    if !b.byte().is_multiple_of(4) {
        // Closed cells: each a tetrahedron or an octahedron of one material in material 0
        // (or inside the previous cell's material), corners jittered (possibly inverted).
        let cells = b.range(1, 3);
        for _ in 0..cells {
            let base = positions.len() as u32;
            let centre = DVec3::new(b.coord(), b.coord(), b.coord()) * 2.0;
            let scale = 0.25 * b.range(1, 8) as f64;
            let jitter = b.byte();
            let (corners, faces): (&[[f64; 3]], &[[u32; 3]]) = if b.byte().is_multiple_of(2) {
                (&TET.0, &TET.1)
            } else {
                (&OCT.0, &OCT.1)
            };
            for c in corners {
                let mut p = centre + DVec3::from_array(*c) * scale;
                if jitter.is_multiple_of(3) {
                    p += DVec3::new(b.coord(), b.coord(), b.coord()) * 0.25;
                }
                positions.push(p);
            }
            let inside = b.range(1, 4) as u32;
            let outside = if b.byte().is_multiple_of(4) {
                b.range(0, 4) as u32
            } else {
                0
            };
            for f in faces {
                tris.push(f.map(|i| i + base));
                labels.push([outside, inside]);
            }
        }
    } else {
        let nv = b.range(3, 8);
        for _ in 0..nv {
            positions.push(DVec3::new(b.coord(), b.coord(), b.coord()));
        }
        let nt = b.range(1, 10);
        for _ in 0..nt {
            tris.push([0, 0, 0].map(|_| b.range(0, nv - 1) as u32));
            labels.push([b.range(0, 3) as u32, b.range(0, 3) as u32]);
        }
    }
    LabeledMesh::from_raw(positions, &tris, &labels).ok()
}

/// A proposal for `mesh`: each vertex displaced by up to ±0.5 in steps of 1/256; a zero
/// byte in the right place makes one coordinate NaN and a short input gives the identity,
/// so both rejection paths and ordinary steps are exercised.
pub fn decode_proposal(b: &mut Bytes<'_>, mesh: &LabeledMesh) -> Vec<DVec3> {
    let scale = 0.25 * b.range(0, 4) as f64;
    let poison = b.byte() == 0xff;
    let mut out = mesh.positions().to_vec();
    for p in &mut out {
        *p += DVec3::new(b.coord(), b.coord(), b.coord()) * scale;
    }
    if poison && let Some(p) = out.first_mut() {
        p.x = f64::NAN;
    }
    out
}

/// Asserts that an accepted mesh survives a binary PLY round trip bit for bit.
fn assert_round_trip(mesh: &LabeledMesh) {
    let mut buf = Vec::new();
    write_ply(mesh, &mut buf, PlyFormat::BinaryLittleEndian)
        .expect("a mesh the reader accepted can be written");
    let back = read_ply(&buf[..], &ReadOptions::default()).expect("what we write reads back");
    assert_same_mesh(mesh, &back, "PLY round trip");
}

/// Asserts two meshes have the same live arrays: positions bitwise, triangles and labels.
pub fn assert_same_mesh(a: &LabeledMesh, b: &LabeledMesh, what: &str) {
    let (pa, ta, la) = a.to_raw();
    let (pb, tb, lb) = b.to_raw();
    let bits = |p: &[DVec3]| -> Vec<[u64; 3]> {
        p.iter()
            .map(|v| [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()])
            .collect()
    };
    assert_eq!(bits(&pa), bits(&pb), "{what}: positions differ");
    assert_eq!(ta, tb, "{what}: triangles differ");
    assert_eq!(la, lb, "{what}: labels differ");
}

/// The PLY reader under every unlabelled-file policy, stitched or not: no panic, exact round trips.
pub fn check_ply(data: &[u8]) {
    for unlabeled in [Unlabeled::ClosedTwoMaterial, Unlabeled::AssumeOutward] {
        for stitch in [false, true] {
            if let Ok(mesh) = read_ply(data, &ReadOptions { unlabeled, stitch }) {
                assert_round_trip(&mesh);
            }
        }
    }
}

/// The OBJ reader under every unlabelled-file policy, stitched or not: no panic, exact round trips.
pub fn check_obj(data: &[u8]) {
    for unlabeled in [Unlabeled::ClosedTwoMaterial, Unlabeled::AssumeOutward] {
        for stitch in [false, true] {
            if let Ok(mesh) = read_obj(data, &ReadOptions { unlabeled, stitch }) {
                assert_round_trip(&mesh);
            }
        }
    }
}

/// `grid_tracker::fix` on a decoded mesh: no panic; `Ok` means a valid mesh (layers 1–3).
pub fn check_fix(data: &[u8]) {
    let mut b = Bytes::new(data);
    let Some(mesh) = decode_mesh(&mut b) else {
        return;
    };
    let cell = match b.range(0, 4) {
        0 => None,
        k => Some(0.125 * k as f64),
    };
    if let Ok(out) = surftrack::grid_tracker::fix(&mesh, cell) {
        let report = validate(&out, &ValidateOptions::default());
        assert!(report.is_valid(), "fix returned an invalid mesh: {report}");
    }
}

/// Two `advance` calls of the chosen backend on a decoded mesh: no panic; `Ok` leaves a
/// valid mesh, `Err` leaves the previous mesh bit-identical. The collision backend is
/// skipped when `SURFTRACK_FUZZ_GRID_ONLY` is set (its internals are fuzzed separately).
pub fn check_advance(data: &[u8]) {
    let mut b = Bytes::new(data);
    let backend = if b.byte().is_multiple_of(2) {
        Backend::Grid
    } else {
        Backend::Collision
    };
    if backend == Backend::Collision && std::env::var_os("SURFTRACK_FUZZ_GRID_ONLY").is_some() {
        return;
    }
    let Some(mesh) = decode_mesh(&mut b) else {
        return;
    };
    let options = TrackerOptions {
        length_scale: match b.range(0, 3) {
            0 => None,
            k => Some(0.25 * k as f64),
        },
        seed: b.byte() as u64,
        validate_each_step: Some(true),
    };
    let Ok(mut tracker) = make_tracker_with(backend, mesh, &options) else {
        return;
    };
    for _ in 0..2 {
        let proposed = decode_proposal(&mut b, tracker.mesh());
        let before = tracker.mesh().clone();
        match tracker.advance(&proposed) {
            Ok(_) => {
                let report = validate(tracker.mesh(), &ValidateOptions::default());
                assert!(
                    report.is_valid(),
                    "{backend}: advance returned Ok with an invalid mesh: {report}"
                );
            }
            Err(_) => assert_same_mesh(&before, tracker.mesh(), "mesh after a failed advance"),
        }
    }
}
