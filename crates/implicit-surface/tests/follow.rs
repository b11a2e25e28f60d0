//! Behaviour of the follower on the scenes the issue names: two crossing skeleton
//! elements blend into one component and split into two again, three blobs meet in one
//! place, every frame valid and on the surface.

use implicit_surface::{FollowParams, Follower, ImplicitField, scenes};
use mesh_core::validate::{ValidateOptions, validate};

/// Runs an animation, checking every frame; returns the component count per frame.
/// A follower of `anim` from its start, at the animation's edge length.
fn follower(anim: &scenes::Animation) -> Follower<implicit_surface::SkeletonField> {
    Follower::new(
        anim.field.clone(),
        anim.t0,
        None,
        FollowParams::new(anim.edge_length),
    )
    .unwrap()
}

fn run(anim: &scenes::Animation, tol: f64) -> Vec<usize> {
    let params = FollowParams::new(anim.edge_length);
    let mut f = Follower::new(anim.field.clone(), anim.t0, None, params).unwrap();
    let mut comps = Vec::new();
    let mut frames_off = 0;
    for k in 1..=anim.frames {
        let t = anim.time(k, anim.frames);
        let r = f.advance_to(t).unwrap_or_else(|e| panic!("frame {k}: {e}"));
        // Valid with the exact intersection check: the re-projection holds back a vertex
        // whose move would fold the mesh (before, the frames where the blobs merge and
        // separate intersected themselves, and one left an inside-out piece).
        let report = validate(f.mesh(), &ValidateOptions::with_intersections());
        assert!(report.is_valid(), "frame {k} (t = {t}): {report}");
        // Within tolerance of F = 0: first-order distance |F|/|∇F| at every vertex.
        let mut worst: f64 = 0.0;
        for v in f.mesh().vertices() {
            let p = f.mesh().position(v);
            let (val, g) = anim.field.value_and_gradient(p, t);
            worst = worst.max(val.abs() / g.length().max(1e-12));
        }
        eprintln!(
            "frame {k:3} t={t:.3} comps={} tris={} qc={} unproj={} worst={worst:.2e} persisted={}/{} ms={:.1}",
            r.components,
            r.triangles,
            r.quasi_critical.len(),
            r.unprojected,
            r.persisted,
            r.vertices,
            r.seconds * 1e3
        );
        // A vertex the re-projection could not place is one still in flight across a gap
        // closing under it (its own sheet's ray meets no surface within reach, e.g. the
        // wall of the channel the three blobs close at the centre), or one whose move
        // would turn a triangle over where the tracker's mesh has not caught up with a
        // merge or a cut yet: the tracker resolves it within a few frames. Those are
        // reported, around the topology changes only, and gone by the end; every other
        // vertex is on the surface.
        if r.unprojected == 0 {
            assert!(
                worst < tol * anim.edge_length,
                "frame {k}: |F|/|∇F| = {worst}"
            );
        } else {
            frames_off += 1;
            assert!(r.unprojected * 100 <= 10 * r.vertices, "frame {k}: {r:?}");
            assert!(
                r.max_residual < tol * anim.edge_length,
                "frame {k}: |F|/|∇F| = {}",
                r.max_residual
            );
        }
        if k == anim.frames {
            assert_eq!(r.unprojected, 0, "frame {k}");
        }
        comps.push(r.components);
    }
    assert!(
        frames_off * 3 <= anim.frames,
        "{frames_off} frames off the surface"
    );
    comps
}

#[test]
fn crossing_elements_blend_into_one_component_then_split_into_two() {
    let anim = scenes::crossing(1.1, 0.12, 40).unwrap();
    let comps = run(&anim, 0.05);
    // Apart at the start, one while they overlap (around t = ½), two at the end.
    assert_eq!(comps[0], 2);
    let mid = anim.frames / 2;
    assert_eq!(comps[mid - 1], 1, "{comps:?}");
    assert_eq!(*comps.last().unwrap(), 2, "{comps:?}");
}

#[test]
fn three_blobs_meeting_in_one_place_merge_into_one_and_separate_into_three() {
    let anim = scenes::triple(1.3, 0.12, 30).unwrap();
    let comps = run(&anim, 0.05);
    assert_eq!(comps[0], 3, "{comps:?}");
    assert_eq!(comps[anim.frames / 2 - 1], 1, "{comps:?}");
    assert_eq!(*comps.last().unwrap(), 3, "{comps:?}");
}

#[test]
fn the_geometric_mesh_of_a_followed_frame_is_crack_free() {
    use implicit_surface::{RefineParams, refine};
    let anim = scenes::crossing(1.1, 0.15, 20).unwrap();
    let mut f = follower(&anim);
    // Into the blended state, where the neck has the most curvature.
    for k in 1..=8 {
        f.advance_to(anim.time(k, 20)).unwrap();
    }
    let t = f.time();
    let r = refine(f.mesh(), &anim.field, t, &RefineParams::default()).unwrap();
    assert!(r.split_edges > 0);
    let report = validate(&r.mesh, &ValidateOptions::default());
    assert!(report.is_valid(), "{report}");
    // Watertight: every edge has exactly two triangles.
    let mut edges = std::collections::HashMap::<(u32, u32), u32>::new();
    for tri in r.mesh.triangles() {
        let [a, b, c] = r.mesh.tri(tri).map(|v| v.raw());
        for (x, y) in [(a, b), (b, c), (c, a)] {
            *edges.entry((x.min(y), x.max(y))).or_default() += 1;
        }
    }
    assert!(edges.values().all(|&n| n == 2));
}

#[test]
fn a_sampled_grid_field_is_followed_too() {
    use glam::DVec3;
    use implicit_surface::{GridField, SphereField};
    // A sphere moving along x, sampled at two time frames: the follower sees a
    // trilinear, piecewise-linear-in-time field.
    let s = SphereField {
        centre: DVec3::ZERO,
        velocity: DVec3::new(0.5, 0.0, 0.0),
        radius: 0.5,
    };
    let bounds = [DVec3::splat(-0.7), DVec3::new(1.2, 0.7, 0.7)];
    let g = GridField::sample(&s, bounds, 0.05, &[0.0, 1.0], -1.0).unwrap();
    let mut f = Follower::new(g.clone(), 0.0, Some(bounds), FollowParams::new(0.1)).unwrap();
    for k in 1..=10 {
        let t = k as f64 * 0.1;
        let r = f.advance_to(t).unwrap();
        assert_eq!(r.components, 1);
        assert!(validate(f.mesh(), &ValidateOptions::default()).is_valid());
        for v in f.mesh().vertices() {
            let p = f.mesh().position(v);
            assert!(
                g.value(p, t).abs() < 1e-6,
                "frame {k}: F = {}",
                g.value(p, t)
            );
        }
    }
    // The mesh moved with the sphere: its bounding box is centred near x = 0.5.
    let (lo, hi) = f
        .mesh()
        .vertices()
        .map(|v| f.mesh().position(v))
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p), hi.max(p))
        });
    let c = (lo + hi) * 0.5;
    assert!((c.x - 0.5).abs() < 0.02, "{c}");
    assert!((hi.x - lo.x - 1.0).abs() < 0.02, "{lo} {hi}");
}

#[test]
fn bad_parameters_are_typed_errors_not_panics() {
    let anim = scenes::crossing(1.1, 0.12, 4).unwrap();
    let mut p = FollowParams::new(0.0);
    assert!(Follower::new(anim.field.clone(), 0.0, None, p.clone()).is_err());
    p.edge_length = 0.12;
    p.hint_push = f64::NAN;
    assert!(Follower::new(anim.field.clone(), 0.0, None, p).is_err());
    let mut f = Follower::new(anim.field.clone(), 0.0, None, FollowParams::new(0.12)).unwrap();
    assert!(f.advance_to(f64::NAN).is_err());
    // A failed frame leaves the mesh as it was.
    assert_eq!(f.time(), 0.0);
}

/// Regression (issue 16, item 5): the crossing at ℓ = 0.15 in 10 frames moves each
/// surface about 1.5 ℓ per frame (3 ℓ relative), so at frame 4 the elements overlap
/// deeply. Newton projection used to take the vertices of one element that had entered
/// the other to the other's surface, moving them *inward*: the sheet folded onto the
/// union's surface with its orientation reversed, the windings cancelled, the tracker's
/// exact ray casting saw outside in the overlap and the material vanished (volume 1.81
/// → 0.11 at frame 4, no surface left by frame 6). Every frame must now enclose about the
/// field's volume, measured independently by polygonizing `F`.
#[test]
fn a_fast_deep_crossing_keeps_its_volume_in_every_frame() {
    use implicit_surface::polygonize_mesh;
    use mesh_core::Label;
    use mesh_core::geometry::label_volumes;
    let anim = scenes::crossing(1.1, 0.15, 10).unwrap();
    let mut f = follower(&anim);
    let mut merged = false;
    for k in 1..=anim.frames {
        let t = anim.time(k, anim.frames);
        let r = f.advance_to(t).unwrap_or_else(|e| panic!("frame {k}: {e}"));
        assert!(r.tracker.events.vanished.is_empty(), "frame {k}: {r:?}");
        merged |= r.components == 1;
        let bounds = anim.field.bounds(t).unwrap();
        let reference = polygonize_mesh(&anim.field, t, bounds, 0.05).unwrap();
        let want = label_volumes(&reference)[&Label::new(1)];
        let got = label_volumes(f.mesh())
            .get(&Label::new(1))
            .copied()
            .unwrap_or(0.0);
        assert!(
            (got - want).abs() < 0.15 * want,
            "frame {k} (t = {t}): volume {got}, field {want}"
        );
    }
    assert!(merged, "the elements never merged");
}
