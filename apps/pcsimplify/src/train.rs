//! `pcsimplify train DATA_DIR -o weights.safetensors [--epochs E] [--seed S] [--resume]`:
//! trains the learnable simplifier (thesis ch. 5.6) on a `synth shapes` folder (or any folder
//! dataset with a manifest), with a progress bar showing the loss.
//!
//! Only the named splits are read (default `train`: the boxes, gears and creatures-a
//! families; the `test` families stay unseen for the zero-shot evaluation). Every mesh gives
//! `--clouds-per-shape` clouds of `--points` surface samples. After every epoch a resumable
//! checkpoint (weights + Adam state) is written to `OUTPUT.checkpoint`; at the end the weights
//! alone go to `OUTPUT`, the small file `--weights` and the bundled default use.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressStyle};
use meshgnn_data::FolderDataset;
use meshgnn_geometry::sample_surface;
use meshgnn_models::point_simplifier::{
    PointSimplifierConfig, Trainer, TrainingConfig, TrainingSample, prepare_training_sample,
};
use rayon::prelude::*;

/// Arguments of `pcsimplify train`.
#[derive(clap::Args, Debug)]
pub struct TrainArgs {
    /// Dataset folder with a `dataset.json` manifest (e.g. from `synth shapes -o DIR`).
    pub data: PathBuf,
    /// Where the trained weights go (safetensors).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Epochs (passes over the training clouds).
    #[arg(long, default_value_t = 40)]
    pub epochs: usize,
    /// Seed of initialisation, surface sampling, ratios and FPS starts.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Continue from `OUTPUT.checkpoint` (written after every epoch).
    #[arg(long)]
    pub resume: bool,
    /// Splits of the manifest to train on (comma separated).
    #[arg(long, default_value = "train", value_delimiter = ',')]
    pub splits: Vec<String>,
    /// Surface samples per training cloud.
    #[arg(long, default_value_t = 2048)]
    pub points: usize,
    /// Differently sampled clouds per mesh.
    #[arg(long, default_value_t = 2)]
    pub clouds_per_shape: usize,
    /// Initial Adam learning rate (decayed ×0.99 per epoch).
    #[arg(long, default_value_t = 1e-3)]
    pub learning_rate: f64,
}

/// The resumable checkpoint next to `output`.
fn checkpoint_path(output: &Path) -> PathBuf {
    let mut name = output.as_os_str().to_owned();
    name.push(".checkpoint");
    PathBuf::from(name)
}

/// Loads the clouds, trains, writes the weights.
pub fn run(args: &TrainArgs) -> Result<()> {
    if args.points < 16 || args.clouds_per_shape == 0 {
        bail!("--points must be at least 16 and --clouds-per-shape at least 1");
    }
    let started = Instant::now();
    let dataset = FolderDataset::open(&args.data)
        .with_context(|| format!("opening the dataset {}", args.data.display()))?;
    let mut names = Vec::new();
    for split in &args.splits {
        names.extend(dataset.split(split)?.iter().cloned());
    }
    if names.is_empty() {
        bail!("the splits {:?} list no shapes", args.splits);
    }
    let model_config = PointSimplifierConfig::default();
    let config = TrainingConfig {
        epochs: args.epochs,
        seed: args.seed,
        learning_rate: args.learning_rate,
        ..Default::default()
    };
    let jobs: Vec<(usize, &String)> = names
        .iter()
        .enumerate()
        .flat_map(|(i, n)| {
            (0..args.clouds_per_shape).map(move |c| (i * args.clouds_per_shape + c, n))
        })
        .collect();
    let samples = jobs
        .par_iter()
        .map(|&(k, name)| -> Result<TrainingSample> {
            let mesh = dataset.load(name)?;
            let cloud = sample_surface(&mesh, args.points, args.seed.wrapping_add(k as u64))
                .with_context(|| format!("sampling {name}"))?;
            prepare_training_sample(&cloud.points, &model_config, &config)
                .with_context(|| format!("preparing {name}"))
        })
        .collect::<Result<Vec<_>>>()?;
    let checkpoint = checkpoint_path(&args.output);
    let mut trainer = if args.resume {
        Trainer::resume(&checkpoint, &config)
            .with_context(|| format!("resuming from {}", checkpoint.display()))?
    } else {
        Trainer::new(&model_config, &config)?
    };
    let remaining = args.epochs.saturating_sub(trainer.epoch());
    let bar = ProgressBar::new((remaining * samples.len()) as u64);
    if let Ok(style) = ProgressStyle::with_template(
        "train [{elapsed_precise}] {wide_bar} {pos}/{len} ({eta} left) {msg}",
    ) {
        bar.set_style(style);
    }
    eprintln!(
        "training on {} clouds of {} points from {} shapes ({:?}), {} epochs from epoch {}",
        samples.len(),
        args.points,
        names.len(),
        args.splits,
        args.epochs,
        trainer.epoch()
    );
    let mut last = f64::NAN;
    while trainer.epoch() < args.epochs {
        let mut running = 0.0;
        let epoch_loss = trainer.train_epoch(&samples, &mut |p| {
            running += p.loss;
            bar.set_message(format!(
                "epoch {} loss {:.5} (mean {:.5}) lr {:.2e}",
                p.epoch + 1,
                p.loss,
                running / p.step_in_epoch as f64,
                p.learning_rate
            ));
            bar.inc(1);
        })?;
        trainer
            .save(&checkpoint)
            .with_context(|| format!("writing {}", checkpoint.display()))?;
        let line = format!(
            "epoch {:>3}: mean loss {epoch_loss:.6}  ({:.0} s)",
            trainer.epoch(),
            started.elapsed().as_secs_f64()
        );
        // a hidden bar (output not a terminal, e.g. a log file) prints nothing: log plainly
        if bar.is_hidden() {
            eprintln!("{line}");
        } else {
            bar.println(line);
        }
        last = epoch_loss;
    }
    bar.finish();
    trainer
        .save_weights(&args.output)
        .with_context(|| format!("writing {}", args.output.display()))?;
    println!(
        "wrote {} after {} epochs ({} steps), final mean loss {last:.6}, {:.1} s",
        args.output.display(),
        trainer.epoch(),
        trainer.steps(),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}
