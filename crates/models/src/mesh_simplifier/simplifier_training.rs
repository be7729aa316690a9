//! Training the neural mesh simplifier with the crate's one loop ([`crate::training::train`]).
//! Beyond the thesis, whose eq. 6.14 collapses to an empty mesh (docs/mesh_simplifier_model.md),
//! every module learns a supervised target:
//!
//! - the **point sampler** the QEM importance of each vertex ([`qem_importance`]), as a
//!   binary cross-entropy with soft labels, so its inclusion probabilities are dense where a
//!   quadric decimation keeps vertices (creases, thin parts) and sparse on flat regions;
//! - the **edge predictor** and the **face classifier** the nearest-seed Voronoi dual of the
//!   drawn vertices ([`DualTargets`]).
//!
//! # Conventions
//! - Step `s` draws each mesh's vertex ratio uniformly from `ratios` and the sampler's seed
//!   from `StdRng::seed_from_u64(seed ^ s·0xD1B5_4A32_D192_ED03)`.
//! - Validation: the same losses on the held-out meshes at every ratio of
//!   [`VALIDATION_RATIOS`], seeds fixed, so the figure moves only with the weights.
//! - Initial weights from `seed` ([`crate::spiral::seeded_initialization`]).

use std::path::Path;

use candle_core::{DType, Device, Tensor, Var};
use candle_nn::{VarBuilder, VarMap};
use meshgnn_geometry::TriMesh;
use meshgnn_graph::qem_vertices;
use meshgnn_losses::losses::edge_valence_excess;
use rand::{Rng, SeedableRng, rngs::StdRng};

use super::checkpoint::NEURAL_MESH_SIMPLIFIER_NAME;
use super::{DualTargets, MeshInput, NeuralMeshSimplifier, NeuralMeshSimplifierConfig};
use crate::checkpoint::{check_same_config, checkpoint_of, set_vars, vars_checkpoint};
use crate::training::{BatchLoss, StepContext, Trainable, batch_mean};
use crate::{Checkpoint, Error, Result, sorted_vars};

/// Vertex ratios of the validation passes.
pub const VALIDATION_RATIOS: [f64; 3] = [0.05, 0.1, 0.2];

/// Ratios at which [`qem_importance`] asks QEM which vertices it keeps.
const IMPORTANCE_RATIOS: [f64; 5] = [0.02, 0.05, 0.1, 0.2, 0.4];

/// Importance of a vertex no ratio keeps, so flat regions are still sampled.
const IMPORTANCE_FLOOR: f32 = 0.1;

/// Smallest probability a logarithm sees.
const LOG_FLOOR: f64 = 1e-6;

/// The sampler's target per vertex: `(0.1 + r) / (0.1 + 5)`, `r` the number of the vertex
/// ratios 2, 5, 10, 20 and 40 % (at least 8 vertices) at which QEM with original positions
/// ([`meshgnn_graph::qem_vertices`]) keeps the vertex. In (0, 1]. A ratio QEM cannot reach
/// (a small or non-manifold mesh) keeps nothing.
pub fn qem_importance(mesh: &TriMesh) -> Result<Vec<f32>> {
    let n = mesh.vertex_count();
    let mut kept = vec![0u32; n];
    for ratio in IMPORTANCE_RATIOS {
        let count = ((n as f64 * ratio).round() as usize).clamp(8.min(n), n);
        let Ok(selection) = qem_vertices(mesh, count) else {
            continue;
        };
        for i in selection.indices {
            kept[i as usize] += 1;
        }
    }
    let top = IMPORTANCE_FLOOR + IMPORTANCE_RATIOS.len() as f32;
    Ok(kept
        .into_iter()
        .map(|r| (IMPORTANCE_FLOOR + r as f32) / top)
        .collect())
}

/// One training mesh: the network's input and the sampler's target.
#[derive(Clone, Debug)]
pub struct SimplifierExample {
    /// The mesh as given.
    pub mesh: TriMesh,
    /// Its network input.
    pub input: MeshInput,
    /// [`qem_importance`] of every vertex, `(N)`.
    pub importance: Tensor,
}

impl SimplifierExample {
    /// Prepares `mesh` (a manifold mesh QEM can decimate).
    pub fn new(mesh: TriMesh) -> Result<Self> {
        let input = MeshInput::new(&mesh, &Device::Cpu)?;
        let importance = qem_importance(&mesh)?;
        let n = importance.len();
        Ok(Self {
            importance: Tensor::from_vec(importance, n, &Device::Cpu)?,
            input,
            mesh,
        })
    }
}

/// The three losses of one pass.
#[derive(Clone, Debug)]
pub struct SimplifierLosses {
    /// Soft-label cross-entropy of the inclusion probabilities against the QEM importance.
    pub sampler: Tensor,
    /// [`DualTargets::edge_loss`].
    pub edges: Tensor,
    /// [`DualTargets::face_loss`].
    pub faces: Tensor,
    /// [`edge_valence_excess`] of the face probabilities over the candidates, times the
    /// training's valence weight.
    pub valence: Tensor,
    /// Dual triangles among the candidates (their recall), for reports.
    pub candidate_recall: f64,
}

impl SimplifierLosses {
    /// The sum the optimiser minimises.
    pub fn total(&self) -> Result<Tensor> {
        Ok(self
            .sampler
            .add(&self.edges)?
            .add(&self.faces)?
            .add(&self.valence)?)
    }
}

/// The model with its parameters and its training and held-out meshes.
pub struct SimplifierTraining {
    config: NeuralMeshSimplifierConfig,
    varmap: VarMap,
    model: NeuralMeshSimplifier,
    train: Vec<SimplifierExample>,
    validation: Vec<SimplifierExample>,
    ratios: (f64, f64),
    valence_weight: f64,
}

impl SimplifierTraining {
    /// A fresh model initialised from `seed` training on `train` with vertex ratios drawn
    /// from `ratios` (`0 < lo ≤ hi ≤ 1`) and validating on `validation` (may be empty).
    pub fn new(
        config: &NeuralMeshSimplifierConfig,
        train: Vec<SimplifierExample>,
        validation: Vec<SimplifierExample>,
        ratios: (f64, f64),
        seed: u64,
    ) -> Result<Self> {
        let (lo, hi) = ratios;
        if !(lo > 0.0 && lo <= hi && hi <= 1.0) {
            return Err(Error::Invalid {
                what: "training ratios".into(),
                reason: format!("{lo}..{hi}: need 0 < lo <= hi <= 1"),
            });
        }
        let varmap = VarMap::new();
        let vb = VarBuilder::from_varmap(&varmap, DType::F32, &Device::Cpu);
        let model = NeuralMeshSimplifier::new(vb, config)?;
        crate::spiral::seeded_initialization(&varmap, seed)?;
        Ok(Self {
            config: *config,
            varmap,
            model,
            train,
            validation,
            ratios,
            valence_weight: 0.0,
        })
    }

    /// Adds `weight ·` [`edge_valence_excess`] of the face probabilities to the loss (0 by
    /// default): the candidates on an edge then compete for its two faces.
    pub fn with_valence_weight(mut self, weight: f64) -> Self {
        self.valence_weight = weight;
        self
    }

    /// The model being trained (shares its parameters).
    pub fn model(&self) -> &NeuralMeshSimplifier {
        &self.model
    }

    /// The losses of one pass over `example` keeping `ratio` of its vertices, drawn with
    /// `seed`.
    pub fn losses(
        &self,
        example: &SimplifierExample,
        ratio: f64,
        seed: u64,
    ) -> Result<SimplifierLosses> {
        let n = example.mesh.vertex_count();
        let target = ((n as f64 * ratio).round() as usize).clamp(3, n);
        let pass = self.model.forward(&example.input, target, seed)?;
        let targets = DualTargets::new(&pass)?;
        let p = pass
            .sampled
            .probabilities
            .clamp(LOG_FLOOR, 1.0 - LOG_FLOOR)?;
        let t = &example.importance;
        let sampler = t
            .mul(&p.log()?)?
            .add(&t.affine(-1.0, 1.0)?.mul(&p.affine(-1.0, 1.0)?.log()?)?)?
            .mean_all()?
            .neg()?;
        let faces = &pass.candidates.triangles;
        let valence = if faces.is_empty() || self.valence_weight == 0.0 {
            pass.face_probabilities.zeros_like()?.sum_all()?
        } else {
            edge_valence_excess(faces, &pass.face_probabilities)?
                .affine(self.valence_weight, 0.0)?
        };
        Ok(SimplifierLosses {
            sampler,
            edges: targets.edge_loss(&pass)?,
            faces: targets.face_loss(&pass)?,
            valence,
            candidate_recall: targets.candidate_hits as f64 / targets.dual_faces.max(1) as f64,
        })
    }

    /// The mean total loss over `examples` at [`VALIDATION_RATIOS`], seed `i` for example `i`.
    pub fn validation_loss(&self, examples: &[SimplifierExample]) -> Result<f64> {
        if examples.is_empty() {
            return Err(Error::Invalid {
                what: "validation meshes".into(),
                reason: "none given".into(),
            });
        }
        let mut total = 0.0;
        for (i, example) in examples.iter().enumerate() {
            for ratio in VALIDATION_RATIOS {
                let loss = self.losses(example, ratio, i as u64)?.total()?;
                total += f64::from(loss.to_scalar::<f32>()?);
            }
        }
        Ok(total / (examples.len() * VALIDATION_RATIOS.len()) as f64)
    }
}

impl Trainable for SimplifierTraining {
    fn model_name(&self) -> &'static str {
        NEURAL_MESH_SIMPLIFIER_NAME
    }

    fn train_len(&self) -> usize {
        self.train.len()
    }

    fn parameters(&self) -> Vec<(String, Var)> {
        sorted_vars(&self.varmap)
    }

    /// The losses of every mesh of `batch` at its drawn ratio, averaged; the figure is the
    /// mean candidate recall of the dual triangles.
    fn batch_loss(&self, batch: &[usize], context: &StepContext) -> Result<BatchLoss> {
        let mut rng =
            StdRng::seed_from_u64(context.seed ^ context.step.wrapping_mul(0xD1B5_4A32_D192_ED03));
        let mut losses = Vec::with_capacity(batch.len());
        let mut recall = 0.0;
        for &i in batch {
            let example = self.train.get(i).ok_or_else(|| Error::Invalid {
                what: format!("training mesh {i}"),
                reason: format!("out of range (there are {})", self.train.len()),
            })?;
            let ratio = rng.random_range(self.ratios.0..=self.ratios.1);
            let pass = self.losses(example, ratio, rng.random())?;
            recall += pass.candidate_recall;
            losses.push(pass.total()?);
        }
        Ok(BatchLoss {
            loss: batch_mean(losses)?,
            figure: Some(recall / batch.len() as f64),
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
        let config = NeuralMeshSimplifierConfig::from_header(&checkpoint.header, source)?;
        check_same_config(source, &config, &self.config)?;
        set_vars(&self.varmap, &checkpoint.tensors).map_err(|e| checkpoint_of(source, e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh_simplifier::FaceClassifierConfig;
    use crate::training::{TrainingConfig, train};

    fn small() -> NeuralMeshSimplifierConfig {
        let mut config = NeuralMeshSimplifierConfig::default();
        config.sampler.hidden = 8;
        config.edges.hidden = 8;
        config.faces = FaceClassifierConfig {
            hidden: 8,
            ..Default::default()
        };
        config
    }

    #[test]
    fn qem_importance_ranks_corners_above_flat_faces() {
        // subdivided_cube(4): the 8 corners are kept at every ratio, face centres rarely.
        let cube = meshgnn_geometry::subdivided_cube(4);
        let importance = qem_importance(&cube).unwrap();
        let corner = cube
            .vertices()
            .iter()
            .position(|p| p.iter().all(|c| c.abs() > 0.99))
            .unwrap();
        assert!(
            (importance[corner] - 1.0).abs() < 1e-6,
            "{}",
            importance[corner]
        );
        let mean = importance.iter().sum::<f32>() / importance.len() as f32;
        assert!(mean < 0.5, "{mean}");
        assert!(importance.iter().all(|&v| v > 0.0 && v <= 1.0));
    }

    #[test]
    fn the_valence_term_is_its_weight_times_the_excess_of_the_pass() {
        let example = SimplifierExample::new(meshgnn_geometry::icosphere(3)).unwrap();
        let task = |weight| {
            SimplifierTraining::new(&small(), vec![example.clone()], vec![], (0.3, 0.3), 2)
                .unwrap()
                .with_valence_weight(weight)
        };
        let off = task(0.0).losses(&example, 0.3, 5).unwrap();
        assert_eq!(off.valence.to_scalar::<f32>().unwrap(), 0.0);
        let on = task(2.5);
        let losses = on.losses(&example, 0.3, 5).unwrap();
        let pass = on.model().forward(&example.input, 193, 5).unwrap();
        let excess: f32 = edge_valence_excess(&pass.candidates.triangles, &pass.face_probabilities)
            .unwrap()
            .to_scalar()
            .unwrap();
        let valence: f32 = losses.valence.to_scalar().unwrap();
        assert!(excess > 0.0, "an untrained classifier overfills some edge");
        assert!(
            (valence - 2.5 * excess).abs() <= 1e-5 * valence,
            "{valence} vs {excess}"
        );
    }

    #[test]
    fn training_lowers_every_loss_and_resumes_exactly() {
        let meshes = [2u32, 3].map(|s| {
            let m = meshgnn_geometry::icosphere(s);
            let v = m
                .vertices()
                .iter()
                .map(|p| [p[0] * 1.5, p[1], p[2] * 0.7])
                .collect();
            SimplifierExample::new(TriMesh::new(v, m.triangles().to_vec()).unwrap()).unwrap()
        });
        let fresh = || {
            SimplifierTraining::new(
                &small(),
                meshes.to_vec(),
                vec![meshes[1].clone()],
                (0.2, 0.3),
                4,
            )
            .unwrap()
        };
        let mut task = fresh();
        let before = task.losses(&meshes[1], 0.25, 0).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let config = TrainingConfig {
            epochs: 6,
            batch_size: 1,
            learning_rate: 3e-3,
            checkpoint: Some(dir.path().join("c.safetensors")),
            ..Default::default()
        };
        train(&mut task, &config, &mut |_| {}).unwrap();
        let after = task.losses(&meshes[1], 0.25, 0).unwrap();
        for (name, b, a) in [
            ("sampler", &before.sampler, &after.sampler),
            ("edges", &before.edges, &after.edges),
            ("faces", &before.faces, &after.faces),
        ] {
            let (b, a) = (b.to_scalar::<f32>().unwrap(), a.to_scalar::<f32>().unwrap());
            assert!(a < b, "{name}: {b} -> {a}");
        }
        // Three more epochs from the checkpoint equal nine at once.
        let mut resumed = fresh();
        let more = TrainingConfig {
            epochs: 9,
            resume: true,
            ..config.clone()
        };
        train(&mut resumed, &more, &mut |_| {}).unwrap();
        let mut straight = fresh();
        let once = TrainingConfig {
            epochs: 9,
            checkpoint: Some(dir.path().join("d.safetensors")),
            ..config
        };
        train(&mut straight, &once, &mut |_| {}).unwrap();
        let straight = straight.checkpoint().unwrap().tensors;
        let resumed = resumed.checkpoint().unwrap().tensors;
        assert_eq!(resumed.len(), straight.len());
        for (name, t) in resumed {
            let u = &straight[&name];
            let d: f32 = (t - u)
                .unwrap()
                .abs()
                .unwrap()
                .sum_all()
                .unwrap()
                .to_scalar()
                .unwrap();
            assert_eq!(d, 0.0, "{name}");
        }
    }
}
