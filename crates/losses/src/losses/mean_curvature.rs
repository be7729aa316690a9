//! The Gaussian-weighted mean curvature `K̄` of eq. 5.1-5.3 as a differentiable function of the
//! point positions, so that eq. 5.8 can judge the curvature of the simplified cloud itself
//! (`K̄_2` is computed on `P_2`, as the thesis writes it) and send gradients to where its
//! points sit.
//!
//! # How the derivative is taken
//! - Neighbourhoods (the `k` nearest other points, the rule of
//!   `meshgnn_geometry::curvature_features`) are fixed: they are constants of the loss, like
//!   every correspondence in this crate.
//! - Eq. 5.2 `κ_i = λ0 / (λ0 + λ1 + λ2)` of the covariance `C_i = Σ_j d_ij d_ijᵀ`,
//!   `d_ij = p_j − p_i`. The trace is `Σ_j ‖d_ij‖²`; the smallest eigenvalue is written
//!   `λ0 = Σ_j (d_ij · v_i)²` with its unit eigenvector `v_i` held constant, which has the exact
//!   value and, by the Hellmann–Feynman identity `∂λ0 = v_iᵀ ∂C_i v_i`, the exact gradient.
//! - Eq. 5.3 with `h` the mean squared neighbour distance, differentiated too (it is a
//!   function of the positions), so the result matches the metric's value and scale
//!   invariance.

use crate::Error;
use crate::Result;
use crate::losses::tensor_points::{index_tensor, points_of};
use candle_core::{DType, Tensor};
use meshgnn_geometry::{curvature_neighbourhoods, symmetric_eigen3};
use rayon::prelude::*;

/// Squared lengths below this count as a point sitting on all its neighbours (κ = 0 there, as
/// in the metric).
const TINY_TRACE: f64 = 1e-30;

/// Eq. 5.1-5.3: `K̄: (M)` of `points: (M, 3)` with `k` neighbours (capped at `M − 1`),
/// differentiable in `points` (module docs). Equal in value to
/// `meshgnn_geometry::curvature_features(points, k).mean_curvature` up to `f32` rounding.
/// Fails for fewer than 3 points, `k < 2` or non-finite coordinates.
///
/// ```
/// use candle_core::{Device, Tensor};
/// use meshgnn_losses::losses::mean_curvature;
/// // A flat grid has zero curvature everywhere.
/// let grid: Vec<f32> = (0..100).flat_map(|i| [(i % 10) as f32, (i / 10) as f32, 0.0]).collect();
/// let p = Tensor::from_vec(grid, (100, 3), &Device::Cpu)?;
/// let k = mean_curvature(&p, 8)?.to_vec1::<f32>()?;
/// assert!(k.iter().all(|x| x.abs() < 1e-6));
/// # Ok::<(), meshgnn_losses::Error>(())
/// ```
pub fn mean_curvature(points: &Tensor, k: usize) -> Result<Tensor> {
    let pts = points_of("points", points)?;
    let m = pts.len();
    if m < 3 {
        return Err(Error::InvalidParameter {
            name: "points",
            message: format!("curvature needs at least 3 points, got {m}"),
        });
    }
    if k < 2 {
        return Err(Error::InvalidParameter {
            name: "k",
            message: format!("curvature needs at least 2 neighbours, got {k}"),
        });
    }
    let k = k.min(m - 1);
    let neighbours = neighbours_excluding_self(&pts, k)?;
    let idx = index_tensor(neighbours, points.device())?;
    // d_ij = p_j − p_i: (M, k, 3)
    let offsets = points
        .index_select(&idx, 0)?
        .reshape((m, k, 3))?
        .broadcast_sub(&points.unsqueeze(1)?)?;
    let normals = smallest_eigenvectors(&offsets, m, k)?
        .to_dtype(points.dtype())?
        .reshape((m, 3, 1))?;
    let smallest = offsets.matmul(&normals)?.sqr()?.sum((1, 2))?;
    let squared = offsets.sqr()?.sum(2)?; // (M, k)
    let trace = squared.sum(1)?;
    let kappa = smallest.div(&trace.clamp(TINY_TRACE, f64::INFINITY)?)?;
    let h = squared.mean_all()?;
    let weights = squared.broadcast_div(&h)?.neg()?.exp()?;
    let kappa_j = kappa.index_select(&idx, 0)?.reshape((m, k))?;
    Ok(weights.mul(&kappa_j)?.sum(1)?.div(&weights.sum(1)?)?)
}

/// The `k` nearest other points of every point, flattened `#P·k`: the very neighbourhoods of
/// `meshgnn_geometry::curvature_features` (one function serves both).
fn neighbours_excluding_self(points: &[[f32; 3]], k: usize) -> Result<Vec<u32>> {
    Ok(curvature_neighbourhoods(points, k)?.indices)
}

/// Unit eigenvectors of the smallest eigenvalue of every `Σ_j d_ij d_ijᵀ`, `(M, 3)` in `f64`,
/// read detached from `offsets: (M, k, 3)`.
fn smallest_eigenvectors(offsets: &Tensor, m: usize, k: usize) -> Result<Tensor> {
    let values: Vec<f64> = offsets
        .detach()
        .to_dtype(DType::F64)?
        .flatten_all()?
        .to_vec1()?;
    let vectors: Vec<f64> = values
        .par_chunks(3 * k)
        .flat_map_iter(|hood| {
            let mut c = [[0.0f64; 3]; 3];
            for d in hood.chunks_exact(3) {
                for (r, row) in c.iter_mut().enumerate() {
                    for (s, cell) in row.iter_mut().enumerate() {
                        *cell += d[r] * d[s];
                    }
                }
            }
            symmetric_eigen3(c).1[0]
        })
        .collect();
    Ok(Tensor::from_vec(vectors, (m, 3), offsets.device())?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::losses::gradient_check::assert_gradient_matches;
    use candle_core::Device;
    use meshgnn_geometry::{curvature_features, icosphere, sample_surface, subdivided_cube};
    use rand::{Rng, SeedableRng, rngs::StdRng};

    #[test]
    fn equals_the_metric_features_on_a_cube() {
        let pts = sample_surface(&subdivided_cube(4), 700, 3).unwrap().points;
        let want = curvature_features(&pts, 16).unwrap().mean_curvature;
        let t = Tensor::from_slice(pts.as_flattened(), (700, 3), &Device::Cpu).unwrap();
        let got = mean_curvature(&t, 16).unwrap().to_vec1::<f32>().unwrap();
        let worst = got
            .iter()
            .zip(&want)
            .fold(0.0f32, |w, (a, b)| w.max((a - b).abs()));
        assert!(worst < 1e-5, "largest difference {worst}");
        // the cube's edges and corners are curved, its faces flat
        assert!(want.iter().any(|&x| x > 0.05) && want.iter().any(|&x| x < 1e-4));
    }

    #[test]
    fn loss_and_metric_share_neighbourhoods_on_a_cloud_with_duplicates_and_ties() {
        // A 6×6 grid (many equal distances), each node twice, plus jittered points, some of
        // them repeated three times.
        let mut rng = StdRng::seed_from_u64(11);
        let mut pts: Vec<[f32; 3]> = (0..72)
            .map(|i| [((i / 2) % 6) as f32, ((i / 2) / 6) as f32, 0.0])
            .collect();
        for _ in 0..60 {
            let p = [
                rng.random_range(0.0..5.0f32),
                rng.random_range(0.0..5.0f32),
                rng.random_range(0.2..1.0f32),
            ];
            let copies = if rng.random_bool(0.3) { 3 } else { 1 };
            pts.extend(std::iter::repeat_n(p, copies));
        }
        let k = 8;
        let loss_hoods = neighbours_excluding_self(&pts, k).unwrap();
        let metric_hoods = curvature_neighbourhoods(&pts, k).unwrap();
        assert_eq!(loss_hoods, metric_hoods.indices);
        // Ties were resolved by index, as a brute-force sort of (distance, index) says.
        for (i, p) in pts.iter().enumerate() {
            let mut all: Vec<(f32, u32)> = (0..pts.len())
                .filter(|&j| j != i)
                .map(|j| (meshgnn_geometry::squared_distance(&pts[j], p), j as u32))
                .collect();
            all.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            let want: Vec<u32> = all.iter().take(k).map(|x| x.1).collect();
            assert_eq!(metric_hoods.row(i), want.as_slice(), "point {i}");
        }
        let want = curvature_features(&pts, k).unwrap().mean_curvature;
        let t = Tensor::from_slice(pts.as_flattened(), (pts.len(), 3), &Device::Cpu).unwrap();
        let got = mean_curvature(&t, k).unwrap().to_vec1::<f32>().unwrap();
        let worst = got
            .iter()
            .zip(&want)
            .fold(0.0f32, |w, (a, b)| w.max((a - b).abs()));
        assert!(worst < 1e-5, "largest difference {worst}");
    }

    #[test]
    fn gradient_matches_finite_differences() {
        // A jittered sphere patch: no ties among neighbour distances, no degenerate spectrum.
        let sphere = icosphere(1);
        let mut rng = StdRng::seed_from_u64(7);
        let coords: Vec<f64> = sphere
            .vertices()
            .iter()
            .flat_map(|p| p.map(|x| f64::from(x) + rng.random_range(-0.025..0.025)))
            .collect();
        let n = coords.len() / 3;
        let x = Tensor::from_vec(coords, (n, 3), &Device::Cpu).unwrap();
        let probe: Vec<f64> = (0..n).map(|i| ((i * 7) % 5) as f64 - 2.0).collect();
        let probe = Tensor::from_vec(probe, n, &Device::Cpu).unwrap();
        assert_gradient_matches(
            &x,
            |p| Ok(mean_curvature(p, 6)?.mul(&probe)?.sum_all()?),
            1e-5,
        );
    }

    #[test]
    fn rejects_too_few_points_and_neighbours() {
        let t = Tensor::new(&[[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0]], &Device::Cpu).unwrap();
        assert!(mean_curvature(&t, 2).is_err());
        let t = Tensor::new(
            &[[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            &Device::Cpu,
        )
        .unwrap();
        assert!(mean_curvature(&t, 1).is_err());
        assert!(mean_curvature(&t, 5).is_ok());
    }
}
