//! The mean curvature `K̄` of eq. 5.1-5.3 at one kernel radius, as the fair metrics measure it
//! (`meshgnn_geometry::curvature_at_scale`), as a differentiable function of the cloud's
//! positions: the simplified side of the curvature loss [`super::curvature_preservation`]
//! (eq. 5.8 at one physical scale, docs/losses.md "Fair curvature metrics").
//!
//! # How the derivative is taken
//! - Neighbourhoods come from `meshgnn_geometry::kernel_neighbourhood` (the metric's rule) and
//!   are constants of the loss, as every correspondence in this crate.
//! - Weights `w_j = exp(−(|p_j − q|² − c)/ρ²)` are differentiated; the shift `c` (the nearest
//!   squared distance, held constant) cancels in every ratio below.
//! - Eq. 5.2 on the weighted covariance centred at its weighted mean `μ`: `κ = λ0 / tr C` with
//!   `λ0 = vᵀ C v` for the unit eigenvector `v` held constant (exact value and, by the
//!   Hellmann–Feynman identity, exact gradient) and `tr C = Σ w |p − μ|² / Σ w`.
//! - Eq. 5.3: `K̄(q) = Σ w_qj κ_j / Σ w_qj` over the neighbourhood of `q`.

use crate::losses::tensor_points::{index_tensor, points_of};
use crate::validate::check_finite;
use crate::{Error, Result};
use candle_core::{DType, Tensor};
use meshgnn_geometry::{SpatialIndex, kernel_neighbourhood, symmetric_eigen3};
use rayon::prelude::*;

/// Traces below this count as a neighbourhood collapsed onto one point (κ = 0, as the metric).
const TINY_TRACE: f64 = 1e-30;

/// Eq. 5.1-5.3 at kernel radius `radius`: `K̄: (Q)` of the cloud `points: (M, 3)` at the
/// fixed locations `queries: #Q×3`, differentiable in `points` (module docs). Equal in value
/// to `meshgnn_geometry::curvature_at_scale(points, queries, radius).mean_curvature` up to
/// rounding. Fails for fewer than 3 points, non-finite coordinates or a radius that is not
/// positive and finite.
///
/// ```
/// use candle_core::{Device, Tensor};
/// use meshgnn_losses::losses::mean_curvature_at_scale;
/// let grid: Vec<f32> = (0..100).flat_map(|i| [(i % 10) as f32, (i / 10) as f32, 0.0]).collect();
/// let p = Tensor::from_vec(grid, (100, 3), &Device::Cpu)?;
/// let k = mean_curvature_at_scale(&p, &[[4.5, 4.5, 0.0]], 2.0)?.to_vec1::<f32>()?;
/// assert!(k[0].abs() < 1e-6); // a plane
/// # Ok::<(), meshgnn_losses::Error>(())
/// ```
pub fn mean_curvature_at_scale(
    points: &Tensor,
    queries: &[[f32; 3]],
    radius: f64,
) -> Result<Tensor> {
    let pts = points_of("points", points)?;
    if pts.len() < 3 {
        return Err(Error::InvalidParameter {
            name: "points",
            message: format!("curvature needs at least 3 points, got {}", pts.len()),
        });
    }
    if !(radius > 0.0 && radius.is_finite()) {
        return Err(Error::InvalidParameter {
            name: "radius",
            message: format!("must be positive and finite, got {radius}"),
        });
    }
    check_finite("queries", queries)?;
    let index = SpatialIndex::new(&pts)?;
    let own = Hoods::new(&index, &pts, radius, points)?;
    let kappa = own.curvature(points, points, radius)?;
    let at_queries = Hoods::new(&index, queries, radius, points)?;
    let q = Tensor::from_slice(queries.as_flattened(), (queries.len(), 3), points.device())?
        .to_dtype(points.dtype())?;
    let weights = at_queries.weights(points, &q, radius)?;
    let kappa_j = kappa
        .index_select(&at_queries.indices, 0)?
        .reshape((queries.len(), at_queries.width))?;
    Ok(weights.mul(&kappa_j)?.sum(1)?.div(&weights.sum(1)?)?)
}

/// Kernel neighbourhoods of a set of locations, padded to one width.
struct Hoods {
    /// `#L·width` neighbour indices; padding repeats a real neighbour with mask 0.
    indices: Tensor,
    /// `(#L, width)`: 1 for a neighbour, 0 for padding.
    mask: Tensor,
    /// `(#L, 1)`: the nearest squared distance of each location (the weights' shift).
    shift: Tensor,
    width: usize,
    count: usize,
}

impl Hoods {
    fn new(
        index: &SpatialIndex,
        locations: &[[f32; 3]],
        radius: f64,
        like: &Tensor,
    ) -> Result<Self> {
        let rows: Vec<Vec<(f32, u32)>> = locations
            .par_iter()
            .map(|q| {
                let mut hood = Vec::new();
                kernel_neighbourhood(index, q, radius, &mut hood);
                hood
            })
            .collect();
        let width = rows.iter().map(Vec::len).max().unwrap_or(1).max(1);
        let (mut indices, mut mask, mut shift) = (Vec::new(), Vec::new(), Vec::new());
        for row in &rows {
            let first = row.first().map_or(0, |n| n.1);
            for slot in 0..width {
                let (id, on) = row.get(slot).map_or((first, 0.0), |n| (n.1, 1.0));
                indices.push(id);
                mask.push(on);
            }
            shift.push(
                row.iter()
                    .map(|n| n.0)
                    .fold(f32::INFINITY, f32::min)
                    .min(f32::MAX),
            );
        }
        let device = like.device();
        let count = rows.len();
        Ok(Self {
            indices: index_tensor(indices, device)?,
            mask: Tensor::from_vec(mask, (count, width), device)?.to_dtype(like.dtype())?,
            shift: Tensor::from_vec(shift, (count, 1), device)?.to_dtype(like.dtype())?,
            width,
            count,
        })
    }

    /// `(#L, width, 3)` neighbour positions.
    fn gather(&self, points: &Tensor) -> Result<Tensor> {
        Ok(points
            .index_select(&self.indices, 0)?
            .reshape((self.count, self.width, 3))?)
    }

    /// `(#L, width)` kernel weights of the neighbours of `locations: (#L, 3)`, 0 on padding.
    fn weights(&self, points: &Tensor, locations: &Tensor, radius: f64) -> Result<Tensor> {
        let d2 = self
            .gather(points)?
            .broadcast_sub(&locations.unsqueeze(1)?)?
            .sqr()?
            .sum(2)?;
        Ok(d2
            .broadcast_sub(&self.shift)?
            .affine(-1.0 / (radius * radius), 0.0)?
            .exp()?
            .mul(&self.mask)?)
    }

    /// Eq. 5.2 on the weighted covariance of each neighbourhood (module docs), `(#L)`.
    fn curvature(&self, points: &Tensor, locations: &Tensor, radius: f64) -> Result<Tensor> {
        let w = self.weights(points, locations, radius)?;
        let total = w.sum_keepdim(1)?; // (L, 1)
        let neighbours = self.gather(points)?;
        let mean = neighbours
            .broadcast_mul(&w.unsqueeze(2)?)?
            .sum(1)?
            .broadcast_div(&total)?; // (L, 3)
        let centred = neighbours.broadcast_sub(&mean.unsqueeze(1)?)?; // (L, width, 3)
        let normals = smallest_eigenvectors(&centred, &w, self.count, self.width)?
            .to_dtype(points.dtype())?
            .reshape((self.count, 3, 1))?;
        let along = centred.matmul(&normals)?.squeeze(2)?.sqr()?; // (L, width)
        let smallest = along.mul(&w)?.sum_keepdim(1)?.div(&total)?;
        let trace = centred
            .sqr()?
            .sum(2)?
            .mul(&w)?
            .sum_keepdim(1)?
            .div(&total)?;
        Ok(smallest
            .div(&trace.clamp(TINY_TRACE, f64::INFINITY)?)?
            .squeeze(1)?)
    }
}

/// Unit eigenvectors of the smallest eigenvalue of each `Σ_j w_j e_j e_jᵀ`, `(L, 3)` in `f64`,
/// read detached from `centred: (L, width, 3)` and `weights: (L, width)`.
fn smallest_eigenvectors(
    centred: &Tensor,
    weights: &Tensor,
    count: usize,
    width: usize,
) -> Result<Tensor> {
    let e: Vec<f64> = centred
        .detach()
        .to_dtype(DType::F64)?
        .flatten_all()?
        .to_vec1()?;
    let w: Vec<f64> = weights
        .detach()
        .to_dtype(DType::F64)?
        .flatten_all()?
        .to_vec1()?;
    let vectors: Vec<f64> = e
        .par_chunks(3 * width)
        .zip(w.par_chunks(width))
        .flat_map_iter(|(hood, weights)| {
            let mut c = [[0.0f64; 3]; 3];
            for (d, &wj) in hood.chunks_exact(3).zip(weights) {
                for (r, row) in c.iter_mut().enumerate() {
                    for (s, cell) in row.iter_mut().enumerate() {
                        *cell += wj * d[r] * d[s];
                    }
                }
            }
            symmetric_eigen3(c).1[0]
        })
        .collect();
    Ok(Tensor::from_vec(vectors, (count, 3), centred.device())?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::losses::gradient_check::assert_gradient_matches;
    use candle_core::Device;
    use meshgnn_geometry::{curvature_at_scale, icosphere, sample_surface, subdivided_cube};
    use rand::{Rng, SeedableRng, rngs::StdRng};

    #[test]
    fn equals_the_metric_fields_on_a_cube() {
        let pts = sample_surface(&subdivided_cube(4), 1500, 3).unwrap().points;
        let queries = sample_surface(&subdivided_cube(4), 300, 4).unwrap().points;
        for radius in [0.15, 0.4] {
            let want = curvature_at_scale(&pts, &queries, radius)
                .unwrap()
                .mean_curvature;
            let t = Tensor::from_slice(pts.as_flattened(), (1500, 3), &Device::Cpu)
                .unwrap()
                .to_dtype(DType::F64)
                .unwrap();
            let got = mean_curvature_at_scale(&t, &queries, radius)
                .unwrap()
                .to_vec1::<f64>()
                .unwrap();
            let worst = got
                .iter()
                .zip(&want)
                .fold(0.0f64, |w, (a, b)| w.max((a - f64::from(*b)).abs()));
            assert!(worst < 1e-6, "ρ {radius}: largest difference {worst}");
            // the edges and corners read curved; at the smaller radius, face centres flat
            assert!(want.iter().any(|&x| x > 0.02));
            assert!(radius > 0.2 || want.iter().any(|&x| x < 1e-3));
        }
    }

    #[test]
    fn gradient_matches_finite_differences() {
        // A jittered sphere; the radius puts every point in every neighbourhood (no point
        // crosses the cut under the finite-difference steps).
        let sphere = icosphere(1);
        let mut rng = StdRng::seed_from_u64(7);
        let coords: Vec<f64> = sphere
            .vertices()
            .iter()
            .flat_map(|p| p.map(|x| f64::from(x) + rng.random_range(-0.025..0.025)))
            .collect();
        let n = coords.len() / 3;
        let x = Tensor::from_vec(coords, (n, 3), &Device::Cpu).unwrap();
        let queries: Vec<[f32; 3]> = sphere.vertices().iter().step_by(3).copied().collect();
        let probe: Vec<f64> = (0..queries.len())
            .map(|i| ((i * 7) % 5) as f64 - 2.0)
            .collect();
        let probe = Tensor::from_vec(probe, queries.len(), &Device::Cpu).unwrap();
        assert_gradient_matches(
            &x,
            |p| {
                Ok(mean_curvature_at_scale(p, &queries, 1.1)?
                    .mul(&probe)?
                    .sum_all()?)
            },
            1e-5,
        );
    }

    #[test]
    fn rejects_bad_input() {
        let t = Tensor::new(&[[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0]], &Device::Cpu).unwrap();
        assert!(mean_curvature_at_scale(&t, &[[0.0; 3]], 1.0).is_err());
        let t = Tensor::new(
            &[[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            &Device::Cpu,
        )
        .unwrap();
        assert!(mean_curvature_at_scale(&t, &[[0.0; 3]], 0.0).is_err());
        assert!(mean_curvature_at_scale(&t, &[[f32::NAN, 0.0, 0.0]], 1.0).is_err());
        assert!(mean_curvature_at_scale(&t, &[[0.0; 3]], 1.0).is_ok());
    }
}
