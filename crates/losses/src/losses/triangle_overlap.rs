//! Overlapping triangles loss (thesis eq. 6.13).

use crate::Result;
use crate::losses::face_penalty::face_penalty;
use crate::predicates::{InsideTolerance, triangle_lattice, triangles_overlap};
use candle_core::Tensor;

/// Eq. 6.13: `L_o = (1/|F_s|) Σ_t p_t m_o(t)`, `m_o(t)` the number of the `k` nearest faces
/// (the thesis uses 50) containing at least one of `t`'s 100 interior lattice points
/// (`triangle_lattice(10)`) by the area test with tolerance `tol`
/// ([`crate::predicates::triangles_overlap`]). `vertices: #V×3`, `faces: #F×3`,
/// `face_probs: (F)`; differentiable in the probabilities.
///
/// ```
/// use candle_core::{Device, Tensor};
/// use meshgnn_losses::losses::triangle_overlap;
/// use meshgnn_losses::predicates::InsideTolerance;
/// let v = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0], [2.0, 2.0, 0.0]];
/// let p = Tensor::new(&[1.0f32, 1.0], &Device::Cpu)?;
/// // two faces sharing an edge, side by side: no overlap
/// let l = triangle_overlap(&v, &[[0, 1, 2], [1, 3, 2]], &p, 50, InsideTolerance::default())?;
/// assert_eq!(l.to_scalar::<f32>()?, 0.0);
/// // the same face twice: each overlaps the other
/// let l = triangle_overlap(&v, &[[0, 1, 2], [0, 1, 2]], &p, 50, InsideTolerance::default())?;
/// assert_eq!(l.to_scalar::<f32>()?, 1.0);
/// # Ok::<(), meshgnn_losses::Error>(())
/// ```
pub fn triangle_overlap(
    vertices: &[[f32; 3]],
    faces: &[[u32; 3]],
    face_probs: &Tensor,
    k: usize,
    tol: InsideTolerance,
) -> Result<Tensor> {
    let lattice = triangle_lattice(10);
    face_penalty(vertices, faces, face_probs, k, |t, u| {
        usize::from(triangles_overlap(t, u, &lattice, tol))
    })
}
