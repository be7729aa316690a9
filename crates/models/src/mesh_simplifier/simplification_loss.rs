//! The training objective of the neural mesh simplifier, thesis eq. 6.14, assembled from the
//! terms of meshgnn-losses for one forward pass: the probabilistic Chamfer distance between the
//! sampled and the original vertices (eq. 6.8), the probabilistic surface distances both ways
//! (eq. 6.9-6.10), and the collision, edge-crossing and overlap penalties of the candidate
//! triangles (eq. 6.11-6.13).
//!
//! # Conventions
//! - Everything is measured in the unit-sphere frame of [`MeshInput`].
//! - The reverse surface term compares against `surface_samples` points drawn on the original
//!   surface ([`SimplificationTarget::new`]); the forward term against the original faces'
//!   barycentres.
//! - The three penalties look at each candidate's `k = 20` nearest candidates (the face
//!   classifier's neighbourhood, ch. 6.4).

use candle_core::Tensor;
use meshgnn_geometry::sample_surface;
use meshgnn_losses::losses::{
    ReverseSurfaceParams, SimplificationTerms, SimplificationWeights, edge_crossings,
    probabilistic_chamfer, probabilistic_surface_forward, probabilistic_surface_reverse,
    simplification_objective, triangle_collision, triangle_overlap,
};
use meshgnn_losses::predicates::InsideTolerance;

use super::{MeshInput, SimplifierPass};
use crate::{Error, Result};

/// Candidates each penalty compares a candidate triangle with (ch. 6.4's k = 20).
pub const PENALTY_NEIGHBOURS: usize = 20;

/// What a simplification of one mesh is compared with, in the unit-sphere frame.
#[derive(Clone, Debug)]
pub struct SimplificationTarget {
    /// Barycentres of the original faces, `(F₀, 3)`.
    pub barycentres: Tensor,
    /// Points on the original surface, `(S, 3)`.
    pub surface_samples: Tensor,
}

impl SimplificationTarget {
    /// The target of the mesh `input` holds, in its unit-sphere frame, with `samples` surface
    /// points drawn with `seed`.
    pub fn new(input: &MeshInput, samples: usize, seed: u64) -> Result<Self> {
        let unit = &input.surface;
        let barycentres: Vec<[f32; 3]> =
            meshgnn_graph::triangle_barycentres(unit.vertices(), unit.triangles())?;
        let points = sample_surface(unit, samples, seed)?.points;
        let device = input.tensor.device();
        Ok(Self {
            barycentres: Tensor::from_slice(
                barycentres.as_flattened(),
                (barycentres.len(), 3),
                device,
            )?,
            surface_samples: Tensor::from_slice(points.as_flattened(), (points.len(), 3), device)?,
        })
    }
}

/// The six terms of eq. 6.14 for `pass` over `input`, compared with `target`. Errors when the
/// pass proposed no candidate triangle.
pub fn simplification_terms(
    pass: &SimplifierPass,
    input: &MeshInput,
    target: &SimplificationTarget,
) -> Result<SimplificationTerms> {
    let faces = &pass.candidates.triangles;
    if faces.is_empty() {
        return Err(Error::Invalid {
            what: "simplification pass".into(),
            reason: "proposed no candidate triangle".into(),
        });
    }
    let device = input.tensor.device();
    let sampled = &pass.sampled.indices;
    let index = Tensor::from_slice(sampled.as_slice(), sampled.len(), device)?;
    let vertices = input.tensor.index_select(&index, 0)?;
    let sample_probabilities = pass.sampled.probabilities.index_select(&index, 0)?;
    let corners: Vec<[f32; 3]> = sampled
        .iter()
        .map(|&i| input.surface.vertices()[i as usize])
        .collect();
    let p = &pass.face_probabilities;
    // A lone candidate has no neighbour to collide with, cross or overlap.
    let (collision, crossings, overlap) = match faces.len() {
        1 => {
            let zero = p.zeros_like()?.sum_all()?;
            (zero.clone(), zero.clone(), zero)
        }
        count => {
            let k = PENALTY_NEIGHBOURS.min(count - 1);
            (
                triangle_collision(&corners, faces, p, k)?,
                edge_crossings(&corners, faces, p, k)?,
                triangle_overlap(&corners, faces, p, k, InsideTolerance::default())?,
            )
        }
    };
    Ok(SimplificationTerms {
        probabilistic_chamfer: probabilistic_chamfer(
            &input.tensor,
            &vertices,
            &sample_probabilities,
        )?,
        surface_forward: probabilistic_surface_forward(&vertices, faces, p, &target.barycentres)?,
        surface_reverse: probabilistic_surface_reverse(
            &vertices,
            faces,
            p,
            &target.surface_samples,
            ReverseSurfaceParams::default(),
        )?,
        collision,
        edge_crossings: crossings,
        overlap,
    })
}

/// Eq. 6.14 for `pass`: the sum of [`simplification_terms`] with `weights` on the penalties.
pub fn simplification_loss(
    pass: &SimplifierPass,
    input: &MeshInput,
    target: &SimplificationTarget,
    weights: SimplificationWeights,
) -> Result<Tensor> {
    let terms = simplification_terms(pass, input, target)?;
    Ok(simplification_objective(&terms, weights)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh_simplifier::{NeuralMeshSimplifier, NeuralMeshSimplifierConfig};
    use candle_core::{DType, Device};
    use candle_nn::{VarBuilder, VarMap};

    #[test]
    fn every_term_is_finite_and_the_loss_reaches_all_three_modules() {
        let map = VarMap::new();
        let vb = VarBuilder::from_varmap(&map, DType::F32, &Device::Cpu);
        let mut config = NeuralMeshSimplifierConfig::default();
        config.faces.hidden = 32;
        let model = NeuralMeshSimplifier::new(vb, &config).unwrap();
        let mesh = meshgnn_geometry::icosphere(3);
        let input = MeshInput::new(&mesh, &Device::Cpu).unwrap();
        let target = SimplificationTarget::new(&input, 2000, 1).unwrap();
        let pass = model.forward(&input, 160, 2).unwrap();
        let terms = simplification_terms(&pass, &input, &target).unwrap();
        for (name, t) in [
            ("chamfer", &terms.probabilistic_chamfer),
            ("forward", &terms.surface_forward),
            ("reverse", &terms.surface_reverse),
            ("collision", &terms.collision),
            ("crossings", &terms.edge_crossings),
            ("overlap", &terms.overlap),
        ] {
            let v: f32 = t.to_scalar().unwrap();
            assert!(v.is_finite() && v >= 0.0, "{name} = {v}");
        }
        let loss = simplification_objective(&terms, SimplificationWeights::default()).unwrap();
        let grads = loss.backward().unwrap();
        let data = map.data().lock().unwrap();
        for name in [
            "sampler.layers.0.theta.weight",
            "edges.query.weight",
            "faces.layers.0.mlp.0.weight",
        ] {
            let g = grads.get(data[name].as_tensor()).unwrap();
            let norm: f32 = g.sqr().unwrap().sum_all().unwrap().to_scalar().unwrap();
            assert!(norm > 0.0 && norm.is_finite(), "{name}: |g|² = {norm}");
        }
    }
}
