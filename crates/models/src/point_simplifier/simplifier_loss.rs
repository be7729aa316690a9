//! The simplifier's training objective, thesis eq. 5.9:
//! `L = d^Adapt(P1, P2) + λ E_c(P1, P2)` with the adaptive Chamfer distance eq. 5.7 (weights
//! `sigmoid(normalised K̄ / τ)`, τ = 10) and the curvature preservation error eq. 5.8, λ = 0.1.
//! Both terms are the ones of `meshgnn-losses`; this file only combines them.
//!
//! # Conventions
//! The simplified points' curvatures `K̄_2` are computed on the simplified cloud itself
//! (`meshgnn_losses::losses::mean_curvature`, differentiable in the refined positions), as
//! eq. 5.8 writes them and as the CE metric scores them: the curvature term then trains AttRef's
//! displacements and, through the embeddings AttRef reads, the projector. The FPS selection
//! itself stays the non-differentiable step, as in the thesis.

use candle_core::Tensor;
use meshgnn_losses::losses::{adaptive_chamfer, curvature_preservation};

use crate::Result;

/// λ of eq. 5.9.
pub const CURVATURE_LOSS_WEIGHT: f64 = 0.1;

/// The two terms of eq. 5.9 and their weighted sum, each a 0-d tensor.
#[derive(Clone, Debug)]
pub struct SimplifierLoss {
    /// `d^Adapt + λ E_c`.
    pub total: Tensor,
    /// Eq. 5.7.
    pub adaptive_chamfer: Tensor,
    /// Eq. 5.8 (unweighted).
    pub curvature: Tensor,
}

/// Eq. 5.9 for `original: (N, 3)` with adaptive weights `weights: (N)` and mean curvatures
/// `curvature: (N)`, and `simplified: (M, 3)` with `simplified_curvature: (M)`; `lambda` is
/// λ ([`CURVATURE_LOSS_WEIGHT`] in the thesis).
///
/// ```
/// use candle_core::{Device, Tensor};
/// use meshgnn_models::point_simplifier::simplifier_loss;
/// let d = Device::Cpu;
/// let p1 = Tensor::new(&[[0.0f32, 0.0, 0.0], [2.0, 0.0, 0.0]], &d)?;
/// let p2 = Tensor::new(&[[0.0f32, 0.0, 0.0]], &d)?;
/// let w = Tensor::new(&[1.0f32, 0.5], &d)?;
/// let k1 = Tensor::new(&[0.0f32, 0.3], &d)?;
/// let k2 = Tensor::new(&[0.0f32], &d)?;
/// let l = simplifier_loss(&p1, &w, &k1, &p2, &k2, 0.1)?;
/// // adaptive Chamfer (0 + 0.5·4)/2 + 0 = 1; E_c = sqrt(0.09 / 2)
/// let want = 1.0 + 0.1 * (0.09f32 / 2.0).sqrt();
/// assert!((l.total.to_scalar::<f32>()? - want).abs() < 1e-6);
/// # Ok::<(), meshgnn_models::Error>(())
/// ```
pub fn simplifier_loss(
    original: &Tensor,
    weights: &Tensor,
    curvature: &Tensor,
    simplified: &Tensor,
    simplified_curvature: &Tensor,
    lambda: f64,
) -> Result<SimplifierLoss> {
    let chamfer = adaptive_chamfer(original, simplified, weights)?;
    let ce = curvature_preservation(original, curvature, simplified, simplified_curvature)?;
    let total = chamfer.add(&ce.affine(lambda, 0.0)?)?;
    Ok(SimplifierLoss {
        total,
        adaptive_chamfer: chamfer,
        curvature: ce,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use candle_core::Device;
    use meshgnn_geometry::{curvature_features, sample_surface, subdivided_cube};
    use meshgnn_losses::losses::adaptive_chamfer_weights;

    #[test]
    fn total_is_the_sum_of_the_separately_computed_parts() {
        let dev = Device::Cpu;
        let pts = sample_surface(&subdivided_cube(4), 600, 1).unwrap().points;
        let feats = curvature_features(&pts, 16).unwrap();
        let w = adaptive_chamfer_weights(&feats.mean_curvature, 10.0).unwrap();
        let keep: Vec<u32> = (0..600).step_by(7).collect();
        let p1 = Tensor::from_slice(pts.as_flattened(), (600, 3), &dev).unwrap();
        let k1 = Tensor::from_slice(&feats.mean_curvature, 600, &dev).unwrap();
        let wt = Tensor::from_slice(&w, 600, &dev).unwrap();
        let idx = Tensor::from_slice(&keep, keep.len(), &dev).unwrap();
        let p2 = p1
            .index_select(&idx, 0)
            .unwrap()
            .affine(1.01, 0.002)
            .unwrap();
        let k2 = k1.index_select(&idx, 0).unwrap();
        let l = simplifier_loss(&p1, &wt, &k1, &p2, &k2, CURVATURE_LOSS_WEIGHT).unwrap();
        let acd = adaptive_chamfer(&p1, &p2, &wt)
            .unwrap()
            .to_scalar::<f32>()
            .unwrap();
        let ce = curvature_preservation(&p1, &k1, &p2, &k2)
            .unwrap()
            .to_scalar::<f32>()
            .unwrap();
        assert!(acd > 0.0 && ce > 0.0);
        let total = l.total.to_scalar::<f32>().unwrap();
        assert!(
            (total - (acd + 0.1 * ce)).abs() <= 1e-6 * total,
            "{total} vs {acd} + 0.1·{ce}"
        );
        assert_eq!(l.adaptive_chamfer.to_scalar::<f32>().unwrap(), acd);
        assert_eq!(l.curvature.to_scalar::<f32>().unwrap(), ce);
    }
}
