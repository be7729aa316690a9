//! `express train`: trains the expression generator (or, with `--decoder blendshape`, its
//! baseline; with `--decoder residual`, blendshapes plus a spiral decoder of the remainder)
//! with the thesis' optimiser (Adam, weight decay 5e-5) on a 4D face dataset's `train` split (eq. 4.2, Adam, lr 1e-3 × 0.99 per epoch),
//! choosing the epoch by the per-vertex error on the last `--validation-subjects` training
//! subjects (subject-disjoint; the `test` split is never read).

use std::path::PathBuf;

use anyhow::{Result, bail};
use candle_core::Device;
use clap::{Args, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};
use meshgnn_geometry::{OutputGuard, check_count, stderr_line, stdout_line};
use meshgnn_models::expression::{
    DecoderKind, ExpressionGeneratorConfig, ExpressionModel, ExpressionTraining,
};
use meshgnn_models::training::{self, TrainingConfig};
use meshgnn_models::{MAX_BATCH_SIZE, MAX_EPOCHS};
use serde_json::json;

use crate::face_folder::read_face_folder;

/// The decoder to train.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Decoder {
    /// The spiral mesh decoder of Table 4.1 (the thesis' model).
    Spiral,
    /// PCA blendshapes of the training displacements (the baseline).
    Blendshape,
    /// Blendshapes plus a spiral decoder of their remainder (start it from a trained
    /// baseline with `--init`).
    Residual,
}

/// Arguments of `express train`.
#[derive(Args, Debug)]
pub struct TrainArgs {
    /// Dataset folder (`synth faces` output).
    pub data: PathBuf,
    /// Output model file (safetensors); the resumable checkpoint goes beside it.
    #[arg(short, long)]
    pub output: PathBuf,
    /// The decoder.
    #[arg(long, value_enum, default_value_t = Decoder::Spiral)]
    pub decoder: Decoder,
    /// Start from this model's parameters wherever names and shapes match (and its
    /// blendshapes): `--decoder residual --init BASELINE.safetensors` starts as the baseline.
    #[arg(long, value_name = "MODEL")]
    pub init: Option<PathBuf>,
    /// Passes over the training sequences.
    #[arg(long, default_value_t = 100)]
    pub epochs: usize,
    /// Sequences per step.
    #[arg(long, default_value_t = 4)]
    pub batch_size: usize,
    /// Initial Adam learning rate.
    #[arg(long, default_value_t = 1e-3)]
    pub lr: f64,
    /// Learning-rate factor per epoch.
    #[arg(long, default_value_t = 0.99)]
    pub lr_decay: f64,
    /// Adam's weight decay (the thesis' 5e-5).
    #[arg(long, default_value_t = 5e-5)]
    pub weight_decay: f64,
    /// Training subjects held out to choose the epoch.
    #[arg(long, default_value_t = 4)]
    pub validation_subjects: usize,
    /// Seed of the weights and the data order.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Continue from the checkpoint beside the output.
    #[arg(long)]
    pub resume: bool,
    /// Print a JSON summary on stdout.
    #[arg(long)]
    pub json: bool,
}

/// `OUTPUT.checkpoint`: the resumable training state beside the model file.
fn checkpoint_path(output: &std::path::Path) -> PathBuf {
    let mut name = output.as_os_str().to_owned();
    name.push(".checkpoint");
    PathBuf::from(name)
}

pub fn run(args: &TrainArgs) -> Result<()> {
    let guard = OutputGuard::new(std::iter::once(&args.data).chain(&args.init));
    guard.check(&args.output)?;
    guard.check(&checkpoint_path(&args.output))?;
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
        "sequences per step",
    )?;
    if !(args.lr > 0.0 && args.lr.is_finite()) {
        bail!("--lr {}: must be a finite learning rate > 0", args.lr);
    }
    if !(args.lr_decay > 0.0 && args.lr_decay <= 1.0) {
        bail!("--lr-decay {}: must be in (0, 1]", args.lr_decay);
    }
    if !(args.weight_decay >= 0.0 && args.weight_decay.is_finite()) {
        bail!(
            "--weight-decay {}: must be a finite number ≥ 0",
            args.weight_decay
        );
    }
    let folder = read_face_folder(&args.data, "train")?;
    if args.validation_subjects >= folder.subjects {
        bail!(
            "--validation-subjects {}: the train split has only {} subjects",
            args.validation_subjects,
            folder.subjects
        );
    }
    let (train, validation) = folder.sequences.hold_out_subjects(args.validation_subjects);
    let config = ExpressionGeneratorConfig {
        decoder: match args.decoder {
            Decoder::Spiral => DecoderKind::Spiral,
            Decoder::Blendshape => DecoderKind::Blendshape,
            Decoder::Residual => DecoderKind::Residual,
        },
        displacement_scale: train.displacement_rms().max(1e-6),
        ..Default::default()
    };
    stderr_line!(
        "training the {:?} expression model on {} sequences ({} frames) of {} subjects, choosing \
         the epoch on {} held-out subjects",
        args.decoder,
        train.sequences.len(),
        train.frame_count(),
        train.neutrals.len(),
        validation.neutrals.len()
    );
    let mut task = match &args.init {
        Some(path) => {
            let init = ExpressionModel::load(path, &Device::Cpu)?;
            let (task, taken) = ExpressionTraining::starting_from(
                &init,
                path,
                &config,
                &train,
                &validation,
                args.seed,
            )?;
            stderr_line!("{taken} parameter tensors start from {}", path.display());
            task
        }
        None => ExpressionTraining::new(
            &folder.template,
            &config,
            &train,
            &validation,
            args.seed,
            &Device::Cpu,
        )?,
    };
    let steps = train.sequences.len().div_ceil(args.batch_size);
    let bar = ProgressBar::new((args.epochs * steps) as u64);
    if let Ok(style) =
        ProgressStyle::with_template("[{elapsed_precise}] {wide_bar} epoch {msg} ({eta} left)")
    {
        bar.set_style(style);
    }
    let training_config = TrainingConfig {
        epochs: args.epochs,
        batch_size: args.batch_size,
        learning_rate: args.lr,
        lr_decay: args.lr_decay,
        weight_decay: args.weight_decay,
        seed: args.seed,
        checkpoint: Some(checkpoint_path(&args.output)),
        resume: args.resume && checkpoint_path(&args.output).exists(),
        best_weights: Some(args.output.clone()),
    };
    let run = training::train(&mut task, &training_config, &mut |p| {
        if p.epoch_end {
            bar.suspend(|| {
                stderr_line!(
                    "epoch {:>3}: loss {:.4}, train {:.3} mm, held-out {:.3} mm{}",
                    p.epoch + 1,
                    p.loss,
                    p.figure.unwrap_or(f64::NAN),
                    p.validation.unwrap_or(f64::NAN),
                    if p.improved { " (best)" } else { "" }
                )
            });
        } else {
            bar.set_message(format!("{}/{}", p.epoch + 1, p.epochs));
            bar.inc(1);
        }
    })?;
    bar.finish_and_clear();
    let best = run.state.best_validation;
    stderr_line!(
        "wrote {} (best held-out error {:.3} mm) in {:.0} s",
        args.output.display(),
        best.unwrap_or(f64::NAN),
        run.seconds
    );
    if args.json {
        stdout_line!(
            "{}",
            json!({
                "output": args.output.display().to_string(),
                "decoder": format!("{:?}", args.decoder).to_lowercase(),
                "epochs": run.state.epochs_completed,
                "seconds": run.seconds,
                "best_validation_mm": best,
                "history": run.history.iter().map(|p| json!({
                    "epoch": p.epoch + 1, "loss": p.loss, "train_mm": p.figure, "validation_mm": p.validation,
                })).collect::<Vec<_>>(),
            })
        );
    }
    Ok(())
}
