//! Training the point simplifier (thesis ch. 5.6): Adam, learning rate 1e-3 multiplied by 0.99
//! after every epoch, loss eq. 5.9, one cloud per step with a target ratio drawn uniformly from
//! `[0.05, 0.5]` so one model serves any ratio. Deterministic from one seed: weight
//! initialisation, epoch order, ratios and FPS starts; checkpoints hold the Adam moments, so a
//! resumed run continues exactly where it stopped.
//!
//! # Conventions
//! - Initialisation: every linear weight and bias `U(−1/√fan_in, 1/√fan_in)` (PyTorch's
//!   default), batch-norm scale 1, shift 0; drawn from `StdRng::seed_from_u64(seed)` in name
//!   order.
//! - Adam ([`crate::Adam`]): β = (0.9, 0.999), ε = 1e-8, no weight decay; batch-norm running statistics are
//!   state, not parameters.
//! - Step `s` draws its ratio and FPS seed from `StdRng::seed_from_u64(seed ^ s·0xD1B5_4A32_D192_ED03)`;
//!   epoch `e` shuffles the clouds with `StdRng::seed_from_u64(seed + e)`.

use std::path::Path;

use candle_core::{DType, Device, Tensor};
use candle_nn::{VarBuilder, VarMap};
use meshgnn_geometry::{curvature_features, unit_sphere_normalization};
use meshgnn_graph::knn_graph;
use meshgnn_losses::losses::{adaptive_chamfer_weights, mean_curvature};
use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng, rngs::StdRng};

use super::checkpoint::OPTIMIZER_PREFIX;
use super::{
    CheckpointState, LatentSamplingOptions, NeighbourIndex, PointSimplifier, PointSimplifierConfig,
    read_checkpoint, simplifier_loss, write_checkpoint,
};
use crate::adam::sorted_vars;
use crate::{Adam, AdamConfig, Error, Result};

/// Target ratios of [`Trainer::validation_loss`]: those of the benchmark (thesis Table 5.1).
pub const VALIDATION_RATIOS: [f64; 3] = [0.2, 0.1, 0.05];

/// Training hyper-parameters; defaults follow ch. 5.6 except the epoch count (the thesis trains
/// 150 epochs on its datasets; our default run is sized for a 2-core machine).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrainingConfig {
    /// Passes over the training clouds.
    pub epochs: usize,
    /// Initial Adam learning rate (1e-3).
    pub learning_rate: f64,
    /// Factor applied to the learning rate after every epoch (0.99).
    pub lr_decay: f64,
    /// Smallest target ratio drawn per step (0.05).
    pub min_ratio: f64,
    /// Largest target ratio drawn per step (0.5).
    pub max_ratio: f64,
    /// λ of eq. 5.9 (0.1).
    pub curvature_weight: f64,
    /// Temperature τ of the adaptive Chamfer weights (10).
    pub tau: f32,
    /// Neighbours of the curvature estimate eq. 5.1-5.3 (16, as the evaluation).
    pub curvature_neighbours: usize,
    /// Seed of every random choice.
    pub seed: u64,
}

impl Default for TrainingConfig {
    fn default() -> Self {
        Self {
            epochs: 150,
            learning_rate: 1e-3,
            lr_decay: 0.99,
            min_ratio: 0.05,
            max_ratio: 0.5,
            curvature_weight: 0.1,
            tau: 10.0,
            curvature_neighbours: 16,
            seed: 0,
        }
    }
}

/// One training cloud with everything the loss needs, precomputed once.
#[derive(Clone, Debug)]
pub struct TrainingSample {
    /// Points in the unit-sphere frame, `#N×3`.
    pub points: Vec<[f32; 3]>,
    /// The projector's k-NN graph.
    pub graph: NeighbourIndex,
    /// `points` as a tensor `(N, 3)`.
    pub positions: Tensor,
    /// Mean curvature K̄ (eq. 5.3), `(N)`.
    pub curvature: Tensor,
    /// Adaptive Chamfer weights (eq. 5.7), `(N)`.
    pub weights: Tensor,
}

/// Prepares `points: #N×3` (any units; normalised to the unit sphere here) for training:
/// curvature features, adaptive weights, k-NN graph. Needs at least 3 points.
///
/// ```
/// use meshgnn_geometry::icosphere;
/// use meshgnn_models::point_simplifier::{PointSimplifierConfig, TrainingConfig, prepare_training_sample};
/// let pts = icosphere(2).vertices().to_vec();
/// let s = prepare_training_sample(&pts, &PointSimplifierConfig::default(), &TrainingConfig::default())?;
/// assert_eq!(s.points.len(), 162);
/// # Ok::<(), meshgnn_models::Error>(())
/// ```
pub fn prepare_training_sample(
    points: &[[f32; 3]],
    model: &PointSimplifierConfig,
    training: &TrainingConfig,
) -> Result<TrainingSample> {
    let n = points.len();
    if n < 3 {
        return Err(Error::Invalid {
            what: "training cloud".into(),
            reason: format!("needs at least 3 points, has {n}"),
        });
    }
    let unit = unit_sphere_normalization(points)?.apply(points);
    let features = curvature_features(&unit, training.curvature_neighbours.clamp(2, n - 1))?;
    let weights = adaptive_chamfer_weights(&features.mean_curvature, training.tau)?;
    let device = Device::Cpu;
    let graph =
        NeighbourIndex::from_knn(&knn_graph(&unit, model.gnn_neighbours.min(n - 1))?, &device)?;
    Ok(TrainingSample {
        positions: Tensor::from_slice(unit.as_flattened(), (n, 3), &device)?,
        curvature: Tensor::from_slice(&features.mean_curvature, n, &device)?,
        weights: Tensor::from_vec(weights, n, &device)?,
        points: unit,
        graph,
    })
}

/// What the progress callback sees after every step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrainingProgress {
    /// Current epoch (0-based).
    pub epoch: usize,
    /// Steps done in this epoch.
    pub step_in_epoch: usize,
    /// Steps per epoch (clouds).
    pub steps_per_epoch: usize,
    /// Loss of this step.
    pub loss: f64,
    /// Learning rate of this epoch.
    pub learning_rate: f64,
}

/// The model, its parameters and Adam state, and where training stands.
pub struct Trainer {
    model_config: PointSimplifierConfig,
    config: TrainingConfig,
    varmap: VarMap,
    model: PointSimplifier,
    optimizer: Adam,
    epoch: usize,
    step: u64,
    last_loss: f64,
    best_validation: Option<f64>,
}

impl Trainer {
    /// A fresh model initialised from `config.seed` (module docs).
    pub fn new(model_config: &PointSimplifierConfig, config: &TrainingConfig) -> Result<Self> {
        check_config(config)?;
        let varmap = VarMap::new();
        let vb = VarBuilder::from_varmap(&varmap, DType::F32, &Device::Cpu);
        let model = PointSimplifier::new(vb, model_config)?;
        let mut rng = StdRng::seed_from_u64(config.seed);
        let all = sorted_vars(&varmap);
        let fan_in = |name: &str| -> Option<usize> {
            let stem = name
                .strip_suffix(".bias")
                .or(name.strip_suffix(".weight"))?;
            let w = all.iter().find(|(n, _)| n == &format!("{stem}.weight"))?;
            match w.1.dims() {
                [_, i] => Some(*i),
                _ => None,
            }
        };
        for (name, var) in &all {
            if let Some(fi) = fan_in(name) {
                let b = 1.0 / (fi as f64).sqrt();
                let values: Vec<f32> = (0..var.elem_count())
                    .map(|_| rng.random_range(-b..b) as f32)
                    .collect();
                var.set(&Tensor::from_vec(values, var.dims(), &Device::Cpu)?)?;
            }
        }
        let start = CheckpointState {
            seed: config.seed,
            loss: f64::NAN,
            ..Default::default()
        };
        Self::assemble(*model_config, *config, varmap, model, start, None)
    }

    /// Continues the run saved by [`Trainer::save`] at `path`, with `config` (its `epochs` may
    /// extend the run; the seed is the checkpoint's).
    pub fn resume(path: &Path, config: &TrainingConfig) -> Result<Self> {
        let bytes = std::fs::read(path).map_err(|e| Error::Checkpoint {
            path: path.to_path_buf(),
            reason: format!("cannot read: {e}"),
        })?;
        let ckpt = read_checkpoint(&bytes, path)?;
        let state = ckpt.state.ok_or_else(|| Error::Checkpoint {
            path: path.to_path_buf(),
            reason: "holds weights only, no training state to resume".into(),
        })?;
        let config = TrainingConfig {
            seed: state.seed,
            ..*config
        };
        check_config(&config)?;
        let varmap = VarMap::new();
        let vb = VarBuilder::from_varmap(&varmap, DType::F32, &Device::Cpu);
        let model = PointSimplifier::new(vb, &ckpt.config)?;
        for (name, var) in sorted_vars(&varmap) {
            let t = ckpt.tensors.get(&name).ok_or_else(|| Error::Checkpoint {
                path: path.to_path_buf(),
                reason: format!("tensor {name:?} is missing"),
            })?;
            var.set(t)?;
        }
        Self::assemble(
            ckpt.config,
            config,
            varmap,
            model,
            state,
            Some(&ckpt.tensors),
        )
    }

    fn assemble(
        model_config: PointSimplifierConfig,
        config: TrainingConfig,
        varmap: VarMap,
        model: PointSimplifier,
        state: CheckpointState,
        moments: Option<&std::collections::HashMap<String, Tensor>>,
    ) -> Result<Self> {
        let params = sorted_vars(&varmap)
            .into_iter()
            .filter(|(n, _)| !n.contains("running_"))
            .collect();
        let mut optimizer = Adam::new(
            params,
            AdamConfig {
                learning_rate: config.learning_rate,
                ..Default::default()
            },
        )?;
        if let Some(tensors) = moments {
            optimizer.restore(tensors, OPTIMIZER_PREFIX, state.step)?;
        }
        Ok(Self {
            model_config,
            config,
            varmap,
            model,
            optimizer,
            epoch: state.epoch,
            step: state.step,
            last_loss: state.loss,
            best_validation: state.best_validation,
        })
    }

    /// The model being trained (shares its parameters).
    pub fn model(&self) -> &PointSimplifier {
        &self.model
    }

    /// Epochs completed.
    pub fn epoch(&self) -> usize {
        self.epoch
    }

    /// Optimiser steps taken.
    pub fn steps(&self) -> u64 {
        self.step
    }

    /// Learning rate of the current epoch: `learning_rate · lr_decay^epoch`.
    pub fn learning_rate(&self) -> f64 {
        self.config.learning_rate * self.config.lr_decay.powi(self.epoch as i32)
    }

    /// Eq. 5.9 on `sample` keeping `target` points with FPS seed `seed` (batch statistics when
    /// `train`), as a 0-d tensor attached to the parameters.
    pub fn loss(
        &self,
        sample: &TrainingSample,
        target: usize,
        seed: u64,
        train: bool,
    ) -> Result<Tensor> {
        let exact = LatentSamplingOptions {
            cell_size: sample.points.len().max(1),
        };
        let out = self
            .model
            .forward(&sample.points, &sample.graph, target, exact, seed, train)?;
        let k2 = simplified_curvature(
            sample,
            &out.points,
            &out.indices,
            self.config.curvature_neighbours,
        )?;
        Ok(simplifier_loss(
            &sample.positions,
            &sample.weights,
            &sample.curvature,
            &out.points,
            &k2,
            self.config.curvature_weight,
        )?
        .total)
    }

    /// One Adam step on `sample` with this step's random ratio; returns the loss.
    pub fn train_step(&mut self, sample: &TrainingSample) -> Result<f64> {
        let mut rng =
            StdRng::seed_from_u64(self.config.seed ^ self.step.wrapping_mul(0xD1B5_4A32_D192_ED03));
        let ratio = rng.random_range(self.config.min_ratio..=self.config.max_ratio);
        let n = sample.points.len();
        let target = ((ratio * n as f64).round() as usize).clamp(1, n);
        let fps_seed: u64 = rng.random();
        self.train_step_with(sample, target, fps_seed)
    }

    /// One Adam step on `sample` keeping `target` points with FPS seed `seed`; returns the loss.
    pub fn train_step_with(
        &mut self,
        sample: &TrainingSample,
        target: usize,
        seed: u64,
    ) -> Result<f64> {
        let loss = self.loss(sample, target, seed, true)?;
        let value = f64::from(loss.to_dtype(DType::F32)?.to_scalar::<f32>()?);
        if !value.is_finite() {
            return Err(Error::Invalid {
                what: format!("loss at step {}", self.step),
                reason: format!("is {value}; lower the learning rate"),
            });
        }
        self.optimizer.set_learning_rate(self.learning_rate());
        self.optimizer.backward_step(&loss)?;
        self.step += 1;
        Ok(value)
    }

    /// Eq. 5.9 in evaluation mode (batch-norm running statistics) averaged over `samples` and
    /// the benchmark's ratios [`VALIDATION_RATIOS`], each with a fixed FPS start: a
    /// deterministic score of the current weights on held-out clouds, for keeping the best
    /// epoch (the per-step training loss mixes random ratios and is too noisy for that).
    pub fn validation_loss(&self, samples: &[TrainingSample]) -> Result<f64> {
        if samples.is_empty() {
            return Err(Error::Invalid {
                what: "validation samples".into(),
                reason: "none given".into(),
            });
        }
        let mut total = 0.0;
        for (i, sample) in samples.iter().enumerate() {
            let n = sample.points.len();
            for ratio in VALIDATION_RATIOS {
                let target = ((ratio * n as f64).round() as usize).clamp(1, n);
                let loss = self.loss(sample, target, i as u64, false)?;
                total += f64::from(loss.to_dtype(DType::F32)?.to_scalar::<f32>()?);
            }
        }
        Ok(total / (samples.len() * VALIDATION_RATIOS.len()) as f64)
    }

    /// Records a validation loss of the current weights; true when it is the lowest so far (the
    /// caller then keeps these weights). Carried in checkpoints, so a resumed run keeps its best.
    pub fn record_validation(&mut self, loss: f64) -> bool {
        let improved = loss.is_finite() && self.best_validation.is_none_or(|best| loss < best);
        if improved {
            self.best_validation = Some(loss);
        }
        improved
    }

    /// The lowest validation loss recorded so far.
    pub fn best_validation(&self) -> Option<f64> {
        self.best_validation
    }

    /// One pass over `samples` in this epoch's shuffled order, calling `progress` after every
    /// step; returns the epoch's mean loss and advances the epoch (and the learning rate).
    pub fn train_epoch(
        &mut self,
        samples: &[TrainingSample],
        progress: &mut dyn FnMut(&TrainingProgress),
    ) -> Result<f64> {
        if samples.is_empty() {
            return Err(Error::Invalid {
                what: "training samples".into(),
                reason: "none given".into(),
            });
        }
        let mut order: Vec<usize> = (0..samples.len()).collect();
        order.shuffle(&mut StdRng::seed_from_u64(
            self.config.seed.wrapping_add(self.epoch as u64),
        ));
        let mut total = 0.0;
        for (i, &s) in order.iter().enumerate() {
            let Some(sample) = samples.get(s) else {
                continue;
            };
            let loss = self.train_step(sample)?;
            total += loss;
            progress(&TrainingProgress {
                epoch: self.epoch,
                step_in_epoch: i + 1,
                steps_per_epoch: samples.len(),
                loss,
                learning_rate: self.learning_rate(),
            });
        }
        self.epoch += 1;
        self.last_loss = total / samples.len() as f64;
        Ok(self.last_loss)
    }

    /// Writes a resumable checkpoint (weights, Adam moments, config, epoch, step, seed, loss).
    pub fn save(&self, path: &Path) -> Result<()> {
        let mut tensors = self.weights()?;
        tensors.extend(self.optimizer.state_tensors(OPTIMIZER_PREFIX));
        write_checkpoint(path, &tensors, &self.model_config, Some(&self.state()))
    }

    /// Writes the weights only (the small file that is embedded as the default).
    pub fn save_weights(&self, path: &Path) -> Result<()> {
        write_checkpoint(
            path,
            &self.weights()?,
            &self.model_config,
            Some(&self.state()),
        )
    }

    fn state(&self) -> CheckpointState {
        CheckpointState {
            epoch: self.epoch,
            step: self.step,
            seed: self.config.seed,
            loss: self.last_loss,
            best_validation: self.best_validation,
        }
    }

    /// Every model tensor (parameters and batch-norm statistics) by name, sorted.
    fn weights(&self) -> Result<Vec<(String, Tensor)>> {
        Ok(sorted_vars(&self.varmap)
            .into_iter()
            .map(|(n, v)| (n, v.as_detached_tensor()))
            .collect())
    }
}

/// `K̄_2` of eq. 5.8: the mean curvature of the simplified cloud `points: (M, 3)` itself
/// (eq. 5.1-5.3 with `k` neighbours, differentiable in the positions, so the curvature term
/// trains AttRef and, through the embeddings it reads, the projector). Fewer than 3 kept points
/// have no curvature of their own; the input's `K̄` at the kept `indices` stands in.
fn simplified_curvature(
    sample: &TrainingSample,
    points: &Tensor,
    indices: &[u32],
    k: usize,
) -> Result<Tensor> {
    if indices.len() >= 3 {
        return Ok(mean_curvature(points, k)?);
    }
    let idx = Tensor::from_slice(indices, indices.len(), &Device::Cpu)?;
    Ok(sample.curvature.index_select(&idx, 0)?)
}

fn check_config(c: &TrainingConfig) -> Result<()> {
    let bad = |what: &str, reason: String| {
        Err(Error::Invalid {
            what: format!("training config {what}"),
            reason,
        })
    };
    if !(c.learning_rate > 0.0 && c.learning_rate.is_finite()) {
        return bad(
            "learning_rate",
            format!("must be positive, got {}", c.learning_rate),
        );
    }
    if !(c.curvature_weight >= 0.0 && c.curvature_weight.is_finite()) {
        return bad(
            "curvature_weight",
            format!(
                "must be finite and non-negative, got {}",
                c.curvature_weight
            ),
        );
    }
    if !(c.lr_decay > 0.0 && c.lr_decay <= 1.0) {
        return bad("lr_decay", format!("must be in (0, 1], got {}", c.lr_decay));
    }
    if !(c.min_ratio > 0.0 && c.min_ratio <= c.max_ratio && c.max_ratio <= 1.0) {
        return bad(
            "ratios",
            format!(
                "need 0 < min ≤ max ≤ 1, got {} .. {}",
                c.min_ratio, c.max_ratio
            ),
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshgnn_geometry::{sample_surface, subdivided_cube};

    fn tiny() -> (PointSimplifierConfig, TrainingConfig, TrainingSample) {
        let mc = PointSimplifierConfig {
            hidden: 16,
            attention_dim: 8,
            phi_hidden: 8,
            gamma_hidden: 8,
            ..Default::default()
        };
        let tc = TrainingConfig {
            seed: 5,
            learning_rate: 1e-3,
            ..Default::default()
        };
        let pts = sample_surface(&subdivided_cube(3), 300, 2).unwrap().points;
        let s = prepare_training_sample(&pts, &mc, &tc).unwrap();
        (mc, tc, s)
    }

    #[test]
    fn gradients_reach_the_projector_through_the_gathered_embeddings() {
        let (mc, tc, s) = tiny();
        let trainer = Trainer::new(&mc, &tc).unwrap();
        let loss = trainer.loss(&s, 40, 1, true).unwrap();
        let grads = loss.backward().unwrap();
        let vars = sorted_vars(&trainer.varmap);
        for name in [
            "projector.mlp.0.linear.weight",
            "projector.gnn.neighbour.weight",
            "refine.query.weight",
            "refine.gamma.1.weight",
        ] {
            let var = &vars.iter().find(|(n, _)| n == name).unwrap().1;
            let g = grads
                .get(var.as_tensor())
                .unwrap_or_else(|| panic!("no gradient for {name}"));
            let norm = g
                .sqr()
                .unwrap()
                .sum_all()
                .unwrap()
                .to_scalar::<f32>()
                .unwrap();
            assert!(norm > 0.0 && norm.is_finite(), "{name}: |g|² = {norm}");
        }
    }

    #[test]
    fn the_curvature_term_sends_its_own_gradient_to_the_refinement() {
        // K̄_2 is computed on the refined points, so E_c changes AttRef's gradient (with the
        // input's K̄ gathered at the kept indices it would add nothing).
        let (mc, tc, s) = tiny();
        let gradient = |lambda: f64| -> Vec<f32> {
            let trainer = Trainer::new(
                &mc,
                &TrainingConfig {
                    curvature_weight: lambda,
                    ..tc
                },
            )
            .unwrap();
            let grads = trainer.loss(&s, 40, 1, true).unwrap().backward().unwrap();
            let vars = sorted_vars(&trainer.varmap);
            let var = &vars
                .iter()
                .find(|(n, _)| n == "refine.gamma.1.weight")
                .unwrap()
                .1;
            let g = grads.get(var.as_tensor()).unwrap();
            g.flatten_all().unwrap().to_vec1::<f32>().unwrap()
        };
        let (without, with) = (gradient(0.0), gradient(1.0));
        let change: f32 = without.iter().zip(&with).map(|(a, b)| (a - b).abs()).sum();
        let size: f32 = without.iter().map(|a| a.abs()).sum();
        assert!(
            change > 1e-3 * size,
            "E_c changed the gradient by {change} (of {size})"
        );
    }

    #[test]
    fn a_few_steps_lower_the_loss_on_a_fixed_cloud() {
        let (mc, tc, _) = tiny();
        // 1500 points to 150: the curvature term's k = 16 neighbourhoods stay local on the
        // kept cloud, as in real training (2048 points, ratios ≥ 0.05); on a 30-point cloud
        // they span half the shape and E_c is set by which points FPS picks, not by training
        let pts = sample_surface(&subdivided_cube(3), 1500, 2).unwrap().points;
        let s = prepare_training_sample(&pts, &mc, &tc).unwrap();
        let mut trainer = Trainer::new(&mc, &tc).unwrap();
        // the fixed batch: one cloud, one target, one FPS start
        let eval = |t: &Trainer| -> f32 {
            t.loss(&s, 150, 3, true)
                .unwrap()
                .to_scalar::<f32>()
                .unwrap()
        };
        let before = eval(&trainer);
        // the selection moves with the embeddings, so single steps are noisy; over 100 steps
        // the loss falls
        for _ in 0..100 {
            trainer.train_step_with(&s, 150, 3).unwrap();
        }
        let after = eval(&trainer);
        assert!(after < 0.95 * before, "{before} → {after}");
    }

    #[test]
    fn save_load_round_trip_is_bit_identical_and_resume_is_exact() {
        let (mc, tc, s) = tiny();
        let samples = vec![s.clone(), s];
        let mut a = Trainer::new(&mc, &tc).unwrap();
        a.train_epoch(&samples, &mut |_| {}).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("ckpt.safetensors");
        let v = a.validation_loss(&samples[..1]).unwrap();
        assert!(v.is_finite() && v > 0.0);
        assert_eq!(
            v,
            a.validation_loss(&samples[..1]).unwrap(),
            "deterministic"
        );
        assert!(a.record_validation(v) && !a.record_validation(v) && a.record_validation(0.5 * v));
        a.save(&path).unwrap();
        let loaded = PointSimplifier::load(&path).unwrap();
        assert_eq!(loaded.config(), &mc);
        let bytes = std::fs::read(&path).unwrap();
        let ck = read_checkpoint(&bytes, &path).unwrap();
        let bits = |t: &Tensor| -> Vec<u32> {
            let values = t.flatten_all().unwrap().to_vec1::<f32>().unwrap();
            values.iter().map(|v| v.to_bits()).collect()
        };
        for (name, t) in a.weights().unwrap() {
            assert_eq!(bits(&t), bits(&ck.tensors[&name]), "{name}");
        }
        // the loaded model (inference path: sparse mean in f64, host gathers) simplifies like
        // the trained one (autograd path): same selection, positions equal to rounding
        let pts = sample_surface(&subdivided_cube(2), 200, 4).unwrap().points;
        let o = super::super::SimplifyOptions::default();
        let p = a.model().simplify(&pts, None, None, 20, &o).unwrap();
        let q = loaded.simplify(&pts, None, None, 20, &o).unwrap();
        assert_eq!(p.indices, q.indices);
        for (u, v) in p.points.iter().zip(&q.points) {
            for d in 0..3 {
                assert!((u[d] - v[d]).abs() < 1e-5, "{u:?} vs {v:?}");
            }
        }
        // resume: one more epoch from the file equals one more epoch in memory
        let mut b = Trainer::resume(&path, &tc).unwrap();
        assert_eq!((b.epoch(), b.steps()), (1, 2));
        assert_eq!(b.best_validation(), Some(0.5 * v));
        let la = a.train_epoch(&samples, &mut |_| {}).unwrap();
        let lb = b.train_epoch(&samples, &mut |_| {}).unwrap();
        assert_eq!(la, lb);
        assert!(Trainer::resume(&dir.path().join("missing"), &tc).is_err());
    }
}
