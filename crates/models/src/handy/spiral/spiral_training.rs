//! What Handy++ trains (thesis ch. 3.3.4: "trained using L1 loss on the reconstructed hand
//! meshes"; Adam as Neural3DMM, Bouritsas et al. ICCV 2019): per-vertex normalisation fitted
//! on the training split, L1 on normalised coordinates
//! (`meshgnn_losses::losses::reconstruction_l1`, eq. 4.2), validation as the mean per-vertex
//! Euclidean error in data units. A model with the PCA path (`linear_skip`) trains on the L1
//! error in data units instead: normalised coordinates weigh the vertices that vary least
//! the most, so their L1 pulls a model that starts at the PCA (optimal in data units) away
//! from it — measured: 2.17 → 2.44 mm on its own training hands in 16 epochs. The loop itself (seeded batches, Adam with the per-epoch
//! decay, checkpoints, resuming) is [`crate::training::train`].

use std::path::Path;

use candle_core::{Device, Tensor, Var};
use meshgnn_geometry::TriMesh;
use meshgnn_losses::losses::reconstruction_l1;

use crate::adam::sorted_vars;
use crate::handy::spiral::vertex_normalization::check_meshes;
use crate::handy::spiral::{
    LinearSkip, SPIRAL_MODEL_NAME, SpiralAutoencoderConfig, SpiralMorphableModel,
    VertexNormalization, mesh_batch,
};
use crate::training::{BatchLoss, StepContext, Trainable};
use crate::{Checkpoint, MorphableModel, Pca, Result};

/// Meshes per forward pass of the validation.
const VALIDATION_BATCH: usize = 32;

/// A spiral morphable model with its normalised training and validation meshes.
pub struct SpiralTraining {
    model: SpiralMorphableModel,
    template: TriMesh,
    train: Vec<Vec<[f32; 3]>>,
    validation: Vec<Vec<[f32; 3]>>,
    train_data: Tensor,
    validation_data: Option<Tensor>,
    device: Device,
}

impl SpiralTraining {
    /// A fresh model (weights from `seed`, normalisation — and with `linear_skip` the PCA
    /// path — fitted on `train`) of the registered
    /// meshes `train: #S × (#V×3)` on `template`'s faces, validated on `validation` (may be
    /// empty). Errors when the meshes disagree with the template or a coordinate is not finite.
    ///
    /// ```
    /// use candle_core::Device;
    /// use meshgnn_models::spiral::{SpiralAutoencoderConfig, SpiralTraining};
    /// use meshgnn_models::training::{TrainingConfig, train};
    /// let sphere = meshgnn_geometry::icosphere(2);
    /// let shapes: Vec<Vec<[f32; 3]>> = (0..4)
    ///     .map(|s| sphere.vertices().iter().map(|p| [p[0] * (1.0 + 0.1 * s as f32), p[1], p[2]]).collect())
    ///     .collect();
    /// let cfg = SpiralAutoencoderConfig { channels: vec![8, 16], factors: vec![4.0; 2],
    ///     spiral_lengths: vec![9; 3], dilations: vec![1; 3], ..Default::default() };
    /// let mut task = SpiralTraining::new(&sphere, &cfg, &shapes, &shapes, 0, &Device::Cpu)?;
    /// let config = TrainingConfig { epochs: 2, batch_size: 2, ..Default::default() };
    /// let run = train(&mut task, &config, &mut |_| {})?;
    /// assert_eq!(run.history.len(), 2);
    /// assert!(run.history[1].validation.is_some());
    /// # Ok::<(), meshgnn_models::Error>(())
    /// ```
    pub fn new(
        template: &TriMesh,
        config: &SpiralAutoencoderConfig,
        train: &[Vec<[f32; 3]>],
        validation: &[Vec<[f32; 3]>],
        seed: u64,
        device: &Device,
    ) -> Result<Self> {
        let v = template.vertex_count();
        check_meshes("training meshes", train, Some(v))?;
        if !validation.is_empty() {
            check_meshes("validation meshes", validation, Some(v))?;
        }
        let normalization = VertexNormalization::fit(train, device)?;
        let skip = match config.linear_skip {
            true => Some(LinearSkip::from_pca(
                &Pca::fit(template, train, config.latent_size)?,
                &normalization,
            )?),
            false => None,
        };
        let model = SpiralMorphableModel::new(template, config, normalization, skip, seed, device)?;
        let mut task = Self {
            train_data: Tensor::zeros(1, candle_core::DType::F32, device)?,
            validation_data: None,
            model,
            template: template.clone(),
            train: train.to_vec(),
            validation: validation.to_vec(),
            device: device.clone(),
        };
        task.normalize_data()?;
        Ok(task)
    }

    /// The model being trained.
    pub fn model(&self) -> &SpiralMorphableModel {
        &self.model
    }

    /// The trained model.
    pub fn into_model(self) -> SpiralMorphableModel {
        self.model
    }

    /// The data normalised with the model's normalisation.
    fn normalize_data(&mut self) -> Result<()> {
        let normalization = self.model.normalization();
        self.train_data = normalization.normalize(&mesh_batch(&self.train, &self.device)?)?;
        self.validation_data = if self.validation.is_empty() {
            None
        } else {
            Some(normalization.normalize(&mesh_batch(&self.validation, &self.device)?)?)
        };
        Ok(())
    }
}

impl Trainable for SpiralTraining {
    fn model_name(&self) -> &'static str {
        SPIRAL_MODEL_NAME
    }

    fn train_len(&self) -> usize {
        self.train.len()
    }

    fn parameters(&self) -> Vec<(String, Var)> {
        sorted_vars(self.model.vars())
    }

    fn batch_loss(&self, batch: &[usize], _: &StepContext) -> Result<BatchLoss> {
        let ids: Vec<u32> = batch.iter().map(|&i| i as u32).collect();
        let ids = Tensor::from_vec(ids, batch.len(), &self.device)?;
        let x = self.train_data.index_select(&ids, 0)?;
        let predicted = self.model.network().forward(&x)?;
        let mm = self
            .model
            .normalization()
            .euclidean_error(&predicted.detach(), &x)?;
        let loss = if self.model.config().linear_skip {
            // in data units, where the PCA path is optimal (see the module docs)
            let std = self.model.normalization().std();
            reconstruction_l1(&predicted.broadcast_mul(std)?, &x.broadcast_mul(std)?)?
        } else {
            reconstruction_l1(&predicted, &x)?
        };
        Ok(BatchLoss {
            loss,
            figure: Some(f64::from(mm.to_scalar::<f32>()?)),
        })
    }

    /// Mean per-vertex Euclidean error (data units) of reconstructing the validation meshes.
    fn validation(&self) -> Result<Option<f64>> {
        let Some(data) = &self.validation_data else {
            return Ok(None);
        };
        let count = data.dim(0)?;
        let mut sum = 0.0f64;
        let mut start = 0;
        while start < count {
            let len = VALIDATION_BATCH.min(count - start);
            let x = data.narrow(0, start, len)?.detach();
            let predicted = self.model.network().forward(&x)?.detach();
            let error = self.model.normalization().euclidean_error(&predicted, &x)?;
            sum += len as f64 * f64::from(error.to_scalar::<f32>()?);
            start += len;
        }
        Ok(Some(sum / count.max(1) as f64))
    }

    fn checkpoint(&self) -> Result<Checkpoint> {
        self.model.to_checkpoint()
    }

    /// The checkpoint's model, normalisation included; it must have this config and template
    /// faces.
    fn restore(&mut self, checkpoint: &Checkpoint, source: &Path) -> Result<()> {
        let model = SpiralMorphableModel::from_checkpoint(checkpoint, source, &self.device)?;
        crate::checkpoint::check_resumable(
            source,
            (model.config(), model.template().triangles()),
            (self.model.config(), self.template.triangles()),
        )?;
        self.model = model;
        self.normalize_data()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::handy::spiral::test_fixtures::{deformed_shapes, tiny_config};
    use crate::training::{TrainingConfig, TrainingRun, train};

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

    /// Trains a `tiny_config(latent)` model of `shapes` on the unit icosphere.
    fn run_with(
        latent: usize,
        shapes: &[Vec<[f32; 3]>],
        validation: &[Vec<[f32; 3]>],
        config: &TrainingConfig,
        progress: &mut dyn FnMut(&crate::training::TrainingProgress),
    ) -> Result<(SpiralMorphableModel, TrainingRun)> {
        let sphere = meshgnn_geometry::icosphere(2);
        let mut task = SpiralTraining::new(
            &sphere,
            &tiny_config(latent),
            shapes,
            validation,
            config.seed,
            &Device::Cpu,
        )?;
        let run = train(&mut task, config, progress)?;
        Ok((task.into_model(), run))
    }

    #[test]
    fn overfits_four_shapes() {
        let sphere = meshgnn_geometry::icosphere(2);
        let shapes = deformed_shapes(&sphere, 4);
        let config = TrainingConfig {
            epochs: 300,
            batch_size: 4,
            learning_rate: 3e-3,
            lr_decay: 0.995,
            ..Default::default()
        };
        let mut steps = 0;
        let (_, out) = run_with(8, &shapes, &shapes, &config, &mut |p| {
            steps += usize::from(!p.epoch_end);
        })
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
        assert!(first.validation.unwrap() > 0.3 * spread, "{first:?}");
        assert!(
            last.validation.unwrap() < 0.02 * spread,
            "{last:?} vs spread {spread}"
        );
        assert!(last.loss < 0.1 * first.loss, "{first:?} {last:?}");
    }

    #[test]
    fn with_the_linear_skip_a_fresh_model_is_the_pca_and_training_beats_it() {
        // a finger-like bend: the upper half rotates about the x axis by 0-90 degrees, an arc
        // that one linear component cannot follow
        let sphere = meshgnn_geometry::icosphere(2);
        let shapes: Vec<Vec<[f32; 3]>> = (0..12)
            .map(|i| {
                let angle = 1.5 * i as f32 / 11.0;
                sphere
                    .vertices()
                    .iter()
                    .map(|p| {
                        let (s, c) = (angle * p[1].max(0.0)).sin_cos();
                        [
                            10.0 * p[0],
                            10.0 * (c * p[1] - s * p[2]),
                            10.0 * (s * p[1] + c * p[2]),
                        ]
                    })
                    .collect()
            })
            .collect();
        let config = SpiralAutoencoderConfig {
            linear_skip: true,
            ..tiny_config(1)
        };
        let mut task =
            SpiralTraining::new(&sphere, &config, &shapes, &shapes, 2, &Device::Cpu).unwrap();
        let pca = Pca::fit(&sphere, &shapes, 1).unwrap();
        let pca_error = crate::generalisation_error(&pca, &shapes).unwrap().mean;
        let start = task.validation().unwrap().unwrap();
        assert!(
            (start - pca_error).abs() < 1e-4 * pca_error.max(1.0),
            "fresh {start} mm, PCA {pca_error} mm"
        );
        let config = TrainingConfig {
            epochs: 150,
            batch_size: 4,
            learning_rate: 3e-3,
            ..Default::default()
        };
        train(&mut task, &config, &mut |_| {}).unwrap();
        let end = task.validation().unwrap().unwrap();
        assert!(
            end < 0.8 * pca_error,
            "trained {end} mm, PCA {pca_error} mm"
        );
        // the skip travels with the model file
        let bytes = task.model().to_bytes().unwrap();
        let back = SpiralMorphableModel::from_bytes(&bytes, &Device::Cpu).unwrap();
        assert!(back.network().linear_skip().is_some());
        let x = mesh_batch(&shapes, &Device::Cpu).unwrap();
        let values = |t: Tensor| t.flatten_all().unwrap().to_vec1::<f32>().unwrap();
        assert_eq!(
            values(back.reconstruct(&x).unwrap()),
            values(task.model().reconstruct(&x).unwrap())
        );
    }

    #[test]
    fn deterministic_checkpointed_and_resumable() {
        let sphere = meshgnn_geometry::icosphere(2);
        let shapes = deformed_shapes(&sphere, 6);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("ckpt.safetensors");
        let base = TrainingConfig {
            epochs: 2,
            batch_size: 4,
            seed: 5,
            ..Default::default()
        };
        let run = |config: &TrainingConfig| run_with(8, &shapes, &[], config, &mut |_| {}).unwrap();
        let a = run(&base);
        let b = run(&TrainingConfig {
            checkpoint: Some(path.clone()),
            ..base.clone()
        });
        assert_eq!(weights(&a.0), weights(&b.0), "same seed, same weights");
        assert_eq!(a.1.history[1].step, 4);
        assert!(a.1.history[1].validation.is_none());
        // The checkpoint holds the final weights and the training state.
        let saved = SpiralMorphableModel::load(&path, &Device::Cpu).unwrap();
        assert_eq!(weights(&saved), weights(&b.0));
        let state = Checkpoint::load(&path).unwrap().header.training.unwrap();
        assert_eq!((state.epochs_completed, state.step, state.seed), (2, 4, 5));
        // Resuming runs only the remaining epochs, from the checkpoint.
        let resumed = run(&TrainingConfig {
            epochs: 3,
            checkpoint: Some(path.clone()),
            resume: true,
            ..base.clone()
        });
        assert_eq!(resumed.1.history.len(), 1);
        assert_eq!(
            (resumed.1.history[0].epoch, resumed.1.history[0].step),
            (2, 6)
        );
        // ... and ends bit-identical with an uninterrupted three-epoch run (Adam's moments and
        // step count come back from the checkpoint).
        let straight = run(&TrainingConfig {
            epochs: 3,
            ..base.clone()
        });
        assert_eq!(weights(&resumed.0), weights(&straight.0));
        assert_eq!(resumed.1.history[0], straight.1.history[2]);
        // The checkpoint still loads as a plain model, and a checkpoint without optimiser
        // tensors (written before they were stored) still resumes, not bit-exactly.
        let plain = SpiralMorphableModel::load(&path, &Device::Cpu).unwrap();
        assert_eq!(weights(&plain), weights(&resumed.0));
        let old = dir.path().join("old.safetensors");
        let mut without_moments = saved.to_checkpoint().unwrap();
        without_moments.header.training = Some(crate::TrainingState {
            epochs_completed: 2,
            step: 4,
            seed: 5,
            ..Default::default()
        });
        without_moments.save(&old).unwrap();
        let from_old = run(&TrainingConfig {
            epochs: 3,
            checkpoint: Some(old),
            resume: true,
            ..base.clone()
        });
        assert_eq!(from_old.1.history[0].step, 6);
        assert_ne!(weights(&from_old.0), weights(&straight.0));
        // A different architecture cannot resume from it.
        let other = run_with(
            30,
            &shapes,
            &[],
            &TrainingConfig {
                epochs: 3,
                checkpoint: Some(path),
                resume: true,
                ..base
            },
            &mut |_| {},
        );
        assert!(other.is_err());
    }

    #[test]
    fn same_weights_for_any_thread_count() {
        let sphere = meshgnn_geometry::icosphere(2);
        let shapes = deformed_shapes(&sphere, 6);
        let config = TrainingConfig {
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
                let (model, out) = run_with(8, &shapes, &shapes, &config, &mut |_| {}).unwrap();
                (weights(&model), out.history[1].validation)
            })
        };
        assert_eq!(run(1), run(3));
    }

    #[test]
    fn rejects_bad_data() {
        let sphere = meshgnn_geometry::icosphere(2);
        let mut shapes = deformed_shapes(&sphere, 2);
        let config = TrainingConfig {
            epochs: 1,
            ..Default::default()
        };
        let run = |train: &[Vec<[f32; 3]>], cfg: &TrainingConfig| {
            run_with(8, train, &[], cfg, &mut |_| {})
        };
        assert!(run(&[], &config).is_err());
        assert!(
            run(
                &shapes,
                &TrainingConfig {
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
