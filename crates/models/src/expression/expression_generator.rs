//! The 4D expression generator of thesis ch. 4.3 (Fig. 4.1, Table 4.1; Potamias et al.,
//! "Learning to Generate Customized Dynamic 3D Facial Expressions", ECCV 2020): an LSTM
//! encodes the label signal into per-frame latents `z_t = E(e_t)` and a mesh decoder turns
//! each into a displacement of the subject's neutral face, `x̂_t = D(z_t) + x_id` (eq. 4.1).
//!
//! # Architecture (defaults = Table 4.1)
//! - `E`: [`LabelEncoder`], an LSTM of 64 units.
//! - `D` ([`DecoderKind::Spiral`]): [`SpiralDecoder`] — `FC(64 → V₄·64)`, then four times
//!   unpooling ×5 and a spiral convolution (64 → 32 → 16 → 8 → 3), ReLU after all but the last,
//!   on the template's own QEM hierarchy (5 040 → 1 008 → 202 → 41 → 9 vertices for the
//!   synthetic face; 28 431 → … → 46 in the thesis).
//! - `D` ([`DecoderKind::Blendshape`]): the baseline, [`BlendshapeDecoder`] with as many
//!   blendshapes as latent units.
//! - `D` ([`DecoderKind::Residual`], beyond the thesis): the blendshape decoder plus a spiral
//!   decoder of what the blendshapes miss, `D(z) = B(z) + S(z)`. Its spiral output layer
//!   starts at zero, so a fresh model is exactly its blendshape part and can start from a
//!   trained baseline (`ExpressionModel::initialize_from`); the spiral half then only has to
//!   learn the non-linear remainder (docs/expression_model.md).
//! - The spiral decoder's output is multiplied by `displacement_scale` (mm; `express train`
//!   sets the RMS of the training displacements), so a freshly initialised network starts at
//!   the data's scale; the blendshapes are in data units already.
//!
//! # Parameter names
//! `encoder.{weight,bias}_{ih,hh}_l0` (PyTorch's LSTM), then `decoder.latent.*`,
//! `decoder.conv{i}.*` (spiral), `decoder.coefficients.*` (blendshape) or
//! `decoder.coefficients.*` and `decoder.residual.{latent,conv{i}}.*` (residual).

use candle_core::Tensor;
use candle_nn::VarBuilder;
use meshgnn_graph::HierarchyOptions;
use serde::{Deserialize, Serialize};

use crate::expression::{BlendshapeDecoder, Blendshapes, LabelEncoder};
use crate::spiral::{Activation, SpiralDecoder, SpiralPadding, TemplateTensors};
use crate::{Error, Result};

/// Which decoder turns latents into displacements.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum DecoderKind {
    /// The spiral mesh decoder of Table 4.1 (the thesis' model).
    #[default]
    Spiral,
    /// PCA blendshapes of the training displacements (the thesis' baseline).
    Blendshape,
    /// Blendshapes plus a spiral decoder of their remainder.
    Residual,
}

impl DecoderKind {
    /// Whether the decoder has blendshapes (fitted on the training displacements).
    pub fn uses_blendshapes(self) -> bool {
        matches!(self, Self::Blendshape | Self::Residual)
    }
}

/// Prefix of the residual decoder's spiral half.
pub const RESIDUAL_PREFIX: &str = "decoder.residual";

/// Hyper-parameters of an [`ExpressionGenerator`]; defaults are Table 4.1.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ExpressionGeneratorConfig {
    /// LSTM units = latent size. Default 64.
    pub hidden_size: usize,
    /// The decoder. Default spiral.
    pub decoder: DecoderKind,
    /// Spiral decoder features per pooling level, finest first. Default `[8, 16, 32, 64]`.
    pub channels: Vec<usize>,
    /// Vertex reduction per level. Default `[5; 4]` ("each upsampling layer increases the
    /// number of vertices by five times").
    pub factors: Vec<f64>,
    /// Spiral length per level (`channels.len() + 1`). Default 9.
    pub spiral_lengths: Vec<usize>,
    /// Spiral dilation per level (`channels.len() + 1`). Default 1.
    pub dilations: Vec<usize>,
    /// Millimetres per unit of spiral decoder output. Default 1.
    pub displacement_scale: f64,
}

impl Default for ExpressionGeneratorConfig {
    fn default() -> Self {
        Self {
            hidden_size: 64,
            decoder: DecoderKind::Spiral,
            channels: vec![8, 16, 32, 64],
            factors: vec![5.0; 4],
            spiral_lengths: vec![9; 5],
            dilations: vec![1; 5],
            displacement_scale: 1.0,
        }
    }
}

impl ExpressionGeneratorConfig {
    /// The options that build the decoder's template hierarchy.
    pub fn hierarchy_options(&self) -> HierarchyOptions {
        HierarchyOptions {
            factors: self.factors.clone(),
            spiral_lengths: self.spiral_lengths.clone(),
            dilations: self.dilations.clone(),
        }
    }

    /// Checks the sizes agree with each other.
    pub fn validate(&self) -> Result<()> {
        let n = self.channels.len();
        let ok = self.hidden_size > 0
            && n > 0
            && !self.channels.contains(&0)
            && self.factors.len() == n
            && self.spiral_lengths.len() == n + 1
            && self.dilations.len() == n + 1
            && self.displacement_scale.is_finite()
            && self.displacement_scale > 0.0;
        if ok {
            Ok(())
        } else {
            Err(Error::Invalid {
                what: "expression generator config".into(),
                reason: format!(
                    "{self:?}: need a positive hidden size and scale, one factor per channel \
                     count and one spiral length and dilation more"
                ),
            })
        }
    }
}

#[derive(Debug, Clone)]
enum Decoder {
    Spiral(SpiralDecoder),
    Blendshape(BlendshapeDecoder),
    Residual(BlendshapeDecoder, SpiralDecoder),
}

/// Eq. 4.1: label signals `(B, T, 6)` and neutral faces `(B, V, 3)` → frames `(B, T, V, 3)`.
#[derive(Debug, Clone)]
pub struct ExpressionGenerator {
    encoder: LabelEncoder,
    decoder: Decoder,
    scale: f64,
    vertices: usize,
}

impl ExpressionGenerator {
    /// The network of `config` on `template` (built with `config.hierarchy_options()`);
    /// `blendshapes` are required by (and only used by) the blendshape and residual decoders.
    ///
    /// ```
    /// use candle_core::{DType, Device, Tensor};
    /// use candle_nn::{VarBuilder, VarMap};
    /// use meshgnn_models::expression::{ExpressionGenerator, ExpressionGeneratorConfig};
    /// use meshgnn_models::spiral::TemplateTensors;
    /// let cfg = ExpressionGeneratorConfig { channels: vec![8, 16], factors: vec![4.0; 2],
    ///     spiral_lengths: vec![9; 3], dilations: vec![1; 3], ..Default::default() };
    /// let template = TemplateTensors::new(&meshgnn_geometry::icosphere(2), &cfg.hierarchy_options(), &Device::Cpu)?;
    /// let vars = VarMap::new();
    /// let net = ExpressionGenerator::new(VarBuilder::from_varmap(&vars, DType::F32, &Device::Cpu), &cfg, &template, None)?;
    /// let labels = Tensor::zeros((2, 5, 6), DType::F32, &Device::Cpu)?;
    /// let neutral = Tensor::zeros((2, 162, 3), DType::F32, &Device::Cpu)?;
    /// assert_eq!(net.forward(&labels, &neutral)?.dims(), &[2, 5, 162, 3]);
    /// # Ok::<(), meshgnn_models::Error>(())
    /// ```
    pub fn new(
        vb: VarBuilder,
        config: &ExpressionGeneratorConfig,
        template: &TemplateTensors,
        blendshapes: Option<&Blendshapes>,
    ) -> Result<Self> {
        config.validate()?;
        let vertices = template.template().vertex_count();
        let spiral = |vb: VarBuilder| {
            SpiralDecoder::new(
                vb,
                template,
                &config.channels,
                config.hidden_size,
                Activation::Relu,
                SpiralPadding::Repeat,
            )
        };
        let blendshape = |vb: VarBuilder| -> Result<BlendshapeDecoder> {
            match blendshapes {
                Some(b) if b.vertex_count() == vertices => {
                    BlendshapeDecoder::new(vb, config.hidden_size, b.to_device(template.device())?)
                }
                _ => Err(Error::Invalid {
                    what: "blendshape decoder".into(),
                    reason: match blendshapes {
                        Some(b) => format!(
                            "blendshapes of {} vertices for a template of {vertices}",
                            b.vertex_count()
                        ),
                        None => "needs the blendshapes".into(),
                    },
                }),
            }
        };
        let decoder = match config.decoder {
            DecoderKind::Spiral => Decoder::Spiral(spiral(vb.pp("decoder"))?),
            DecoderKind::Blendshape => Decoder::Blendshape(blendshape(vb.pp("decoder"))?),
            DecoderKind::Residual => Decoder::Residual(
                blendshape(vb.pp("decoder"))?,
                spiral(vb.pp(RESIDUAL_PREFIX))?,
            ),
        };
        Ok(Self {
            encoder: LabelEncoder::new(vb.pp("encoder"), config.hidden_size)?,
            decoder,
            scale: config.displacement_scale,
            vertices,
        })
    }

    /// Vertex count `V` of the faces generated.
    pub fn vertex_count(&self) -> usize {
        self.vertices
    }

    /// `D(E(e))`: `labels: (B, T, 6)` → displacements `(B, T, V, 3)` in data units.
    pub fn displacements(&self, labels: &Tensor) -> Result<Tensor> {
        let z = self.encoder.forward(labels)?;
        let (b, t, h) = z.dims3()?;
        let flat = z.reshape((b * t, h))?;
        let d = match &self.decoder {
            Decoder::Spiral(decoder) => (decoder.forward(&flat)? * self.scale)?,
            Decoder::Blendshape(decoder) => decoder.forward(&flat)?,
            Decoder::Residual(blendshapes, spiral) => {
                (blendshapes.forward(&flat)? + (spiral.forward(&flat)? * self.scale)?)?
            }
        };
        Ok(d.reshape((b, t, self.vertices, 3))?)
    }

    /// Eq. 4.1: `labels: (B, T, 6)`, `neutral: (B, V, 3)` → `(B, T, V, 3)`.
    pub fn forward(&self, labels: &Tensor, neutral: &Tensor) -> Result<Tensor> {
        match neutral.dims() {
            [b, v, 3] if *v == self.vertices && Some(*b) == labels.dims().first().copied() => {}
            dims => {
                return Err(Error::Invalid {
                    what: "neutral faces".into(),
                    reason: format!(
                        "shape {dims:?}, expected (B, {}, 3) with B = the labels' batch",
                        self.vertices
                    ),
                });
            }
        }
        Ok(self
            .displacements(labels)?
            .broadcast_add(&neutral.unsqueeze(1)?)?)
    }
}
