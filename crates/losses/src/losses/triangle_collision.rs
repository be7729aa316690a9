//! Triangle collision loss (thesis eq. 6.11).

use crate::Result;
use crate::losses::face_penalty::face_penalty;
use crate::predicates::triangles_intersect;
use candle_core::Tensor;

/// Eq. 6.11: `L_c = (1/|F_s|) Σ_t p_t m_c(t)`, `m_c(t)` the number of faces among the `k`
/// nearest (by barycentre; the thesis' face classifier uses k = 20) that `t` penetrates
/// ([`crate::predicates::triangles_intersect`]: an edge of one properly pierces the other;
/// mesh neighbours sharing an edge or vertex do not count). `vertices: #V×3`, `faces: #F×3`,
/// `face_probs: (F)`; differentiable in the probabilities.
///
/// ```
/// use candle_core::{Device, Tensor};
/// use meshgnn_losses::losses::triangle_collision;
/// let v = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0],
///          [0.5, 0.5, -1.0], [0.5, 0.5, 1.0], [3.0, 3.0, 0.5]];
/// let p = Tensor::new(&[0.5f32, 1.0], &Device::Cpu)?;
/// let l = triangle_collision(&v, &[[0, 1, 2], [3, 4, 5]], &p, 20)?;
/// assert_eq!(l.to_scalar::<f32>()?, 0.75); // (0.5·1 + 1·1) / 2
/// # Ok::<(), meshgnn_losses::Error>(())
/// ```
pub fn triangle_collision(
    vertices: &[[f32; 3]],
    faces: &[[u32; 3]],
    face_probs: &Tensor,
    k: usize,
) -> Result<Tensor> {
    face_penalty(vertices, faces, face_probs, k, |t, u| {
        usize::from(triangles_intersect(t, u))
    })
}
