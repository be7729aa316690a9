//! `handy train`: trains Handy++ (the spiral autoencoder) on a registered dataset's `train`
//! split, monitoring the per-vertex error (mm) on its `test` split, then stores the Gaussian of
//! the training latents in the model file.

use std::path::PathBuf;

use anyhow::{Context, Result};
use candle_core::Device;
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use meshgnn_geometry::OutputGuard;
use meshgnn_models::spiral::{
    SpiralAutoencoderConfig, SpiralMorphableModel, TrainConfig, train_spiral_model,
};
use meshgnn_models::{generalisation_error, latent_gaussian};
use serde_json::json;

use crate::dataset;
use crate::model::{LATENT_GAUSSIAN_KEY, gaussian_json};

/// Arguments of `handy train`.
#[derive(Args, Debug)]
pub struct TrainArgs {
    /// Dataset folder (`synth hands` output or any registered folder dataset).
    pub data: PathBuf,
    /// Latent size Z (the thesis reports 8 and 30).
    #[arg(long, default_value_t = 8)]
    pub latent: usize,
    /// Output model file (safetensors); also the per-epoch checkpoint.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Pooling levels of the network (1-4; Table 3.1 uses 4: channels 8, 16, 32, 64, each
    /// level reducing the vertices ~4x). Fewer for small templates.
    #[arg(long, default_value_t = 4)]
    pub levels: usize,
    /// Passes over the training split.
    #[arg(long, default_value_t = 40)]
    pub epochs: usize,
    /// Meshes per step.
    #[arg(long, default_value_t = 8)]
    pub batch_size: usize,
    /// Initial Adam learning rate.
    #[arg(long, default_value_t = 1e-3)]
    pub lr: f64,
    /// Learning-rate factor per epoch.
    #[arg(long, default_value_t = 0.96)]
    pub lr_decay: f64,
    /// Seed of the weights and the data order.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Continue from the output file when it is a checkpoint of the same configuration.
    #[arg(long)]
    pub resume: bool,
    /// Print a JSON summary on stdout.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: &TrainArgs) -> Result<()> {
    OutputGuard::new([&args.data]).check(&args.output)?;
    let data = dataset::open(&args.data)?;
    let train = data.load("train", None)?;
    let validation = if data.has_split("test") {
        data.load("test", None)?
    } else {
        Vec::new()
    };
    if !(1..=4).contains(&args.levels) {
        anyhow::bail!("--levels {}: must be 1 to 4", args.levels);
    }
    let defaults = SpiralAutoencoderConfig::default();
    let model_config = SpiralAutoencoderConfig {
        latent_size: args.latent,
        channels: defaults
            .channels
            .iter()
            .take(args.levels)
            .copied()
            .collect(),
        factors: defaults.factors.iter().take(args.levels).copied().collect(),
        spiral_lengths: defaults
            .spiral_lengths
            .iter()
            .take(args.levels + 1)
            .copied()
            .collect(),
        dilations: defaults
            .dilations
            .iter()
            .take(args.levels + 1)
            .copied()
            .collect(),
        ..defaults
    };
    let config = TrainConfig {
        epochs: args.epochs,
        batch_size: args.batch_size,
        learning_rate: args.lr,
        lr_decay: args.lr_decay,
        seed: args.seed,
        checkpoint: Some(args.output.clone()),
        resume: args.resume,
    };
    eprintln!(
        "training Handy++ (latent {}) on {} meshes of {} vertices, validating on {}",
        args.latent,
        train.len(),
        data.template.vertex_count(),
        validation.len()
    );
    let bar = ProgressBar::new((args.epochs * train.len().div_ceil(args.batch_size.max(1))) as u64);
    if let Ok(style) =
        ProgressStyle::with_template("[{elapsed_precise}] {wide_bar} epoch {msg} ({eta} left)")
    {
        bar.set_style(style);
    }
    let mut last_val = None;
    let trained = train_spiral_model(
        &data.template,
        &model_config,
        &train,
        &validation,
        &config,
        &Device::Cpu,
        &mut |p| {
            bar.set_position(p.step as u64);
            if let Some(v) = p.val_mm {
                last_val = Some(v);
            }
            let val = last_val.map_or(String::from("-"), |v| format!("{v:.3}"));
            bar.set_message(format!(
                "{}/{}  train {:.3} mm  val {val} mm",
                p.epoch + 1,
                p.epochs,
                p.train_mm
            ));
            if p.epoch_end {
                let line = format!(
                    "epoch {:>3}/{}  lr {:.2e}  train {:.3} mm  val {val} mm",
                    p.epoch + 1,
                    p.epochs,
                    p.learning_rate,
                    p.train_mm
                );
                // a hidden bar (no terminal, e.g. a log file) drops `println`
                if bar.is_hidden() {
                    eprintln!("{line}");
                } else {
                    bar.println(line);
                }
            }
        },
    )?;
    bar.finish_and_clear();
    let model = trained.model;
    let gaussian = latent_gaussian(&model, &train)?;
    let train_mm = generalisation_error(&model, &train)?.mean;
    let val_mm = if validation.is_empty() {
        None
    } else {
        Some(generalisation_error(&model, &validation)?.mean)
    };
    // keep the checkpoint's training state so `--resume` can continue with more epochs
    let (_, meta) = SpiralMorphableModel::load_with_metadata(&args.output, &Device::Cpu)
        .with_context(|| format!("re-reading {}", args.output.display()))?;
    let mut extra = vec![
        (LATENT_GAUSSIAN_KEY, gaussian_json(&gaussian)),
        (
            "trained_on",
            format!("{} ({} training meshes)", args.data.display(), train.len()),
        ),
        ("train_mm", format!("{train_mm:.4}")),
    ];
    if let Some(v) = val_mm {
        extra.push(("val_mm", format!("{v:.4}")));
    }
    if let Some(t) = meta.get("training") {
        extra.push(("training", t.clone()));
    }
    model
        .save_with_metadata(&args.output, &extra)
        .with_context(|| format!("writing {}", args.output.display()))?;
    let summary = json!({
        "latent": args.latent,
        "epochs": args.epochs,
        "seed": args.seed,
        "train_meshes": train.len(),
        "validation_meshes": validation.len(),
        "train_mm": train_mm,
        "val_mm": val_mm,
        "seconds": trained.seconds,
        "output": args.output.display().to_string(),
    });
    if args.json {
        println!("{summary}");
    } else {
        eprintln!(
            "done in {:.0} s: train {train_mm:.3} mm, validation {} mm → {}",
            trained.seconds,
            val_mm.map_or("-".into(), |v| format!("{v:.3}")),
            args.output.display()
        );
    }
    Ok(())
}
