//! The edge predictor of the neural mesh simplifier (thesis ch. 6.3.2): a DevConv layer
//! (eq. 6.1, hidden 64) on the extended graph, sparse self-attention over each vertex's
//! extended neighbourhood (eq. 6.2), the simplified adjacency `A_s = Ŝᵀ A Ŝ` (eq. 6.3-6.4) and
//! the candidate triangles with their prior probability (eq. 6.5). Sparse throughout: the
//! attention lives on the graph's slots and `A_s` on its non-zero pattern
//! ([`ExtendedGraph`]); no `N×M` or `M×M` matrix is ever dense.
//!
//! Eq. 6.2 as printed: `S[i, j] = softmax_j((W_q f_j)ᵀ (W_k f_i))` over the neighbourhood of
//! `i` (here including `i`, see [`ExtendedGraph`]), without a `1/√d` scale.

use candle_core::{D, Tensor};
use candle_nn::{Linear, Module, VarBuilder};
use rayon::prelude::*;

use super::{DevConv, DevConvConfig, ExtendedGraph, slot_dot_products};
use crate::{Error, Result};

/// Hyper-parameters; defaults are the thesis' (ch. 6.4).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EdgePredictorConfig {
    /// Channels of the DevConv layer and of the attention projections (64).
    pub hidden: usize,
    /// k of the k-NN graph over the sampled vertices that extends the adjacency (15).
    pub neighbours: usize,
    /// Strongest `A_s` entries per sampled vertex that candidate triangles are built from
    /// (beyond the thesis, [`ExtendedGraph::strongest_pattern`]; the dual's edges are always
    /// added, so every dual triangle is a candidate; retrained each time, 10 gives the CD of
    /// 16 and 12 with fewer candidates for the face classifier, 8 a real-set CD 4 % higher at
    /// 20 %; docs/mesh_simplifier_model.md, "Sequential stages off the critical path").
    pub candidate_neighbours: usize,
}

impl Default for EdgePredictorConfig {
    fn default() -> Self {
        Self {
            hidden: 64,
            neighbours: 15,
            candidate_neighbours: 10,
        }
    }
}

/// One forward pass of the edge predictor.
#[derive(Clone, Debug)]
pub struct EdgePrediction {
    /// `S` of eq. 6.2 on the attention slots, `(N, W)`; every row sums to 1.
    pub attention: Tensor,
    /// `A_s` of eq. 6.4 on [`ExtendedGraph::pairs`], `(nnz)`.
    pub adjacency: Tensor,
    /// [`EdgePredictorConfig::candidate_neighbours`].
    pub candidate_neighbours: usize,
}

/// Candidate triangles (eq. 6.5).
#[derive(Clone, Debug)]
pub struct CandidateFaces {
    /// Every 3-clique `[a, b, c]` (`a < b < c`, sampled-vertex numbering) of `A_s`.
    pub triangles: Vec<[u32; 3]>,
    /// `p_init` of every triangle, `(F)`: the mean of its three `A_s` entries.
    pub prior: Tensor,
}

/// DevConv `conv`, attention projections `query` and `key` (no biases).
#[derive(Clone, Debug)]
pub struct EdgePredictor {
    conv: DevConv,
    query: Linear,
    key: Linear,
    candidate_neighbours: usize,
}

impl EdgePredictor {
    /// The predictor of `config`, parameters under `vb`.
    pub fn new(vb: VarBuilder, config: &EdgePredictorConfig) -> Result<Self> {
        let h = config.hidden;
        Ok(Self {
            conv: DevConv::new(
                vb.pp("conv"),
                &DevConvConfig {
                    input: 3,
                    output: h,
                },
            )?,
            query: candle_nn::linear_no_bias(h, h, vb.pp("query"))?,
            key: candle_nn::linear_no_bias(h, h, vb.pp("key"))?,
            candidate_neighbours: config.candidate_neighbours,
        })
    }

    /// Eq. 6.1-6.4 on `positions: (N, 3)` over `graph`.
    pub fn forward(&self, positions: &Tensor, graph: &ExtendedGraph) -> Result<EdgePrediction> {
        let slots = &graph.attention_slots;
        let (n, _) = positions.dims2()?;
        if n != slots.len() {
            return Err(Error::Invalid {
                what: "edge predictor positions".into(),
                reason: format!("{n} rows for a graph over {} points", slots.len()),
            });
        }
        let features = self.conv.forward(positions, &graph.conv_slots)?;
        let query = self.query.forward(&features)?;
        let key = self.key.forward(&features)?;
        // Empty slots (index N) give 0; their logits are masked here.
        let logits = slot_dot_products(&query, &key, slots.indices())?
            .add(&graph.attention_mask.to_dtype(query.dtype())?)?;
        // `softmax`, not `softmax_last_dim`: the fused kernel has no backward pass.
        let attention = candle_nn::ops::softmax(&logits, D::Minus1)?;
        let adjacency = graph.simplified_adjacency(&attention)?;
        Ok(EdgePrediction {
            attention,
            adjacency,
            candidate_neighbours: self.candidate_neighbours,
        })
    }
}

impl EdgePrediction {
    /// Eq. 6.5: the 3-cliques of the strongest entries of `A_s`
    /// ([`ExtendedGraph::strongest_pattern`]) and their prior
    /// `(A_s[a,b] + A_s[a,c] + A_s[b,c]) / 3`.
    pub fn candidate_faces(&self, graph: &ExtendedGraph) -> Result<CandidateFaces> {
        let values: Vec<f32> = self
            .adjacency
            .detach()
            .to_dtype(candle_core::DType::F32)?
            .to_vec1()?;
        let pattern = graph.strongest_pattern(&values, self.candidate_neighbours)?;
        let triangles = meshgnn_graph::candidate_triangles(&pattern)?;
        let pair_index = |u: u32, v: u32| -> Result<u32> {
            let index = graph.pair_index(u, v).ok_or_else(|| Error::Invalid {
                what: format!("candidate edge ({u}, {v})"),
                reason: "missing from the simplified adjacency".into(),
            })?;
            Ok(index as u32)
        };
        let entries: Vec<[u32; 3]> = triangles
            .par_iter()
            .map(|&[a, b, c]| Ok([pair_index(a, b)?, pair_index(a, c)?, pair_index(b, c)?]))
            .collect::<Result<_>>()?;
        let count = triangles.len();
        let entries =
            Tensor::from_vec(entries.into_flattened(), count * 3, self.adjacency.device())?;
        let prior = self
            .adjacency
            .index_select(&entries, 0)?
            .reshape((count, 3))?
            .mean(D::Minus1)?;
        Ok(CandidateFaces { triangles, prior })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use candle_core::{DType, Device};
    use candle_nn::VarMap;
    use meshgnn_graph::{CsrMatrix, vertex_adjacency};

    fn predictor(dtype: DType) -> (VarMap, EdgePredictor) {
        let map = VarMap::new();
        let vb = VarBuilder::from_varmap(&map, dtype, &Device::Cpu);
        let config = EdgePredictorConfig {
            hidden: 8,
            neighbours: 4,
            candidate_neighbours: 64, // every A_s entry
        };
        let model = EdgePredictor::new(vb, &config).unwrap();
        (map, model)
    }

    fn setup(sampled: &[u32]) -> (Vec<[f32; 3]>, CsrMatrix, ExtendedGraph) {
        let mesh = meshgnn_geometry::icosphere(1); // 42 vertices
        let adjacency = vertex_adjacency(&mesh).unwrap();
        let points = mesh.vertices().to_vec();
        let graph = ExtendedGraph::new(&points, &adjacency, sampled, 4, &[], &Device::Cpu).unwrap();
        (points, adjacency, graph)
    }

    /// `ŜᵀAŜ` computed densely from the attention rows, for comparison.
    fn dense_product(graph: &ExtendedGraph, attention: &[Vec<f64>]) -> Vec<Vec<f64>> {
        let n = attention.len();
        let width = graph.attention_slots.width();
        let slots: Vec<u32> = graph.attention_slots.indices().to_vec1().unwrap();
        let mut s = vec![vec![0.0; n]; n];
        let mut a = vec![vec![0.0; n]; n];
        for i in 0..n {
            for k in 0..width {
                let j = slots[i * width + k] as usize;
                if j < n {
                    s[i][j] = attention[i][k];
                    a[i][j] = 1.0; // A_ext + I: the attention row's members
                }
            }
        }
        let idx = graph.sampled();
        let m = idx.len();
        let mut out = vec![vec![0.0; m]; m];
        for (p, &ia) in idx.iter().enumerate() {
            for (q, &ib) in idx.iter().enumerate() {
                let mut total = 0.0;
                for i in 0..n {
                    for j in 0..n {
                        total += s[i][ia as usize] * a[i][j] * s[j][ib as usize];
                    }
                }
                out[p][q] = total;
            }
        }
        out
    }

    #[test]
    fn sparse_product_equals_the_dense_equation() {
        let sampled: Vec<u32> = (0..42).step_by(3).collect();
        let (points, _, graph) = setup(&sampled);
        let (_, model) = predictor(DType::F64);
        let x = Tensor::from_slice(points.as_flattened(), (42, 3), &Device::Cpu)
            .unwrap()
            .to_dtype(DType::F64)
            .unwrap();
        let out = model.forward(&x, &graph).unwrap();
        let attention: Vec<Vec<f64>> = out.attention.to_vec2().unwrap();
        for row in &attention {
            assert!((row.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        }
        let dense = dense_product(&graph, &attention);
        let values: Vec<f64> = out.adjacency.to_vec1().unwrap();
        // A_s is evaluated on the sampled pairs linked in the extended graph, exactly there.
        let width = graph.attention_slots.width();
        let slots: Vec<u32> = graph.attention_slots.indices().to_vec1().unwrap();
        let linked = |a: u32, b: u32| {
            let row = &slots[a as usize * width..(a as usize + 1) * width];
            row.contains(&b)
        };
        let mut evaluated = 0;
        let mut outside = 0;
        for (p, row) in dense.iter().enumerate() {
            for (q, &expected) in row.iter().enumerate() {
                if p == q {
                    continue;
                }
                let (i, j) = (sampled[p], sampled[q]);
                match graph.pair_index(p as u32, q as u32) {
                    Some(e) => {
                        assert!(linked(i, j), "({p}, {q}) not linked");
                        assert!((values[e] - expected).abs() <= 1e-12, "({p}, {q})");
                        assert!(expected > 0.0);
                        evaluated += 1;
                    }
                    None if linked(i, j) => panic!("linked pair ({p}, {q}) missing"),
                    None => outside += usize::from(expected > 0.0),
                }
            }
        }
        assert_eq!(evaluated, graph.pairs().len());
        assert!(outside > 0, "the restriction should drop some 2-hop pairs");
        // symmetric pattern
        for &[a, b] in graph.pairs() {
            assert!(graph.pair_index(b, a).is_some());
        }
    }

    #[test]
    fn every_face_survives_when_every_vertex_is_sampled_and_gradients_flow() {
        let all: Vec<u32> = (0..42).collect();
        let (points, _, graph) = setup(&all);
        let (map, model) = predictor(DType::F32);
        let x = Tensor::from_slice(points.as_flattened(), (42, 3), &Device::Cpu).unwrap();
        let out = model.forward(&x, &graph).unwrap();
        let faces = out.candidate_faces(&graph).unwrap();
        let mesh = meshgnn_geometry::icosphere(1);
        for t in mesh.triangles() {
            let mut t = *t;
            t.sort_unstable();
            assert!(faces.triangles.contains(&t), "face {t:?} not a candidate");
        }
        let prior: Vec<f32> = faces.prior.to_vec1().unwrap();
        assert_eq!(prior.len(), faces.triangles.len());
        assert!(prior.iter().all(|&p| p > 0.0 && p.is_finite()));
        let grads = faces.prior.sum_all().unwrap().backward().unwrap();
        let data = map.data().lock().unwrap();
        for name in ["conv.theta.weight", "query.weight", "key.weight"] {
            let g = grads.get(data[name].as_tensor()).unwrap();
            let norm: f32 = g.sqr().unwrap().sum_all().unwrap().to_scalar().unwrap();
            assert!(norm > 0.0, "{name}");
        }
    }

    #[test]
    fn the_knn_extension_links_every_sampled_vertex() {
        // Two far-apart sampled vertices of a sparse sample still get a link.
        let (_, _, graph) = setup(&[0, 41]);
        assert!(graph.pair_index(0, 1).is_some());
        let repeated = ExtendedGraph::new(
            meshgnn_geometry::icosphere(1).vertices(),
            &vertex_adjacency(&meshgnn_geometry::icosphere(1)).unwrap(),
            &[3, 3],
            4,
            &[],
            &Device::Cpu,
        );
        assert!(repeated.is_err());
    }

    #[test]
    fn dual_triangles_link_their_corners() {
        let mesh = meshgnn_geometry::icosphere(1);
        let adjacency = vertex_adjacency(&mesh).unwrap();
        let sampled = [0, 5, 41];
        let graph = |dual: &[[u32; 3]]| {
            ExtendedGraph::new(mesh.vertices(), &adjacency, &sampled, 0, dual, &Device::Cpu)
        };
        // Without k-NN links the three far-apart vertices share no edge ...
        assert!(graph(&[]).unwrap().pairs().is_empty());
        // ... and a dual triangle over them links all three, both ways.
        let linked = graph(&[[0, 1, 2]]).unwrap();
        assert_eq!(
            linked.pairs(),
            &[[0, 1], [0, 2], [1, 0], [1, 2], [2, 0], [2, 1]]
        );
        // Its edges are candidates even when no A_s entry is among the strongest (k = 0).
        let pattern = linked.strongest_pattern(&[0.0; 6], 0).unwrap();
        assert_eq!(
            meshgnn_graph::candidate_triangles(&pattern).unwrap(),
            vec![[0, 1, 2]]
        );
        assert!(graph(&[[0, 1, 3]]).is_err());
    }
}
