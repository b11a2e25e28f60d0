//! Follows one of the built-in animations and prints, per frame, the component count,
//! triangles, quasi-critical points and time — the quickest way to see blending and
//! splitting happen.
//!
//! ```text
//! EDGE=0.12 FRAMES=40 cargo run --release -p implicit-surface --example metaballs -- [crossing|triple|swarm] [hint_push] [deep_radius]
//! ```

use implicit_surface::{FollowParams, Follower, ImplicitError, ImplicitField, polygonize, scenes};

fn main() -> Result<(), ImplicitError> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let scene = args.first().map_or("crossing", String::as_str);
    let h: f64 = std::env::var("EDGE")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(0.12);
    let frames: usize = std::env::var("FRAMES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(40);
    let anim = match scene {
        "triple" => scenes::triple(1.3, h, frames)?,
        "swarm" => scenes::swarm(12, 1, h, frames)?,
        _ => scenes::crossing(1.1, h, frames)?,
    };
    let mut params = FollowParams::new(anim.edge_length);
    if let Some(push) = args.get(1).and_then(|s| s.parse().ok()) {
        params.hint_push = push;
    }
    if let Some(r) = args.get(2).and_then(|s| s.parse().ok()) {
        params.deep_radius = r;
    }
    let mut follower = Follower::new(anim.field.clone(), anim.t0, None, params)?;
    for k in 1..=anim.frames {
        let r = follower.advance_to(anim.time(k, anim.frames))?;
        let t = r.t;
        if std::env::var_os("SHELLS").is_some() {
            let regions = follower.mesh().regions();
            let shells: Vec<String> = regions
                .bounded()
                .map(|s| format!("{}:{:.4}", s.sides, s.volume))
                .collect();
            println!("  shells {}", shells.join(" "));
            let mut kinds = std::collections::BTreeMap::new();
            for q in &r.quasi_critical {
                *kinds
                    .entry(format!("{:?}/{:?}", q.kind, q.outcome))
                    .or_insert(0) += 1;
            }
            println!("  quasi-critical {kinds:?} debris {}", r.debris_removed);
        }
        let bounds = anim.field.bounds(t).unwrap_or_default();
        let reference = polygonize(&anim.field, t, bounds, 0.25 * anim.edge_length)?.components();
        println!(
            "frame {k:3}  t = {:.3}  components {} (field: {reference})  triangles {:5}  quasi-critical {:3}  persisted {:.3}  {:.1} ms",
            r.t,
            r.components,
            r.triangles,
            r.quasi_critical.len(),
            r.persisted as f64 / r.vertices.max(1) as f64,
            r.seconds * 1e3
        );
    }
    Ok(())
}
