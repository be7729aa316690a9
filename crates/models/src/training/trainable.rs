//! What a model trains: the contract between a model and the training loop
//! [`super::train`].

use std::path::Path;

use candle_core::{Tensor, Var};

use crate::{Checkpoint, Result};

/// Where the loop stands when it asks for a batch's loss.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StepContext {
    /// Current epoch (0-based).
    pub epoch: usize,
    /// Optimiser steps taken before this one (over all epochs).
    pub step: u64,
    /// Seed of the run (the checkpoint's when resuming).
    pub seed: u64,
}

/// The loss of one training batch.
#[derive(Clone, Debug)]
pub struct BatchLoss {
    /// The 0-d loss the optimiser minimises, attached to the parameters.
    pub loss: Tensor,
    /// A figure of the batch in the model's own units for progress reports (e.g. Handy++'s
    /// per-vertex error in mm), when the model has one.
    pub figure: Option<f64>,
}

/// A model with its training data, as the training loop sees it. Implementations must be
/// deterministic given the [`StepContext`], so a run is reproducible from its seed and a
/// resumed run equals an uninterrupted one.
pub trait Trainable {
    /// The model's name in checkpoints ([`crate::CheckpointHeader::model`]).
    fn model_name(&self) -> &'static str;

    /// Number of training examples; the loop shuffles `0..len` every epoch.
    fn train_len(&self) -> usize;

    /// The parameters Adam updates, in a fixed (name) order.
    fn parameters(&self) -> Vec<(String, Var)>;

    /// The loss of the training examples `batch` (indices into `0..train_len()`).
    fn batch_loss(&self, batch: &[usize], context: &StepContext) -> Result<BatchLoss>;

    /// A deterministic figure of the current weights on held-out data (lower is better), or
    /// `None` when there is no held-out data.
    fn validation(&self) -> Result<Option<f64>>;

    /// The model as a checkpoint (its tensors, name and config; no training state).
    fn checkpoint(&self) -> Result<Checkpoint>;

    /// Replaces the model's weights (and whatever else its checkpoint carries) with those of
    /// `checkpoint`, read from `source`; errors when it holds a different configuration.
    fn restore(&mut self, checkpoint: &Checkpoint, source: &Path) -> Result<()>;
}

/// The mean of the per-example `losses` of a batch (0-d tensors); errors on an empty batch.
pub fn batch_mean(losses: Vec<Tensor>) -> Result<Tensor> {
    let count = losses.len();
    let mut sum = losses.into_iter();
    let first = sum.next().ok_or_else(|| crate::Error::Invalid {
        what: "training batch".into(),
        reason: "empty".into(),
    })?;
    let total = sum.try_fold(first, |t, l| t + l)?;
    Ok(if count == 1 {
        total
    } else {
        total.affine(1.0 / count as f64, 0.0)?
    })
}
