//! Faces beyond two per edge, in expectation: a smooth penalty on the edges a face classifier's
//! candidates would make non-manifold. Beyond the thesis: its WA (ch. 6.5.1) counts the edges
//! with one or with three and more faces, and a classifier trained on a target alone keeps
//! competing candidates on the same edge (docs/mesh_simplifier_model.md, "Where the raw WA is
//! lost"); this term makes them compete.

use crate::losses::tensor_points::{check_vector, index_tensor};
use crate::{Error, Result};
use candle_core::Tensor;

/// `L = (1/E) Σ_e max(0, s_e − 2)²` with `s_e = Σ_{t ∋ e} p_t`, over the `E` distinct
/// undirected edges of `faces` (`#F×3`, any vertex numbering); `face_probs: (F)`.
/// Differentiable in the probabilities: `∂L/∂p_t = (2/E) Σ_{e ∈ t} max(0, s_e − 2)`, so only
/// faces on over-full edges are pushed down, all of them alike; a target-aware term beside it
/// decides which survive.
///
/// ```
/// use candle_core::{Device, Tensor};
/// use meshgnn_losses::losses::edge_valence_excess;
/// // Three certain faces on the edge (0, 1): s = 3 there, 1 on the six other edges.
/// let faces = [[0, 1, 2], [1, 0, 3], [0, 1, 4]];
/// let p = Tensor::new(&[1.0f32, 1.0, 1.0], &Device::Cpu)?;
/// let l = edge_valence_excess(&faces, &p)?.to_scalar::<f32>()?;
/// assert!((l - 1.0 / 7.0).abs() < 1e-7);
/// # Ok::<(), meshgnn_losses::Error>(())
/// ```
pub fn edge_valence_excess(faces: &[[u32; 3]], face_probs: &Tensor) -> Result<Tensor> {
    if faces.is_empty() {
        return Err(Error::Empty { what: "faces" });
    }
    check_vector("face probabilities", face_probs, faces.len())?;
    // Every (edge, face) incidence, sorted by edge: runs of equal keys are one edge.
    let mut incidences: Vec<(u32, u32, u32)> = faces
        .iter()
        .enumerate()
        .flat_map(|(f, t)| {
            (0..3).map(move |k| {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                (a.min(b), a.max(b), f as u32)
            })
        })
        .collect();
    incidences.sort_unstable();
    let mut edge_of_incidence = Vec::with_capacity(incidences.len());
    let mut edges = 0u32;
    for (i, &(a, b, _)) in incidences.iter().enumerate() {
        if i > 0 && (incidences[i - 1].0, incidences[i - 1].1) != (a, b) {
            edges += 1;
        }
        edge_of_incidence.push(edges);
    }
    let edge_count = edges as usize + 1;
    let device = face_probs.device();
    let face_of_incidence = incidences.iter().map(|&(_, _, f)| f).collect();
    let per_incidence = face_probs.index_select(&index_tensor(face_of_incidence, device)?, 0)?;
    let expected_faces = Tensor::zeros(edge_count, face_probs.dtype(), device)?.index_add(
        &index_tensor(edge_of_incidence, device)?,
        &per_incidence,
        0,
    )?;
    let excess = expected_faces.affine(1.0, -2.0)?.relu()?;
    Ok(excess
        .sqr()?
        .sum_all()?
        .affine(1.0 / edge_count as f64, 0.0)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::losses::gradient_check::assert_gradient_matches;
    use candle_core::Device;

    #[test]
    fn a_closed_manifold_costs_nothing_and_a_doubled_face_does() {
        let sphere = meshgnn_geometry::icosphere(2);
        let faces = sphere.triangles();
        let ones = Tensor::ones(faces.len(), candle_core::DType::F32, &Device::Cpu).unwrap();
        let l: f32 = edge_valence_excess(faces, &ones)
            .unwrap()
            .to_scalar()
            .unwrap();
        assert_eq!(l, 0.0);
        // One face listed twice: its three edges carry three faces each, E unchanged.
        let mut doubled = faces.to_vec();
        doubled.push(faces[0]);
        let ones = Tensor::ones(doubled.len(), candle_core::DType::F32, &Device::Cpu).unwrap();
        let l: f32 = edge_valence_excess(&doubled, &ones)
            .unwrap()
            .to_scalar()
            .unwrap();
        let edges = 3 * faces.len() / 2;
        assert!((l - 3.0 / edges as f32).abs() < 1e-7, "{l}");
    }

    #[test]
    fn gradient_matches_finite_differences_and_the_hand_computed_value() {
        // A fan of four faces on the edge (0, 1) and one face elsewhere: 12 edges,
        // s(0, 1) = 2.6, so ∂L/∂p = 2 · 0.6 / 12 = 0.1 on the fan and 0 on the lone face.
        let faces = [[0, 1, 2], [1, 0, 3], [0, 1, 4], [0, 1, 5], [2, 3, 6]];
        let p = Tensor::new(&[0.9f64, 0.8, 0.5, 0.4, 0.7], &Device::Cpu).unwrap();
        assert_gradient_matches(&p, |p| edge_valence_excess(&faces, p), 1e-6);
        let p = candle_core::Var::from_tensor(&p).unwrap();
        let grads = edge_valence_excess(&faces, &p).unwrap().backward().unwrap();
        let g: Vec<f64> = grads.get(&p).unwrap().to_vec1().unwrap();
        for (got, want) in g.iter().zip([0.1, 0.1, 0.1, 0.1, 0.0]) {
            assert!((got - want).abs() < 1e-12, "{g:?}");
        }
    }

    #[test]
    fn mismatched_probabilities_and_no_faces_are_refused() {
        let p = Tensor::new(&[0.5f32], &Device::Cpu).unwrap();
        assert!(edge_valence_excess(&[[0, 1, 2], [1, 2, 3]], &p).is_err());
        assert!(edge_valence_excess(&[], &p).is_err());
    }
}
