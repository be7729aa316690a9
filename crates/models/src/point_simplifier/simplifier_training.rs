//! What the point simplifier trains (thesis ch. 5.6): loss eq. 5.9 on one cloud per example
//! with a target ratio drawn uniformly from `[0.05, 0.5]`, so one model serves any ratio;
//! validation is eq. 5.9 on held-out clouds at the benchmark's ratios. The loop itself (seeded
//! order, Adam with lr 1e-3 × 0.99 per epoch, checkpoints, resuming, the best epoch) is
//! [`crate::training::train`]; the thesis' settings are batch size 1 and 150 epochs.
//!
//! # Conventions
//! - Initialisation: every linear weight and bias `U(−1/√fan_in, 1/√fan_in)` (PyTorch's
//!   default), batch-norm scale 1, shift 0; drawn from `StdRng::seed_from_u64(seed)` in name
//!   order by [`crate::spiral::seeded_initialization`], the crate's one initialisation.
//! - Adam's parameters are the weights; batch-norm running statistics are state, saved in
//!   checkpoints but not optimised.
//! - Step `s` draws its ratios and FPS seeds from `StdRng::seed_from_u64(seed ^
//!   s·0xD1B5_4A32_D192_ED03)`, one pair per cloud of the batch.

use std::path::Path;

use candle_core::{DType, Device, Tensor, Var};
use candle_nn::{VarBuilder, VarMap};
use meshgnn_geometry::{curvature_features, unit_sphere_normalization};
use meshgnn_graph::knn_graph;
use meshgnn_losses::losses::adaptive_chamfer_weights;
use rand::{Rng, SeedableRng, rngs::StdRng};

use super::{
    CurvatureTarget, LatentSamplingOptions, NeighbourIndex, POINT_SIMPLIFIER_NAME, PointSimplifier,
    PointSimplifierConfig, simplifier_loss,
};
use crate::adam::sorted_vars;
use crate::checkpoint::{check_same_config, checkpoint_of, set_vars, vars_checkpoint};
use crate::training::{BatchLoss, StepContext, Trainable, batch_mean};
use crate::{Checkpoint, Error, Result};

/// Target ratios of the validation figure: those of the benchmark (thesis Table 5.1).
pub const VALIDATION_RATIOS: [f64; 3] = [0.2, 0.1, 0.05];

/// The settings of the simplifier's objective; defaults follow ch. 5.6.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SimplifierObjective {
    /// Smallest target ratio drawn per cloud (0.05).
    pub min_ratio: f64,
    /// Largest target ratio drawn per cloud (0.5).
    pub max_ratio: f64,
    /// λ of eq. 5.9 (0.1).
    pub curvature_weight: f64,
    /// Temperature τ of the adaptive Chamfer weights (10).
    pub tau: f32,
    /// `k` of the curvature estimates, as the evaluation's (16): neighbours of the adaptive
    /// weights' `K̄` on the original, simplified points per kernel radius of `E_c`.
    pub curvature_neighbours: usize,
}

impl Default for SimplifierObjective {
    fn default() -> Self {
        Self {
            min_ratio: 0.05,
            max_ratio: 0.5,
            curvature_weight: 0.1,
            tau: 10.0,
            curvature_neighbours: 16,
        }
    }
}

impl SimplifierObjective {
    fn check(&self) -> Result<()> {
        let bad = |what: &str, reason: String| {
            Err(Error::Invalid {
                what: format!("simplifier objective {what}"),
                reason,
            })
        };
        if !(self.curvature_weight >= 0.0 && self.curvature_weight.is_finite()) {
            return bad(
                "curvature_weight",
                format!(
                    "must be finite and non-negative, got {}",
                    self.curvature_weight
                ),
            );
        }
        if !(self.min_ratio > 0.0 && self.min_ratio <= self.max_ratio && self.max_ratio <= 1.0) {
            return bad(
                "ratios",
                format!(
                    "need 0 < min ≤ max ≤ 1, got {} .. {}",
                    self.min_ratio, self.max_ratio
                ),
            );
        }
        Ok(())
    }
}

/// One training cloud with everything the loss needs, precomputed once.
#[derive(Clone, Debug)]
pub struct TrainingSample {
    /// The points the model reads, in the unit-sphere frame of the clean cloud, `#N×3`.
    pub points: Vec<[f32; 3]>,
    /// The projector's k-NN graph over `points`.
    pub graph: NeighbourIndex,
    /// The clean cloud the loss compares with (equal to `points` without noise), `#N×3`.
    pub clean: Vec<[f32; 3]>,
    /// `clean` as a tensor `(N, 3)`.
    pub positions: Tensor,
    /// Adaptive Chamfer weights (eq. 5.7) of `clean`, `(N)`.
    pub weights: Tensor,
}

/// Prepares `points: #N×3` (any units; normalised to the unit sphere here) for training:
/// curvature features, adaptive weights, k-NN graph. Needs at least 3 points.
///
/// ```
/// use meshgnn_geometry::icosphere;
/// use meshgnn_models::point_simplifier::{PointSimplifierConfig, SimplifierObjective, prepare_training_sample};
/// let pts = icosphere(2).vertices().to_vec();
/// let s = prepare_training_sample(&pts, &PointSimplifierConfig::default(), &SimplifierObjective::default())?;
/// assert_eq!(s.points.len(), 162);
/// # Ok::<(), meshgnn_models::Error>(())
/// ```
pub fn prepare_training_sample(
    points: &[[f32; 3]],
    model: &PointSimplifierConfig,
    objective: &SimplifierObjective,
) -> Result<TrainingSample> {
    prepare_denoising_sample(points, points, model, objective)
}

/// [`prepare_training_sample`] for a model that reads `input: #N×3` (`clean` with noise) and
/// is scored against `clean: #N×3`: both are normalised with the clean cloud's centre and
/// radius, so the loss asks the refinement to undo the noise (ch. 5.5.7 tests that robustness;
/// training for it is beyond the thesis). Errors when the two clouds differ in size.
pub fn prepare_denoising_sample(
    clean: &[[f32; 3]],
    input: &[[f32; 3]],
    model: &PointSimplifierConfig,
    objective: &SimplifierObjective,
) -> Result<TrainingSample> {
    let n = clean.len();
    if n < 3 {
        return Err(Error::Invalid {
            what: "training cloud".into(),
            reason: format!("needs at least 3 points, has {n}"),
        });
    }
    if input.len() != n {
        return Err(Error::Invalid {
            what: "training input".into(),
            reason: format!("{} input points for {n} clean ones", input.len()),
        });
    }
    let norm = unit_sphere_normalization(clean)?;
    let unit = norm.apply(clean);
    let points = norm.apply(input);
    let features = curvature_features(&unit, objective.curvature_neighbours.clamp(2, n - 1))?;
    let weights = adaptive_chamfer_weights(&features.mean_curvature, objective.tau)?;
    let device = Device::Cpu;
    let graph = NeighbourIndex::from_knn(
        &knn_graph(&points, model.gnn_neighbours.min(n - 1))?,
        &device,
    )?;
    Ok(TrainingSample {
        positions: Tensor::from_slice(unit.as_flattened(), (n, 3), &device)?,
        weights: Tensor::from_vec(weights, n, &device)?,
        points,
        clean: unit,
        graph,
    })
}

/// The simplifier with its parameters and its training and held-out clouds.
pub struct SimplifierTraining {
    config: PointSimplifierConfig,
    objective: SimplifierObjective,
    varmap: VarMap,
    model: PointSimplifier,
    train: Vec<TrainingSample>,
    validation: Vec<TrainingSample>,
}

impl SimplifierTraining {
    /// A fresh model initialised from `seed` (module docs) training on `train` and validating
    /// on `validation` (may be empty: no best epoch then).
    pub fn new(
        config: &PointSimplifierConfig,
        objective: &SimplifierObjective,
        train: Vec<TrainingSample>,
        validation: Vec<TrainingSample>,
        seed: u64,
    ) -> Result<Self> {
        objective.check()?;
        let varmap = VarMap::new();
        let vb = VarBuilder::from_varmap(&varmap, DType::F32, &Device::Cpu);
        let model = PointSimplifier::new(vb, config)?;
        crate::spiral::seeded_initialization(&varmap, seed)?;
        Ok(Self {
            config: *config,
            objective: *objective,
            varmap,
            model,
            train,
            validation,
        })
    }

    /// The model being trained (shares its parameters).
    pub fn model(&self) -> &PointSimplifier {
        &self.model
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
        let curvature = CurvatureTarget::new(
            &sample.clean,
            out.indices.len(),
            self.objective.curvature_neighbours,
        )?;
        Ok(simplifier_loss(
            &sample.positions,
            &sample.weights,
            &out.points,
            &curvature,
            self.objective.curvature_weight,
        )?
        .total)
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
}

impl Trainable for SimplifierTraining {
    fn model_name(&self) -> &'static str {
        POINT_SIMPLIFIER_NAME
    }

    fn train_len(&self) -> usize {
        self.train.len()
    }

    fn parameters(&self) -> Vec<(String, Var)> {
        sorted_vars(&self.varmap)
            .into_iter()
            .filter(|(n, _)| !n.contains("running_"))
            .collect()
    }

    /// Eq. 5.9 of every cloud of `batch` at its drawn ratio and FPS start, averaged.
    fn batch_loss(&self, batch: &[usize], context: &StepContext) -> Result<BatchLoss> {
        let mut rng =
            StdRng::seed_from_u64(context.seed ^ context.step.wrapping_mul(0xD1B5_4A32_D192_ED03));
        let mut losses = Vec::with_capacity(batch.len());
        for &i in batch {
            let sample = self.train.get(i).ok_or_else(|| Error::Invalid {
                what: format!("training cloud {i}"),
                reason: format!("out of range (there are {})", self.train.len()),
            })?;
            let ratio = rng.random_range(self.objective.min_ratio..=self.objective.max_ratio);
            let n = sample.points.len();
            let target = ((ratio * n as f64).round() as usize).clamp(1, n);
            let fps_seed: u64 = rng.random();
            losses.push(self.loss(sample, target, fps_seed, true)?);
        }
        Ok(BatchLoss {
            loss: batch_mean(losses)?,
            figure: None,
        })
    }

    fn validation(&self) -> Result<Option<f64>> {
        if self.validation.is_empty() {
            return Ok(None);
        }
        self.validation_loss(&self.validation).map(Some)
    }

    fn checkpoint(&self) -> Result<Checkpoint> {
        Ok(vars_checkpoint(self.config.header(), &self.varmap))
    }

    /// Every model tensor from the checkpoint, which must hold this config.
    fn restore(&mut self, checkpoint: &Checkpoint, source: &Path) -> Result<()> {
        let config = PointSimplifierConfig::from_header(&checkpoint.header, source)?;
        check_same_config(source, &config, &self.config)?;
        set_vars(&self.varmap, &checkpoint.tensors).map_err(|e| checkpoint_of(source, e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::training::{TrainingConfig, train};
    use meshgnn_geometry::{sample_surface, subdivided_cube};

    fn tiny() -> (PointSimplifierConfig, SimplifierObjective, TrainingSample) {
        let mc = PointSimplifierConfig {
            hidden: 16,
            attention_dim: 8,
            phi_hidden: 8,
            gamma_hidden: 8,
            ..Default::default()
        };
        let objective = SimplifierObjective::default();
        let pts = sample_surface(&subdivided_cube(3), 300, 2).unwrap().points;
        let s = prepare_training_sample(&pts, &mc, &objective).unwrap();
        (mc, objective, s)
    }

    fn task(mc: &PointSimplifierConfig, objective: &SimplifierObjective) -> SimplifierTraining {
        SimplifierTraining::new(mc, objective, Vec::new(), Vec::new(), 5).unwrap()
    }

    /// One Adam step on `sample` keeping `target` points with FPS seed `seed`.
    fn step(t: &SimplifierTraining, adam: &mut crate::Adam, s: &TrainingSample, target: usize) {
        adam.backward_step(&t.loss(s, target, 3, true).unwrap())
            .unwrap();
    }

    #[test]
    fn a_denoising_sample_reads_the_noisy_cloud_and_targets_the_clean_one() {
        let (mc, objective, clean) = tiny();
        let pts = sample_surface(&subdivided_cube(3), 300, 2).unwrap().points;
        let noisy: Vec<[f32; 3]> = pts
            .iter()
            .enumerate()
            .map(|(i, p)| [p[0] + 0.01 * (i % 3) as f32, p[1], p[2]])
            .collect();
        let s = prepare_denoising_sample(&pts, &noisy, &mc, &objective).unwrap();
        assert_eq!(s.clean, clean.points);
        let pos: Vec<f32> = s.positions.flatten_all().unwrap().to_vec1().unwrap();
        assert_eq!(pos, clean.clean.as_flattened());
        // the input is normalised with the clean cloud's centre and radius
        let norm = unit_sphere_normalization(&pts).unwrap();
        assert_eq!(s.points, norm.apply(&noisy));
        assert_ne!(s.points, s.clean);
        let err = prepare_denoising_sample(&pts, &noisy[1..], &mc, &objective).unwrap_err();
        assert!(
            err.to_string().contains("299 input points for 300"),
            "{err}"
        );
    }

    #[test]
    fn gradients_reach_the_projector_through_the_gathered_embeddings() {
        let (mc, objective, s) = tiny();
        let trainer = task(&mc, &objective);
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
        let (mc, objective, s) = tiny();
        let gradient = |lambda: f64| -> Vec<f32> {
            let trainer = task(
                &mc,
                &SimplifierObjective {
                    curvature_weight: lambda,
                    ..objective
                },
            );
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
        let (mc, objective, _) = tiny();
        // 1500 points to 150: the curvature term's k = 16 neighbourhoods stay local on the
        // kept cloud, as in real training (2048 points, ratios ≥ 0.05); on a 30-point cloud
        // they span half the shape and E_c is set by which points FPS picks, not by training
        let pts = sample_surface(&subdivided_cube(3), 1500, 2).unwrap().points;
        let s = prepare_training_sample(&pts, &mc, &objective).unwrap();
        let trainer = task(&mc, &objective);
        let mut adam =
            crate::Adam::new(trainer.parameters(), crate::AdamConfig::default()).unwrap();
        // the fixed batch: one cloud, one target, one FPS start
        let eval = |t: &SimplifierTraining| -> f32 {
            t.loss(&s, 150, 3, true)
                .unwrap()
                .to_scalar::<f32>()
                .unwrap()
        };
        let before = eval(&trainer);
        // the selection moves with the embeddings, so single steps are noisy; over 100 steps
        // the loss falls
        for _ in 0..100 {
            step(&trainer, &mut adam, &s, 150);
        }
        let after = eval(&trainer);
        assert!(after < 0.95 * before, "{before} → {after}");
    }

    #[test]
    fn save_load_round_trip_is_bit_identical_and_resume_is_exact() {
        let (mc, objective, s) = tiny();
        let samples = vec![s.clone(), s];
        let make = || {
            SimplifierTraining::new(&mc, &objective, samples.clone(), samples[..1].to_vec(), 5)
                .unwrap()
        };
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("ckpt.safetensors");
        let best = dir.path().join("best.safetensors");
        let config = TrainingConfig {
            epochs: 1,
            batch_size: 1,
            seed: 5,
            checkpoint: Some(path.clone()),
            best_weights: Some(best.clone()),
            ..Default::default()
        };
        let mut a = make();
        let first = train(&mut a, &config, &mut |_| {}).unwrap();
        let v = a.validation_loss(&samples[..1]).unwrap();
        assert!(v.is_finite() && v > 0.0);
        assert_eq!(
            v,
            a.validation_loss(&samples[..1]).unwrap(),
            "deterministic"
        );
        assert_eq!(first.state.best_validation, Some(v));
        let loaded = PointSimplifier::load(&path).unwrap();
        assert_eq!(loaded.config(), &mc);
        let ck = Checkpoint::load(&path).unwrap();
        let bits = |t: &Tensor| -> Vec<u32> {
            let values = t.flatten_all().unwrap().to_vec1::<f32>().unwrap();
            values.iter().map(|v| v.to_bits()).collect()
        };
        for (name, t) in a.checkpoint().unwrap().tensors {
            assert_eq!(bits(&t), bits(&ck.tensors[&name]), "{name}");
        }
        // the best weights are the checkpoint's model, without Adam's moments
        let best_tensors = Checkpoint::load(&best).unwrap().tensors;
        assert_eq!(best_tensors.len(), ck.model_tensors().len());
        assert!(best_tensors.len() < ck.tensors.len());
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
        let two = TrainingConfig {
            epochs: 2,
            checkpoint: None,
            best_weights: None,
            ..config.clone()
        };
        let mut straight = make();
        let all = train(&mut straight, &two, &mut |_| {}).unwrap();
        let mut b = make();
        let rest = train(
            &mut b,
            &TrainingConfig {
                checkpoint: Some(path.clone()),
                resume: true,
                ..two.clone()
            },
            &mut |_| {},
        )
        .unwrap();
        assert_eq!((rest.history[0].epoch, rest.history[0].step), (1, 4));
        assert_eq!(rest.history[0].loss, all.history[1].loss);
        assert_eq!(rest.state, all.state);
        let missing = TrainingConfig {
            checkpoint: Some(dir.path().join("missing")),
            resume: true,
            ..two
        };
        assert!(train(&mut make(), &missing, &mut |_| {}).is_err());
    }
}
