//! `pcsimplify train DATA_DIR -o weights.safetensors [--epochs E] [--seed S] [--resume]`:
//! trains the learnable simplifier (thesis ch. 5.6) on a `synth shapes` folder (or any folder
//! dataset with a manifest), with a progress bar showing the loss.
//!
//! Only the named splits are read (default `train`: the boxes, gears and creatures-a
//! families; the `test` families stay unseen for the zero-shot evaluation). Every mesh gives
//! `--clouds-per-shape` clouds of `--points` surface samples. `--validation-shapes` of them
//! (spread over the list, so every family gives some) are held out: after every epoch their
//! loss eq. 5.9 at the benchmark's ratios is computed, and whenever it is the lowest so far the
//! weights alone go to `OUTPUT` (the small file `--weights` and the bundled default use), so
//! `OUTPUT` holds the best epoch, not the last. A resumable checkpoint (weights, Adam state,
//! best validation loss) is written to `OUTPUT.checkpoint` after every epoch.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressStyle};
use meshgnn_data::{FolderDataset, gaussian_noise};
use meshgnn_geometry::{OutputGuard, check_count, sample_surface, stderr_line, stdout_line};
use meshgnn_models::point_simplifier::{
    PointSimplifierConfig, SelectorSpace, SimplifierObjective, SimplifierTraining, TrainingSample,
    prepare_denoising_sample,
};
use meshgnn_models::training::{Trainable, TrainingConfig, train};
use meshgnn_models::{MAX_CLOUDS_PER_SHAPE, MAX_EPOCHS, MAX_TRAINING_CLOUD_POINTS};
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
    /// λ of eq. 5.9, the weight of the curvature term.
    #[arg(long, default_value_t = 0.1)]
    pub curvature_weight: f64,
    /// Temperature τ of the adaptive Chamfer weights (eq. 5.7).
    #[arg(long, default_value_t = 10.0)]
    pub tau: f32,
    /// Gaussian noise levels σ of the training inputs, as fractions of the bounding-sphere
    /// radius (comma separated): cloud c of each shape reads level c mod count, the loss
    /// compares with the clean cloud (training the refinement to denoise).
    #[arg(long, value_delimiter = ',', default_values_t = [0.0])]
    pub noise: Vec<f64>,
    /// Where the selector runs FPS: `latent` (the thesis), `position`, or `centroidal`
    /// (positions, then Lloyd steps snapped to the input points); stored in the weights.
    #[arg(long, value_enum, default_value_t = SelectorSpace::Latent)]
    pub selector: SelectorSpace,
    /// Shapes held out of training to pick the best epoch (0: keep the last epoch).
    #[arg(long, default_value_t = 4)]
    pub validation_shapes: usize,
}

/// The resumable checkpoint next to `output`.
fn checkpoint_path(output: &Path) -> PathBuf {
    let mut name = output.as_os_str().to_owned();
    name.push(".checkpoint");
    PathBuf::from(name)
}

/// Loads the clouds, trains (`meshgnn_models::training::train`), writes the weights.
pub fn run(args: &TrainArgs) -> Result<()> {
    check_count(
        "--points",
        args.points,
        16..=MAX_TRAINING_CLOUD_POINTS,
        "surface samples per training cloud",
    )?;
    check_count(
        "--clouds-per-shape",
        args.clouds_per_shape,
        1..=MAX_CLOUDS_PER_SHAPE,
        "training clouds sampled from each mesh",
    )?;
    check_count(
        "--epochs",
        args.epochs,
        1..=MAX_EPOCHS,
        "passes over the data",
    )?;
    for (name, value) in [
        ("--learning-rate", args.learning_rate),
        ("--tau", f64::from(args.tau)),
    ] {
        if !(value > 0.0 && value.is_finite()) {
            bail!("{name} {value}: must be finite and > 0");
        }
    }
    if args.noise.is_empty() || args.noise.iter().any(|s| !(s.is_finite() && *s >= 0.0)) {
        bail!("--noise: give finite levels σ >= 0, got {:?}", args.noise);
    }
    if !(args.curvature_weight >= 0.0 && args.curvature_weight.is_finite()) {
        bail!(
            "--curvature-weight {}: must be finite and >= 0",
            args.curvature_weight
        );
    }
    let guard = OutputGuard::new([&args.data]);
    guard.check(&args.output)?;
    guard.check(&checkpoint_path(&args.output))?;
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
    let model_config = PointSimplifierConfig {
        selector: args.selector,
        ..Default::default()
    };
    let objective = SimplifierObjective {
        curvature_weight: args.curvature_weight,
        tau: args.tau,
        ..Default::default()
    };
    let (train_names, validation_names) = hold_out(&names, args.validation_shapes)?;
    let load = |names: &[&String], first_seed: u64| -> Result<Vec<TrainingSample>> {
        let jobs: Vec<(usize, &String)> = names
            .iter()
            .enumerate()
            .flat_map(|(i, n)| {
                (0..args.clouds_per_shape).map(move |c| (i * args.clouds_per_shape + c, *n))
            })
            .collect();
        jobs.par_iter()
            .map(|&(k, name)| -> Result<TrainingSample> {
                let mesh = dataset.load(name)?;
                let seed = first_seed.wrapping_add(k as u64);
                let cloud = sample_surface(&mesh, args.points, seed)
                    .with_context(|| format!("sampling {name}"))?;
                let sigma = args.noise[k % args.clouds_per_shape % args.noise.len()];
                let input = gaussian_noise(&cloud.points, sigma, seed)?;
                prepare_denoising_sample(&cloud.points, &input, &model_config, &objective)
                    .with_context(|| format!("preparing {name}"))
            })
            .collect()
    };
    let samples = load(&train_names, args.seed)?;
    let validation = load(&validation_names, args.seed.wrapping_add(1 << 32))?;
    let checkpoint = checkpoint_path(&args.output);
    let (clouds, held_out) = (samples.len(), !validation.is_empty());
    let mut task =
        SimplifierTraining::new(&model_config, &objective, samples, validation, args.seed)?;
    let config = TrainingConfig {
        epochs: args.epochs,
        // one cloud per step (ch. 5.6)
        batch_size: 1,
        learning_rate: args.learning_rate,
        lr_decay: 0.99,
        weight_decay: 0.0,
        seed: args.seed,
        checkpoint: Some(checkpoint.clone()),
        resume: args.resume,
        best_weights: held_out.then(|| args.output.clone()),
    };
    let bar = ProgressBar::new((args.epochs * clouds) as u64);
    if let Ok(style) = ProgressStyle::with_template(
        "train [{elapsed_precise}] {wide_bar} {pos}/{len} ({eta} left) {msg}",
    ) {
        bar.set_style(style);
    }
    stderr_line!(
        "training on {clouds} clouds of {} points from {} shapes ({:?}; {} held out: {:?}), {} epochs{}",
        args.points,
        train_names.len(),
        args.splits,
        validation_names.len(),
        validation_names,
        args.epochs,
        if args.resume {
            format!(" from {}", checkpoint.display())
        } else {
            String::new()
        },
    );
    let mut running = 0.0;
    let run = train(&mut task, &config, &mut |p| {
        if !p.epoch_end {
            if p.step_in_epoch == 1 {
                running = 0.0;
            }
            running += p.loss;
            bar.set_message(format!(
                "epoch {} loss {:.5} (mean {:.5}) lr {:.2e}",
                p.epoch + 1,
                p.loss,
                running / p.step_in_epoch as f64,
                p.learning_rate
            ));
            bar.inc(1);
            return;
        }
        let validation_text = p
            .validation
            .map_or(String::new(), |v| format!("  validation {v:.6}"));
        let kept = if p.improved {
            "  (best so far: kept)"
        } else {
            ""
        };
        let line = format!(
            "epoch {:>3}: mean loss {:.6}{validation_text}{kept}  ({:.0} s)",
            p.epoch + 1,
            p.loss,
            started.elapsed().as_secs_f64()
        );
        // a hidden bar (output not a terminal, e.g. a log file) prints nothing: log plainly
        if bar.is_hidden() {
            stderr_line!("{line}");
        } else {
            bar.println(line);
        }
    })
    .with_context(|| format!("training (checkpoint {})", checkpoint.display()))?;
    bar.finish();
    let kept = match run.state.best_validation {
        Some(best) => format!("the best epoch's weights (validation loss {best:.6})"),
        None => {
            let mut weights = task.checkpoint()?;
            weights.header.training = Some(run.state);
            weights
                .save(&args.output)
                .with_context(|| format!("writing {}", args.output.display()))?;
            "the last epoch's weights".into()
        }
    };
    stdout_line!(
        "wrote {} ({kept}) after {} epochs ({} steps), final mean loss {:.6}, {:.1} s",
        args.output.display(),
        run.state.epochs_completed,
        run.state.step,
        run.history.last().map_or(f64::NAN, |p| p.loss),
        started.elapsed().as_secs_f64()
    );
    Ok(())
}

/// Splits `names` into training and `count` validation shapes, spread evenly over the list (a
/// `synth shapes` manifest lists the families in blocks, so every family gives some).
fn hold_out(names: &[String], count: usize) -> Result<(Vec<&String>, Vec<&String>)> {
    if count >= names.len() {
        bail!(
            "--validation-shapes {count} leaves no training shape out of {}",
            names.len()
        );
    }
    if count == 0 {
        return Ok((names.iter().collect(), Vec::new()));
    }
    let stride = names.len() / count;
    let held = |i: usize| i % stride == stride - 1 && i / stride < count;
    let (validation, train): (Vec<_>, Vec<_>) =
        names.iter().enumerate().partition(|&(i, _)| held(i));
    Ok((
        train.into_iter().map(|(_, n)| n).collect(),
        validation.into_iter().map(|(_, n)| n).collect(),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hold_out_spreads_the_validation_shapes_over_the_families() {
        let names: Vec<String> = ["boxes", "gears", "creatures-a"]
            .iter()
            .flat_map(|f| (0..8).map(move |i| format!("{f}_{i:02}")))
            .collect();
        let (train, validation) = hold_out(&names, 4).unwrap();
        assert_eq!(
            validation,
            ["boxes_05", "gears_03", "creatures-a_01", "creatures-a_07"]
        );
        assert_eq!(train.len(), 20);
        assert!(train.iter().all(|n| !validation.contains(n)));
        let (all, none) = hold_out(&names, 0).unwrap();
        assert_eq!((all.len(), none.len()), (24, 0));
        assert!(hold_out(&names, 24).is_err());
    }
}
