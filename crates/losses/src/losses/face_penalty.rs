//! The shared form of thesis eq. 6.11-6.13: `(1/|F_s|) Σ_t p_t m(t)`, where `m(t)` counts the
//! nearby faces that face `t` conflicts with. Counts are computed on the detached geometry
//! (they are integers); the loss is differentiable in the face probabilities. "Nearby" is the
//! barycentre k-NN graph of the face classifier, [`meshgnn_graph::triangle_knn_graph`] (ch. 6.3).

use crate::losses::tensor_points::check_vector;
use crate::validate::{check_faces, check_points};
use crate::{Error, Result};
use candle_core::Tensor;
use meshgnn_graph::triangle_knn_graph;
use rayon::prelude::*;

/// The corner positions of face `f`.
pub(crate) fn corners(vertices: &[[f32; 3]], f: &[u32; 3]) -> [[f32; 3]; 3] {
    f.map(|i| vertices.get(i as usize).copied().unwrap_or([0.0; 3]))
}

/// For each face, `m(t) = Σ_{u ∈ N_k(t)} conflict(t, u)` over its `k` nearest other faces by
/// barycentre (all others when fewer than `k`); then `(1/F) Σ_t p_t m(t)` with
/// `face_probs: (F)`.
pub(crate) fn face_penalty<C>(
    vertices: &[[f32; 3]],
    faces: &[[u32; 3]],
    face_probs: &Tensor,
    k: usize,
    conflict: C,
) -> Result<Tensor>
where
    C: Fn(&[[f32; 3]; 3], &[[f32; 3]; 3]) -> usize + Sync,
{
    check_points("vertices", vertices)?;
    if faces.is_empty() {
        return Err(Error::Empty { what: "faces" });
    }
    check_faces("faces", faces, vertices.len())?;
    check_vector("face probabilities", face_probs, faces.len())?;
    let counts = conflict_counts(vertices, faces, k, conflict)?;
    let m =
        Tensor::from_vec(counts, faces.len(), face_probs.device())?.to_dtype(face_probs.dtype())?;
    Ok(face_probs.mul(&m)?.mean_all()?)
}

/// `m(t)` for every face (see [`face_penalty`]), in parallel. `vertices` and `faces` are
/// checked by the caller.
pub(crate) fn conflict_counts<C>(
    vertices: &[[f32; 3]],
    faces: &[[u32; 3]],
    k: usize,
    conflict: C,
) -> Result<Vec<f32>>
where
    C: Fn(&[[f32; 3]; 3], &[[f32; 3]; 3]) -> usize + Sync,
{
    let k = k.min(faces.len().saturating_sub(1));
    if k == 0 {
        return Ok(vec![0.0; faces.len()]);
    }
    let tris: Vec<[[f32; 3]; 3]> = faces.iter().map(|f| corners(vertices, f)).collect();
    let nearby = triangle_knn_graph(vertices, faces, k)?;
    Ok(tris
        .par_iter()
        .zip(nearby.indices.par_chunks(k))
        .map(|(t, row)| {
            row.iter()
                .filter_map(|&j| tris.get(j as usize))
                .map(|u| conflict(t, u))
                .sum::<usize>() as f32
        })
        .collect())
}
