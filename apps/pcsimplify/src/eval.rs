//! `pcsimplify eval ORIGINAL SIMPLIFIED [--json] [--k 16]`: perceptual quality of a simplified
//! point cloud (thesis ch. 5.4, Table 5.1).
//!
//! Both clouds are normalised by the original's centroid and bounding-sphere radius. The
//! `--json` keys are a stable interface (see docs/losses.md): `cd` (Chamfer distance, per-point
//! means of both directions, squared unit-sphere units), `nc` (normal consistency of the PCA
//! normals, eq. 5.14, unoriented, in [0, 2]), `ce` (curvature error, eq. 5.8), `re` (roughness
//! error), `sdm` (structural distortion, eq. 5.10-5.13, in [0, 1]); the last three are
//! dimensionless.

use std::path::PathBuf;

use anyhow::{Context, Result};
use meshgnn_geometry::{check_count, read_input_point_cloud, stdout_line};
use meshgnn_losses::metrics::{
    EVALUATION_CURVATURE_NEIGHBOURS, MAX_EVALUATION_CURVATURE_NEIGHBOURS, PointCloudEvaluation,
    point_cloud_evaluation,
};
use serde_json::json;

/// Arguments of `pcsimplify eval`.
#[derive(clap::Args, Debug)]
pub struct EvalArgs {
    /// The original point cloud (.ply .obj .xyz; a mesh file gives its vertices).
    pub original: PathBuf,
    /// The simplified point cloud to evaluate against it.
    pub simplified: PathBuf,
    /// Print one JSON object instead of text.
    #[arg(long)]
    pub json: bool,
    /// Neighbours for the curvature features (eq. 5.1-5.3), 2 to 256.
    #[arg(long, default_value_t = EVALUATION_CURVATURE_NEIGHBOURS)]
    pub k: usize,
}

/// Fails unless `--k` (curvature neighbours of the metrics) is within its bound.
pub fn check_curvature_neighbours(k: usize) -> Result<()> {
    check_count(
        "--k",
        k,
        2..=MAX_EVALUATION_CURVATURE_NEIGHBOURS,
        "curvature neighbours per point",
    )?;
    Ok(())
}

/// Loads both clouds, evaluates, prints text or JSON.
pub fn run(args: &EvalArgs) -> Result<()> {
    check_curvature_neighbours(args.k)?;
    let read = |path: &PathBuf, role: &str| {
        read_input_point_cloud(path).with_context(|| format!("reading the {role} cloud"))
    };
    let original = read(&args.original, "original")?;
    let simplified = read(&args.simplified, "simplified")?;
    let e = point_cloud_evaluation(original.points(), simplified.points(), args.k).with_context(
        || {
            format!(
                "evaluating {} against the original {}",
                args.simplified.display(),
                args.original.display()
            )
        },
    )?;
    if args.json {
        stdout_line!("{}", to_json(&e));
    } else {
        stdout_line!("CD   {:.6e}  (squared unit-sphere units)", e.cd);
        stdout_line!("NC   {:.6}", e.nc);
        stdout_line!("CE   {:.6}", e.ce);
        stdout_line!("RE   {:.6}", e.re);
        stdout_line!("SDM  {:.6e}  (PC-MSDM)", e.sdm);
        stdout_line!("SDM-nn {:.6}  (the earlier variant)", e.sdm_nearest);
    }
    Ok(())
}

fn to_json(e: &PointCloudEvaluation) -> serde_json::Value {
    json!({
        "cd": e.cd, "nc": e.nc, "ce": e.ce, "re": e.re, "sdm": e.sdm,
        "sdm_nearest": e.sdm_nearest,
    })
}
