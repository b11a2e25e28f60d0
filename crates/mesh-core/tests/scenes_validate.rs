//! Issue 2 acceptance across modules: every generator's output passes the full validation
//! (exact self-intersection check included), `copies` of overlapping meshes is caught
//! intersecting, and PLY/OBJ round trips keep a mesh bit-identical.

use glam::DVec3;
use mesh_core::generators::{
    copies, double_bubble, icosphere, random_spheres, voronoi_foam, zalesak,
};
use mesh_core::geometry::label_volumes;
use mesh_core::io::{PlyFormat, ReadOptions, read_obj, read_ply, write_obj, write_ply};
use mesh_core::validate::{ValidateOptions, validate};
use mesh_core::{Label, LabeledMesh};

fn exact() -> ValidateOptions {
    ValidateOptions {
        intersections: true,
        ..ValidateOptions::default()
    }
}

fn assert_clean(name: &str, mesh: &LabeledMesh) {
    let report = validate(mesh, &exact());
    assert!(report.is_valid(), "{name}: {report}");
    assert_eq!(
        report.self_intersecting_pairs.as_ref().map(|l| l.count),
        Some(0),
        "{name}"
    );
}

#[test]
fn generated_scenes_are_valid_and_intersection_free() {
    let sphere = icosphere(3, DVec3::ZERO, 1.0, [Label::OUTSIDE, Label::new(1)]).unwrap();
    assert_clean("icosphere", &sphere);
    let spheres = random_spheres(12, DVec3::ZERO, DVec3::ONE, [0.05, 0.12], 2, 3).unwrap();
    assert_clean("spheres", &spheres);
    assert_eq!(spheres.label_set().len(), 13);
    let bubble = double_bubble(1.0, 24).unwrap();
    assert_clean("double bubble", &bubble);
    assert_eq!(
        bubble.label_set(),
        vec![Label::new(0), Label::new(1), Label::new(2)]
    );
    let foam = voronoi_foam(20, 5, DVec3::ZERO, DVec3::ONE).unwrap();
    assert_clean("foam", &foam);
    let notched = zalesak(24).unwrap();
    assert_clean("zalesak", &notched);
}

#[test]
fn foam_cells_fill_the_cube() {
    let foam = voronoi_foam(30, 11, DVec3::splat(-1.0), DVec3::splat(1.0)).unwrap();
    let volumes = label_volumes(&foam);
    let cells: f64 = volumes
        .iter()
        .filter(|(l, _)| **l != Label::OUTSIDE)
        .map(|(_, v)| v)
        .sum();
    assert!((cells - 8.0).abs() < 1e-9, "cells sum to {cells}");
    assert!(
        volumes
            .iter()
            .filter(|(l, _)| **l != Label::OUTSIDE)
            .all(|(_, v)| *v > 0.0)
    );
}

#[test]
fn overlapping_copies_are_reported_intersecting() {
    let base = zalesak(16).unwrap();
    let union = copies(&base, 3, 9).unwrap();
    let report = validate(&union, &exact());
    let pairs = report
        .self_intersecting_pairs
        .as_ref()
        .map_or(0, |l| l.count);
    assert!(pairs > 0, "copies must intersect: {report}");
    assert!(!report.is_valid());
    // Apart from the intersections, each copy is a valid closed surface.
    let topological = validate(&union, &ValidateOptions::default());
    assert!(topological.is_valid(), "{topological}");
}

#[test]
fn io_round_trips_are_bit_identical() {
    let bubble = double_bubble(0.7, 16).unwrap();
    let raw = bubble.to_raw();
    for format in [
        PlyFormat::Ascii,
        PlyFormat::BinaryLittleEndian,
        PlyFormat::BinaryBigEndian,
    ] {
        let mut bytes = Vec::new();
        write_ply(&bubble, &mut bytes, format).unwrap();
        let back = read_ply(bytes.as_slice(), &ReadOptions::default()).unwrap();
        assert_eq!(back.to_raw(), raw, "{format:?}");
        assert_clean("ply round trip", &back);
    }
    let mut bytes = Vec::new();
    write_obj(&bubble, &mut bytes).unwrap();
    let back = read_obj(bytes.as_slice(), &ReadOptions::default()).unwrap();
    assert_eq!(back.to_raw(), raw);
}
