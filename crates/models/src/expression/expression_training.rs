//! What the expression generator trains (thesis ch. 4.3): eq. 4.2, `L = L_r + L_c` (L1
//! reconstruction plus temporal coherence, `meshgnn_losses::losses`), on whole sequences,
//! in millimetres; validation is the mean per-vertex Euclidean error (mm) on held-out
//! subjects. The loop (Adam, lr 1e-3 × 0.99 per epoch, checkpoints, resuming) is
//! [`crate::training::train`]. The baseline trains the same way: only its decoder differs.

use std::path::Path;

use candle_core::{Device, Tensor, Var};
use meshgnn_geometry::TriMesh;
use meshgnn_losses::losses::{reconstruction_l1, temporal_coherence};

use crate::adam::sorted_vars;
use crate::expression::{
    Blendshapes, EXPRESSION_MODEL_NAME, ExpressionGeneratorConfig, ExpressionModel,
    ExpressionSequences,
};
use crate::training::{BatchLoss, StepContext, Trainable};
use crate::{Checkpoint, Result};

/// One sequence as tensors: labels `(1, T, 6)` and displacements from neutral `(1, T, V, 3)`.
struct SequenceTensors {
    labels: Tensor,
    displacements: Tensor,
}

fn sequence_tensors(data: &ExpressionSequences, device: &Device) -> Result<Vec<SequenceTensors>> {
    let displacements = data.displacements();
    let mut at = 0;
    data.sequences
        .iter()
        .map(|q| {
            let t = q.frames.len();
            let v = q.frames.first().map_or(0, Vec::len);
            let d: Vec<f32> = displacements[at..at + t]
                .iter()
                .flatten()
                .flatten()
                .copied()
                .collect();
            at += t;
            Ok(SequenceTensors {
                labels: Tensor::from_vec(q.labels.concat(), (1, t, 6), device)?,
                displacements: Tensor::from_vec(d, (1, t, v, 3), device)?,
            })
        })
        .collect()
}

/// Eq. 4.2 of `predicted` against `target`, both `(1, T, V, 3)`: `L_r`, plus `L_c` when the
/// sequence has two frames or more.
pub fn expression_loss(predicted: &Tensor, target: &Tensor) -> Result<Tensor> {
    let reconstruction = reconstruction_l1(predicted, target)?;
    if predicted.dim(1)? < 2 {
        return Ok(reconstruction);
    }
    Ok((reconstruction + temporal_coherence(predicted, target)?)?)
}

/// Mean per-vertex Euclidean distance of `(…, 3)` tensors, as a number.
pub(crate) fn mean_vertex_distance(a: &Tensor, b: &Tensor) -> Result<f64> {
    let d = a
        .sub(b)?
        .sqr()?
        .sum_keepdim(candle_core::D::Minus1)?
        .sqrt()?;
    Ok(f64::from(d.mean_all()?.to_scalar::<f32>()?))
}

/// Refuses sequences that are not finite, labelled in range and on `template`'s vertices.
fn check_sequences(
    template: &TriMesh,
    train: &ExpressionSequences,
    validation: &ExpressionSequences,
) -> Result<()> {
    let v = template.vertex_count();
    train.check("training sequences", v)?;
    validation.check("validation sequences", v)
}

/// The blendshapes a decoder of `config` needs: `given` when there are, else fitted on the
/// training displacements; none for the spiral decoder.
fn blendshapes_for(
    config: &ExpressionGeneratorConfig,
    template: &TriMesh,
    train: &ExpressionSequences,
    given: Option<&Blendshapes>,
) -> Result<Option<Blendshapes>> {
    Ok(match (config.decoder.uses_blendshapes(), given) {
        (false, _) => None,
        (true, Some(b)) => Some(b.clone()),
        (true, None) => Some(Blendshapes::fit(
            template,
            &train.displacements(),
            config.hidden_size,
        )?),
    })
}

/// An expression model with its training and validation sequences.
pub struct ExpressionTraining {
    model: ExpressionModel,
    template: TriMesh,
    train: Vec<SequenceTensors>,
    validation: Vec<SequenceTensors>,
    device: Device,
}

impl ExpressionTraining {
    /// A fresh model of `config` (weights from `seed`) on `template`, to be trained on `train`
    /// and validated on `validation` (may be empty). The blendshape decoder's blendshapes are
    /// fitted here, on the training displacements.
    ///
    /// ```
    /// use candle_core::Device;
    /// use meshgnn_models::expression::{ExpressionGeneratorConfig, ExpressionSequence, ExpressionSequences, ExpressionTraining};
    /// use meshgnn_models::training::{TrainingConfig, train};
    /// let sphere = meshgnn_geometry::icosphere(2);
    /// let smile = |a: f32| sphere.vertices().iter().map(|p| [p[0], p[1] + a * p[0] * p[0], p[2]]).collect::<Vec<_>>();
    /// let labels: Vec<[f32; 6]> = [0.0, 0.5, 1.0].iter().map(|&a| [a, 0.0, 0.0, 0.0, 0.0, 0.0]).collect();
    /// let data = ExpressionSequences {
    ///     neutrals: vec![smile(0.0)],
    ///     sequences: vec![ExpressionSequence { subject: 0, expression: 0, labels,
    ///         frames: vec![smile(0.0), smile(0.1), smile(0.2)] }],
    /// };
    /// let cfg = ExpressionGeneratorConfig { channels: vec![8, 16], factors: vec![4.0; 2],
    ///     spiral_lengths: vec![9; 3], dilations: vec![1; 3], ..Default::default() };
    /// let mut task = ExpressionTraining::new(&sphere, &cfg, &data, &data, 0, &Device::Cpu)?;
    /// let run = train(&mut task, &TrainingConfig { epochs: 2, batch_size: 1, ..Default::default() }, &mut |_| {})?;
    /// assert!(run.history[1].validation.is_some());
    /// # Ok::<(), meshgnn_models::Error>(())
    /// ```
    pub fn new(
        template: &TriMesh,
        config: &ExpressionGeneratorConfig,
        train: &ExpressionSequences,
        validation: &ExpressionSequences,
        seed: u64,
        device: &Device,
    ) -> Result<Self> {
        check_sequences(template, train, validation)?;
        let blendshapes = blendshapes_for(config, template, train, None)?;
        let model = ExpressionModel::new(template, config, blendshapes, seed, device)?;
        Self::with_model(model, train, validation)
    }

    /// Like [`Self::new`], but every parameter `init` (read from `path`) has under the same
    /// name and shape starts at its value, and a decoder with blendshapes takes `init`'s
    /// when it has them: the residual decoder then starts as the trained baseline `init`.
    /// Also returns how many parameters were taken.
    pub fn starting_from(
        init: &ExpressionModel,
        path: &Path,
        config: &ExpressionGeneratorConfig,
        train: &ExpressionSequences,
        validation: &ExpressionSequences,
        seed: u64,
    ) -> Result<(Self, usize)> {
        let template = init.template();
        check_sequences(template, train, validation)?;
        let blendshapes = blendshapes_for(config, template, train, init.blendshapes())?;
        let model = ExpressionModel::new(template, config, blendshapes, seed, init.device())?;
        let taken = model.initialize_from(init, path)?;
        Ok((Self::with_model(model, train, validation)?, taken))
    }

    /// Training of `model` as it stands.
    fn with_model(
        model: ExpressionModel,
        train: &ExpressionSequences,
        validation: &ExpressionSequences,
    ) -> Result<Self> {
        let device = model.device().clone();
        Ok(Self {
            template: model.template().clone(),
            train: sequence_tensors(train, &device)?,
            validation: sequence_tensors(validation, &device)?,
            model,
            device,
        })
    }

    /// The model being trained.
    pub fn model(&self) -> &ExpressionModel {
        &self.model
    }

    /// The trained model.
    pub fn into_model(self) -> ExpressionModel {
        self.model
    }
}

impl Trainable for ExpressionTraining {
    fn model_name(&self) -> &'static str {
        EXPRESSION_MODEL_NAME
    }

    fn train_len(&self) -> usize {
        self.train.len()
    }

    fn parameters(&self) -> Vec<(String, Var)> {
        sorted_vars(self.model.vars())
    }

    /// Eq. 4.2 averaged over the batch's sequences; the figure is the mean per-vertex error
    /// (mm).
    fn batch_loss(&self, batch: &[usize], _: &StepContext) -> Result<BatchLoss> {
        let mut total: Option<Tensor> = None;
        let mut mm = 0.0;
        for &i in batch {
            let Some(q) = self.train.get(i) else { continue };
            let predicted = self.model.network().displacements(&q.labels)?;
            let loss = expression_loss(&predicted, &q.displacements)?;
            mm += mean_vertex_distance(&predicted.detach(), &q.displacements)?;
            total = Some(match total {
                Some(t) => (t + loss)?,
                None => loss,
            });
        }
        let n = batch.len().max(1) as f64;
        let loss = match total {
            Some(t) => (t / n)?,
            None => Tensor::new(0f32, &self.device)?,
        };
        Ok(BatchLoss {
            loss,
            figure: Some(mm / n),
        })
    }

    /// Mean per-vertex Euclidean error (mm) over every validation frame.
    fn validation(&self) -> Result<Option<f64>> {
        if self.validation.is_empty() {
            return Ok(None);
        }
        let (mut sum, mut frames) = (0.0, 0usize);
        for q in &self.validation {
            let predicted = self.model.network().displacements(&q.labels)?.detach();
            let t = q.labels.dim(1)?;
            sum += t as f64 * mean_vertex_distance(&predicted, &q.displacements)?;
            frames += t;
        }
        Ok(Some(sum / frames.max(1) as f64))
    }

    fn checkpoint(&self) -> Result<Checkpoint> {
        self.model.to_checkpoint()
    }

    /// The checkpoint's model; it must have this config and template faces.
    fn restore(&mut self, checkpoint: &Checkpoint, source: &Path) -> Result<()> {
        let model = ExpressionModel::from_checkpoint(checkpoint, source, &self.device)?;
        crate::checkpoint::check_resumable(
            source,
            (model.config(), model.template().triangles()),
            (self.model.config(), self.template.triangles()),
        )?;
        self.model = model;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::expression::{DecoderKind, ExpressionSequence, evaluate_expressions};
    use crate::training::{TrainingConfig, train};

    /// Two subjects (the second 10% wider) opening a "jaw" (a rotation of the lower half about
    /// the x axis) over five frames, labelled on channel 2.
    fn jaw_sequences(sphere: &TriMesh) -> ExpressionSequences {
        let face = |width: f32, angle: f32| -> Vec<[f32; 3]> {
            sphere
                .vertices()
                .iter()
                .map(|p| {
                    let (s, c) = (angle * (-p[1]).max(0.0)).sin_cos();
                    [
                        10.0 * width * p[0],
                        10.0 * (c * p[1] - s * p[2]),
                        10.0 * (s * p[1] + c * p[2]),
                    ]
                })
                .collect()
        };
        let motion = [0.0f32, 0.5, 1.0, 0.5, 0.0];
        let sequence = |subject: usize, width: f32| ExpressionSequence {
            subject,
            expression: 2,
            labels: motion
                .iter()
                .map(|&m| [0.0, 0.0, m, 0.0, 0.0, 0.0])
                .collect(),
            frames: motion.iter().map(|&m| face(width, 0.6 * m)).collect(),
        };
        ExpressionSequences {
            neutrals: vec![face(1.0, 0.0), face(1.1, 0.0)],
            sequences: vec![sequence(0, 1.0), sequence(1, 1.1)],
        }
    }

    fn tiny(decoder: DecoderKind, data: &ExpressionSequences) -> ExpressionGeneratorConfig {
        ExpressionGeneratorConfig {
            // this data has two blendshapes of non-zero variance: the other 14 are zero
            hidden_size: 16,
            decoder,
            channels: vec![8, 16],
            factors: vec![4.0; 2],
            spiral_lengths: vec![9; 3],
            dilations: vec![1; 3],
            displacement_scale: data.displacement_rms(),
        }
    }

    #[test]
    fn a_few_steps_lower_the_loss_for_every_decoder_and_resume_bit_exactly() {
        let sphere = meshgnn_geometry::icosphere(2);
        let data = jaw_sequences(&sphere);
        for decoder in [
            DecoderKind::Spiral,
            DecoderKind::Blendshape,
            DecoderKind::Residual,
        ] {
            let config = tiny(decoder, &data);
            let mut task =
                ExpressionTraining::new(&sphere, &config, &data, &data, 3, &Device::Cpu).unwrap();
            let before = evaluate_expressions(task.model(), &data).unwrap().total_mm;
            let run = train(
                &mut task,
                &TrainingConfig {
                    epochs: 150,
                    batch_size: 1,
                    learning_rate: 3e-3,
                    ..Default::default()
                },
                &mut |_| {},
            )
            .unwrap();
            let after = evaluate_expressions(task.model(), &data).unwrap();
            assert!(
                after.total_mm < 0.75 * before,
                "{decoder:?}: {before} mm -> {} mm",
                after.total_mm
            );
            assert!(run.history[149].loss < run.history[0].loss);
            assert_eq!(after.per_expression_mm.iter().flatten().count(), 1);
            // The checkpoint holds the same model.
            let dir = tempfile::tempdir().unwrap();
            let path = dir.path().join("m.safetensors");
            task.model().save(&path).unwrap();
            let back = ExpressionModel::load(&path, &Device::Cpu).unwrap();
            let labels = &data.sequences[0].labels;
            assert_eq!(
                back.generate(labels, &data.neutrals[1]).unwrap(),
                task.model().generate(labels, &data.neutrals[1]).unwrap()
            );
            assert_eq!(back.blendshapes().is_some(), decoder.uses_blendshapes());
        }
    }

    #[test]
    fn a_residual_model_started_from_a_baseline_is_that_baseline_until_trained() {
        let sphere = meshgnn_geometry::icosphere(2);
        let data = jaw_sequences(&sphere);
        let mut baseline = ExpressionTraining::new(
            &sphere,
            &tiny(DecoderKind::Blendshape, &data),
            &data,
            &data,
            1,
            &Device::Cpu,
        )
        .unwrap();
        let config = TrainingConfig {
            epochs: 20,
            batch_size: 1,
            learning_rate: 3e-3,
            ..Default::default()
        };
        train(&mut baseline, &config, &mut |_| {}).unwrap();
        let path = Path::new("baseline.safetensors");
        let (mut residual, taken) = ExpressionTraining::starting_from(
            baseline.model(),
            path,
            &tiny(DecoderKind::Residual, &data),
            &data,
            &data,
            2,
        )
        .unwrap();
        // the LSTM's four tensors and the blendshape weights and bias
        assert_eq!(taken, 6);
        let (labels, neutral) = (&data.sequences[1].labels, &data.neutrals[1]);
        let expected = baseline.model().generate(labels, neutral).unwrap();
        assert_eq!(
            residual.model().generate(labels, neutral).unwrap(),
            expected
        );
        let before = evaluate_expressions(residual.model(), &data)
            .unwrap()
            .total_mm;
        train(&mut residual, &config, &mut |_| {}).unwrap();
        let after = evaluate_expressions(residual.model(), &data)
            .unwrap()
            .total_mm;
        assert!(after < before, "{before} mm -> {after} mm");
        // another template is refused, naming the file
        let flipped = sphere
            .triangles()
            .iter()
            .map(|&[a, b, c]| [a, c, b])
            .collect();
        let other = TriMesh::new(sphere.vertices().to_vec(), flipped).unwrap();
        let model = ExpressionModel::new(
            &other,
            &tiny(DecoderKind::Spiral, &data),
            None,
            0,
            &Device::Cpu,
        )
        .unwrap();
        let error = residual.model().initialize_from(&model, path).unwrap_err();
        assert!(
            error.to_string().contains("baseline.safetensors"),
            "{error}"
        );
    }

    #[test]
    fn bad_data_is_refused() {
        let sphere = meshgnn_geometry::icosphere(2);
        let mut data = jaw_sequences(&sphere);
        let config = tiny(DecoderKind::Spiral, &data);
        data.sequences[0].labels.pop();
        assert!(ExpressionTraining::new(&sphere, &config, &data, &data, 0, &Device::Cpu).is_err());
        let mut data = jaw_sequences(&sphere);
        data.sequences[1].frames[2][7][0] = f32::NAN;
        assert!(ExpressionTraining::new(&sphere, &config, &data, &data, 0, &Device::Cpu).is_err());
        let mut data = jaw_sequences(&sphere);
        data.sequences[1].labels[2][0] = 1.5;
        assert!(ExpressionTraining::new(&sphere, &config, &data, &data, 0, &Device::Cpu).is_err());
    }
}
