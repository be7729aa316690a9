//! Safetensors checkpoints of the point simplifier: the weights under their stable names, the
//! [`PointSimplifierConfig`] and the training position in the header metadata (string pairs),
//! and — for resumable training — the optimiser moments under `optimizer.{m,v}.<name>`.
//! Files are written atomically (temporary file in the same folder, then rename).

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use candle_core::{DType, Device, Tensor};
use candle_nn::VarBuilder;

use super::{PointSimplifier, PointSimplifierConfig};
use crate::{Error, Result};

/// Value of the `format` metadata key.
const FORMAT: &str = "meshgnn-point-simplifier/1";

/// Prefix of optimiser-state tensors (ignored when loading a model for inference).
pub(crate) const OPTIMIZER_PREFIX: &str = "optimizer.";

/// Where training stood when a checkpoint was written.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CheckpointState {
    /// Epochs completed.
    pub epoch: usize,
    /// Optimiser steps taken.
    pub step: u64,
    /// The training seed.
    pub seed: u64,
    /// Mean loss of the last completed epoch.
    pub loss: f64,
    /// Lowest validation loss recorded so far ([`super::Trainer::record_validation`]), if any.
    pub best_validation: Option<f64>,
}

/// A decoded checkpoint.
#[derive(Clone, Debug)]
pub struct Checkpoint {
    /// Every stored tensor by name (weights, batch-norm statistics, optimiser moments).
    pub tensors: HashMap<String, Tensor>,
    /// The model's hyper-parameters.
    pub config: PointSimplifierConfig,
    /// The training position, when the file was written by training.
    pub state: Option<CheckpointState>,
}

/// Writes `tensors` with `config` and `state` to `path` atomically.
///
/// ```
/// use candle_core::{Device, Tensor};
/// use meshgnn_models::point_simplifier::{PointSimplifierConfig, read_checkpoint, write_checkpoint};
/// let dir = tempfile::tempdir()?;
/// let path = dir.path().join("w.safetensors");
/// let t = Tensor::new(&[1.0f32, 2.0], &Device::Cpu)?;
/// write_checkpoint(&path, &[("a".to_string(), t)], &PointSimplifierConfig::default(), None)?;
/// let c = read_checkpoint(&std::fs::read(&path)?, &path)?;
/// assert_eq!(c.config.hidden, 64);
/// assert_eq!(c.tensors["a"].to_vec1::<f32>()?, vec![1.0, 2.0]);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn write_checkpoint(
    path: &Path,
    tensors: &[(String, Tensor)],
    config: &PointSimplifierConfig,
    state: Option<&CheckpointState>,
) -> Result<()> {
    let fail = |reason: String| Error::Checkpoint {
        path: path.to_path_buf(),
        reason,
    };
    let mut meta: HashMap<String, String> = config
        .entries()
        .iter()
        .map(|(k, v)| ((*k).to_string(), v.to_string()))
        .collect();
    meta.insert("format".into(), FORMAT.into());
    if let Some(s) = state {
        meta.insert("epoch".into(), s.epoch.to_string());
        meta.insert("step".into(), s.step.to_string());
        meta.insert("seed".into(), s.seed.to_string());
        meta.insert("loss".into(), format!("{:e}", s.loss));
        if let Some(v) = s.best_validation {
            meta.insert("best_validation".into(), format!("{v:e}"));
        }
    }
    let contiguous = tensors
        .iter()
        .map(|(k, t)| Ok((k.clone(), t.contiguous()?)))
        .collect::<Result<Vec<_>>>()?;
    let bytes = safetensors::serialize(contiguous.iter().map(|(k, t)| (k.as_str(), t)), Some(meta))
        .map_err(|e| fail(format!("cannot serialise: {e}")))?;
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "checkpoint".into());
    let tmp: PathBuf = dir.join(format!(".{name}.tmp{}", std::process::id()));
    std::fs::write(&tmp, &bytes)
        .map_err(|e| fail(format!("cannot write {}: {e}", tmp.display())))?;
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        fail(format!("cannot rename the temporary file into place: {e}"))
    })
}

/// Decodes a checkpoint from `bytes` (`path` names it in errors). Errors when the header or a
/// config field is missing or malformed.
pub fn read_checkpoint(bytes: &[u8], path: &Path) -> Result<Checkpoint> {
    let fail = |reason: String| Error::Checkpoint {
        path: path.to_path_buf(),
        reason,
    };
    let (_, header) = safetensors::SafeTensors::read_metadata(bytes)
        .map_err(|e| fail(format!("not a safetensors file: {e}")))?;
    let meta = header
        .metadata()
        .clone()
        .ok_or_else(|| fail("no metadata: not a point-simplifier checkpoint".into()))?;
    if meta.get("format").map(String::as_str) != Some(FORMAT) {
        return Err(fail(format!(
            "format {:?}, expected {FORMAT:?}",
            meta.get("format")
        )));
    }
    let get = |key: &str| -> Result<&String> {
        meta.get(key)
            .ok_or_else(|| fail(format!("metadata key {key:?} is missing")))
    };
    let num = |key: &str| -> Result<usize> {
        get(key)?
            .parse()
            .map_err(|e| fail(format!("metadata {key:?} is not a count: {e}")))
    };
    let config = PointSimplifierConfig {
        hidden: num("hidden")?,
        mlp_layers: num("mlp_layers")?,
        gnn_neighbours: num("gnn_neighbours")?,
        refine_neighbours: num("refine_neighbours")?,
        attention_dim: num("attention_dim")?,
        phi_hidden: num("phi_hidden")?,
        gamma_hidden: num("gamma_hidden")?,
    };
    let state = if meta.contains_key("epoch") {
        let parse_u64 = |key: &str| -> Result<u64> {
            get(key)?
                .parse()
                .map_err(|e| fail(format!("metadata {key:?}: {e}")))
        };
        Some(CheckpointState {
            epoch: num("epoch")?,
            step: parse_u64("step")?,
            seed: parse_u64("seed")?,
            loss: get("loss")?
                .parse()
                .map_err(|e| fail(format!("metadata \"loss\": {e}")))?,
            best_validation: meta
                .get("best_validation")
                .map(|v| v.parse())
                .transpose()
                .map_err(|e| fail(format!("metadata \"best_validation\": {e}")))?,
        })
    } else {
        None
    };
    let tensors = candle_core::safetensors::load_buffer(bytes, &Device::Cpu)
        .map_err(|e| fail(format!("cannot decode the tensors: {e}")))?;
    Ok(Checkpoint {
        tensors,
        config,
        state,
    })
}

impl PointSimplifier {
    /// The model stored in safetensors `bytes` (`path` names it in errors), on the CPU, with
    /// plain (non-trainable) tensors: inference builds no autograd graph.
    pub fn from_safetensors(bytes: &[u8], path: &Path) -> Result<Self> {
        let checkpoint = read_checkpoint(bytes, path)?;
        let weights: HashMap<String, Tensor> = checkpoint
            .tensors
            .into_iter()
            .filter(|(k, _)| !k.starts_with(OPTIMIZER_PREFIX))
            .collect();
        let vb = VarBuilder::from_tensors(weights, DType::F32, &Device::Cpu);
        Self::new(vb, &checkpoint.config).map_err(|e| Error::Checkpoint {
            path: path.to_path_buf(),
            reason: format!("does not hold a complete model: {e}"),
        })
    }

    /// Loads a checkpoint file written by training ([`write_checkpoint`]).
    pub fn load(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let bytes = std::fs::read(path).map_err(|e| Error::Checkpoint {
            path: path.to_path_buf(),
            reason: format!("cannot read: {e}"),
        })?;
        Self::from_safetensors(&bytes, path)
    }
}
