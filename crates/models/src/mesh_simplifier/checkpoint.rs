//! The neural mesh simplifier in the crate's checkpoint layout ([`crate::Checkpoint`]): the
//! weights under their stable names (`sampler.*`, `edges.*`, `faces.*`), the
//! [`NeuralMeshSimplifierConfig`] sizes as the header's `config`.

use std::collections::HashMap;
use std::path::Path;

use candle_core::{DType, Device, Tensor};
use candle_nn::VarBuilder;
use serde_json::{Map, Value};

use super::{NeuralMeshSimplifier, NeuralMeshSimplifierConfig};
use crate::checkpoint::{checkpoint_of, read_file};
use crate::{Checkpoint, CheckpointHeader, Error, LoadCheckpoint, Result, pretrained};

/// The model's name in checkpoints.
pub const NEURAL_MESH_SIMPLIFIER_NAME: &str = "neural_mesh_simplifier";

impl NeuralMeshSimplifierConfig {
    /// Every size as `(entry name, value)`.
    fn entries(&self) -> [(&'static str, usize); 8] {
        [
            ("sampler_hidden", self.sampler.hidden),
            ("sampler_layers", self.sampler.layers),
            ("edge_hidden", self.edges.hidden),
            ("edge_neighbours", self.edges.neighbours),
            ("candidate_neighbours", self.edges.candidate_neighbours),
            ("face_hidden", self.faces.hidden),
            ("face_layers", self.faces.layers),
            ("face_neighbours", self.faces.neighbours),
        ]
    }

    /// The field of entry `name` (module docs); `None` for an unknown name.
    fn entry_mut(&mut self, name: &str) -> Option<&mut usize> {
        Some(match name {
            "sampler_hidden" => &mut self.sampler.hidden,
            "sampler_layers" => &mut self.sampler.layers,
            "edge_hidden" => &mut self.edges.hidden,
            "edge_neighbours" => &mut self.edges.neighbours,
            "candidate_neighbours" => &mut self.edges.candidate_neighbours,
            "face_hidden" => &mut self.faces.hidden,
            "face_layers" => &mut self.faces.layers,
            "face_neighbours" => &mut self.faces.neighbours,
            _ => return None,
        })
    }

    /// A checkpoint header of this config (no training state).
    pub fn header(&self) -> CheckpointHeader {
        let config: Map<String, Value> = self
            .entries()
            .iter()
            .map(|(k, v)| ((*k).to_string(), Value::from(*v)))
            .collect();
        CheckpointHeader::new(NEURAL_MESH_SIMPLIFIER_NAME, config)
    }

    /// The config stored in `header` (read from `source`); errors when the header is another
    /// model's or an entry is missing.
    pub fn from_header(header: &CheckpointHeader, source: &Path) -> Result<Self> {
        header.expect_model(NEURAL_MESH_SIMPLIFIER_NAME, source)?;
        let mut config = Self::default();
        for (key, _) in Self::default().entries() {
            let value = header.config_count(key, source)?;
            if let Some(field) = config.entry_mut(key) {
                *field = value;
            }
        }
        Ok(config)
    }
}

impl NeuralMeshSimplifier {
    /// The model in `checkpoint` (read from `source`), on the CPU, with plain (non-trainable)
    /// tensors.
    pub fn from_checkpoint(checkpoint: &Checkpoint, source: &Path) -> Result<Self> {
        let config = NeuralMeshSimplifierConfig::from_header(&checkpoint.header, source)?;
        let weights: HashMap<String, Tensor> = checkpoint.model_tensors();
        let vb = VarBuilder::from_tensors(weights, DType::F32, &Device::Cpu);
        Self::new(vb, &config).map_err(|e| Error::Checkpoint {
            path: source.to_path_buf(),
            reason: format!("does not hold a complete model: {e}"),
        })
    }

    /// Loads a checkpoint file written by training ([`crate::training::train`]).
    pub fn load(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        Self::from_checkpoint_bytes(&read_file(path)?, path)
    }

    /// The checkpoint at `weights`, or the bundled weights without one.
    pub fn load_or_bundled(weights: Option<&Path>) -> Result<Self> {
        match weights {
            Some(path) => Self::load(path),
            None => pretrained::load(NEURAL_MESH_SIMPLIFIER_NAME),
        }
    }
}

impl LoadCheckpoint for NeuralMeshSimplifier {
    fn from_checkpoint_bytes(bytes: &[u8], source: &Path) -> Result<Self> {
        Self::from_checkpoint(&Checkpoint::from_bytes(bytes, source)?, source)
            .map_err(|e| checkpoint_of(source, e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh_simplifier::{EdgePredictorConfig, FaceClassifierConfig};
    use candle_nn::VarMap;

    #[test]
    fn the_config_round_trips_through_the_header_and_a_file() {
        let config = NeuralMeshSimplifierConfig {
            faces: FaceClassifierConfig {
                hidden: 16,
                ..Default::default()
            },
            edges: EdgePredictorConfig {
                candidate_neighbours: 9,
                ..Default::default()
            },
            ..Default::default()
        };
        let header = config.header();
        assert_eq!(
            NeuralMeshSimplifierConfig::from_header(&header, Path::new("h")).unwrap(),
            config
        );
        let map = VarMap::new();
        let model = NeuralMeshSimplifier::new(
            VarBuilder::from_varmap(&map, DType::F32, &Device::Cpu),
            &config,
        )
        .unwrap();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("w.safetensors");
        crate::checkpoint::vars_checkpoint(header, &map)
            .save(&path)
            .unwrap();
        let loaded = NeuralMeshSimplifier::load(&path).unwrap();
        assert_eq!(loaded.config(), model.config());
        let sphere = meshgnn_geometry::icosphere(2);
        let (a, b) = (
            model.simplify(&sphere, 40, 1, &Default::default()).unwrap(),
            loaded
                .simplify(&sphere, 40, 1, &Default::default())
                .unwrap(),
        );
        assert_eq!(a.mesh, b.mesh);
        let mut header = config.header();
        header.config.remove("face_hidden");
        let err = NeuralMeshSimplifierConfig::from_header(&header, Path::new("p.st")).unwrap_err();
        assert!(err.to_string().contains("face_hidden"), "{err}");
        let other = CheckpointHeader::new("pca", Map::new());
        assert!(NeuralMeshSimplifierConfig::from_header(&other, Path::new("p.st")).is_err());
    }
}
