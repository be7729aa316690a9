//! The point sampler of the neural mesh simplifier (thesis ch. 6.3.1 and 6.4): three DevConv
//! layers (eq. 6.1, hidden 64, ReLU) on the mesh adjacency (or a k-NN graph for a point cloud)
//! give every vertex an inclusion probability, and `M` vertices are drawn without replacement
//! with inclusion proportional to it. Unlike FPS the cost does not grow with `M`.
//!
//! Beyond the thesis, the draw is spatially balanced ([`meshgnn_graph::balanced_sampling`]:
//! systematic sampling along a Hilbert curve) rather than the independent multinomial draws of
//! ch. 6.3.1 ([`meshgnn_graph::weighted_sampling`]): the same inclusion probabilities, but no
//! clumps and gaps. The Voronoi dual of the picks, the surface the rest of the model proposes,
//! comes out 1.15-1.6× closer to the input in Chamfer distance (docs/mesh_simplifier_model.md).
//!
//! The probability is a sigmoid of a linear read-out of the last layer's features. The
//! probabilities stay attached to the autograd graph: the probabilistic losses of eq. 6.8-6.10
//! weight each sampled point by its own.

use candle_core::Tensor;
use candle_nn::{Linear, Module, VarBuilder};

use super::{DevConv, DevConvConfig, NeighbourSlots};
use crate::{Error, Result};

/// Hyper-parameters; defaults are the thesis' (ch. 6.4).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PointSamplerConfig {
    /// Channels of every DevConv layer (64).
    pub hidden: usize,
    /// Number of DevConv layers (3).
    pub layers: usize,
}

impl Default for PointSamplerConfig {
    fn default() -> Self {
        Self {
            hidden: 64,
            layers: 3,
        }
    }
}

/// The sampled vertices of one forward pass.
#[derive(Clone, Debug)]
pub struct SampledPoints {
    /// Indices of the `M` drawn vertices, distinct, in draw order (in the mesh simplifier,
    /// about `M`: a draw shortened by the island seeds it is then followed by,
    /// [`super::with_island_seeds`]).
    pub indices: Vec<u32>,
    /// Inclusion probability of every vertex, `(N)`, attached to the autograd graph.
    pub probabilities: Tensor,
}

/// DevConv layers `layers.{l}` and the read-out `score` (`(1, hidden)` weight and bias).
#[derive(Clone, Debug)]
pub struct PointSampler {
    layers: Vec<DevConv>,
    score: Linear,
}

impl PointSampler {
    /// The sampler of `config`, parameters under `vb`.
    ///
    /// ```
    /// use candle_core::{DType, Device, Tensor};
    /// use candle_nn::{VarBuilder, VarMap};
    /// use meshgnn_graph::vertex_adjacency;
    /// use meshgnn_models::mesh_simplifier::{NeighbourSlots, PointSampler, PointSamplerConfig};
    /// let map = VarMap::new();
    /// let vb = VarBuilder::from_varmap(&map, DType::F32, &Device::Cpu);
    /// let sampler = PointSampler::new(vb, &PointSamplerConfig::default())?;
    /// let mesh = meshgnn_geometry::icosphere(2); // 162 vertices
    /// let slots = NeighbourSlots::from_adjacency(&vertex_adjacency(&mesh)?, &Device::Cpu)?;
    /// let v = mesh.vertices();
    /// let x = Tensor::from_slice(v.as_flattened(), (v.len(), 3), &Device::Cpu)?;
    /// let sampled = sampler.sample(&x, v, &slots, 40, 7)?;
    /// assert_eq!((sampled.indices.len(), sampled.probabilities.dims1()?), (40, 162));
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn new(vb: VarBuilder, config: &PointSamplerConfig) -> Result<Self> {
        if config.layers == 0 || config.hidden == 0 {
            return Err(Error::Invalid {
                what: "point sampler config".into(),
                reason: format!("{config:?}: layers and hidden must be at least 1"),
            });
        }
        let layers = (0..config.layers)
            .map(|l| {
                let input = if l == 0 { 3 } else { config.hidden };
                let widths = DevConvConfig {
                    input,
                    output: config.hidden,
                };
                DevConv::new(vb.pp(format!("layers.{l}")), &widths)
            })
            .collect::<Result<Vec<_>>>()?;
        let score = candle_nn::linear(config.hidden, 1, vb.pp("score"))?;
        Ok(Self { layers, score })
    }

    /// The inclusion probability of every vertex: `positions: (N, 3)` over the points of
    /// `slots` → `(N)` in (0, 1).
    pub fn forward(&self, positions: &Tensor, slots: &NeighbourSlots) -> Result<Tensor> {
        let mut features = positions.clone();
        for layer in &self.layers {
            features = layer.forward(&features, slots)?;
        }
        Ok(candle_nn::ops::sigmoid(&self.score.forward(&features)?)?.squeeze(1)?)
    }

    /// Draws `target` distinct vertices (`1 ≤ target ≤ N`) by their probabilities, spread over
    /// `points` (the positions as on the host), seeded.
    pub fn sample(
        &self,
        positions: &Tensor,
        points: &[[f32; 3]],
        slots: &NeighbourSlots,
        target: usize,
        seed: u64,
    ) -> Result<SampledPoints> {
        let n = slots.len();
        if target == 0 || target > n {
            return Err(Error::Invalid {
                what: "target count".into(),
                reason: format!("must be in 1..={n} for {n} vertices, got {target}"),
            });
        }
        let probabilities = self.forward(positions, slots)?;
        let weights: Vec<f32> = probabilities.detach().to_vec1()?;
        let indices = meshgnn_graph::balanced_sampling(points, &weights, target, seed)?;
        Ok(SampledPoints {
            indices,
            probabilities,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use candle_core::{DType, Device};
    use candle_nn::VarMap;
    use meshgnn_graph::vertex_adjacency;

    fn sphere() -> (Tensor, Vec<[f32; 3]>, NeighbourSlots) {
        let mesh = meshgnn_geometry::icosphere(3);
        let adjacency = vertex_adjacency(&mesh).unwrap();
        let slots = NeighbourSlots::from_adjacency(&adjacency, &Device::Cpu).unwrap();
        let v = mesh.vertices();
        let x = Tensor::from_slice(v.as_flattened(), (v.len(), 3), &Device::Cpu).unwrap();
        (x, v.to_vec(), slots)
    }

    #[test]
    fn draws_are_distinct_seeded_and_follow_the_probabilities() {
        let map = VarMap::new();
        let vb = VarBuilder::from_varmap(&map, DType::F32, &Device::Cpu);
        let sampler = PointSampler::new(vb, &PointSamplerConfig::default()).unwrap();
        // Seeded: candle's own initial draw is not, and one run of the suite drew weights
        // under which seeds 5 and 6 drew the same vertices.
        crate::spiral::seeded_initialization(&map, 0).unwrap();
        let (x, v, slots) = sphere();
        let a = sampler.sample(&x, &v, &slots, 100, 5).unwrap();
        let b = sampler.sample(&x, &v, &slots, 100, 5).unwrap();
        assert_eq!(a.indices, b.indices);
        let mut distinct = a.indices.clone();
        distinct.sort_unstable();
        distinct.dedup();
        assert_eq!(distinct.len(), 100);
        let p: Vec<f32> = a.probabilities.to_vec1().unwrap();
        assert!(p.iter().all(|&v| v > 0.0 && v < 1.0));
        assert_ne!(
            sampler.sample(&x, &v, &slots, 100, 6).unwrap().indices,
            a.indices
        );
        assert!(sampler.sample(&x, &v, &slots, 0, 5).is_err());
        assert!(sampler.sample(&x, &v, &slots, 643, 5).is_err());
        assert_eq!(
            sampler
                .sample(&x, &v, &slots, 642, 5)
                .unwrap()
                .indices
                .len(),
            642
        );
    }

    #[test]
    fn probabilities_carry_gradients_to_every_layer() {
        let map = VarMap::new();
        let vb = VarBuilder::from_varmap(&map, DType::F32, &Device::Cpu);
        let sampler = PointSampler::new(vb, &PointSamplerConfig::default()).unwrap();
        let (x, v, slots) = sphere();
        let sampled = sampler.sample(&x, &v, &slots, 50, 1).unwrap();
        let index = Tensor::new(sampled.indices.as_slice(), &Device::Cpu).unwrap();
        let loss = sampled
            .probabilities
            .index_select(&index, 0)
            .unwrap()
            .sum_all()
            .unwrap();
        let grads = loss.backward().unwrap();
        let data = map.data().lock().unwrap();
        for name in [
            "layers.0.theta.weight",
            "layers.2.phi.weight",
            "score.weight",
        ] {
            let g = grads.get(data[name].as_tensor()).unwrap();
            let norm: f32 = g.sqr().unwrap().sum_all().unwrap().to_scalar().unwrap();
            assert!(norm > 0.0, "{name}");
        }
    }
}
