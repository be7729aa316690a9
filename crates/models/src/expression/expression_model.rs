//! The expression generator as a usable model (thesis ch. 4): network, template hierarchy,
//! blendshapes (for the baseline) and config in one self-contained safetensors file; generates
//! frames in data units (millimetres for the synthetic faces).
//!
//! # File format: a [`crate::Checkpoint`] of model [`EXPRESSION_MODEL_NAME`]
//! - Tensors: the network parameters (names in [`super::ExpressionGenerator`]'s docs), the
//!   template under `template.` (table in [`crate::spiral::TemplateTensors`]'s docs) and, for
//!   the blendshape and residual decoders, `blendshapes.mean (1, 3V)` and
//!   `blendshapes.basis (K, 3V)`.
//! - Header: `config` = the [`ExpressionGeneratorConfig`].

use std::collections::HashMap;
use std::path::Path;

use candle_core::{DType, Device, Tensor};
use candle_nn::{VarBuilder, VarMap};
use meshgnn_geometry::TriMesh;

use crate::checkpoint::{checkpoint_of, lock, read_file, set_vars, zero_vars};
use crate::expression::{
    Blendshapes, DecoderKind, ExpressionGenerator, ExpressionGeneratorConfig, RESIDUAL_PREFIX,
};
use crate::spiral::{SpiralDecoder, TemplateTensors, seeded_initialization};
use crate::{Checkpoint, CheckpointHeader, Error, LoadCheckpoint, Result};

/// The model's name in checkpoints.
pub const EXPRESSION_MODEL_NAME: &str = "expression_generator";

const TEMPLATE_PREFIX: &str = "template.";
const BLENDSHAPE_MEAN: &str = "blendshapes.mean";
const BLENDSHAPE_BASIS: &str = "blendshapes.basis";

/// Generator + template + blendshapes + config: a complete expression model.
pub struct ExpressionModel {
    config: ExpressionGeneratorConfig,
    template: TemplateTensors,
    blendshapes: Option<Blendshapes>,
    network: ExpressionGenerator,
    vars: VarMap,
}

impl std::fmt::Debug for ExpressionModel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ExpressionModel")
            .field("config", &self.config)
            .field("vertices", &self.network.vertex_count())
            .finish_non_exhaustive()
    }
}

impl ExpressionModel {
    /// A freshly initialised model (weights from `seed`) on `template`; `blendshapes` for the
    /// blendshape and residual decoders (the residual's spiral output layer starts at zero).
    ///
    /// ```
    /// use candle_core::Device;
    /// use meshgnn_models::expression::{ExpressionGeneratorConfig, ExpressionModel};
    /// let sphere = meshgnn_geometry::icosphere(2);
    /// let cfg = ExpressionGeneratorConfig { channels: vec![8, 16], factors: vec![4.0; 2],
    ///     spiral_lengths: vec![9; 3], dilations: vec![1; 3], ..Default::default() };
    /// let model = ExpressionModel::new(&sphere, &cfg, None, 0, &Device::Cpu)?;
    /// let frames = model.generate(&[[0.0; 6], [0.5, 0.0, 0.0, 0.0, 0.0, 0.0]], sphere.vertices())?;
    /// assert_eq!((frames.len(), frames[1].len()), (2, 162));
    /// # Ok::<(), meshgnn_models::Error>(())
    /// ```
    pub fn new(
        template: &TriMesh,
        config: &ExpressionGeneratorConfig,
        blendshapes: Option<Blendshapes>,
        seed: u64,
        device: &Device,
    ) -> Result<Self> {
        config.validate()?;
        let tensors = TemplateTensors::new(template, &config.hierarchy_options(), device)?;
        let model = Self::assemble(tensors, config, blendshapes)?;
        seeded_initialization(&model.vars, seed)?;
        if config.decoder == DecoderKind::Residual {
            let output = format!("{RESIDUAL_PREFIX}.{}.", SpiralDecoder::OUTPUT_LAYER);
            zero_vars(&model.vars, &[output])?;
        }
        Ok(model)
    }

    /// Sets every parameter that `source` has under the same name and shape to its value
    /// (the LSTM and blendshape weights of a trained baseline, say); returns how many were
    /// set. The two models must share the template's faces.
    pub fn initialize_from(&self, source: &ExpressionModel, path: &Path) -> Result<usize> {
        if source.template().triangles() != self.template().triangles() {
            return Err(checkpoint_of(
                path,
                Error::Invalid {
                    what: "template".into(),
                    reason: "its faces differ from the training data's template".into(),
                },
            ));
        }
        let theirs = lock(&source.vars)?;
        let mut set = 0;
        for (name, var) in lock(&self.vars)?.iter() {
            if let Some(value) = theirs.get(name).filter(|v| v.dims() == var.dims()) {
                var.set(&value.as_tensor().to_device(self.device())?)?;
                set += 1;
            }
        }
        Ok(set)
    }

    fn assemble(
        template: TemplateTensors,
        config: &ExpressionGeneratorConfig,
        blendshapes: Option<Blendshapes>,
    ) -> Result<Self> {
        let vars = VarMap::new();
        let network = ExpressionGenerator::new(
            VarBuilder::from_varmap(&vars, DType::F32, template.device()),
            config,
            &template,
            blendshapes.as_ref(),
        )?;
        Ok(Self {
            config: config.clone(),
            template,
            blendshapes,
            network,
            vars,
        })
    }

    /// The hyper-parameters.
    pub fn config(&self) -> &ExpressionGeneratorConfig {
        &self.config
    }

    /// The template mesh (topology of every generated frame).
    pub fn template(&self) -> &TriMesh {
        self.template.template()
    }

    /// The device the model runs on.
    pub fn device(&self) -> &Device {
        self.template.device()
    }

    /// The network.
    pub fn network(&self) -> &ExpressionGenerator {
        &self.network
    }

    /// The trainable parameters.
    pub fn vars(&self) -> &VarMap {
        &self.vars
    }

    /// The blendshapes of a blendshape or residual model.
    pub fn blendshapes(&self) -> Option<&Blendshapes> {
        self.blendshapes.as_ref()
    }

    /// Eq. 4.1 for one sequence: `labels: #T×6` and `neutral: #V×3` → `#T × (#V×3)` frames.
    pub fn generate(
        &self,
        labels: &[[f32; 6]],
        neutral: &[[f32; 3]],
    ) -> Result<Vec<Vec<[f32; 3]>>> {
        let v = self.network.vertex_count();
        if neutral.len() != v || labels.is_empty() {
            return Err(Error::Invalid {
                what: "expression request".into(),
                reason: format!(
                    "{} labels and a neutral face of {} vertices; needs at least one label and \
                     the template's {v} vertices",
                    labels.len(),
                    neutral.len()
                ),
            });
        }
        let device = self.template.device();
        let t = labels.len();
        let labels = Tensor::from_vec(labels.concat(), (1, t, 6), device)?;
        let neutral = Tensor::from_vec(neutral.concat(), (1, v, 3), device)?;
        let frames = self.network.forward(&labels, &neutral)?;
        let flat: Vec<f32> = frames.flatten_all()?.to_vec1()?;
        Ok(flat
            .chunks_exact(3 * v)
            .map(|frame| frame.chunks_exact(3).map(|p| [p[0], p[1], p[2]]).collect())
            .collect())
    }

    /// The model as a checkpoint (network, template, blendshapes; config in the header).
    pub fn to_checkpoint(&self) -> Result<Checkpoint> {
        let mut tensors = self.template.to_named_tensors(TEMPLATE_PREFIX)?;
        if let Some(b) = &self.blendshapes {
            tensors.insert(BLENDSHAPE_MEAN.into(), b.mean().to_device(&Device::Cpu)?);
            tensors.insert(BLENDSHAPE_BASIS.into(), b.basis().to_device(&Device::Cpu)?);
        }
        for (name, var) in lock(&self.vars)?.iter() {
            tensors.insert(name.clone(), var.as_tensor().to_device(&Device::Cpu)?);
        }
        let config = match serde_json::to_value(&self.config) {
            Ok(serde_json::Value::Object(config)) => config,
            other => {
                return Err(Error::Invalid {
                    what: "model config".into(),
                    reason: format!("cannot serialise: {other:?}"),
                });
            }
        };
        Ok(Checkpoint {
            header: CheckpointHeader::new(EXPRESSION_MODEL_NAME, config),
            tensors,
        })
    }

    /// Writes the model to `path` atomically.
    pub fn save(&self, path: &Path) -> Result<()> {
        self.to_checkpoint()?.save(path)
    }

    /// Reads a model file onto `device`; errors name the file and the missing or malformed
    /// tensor.
    pub fn load(path: &Path, device: &Device) -> Result<Self> {
        let bytes = read_file(path)?;
        Checkpoint::from_bytes(&bytes, path)
            .and_then(|c| Self::from_checkpoint(&c, path, device))
            .map_err(|e| checkpoint_of(path, e))
    }

    /// The model stored in `checkpoint` (read from `source`), on `device`.
    pub fn from_checkpoint(
        checkpoint: &Checkpoint,
        source: &Path,
        device: &Device,
    ) -> Result<Self> {
        checkpoint
            .header
            .expect_model(EXPRESSION_MODEL_NAME, source)?;
        let config: ExpressionGeneratorConfig =
            serde_json::from_value(serde_json::Value::Object(checkpoint.header.config.clone()))
                .map_err(|e| Error::Invalid {
                    what: "model file".into(),
                    reason: format!("bad `config`: {e}"),
                })?;
        config.validate()?;
        let tensors: HashMap<String, Tensor> = checkpoint
            .model_tensors()
            .into_iter()
            .map(|(k, t)| Ok((k, t.to_device(device)?)))
            .collect::<Result<_>>()?;
        let get = |name: &str| {
            tensors.get(name).cloned().ok_or_else(|| Error::Invalid {
                what: format!("tensor `{name}`"),
                reason: "missing from the model file".into(),
            })
        };
        let template = TemplateTensors::from_named_tensors(&tensors, TEMPLATE_PREFIX, device)?;
        let blendshapes = match config.decoder.uses_blendshapes() {
            true => Some(Blendshapes::from_tensors(
                get(BLENDSHAPE_MEAN)?,
                get(BLENDSHAPE_BASIS)?,
            )?),
            false => None,
        };
        let model = Self::assemble(template, &config, blendshapes)?;
        set_vars(&model.vars, &tensors)?;
        Ok(model)
    }
}

impl LoadCheckpoint for ExpressionModel {
    /// On the CPU.
    fn from_checkpoint_bytes(bytes: &[u8], source: &Path) -> Result<Self> {
        Checkpoint::from_bytes(bytes, source)
            .and_then(|c| Self::from_checkpoint(&c, source, &Device::Cpu))
            .map_err(|e| checkpoint_of(source, e))
    }
}
