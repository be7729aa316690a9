//! The spiral mesh decoder (thesis Table 3.1's decoder half and Table 4.1; Bouritsas et al.,
//! "Neural 3D Morphable Models", ICCV 2019): a fully connected layer from a latent code to
//! the coarsest level of a QEM hierarchy, then for each finer level an unpooling and a spiral
//! convolution (eq. 2.29), an activation after every convolution but the last, which outputs
//! the 3 coordinates. Handy++'s autoencoder and the ch. 4 expression generator share it.
//!
//! # Conventions
//! - `channels[i]` is the number of features the decoder produces on level `i + 1` (the
//!   encoder's output channels in Table 3.1 order, `[8, 16, 32, 64]`); level 0 gets 3.
//! - Latent codes are `(B, Z)`, outputs `(B, V, 3)` with `V` the template's vertex count.
//! - Parameter names under the decoder's `vb`: `latent.{weight,bias}`, `conv{i}.{weight,bias}`
//!   with `i` the level the convolution runs on.

use candle_core::Tensor;
use candle_nn::{Linear, Module, VarBuilder};

use crate::handy::spiral::{
    Activation, SpiralConv, SpiralConvConfig, SpiralPadding, TemplateTensors, Unpool,
};
use crate::{Error, Result};

/// One spiral convolution with its level's spiral indices.
#[derive(Debug, Clone)]
pub(crate) struct SpiralLevel {
    conv: SpiralConv,
    spirals: Tensor,
}

impl SpiralLevel {
    /// The convolution `conv{level}` of `vb` on `template`'s level `level`.
    pub(crate) fn new(
        vb: VarBuilder,
        template: &TemplateTensors,
        level: usize,
        in_channels: usize,
        out_channels: usize,
        padding: SpiralPadding,
    ) -> Result<Self> {
        let config = SpiralConvConfig {
            length: template.spiral_lengths()[level],
            padding,
        };
        Ok(Self {
            conv: SpiralConv::new(
                vb.pp(format!("conv{level}")),
                in_channels,
                out_channels,
                config,
            )?,
            spirals: template.spirals(level, padding)?,
        })
    }

    pub(crate) fn forward(&self, x: &Tensor) -> Result<Tensor> {
        self.conv.forward(x, &self.spirals)
    }
}

/// Latent code `(B, Z)` → mesh `(B, V, 3)` through the template's hierarchy.
#[derive(Debug, Clone)]
pub struct SpiralDecoder {
    latent: Linear,
    unpools: Vec<Unpool>,
    /// Finest level first.
    levels: Vec<SpiralLevel>,
    activation: Activation,
    coarse_vertices: usize,
    coarse_channels: usize,
    latent_size: usize,
}

impl SpiralDecoder {
    /// Name of the output convolution (level 0, 3 channels) under the decoder's `vb`.
    pub const OUTPUT_LAYER: &str = "conv0";

    /// A decoder from `latent_size` codes through `channels` (one per pooling level of
    /// `template`, finest first) with parameters from `vb` (names in the module docs).
    ///
    /// ```
    /// use candle_core::{DType, Device, Tensor};
    /// use candle_nn::{VarBuilder, VarMap};
    /// use meshgnn_graph::HierarchyOptions;
    /// use meshgnn_models::spiral::{Activation, SpiralDecoder, SpiralPadding, TemplateTensors};
    /// let options = HierarchyOptions { factors: vec![4.0; 2], ..Default::default() };
    /// let template = TemplateTensors::new(&meshgnn_geometry::icosphere(2), &options, &Device::Cpu)?;
    /// let vars = VarMap::new();
    /// let vb = VarBuilder::from_varmap(&vars, DType::F32, &Device::Cpu);
    /// let decoder = SpiralDecoder::new(vb, &template, &[8, 16], 5, Activation::Relu, SpiralPadding::Repeat)?;
    /// let z = Tensor::zeros((2, 5), DType::F32, &Device::Cpu)?;
    /// assert_eq!(decoder.forward(&z)?.dims(), &[2, 162, 3]);
    /// # Ok::<(), meshgnn_models::Error>(())
    /// ```
    pub fn new(
        vb: VarBuilder,
        template: &TemplateTensors,
        channels: &[usize],
        latent_size: usize,
        activation: Activation,
        padding: SpiralPadding,
    ) -> Result<Self> {
        let n = channels.len();
        if n == 0 || channels.contains(&0) || latent_size == 0 || template.level_count() != n + 1 {
            return Err(Error::Invalid {
                what: "spiral decoder".into(),
                reason: format!(
                    "channels {channels:?} and latent size {latent_size} on a template of {} \
                     levels: need one channel count per pooling level and positive sizes",
                    template.level_count()
                ),
            });
        }
        let mut all = vec![3];
        all.extend_from_slice(channels);
        let levels = (0..n)
            .map(|i| SpiralLevel::new(vb.clone(), template, i, all[i + 1], all[i], padding))
            .collect::<Result<Vec<_>>>()?;
        let coarse_vertices = template.vertex_counts()[n];
        Ok(Self {
            latent: candle_nn::linear(latent_size, coarse_vertices * all[n], vb.pp("latent"))?,
            unpools: (0..n)
                .map(|i| template.unpool(i).cloned())
                .collect::<Result<_>>()?,
            levels,
            activation,
            coarse_vertices,
            coarse_channels: all[n],
            latent_size,
        })
    }

    /// Latent size `Z`.
    pub fn latent_size(&self) -> usize {
        self.latent_size
    }

    /// `z: (B, Z)` → `(B, V, 3)`.
    pub fn forward(&self, z: &Tensor) -> Result<Tensor> {
        let batch = match z.dims() {
            [b, k] if *k == self.latent_size => *b,
            dims => {
                return Err(Error::Invalid {
                    what: "latent codes".into(),
                    reason: format!("shape {dims:?}, expected (B, {})", self.latent_size),
                });
            }
        };
        let mut h =
            self.latent
                .forward(z)?
                .reshape((batch, self.coarse_vertices, self.coarse_channels))?;
        for (i, (level, unpool)) in self.levels.iter().zip(&self.unpools).enumerate().rev() {
            h = level.forward(&unpool.forward(&h)?)?;
            if i > 0 {
                h = self.activation.apply(&h)?;
            }
        }
        Ok(h)
    }
}
