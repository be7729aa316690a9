//! The "Handy++" spiral-convolution mesh autoencoder (thesis ch. 3.3.4, Fig. 3.7, Table 3.1;
//! Bouritsas et al., "Neural 3D Morphable Models", ICCV 2019): an encoder of spiral
//! convolutions (eq. 2.29) and poolings down a QEM hierarchy, a fully connected layer to a
//! latent code, and a mirrored decoder of unpoolings and spiral convolutions.
//!
//! # Architecture (Table 3.1, `channels = [8, 16, 32, 64]`, 4 pooling steps)
//! - Encoder, for each level `i = 0..n`: `SpiralConv(c_i → c_{i+1})` on level `i`, activation,
//!   `Pool` to level `i + 1` (`c_0 = 3`); flatten `(B, V_n·c_n)`; `Linear → Z`.
//! - Decoder: `Linear(Z → V_n·c_n)`, reshape `(B, V_n, c_n)`; for `i = n−1..0`: `Unpool` to
//!   level `i`, `SpiralConv(c_{i+1} → c_i)` on level `i`, activation except on the last layer,
//!   which outputs the 3 coordinates.
//!
//! - With `linear_skip` (beyond the thesis): `encode(x) = PCA(x) + E(x)` and
//!   `decode(z) = PCA⁻¹(z) + D(z)` ([`LinearSkip`]); a fresh model's `encoder.latent` and
//!   `decoder.conv0` are zero, so it starts as the PCA model.
//!
//! # Parameter names (the safetensors names)
//! `encoder.conv{i}.{weight,bias}`, `encoder.latent.{weight,bias}`,
//! `decoder.latent.{weight,bias}`, `decoder.conv{i}.{weight,bias}` (`i` = level).

use candle_core::Tensor;
use candle_nn::{Linear, Module, VarBuilder};
use meshgnn_graph::HierarchyOptions;
use serde::{Deserialize, Serialize};

use crate::handy::spiral::pool::check_vertices;
use crate::handy::spiral::spiral_decoder::SpiralLevel;
use crate::handy::spiral::{LinearSkip, Pool, SpiralDecoder, SpiralPadding, TemplateTensors};
use crate::{Error, Result};

/// The non-linearity after every spiral convolution but the last.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum Activation {
    /// `ELU(x) = x` for `x > 0`, `eˣ − 1` otherwise (Neural3DMM; the default).
    #[default]
    Elu,
    /// `max(x, 0)`.
    Relu,
}

impl Activation {
    /// Applies the activation element-wise.
    pub fn apply(self, x: &Tensor) -> Result<Tensor> {
        Ok(match self {
            Activation::Elu => x.elu(1.0)?,
            Activation::Relu => x.relu()?,
        })
    }
}

/// Hyper-parameters of a [`SpiralAutoencoder`] and of its template hierarchy; defaults are
/// Table 3.1 with COMA's reduction factor 4 and spirals of length 9.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SpiralAutoencoderConfig {
    /// Encoder output channels per level (one pooling step each). Default `[8, 16, 32, 64]`.
    pub channels: Vec<usize>,
    /// Latent size `Z`. Default 8 (the thesis reports 8 and 30).
    pub latent_size: usize,
    /// Vertex reduction of each pooling step (`channels.len()` entries). Default `[4; 4]`.
    pub factors: Vec<f64>,
    /// Spiral length per level (`channels.len() + 1` entries). Default 9.
    pub spiral_lengths: Vec<usize>,
    /// Spiral dilation per level (`channels.len() + 1` entries). Default 1.
    pub dilations: Vec<usize>,
    /// Activation after each convolution but the last. Default ELU.
    pub activation: Activation,
    /// Treatment of padded spiral entries. Default repeat.
    pub padding: SpiralPadding,
    /// Add the fixed PCA path ([`LinearSkip`]) to encoder and decoder, so the spiral layers
    /// learn the non-linear remainder (beyond the thesis). Default off (Table 3.1).
    #[serde(default)]
    pub linear_skip: bool,
}

impl Default for SpiralAutoencoderConfig {
    fn default() -> Self {
        Self {
            channels: vec![8, 16, 32, 64],
            latent_size: 8,
            factors: vec![4.0; 4],
            spiral_lengths: vec![9; 5],
            dilations: vec![1; 5],
            activation: Activation::Elu,
            padding: SpiralPadding::Repeat,
            linear_skip: false,
        }
    }
}

impl SpiralAutoencoderConfig {
    /// The options that build this network's template hierarchy.
    pub fn hierarchy_options(&self) -> HierarchyOptions {
        HierarchyOptions {
            factors: self.factors.clone(),
            spiral_lengths: self.spiral_lengths.clone(),
            dilations: self.dilations.clone(),
        }
    }

    /// Checks the sizes agree with each other (and with `template` when given).
    pub fn validate(&self, template: Option<&TemplateTensors>) -> Result<()> {
        let bad = |reason: String| {
            Err(Error::Invalid {
                what: "spiral autoencoder config".into(),
                reason,
            })
        };
        let n = self.channels.len();
        if n == 0 || self.channels.contains(&0) || self.latent_size == 0 {
            return bad(format!(
                "channels {:?} and latent size {}: need at least one level and positive sizes",
                self.channels, self.latent_size
            ));
        }
        if self.factors.len() != n
            || self.spiral_lengths.len() != n + 1
            || self.dilations.len() != n + 1
        {
            return bad(format!(
                "{n} levels need {n} factors and {} spiral lengths and dilations; got {}, {} \
                 and {}",
                n + 1,
                self.factors.len(),
                self.spiral_lengths.len(),
                self.dilations.len()
            ));
        }
        if let Some(t) = template
            && (t.level_count() != n + 1 || t.spiral_lengths() != self.spiral_lengths)
        {
            return bad(format!(
                "expects {} levels with spiral lengths {:?}; the template has {} with {:?}",
                n + 1,
                self.spiral_lengths,
                t.level_count(),
                t.spiral_lengths()
            ));
        }
        Ok(())
    }
}

/// Table 3.1's autoencoder: `(B, V, 3)` ↔ `(B, Z)`, on normalised coordinates.
#[derive(Debug, Clone)]
pub struct SpiralAutoencoder {
    encoder: Vec<SpiralLevel>,
    pools: Vec<Pool>,
    encoder_latent: Linear,
    decoder: SpiralDecoder,
    skip: Option<LinearSkip>,
    activation: Activation,
    vertices: usize,
    coarse_vertices: usize,
    coarse_channels: usize,
    latent_size: usize,
}

impl SpiralAutoencoder {
    /// The network of `config` on `template` (built with `config.hierarchy_options()`), its
    /// parameters taken from `vb` (names in the module docs).
    ///
    /// ```
    /// use candle_core::{DType, Device, Tensor};
    /// use candle_nn::{VarBuilder, VarMap};
    /// use meshgnn_models::spiral::{SpiralAutoencoder, SpiralAutoencoderConfig, TemplateTensors};
    /// let cfg = SpiralAutoencoderConfig { channels: vec![8, 16], factors: vec![4.0; 2],
    ///     spiral_lengths: vec![9; 3], dilations: vec![1; 3], ..Default::default() };
    /// let template = TemplateTensors::new(&meshgnn_geometry::icosphere(2), &cfg.hierarchy_options(), &Device::Cpu)?;
    /// let vars = VarMap::new();
    /// let net = SpiralAutoencoder::new(VarBuilder::from_varmap(&vars, DType::F32, &Device::Cpu), &cfg, &template, None)?;
    /// let x = Tensor::zeros((2, 162, 3), DType::F32, &Device::Cpu)?;
    /// assert_eq!(net.encode(&x)?.dims(), &[2, 8]);
    /// assert_eq!(net.forward(&x)?.dims(), &[2, 162, 3]);
    /// # Ok::<(), meshgnn_models::Error>(())
    /// ```
    pub fn new(
        vb: VarBuilder,
        config: &SpiralAutoencoderConfig,
        template: &TemplateTensors,
        skip: Option<LinearSkip>,
    ) -> Result<Self> {
        config.validate(Some(template))?;
        let v = template.vertex_counts()[0];
        match &skip {
            Some(s)
                if !(config.linear_skip
                    && s.latent_size() == config.latent_size
                    && s.vertex_count() == v) =>
            {
                return Err(Error::Invalid {
                    what: "linear skip".into(),
                    reason: format!(
                        "latent {} on {} vertices for a config of latent {} on {v} (linear_skip \
                         {})",
                        s.latent_size(),
                        s.vertex_count(),
                        config.latent_size,
                        config.linear_skip
                    ),
                });
            }
            None if config.linear_skip => {
                return Err(Error::Invalid {
                    what: "linear skip".into(),
                    reason: "the config asks for it, none given".into(),
                });
            }
            _ => {}
        }
        let n = config.channels.len();
        let mut channels = vec![3];
        channels.extend_from_slice(&config.channels);
        let venc = vb.pp("encoder");
        let encoder = (0..n)
            .map(|i| {
                SpiralLevel::new(
                    venc.clone(),
                    template,
                    i,
                    channels[i],
                    channels[i + 1],
                    config.padding,
                )
            })
            .collect::<Result<Vec<_>>>()?;
        let coarse_vertices = template.vertex_counts()[n];
        let coarse_channels = channels[n];
        Ok(Self {
            encoder,
            pools: (0..n)
                .map(|i| template.pool(i).cloned())
                .collect::<Result<_>>()?,
            encoder_latent: candle_nn::linear(
                coarse_vertices * coarse_channels,
                config.latent_size,
                venc.pp("latent"),
            )?,
            decoder: SpiralDecoder::new(
                vb.pp("decoder"),
                template,
                &config.channels,
                config.latent_size,
                config.activation,
                config.padding,
            )?,
            skip,
            activation: config.activation,
            vertices: v,
            coarse_vertices,
            coarse_channels,
            latent_size: config.latent_size,
        })
    }

    /// Vertex count `V` of the meshes the network takes.
    pub fn vertex_count(&self) -> usize {
        self.vertices
    }

    /// Latent size `Z`.
    pub fn latent_size(&self) -> usize {
        self.latent_size
    }

    /// Encoder: `x: (B, V, 3)` → `(B, Z)`.
    pub fn encode(&self, x: &Tensor) -> Result<Tensor> {
        check_vertices("autoencoder input", x, self.vertices)?;
        if x.dim(2)? != 3 {
            return Err(Error::Invalid {
                what: "autoencoder input".into(),
                reason: format!("shape {:?}, expected (B, {}, 3)", x.dims(), self.vertices),
            });
        }
        let mut h = x.clone();
        for (level, pool) in self.encoder.iter().zip(&self.pools) {
            h = pool.forward(&self.activation.apply(&level.forward(&h)?)?)?;
        }
        let batch = h.dim(0)?;
        let flat = h.reshape((batch, self.coarse_vertices * self.coarse_channels))?;
        let z = self.encoder_latent.forward(&flat)?;
        Ok(match &self.skip {
            Some(skip) => (skip.encode(x)? + z)?,
            None => z,
        })
    }

    /// Decoder: `z: (B, Z)` → `(B, V, 3)`.
    pub fn decode(&self, z: &Tensor) -> Result<Tensor> {
        let y = self.decoder.forward(z)?;
        Ok(match &self.skip {
            Some(skip) => (skip.decode(z)? + y)?,
            None => y,
        })
    }

    /// The PCA path, when the config has `linear_skip`.
    pub fn linear_skip(&self) -> Option<&LinearSkip> {
        self.skip.as_ref()
    }

    /// `decode(encode(x))`: `(B, V, 3)` → `(B, V, 3)`.
    pub fn forward(&self, x: &Tensor) -> Result<Tensor> {
        self.decode(&self.encode(x)?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::handy::spiral::test_fixtures::tiny_config;
    use candle_core::{DType, Device};
    use candle_nn::VarMap;

    #[test]
    fn shapes_for_latent_8_and_30_and_parameter_names() {
        let sphere = meshgnn_geometry::icosphere(2);
        for latent in [8, 30] {
            let cfg = tiny_config(latent);
            let t = TemplateTensors::new(&sphere, &cfg.hierarchy_options(), &Device::Cpu).unwrap();
            assert_eq!(t.vertex_counts(), vec![162, 42, 12]);
            let vars = VarMap::new();
            let net = SpiralAutoencoder::new(
                VarBuilder::from_varmap(&vars, DType::F32, &Device::Cpu),
                &cfg,
                &t,
                None,
            )
            .unwrap();
            let x = Tensor::randn(0f32, 1.0, (3, 162, 3), &Device::Cpu).unwrap();
            let z = net.encode(&x).unwrap();
            assert_eq!(z.dims(), &[3, latent]);
            assert_eq!(net.decode(&z).unwrap().dims(), &[3, 162, 3]);
            let mut names: Vec<String> = vars.data().lock().unwrap().keys().cloned().collect();
            names.sort();
            assert_eq!(
                names,
                [
                    "decoder.conv0.bias",
                    "decoder.conv0.weight",
                    "decoder.conv1.bias",
                    "decoder.conv1.weight",
                    "decoder.latent.bias",
                    "decoder.latent.weight",
                    "encoder.conv0.bias",
                    "encoder.conv0.weight",
                    "encoder.conv1.bias",
                    "encoder.conv1.weight",
                    "encoder.latent.bias",
                    "encoder.latent.weight",
                ]
            );
            // Table 3.1 shapes: conv0 3→8 with L = 9, latent from 12·16.
            let data = vars.data().lock().unwrap();
            assert_eq!(data["encoder.conv0.weight"].dims(), &[8, 27]);
            assert_eq!(data["decoder.conv0.weight"].dims(), &[3, 72]);
            assert_eq!(data["encoder.latent.weight"].dims(), &[latent, 12 * 16]);
            drop(data);
            assert!(net.encode(&x.narrow(1, 0, 100).unwrap()).is_err());
            assert!(
                net.decode(&Tensor::zeros((1, latent + 1), DType::F32, &Device::Cpu).unwrap())
                    .is_err()
            );
        }
    }

    #[test]
    fn config_mismatches_are_errors() {
        let sphere = meshgnn_geometry::icosphere(2);
        let cfg = tiny_config(8);
        let t = TemplateTensors::new(&sphere, &cfg.hierarchy_options(), &Device::Cpu).unwrap();
        let vb = || VarBuilder::zeros(DType::F32, &Device::Cpu);
        let three_levels = SpiralAutoencoderConfig {
            channels: vec![8, 16, 32],
            ..cfg.clone()
        };
        assert!(SpiralAutoencoder::new(vb(), &three_levels, &t, None).is_err());
        let other_length = SpiralAutoencoderConfig {
            spiral_lengths: vec![7; 3],
            ..cfg.clone()
        };
        assert!(SpiralAutoencoder::new(vb(), &other_length, &t, None).is_err());
        assert!(
            SpiralAutoencoderConfig {
                latent_size: 0,
                ..cfg
            }
            .validate(None)
            .is_err()
        );
        let d = SpiralAutoencoderConfig::default();
        assert_eq!(
            (d.channels.clone(), d.latent_size, d.activation),
            (vec![8, 16, 32, 64], 8, Activation::Elu)
        );
        d.validate(None).unwrap();
    }

    #[test]
    fn activations() {
        let x = Tensor::new(&[-1.0f32, 0.0, 2.0], &Device::Cpu).unwrap();
        let elu = Activation::Elu.apply(&x).unwrap().to_vec1::<f32>().unwrap();
        assert!((elu[0] - ((-1.0f32).exp() - 1.0)).abs() < 1e-6 && elu[1] == 0.0 && elu[2] == 2.0);
        assert_eq!(
            Activation::Relu
                .apply(&x)
                .unwrap()
                .to_vec1::<f32>()
                .unwrap(),
            vec![0.0, 0.0, 2.0]
        );
    }
}
