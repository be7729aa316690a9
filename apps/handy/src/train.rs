//! `handy train`: trains Handy++ (the spiral autoencoder) on a registered dataset's `train`
//! split, monitoring the per-vertex error (mm) on its `test` split, then stores the Gaussian of
//! the training latents in the model file.

use std::path::PathBuf;

use anyhow::{Context, Result};
use candle_core::Device;
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use meshgnn_geometry::{OutputGuard, check_count, stderr_line, stdout_line};
use meshgnn_models::spiral::{SpiralAutoencoderConfig, SpiralTraining};
use meshgnn_models::training::{self, TrainingConfig};
use meshgnn_models::{
    LATENT_GAUSSIAN_KEY, MAX_BATCH_SIZE, MAX_EPOCHS, MAX_LATENT_SIZE, generalisation_error,
    latent_gaussian,
};
use serde_json::json;

use crate::dataset;

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
    #[arg(long, default_value_t = 150)]
    pub epochs: usize,
    /// Meshes per step.
    #[arg(long, default_value_t = 8)]
    pub batch_size: usize,
    /// Initial Adam learning rate.
    #[arg(long, default_value_t = 1e-3)]
    pub lr: f64,
    /// Learning-rate factor per epoch.
    #[arg(long, default_value_t = 0.98)]
    pub lr_decay: f64,
    /// Seed of the weights and the data order.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Train the thesis' Table 3.1 network alone. By default a fixed PCA path runs beside
    /// the spiral layers: the model starts as the PCA of the training hands and learns the
    /// non-linear remainder (beyond the thesis).
    #[arg(long)]
    pub no_linear_skip: bool,
    /// Continue from the output file when it is a checkpoint of the same configuration.
    #[arg(long)]
    pub resume: bool,
    /// Print a JSON summary on stdout.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: &TrainArgs) -> Result<()> {
    OutputGuard::new([&args.data]).check(&args.output)?;
    check_count(
        "--latent",
        args.latent,
        1..=MAX_LATENT_SIZE,
        "latent code size",
    )?;
    check_count(
        "--epochs",
        args.epochs,
        1..=MAX_EPOCHS,
        "passes over the data",
    )?;
    check_count(
        "--batch-size",
        args.batch_size,
        1..=MAX_BATCH_SIZE,
        "meshes per step",
    )?;
    check_count(
        "--levels",
        args.levels,
        1..=4,
        "pooling levels of Table 3.1",
    )?;
    if !(args.lr > 0.0 && args.lr.is_finite()) {
        anyhow::bail!("--lr {}: must be a finite learning rate > 0", args.lr);
    }
    if !(args.lr_decay > 0.0 && args.lr_decay <= 1.0) {
        anyhow::bail!("--lr-decay {}: must be in (0, 1]", args.lr_decay);
    }
    let data = dataset::open(&args.data)?;
    let train = data.load("train", None)?;
    let validation = if data.has_split("test") {
        data.load("test", None)?
    } else {
        Vec::new()
    };
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
        linear_skip: !args.no_linear_skip,
        ..defaults
    };
    let config = TrainingConfig {
        epochs: args.epochs,
        batch_size: args.batch_size,
        learning_rate: args.lr,
        lr_decay: args.lr_decay,
        weight_decay: 0.0,
        seed: args.seed,
        checkpoint: Some(args.output.clone()),
        // `--resume` without a checkpoint yet starts afresh
        resume: args.resume && args.output.exists(),
        best_weights: None,
    };
    stderr_line!(
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
    let mut task = SpiralTraining::new(
        &data.template,
        &model_config,
        &train,
        &validation,
        args.seed,
        &Device::Cpu,
    )?;
    let mut last_val = None;
    let trained = training::train(&mut task, &config, &mut |p| {
        bar.set_position(p.step);
        if let Some(v) = p.validation {
            last_val = Some(v);
        }
        let val = last_val.map_or(String::from("-"), |v| format!("{v:.3}"));
        let train_mm = p.figure.unwrap_or(f64::NAN);
        bar.set_message(format!(
            "{}/{}  train {train_mm:.3} mm  val {val} mm",
            p.epoch + 1,
            p.epochs,
        ));
        if p.epoch_end {
            let line = format!(
                "epoch {:>3}/{}  lr {:.2e}  train {train_mm:.3} mm  val {val} mm",
                p.epoch + 1,
                p.epochs,
                p.learning_rate,
            );
            // a hidden bar (no terminal, e.g. a log file) drops `println`
            if bar.is_hidden() {
                stderr_line!("{line}");
            } else {
                bar.println(line);
            }
        }
    })?;
    bar.finish_and_clear();
    let model = task.into_model();
    let gaussian = latent_gaussian(&model, &train)?;
    let train_mm = generalisation_error(&model, &train)?.mean;
    let val_mm = if validation.is_empty() {
        None
    } else {
        Some(generalisation_error(&model, &validation)?.mean)
    };
    // the model file: the weights, the latent Gaussian `handy` samples from, and the training
    // state, so `--resume` can continue with more epochs
    let mut file = model.to_checkpoint()?;
    file.header.training = Some(trained.state);
    let entries = &mut file.header.entries;
    entries.insert(LATENT_GAUSSIAN_KEY.into(), gaussian.to_json());
    entries.insert(
        "trained_on".into(),
        format!("{} ({} training meshes)", args.data.display(), train.len()),
    );
    entries.insert("train_mm".into(), format!("{train_mm:.4}"));
    if let Some(v) = val_mm {
        entries.insert("val_mm".into(), format!("{v:.4}"));
    }
    file.save(&args.output)
        .with_context(|| format!("writing {}", args.output.display()))?;
    let summary = json!({
        "latent": args.latent,
        "linear_skip": !args.no_linear_skip,
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
        stdout_line!("{summary}");
    } else {
        stderr_line!(
            "done in {:.0} s: train {train_mm:.3} mm, validation {} mm → {}",
            trained.seconds,
            val_mm.map_or("-".into(), |v| format!("{v:.3}")),
            args.output.display()
        );
    }
    Ok(())
}
