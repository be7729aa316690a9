//! The simplifier's training objective, thesis eq. 5.9:
//! `L = d^Adapt(P1, P2) + λ E_c(P1, P2)` with the adaptive Chamfer distance eq. 5.7 (weights
//! `sigmoid(normalised K̄ / τ)`, τ = 10) and the curvature preservation error eq. 5.8, λ = 0.1.
//! Both terms are the ones of `meshgnn-losses`; this file only combines them.
//!
//! # Conventions
//! `E_c` is measured as the CE metric measures it (docs/losses.md, "Fair curvature metrics"):
//! the original's `K̄` at its reference points `R` and the simplified cloud's `K̄` at the same
//! points, both at the kernel radius that holds `k` simplified points
//! ([`CurvatureTarget`]); the simplified side is differentiable in the refined positions, so the
//! term trains AttRef's displacements and, through the embeddings AttRef reads, the projector.
//! The FPS selection itself stays the non-differentiable step, as in the thesis. The adaptive
//! weights of eq. 5.7 only rank the original's points against each other, so they keep the
//! original's own k-NN `K̄` (normalised by its mean, as the thesis' footnote describes).

use candle_core::{Device, Tensor};
use meshgnn_geometry::curvature_at_scale;
use meshgnn_losses::losses::{adaptive_chamfer, curvature_preservation};
use meshgnn_losses::metrics::{CurvatureReference, curvature_reference};

use crate::Result;

/// λ of eq. 5.9.
pub const CURVATURE_LOSS_WEIGHT: f64 = 0.1;

/// The original's side of `E_c` for one simplified size: reference points, their `K̄` and the
/// kernel radius (constants of the loss).
#[derive(Clone, Debug)]
pub struct CurvatureTarget {
    /// The original's reference points `R`, `#R×3`.
    pub reference: Vec<[f32; 3]>,
    /// The original's `K̄` at `R`, `(R)`.
    pub curvature: Tensor,
    /// The kernel radius `ρ`.
    pub radius: f64,
}

impl CurvatureTarget {
    /// The target for simplifying `original: #N×3` to `simplified_count` points with `k`
    /// simplified points per kernel radius (the CE metric's definition).
    ///
    /// ```
    /// use meshgnn_geometry::icosphere;
    /// use meshgnn_models::point_simplifier::CurvatureTarget;
    /// let p = icosphere(3).vertices().to_vec();
    /// let t = CurvatureTarget::new(&p, 60, 16)?;
    /// assert_eq!(t.reference.len(), 480);
    /// # Ok::<(), meshgnn_models::Error>(())
    /// ```
    pub fn new(original: &[[f32; 3]], simplified_count: usize, k: usize) -> Result<Self> {
        let CurvatureReference { points, radius } =
            curvature_reference(original, simplified_count, k, 1.0)?;
        let k_bar = curvature_at_scale(&points, &points, radius)?.mean_curvature;
        Ok(Self {
            curvature: Tensor::from_slice(&k_bar, k_bar.len(), &Device::Cpu)?,
            reference: points,
            radius,
        })
    }
}

/// The two terms of eq. 5.9 and their weighted sum, each a 0-d tensor.
#[derive(Clone, Debug)]
pub struct SimplifierLoss {
    /// `d^Adapt + λ E_c`.
    pub total: Tensor,
    /// Eq. 5.7.
    pub adaptive_chamfer: Tensor,
    /// Eq. 5.8 at one scale (unweighted); 0 when fewer than 3 points are kept (no curvature).
    pub curvature: Tensor,
}

/// Eq. 5.9 for `original: (N, 3)` with adaptive weights `weights: (N)`, `simplified: (M, 3)`
/// and the curvature `target` of the original at `M` points; `lambda` is λ
/// ([`CURVATURE_LOSS_WEIGHT`] in the thesis).
///
/// ```
/// use candle_core::{Device, Tensor};
/// use meshgnn_geometry::icosphere;
/// use meshgnn_models::point_simplifier::{CurvatureTarget, simplifier_loss};
/// let d = Device::Cpu;
/// let pts = icosphere(3).vertices().to_vec();
/// let p1 = Tensor::from_slice(pts.as_flattened(), (pts.len(), 3), &d)?;
/// let w = Tensor::ones(pts.len(), candle_core::DType::F32, &d)?;
/// let target = CurvatureTarget::new(&pts, pts.len(), 16)?;
/// let l = simplifier_loss(&p1, &w, &p1, &target, 0.1)?;
/// // the cloud against itself: no Chamfer distance and (up to rounding) no curvature error
/// assert!(l.total.to_scalar::<f32>()? < 1e-6);
/// # Ok::<(), meshgnn_models::Error>(())
/// ```
pub fn simplifier_loss(
    original: &Tensor,
    weights: &Tensor,
    simplified: &Tensor,
    target: &CurvatureTarget,
    lambda: f64,
) -> Result<SimplifierLoss> {
    let chamfer = adaptive_chamfer(original, simplified, weights)?;
    let ce = if simplified.dim(0)? >= 3 {
        curvature_preservation(
            &target.reference,
            &target.curvature,
            simplified,
            target.radius,
        )?
    } else {
        chamfer.zeros_like()?
    };
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
        let wt = Tensor::from_slice(&w, 600, &dev).unwrap();
        let idx = Tensor::from_slice(&keep, keep.len(), &dev).unwrap();
        let p2 = p1
            .index_select(&idx, 0)
            .unwrap()
            .affine(1.01, 0.002)
            .unwrap();
        let target = CurvatureTarget::new(&pts, keep.len(), 16).unwrap();
        let l = simplifier_loss(&p1, &wt, &p2, &target, CURVATURE_LOSS_WEIGHT).unwrap();
        let acd = adaptive_chamfer(&p1, &p2, &wt)
            .unwrap()
            .to_scalar::<f32>()
            .unwrap();
        let ce = curvature_preservation(&target.reference, &target.curvature, &p2, target.radius)
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

    /// The loss's curvature term is the CE metric: same reference, scale and fields.
    #[test]
    fn curvature_term_equals_the_ce_metric() {
        let pts = sample_surface(&subdivided_cube(4), 3000, 2).unwrap().points;
        let kept: Vec<[f32; 3]> = pts.iter().step_by(10).copied().collect();
        let target = CurvatureTarget::new(&pts, kept.len(), 16).unwrap();
        let t = Tensor::from_slice(kept.as_flattened(), (kept.len(), 3), &Device::Cpu).unwrap();
        let ce = curvature_preservation(&target.reference, &target.curvature, &t, target.radius)
            .unwrap()
            .to_scalar::<f32>()
            .unwrap();
        let metric = meshgnn_losses::metrics::curvature_error(&pts, &kept, 16).unwrap();
        assert!(
            (f64::from(ce) - metric).abs() < 1e-4 * metric,
            "{ce} vs {metric}"
        );
    }
}
