//! The training loop: epochs of seeded shuffled batches, Adam (the crate's own [`Adam`], so its
//! state can be saved) with the learning rate `lr · decay^epoch`, validation after every epoch,
//! the best epoch's weights kept, a resumable checkpoint after every epoch.
//!
//! # Resuming
//! A checkpoint holds the model's tensors, Adam's moments (`optimizer.{m,v}.<name>`) and the
//! [`TrainingState`] (epochs completed, steps, seed, best validation). The shuffle of epoch `e`
//! depends only on `(seed, e)` ([`epoch_order`]) and a model's batch loss only on its
//! [`StepContext`], so a run resumed from a checkpoint ends bit-identical with an
//! uninterrupted one. A checkpoint written before the moments were stored still resumes, with
//! the moments restarted at zero.

use std::path::PathBuf;
use std::time::Instant;

use candle_core::DType;
use rand::{SeedableRng, rngs::StdRng, seq::SliceRandom};

use super::{StepContext, Trainable};
use crate::checkpoint::{OPTIMIZER_PREFIX, checkpoint_error};
use crate::{Adam, AdamConfig, Checkpoint, Error, Result, TrainingState};

/// Settings of [`train`]; update with `..Default::default()`.
#[derive(Debug, Clone, PartialEq)]
pub struct TrainingConfig {
    /// Passes over the training examples. Default 100.
    pub epochs: usize,
    /// Examples per optimiser step. Default 16.
    pub batch_size: usize,
    /// Initial Adam learning rate. Default 1e-3.
    pub learning_rate: f64,
    /// Learning rate factor per epoch (`lr_e = lr · decay^e`). Default 0.99.
    pub lr_decay: f64,
    /// Adam's weight decay `λ` (see [`crate::AdamConfig`]). Default 0.
    pub weight_decay: f64,
    /// Seed of the data order (and of whatever the model draws per step). Default 0.
    pub seed: u64,
    /// Resumable checkpoint written (atomically) after every epoch; none when `None`.
    pub checkpoint: Option<PathBuf>,
    /// Continue from `checkpoint`, which must exist.
    pub resume: bool,
    /// Where the weights of the epoch with the lowest validation figure go (without the
    /// optimiser state), written whenever the figure improves; none when `None`.
    pub best_weights: Option<PathBuf>,
}

impl Default for TrainingConfig {
    fn default() -> Self {
        Self {
            epochs: 100,
            batch_size: 16,
            learning_rate: 1e-3,
            lr_decay: 0.99,
            weight_decay: 0.0,
            seed: 0,
            checkpoint: None,
            resume: false,
            best_weights: None,
        }
    }
}

/// What the progress callback receives after every step and at the end of every epoch.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrainingProgress {
    /// Current epoch, `0..epochs`.
    pub epoch: usize,
    /// Total epochs.
    pub epochs: usize,
    /// Optimiser steps taken so far (over all epochs).
    pub step: u64,
    /// Steps taken in this epoch.
    pub step_in_epoch: usize,
    /// Steps per epoch.
    pub steps_per_epoch: usize,
    /// The loss of the last batch during an epoch; the epoch's mean (weighted by batch size)
    /// at its end.
    pub loss: f64,
    /// The model's own figure ([`super::BatchLoss::figure`]), averaged as `loss`.
    pub figure: Option<f64>,
    /// The validation figure; `Some` at the end of an epoch when the model has held-out data.
    pub validation: Option<f64>,
    /// True at the end of an epoch whose validation figure is the lowest so far.
    pub improved: bool,
    /// True for the end-of-epoch report.
    pub epoch_end: bool,
    /// Learning rate of the epoch.
    pub learning_rate: f64,
}

/// What [`train`] returns (the trained weights stay in the model).
#[derive(Debug, Clone)]
pub struct TrainingRun {
    /// The end-of-epoch report of every epoch run by this call.
    pub history: Vec<TrainingProgress>,
    /// Where training stands now (as the last checkpoint records it).
    pub state: TrainingState,
    /// Wall time of this call in seconds.
    pub seconds: f64,
}

/// Trains `model` as `config` says, calling `progress` after every step and at every epoch
/// end. Errors when the config is inconsistent, the model has no training examples, a loss is
/// not finite, or a checkpoint cannot be read or written.
pub fn train(
    model: &mut dyn Trainable,
    config: &TrainingConfig,
    progress: &mut dyn FnMut(&TrainingProgress),
) -> Result<TrainingRun> {
    let started = Instant::now();
    check_config(config)?;
    let count = model.train_len();
    if count == 0 {
        return Err(Error::Invalid {
            what: "training examples".into(),
            reason: "none given".into(),
        });
    }
    let (mut state, optimizer_state) = start(model, config)?;
    let mut optimizer = Adam::new(
        model.parameters(),
        AdamConfig {
            learning_rate: config.learning_rate,
            weight_decay: config.weight_decay,
            ..Default::default()
        },
    )?;
    if let Some(tensors) = &optimizer_state {
        optimizer.restore(tensors, OPTIMIZER_PREFIX, state.step)?;
    }
    let steps_per_epoch = count.div_ceil(config.batch_size);
    let mut history = Vec::new();
    for epoch in state.epochs_completed..config.epochs {
        let learning_rate = config.learning_rate * config.lr_decay.powi(epoch as i32);
        optimizer.set_learning_rate(learning_rate);
        let order = epoch_order(count, state.seed, epoch);
        let (mut loss_sum, mut figure_sum, mut weight_sum) = (0.0f64, None::<f64>, 0.0f64);
        for (i, batch) in order.chunks(config.batch_size).enumerate() {
            let context = StepContext {
                epoch,
                step: state.step,
                seed: state.seed,
            };
            let out = model.batch_loss(batch, &context)?;
            let loss = f64::from(out.loss.to_dtype(DType::F32)?.to_scalar::<f32>()?);
            if !loss.is_finite() {
                return Err(Error::Invalid {
                    what: format!("loss at step {}", state.step),
                    reason: format!("is {loss}; lower the learning rate"),
                });
            }
            optimizer.backward_step(&out.loss)?;
            state.step += 1;
            let w = batch.len() as f64;
            loss_sum += w * loss;
            weight_sum += w;
            if let Some(f) = out.figure {
                figure_sum = Some(figure_sum.unwrap_or(0.0) + w * f);
            }
            progress(&TrainingProgress {
                epoch,
                epochs: config.epochs,
                step: state.step,
                step_in_epoch: i + 1,
                steps_per_epoch,
                loss,
                figure: out.figure,
                validation: None,
                improved: false,
                epoch_end: false,
                learning_rate,
            });
        }
        let validation = model.validation()?;
        let improved = validation
            .is_some_and(|v| v.is_finite() && state.best_validation.is_none_or(|best| v < best));
        state.epochs_completed = epoch + 1;
        state.loss = Some(loss_sum / weight_sum.max(1.0));
        if improved {
            state.best_validation = validation;
            state.best_epoch = Some(epoch + 1);
        }
        // the best weights first, then the checkpoint that records them as the best
        if let (true, Some(path)) = (improved, &config.best_weights) {
            let mut best = model.checkpoint()?;
            best.header.training = Some(state);
            best.save(path)?;
        }
        if let Some(path) = &config.checkpoint {
            let mut checkpoint = model.checkpoint()?;
            checkpoint.header.training = Some(state);
            for (name, t) in optimizer.state_tensors(OPTIMIZER_PREFIX) {
                checkpoint.tensors.insert(name, t);
            }
            checkpoint.save(path)?;
        }
        let report = TrainingProgress {
            epoch,
            epochs: config.epochs,
            step: state.step,
            step_in_epoch: steps_per_epoch,
            steps_per_epoch,
            loss: loss_sum / weight_sum.max(1.0),
            figure: figure_sum.map(|f| f / weight_sum.max(1.0)),
            validation,
            improved,
            epoch_end: true,
            learning_rate,
        };
        progress(&report);
        history.push(report);
    }
    Ok(TrainingRun {
        history,
        state,
        seconds: started.elapsed().as_secs_f64(),
    })
}

/// The training state to start from and, when resuming, the checkpoint's tensors (holding
/// the optimiser moments).
fn start(
    model: &mut dyn Trainable,
    config: &TrainingConfig,
) -> Result<(
    TrainingState,
    Option<std::collections::HashMap<String, candle_core::Tensor>>,
)> {
    let fresh = TrainingState {
        seed: config.seed,
        ..Default::default()
    };
    if !config.resume {
        return Ok((fresh, None));
    }
    let Some(path) = &config.checkpoint else {
        return Err(Error::Invalid {
            what: "training config".into(),
            reason: "resuming needs a checkpoint path".into(),
        });
    };
    let checkpoint = Checkpoint::load(path)?;
    checkpoint.header.expect_model(model.model_name(), path)?;
    let state = checkpoint.header.training.ok_or_else(|| {
        checkpoint_error(
            path,
            "holds weights only, no training state to resume".into(),
        )
    })?;
    model.restore(&checkpoint, path)?;
    Ok((state, Some(checkpoint.tensors)))
}

fn check_config(config: &TrainingConfig) -> Result<()> {
    let positive = |x: f64| x.is_finite() && x > 0.0;
    if config.batch_size == 0 || !positive(config.learning_rate) || !positive(config.lr_decay) {
        return Err(Error::Invalid {
            what: "training config".into(),
            reason: format!(
                "batch size {}, learning rate {} and decay {} must be positive",
                config.batch_size, config.learning_rate, config.lr_decay
            ),
        });
    }
    Ok(())
}

/// The order of the `count` training examples in `epoch`: a shuffle seeded by SplitMix64 of
/// `(seed, epoch)`, so a resumed run reproduces it.
pub fn epoch_order(count: usize, seed: u64, epoch: usize) -> Vec<usize> {
    let mut z = seed
        ^ (epoch as u64)
            .wrapping_add(1)
            .wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    let mut order: Vec<usize> = (0..count).collect();
    order.shuffle(&mut StdRng::seed_from_u64(z ^ (z >> 31)));
    order
}

#[cfg(test)]
mod tests {
    use super::*;
    use candle_core::{Device, Tensor, Var};
    use serde_json::Map;
    use std::path::Path;

    use crate::CheckpointHeader;

    /// Least squares `w·x ≈ y` on a few points; the held-out points' error validates.
    struct Line {
        w: Var,
        train: Vec<(f32, f32)>,
        held_out: Vec<(f32, f32)>,
    }

    impl Line {
        fn new(held_out: Vec<(f32, f32)>) -> Self {
            let w = Var::zeros(1, DType::F32, &Device::Cpu).unwrap();
            let train = vec![(1.0, 2.0), (2.0, 4.1), (3.0, 5.9), (4.0, 8.2)];
            Self { w, train, held_out }
        }
        fn error(&self, points: &[(f32, f32)]) -> Result<Tensor> {
            let x: Vec<f32> = points.iter().map(|p| p.0).collect();
            let y: Vec<f32> = points.iter().map(|p| p.1).collect();
            let x = Tensor::from_vec(x, points.len(), &Device::Cpu)?;
            let y = Tensor::from_vec(y, points.len(), &Device::Cpu)?;
            Ok(x.broadcast_mul(self.w.as_tensor())?
                .sub(&y)?
                .sqr()?
                .mean_all()?)
        }
    }

    impl Trainable for Line {
        fn model_name(&self) -> &'static str {
            "line"
        }
        fn train_len(&self) -> usize {
            self.train.len()
        }
        fn parameters(&self) -> Vec<(String, Var)> {
            vec![("w".into(), self.w.clone())]
        }
        fn batch_loss(&self, batch: &[usize], _: &StepContext) -> Result<super::super::BatchLoss> {
            let points: Vec<(f32, f32)> = batch.iter().map(|&i| self.train[i]).collect();
            Ok(super::super::BatchLoss {
                loss: self.error(&points)?,
                figure: None,
            })
        }
        fn validation(&self) -> Result<Option<f64>> {
            if self.held_out.is_empty() {
                return Ok(None);
            }
            Ok(Some(f64::from(
                self.error(&self.held_out)?.to_scalar::<f32>()?,
            )))
        }
        fn checkpoint(&self) -> Result<Checkpoint> {
            Ok(Checkpoint {
                header: CheckpointHeader::new("line", Map::new()),
                tensors: [("w".to_string(), self.w.as_detached_tensor())].into(),
            })
        }
        fn restore(&mut self, checkpoint: &Checkpoint, _: &Path) -> Result<()> {
            self.w.set(&checkpoint.tensors["w"])?;
            Ok(())
        }
    }

    fn w(line: &Line) -> f32 {
        line.w.as_tensor().to_vec1::<f32>().unwrap()[0]
    }

    #[test]
    fn fits_and_keeps_the_best_epoch() {
        // the held-out point is y = 0: validation gets worse as w approaches 2, so epoch 1 is
        // the best and its weights stay in `best_weights`
        let mut line = Line::new(vec![(1.0, 0.0)]);
        let dir = tempfile::tempdir().unwrap();
        let best = dir.path().join("best.safetensors");
        let config = TrainingConfig {
            epochs: 30,
            batch_size: 2,
            learning_rate: 0.1,
            best_weights: Some(best.clone()),
            ..Default::default()
        };
        let mut steps = 0;
        let run = train(&mut line, &config, &mut |p| {
            steps += usize::from(!p.epoch_end)
        })
        .unwrap();
        assert_eq!((steps, run.state.step), (60, 60));
        assert!((w(&line) - 2.02).abs() < 0.1, "{}", w(&line));
        assert_eq!(run.state.best_epoch, Some(1));
        assert!(run.history[0].improved && !run.history[1].improved);
        let saved = Checkpoint::load(&best).unwrap();
        assert_eq!(saved.header.training.unwrap().epochs_completed, 1);
        let saved_w = saved.tensors["w"].to_vec1::<f32>().unwrap()[0];
        assert!(saved_w < 1.0, "{saved_w}");
    }

    #[test]
    fn resumes_bit_identically_and_refuses_what_it_cannot_resume() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("ckpt.safetensors");
        let config = TrainingConfig {
            epochs: 3,
            batch_size: 3,
            learning_rate: 0.05,
            seed: 9,
            checkpoint: Some(path.clone()),
            ..Default::default()
        };
        let mut straight = Line::new(vec![(5.0, 10.0)]);
        let all = train(&mut straight, &config, &mut |_| {}).unwrap();
        let mut first = Line::new(vec![(5.0, 10.0)]);
        train(
            &mut first,
            &TrainingConfig {
                epochs: 2,
                ..config.clone()
            },
            &mut |_| {},
        )
        .unwrap();
        let mut resumed = Line::new(vec![(5.0, 10.0)]);
        let rest = train(
            &mut resumed,
            &TrainingConfig {
                resume: true,
                ..config.clone()
            },
            &mut |_| {},
        )
        .unwrap();
        assert_eq!(w(&resumed).to_bits(), w(&straight).to_bits());
        assert_eq!(rest.history, all.history[2..]);
        assert_eq!(rest.state, all.state);
        let missing = TrainingConfig {
            resume: true,
            checkpoint: Some(dir.path().join("missing")),
            ..config.clone()
        };
        assert!(train(&mut Line::new(vec![]), &missing, &mut |_| {}).is_err());
        let bad = TrainingConfig {
            batch_size: 0,
            ..config
        };
        assert!(train(&mut Line::new(vec![]), &bad, &mut |_| {}).is_err());
    }

    #[test]
    fn epoch_order_is_a_seeded_permutation() {
        let a = epoch_order(10, 3, 0);
        let mut sorted = a.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..10).collect::<Vec<_>>());
        assert_eq!(a, epoch_order(10, 3, 0));
        assert_ne!(a, epoch_order(10, 3, 1));
        assert_ne!(a, epoch_order(10, 4, 0));
    }
}
