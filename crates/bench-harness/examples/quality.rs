//! Prints the triangle-quality figures of issue 14's bars for each given frame: the
//! fraction of triangles with a minimum angle under 10° and the ratio of the 99th to the
//! 1st percentile of edge length.
//! `cargo run --release -p bench-harness --example quality -- FRAME.ply…`

use mesh_core::io::read_mesh;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.is_empty() {
        eprintln!("usage: quality FRAME.ply…");
        std::process::exit(2);
    }
    println!("| frame | triangles | min angle < 10° | edge p1 | edge p99 | p99/p1 |");
    println!("|---|---:|---:|---:|---:|---:|");
    for path in &args {
        let mesh = match read_mesh(std::path::Path::new(path)) {
            Ok(m) => m,
            Err(e) => {
                eprintln!("{path}: {e}");
                std::process::exit(2);
            }
        };
        let q = bench_harness::quality::triangle_quality(&mesh);
        println!(
            "| {path} | {} | {:.2} % | {:.4} | {:.4} | {:.2} |",
            q.triangles,
            100.0 * q.below_10_deg,
            q.edge_p1,
            q.edge_p99,
            q.edge_p99 / q.edge_p1
        );
    }
}
