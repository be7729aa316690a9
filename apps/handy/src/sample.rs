//! `handy sample`: random hands from the model's latent Gaussian (the Gaussian of the training
//! latents stored in the model file; `N(0, I)` for a PCA model), as OBJ files plus a PNG
//! contact sheet.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use meshgnn_geometry::{OutputGuard, check_count, stderr_line, stdout_line};
use meshgnn_models::{MAX_DECODED_SHAPES, MorphableModel, decode_latents};
use serde_json::json;

use crate::model::load_model;
use crate::shape_folder::{ShapeFolder, write_shape_folder};

/// Arguments of `handy sample`.
#[derive(Args, Debug)]
pub struct SampleArgs {
    /// Number of hands (1 to 1000).
    #[arg(short = 'n', long, default_value_t = 10)]
    pub count: usize,
    /// Output folder (created): `sample_000.obj`, …, and the contact sheet `samples.png`.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Write the contact sheet here instead of `OUTPUT/samples.png`.
    #[arg(long, value_name = "PNG")]
    pub preview: Option<PathBuf>,
    /// Model file (default: the built-in Handy++ model).
    #[arg(long)]
    pub model: Option<PathBuf>,
    /// Seed of the latent samples.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Print a JSON summary on stdout.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: &SampleArgs) -> Result<()> {
    check_count(
        "--count",
        args.count,
        1..=MAX_DECODED_SHAPES,
        "every hand is a decoded mesh and a contact-sheet tile",
    )?;
    let loaded = load_model(args.model.as_deref())?;
    let latents = loaded.gaussian.sample(args.count, args.seed);
    let shapes = decode_latents(&loaded.model, &latents)?;
    let ShapeFolder { files, sheet, .. } = write_shape_folder(
        &OutputGuard::new(&args.model),
        &args.output,
        "sample",
        args.preview
            .clone()
            .unwrap_or_else(|| args.output.join("samples.png")),
        5,
        loaded.model.template(),
        shapes,
    )?;
    if args.json {
        stdout_line!(
            "{}",
            json!({"count": args.count, "seed": args.seed, "files": files, "contact_sheet": sheet.display().to_string(), "latents": latents})
        );
    } else {
        stderr_line!(
            "{} hands from {} → {} (contact sheet {})",
            args.count,
            loaded.kind(),
            args.output.display(),
            sheet.display()
        );
    }
    Ok(())
}
