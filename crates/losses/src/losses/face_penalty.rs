//! The shared form of thesis eq. 6.11-6.13: `(1/|F_s|) Σ_t p_t m(t)`, where `m(t)` counts the
//! nearby faces that face `t` conflicts with. Counts are computed on the detached geometry
//! (they are integers); the loss is differentiable in the face probabilities.

use crate::losses::tensor_points::check_vector;
use crate::point_index::PointIndex;
use crate::validate::{check_faces, check_points};
use crate::{Error, Result};
use candle_core::Tensor;
use rayon::prelude::*;

/// The corner positions of face `f`.
pub(crate) fn corners(vertices: &[[f32; 3]], f: &[u32; 3]) -> [[f32; 3]; 3] {
    f.map(|i| vertices.get(i as usize).copied().unwrap_or([0.0; 3]))
}

/// For each face, `m(t) = Σ_{u ∈ N_k(t)} conflict(t, u)` over its `k` nearest other faces by
/// barycentre; then `(1/F) Σ_t p_t m(t)` with `face_probs: (F)`.
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
    let counts = conflict_counts(vertices, faces, k, conflict);
    let m =
        Tensor::from_vec(counts, faces.len(), face_probs.device())?.to_dtype(face_probs.dtype())?;
    Ok(face_probs.mul(&m)?.mean_all()?)
}

/// `m(t)` for every face (see [`face_penalty`]), in parallel.
pub(crate) fn conflict_counts<C>(
    vertices: &[[f32; 3]],
    faces: &[[u32; 3]],
    k: usize,
    conflict: C,
) -> Vec<f32>
where
    C: Fn(&[[f32; 3]; 3], &[[f32; 3]; 3]) -> usize + Sync,
{
    let tris: Vec<[[f32; 3]; 3]> = faces.iter().map(|f| corners(vertices, f)).collect();
    let centres: Vec<[f32; 3]> = tris
        .iter()
        .map(|t| {
            std::array::from_fn(|c| {
                ((f64::from(t[0][c]) + f64::from(t[1][c]) + f64::from(t[2][c])) / 3.0) as f32
            })
        })
        .collect();
    let tree = PointIndex::new(&centres);
    tris.par_iter()
        .zip(centres.par_iter())
        .enumerate()
        .map(|(i, (t, c))| {
            tree.nearest_k(c, k + 1)
                .into_iter()
                .filter(|(j, _)| *j != i)
                .take(k)
                .filter_map(|(j, _)| tris.get(j))
                .map(|u| conflict(t, u))
                .sum::<usize>() as f32
        })
        .collect()
}
