use std::collections::{BTreeMap, HashMap};

use glam::{DVec3, IVec3};
use mesh_core::validate::{ValidateOptions, validate};
use mesh_core::{Label, LabeledMesh, TriId, VertexId};

use super::*;
use crate::stages::flaws::{FlawOptions, detect_flaws};
use crate::stages::grid::{GridOptions, Lattice, build_grid};
use crate::stages::materials::{MaterialOptions, assign_materials};
use crate::test_util::{cube, sphere, union};

struct Run {
    grid: Grid,
    mats: Materials,
    region: FlawedRegion,
}

/// Grid, materials and detected flaws; then the allocated cells `pick` selects (by centre)
/// are added to the region.
fn run(mesh: &LabeledMesh, ell: f64, opts: &GridOptions, pick: impl Fn(DVec3) -> bool) -> Run {
    let grid = build_grid(mesh, ell, opts).unwrap();
    let mats = assign_materials(mesh, &grid, &MaterialOptions::default()).unwrap();
    let mut region = detect_flaws(mesh, &grid, &mats, &FlawOptions::default()).unwrap();
    let extra: Vec<IVec3> = grid
        .cells()
        .map(|c| grid.cell_coord(c))
        .filter(|&c| pick(grid.lattice().cell_centre(c)))
        .collect();
    if !extra.is_empty() {
        region.grow(mesh, &grid, &mats, &extra);
    }
    Run { grid, mats, region }
}

fn seeded(seed: u64) -> GridOptions {
    GridOptions {
        seed,
        ..GridOptions::default()
    }
}

fn cut(mesh: &LabeledMesh, r: &Run) -> Result<Cut, CutError> {
    cut_mesh(mesh, &r.grid, &r.mats, &r.region, &CutOptions::default())
}

// ----- an independent reference: clip every triangle against every cell box -----------

fn polygon_area(p: &[DVec3]) -> f64 {
    let mut n = DVec3::ZERO;
    for i in 1..p.len().saturating_sub(1) {
        n += (p[i] - p[0]).cross(p[i + 1] - p[0]);
    }
    0.5 * n.length()
}

/// Sutherland–Hodgman: the part of polygon `p` with `sign·(x_axis − bound) ≤ 0`.
fn clip(p: &[DVec3], axis: usize, bound: f64, sign: f64) -> Vec<DVec3> {
    let mut out = Vec::new();
    for i in 0..p.len() {
        let (a, b) = (p[i], p[(i + 1) % p.len()]);
        let (da, db) = (sign * (a[axis] - bound), sign * (b[axis] - bound));
        if da <= 0.0 {
            out.push(a);
        }
        if (da < 0.0 && db > 0.0) || (da > 0.0 && db < 0.0) {
            out.push(a + (b - a) * (da / (da - db)));
        }
    }
    out
}

/// Area per label pair of the input inside intact cells and inside flawed cells.
fn reference_areas(
    mesh: &LabeledMesh,
    lattice: &Lattice,
    region: &FlawedRegion,
) -> (BTreeMap<[Label; 2], f64>, BTreeMap<[Label; 2], f64>) {
    let (mut intact, mut flawed) = (BTreeMap::new(), BTreeMap::new());
    for t in mesh.triangles() {
        let p = mesh.tri_positions(t);
        let [lo, hi] = lattice.cell_range(p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]));
        for x in lo.x..=hi.x {
            for y in lo.y..=hi.y {
                for z in lo.z..=hi.z {
                    let c = IVec3::new(x, y, z);
                    let mut poly = p.to_vec();
                    for a in 0..3 {
                        poly = clip(&poly, a, lattice.plane(a, c[a]), -1.0);
                        poly = clip(&poly, a, lattice.plane(a, c[a] + 1), 1.0);
                    }
                    // Under the perturbation, geometry lying exactly on a cell's lower
                    // plane belongs to the cell below.
                    if (0..3).any(|a| poly.iter().all(|q| q[a] == lattice.plane(a, c[a]))) {
                        continue;
                    }
                    let map = if region.is_flawed(c) {
                        &mut flawed
                    } else {
                        &mut intact
                    };
                    *map.entry(mesh.labels(t)).or_insert(0.0) += polygon_area(&poly);
                }
            }
        }
    }
    (intact, flawed)
}

fn areas(mesh: &LabeledMesh) -> BTreeMap<[Label; 2], f64> {
    let mut m = BTreeMap::new();
    for t in mesh.triangles() {
        *m.entry(mesh.labels(t)).or_insert(0.0) += polygon_area(&mesh.tri_positions(t));
    }
    m
}

// ----- the properties every cut must have -------------------------------------------

/// Checks (1)–(4) of the brief on one cut; returns the number of boundary segments.
fn check_cut(mesh: &LabeledMesh, r: &Run, cut: &Cut) -> usize {
    let lattice = r.grid.lattice();
    let out = &cut.mesh;

    // (1) Areas per label: intact part = input ∩ intact cells, and with the flawed part
    // the input area (the reference is self-consistent).
    let total: f64 = areas(mesh).values().sum();
    let (ref_intact, ref_flawed) = reference_areas(mesh, lattice, &r.region);
    let got = areas(out);
    for (labels, whole) in areas(mesh) {
        let i = ref_intact.get(&labels).copied().unwrap_or(0.0);
        let f = ref_flawed.get(&labels).copied().unwrap_or(0.0);
        assert!(
            (i + f - whole).abs() <= 1e-9 * total,
            "reference {labels:?}"
        );
        let g = got.get(&labels).copied().unwrap_or(0.0);
        assert!(
            (g - i).abs() <= 1e-9 * total,
            "labels {labels:?}: intact area {g} vs reference {i} (flawed {f})"
        );
    }

    // (2) Cut vertices lie on the grid; boundary segments lie in their faces.
    let on_plane = |a: usize, x: f64| lattice.plane(a, lattice.locate(a, x)) == x;
    for &v in &cut.new_vertices {
        let p = out.position(v);
        assert!((0..3).any(|a| on_plane(a, p[a])), "cut vertex {v} at {p}");
    }
    for &(e, v) in &cut.edge_points {
        let p = out.position(v);
        let node = lattice.node_position(e.node);
        let m = e.axis.index();
        for a in 0..3 {
            if a == m {
                assert!(p[a] >= node[a] && p[a] <= lattice.plane(a, e.node[a] + 1));
            } else {
                assert_eq!(p[a], node[a], "edge point {v} off its grid line");
            }
        }
    }
    let mut segments = Vec::new();
    for (face, flawed, segs) in cut.boundary() {
        assert!(r.region.is_flawed(flawed));
        assert!(face.cells().contains(&flawed));
        let a = face.normal.index();
        let (b, c) = face.normal.others();
        for s in segs {
            for key in [s.from, s.to] {
                let RebuildVertexKey::Cut(i) = key else {
                    panic!("segment end {key:?} is not a cut vertex");
                };
                let p = out.position(VertexId::new(i));
                assert_eq!(
                    p[a],
                    lattice.plane(a, face.node[a]),
                    "segment off its plane"
                );
                for m in [b, c] {
                    assert!(
                        p[m] >= lattice.plane(m, face.node[m])
                            && p[m] <= lattice.plane(m, face.node[m] + 1),
                        "segment end outside its face"
                    );
                }
            }
            segments.push(*s);
        }
    }

    // (3) The segments are exactly the boundary edges of the clipped mesh, oriented as
    // their triangle runs them, with its labels (the fans.rs contract).
    let mut edge_tris: HashMap<(VertexId, VertexId), Vec<TriId>> = HashMap::new();
    for t in out.triangles() {
        let v = out.tri(t);
        for k in 0..3 {
            let (a, b) = (v[k], v[(k + 1) % 3]);
            edge_tris.entry((a.min(b), a.max(b))).or_default().push(t);
        }
    }
    let mut boundary: Vec<(u32, u32, [Label; 2])> = Vec::new();
    for (&(a, b), tris) in &edge_tris {
        if tris.len() == 1 {
            let t = tris[0];
            let v = out.tri(t);
            let k = (0..3).find(|&k| v[k] == a || v[k] == b).unwrap();
            let (from, to) = if v[k] == a && v[(k + 1) % 3] == b || v[k] == b && v[(k + 1) % 3] == a
            {
                (v[k], v[(k + 1) % 3])
            } else {
                (v[(k + 2) % 3], v[k])
            };
            boundary.push((from.raw(), to.raw(), out.labels(t)));
        }
    }
    let mut seg_keys: Vec<(u32, u32, [Label; 2])> = segments
        .iter()
        .map(|s| match (s.from, s.to) {
            (RebuildVertexKey::Cut(f), RebuildVertexKey::Cut(t)) => (f, t, s.labels),
            _ => unreachable!(),
        })
        .collect();
    // Within a face the segments form polylines from face edge to face edge: a grid-edge
    // point ends one segment, a mesh-edge point (on a two-triangle edge) joins two.
    let on_edges: std::collections::HashSet<u32> =
        cut.edge_points.iter().map(|e| e.1.raw()).collect();
    for (_, _, segs) in cut.boundary() {
        let mut ends: HashMap<u32, (u32, u32)> = HashMap::new();
        for s in segs {
            if let (RebuildVertexKey::Cut(f), RebuildVertexKey::Cut(t)) = (s.from, s.to) {
                ends.entry(f).or_default().0 += 1;
                ends.entry(t).or_default().1 += 1;
            }
        }
        for (v, (from, to)) in ends {
            if on_edges.contains(&v) {
                assert_eq!(from + to, 1, "grid-edge point {v}");
            } else {
                assert_eq!((from, to), (1, 1), "mesh-edge point {v}");
            }
        }
    }
    boundary.sort_unstable();
    seg_keys.sort_unstable();
    assert_eq!(boundary, seg_keys, "boundary edges vs segments");
    assert_eq!(cut.num_boundary_segments(), seg_keys.len());

    // The clipped mesh is a valid open mesh: linked, labelled, only the hole's edges open.
    let rep = validate(out, &ValidateOptions::default());
    assert_eq!(rep.dangling_references.count, 0);
    assert_eq!(rep.degenerate.count, 0);
    assert_eq!(rep.duplicates.count, 0);
    assert_eq!(rep.corner_table.count, 0, "{:?}", rep.corner_table.items);
    assert_eq!(rep.same_label_triangles.count, 0);
    // Sub-triangles keep their parent's winding: labels agree across every inner edge.
    assert_eq!(
        rep.inconsistent_edges.count, 0,
        "{:?}",
        rep.inconsistent_edges.items
    );
    assert_eq!(rep.non_finite.count, 0);
    assert_eq!(rep.boundary_edges.count, seg_keys.len());

    // (4) Untouched triangles keep ids, vertices and labels.
    let new: std::collections::HashSet<TriId> = cut.new_triangles.iter().copied().collect();
    let mut kept = 0;
    for t in out.triangles().filter(|t| !new.contains(t)) {
        assert!(mesh.is_triangle_alive(t));
        assert_eq!(out.tri(t), mesh.tri(t));
        assert_eq!(out.labels(t), mesh.labels(t));
        for v in out.tri(t) {
            assert_eq!(out.position(v), mesh.position(v));
        }
        kept += 1;
    }
    let s = cut.stats;
    assert_eq!(kept, s.untouched);
    assert_eq!(s.untouched + s.clipped + s.removed, s.triangles_in);
    assert_eq!(out.num_triangles(), s.untouched + s.sub_triangles);
    assert_eq!(
        out.num_vertices(),
        mesh.num_vertices() + s.cut_vertices - s.removed_vertices
    );
    seg_keys.len()
}

// ----- scenes -----------------------------------------------------------------------

#[test]
fn hand_picked_cap_of_a_sphere() {
    let s = sphere(3, DVec3::new(0.013, -0.021, 0.007), 1.0, 0, 1);
    for seed in 0..3 {
        let r = run(&s, 0.15, &seeded(seed), |c| {
            c.distance(DVec3::new(0.9, 0.3, 0.2)) < 0.4
        });
        assert!(!r.region.is_empty());
        let c = cut(&s, &r).unwrap();
        let n = check_cut(&s, &r, &c);
        assert!(
            n > 0 && c.stats.clipped > 0 && c.stats.removed > 0,
            "{:?}",
            c.stats
        );
        assert!(!c.edge_points.is_empty());
    }
}

#[test]
fn overlapping_spheres_with_detected_region() {
    let a = sphere(3, DVec3::new(-0.45, 0.01, 0.0), 1.0, 0, 1);
    let b = sphere(3, DVec3::new(0.45, -0.02, 0.03), 1.0, 0, 2);
    let m = union(&[a, b]);
    for seed in 0..2 {
        let r = run(&m, 0.2, &seeded(seed), |_| false);
        assert!(!r.region.is_empty());
        let c = cut(&m, &r).unwrap();
        let n = check_cut(&m, &r, &c);
        assert!(n > 0, "{:?}", c.stats);
        // Both spheres lose their overlapping part.
        let labels: std::collections::BTreeSet<[Label; 2]> =
            c.mesh.triangles().map(|t| c.mesh.labels(t)).collect();
        assert_eq!(labels.len(), 2);
    }
}

#[test]
fn corner_of_a_box() {
    let m = cube(DVec3::splat(-0.53), DVec3::splat(0.61), 0, 3);
    let r = run(&m, 0.1, &seeded(7), |c| {
        c.distance(DVec3::splat(0.61)) < 0.35
    });
    let c = cut(&m, &r).unwrap();
    let n = check_cut(&m, &r, &c);
    assert!(n > 0);
    // The box has 12 big triangles: they are all clipped or removed near the corner.
    assert!(c.stats.clipped >= 3, "{:?}", c.stats);
}

#[test]
fn empty_region_returns_the_mesh_unchanged() {
    let s = sphere(2, DVec3::new(0.01, 0.02, 0.03), 1.0, 0, 1);
    let r = run(&s, 0.2, &seeded(1), |_| false);
    assert!(r.region.is_empty());
    let c = cut(&s, &r).unwrap();
    assert_eq!(c.mesh.to_raw(), s.to_raw());
    assert!(c.new_vertices.is_empty() && c.new_triangles.is_empty());
    assert_eq!(c.boundary().count(), 0);
    assert_eq!(c.stats.untouched, s.num_triangles());
}

#[test]
fn box_on_grid_planes_cuts_consistently_or_reports_cells() {
    // Unperturbed grid with ℓ = 0.25: every box face and edge lies on grid planes and
    // lines, every vertex on a node.
    let m = cube(DVec3::splat(-0.5), DVec3::splat(0.5), 0, 1);
    let opts = GridOptions {
        perturbation: 0.0,
        ..GridOptions::default()
    };
    let mut cut_ok = 0;
    for centre in [
        DVec3::splat(0.5),
        DVec3::new(0.5, 0.0, 0.0),
        DVec3::new(0.5, 0.5, 0.1),
        DVec3::new(-0.4, 0.3, 0.5),
    ] {
        let r = run(&m, 0.25, &opts, |c| c.distance(centre) < 0.3);
        match cut(&m, &r) {
            Ok(c) => {
                assert!(!r.region.is_empty());
                check_cut(&m, &r, &c);
                cut_ok += 1;
            }
            Err(e) => assert!(!e.cells().is_empty(), "{e}"),
        }
    }
    // Today every one of these cuts consistently (vertices on planes are nudged).
    assert_eq!(cut_ok, 4);
}

#[test]
fn bad_options_are_rejected() {
    let s = sphere(1, DVec3::ZERO, 1.0, 0, 1);
    let r = run(&s, 0.3, &seeded(0), |_| false);
    let bad = CutOptions {
        quantum_bits: 60,
        ..CutOptions::default()
    };
    let e = cut_mesh(&s, &r.grid, &r.mats, &r.region, &bad).unwrap_err();
    assert!(matches!(e, CutError::BadOption { .. }) && e.cells().is_empty());
    let other = sphere(2, DVec3::ZERO, 1.0, 0, 1);
    assert!(matches!(
        cut_mesh(&other, &r.grid, &r.mats, &r.region, &CutOptions::default()),
        Err(CutError::Mismatch(_))
    ));
}

/// Release-mode measurement: `cargo test -p grid-tracker --release --lib cut::tests::timing
/// -- --ignored --nocapture`.
#[test]
#[ignore]
fn timing_large_icosphere() {
    let s = sphere(8, DVec3::new(0.0013, -0.0021, 0.0007), 1.0, 0, 1);
    let t0 = std::time::Instant::now();
    let r = run(&s, 0.01, &seeded(3), |c| {
        c.distance(DVec3::new(0.6, 0.64, 0.48)) < 0.28
    });
    let setup = t0.elapsed();
    let allocated = r.grid.num_cells();
    let t1 = std::time::Instant::now();
    let c = cut(&s, &r).unwrap();
    let elapsed = t1.elapsed();
    println!(
        "{} triangles, {} of {} allocated cells flawed ({:.1}%), setup {:?}, cut_mesh {:?}: {:?}",
        s.num_triangles(),
        r.region.len(),
        allocated,
        100.0 * r.region.len() as f64 / allocated as f64,
        setup,
        elapsed,
        c.stats
    );
}
