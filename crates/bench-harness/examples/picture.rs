//! Draws one frame large, to look at walls and triple curves closely:
//! `cargo run --release -p bench-harness --example picture -- FRAME.ply OUT.png
//! [--size PIXELS] [--cut] [--box x0,y0,z0,x1,y1,z1] [--dir x,y,z] [--only A,B]`.
//! `--box` frames that box instead of the whole mesh (a zoom); `--cut` drops the half
//! nearer the camera, as the reports' cut-away pictures do; `--dir` is the direction from
//! the scene towards the camera (default the reports' view); `--only` draws only the
//! interface between labels A and B (a wall seen face on).

use bench_harness::report::picture::{Camera, VIEW_DIRECTION, bounds_of, render_png};
use glam::DVec3;
use mesh_core::broadphase::Aabb;
use mesh_core::io::read_mesh;
use mesh_core::{Label, LabeledMesh};

fn usage() -> ! {
    eprintln!(
        "usage: picture FRAME.ply OUT.png [--size PIXELS] [--cut] [--box x0,y0,z0,x1,y1,z1] [--dir x,y,z]"
    );
    std::process::exit(2);
}

fn main() {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let mut take = |flag: &str, has_value: bool| -> Option<String> {
        let i = args.iter().position(|a| a == flag)?;
        let value = if has_value {
            args.get(i + 1).cloned().unwrap_or_else(|| usage())
        } else {
            String::new()
        };
        args.drain(i..i + 1 + usize::from(has_value));
        Some(value)
    };
    let size: u32 = take("--size", true).map_or(1024, |s| s.parse().unwrap_or_else(|_| usage()));
    let cut = take("--cut", false).is_some();
    let frame_box = take("--box", true).map(|s| {
        let v: Vec<f64> = s.split(',').filter_map(|x| x.parse().ok()).collect();
        if v.len() != 6 {
            usage();
        }
        Aabb {
            min: DVec3::new(v[0], v[1], v[2]),
            max: DVec3::new(v[3], v[4], v[5]),
        }
    });
    let direction = take("--dir", true).map_or(VIEW_DIRECTION, |s| {
        let v: Vec<f64> = s.split(',').filter_map(|x| x.parse().ok()).collect();
        if v.len() != 3 {
            usage();
        }
        DVec3::new(v[0], v[1], v[2])
    });
    let only = take("--only", true).map(|s| {
        let v: Vec<u32> = s.split(',').filter_map(|x| x.parse().ok()).collect();
        if v.len() != 2 {
            usage();
        }
        let mut pair = [Label::new(v[0]), Label::new(v[1])];
        pair.sort();
        pair
    });
    let [frame, out] = args.as_slice() else {
        usage()
    };
    let mesh = read_mesh(std::path::Path::new(frame)).unwrap_or_else(|e| {
        eprintln!("{frame}: {e}");
        std::process::exit(2);
    });
    let mesh = match only {
        None => mesh,
        Some(pair) => {
            let (positions, tris, labels) = mesh.to_raw();
            let kept: Vec<usize> = (0..tris.len())
                .filter(|&i| {
                    let mut l = labels[i].map(Label::new);
                    l.sort();
                    l == pair
                })
                .collect();
            let tris: Vec<[u32; 3]> = kept.iter().map(|&i| tris[i]).collect();
            let labels: Vec<[u32; 2]> = kept.iter().map(|&i| labels[i]).collect();
            LabeledMesh::from_raw(positions, &tris, &labels).unwrap_or_else(|e| {
                eprintln!("the {pair:?} interface alone: {e}");
                std::process::exit(1);
            })
        }
    };
    let camera = Camera::fit_looking(frame_box.unwrap_or_else(|| bounds_of([&mesh])), direction);
    let png = render_png(&mesh, &camera, size, size * 3 / 4, cut).unwrap_or_else(|e| {
        eprintln!("{e}");
        std::process::exit(1);
    });
    std::fs::write(out, png).unwrap_or_else(|e| {
        eprintln!("{out}: {e}");
        std::process::exit(2);
    });
}
