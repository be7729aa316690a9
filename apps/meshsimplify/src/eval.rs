//! `meshsimplify eval ORIGINAL SIMPLIFIED [--json] [--samples 50000] [--seed S]`: how close a
//! simplified mesh stays to its original (thesis ch. 6.5.1, Table 6.1).
//!
//! Both meshes are normalised by the original's centroid and bounding-sphere radius, so
//! lengths are in units of that radius. The `--json` keys are a stable interface (see
//! docs/losses.md): `cd` (Chamfer distance between `--samples` surface samples, per-point
//! means of both directions, squared unit-sphere units), `hausdorff` (unit-sphere units),
//! `ne` (normal error, eq. 6.15, in [0, 4]), `wa` (percentage of non-watertight edges),
//! `le` (Laplacian error over the first 150 eigenvectors, eq. 6.16, dimensionless), `holes`
//! (boundary loops of the simplified mesh), `edge_manifold` (bool).

use std::path::PathBuf;

use anyhow::{Context, Result};
use meshgnn_geometry::{InputUse, check_count, read_input_mesh, stdout_line};
use meshgnn_losses::metrics::{
    MAX_MESH_EVALUATION_SAMPLES, MESH_EVALUATION_SAMPLES, MeshEvaluation, mesh_evaluation,
};
use serde_json::json;

/// Arguments of `meshsimplify eval`.
#[derive(clap::Args, Debug)]
pub struct EvalArgs {
    /// The original mesh (.obj .ply .off .gltf .glb).
    pub original: PathBuf,
    /// The simplified mesh to evaluate against it.
    pub simplified: PathBuf,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
    /// Surface samples per mesh for CD and Hausdorff (the thesis uses 50 000; at most
    /// 10 000 000).
    #[arg(long, default_value_t = MESH_EVALUATION_SAMPLES)]
    pub samples: usize,
    /// Seed of the surface sampling; the same seed gives the same figures.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
}

/// Loads both meshes, evaluates, prints text or JSON.
pub fn run(args: &EvalArgs) -> Result<()> {
    check_count(
        "--samples",
        args.samples,
        1..=MAX_MESH_EVALUATION_SAMPLES,
        "surface samples per mesh",
    )?;
    let read = |path: &PathBuf, role: &str| {
        read_input_mesh(path, InputUse::Surface).with_context(|| format!("reading the {role} mesh"))
    };
    let original = read(&args.original, "original")?;
    let simplified = read(&args.simplified, "simplified")?;
    let e =
        mesh_evaluation(&original, &simplified, args.samples, args.seed).with_context(|| {
            format!(
                "evaluating {} against the original {}",
                args.simplified.display(),
                args.original.display()
            )
        })?;
    if args.json {
        stdout_line!("{}", to_json(&e));
    } else {
        stdout_line!("CD         {:.6e}  (squared unit-sphere units)", e.cd);
        stdout_line!("Hausdorff  {:.6e}  (unit-sphere units)", e.hausdorff);
        stdout_line!("NE         {:.6}", e.ne);
        stdout_line!("WA         {:.3} %", e.wa);
        stdout_line!("LE         {:.6}", e.le);
        stdout_line!("holes      {}", e.holes);
        stdout_line!("manifold   {}", e.edge_manifold);
    }
    Ok(())
}

fn to_json(e: &MeshEvaluation) -> serde_json::Value {
    json!({
        "cd": e.cd,
        "hausdorff": e.hausdorff,
        "ne": e.ne,
        "wa": e.wa,
        "le": e.le,
        "holes": e.holes,
        "edge_manifold": e.edge_manifold,
    })
}
