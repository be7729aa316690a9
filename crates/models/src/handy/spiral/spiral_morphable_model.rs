//! "Handy++" as a usable morphable model (thesis ch. 3.3.4): the spiral autoencoder, its
//! template tensors, the per-vertex normalisation of the training data and the config, saved
//! together in one self-contained safetensors file. Encodes and decodes in data units
//! (millimetres for the synthetic hands).
//!
//! # File format: a [`crate::Checkpoint`] of model [`SPIRAL_MODEL_NAME`]
//! - Tensors: the network parameters (names in [`crate::handy::spiral::SpiralAutoencoder`]'s
//!   docs), `normalization.mean` / `normalization.std` `(V, 3)` f32, the template under
//!   `template.` (table in [`crate::handy::spiral::TemplateTensors`]'s docs) and, with
//!   `linear_skip`, the PCA path under `skip.` ([`LinearSkip`]).
//! - Header: `config` = the [`SpiralAutoencoderConfig`]; training checkpoints add the
//!   training state, `handy` adds the latent Gaussian as an entry. Files of the earlier
//!   `meshgnn.spiral_morphable_model.v1` layout (the bundled Handy++) load unchanged.

use std::collections::HashMap;
use std::path::Path;

use candle_core::{DType, Device, Tensor};
use candle_nn::{VarBuilder, VarMap};
use meshgnn_geometry::TriMesh;

use crate::checkpoint::{checkpoint_of, lock, set_vars, zero_vars};
use crate::handy::spiral::{
    LinearSkip, SpiralAutoencoder, SpiralAutoencoderConfig, SpiralDecoder, TemplateTensors,
    VertexNormalization, seeded_initialization,
};
use crate::{Checkpoint, CheckpointHeader, Error, LoadCheckpoint, MorphableModel, Result};

/// The model's name in checkpoints.
pub const SPIRAL_MODEL_NAME: &str = "spiral_morphable_model";

const TEMPLATE_PREFIX: &str = "template.";
const MEAN: &str = "normalization.mean";
const STD: &str = "normalization.std";

/// Spiral autoencoder + template + normalisation + config: a complete neural morphable model.
pub struct SpiralMorphableModel {
    config: SpiralAutoencoderConfig,
    template: TemplateTensors,
    normalization: VertexNormalization,
    network: SpiralAutoencoder,
    vars: VarMap,
}

impl std::fmt::Debug for SpiralMorphableModel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SpiralMorphableModel")
            .field("config", &self.config)
            .field("vertices", &self.network.vertex_count())
            .finish_non_exhaustive()
    }
}

impl SpiralMorphableModel {
    /// A freshly initialised model (weights from `seed`) on `template`, whose hierarchy is
    /// built from `config.hierarchy_options()`; `normalization` is usually
    /// [`VertexNormalization::fit`] of the training meshes, `skip` the PCA path a
    /// `linear_skip` config needs ([`LinearSkip::from_pca`]; then the model starts as that PCA).
    ///
    /// ```
    /// use candle_core::Device;
    /// use meshgnn_models::MorphableModel;
    /// use meshgnn_models::spiral::{SpiralAutoencoderConfig, SpiralMorphableModel, VertexNormalization};
    /// let sphere = meshgnn_geometry::icosphere(2);
    /// let cfg = SpiralAutoencoderConfig { channels: vec![8, 16], factors: vec![4.0; 2],
    ///     spiral_lengths: vec![9; 3], dilations: vec![1; 3], ..Default::default() };
    /// let norm = VertexNormalization::fit(&[sphere.vertices().to_vec()], &Device::Cpu)?;
    /// let model = SpiralMorphableModel::new(&sphere, &cfg, norm, None, 0, &Device::Cpu)?;
    /// assert_eq!((model.latent_size(), model.template().vertex_count()), (8, 162));
    /// # Ok::<(), meshgnn_models::Error>(())
    /// ```
    pub fn new(
        template: &TriMesh,
        config: &SpiralAutoencoderConfig,
        normalization: VertexNormalization,
        skip: Option<LinearSkip>,
        seed: u64,
        device: &Device,
    ) -> Result<Self> {
        config.validate(None)?;
        let tensors = TemplateTensors::new(template, &config.hierarchy_options(), device)?;
        let model = Self::assemble(tensors, config, normalization, skip)?;
        seeded_initialization(&model.vars, seed)?;
        if config.linear_skip {
            // the spiral halves' last maps start at zero: the fresh model is its PCA path
            let output = format!("decoder.{}.", SpiralDecoder::OUTPUT_LAYER);
            zero_vars(&model.vars, &["encoder.latent.".to_string(), output])?;
        }
        Ok(model)
    }

    fn assemble(
        template: TemplateTensors,
        config: &SpiralAutoencoderConfig,
        normalization: VertexNormalization,
        skip: Option<LinearSkip>,
    ) -> Result<Self> {
        let v = template.template().vertex_count();
        if normalization.mean().dims() != [v, 3] {
            return Err(Error::Invalid {
                what: "vertex normalisation".into(),
                reason: format!(
                    "shape {:?}, the template has {v} vertices",
                    normalization.mean().dims()
                ),
            });
        }
        let device = template.device().clone();
        let normalization = VertexNormalization::from_tensors(
            normalization.mean().to_device(&device)?,
            normalization.std().to_device(&device)?,
        )?;
        let vars = VarMap::new();
        let network = SpiralAutoencoder::new(
            VarBuilder::from_varmap(&vars, DType::F32, &device),
            config,
            &template,
            skip,
        )?;
        Ok(Self {
            config: config.clone(),
            template,
            normalization,
            network,
            vars,
        })
    }

    /// The network's hyper-parameters.
    pub fn config(&self) -> &SpiralAutoencoderConfig {
        &self.config
    }

    /// The template hierarchy tensors.
    pub fn template_tensors(&self) -> &TemplateTensors {
        &self.template
    }

    /// The per-vertex normalisation of the training data.
    pub fn normalization(&self) -> &VertexNormalization {
        &self.normalization
    }

    /// The autoencoder, working on normalised coordinates.
    pub fn network(&self) -> &SpiralAutoencoder {
        &self.network
    }

    /// The trainable parameters (for an optimiser).
    pub fn vars(&self) -> &VarMap {
        &self.vars
    }

    /// Decode of encode in data units: `vertices: (B, V, 3)` → `(B, V, 3)`.
    pub fn reconstruct(&self, vertices: &Tensor) -> Result<Tensor> {
        self.decode(&self.encode(vertices)?)
    }

    /// The model as a checkpoint ([`crate::Checkpoint`]): the network's parameters, the
    /// normalisation, the template tensors, and the config as the header's `config`.
    pub fn to_checkpoint(&self) -> Result<Checkpoint> {
        let mut tensors = self.template.to_named_tensors(TEMPLATE_PREFIX)?;
        tensors.insert(
            MEAN.into(),
            self.normalization.mean().to_device(&Device::Cpu)?,
        );
        tensors.insert(
            STD.into(),
            self.normalization.std().to_device(&Device::Cpu)?,
        );
        for (name, var) in lock(&self.vars)?.iter() {
            tensors.insert(name.clone(), var.as_tensor().to_device(&Device::Cpu)?);
        }
        if let Some(skip) = self.network.linear_skip() {
            tensors.extend(skip.to_named_tensors()?);
        }
        let config = match serde_json::to_value(&self.config) {
            Ok(serde_json::Value::Object(config)) => config,
            Ok(_) => serde_json::Map::new(),
            Err(e) => {
                return Err(Error::Invalid {
                    what: "model config".into(),
                    reason: format!("cannot serialise: {e}"),
                });
            }
        };
        Ok(Checkpoint {
            header: CheckpointHeader::new(SPIRAL_MODEL_NAME, config),
            tensors,
        })
    }

    /// The model file's bytes (a checkpoint without training state; deterministic).
    pub fn to_bytes(&self) -> Result<Vec<u8>> {
        self.to_checkpoint()?.to_bytes()
    }

    /// Writes the model to `path` atomically (temporary file + rename).
    pub fn save(&self, path: &Path) -> Result<()> {
        self.to_checkpoint()?.save(path)
    }

    /// Reads a model checkpoint (any layout [`CheckpointHeader::from_bytes`] reads) onto
    /// `device`; errors name the file and the missing or malformed tensor.
    pub fn load(path: &Path, device: &Device) -> Result<Self> {
        let bytes = crate::checkpoint::read_file(path)?;
        Self::decode(&bytes, path, device).map_err(|e| checkpoint_of(path, e))
    }

    /// A model from the bytes of a model file (e.g. weights embedded with `include_bytes!`).
    ///
    /// ```
    /// use candle_core::{Device, Tensor};
    /// use meshgnn_models::MorphableModel;
    /// use meshgnn_models::spiral::{SpiralAutoencoderConfig, SpiralMorphableModel, VertexNormalization};
    /// let sphere = meshgnn_geometry::icosphere(2);
    /// let cfg = SpiralAutoencoderConfig { channels: vec![8, 16], factors: vec![4.0; 2],
    ///     spiral_lengths: vec![9; 3], dilations: vec![1; 3], ..Default::default() };
    /// let norm = VertexNormalization::fit(&[sphere.vertices().to_vec()], &Device::Cpu)?;
    /// let model = SpiralMorphableModel::new(&sphere, &cfg, norm, None, 0, &Device::Cpu)?;
    /// let copy = SpiralMorphableModel::from_bytes(&model.to_bytes()?, &Device::Cpu)?;
    /// let z = Tensor::ones((1, 8), candle_core::DType::F32, &Device::Cpu)?;
    /// let (a, b) = (model.decode(&z)?, copy.decode(&z)?);
    /// assert_eq!(a.flatten_all()?.to_vec1::<f32>()?, b.flatten_all()?.to_vec1::<f32>()?);
    /// # Ok::<(), meshgnn_models::Error>(())
    /// ```
    pub fn from_bytes(bytes: &[u8], device: &Device) -> Result<Self> {
        Self::decode(bytes, Path::new("model file"), device)
    }

    /// The model in `bytes` read from `source`.
    fn decode(bytes: &[u8], source: &Path, device: &Device) -> Result<Self> {
        let checkpoint = Checkpoint::from_bytes(bytes, source)?;
        Self::from_checkpoint(&checkpoint, source, device)
    }

    /// The model stored in `checkpoint` (read from `source`), on `device`.
    pub fn from_checkpoint(
        checkpoint: &Checkpoint,
        source: &Path,
        device: &Device,
    ) -> Result<Self> {
        checkpoint.header.expect_model(SPIRAL_MODEL_NAME, source)?;
        let invalid = |reason: String| Error::Invalid {
            what: "model file".into(),
            reason,
        };
        let config: SpiralAutoencoderConfig =
            serde_json::from_value(serde_json::Value::Object(checkpoint.header.config.clone()))
                .map_err(|e| invalid(format!("bad `config`: {e}")))?;
        config.validate(None)?;
        let tensors: HashMap<String, Tensor> = checkpoint
            .model_tensors()
            .into_iter()
            .map(|(k, t)| Ok((k, t.to_device(device)?)))
            .collect::<Result<_>>()?;
        let template = TemplateTensors::from_named_tensors(&tensors, TEMPLATE_PREFIX, device)?;
        let get = |name: &str| {
            tensors.get(name).cloned().ok_or_else(|| Error::Invalid {
                what: format!("tensor `{name}`"),
                reason: "missing from the model file".into(),
            })
        };
        let normalization = VertexNormalization::from_tensors(get(MEAN)?, get(STD)?)?;
        let skip = match config.linear_skip {
            true => Some(LinearSkip::from_named_tensors(&tensors, device)?),
            false => None,
        };
        let model = Self::assemble(template, &config, normalization, skip)?;
        set_vars(&model.vars, &tensors)?;
        Ok(model)
    }
}

impl LoadCheckpoint for SpiralMorphableModel {
    /// On the CPU.
    fn from_checkpoint_bytes(bytes: &[u8], source: &Path) -> Result<Self> {
        Self::decode(bytes, source, &Device::Cpu).map_err(|e| checkpoint_of(source, e))
    }
}

impl MorphableModel for SpiralMorphableModel {
    fn latent_size(&self) -> usize {
        self.network.latent_size()
    }

    fn template(&self) -> &TriMesh {
        self.template.template()
    }

    /// `vertices: (B, V, 3)` in data units → `(B, Z)`.
    fn encode(&self, vertices: &Tensor) -> Result<Tensor> {
        let v = self.network.vertex_count();
        if vertices.dims().len() != 3 || vertices.dim(1).ok() != Some(v) {
            return Err(Error::Invalid {
                what: "vertices".into(),
                reason: format!("shape {:?}, expected (B, {v}, 3)", vertices.dims()),
            });
        }
        let x = self
            .normalization
            .normalize(&vertices.to_dtype(DType::F32)?)?;
        self.network.encode(&x)
    }

    /// `latents: (B, Z)` → `(B, V, 3)` in data units.
    fn decode(&self, latents: &Tensor) -> Result<Tensor> {
        let y = self.network.decode(&latents.to_dtype(DType::F32)?)?;
        self.normalization.denormalize(&y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::handy::spiral::mesh_batch;
    use crate::handy::spiral::test_fixtures::{deformed_shapes, tiny_config};

    fn model(seed: u64) -> (SpiralMorphableModel, Tensor) {
        let sphere = meshgnn_geometry::icosphere(2);
        let shapes = deformed_shapes(&sphere, 4);
        let norm = VertexNormalization::fit(&shapes, &Device::Cpu).unwrap();
        let m = SpiralMorphableModel::new(&sphere, &tiny_config(8), norm, None, seed, &Device::Cpu)
            .unwrap();
        (m, mesh_batch(&shapes, &Device::Cpu).unwrap())
    }

    fn values(t: &Tensor) -> Vec<f32> {
        t.flatten_all().unwrap().to_vec1().unwrap()
    }

    #[test]
    fn save_load_round_trip_is_bit_identical() {
        let (m, x) = model(3);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("hand.safetensors");
        m.save(&path).unwrap();
        let back = SpiralMorphableModel::load(&path, &Device::Cpu).unwrap();
        assert_eq!(back.config(), m.config());
        assert_eq!(
            back.template_tensors().hierarchy(),
            m.template_tensors().hierarchy()
        );
        assert_eq!(
            values(&back.encode(&x).unwrap()),
            values(&m.encode(&x).unwrap())
        );
        assert_eq!(
            values(&back.reconstruct(&x).unwrap()),
            values(&m.reconstruct(&x).unwrap())
        );
        // The same seed gives the same weights; another seed does not.
        assert_eq!(
            values(&model(3).0.encode(&x).unwrap()),
            values(&m.encode(&x).unwrap())
        );
        assert_ne!(
            values(&model(4).0.encode(&x).unwrap()),
            values(&m.encode(&x).unwrap())
        );
        // Saving is deterministic.
        assert_eq!(m.to_bytes().unwrap(), back.to_bytes().unwrap());
    }

    #[test]
    fn missing_or_malformed_tensors_are_named() {
        let (m, _) = model(0);
        let bytes = m.to_bytes().unwrap();
        let parsed = safetensors::SafeTensors::deserialize(&bytes).unwrap();
        let metadata = safetensors::SafeTensors::read_metadata(&bytes)
            .unwrap()
            .1
            .metadata()
            .clone();
        for dropped in [
            "encoder.conv1.weight",
            "template.pool0.up_weights",
            "normalization.std",
        ] {
            let kept: Vec<(String, safetensors::tensor::TensorView)> = parsed
                .tensors()
                .into_iter()
                .filter(|(n, _)| n != dropped)
                .collect();
            let broken = safetensors::tensor::serialize(kept, metadata.clone()).unwrap();
            let dir = tempfile::tempdir().unwrap();
            let path = dir.path().join("broken.safetensors");
            std::fs::write(&path, &broken).unwrap();
            let err = SpiralMorphableModel::load(&path, &Device::Cpu)
                .unwrap_err()
                .to_string();
            assert!(
                err.contains(dropped) && err.contains("broken.safetensors"),
                "{err}"
            );
        }
        assert!(SpiralMorphableModel::from_bytes(&bytes[..bytes.len() / 2], &Device::Cpu).is_err());
        assert!(SpiralMorphableModel::from_bytes(b"not a model", &Device::Cpu).is_err());
        let err =
            SpiralMorphableModel::load(Path::new("/nonexistent/model.safetensors"), &Device::Cpu)
                .unwrap_err();
        assert!(err.to_string().contains("/nonexistent/model.safetensors"));
    }

    #[test]
    fn data_units_and_shape_checks() {
        let (m, x) = model(1);
        assert_eq!(m.latent_size(), 8);
        assert_eq!(m.template().vertex_count(), 162);
        let z = m.encode(&x).unwrap();
        let y = m.decode(&z).unwrap();
        assert_eq!(y.dims(), &[4, 162, 3]);
        // decode = denormalise(network decode).
        let direct = m
            .normalization()
            .denormalize(&m.network().decode(&z).unwrap())
            .unwrap();
        assert_eq!(values(&y), values(&direct));
        assert!(m.encode(&x.narrow(1, 0, 10).unwrap()).is_err());
        assert!(m.encode(&x.flatten_all().unwrap()).is_err());
    }
}
