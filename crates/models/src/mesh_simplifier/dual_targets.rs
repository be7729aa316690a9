//! Supervised targets for the edge predictor and the face classifier: the triangulation dual
//! to the nearest-seed Voronoi partition of the input by the sampled vertices
//! ([`super::SimplifierPass::dual`]). Beyond the thesis: the eq. 6.14 objective weights every
//! term by a face probability and is minimised by dropping every face
//! (docs/mesh_simplifier_model.md), while the dual is a near-manifold surface through exactly
//! the sampled vertices, so "is this candidate a dual triangle" and "is this pair a dual edge"
//! are labels that discriminate. (Until 5 December the target was the geodesic partition's
//! dual, which the classifier's inputs cannot decide where candidates compete: raw WA 70 %.)
//!
//! - Faces: binary cross-entropy between `p_t` and membership of the candidate in the dual.
//! - Edges: for every sampled vertex with dual edges, the share of its `A_s` row (eq. 6.4)
//!   that falls on them, as a negative log (a cross-entropy over the row), so dual edges rank
//!   first in the strongest-entries pattern candidates are built from.

use std::collections::HashSet;

use candle_core::{D, Tensor};

use super::SimplifierPass;
use super::candidate_features::sorted_corners;
use crate::Result;

/// Smallest probability a logarithm sees.
const LOG_FLOOR: f64 = 1e-6;

/// The dual of one pass's sampled vertices, as labels on its candidates and pairs.
#[derive(Clone, Debug)]
pub struct DualTargets {
    /// 1 for candidates that are dual triangles, else 0, `(F)`.
    pub face_labels: Tensor,
    /// Indices into [`super::ExtendedGraph::pairs`] of the dual edges present there.
    pub edge_pairs: Tensor,
    /// Rows (sampled vertices) of those pairs.
    pub edge_rows: Tensor,
    /// Dual triangles, and how many of them are candidates.
    pub dual_faces: usize,
    /// Dual triangles among the candidates.
    pub candidate_hits: usize,
}

impl DualTargets {
    /// The labels of `pass`'s candidates and pairs.
    pub fn new(pass: &SimplifierPass) -> Result<Self> {
        let dual = &pass.dual;
        let dual_set: HashSet<[u32; 3]> = dual.iter().map(sorted_corners).collect();
        let labels: Vec<f32> = pass
            .candidates
            .triangles
            .iter()
            .map(|t| f32::from(u8::from(dual_set.contains(&sorted_corners(t)))))
            .collect();
        let candidate_hits = labels.iter().filter(|&&l| l > 0.0).count();
        let mut dual_edges = HashSet::new();
        for t in dual {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                dual_edges.insert([a, b]);
                dual_edges.insert([b, a]);
            }
        }
        let (mut pairs, mut rows) = (Vec::new(), Vec::new());
        for (e, pair) in pass.graph.pairs().iter().enumerate() {
            if dual_edges.contains(pair) {
                pairs.push(e as u32);
                rows.push(pair[0]);
            }
        }
        let device = pass.face_probabilities.device();
        let count = labels.len();
        Ok(Self {
            face_labels: Tensor::from_vec(labels, count, device)?,
            edge_pairs: Tensor::from_slice(&pairs, pairs.len(), device)?,
            edge_rows: Tensor::from_slice(&rows, rows.len(), device)?,
            dual_faces: dual.len(),
            candidate_hits,
        })
    }

    /// Class-balanced binary cross-entropy of the pass's face probabilities against the
    /// labels: the mean over dual candidates and the mean over the others, averaged. About one
    /// candidate in ten is a dual triangle; unbalanced, every probability sank below 0.5
    /// within 50 steps (measured).
    pub fn face_loss(&self, pass: &SimplifierPass) -> Result<Tensor> {
        let p = pass.face_probabilities.clamp(LOG_FLOOR, 1.0 - LOG_FLOOR)?;
        let y = &self.face_labels;
        let count = y.dims1()? as f64;
        let positives = (self.candidate_hits as f64).max(1.0);
        let negatives = (count - self.candidate_hits as f64).max(1.0);
        let positive = y.mul(&p.log()?)?.sum_all()?.affine(0.5 / positives, 0.0)?;
        let negative = y
            .affine(-1.0, 1.0)?
            .mul(&p.affine(-1.0, 1.0)?.log()?)?
            .sum_all()?
            .affine(0.5 / negatives, 0.0)?;
        Ok(positive.add(&negative)?.neg()?)
    }

    /// Mean over the dual edges of `−log(A_s[a, b] / Σ_c A_s[a, c])`; 0 without dual edges.
    pub fn edge_loss(&self, pass: &SimplifierPass) -> Result<Tensor> {
        let values = &pass.edge_weights;
        if self.edge_pairs.dims1()? == 0 {
            return Ok(values.zeros_like()?.sum_all()?);
        }
        let rows: Vec<u32> = pass.graph.pairs().iter().map(|p| p[0]).collect();
        let rows = Tensor::from_vec(rows, values.dims1()?, values.device())?;
        let m = pass.graph.sampled().len();
        let row_sums =
            Tensor::zeros(m, values.dtype(), values.device())?.index_add(&rows, values, 0)?;
        let share = values
            .index_select(&self.edge_pairs, 0)?
            .div(&row_sums.index_select(&self.edge_rows, 0)?)?
            .clamp(LOG_FLOOR, 1.0)?;
        Ok(share.log()?.mean(D::Minus1)?.neg()?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh_simplifier::{
        FaceClassifierConfig, MeshInput, NeuralMeshSimplifier, NeuralMeshSimplifierConfig,
    };
    use candle_core::{DType, Device};
    use candle_nn::{VarBuilder, VarMap};

    /// A pass keeping every vertex of icosphere(1), with every A_s entry a candidate edge.
    fn full_pass() -> SimplifierPass {
        let map = VarMap::new();
        let vb = VarBuilder::from_varmap(&map, DType::F32, &Device::Cpu);
        let mut config = NeuralMeshSimplifierConfig::default();
        config.edges.candidate_neighbours = 64;
        config.faces = FaceClassifierConfig {
            hidden: 8,
            ..Default::default()
        };
        let model = NeuralMeshSimplifier::new(vb, &config).unwrap();
        let mesh = meshgnn_geometry::icosphere(1);
        let input = MeshInput::new(&mesh, &Device::Cpu).unwrap();
        model.forward(&input, 42, 3).unwrap()
    }

    #[test]
    fn with_every_vertex_drawn_the_dual_is_the_mesh_and_every_face_a_candidate() {
        let pass = full_pass();
        let targets = DualTargets::new(&pass).unwrap();
        assert_eq!((targets.dual_faces, targets.candidate_hits), (80, 80));
        let labels: Vec<f32> = targets.face_labels.to_vec1().unwrap();
        assert_eq!(labels.iter().sum::<f32>(), 80.0);
        // Every mesh edge, both ways, is a dual edge among the pairs.
        assert_eq!(targets.edge_pairs.dims1().unwrap(), 2 * 120);
    }

    #[test]
    fn losses_match_hand_computations() {
        let mut pass = full_pass();
        let targets = DualTargets::new(&pass).unwrap();
        let labels: Vec<f32> = targets.face_labels.to_vec1().unwrap();
        let count = labels.len();
        // p = 0.8 on dual candidates and 0.3 elsewhere: −(ln 0.8 + ln 0.7) / 2.
        let p: Vec<f32> = labels
            .iter()
            .map(|&y| if y > 0.0 { 0.8 } else { 0.3 })
            .collect();
        pass.face_probabilities = Tensor::from_vec(p, count, &Device::Cpu).unwrap();
        let face: f32 = targets.face_loss(&pass).unwrap().to_scalar().unwrap();
        let want = -(0.8f32.ln() + 0.7f32.ln()) / 2.0;
        assert!((face - want).abs() < 1e-5, "{face} vs {want}");
        // All of each row's mass on its dual edges, spread evenly: −ln(1 / degree).
        let dual: Vec<u32> = targets.edge_pairs.to_vec1().unwrap();
        let pairs = pass.graph.pairs().len();
        let mut weights = vec![0f32; pairs];
        for &e in &dual {
            weights[e as usize] = 1.0;
        }
        pass.edge_weights = Tensor::from_vec(weights, pairs, &Device::Cpu).unwrap();
        let rows: Vec<u32> = targets.edge_rows.to_vec1().unwrap();
        let mut degree = [0f32; 42];
        for &r in &rows {
            degree[r as usize] += 1.0;
        }
        let want = rows.iter().map(|&r| degree[r as usize].ln()).sum::<f32>() / rows.len() as f32;
        let edge: f32 = targets.edge_loss(&pass).unwrap().to_scalar().unwrap();
        assert!((edge - want).abs() < 1e-5, "{edge} vs {want}");
    }
}
