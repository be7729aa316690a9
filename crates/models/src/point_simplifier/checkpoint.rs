//! The point simplifier in the crate's checkpoint layout ([`crate::Checkpoint`]): the weights
//! and batch-norm statistics under their stable names, the [`PointSimplifierConfig`] entries as
//! the header's `config`. Files of the earlier `meshgnn-point-simplifier/1` layout (the bundled
//! weights) load unchanged.

use std::collections::HashMap;
use std::path::Path;

use candle_core::{DType, Device, Tensor};
use candle_nn::VarBuilder;
use serde_json::{Map, Value};

use super::{PointSimplifier, PointSimplifierConfig, SelectorSpace};
use crate::checkpoint::{checkpoint_error, checkpoint_of, read_file};
use crate::{Checkpoint, CheckpointHeader, Error, LoadCheckpoint, Result};

/// The model's name in checkpoints.
pub const POINT_SIMPLIFIER_NAME: &str = "point_simplifier";

/// The config entry of [`SelectorSpace`] (0 latent, 1 positions, 2 centroidal).
const SELECTOR_ENTRY: &str = "selector";

impl PointSimplifierConfig {
    /// A checkpoint header of this config (no training state).
    pub fn header(&self) -> CheckpointHeader {
        let mut config: Map<String, Value> = self
            .entries()
            .iter()
            .map(|(k, v)| ((*k).to_string(), Value::from(*v)))
            .collect();
        config.insert(SELECTOR_ENTRY.into(), Value::from(self.selector.code()));
        CheckpointHeader::new(POINT_SIMPLIFIER_NAME, config)
    }

    /// The config stored in `header` (read from `source`); errors when the header is another
    /// model's, a count entry is missing or the selector is unknown. Files written before the
    /// selector entry existed select in latent space.
    pub fn from_header(header: &CheckpointHeader, source: &Path) -> Result<Self> {
        header.expect_model(POINT_SIMPLIFIER_NAME, source)?;
        let mut config = Self::default();
        let keys: Vec<&'static str> = config.entries().iter().map(|e| e.0).collect();
        for key in keys {
            let value = header.config_count(key, source)?;
            config.set_entry(key, value);
        }
        if header.config.contains_key(SELECTOR_ENTRY) {
            let code = header.config_count(SELECTOR_ENTRY, source)?;
            config.selector = SelectorSpace::from_code(code).ok_or_else(|| {
                checkpoint_error(source, format!("unknown selector {code} in the config"))
            })?;
        }
        Ok(config)
    }
}

impl PointSimplifier {
    /// The model in `checkpoint` (read from `source`), on the CPU, with plain (non-trainable)
    /// tensors: inference builds no autograd graph.
    pub fn from_checkpoint(checkpoint: &Checkpoint, source: &Path) -> Result<Self> {
        let config = PointSimplifierConfig::from_header(&checkpoint.header, source)?;
        let weights: HashMap<String, Tensor> = checkpoint.model_tensors();
        let vb = VarBuilder::from_tensors(weights, DType::F32, &Device::Cpu);
        Self::new(vb, &config).map_err(|e| Error::Checkpoint {
            path: source.to_path_buf(),
            reason: format!("does not hold a complete model: {e}"),
        })
    }

    /// The model stored in safetensors `bytes` (`path` names it in errors).
    pub fn from_safetensors(bytes: &[u8], path: &Path) -> Result<Self> {
        Self::from_checkpoint(&Checkpoint::from_bytes(bytes, path)?, path)
    }

    /// Loads a checkpoint file written by training ([`crate::training::train`]).
    pub fn load(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let bytes = read_file(path)?;
        Self::from_safetensors(&bytes, path)
    }
}

impl LoadCheckpoint for PointSimplifier {
    fn from_checkpoint_bytes(bytes: &[u8], source: &Path) -> Result<Self> {
        Self::from_safetensors(bytes, source).map_err(|e| checkpoint_of(source, e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use candle_nn::VarMap;

    #[test]
    fn the_config_round_trips_through_the_header_and_a_file() {
        let config = PointSimplifierConfig {
            selector: SelectorSpace::Position,
            hidden: 8,
            attention_dim: 4,
            ..Default::default()
        };
        let header = config.header();
        let back = PointSimplifierConfig::from_header(&header, Path::new("h")).unwrap();
        assert_eq!(back, config);
        let map = VarMap::new();
        let model = PointSimplifier::new(
            VarBuilder::from_varmap(&map, DType::F32, &Device::Cpu),
            &config,
        )
        .unwrap();
        let tensors = crate::sorted_vars(&map)
            .into_iter()
            .map(|(n, v)| (n, v.as_detached_tensor()))
            .collect();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("w.safetensors");
        Checkpoint { header, tensors }.save(&path).unwrap();
        let loaded = PointSimplifier::load(&path).unwrap();
        assert_eq!(loaded.config(), model.config());
        let err = PointSimplifier::load(dir.path().join("none.safetensors")).unwrap_err();
        assert!(err.to_string().contains("none.safetensors"), "{err}");
    }

    #[test]
    fn a_header_without_selector_is_latent_and_an_unknown_one_is_refused() {
        let mut header = PointSimplifierConfig::default().header();
        header.config.remove(SELECTOR_ENTRY);
        let back = PointSimplifierConfig::from_header(&header, Path::new("old")).unwrap();
        assert_eq!(back.selector, SelectorSpace::Latent);
        header.config.insert(SELECTOR_ENTRY.into(), Value::from(7));
        let err = PointSimplifierConfig::from_header(&header, Path::new("new")).unwrap_err();
        assert!(err.to_string().contains("unknown selector 7"), "{err}");
    }

    #[test]
    fn another_models_checkpoint_is_refused() {
        let header = CheckpointHeader::new("pca", Map::new());
        let err = PointSimplifierConfig::from_header(&header, Path::new("p.st")).unwrap_err();
        assert!(err.to_string().contains("holds a pca model"), "{err}");
    }
}
