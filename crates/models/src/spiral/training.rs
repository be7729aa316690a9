//! Training loop of the spiral morphable model (thesis ch. 3.3.4: "trained using L1 loss on
//! the reconstructed hand meshes"; Adam as Neural3DMM, Bouritsas et al. ICCV 2019): per-vertex
//! normalisation fitted on the training split, seeded shuffling, L1 on normalised coordinates
//! (`meshgnn_losses::losses::reconstruction_l1`, eq. 4.2), Adam with an exponential
//! learning-rate decay per epoch, validation as the mean per-vertex Euclidean error in data
//! units, and a checkpoint (the model file plus the training state) after every epoch.
//!
//! # Resuming
//! With `resume` and an existing checkpoint, training continues after the last completed
//! epoch with the checkpoint's weights, normalisation, learning rate and data order (the
//! shuffle of epoch `e` depends only on `(seed, e)`) and Adam's moment estimates and step
//! count ([`crate::Adam`], stored in the checkpoint as the tensors `optimizer.{m,v}.<name>`
//! beside the model's), so the result is bit-identical with an uninterrupted run. A checkpoint
//! written before the moments were stored still resumes, with the moments restarted at zero.

use std::path::PathBuf;
use std::time::Instant;

use std::collections::HashMap;

use candle_core::{Device, Tensor};
use meshgnn_geometry::TriMesh;
use meshgnn_losses::losses::reconstruction_l1;
use rand::{SeedableRng, rngs::StdRng, seq::SliceRandom};
use serde::{Deserialize, Serialize};

use crate::adam::sorted_vars;
use crate::spiral::vertex_normalization::check_meshes;
use crate::spiral::{
    SpiralAutoencoderConfig, SpiralMorphableModel, VertexNormalization, mesh_batch,
};
use crate::{Adam, AdamConfig, Error, MorphableModel, Result};

/// Prefix of the optimiser-state tensors in a training checkpoint (ignored by model loading).
const OPTIMIZER_PREFIX: &str = "optimizer.";

/// Hyper-parameters of [`train_spiral_model`]; update with `..Default::default()`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrainConfig {
    /// Passes over the training set. Default 100.
    pub epochs: usize,
    /// Meshes per step. Default 16.
    pub batch_size: usize,
    /// Initial Adam learning rate. Default 1e-3.
    pub learning_rate: f64,
    /// Learning rate factor per epoch (`lr_e = lr · decay^e`). Default 0.99.
    pub lr_decay: f64,
    /// Seed of the initial weights and of the shuffling. Default 0.
    pub seed: u64,
    /// Model file written (atomically) after every epoch; none when `None`.
    pub checkpoint: Option<PathBuf>,
    /// Continue from `checkpoint` when it exists.
    pub resume: bool,
}

impl Default for TrainConfig {
    fn default() -> Self {
        Self {
            epochs: 100,
            batch_size: 16,
            learning_rate: 1e-3,
            lr_decay: 0.99,
            seed: 0,
            checkpoint: None,
            resume: false,
        }
    }
}

/// What the progress callback receives after every step and at the end of every epoch.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrainProgress {
    /// Current epoch, `0..epochs`.
    pub epoch: usize,
    /// Total epochs.
    pub epochs: usize,
    /// Optimiser steps taken so far (over all epochs).
    pub step: usize,
    /// Steps per epoch.
    pub steps_per_epoch: usize,
    /// L1 on normalised coordinates: of the last batch during an epoch, the epoch mean at
    /// its end.
    pub train_l1: f64,
    /// Mean per-vertex Euclidean error on training batches in data units (mm), as `train_l1`.
    pub train_mm: f64,
    /// Mean per-vertex Euclidean validation error in data units; `Some` at the end of an
    /// epoch when validation meshes were given.
    pub val_mm: Option<f64>,
    /// True for the end-of-epoch report.
    pub epoch_end: bool,
    /// Learning rate of the epoch.
    pub learning_rate: f64,
}

/// The training state stored in a checkpoint's `training` metadata.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TrainingState {
    /// Epochs completed.
    pub epochs_completed: usize,
    /// Optimiser steps taken.
    pub step: usize,
    /// Seed of the run.
    pub seed: u64,
}

/// The result of [`train_spiral_model`].
#[derive(Debug)]
pub struct TrainedModel {
    /// The model after the last epoch.
    pub model: SpiralMorphableModel,
    /// The end-of-epoch report of every epoch run by this call.
    pub history: Vec<TrainProgress>,
    /// Wall time of this call in seconds.
    pub seconds: f64,
}

/// Trains a spiral morphable model of the registered meshes `train: #S × (#V×3)` (vertices
/// on `template`'s faces), validating on `validation` (may be empty) after every epoch.
/// `progress` is called after every step and at every epoch end.
///
/// Errors when the meshes disagree with the template, a coordinate is not finite, the
/// configs are inconsistent, or a checkpoint cannot be read or written.
///
/// ```
/// use candle_core::Device;
/// use meshgnn_models::spiral::{train_spiral_model, SpiralAutoencoderConfig, TrainConfig};
/// let sphere = meshgnn_geometry::icosphere(2);
/// let shapes: Vec<Vec<[f32; 3]>> = (0..4)
///     .map(|s| sphere.vertices().iter().map(|p| [p[0] * (1.0 + 0.1 * s as f32), p[1], p[2]]).collect())
///     .collect();
/// let cfg = SpiralAutoencoderConfig { channels: vec![8, 16], factors: vec![4.0; 2],
///     spiral_lengths: vec![9; 3], dilations: vec![1; 3], ..Default::default() };
/// let train = TrainConfig { epochs: 2, batch_size: 2, ..Default::default() };
/// let out = train_spiral_model(&sphere, &cfg, &shapes, &shapes, &train, &Device::Cpu, &mut |_| {})?;
/// assert_eq!(out.history.len(), 2);
/// assert!(out.history[1].val_mm.is_some());
/// # Ok::<(), meshgnn_models::Error>(())
/// ```
pub fn train_spiral_model(
    template: &TriMesh,
    model_config: &SpiralAutoencoderConfig,
    train: &[Vec<[f32; 3]>],
    validation: &[Vec<[f32; 3]>],
    config: &TrainConfig,
    device: &Device,
    progress: &mut dyn FnMut(&TrainProgress),
) -> Result<TrainedModel> {
    let started = Instant::now();
    let v = template.vertex_count();
    check_meshes("training meshes", train, Some(v))?;
    if !validation.is_empty() {
        check_meshes("validation meshes", validation, Some(v))?;
    }
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
    let (model, state, saved_optimizer) = start(template, model_config, train, config, device)?;
    let normalization = model.normalization().clone();
    let train_data = normalization.normalize(&mesh_batch(train, device)?)?;
    let validation_data = if validation.is_empty() {
        None
    } else {
        Some(normalization.normalize(&mesh_batch(validation, device)?)?)
    };
    let mut optimizer = Adam::new(
        sorted_vars(model.vars()),
        AdamConfig {
            learning_rate: config.learning_rate,
            ..Default::default()
        },
    )?;
    optimizer.restore(&saved_optimizer, OPTIMIZER_PREFIX, state.step as u64)?;
    let steps_per_epoch = train.len().div_ceil(config.batch_size);
    let mut step = state.step;
    let mut history = Vec::new();
    for epoch in state.epochs_completed..config.epochs {
        let learning_rate = config.learning_rate * config.lr_decay.powi(epoch as i32);
        optimizer.set_learning_rate(learning_rate);
        let mut order: Vec<u32> = (0..train.len() as u32).collect();
        order.shuffle(&mut StdRng::seed_from_u64(epoch_seed(config.seed, epoch)));
        let (mut l1_sum, mut mm_sum, mut weight_sum) = (0.0f64, 0.0f64, 0.0f64);
        for batch in order.chunks(config.batch_size) {
            let ids = Tensor::from_slice(batch, batch.len(), device)?;
            let x = train_data.index_select(&ids, 0)?;
            let predicted = model.network().forward(&x)?;
            let loss = reconstruction_l1(&predicted, &x)?;
            optimizer.backward_step(&loss)?;
            step += 1;
            let train_l1 = f64::from(loss.to_scalar::<f32>()?);
            let train_mm = f64::from(
                normalization
                    .euclidean_error(&predicted.detach(), &x)?
                    .to_scalar::<f32>()?,
            );
            let w = batch.len() as f64;
            (l1_sum, mm_sum, weight_sum) =
                (l1_sum + w * train_l1, mm_sum + w * train_mm, weight_sum + w);
            progress(&TrainProgress {
                epoch,
                epochs: config.epochs,
                step,
                steps_per_epoch,
                train_l1,
                train_mm,
                val_mm: None,
                epoch_end: false,
                learning_rate,
            });
        }
        let val_mm = match &validation_data {
            Some(data) => Some(validation_error(&model, data, config.batch_size.max(32))?),
            None => None,
        };
        let report = TrainProgress {
            epoch,
            epochs: config.epochs,
            step,
            steps_per_epoch,
            train_l1: l1_sum / weight_sum.max(1.0),
            train_mm: mm_sum / weight_sum.max(1.0),
            val_mm,
            epoch_end: true,
            learning_rate,
        };
        if let Some(path) = &config.checkpoint {
            let state = TrainingState {
                epochs_completed: epoch + 1,
                step,
                seed: config.seed,
            };
            let json = serde_json::to_string(&state).map_err(|e| Error::Invalid {
                what: "training state".into(),
                reason: e.to_string(),
            })?;
            save_checkpoint(&model, &optimizer, path, json)?;
        }
        progress(&report);
        history.push(report);
    }
    Ok(TrainedModel {
        model,
        history,
        seconds: started.elapsed().as_secs_f64(),
    })
}

/// Writes the model file with the `training` metadata `state_json` and the optimiser state
/// added as `optimizer.{m,v}.<name>` tensors, atomically.
fn save_checkpoint(
    model: &SpiralMorphableModel,
    optimizer: &Adam,
    path: &std::path::Path,
    state_json: String,
) -> Result<()> {
    let bad = |reason: String| Error::Checkpoint {
        path: path.to_path_buf(),
        reason,
    };
    let bytes = model.to_bytes(&[("training", state_json)])?;
    let (_, header) = safetensors::SafeTensors::read_metadata(&bytes)
        .map_err(|e| bad(format!("cannot re-read the model bytes: {e}")))?;
    let metadata = header.metadata().clone();
    let mut tensors = candle_core::safetensors::load_buffer(&bytes, &Device::Cpu)?;
    for (name, t) in optimizer.state_tensors(OPTIMIZER_PREFIX) {
        tensors.insert(name, t.to_device(&Device::Cpu)?);
    }
    let bytes = safetensors::tensor::serialize(tensors, metadata)
        .map_err(|e| bad(format!("cannot serialise: {e}")))?;
    meshgnn_geometry::atomic_write(path, &bytes)?;
    Ok(())
}

/// A fresh model, or the checkpoint's model, state and optimiser tensors when resuming.
fn start(
    template: &TriMesh,
    model_config: &SpiralAutoencoderConfig,
    train: &[Vec<[f32; 3]>],
    config: &TrainConfig,
    device: &Device,
) -> Result<(SpiralMorphableModel, TrainingState, HashMap<String, Tensor>)> {
    if let (true, Some(path)) = (config.resume, &config.checkpoint)
        && path.exists()
    {
        let (model, metadata) = SpiralMorphableModel::load_with_metadata(path, device)?;
        let bad = |reason: String| Error::Checkpoint {
            path: path.clone(),
            reason,
        };
        let optimizer: HashMap<String, Tensor> = candle_core::safetensors::load(path, device)
            .map_err(|e| bad(format!("unreadable tensors: {e}")))?
            .into_iter()
            .filter(|(k, _)| k.starts_with(OPTIMIZER_PREFIX))
            .collect();
        if model.config() != model_config {
            return Err(bad(format!(
                "was trained with {:?}, not the requested {model_config:?}",
                model.config()
            )));
        }
        if model.template().triangles() != template.triangles() {
            return Err(bad("its template has different faces".into()));
        }
        let state: TrainingState = metadata
            .get("training")
            .ok_or_else(|| bad("no `training` metadata: not a training checkpoint".into()))
            .and_then(|s| {
                serde_json::from_str(s).map_err(|e| bad(format!("bad `training`: {e}")))
            })?;
        return Ok((model, state, optimizer));
    }
    let normalization = VertexNormalization::fit(train, device)?;
    let model =
        SpiralMorphableModel::new(template, model_config, normalization, config.seed, device)?;
    Ok((
        model,
        TrainingState {
            epochs_completed: 0,
            step: 0,
            seed: config.seed,
        },
        HashMap::new(),
    ))
}

/// Seed of the shuffle of `epoch` (SplitMix64 of the pair), so resuming reproduces it.
fn epoch_seed(seed: u64, epoch: usize) -> u64 {
    let mut z = seed
        ^ (epoch as u64)
            .wrapping_add(1)
            .wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Mean per-vertex Euclidean error (data units) of reconstructing normalised `data: (S, V, 3)`.
fn validation_error(model: &SpiralMorphableModel, data: &Tensor, batch: usize) -> Result<f64> {
    let count = data.dim(0)?;
    let mut sum = 0.0f64;
    let mut start = 0;
    while start < count {
        let len = batch.min(count - start);
        let x = data.narrow(0, start, len)?.detach();
        let predicted = model.network().forward(&x)?.detach();
        let error = model.normalization().euclidean_error(&predicted, &x)?;
        sum += len as f64 * f64::from(error.to_scalar::<f32>()?);
        start += len;
    }
    Ok(sum / count.max(1) as f64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spiral::test_fixtures::{deformed_shapes, tiny_config};

    fn weights(model: &SpiralMorphableModel) -> Vec<(String, Vec<f32>)> {
        let data = model.vars().data().lock().unwrap();
        let mut out: Vec<(String, Vec<f32>)> = data
            .iter()
            .map(|(k, v)| {
                (
                    k.clone(),
                    v.as_tensor().flatten_all().unwrap().to_vec1().unwrap(),
                )
            })
            .collect();
        out.sort_by(|a, b| a.0.cmp(&b.0));
        out
    }

    #[test]
    fn overfits_four_shapes() {
        let sphere = meshgnn_geometry::icosphere(2);
        let shapes = deformed_shapes(&sphere, 4);
        let config = TrainConfig {
            epochs: 300,
            batch_size: 4,
            learning_rate: 3e-3,
            lr_decay: 0.995,
            ..Default::default()
        };
        let mut steps = 0;
        let out = train_spiral_model(
            &sphere,
            &tiny_config(8),
            &shapes,
            &shapes,
            &config,
            &Device::Cpu,
            &mut |p| {
                steps += usize::from(!p.epoch_end);
            },
        )
        .unwrap();
        assert_eq!(steps, 300);
        let (first, last) = (out.history[0], out.history[299]);
        // Spread of the set: mean distance of a vertex from its mean position (mm).
        let n = shapes.len() as f64;
        let spread = (0..sphere.vertex_count())
            .map(|v| {
                let mean: Vec<f64> = (0..3)
                    .map(|c| shapes.iter().map(|s| f64::from(s[v][c])).sum::<f64>() / n)
                    .collect();
                shapes
                    .iter()
                    .map(|s| {
                        (0..3)
                            .map(|c| (f64::from(s[v][c]) - mean[c]).powi(2))
                            .sum::<f64>()
                            .sqrt()
                    })
                    .sum::<f64>()
                    / n
            })
            .sum::<f64>()
            / sphere.vertex_count() as f64;
        assert!(spread > 0.5, "{spread}");
        assert!(first.val_mm.unwrap() > 0.3 * spread, "{first:?}");
        assert!(
            last.val_mm.unwrap() < 0.02 * spread,
            "{last:?} vs spread {spread}"
        );
        assert!(last.train_l1 < 0.1 * first.train_l1, "{first:?} {last:?}");
    }

    #[test]
    fn deterministic_checkpointed_and_resumable() {
        let sphere = meshgnn_geometry::icosphere(2);
        let shapes = deformed_shapes(&sphere, 6);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("ckpt.safetensors");
        let base = TrainConfig {
            epochs: 2,
            batch_size: 4,
            seed: 5,
            ..Default::default()
        };
        let run = |config: &TrainConfig| {
            train_spiral_model(
                &sphere,
                &tiny_config(8),
                &shapes,
                &[],
                config,
                &Device::Cpu,
                &mut |_| {},
            )
            .unwrap()
        };
        let a = run(&base);
        let b = run(&TrainConfig {
            checkpoint: Some(path.clone()),
            ..base.clone()
        });
        assert_eq!(
            weights(&a.model),
            weights(&b.model),
            "same seed, same weights"
        );
        assert_eq!(a.history[1].step, 4);
        assert!(a.history[1].val_mm.is_none());
        // The checkpoint holds the final weights and the training state.
        let (saved, metadata) =
            SpiralMorphableModel::load_with_metadata(&path, &Device::Cpu).unwrap();
        assert_eq!(weights(&saved), weights(&b.model));
        let state: TrainingState = serde_json::from_str(&metadata["training"]).unwrap();
        assert_eq!(
            state,
            TrainingState {
                epochs_completed: 2,
                step: 4,
                seed: 5
            }
        );
        // Resuming runs only the remaining epochs, from the checkpoint.
        let resumed = run(&TrainConfig {
            epochs: 3,
            checkpoint: Some(path.clone()),
            resume: true,
            ..base.clone()
        });
        assert_eq!(resumed.history.len(), 1);
        assert_eq!((resumed.history[0].epoch, resumed.history[0].step), (2, 6));
        // ... and ends bit-identical with an uninterrupted three-epoch run (Adam's moments and
        // step count come back from the checkpoint).
        let straight = run(&TrainConfig {
            epochs: 3,
            ..base.clone()
        });
        assert_eq!(weights(&resumed.model), weights(&straight.model));
        assert_eq!(resumed.history[0], straight.history[2]);
        // The checkpoint still loads as a plain model, and a checkpoint without optimiser
        // tensors (written before they were stored) still resumes, not bit-exactly.
        let (plain, _) = SpiralMorphableModel::load_with_metadata(&path, &Device::Cpu).unwrap();
        assert_eq!(weights(&plain), weights(&resumed.model));
        let old = dir.path().join("old.safetensors");
        let state = serde_json::to_string(&TrainingState {
            epochs_completed: 2,
            step: 4,
            seed: 5,
        })
        .unwrap();
        saved
            .save_with_metadata(&old, &[("training", state)])
            .unwrap();
        let from_old = run(&TrainConfig {
            epochs: 3,
            checkpoint: Some(old),
            resume: true,
            ..base.clone()
        });
        assert_eq!(from_old.history[0].step, 6);
        assert_ne!(weights(&from_old.model), weights(&straight.model));
        // A different architecture cannot resume from it.
        let other = train_spiral_model(
            &sphere,
            &tiny_config(30),
            &shapes,
            &[],
            &TrainConfig {
                epochs: 3,
                checkpoint: Some(path),
                resume: true,
                ..base
            },
            &Device::Cpu,
            &mut |_| {},
        );
        assert!(other.is_err());
    }

    #[test]
    fn same_weights_for_any_thread_count() {
        let sphere = meshgnn_geometry::icosphere(2);
        let shapes = deformed_shapes(&sphere, 6);
        let config = TrainConfig {
            epochs: 2,
            batch_size: 4,
            ..Default::default()
        };
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let out = train_spiral_model(
                    &sphere,
                    &tiny_config(8),
                    &shapes,
                    &shapes,
                    &config,
                    &Device::Cpu,
                    &mut |_| {},
                )
                .unwrap();
                (weights(&out.model), out.history[1].val_mm)
            })
        };
        assert_eq!(run(1), run(3));
    }

    #[test]
    fn rejects_bad_data() {
        let sphere = meshgnn_geometry::icosphere(2);
        let mut shapes = deformed_shapes(&sphere, 2);
        let config = TrainConfig {
            epochs: 1,
            ..Default::default()
        };
        let run = |train: &[Vec<[f32; 3]>], cfg: &TrainConfig| {
            train_spiral_model(
                &sphere,
                &tiny_config(8),
                train,
                &[],
                cfg,
                &Device::Cpu,
                &mut |_| {},
            )
        };
        assert!(run(&[], &config).is_err());
        assert!(
            run(
                &shapes,
                &TrainConfig {
                    batch_size: 0,
                    ..config.clone()
                }
            )
            .is_err()
        );
        shapes[1][7][2] = f32::INFINITY;
        let err = run(&shapes, &config).unwrap_err().to_string();
        assert!(err.contains("mesh 1") && err.contains("vertex 7"), "{err}");
        shapes[1].pop();
        assert!(run(&shapes, &config).is_err());
    }
}
