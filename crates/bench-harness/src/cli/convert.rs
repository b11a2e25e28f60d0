//! `surftrack convert IN OUT`: between PLY and OBJ, labels kept.

use std::process::ExitCode;

use anyhow::Context;

use super::ConvertArgs;

pub(super) fn run(args: &ConvertArgs) -> anyhow::Result<ExitCode> {
    let mesh = mesh_core::io::read_mesh(&args.input)
        .with_context(|| format!("reading {}", args.input.display()))?;
    if let Some(refusal) = super::no_triangles(&args.input, &mesh) {
        anyhow::bail!(refusal);
    }
    super::write_mesh_file(&mesh, &args.output, args.binary)?;
    println!(
        "wrote {} ({} triangles)",
        args.output.display(),
        mesh.num_triangles()
    );
    Ok(ExitCode::SUCCESS)
}
