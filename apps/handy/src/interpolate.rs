//! `handy interpolate`: encodes two registered hands, walks the straight line between their
//! latent codes and decodes every step (OBJ files plus a PNG contact sheet).

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;
use meshgnn_geometry::{OutputGuard, TriMesh, check_count, read_mesh, stderr_line, stdout_line};
use meshgnn_models::{MAX_DECODED_SHAPES, MorphableModel, check_registered, interpolate_shapes};
use serde_json::json;

use crate::model::load_model;
use crate::shape_folder::{ShapeFolder, write_shape_folder};

/// Arguments of `handy interpolate`.
#[derive(Args, Debug)]
pub struct InterpolateArgs {
    /// First hand (registered to the model's template).
    pub a: PathBuf,
    /// Second hand.
    pub b: PathBuf,
    /// Number of meshes, both ends included (2 to 1000).
    #[arg(long, default_value_t = 8)]
    pub steps: usize,
    /// Output folder (created): `interp_000.obj`, …, `interpolation.png`.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Model file (default: the built-in Handy++ model).
    #[arg(long)]
    pub model: Option<PathBuf>,
    /// Print a JSON summary on stdout.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: &InterpolateArgs) -> Result<()> {
    check_count(
        "--steps",
        args.steps,
        2..=MAX_DECODED_SHAPES,
        "every step is a decoded mesh and a contact-sheet tile",
    )?;
    let loaded = load_model(args.model.as_deref())?;
    let read = |p: &PathBuf| -> Result<TriMesh> {
        let mesh = read_mesh(p).with_context(|| format!("reading {}", p.display()))?;
        check_registered(&loaded.model, &mesh, p)?;
        Ok(mesh)
    };
    let (a, b) = (read(&args.a)?, read(&args.b)?);
    let shapes = interpolate_shapes(&loaded.model, a.vertices(), b.vertices(), args.steps)?;
    let ShapeFolder {
        meshes,
        files,
        sheet,
    } = write_shape_folder(
        &OutputGuard::new([&args.a, &args.b].into_iter().chain(&args.model)),
        &args.output,
        "interp",
        args.output.join("interpolation.png"),
        4,
        loaded.model.template(),
        shapes,
    )?;
    if args.json {
        stdout_line!(
            "{}",
            json!({"steps": args.steps, "files": files, "contact_sheet": sheet.display().to_string()})
        );
    } else {
        stderr_line!("{} meshes → {}", meshes.len(), args.output.display());
    }
    Ok(())
}
