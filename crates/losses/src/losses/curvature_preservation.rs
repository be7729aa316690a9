//! Curvature preservation loss (thesis eq. 5.8, CE as a training term of eq. 5.9), on the same
//! footing as the CE metric (docs/losses.md, "Fair curvature metrics").

use crate::Result;
use crate::losses::tensor_points::check_vector;
use candle_core::Tensor;

/// Eq. 5.8 measured as the CE metric measures it:
/// `( mean_{q∈R} (K̄_1(q) − K̄_2(q))² )^{1/2}` with `reference: #R×3` the original's reference
/// points and `reference_curvature: (R)` its `K̄` there (constants, e.g. from
/// `meshgnn_geometry::curvature_at_scale`), and `K̄_2` the curvature of `simplified: (M, 3)` at
/// the same points and kernel `radius` ([`super::mean_curvature_at_scale`]), differentiable in
/// `simplified`. The square root has an infinite derivative at 0, so callers train with it only
/// while the error is positive (as the thesis does) or use its square.
///
/// ```
/// use candle_core::{Device, Tensor};
/// use meshgnn_geometry::{curvature_at_scale, icosphere};
/// use meshgnn_losses::losses::curvature_preservation;
/// let p = icosphere(3).vertices().to_vec();
/// let k1 = curvature_at_scale(&p, &p, 0.3)?.mean_curvature;
/// let k1 = Tensor::from_slice(&k1, p.len(), &Device::Cpu)?;
/// let t = Tensor::from_slice(p.as_flattened(), (p.len(), 3), &Device::Cpu)?;
/// let ce = curvature_preservation(&p, &k1, &t, 0.3)?.to_scalar::<f32>()?;
/// assert!(ce < 1e-6); // the same cloud
/// # Ok::<(), meshgnn_losses::Error>(())
/// ```
pub fn curvature_preservation(
    reference: &[[f32; 3]],
    reference_curvature: &Tensor,
    simplified: &Tensor,
    radius: f64,
) -> Result<Tensor> {
    check_vector("reference curvatures", reference_curvature, reference.len())?;
    let k2 = super::mean_curvature_at_scale(simplified, reference, radius)?;
    Ok(reference_curvature
        .to_dtype(k2.dtype())?
        .sub(&k2)?
        .sqr()?
        .mean_all()?
        .sqrt()?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::losses::gradient_check::assert_gradient_matches;
    use crate::metrics::{curvature_error, curvature_reference};
    use candle_core::{DType, Device};
    use meshgnn_geometry::{curvature_at_scale, icosphere, sample_surface, subdivided_cube};
    use rand::{Rng, SeedableRng, rngs::StdRng};

    #[test]
    fn equals_the_ce_metric() {
        let pts = sample_surface(&subdivided_cube(4), 3000, 2).unwrap().points;
        let kept: Vec<[f32; 3]> = pts.iter().step_by(10).copied().collect();
        let reference = curvature_reference(&pts, kept.len(), 16, 1.0).unwrap();
        let (r, rho) = (&reference.points, reference.radius);
        let k1 = curvature_at_scale(r, r, rho).unwrap().mean_curvature;
        let k1 = Tensor::from_slice(&k1, r.len(), &Device::Cpu).unwrap();
        let t = Tensor::from_slice(kept.as_flattened(), (kept.len(), 3), &Device::Cpu).unwrap();
        let ce = curvature_preservation(r, &k1, &t, rho)
            .unwrap()
            .to_scalar::<f32>()
            .unwrap();
        let metric = curvature_error(&pts, &kept, 16).unwrap();
        assert!(metric > 0.0);
        assert!(
            (f64::from(ce) - metric).abs() < 1e-4 * metric,
            "{ce} vs {metric}"
        );
    }

    #[test]
    fn gradient_matches_finite_differences() {
        // A jittered sphere; the radius puts every point in every neighbourhood.
        let sphere = icosphere(1);
        let mut rng = StdRng::seed_from_u64(3);
        let coords: Vec<f64> = sphere
            .vertices()
            .iter()
            .flat_map(|p| p.map(|x| f64::from(x) + rng.random_range(-0.03..0.03)))
            .collect();
        let n = coords.len() / 3;
        let x = Tensor::from_vec(coords, (n, 3), &Device::Cpu).unwrap();
        let reference: Vec<[f32; 3]> = sphere.vertices().to_vec();
        let k1 = Tensor::from_vec(
            vec![0.05f64; reference.len()],
            reference.len(),
            &Device::Cpu,
        )
        .unwrap()
        .to_dtype(DType::F64)
        .unwrap();
        assert_gradient_matches(
            &x,
            |p| curvature_preservation(&reference, &k1, p, 1.1),
            1e-5,
        );
    }

    #[test]
    fn rejects_mismatched_curvatures() {
        let p = icosphere(1).vertices().to_vec();
        let t = Tensor::from_slice(p.as_flattened(), (p.len(), 3), &Device::Cpu).unwrap();
        let k1 = Tensor::zeros(3, DType::F32, &Device::Cpu).unwrap();
        assert!(curvature_preservation(&p, &k1, &t, 0.5).is_err());
    }
}
