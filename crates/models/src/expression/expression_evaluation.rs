//! Thesis Table 4.2 and Fig. 4.5: the generalisation error of an expression model on
//! subjects never trained on — mean per-vertex Euclidean distance (data units, mm) between
//! each generated frame and its ground truth, per expression and in total — and, beyond the
//! thesis, temporal jitter: the mean frame-to-frame acceleration `‖x_{t+1} − 2x_t + x_{t−1}‖`
//! per vertex, of the generated frames and of the ground truth.

use candle_core::Tensor;
use serde::Serialize;

use crate::expression::expression_training::mean_vertex_distance;
use crate::expression::{ExpressionModel, ExpressionSequences};
use crate::{Error, Result};

/// Table 4.2 of one model on one set of sequences.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ExpressionEvaluation {
    /// Mean per-vertex error (mm) per label channel (`None` when no sequence has it).
    pub per_expression_mm: [Option<f64>; 6],
    /// Mean per-vertex error (mm) over every frame.
    pub total_mm: f64,
    /// Mean per-vertex acceleration of the generated frames (mm / frame²).
    pub jitter_mm: f64,
    /// The same of the ground truth.
    pub truth_jitter_mm: f64,
    /// Frames evaluated.
    pub frames: usize,
    /// Sequences evaluated.
    pub sequences: usize,
}

/// Mean per-vertex `‖x_{t+1} − 2x_t + x_{t−1}‖` of `(1, T, V, 3)` displacements and the
/// number of triples (`T − 2`, or 0).
fn acceleration(x: &Tensor) -> Result<(f64, usize)> {
    let t = x.dim(1)?;
    if t < 3 {
        return Ok((0.0, 0));
    }
    let a = x.narrow(1, 2, t - 2)?;
    let b = x.narrow(1, 1, t - 2)?;
    let c = x.narrow(1, 0, t - 2)?;
    let second = ((a - (b * 2.0)?)? + c)?;
    let zero = second.zeros_like()?;
    Ok((mean_vertex_distance(&second, &zero)?, t - 2))
}

/// Evaluates `model` on `data` (each sequence generated from its labels and its subject's
/// neutral face).
///
/// ```
/// use meshgnn_models::expression::{evaluate_expressions, ExpressionGeneratorConfig, ExpressionModel, ExpressionSequence, ExpressionSequences};
/// let sphere = meshgnn_geometry::icosphere(2);
/// let cfg = ExpressionGeneratorConfig { channels: vec![8, 16], factors: vec![4.0; 2],
///     spiral_lengths: vec![9; 3], dilations: vec![1; 3], ..Default::default() };
/// let model = ExpressionModel::new(&sphere, &cfg, None, 0, &candle_core::Device::Cpu)?;
/// let neutral = sphere.vertices().to_vec();
/// let generated = model.generate(&[[0.0; 6]; 3], &neutral)?;
/// let data = ExpressionSequences { neutrals: vec![neutral],
///     sequences: vec![ExpressionSequence { subject: 0, expression: 2, labels: vec![[0.0; 6]; 3], frames: generated }] };
/// let e = evaluate_expressions(&model, &data)?;
/// assert!(e.total_mm < 1e-5 && e.per_expression_mm[0].is_none() && e.frames == 3);
/// # Ok::<(), meshgnn_models::Error>(())
/// ```
pub fn evaluate_expressions(
    model: &ExpressionModel,
    data: &ExpressionSequences,
) -> Result<ExpressionEvaluation> {
    let v = model.template().vertex_count();
    data.check("evaluation sequences", v)?;
    if data.sequences.is_empty() {
        return Err(Error::Invalid {
            what: "evaluation sequences".into(),
            reason: "none".into(),
        });
    }
    let device = model.device();
    let mut sums = [(0.0f64, 0usize); 6];
    let (mut jitter, mut truth_jitter, mut triples) = (0.0, 0.0, 0usize);
    for q in &data.sequences {
        let t = q.frames.len();
        let neutral = &data.neutrals[q.subject];
        let generated = model.generate(&q.labels, neutral)?;
        let to_tensor = |frames: &[Vec<[f32; 3]>]| -> Result<Tensor> {
            let flat: Vec<f32> = frames
                .iter()
                .flat_map(|f| {
                    f.iter()
                        .zip(neutral)
                        .flat_map(|(p, n)| [p[0] - n[0], p[1] - n[1], p[2] - n[2]])
                })
                .collect();
            Ok(Tensor::from_vec(flat, (1, t, v, 3), device)?)
        };
        let (predicted, truth) = (to_tensor(&generated)?, to_tensor(&q.frames)?);
        let error = mean_vertex_distance(&predicted, &truth)?;
        sums[q.expression].0 += error * t as f64;
        sums[q.expression].1 += t;
        let (j, n) = acceleration(&predicted)?;
        let (jt, _) = acceleration(&truth)?;
        jitter += j * n as f64;
        truth_jitter += jt * n as f64;
        triples += n;
    }
    let frames: usize = sums.iter().map(|s| s.1).sum();
    let total: f64 = sums.iter().map(|s| s.0).sum();
    let triples_f = triples.max(1) as f64;
    Ok(ExpressionEvaluation {
        per_expression_mm: sums.map(|(sum, n)| (n > 0).then(|| sum / n as f64)),
        total_mm: total / frames.max(1) as f64,
        jitter_mm: jitter / triples_f,
        truth_jitter_mm: truth_jitter / triples_f,
        frames,
        sequences: data.sequences.len(),
    })
}
