//! `surftrack generate SCENE --out FILE`: built-in scenes written to a mesh file.

use std::process::ExitCode;

use anyhow::{Context, bail};

use crate::scenes::{SceneOptions, build_scene};

use super::GenerateArgs;

pub(super) fn run(args: &GenerateArgs) -> anyhow::Result<ExitCode> {
    let copies_input = match &args.mesh {
        Some(path) => Some(
            super::read_work_mesh(path)
                .with_context(|| format!("reading --mesh {}", path.display()))?,
        ),
        None => None,
    };
    let options = SceneOptions {
        seed: args.seed,
        count: args.count,
        resolution: args.resolution,
        radius: args.radius,
        mesh: copies_input,
    };
    let mesh = build_scene(&args.scene, &options)?;
    // Refuse before writing, so a failed generate leaves no empty file behind.
    if mesh.num_triangles() == 0 {
        bail!("scene `{}` produced an empty mesh", args.scene);
    }
    super::write_mesh_file(&mesh, &args.out, args.binary)?;
    println!(
        "wrote {} ({} vertices, {} triangles, labels {:?})",
        args.out.display(),
        mesh.num_vertices(),
        mesh.num_triangles(),
        mesh.label_set().iter().map(|l| l.raw()).collect::<Vec<_>>()
    );
    Ok(ExitCode::SUCCESS)
}
