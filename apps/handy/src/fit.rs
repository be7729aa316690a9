//! `handy fit`: fits the model (latent code + similarity transform) to a scan by Chamfer
//! distance (thesis ch. 3.4.4) and writes the fitted mesh in the scan's coordinates
//! (`--preview`: the scan over the fit, three views).

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;
use meshgnn_data::{View, points_on_mesh_sheet, write_png};
use meshgnn_geometry::{
    OutputGuard, TriMesh, bounding_box_diagonal, check_count, read_input_point_cloud, stdout_line,
    write_mesh,
};
use meshgnn_models::{ChamferDirection, MAX_FIT_STEPS, MorphableModel, ScanFitOptions, fit_scan};
use serde_json::json;

use crate::model::load_model;

/// Arguments of `handy fit`.
#[derive(Args, Debug)]
pub struct FitArgs {
    /// The scan: a point cloud (PLY, XYZ, …) or a mesh whose vertices are used.
    pub scan: PathBuf,
    /// Output mesh (OBJ, PLY, …), in the scan's coordinates.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Model file (default: the built-in Handy++ model).
    #[arg(long)]
    pub model: Option<PathBuf>,
    /// Adam steps.
    #[arg(long, default_value_t = 300)]
    pub steps: usize,
    /// Use both Chamfer directions (for complete scans); default scan → model only, which
    /// also suits partial scans.
    #[arg(long)]
    pub symmetric: bool,
    /// Estimate the scale from the point spread (for scans not in millimetres).
    #[arg(long)]
    pub estimate_scale: bool,
    /// Direction from the hand to a single-view scanner, `x,y,z`: matches the scan only
    /// against model vertices facing it (for one-sided scans).
    #[arg(long, value_parser = crate::eval::parse_direction)]
    pub camera: Option<[f32; 3]>,
    /// The scan is already in the model's orientation and handedness: skip the global start
    /// (by default five orientations, each on the scan and its mirror image, are tried first:
    /// see `meshgnn_models::ScanFitOptions::global_init`; about 3× the time).
    #[arg(long)]
    pub aligned: bool,
    /// Seed of the scan subsampling.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Write a PNG: the scan's points (orange) over the fitted mesh, from the front, the side
    /// and above.
    #[arg(long, value_name = "PNG")]
    pub preview: Option<PathBuf>,
    /// Print a JSON summary on stdout.
    #[arg(long)]
    pub json: bool,
}

/// Pixels per side of each `--preview` view.
const PREVIEW_TILE: u32 = 400;

pub fn run(args: &FitArgs) -> Result<()> {
    let guard = OutputGuard::new(std::iter::once(&args.scan).chain(&args.model));
    guard.check(&args.output)?;
    if let Some(p) = &args.preview {
        guard.check(p)?;
    }
    check_count(
        "--steps",
        args.steps,
        1..=MAX_FIT_STEPS,
        "Adam steps of the fit",
    )?;
    let loaded = load_model(args.model.as_deref())?;
    let scan = read_input_point_cloud(&args.scan)
        .with_context(|| format!("reading {}", args.scan.display()))?;
    let options = ScanFitOptions {
        steps: args.steps,
        direction: if args.symmetric {
            ChamferDirection::Symmetric
        } else {
            ChamferDirection::ScanToModel
        },
        estimate_scale: args.estimate_scale,
        seed: args.seed,
        view_direction: args.camera,
        global_init: !args.aligned,
        ..Default::default()
    };
    let fit = fit_scan(
        &loaded.model,
        scan.points(),
        Some(&loaded.gaussian),
        &options,
    )
    .with_context(|| format!("fitting {}", args.scan.display()))?;
    // A mirrored fit (a left hand for a right-hand model) keeps its vertices in the scan's
    // frame; its triangles are flipped so that they face out again.
    let triangles = loaded
        .model
        .template()
        .triangles()
        .iter()
        .map(|&[a, b, c]| if fit.mirrored { [a, c, b] } else { [a, b, c] })
        .collect();
    let mirrored = fit.mirrored;
    let mesh = TriMesh::new(fit.vertices, triangles)?;
    write_mesh(&args.output, &mesh)
        .with_context(|| format!("writing {}", args.output.display()))?;
    if let Some(p) = &args.preview {
        let views = [(0.0, 0.0), (90.0, 0.0), (0.0, 90.0)].map(|(yaw, pitch)| View {
            yaw,
            pitch,
            wireframe: false,
        });
        write_png(
            p,
            &points_on_mesh_sheet(&mesh, scan.points(), &views, PREVIEW_TILE)?,
        )?;
    }
    // The scan's own size: R2S and S2R relative to it compare scans in any unit.
    let diagonal = bounding_box_diagonal(scan.points());
    if args.json {
        stdout_line!(
            "{}",
            json!({
                "r2s_mm": fit.distances.r2s,
                "s2r_mm": fit.distances.s2r,
                "r2s_relative": fit.distances.r2s / diagonal,
                "s2r_relative": fit.distances.s2r / diagonal,
                "scan_points": scan.len(),
                "mirrored": mirrored,
                "latent": fit.latent,
                "scale": fit.transform.scale,
                "rotation_wxyz": fit.transform.rotation,
                "translation": fit.transform.translation,
                "loss": fit.loss,
                "output": args.output.display().to_string(),
                "preview": args.preview.as_ref().map(|p| p.display().to_string()),
            })
        );
    } else {
        stdout_line!(
            "R2S {:.3} mm  S2R {:.3} mm  ({} scan points, scale {:.4}, rotation {:.2}°) → {}",
            fit.distances.r2s,
            fit.distances.s2r,
            scan.len(),
            fit.transform.scale,
            fit.transform.angle().to_degrees(),
            args.output.display()
        );
    }
    Ok(())
}
