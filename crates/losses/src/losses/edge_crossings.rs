//! Edge crossings loss (thesis eq. 6.12).

use crate::Result;
use crate::losses::face_penalty::face_penalty;
use crate::predicates::edge_crossing_count;
use candle_core::Tensor;

/// Eq. 6.12: `L_e = (1/|F_s|) Σ_t p_t m_e(t)`, `m_e(t)` the number of (edge of `t`, edge of
/// `u`) pairs that cross ([`crate::predicates::edge_crossing_count`], at most 9 per
/// neighbour) over the `k` nearest faces `u` by barycentre. `vertices: #V×3`, `faces: #F×3`,
/// `face_probs: (F)`; differentiable in the probabilities.
///
/// ```
/// use candle_core::{Device, Tensor};
/// use meshgnn_losses::losses::edge_crossings;
/// let v = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0],
///          [0.5, 0.5, 0.0], [2.5, 0.5, 0.0], [0.5, 2.5, 0.0]];
/// let p = Tensor::new(&[1.0f32, 0.5], &Device::Cpu)?;
/// let l = edge_crossings(&v, &[[0, 1, 2], [3, 4, 5]], &p, 20)?;
/// assert_eq!(l.to_scalar::<f32>()?, 1.5); // two crossings each: (1·2 + 0.5·2) / 2
/// # Ok::<(), meshgnn_losses::Error>(())
/// ```
pub fn edge_crossings(
    vertices: &[[f32; 3]],
    faces: &[[u32; 3]],
    face_probs: &Tensor,
    k: usize,
) -> Result<Tensor> {
    face_penalty(vertices, faces, face_probs, k, edge_crossing_count)
}
