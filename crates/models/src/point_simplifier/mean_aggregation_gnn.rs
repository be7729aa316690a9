//! The projector's graph layer, thesis eq. 5.4 (ch. 5.3.2): each point keeps a projection of
//! its own feature and adds the mean projection of its neighbours',
//! `f'_i = ReLU(W_c f_i + b + 1/|N_i| Σ_{j∈N_i} W_n f_j)` — the mean-aggregation graph
//! convolution of GraphSAGE (Hamilton, Ying & Leskovec 2017, "Inductive representation
//! learning on large graphs", NeurIPS), ReLU-activated as ch. 5.6 states.
//!
//! The neighbour mean is gathered in chunks of points, so a million-point cloud never holds
//! the `N × W × C` gathered tensor at once.

use candle_core::Tensor;
use candle_nn::{Linear, Module, VarBuilder};

use super::NeighbourIndex;
use super::fused_projector::HostAffine;
use crate::{Error, Result};

/// Points per gather chunk (bounds the `chunk × W × C` temporary to ≈ 60 MB at W = 7, C = 64).
const CHUNK: usize = 32_768;

/// Eq. 5.4 with learnable `W_c` (`centre.weight (C_out, C_in)`, `centre.bias`) and `W_n`
/// (`neighbour.weight (C_out, C_in)`, no bias: it would duplicate `b`).
#[derive(Clone, Debug)]
pub struct MeanAggregationGnn {
    centre: Linear,
    neighbour: Linear,
}

impl MeanAggregationGnn {
    /// A layer `input → output` channels with parameters under `vb`.
    ///
    /// ```
    /// use candle_core::{DType, Device, Tensor};
    /// use candle_nn::{VarBuilder, VarMap};
    /// use meshgnn_models::point_simplifier::{MeanAggregationGnn, NeighbourIndex};
    /// let map = VarMap::new();
    /// let vb = VarBuilder::from_varmap(&map, DType::F32, &Device::Cpu);
    /// let gnn = MeanAggregationGnn::new(vb, 4, 6)?;
    /// let g = NeighbourIndex::from_rows(&[vec![1], vec![0]], &Device::Cpu)?;
    /// let y = gnn.forward(&Tensor::ones((2, 4), DType::F32, &Device::Cpu)?, &g)?;
    /// assert_eq!(y.dims(), &[2, 6]);
    /// # Ok::<(), meshgnn_models::Error>(())
    /// ```
    pub fn new(vb: VarBuilder, input: usize, output: usize) -> Result<Self> {
        Ok(Self {
            centre: candle_nn::linear(input, output, vb.pp("centre"))?,
            neighbour: candle_nn::linear_no_bias(input, output, vb.pp("neighbour"))?,
        })
    }

    /// From raw parts (tests, hand-set weights): `centre` is `W_c` (+ bias), `neighbour` `W_n`.
    pub fn from_parts(centre: Linear, neighbour: Linear) -> Self {
        Self { centre, neighbour }
    }

    /// `(W_c with b, W_n)` packed for the fused host projector.
    pub(crate) fn host_affines(&self) -> Result<(HostAffine, HostAffine)> {
        Ok((
            HostAffine::from_linear(&self.centre)?,
            HostAffine::from_linear(&self.neighbour)?,
        ))
    }

    /// Eq. 5.4: `features: (N, C_in)`, `graph` over the same N points → `(N, C_out)`.
    pub fn forward(&self, features: &Tensor, graph: &NeighbourIndex) -> Result<Tensor> {
        let (n, c) = features.dims2()?;
        if n != graph.len() {
            return Err(Error::Invalid {
                what: "GNN features".into(),
                reason: format!("{n} rows for a graph over {} points", graph.len()),
            });
        }
        let mean = if features.track_op() {
            self.gathered_mean(features, graph, n, c)?
        } else {
            // no autograd: one parallel sparse product, no N × W × C temporary
            let host: Vec<f32> = features.flatten_all()?.to_vec1()?;
            let mean = graph.mean_matrix()?.mul_dense(&host, c)?;
            Tensor::from_vec(mean, (n, c), features.device())?
        };
        let out = self
            .centre
            .forward(features)?
            .add(&self.neighbour.forward(&mean)?)?;
        Ok(out.relu()?)
    }

    /// The neighbour mean with differentiable candle gathers, in chunks.
    fn gathered_mean(
        &self,
        features: &Tensor,
        graph: &NeighbourIndex,
        n: usize,
        c: usize,
    ) -> Result<Tensor> {
        let w = graph.width();
        let mut means = Vec::with_capacity(n.div_ceil(CHUNK));
        let mut start = 0;
        while start < n {
            let len = CHUNK.min(n - start);
            let idx = graph.indices()?.narrow(0, start * w, len * w)?;
            let weights = graph.weights()?.narrow(0, start, len)?;
            let mean = features
                .index_select(&idx, 0)?
                .reshape((len, w, c))?
                .broadcast_mul(&weights)?
                .sum(1)?;
            means.push(mean);
            start += len;
        }
        Ok(if means.len() == 1 {
            means.swap_remove(0)
        } else {
            Tensor::cat(&means, 0)?
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use candle_core::Device;

    #[test]
    fn hand_computed_four_point_graph() {
        let dev = Device::Cpu;
        // 1-d features f = (1, 2, 3, -8); W_c = 2, b = 1, W_n = 3 (scalars).
        // graph: 0 → {1, 2}; 1 → {0}; 2 → {0, 1, 3}; 3 → {} (isolated).
        let gnn = MeanAggregationGnn::from_parts(
            Linear::new(
                Tensor::new(&[[2.0f32]], &dev).unwrap(),
                Some(Tensor::new(&[1.0f32], &dev).unwrap()),
            ),
            Linear::new(Tensor::new(&[[3.0f32]], &dev).unwrap(), None),
        );
        let g =
            NeighbourIndex::from_rows(&[vec![1, 2], vec![0], vec![0, 1, 3], vec![]], &dev).unwrap();
        let f = Tensor::new(&[[1.0f32], [2.0], [3.0], [-8.0]], &dev).unwrap();
        let y: Vec<f32> = gnn
            .forward(&f, &g)
            .unwrap()
            .flatten_all()
            .unwrap()
            .to_vec1()
            .unwrap();
        // 0: 2·1 + 1 + 3·(2+3)/2 = 10.5; 1: 2·2 + 1 + 3·1 = 8;
        // 2: 2·3 + 1 + 3·(1+2-8)/3 = 2; 3: relu(2·(-8) + 1 + 0) = 0
        let want = [10.5f32, 8.0, 2.0, 0.0];
        for (a, b) in y.iter().zip(want) {
            assert!((a - b).abs() < 1e-6, "{y:?}");
        }
    }

    #[test]
    fn autograd_gathers_match_the_sparse_product() {
        let dev = Device::Cpu;
        let n = CHUNK + 17;
        let rows: Vec<Vec<u32>> = (0..n)
            .map(|i| vec![((i + 1) % n) as u32, ((i * 7 + 3) % n) as u32])
            .collect();
        let g = NeighbourIndex::from_rows(&rows, &dev).unwrap();
        let f: Vec<f32> = (0..n).map(|i| (i % 13) as f32).collect();
        let ft = Tensor::from_vec(f.clone(), (n, 1), &dev).unwrap();
        let gnn = MeanAggregationGnn::from_parts(
            Linear::new(Tensor::new(&[[0.0f32]], &dev).unwrap(), None),
            Linear::new(Tensor::new(&[[1.0f32]], &dev).unwrap(), None),
        );
        let y: Vec<f32> = gnn
            .forward(&ft, &g)
            .unwrap()
            .flatten_all()
            .unwrap()
            .to_vec1()
            .unwrap();
        // the autograd path (chunked candle gathers) gives the same values
        let var = candle_core::Var::from_tensor(&ft).unwrap();
        let z: Vec<f32> = gnn
            .forward(var.as_tensor(), &g)
            .unwrap()
            .flatten_all()
            .unwrap()
            .to_vec1()
            .unwrap();
        assert_eq!(y, z);
        for (i, row) in rows.iter().enumerate() {
            let want = (f[row[0] as usize] + f[row[1] as usize]) / 2.0;
            assert_eq!(y[i], want, "row {i}");
        }
    }
}
