//! Prints the quality of the wall between two labels in each given frame (issue 15), and
//! how much of their contact is not wall yet (`open_contact`):
//! `cargo run --release -p bench-harness --example wall -- [--labels 1,2] FRAME.ply…`
//! (e.g. the last frames of `surftrack run spheres --spheres 2` with both trackers).

use bench_harness::wall::{OPEN_CONTACT_REACH, open_contact, wall_quality};
use mesh_core::Label;
use mesh_core::io::read_mesh;

fn main() {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let mut labels = [Label::new(1), Label::new(2)];
    if let Some(i) = args.iter().position(|a| a == "--labels") {
        let value = args.get(i + 1).cloned().unwrap_or_default();
        let parsed: Vec<u32> = value.split(',').filter_map(|s| s.parse().ok()).collect();
        if parsed.len() != 2 {
            eprintln!("--labels takes two labels, e.g. --labels 1,2");
            std::process::exit(2);
        }
        labels = [Label::new(parsed[0]), Label::new(parsed[1])];
        args.drain(i..i + 2);
    }
    if args.is_empty() {
        eprintln!("usage: wall [--labels A,B] FRAME.ply…");
        std::process::exit(2);
    }
    println!(
        "| frame | wall triangles | area | radius | RMS to plane / radius | area tilted > 30° \
         | open contact (vertices < {OPEN_CONTACT_REACH} ℓ) |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|");
    for path in &args {
        let mesh = match read_mesh(std::path::Path::new(path)) {
            Ok(m) => m,
            Err(e) => {
                eprintln!("{path}: {e}");
                std::process::exit(2);
            }
        };
        let open = open_contact(&mesh, labels[0], labels[1]);
        match wall_quality(&mesh, labels[0], labels[1]) {
            Some(q) => println!(
                "| {path} | {} | {:.5} | {:.4} | {:.4} | {:.1} % | {open} |",
                q.triangles,
                q.area,
                q.radius,
                q.rms_over_radius,
                100.0 * q.tilted_fraction
            ),
            None => println!("| {path} | 0 | – | – | – | – | {open} |"),
        }
    }
}
