//! The overall neural mesh simplification objective (thesis eq. 6.14).

use crate::Result;
use candle_core::Tensor;

/// Scales `λ_c, λ_e, λ_o` of eq. 6.14 (the thesis leaves their values open; 1 each by default).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SimplificationWeights {
    /// λ_c, weight of the collision loss (eq. 6.11).
    pub collision: f64,
    /// λ_e, weight of the edge crossings loss (eq. 6.12).
    pub edge_crossings: f64,
    /// λ_o, weight of the overlap loss (eq. 6.13).
    pub overlap: f64,
}

impl Default for SimplificationWeights {
    fn default() -> Self {
        Self {
            collision: 1.0,
            edge_crossings: 1.0,
            overlap: 1.0,
        }
    }
}

/// The six scalar terms of eq. 6.14, each a 0-d tensor from this crate's losses.
#[derive(Clone, Debug)]
pub struct SimplificationTerms {
    /// Eq. 6.8, [`super::probabilistic_chamfer`].
    pub probabilistic_chamfer: Tensor,
    /// Eq. 6.9, [`super::probabilistic_surface_forward`].
    pub surface_forward: Tensor,
    /// Eq. 6.10, [`super::probabilistic_surface_reverse`].
    pub surface_reverse: Tensor,
    /// Eq. 6.11, [`super::triangle_collision`].
    pub collision: Tensor,
    /// Eq. 6.12, [`super::edge_crossings`].
    pub edge_crossings: Tensor,
    /// Eq. 6.13, [`super::triangle_overlap`].
    pub overlap: Tensor,
}

/// Eq. 6.14: `L = d_P + d^f_S + d^r_S + λ_c L_c + λ_e L_e + λ_o L_o`.
///
/// ```
/// use candle_core::{Device, Tensor};
/// use meshgnn_losses::losses::{simplification_objective, SimplificationTerms, SimplificationWeights};
/// let s = |v: f32| Tensor::new(v, &Device::Cpu);
/// let terms = SimplificationTerms {
///     probabilistic_chamfer: s(1.0)?, surface_forward: s(2.0)?, surface_reverse: s(3.0)?,
///     collision: s(1.0)?, edge_crossings: s(1.0)?, overlap: s(1.0)?,
/// };
/// let w = SimplificationWeights { collision: 0.5, edge_crossings: 0.25, overlap: 0.25 };
/// assert_eq!(simplification_objective(&terms, w)?.to_scalar::<f32>()?, 7.0);
/// # Ok::<(), meshgnn_losses::Error>(())
/// ```
pub fn simplification_objective(
    terms: &SimplificationTerms,
    weights: SimplificationWeights,
) -> Result<Tensor> {
    let total = terms
        .probabilistic_chamfer
        .add(&terms.surface_forward)?
        .add(&terms.surface_reverse)?
        .add(&terms.collision.affine(weights.collision, 0.0)?)?
        .add(&terms.edge_crossings.affine(weights.edge_crossings, 0.0)?)?
        .add(&terms.overlap.affine(weights.overlap, 0.0)?)?;
    Ok(total)
}
