//! Point curvature, Gaussian-weighted mean curvature and roughness of a point cloud from one
//! k-NN query, thesis section 5.3.1 eq. 5.1-5.3 — the features behind the curvature and
//! roughness losses/metrics (CE, RE) and the point-cloud simplifier of chapter 5.
//!
//! # Conventions
//! - Normals and `κ` as in [`crate::pca_normals_and_curvature`] (same neighbourhood `N_i`:
//!   the `k` nearest points other than `p_i`).
//! - Eq. 5.3: `K̄_i = Σ_{j∈N_i} κ_j e^{−|p_j−p_i|²/h} / Σ_{j∈N_i} e^{−|p_j−p_i|²/h}`.
//! - Default `h`: the mean squared k-NN distance of the cloud, `h = mean_{i, j∈N_i} |p_j−p_i|²`,
//!   so the kernel scales with the sampling density and the result is invariant to a uniform
//!   scaling of the cloud. [`curvature_features_with_h`] takes an explicit `h`.
//! - Roughness `R_i = |κ_i − K̄_i|`.

use rayon::prelude::*;

use crate::curvature_neighbourhoods::curvature_neighbourhoods;
use crate::error::{Error, Result};
use crate::normalization::centroid;
use crate::pca_normals::CovarianceAt;
use crate::spatial_index::Neighbours;

/// Per-point features of eq. 5.1-5.3, each `#P` long.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct CurvatureFeatures {
    /// Unit normals `#P×3` (eq. 5.1), oriented away from the centroid.
    pub normals: Vec<[f32; 3]>,
    /// Point curvature `κ` (eq. 5.2).
    pub curvature: Vec<f32>,
    /// Gaussian-weighted mean curvature `K̄` (eq. 5.3).
    pub mean_curvature: Vec<f32>,
    /// Roughness `|κ − K̄|`.
    pub roughness: Vec<f32>,
    /// The kernel width `h` used in eq. 5.3.
    pub h: f64,
}

/// Eq. 5.1-5.3 and roughness on `points: #P×3` with `k` neighbours and the default `h` (mean
/// squared k-NN distance). Fails on an empty cloud, a non-finite point, or `k` outside `2..#P`.
///
/// ```
/// use meshgnn_geometry::curvature_features;
/// let grid: Vec<[f32; 3]> = (0..100).map(|i| [(i % 10) as f32, (i / 10) as f32, 0.0]).collect();
/// let features = curvature_features(&grid, 8)?;
/// assert!(features.roughness.iter().all(|&r| r.abs() < 1e-6));
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn curvature_features(points: &[[f32; 3]], k: usize) -> Result<CurvatureFeatures> {
    compute(points, k, None)
}

/// [`curvature_features`] with an explicit kernel width `h > 0` (squared length units).
///
/// ```
/// use meshgnn_geometry::curvature_features_with_h;
/// let grid: Vec<[f32; 3]> = (0..100).map(|i| [(i % 10) as f32, (i / 10) as f32, 0.0]).collect();
/// assert_eq!(curvature_features_with_h(&grid, 8, 2.0)?.h, 2.0);
/// assert!(curvature_features_with_h(&grid, 8, 0.0).is_err());
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn curvature_features_with_h(
    points: &[[f32; 3]],
    k: usize,
    h: f64,
) -> Result<CurvatureFeatures> {
    if !(h > 0.0 && h.is_finite()) {
        return Err(Error::InvalidParameter {
            name: "h",
            message: format!("the kernel width must be positive and finite, got {h}"),
        });
    }
    compute(points, k, Some(h))
}

fn compute(points: &[[f32; 3]], k: usize, h: Option<f64>) -> Result<CurvatureFeatures> {
    // One query per point: neighbours and squared distances, #P×k.
    let Neighbours {
        indices: neighbours,
        squared_distances: distances,
        ..
    } = curvature_neighbourhoods(points, k)?;
    let center = centroid(points);
    let (normals, curvature): (Vec<[f32; 3]>, Vec<f32>) =
        (points.par_iter(), neighbours.par_chunks(k))
            .into_par_iter()
            .map(|(&p, ids)| {
                let mut covariance = CovarianceAt::new(p);
                for &j in ids {
                    covariance.add(points[j as usize]);
                }
                covariance.normal_and_curvature(center)
            })
            .unzip();
    let h = match h {
        Some(h) => h,
        None => {
            // Chunked so the sum does not depend on the thread count.
            let partial: Vec<f64> = distances
                .par_chunks(4096)
                .map(|c| c.iter().map(|&d| f64::from(d)).sum::<f64>())
                .collect();
            (partial.iter().sum::<f64>() / distances.len() as f64).max(f64::MIN_POSITIVE)
        }
    };
    let mean_curvature: Vec<f32> = neighbours
        .par_chunks(k)
        .zip(distances.par_chunks(k))
        .map(|(ids, dists)| {
            let (mut weighted, mut total) = (0.0f64, 0.0f64);
            for (&j, &d) in ids.iter().zip(dists) {
                let w = (-f64::from(d) / h).exp();
                weighted += w * f64::from(curvature.get(j as usize).copied().unwrap_or(0.0));
                total += w;
            }
            if total > 0.0 {
                (weighted / total) as f32
            } else {
                0.0
            }
        })
        .collect();
    let roughness = curvature
        .iter()
        .zip(&mean_curvature)
        .map(|(c, m)| (c - m).abs())
        .collect();
    Ok(CurvatureFeatures {
        normals,
        curvature,
        mean_curvature,
        roughness,
        h,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{icosphere, pca_normals_and_curvature};

    /// Brute-force eq. 5.3 on a small cloud.
    #[test]
    fn matches_brute_force_on_a_bumpy_sphere() {
        let sphere = icosphere(2);
        // Irregular radial bumps and tangential jitter, so no two distances tie.
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut jitter = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f32 / (1u64 << 53) as f32 - 0.5
        };
        let points: Vec<[f32; 3]> = sphere
            .vertices()
            .iter()
            .map(|p| {
                let r = 1.0 + 0.05 * jitter();
                [
                    p[0] * r + 0.01 * jitter(),
                    p[1] * r + 0.01 * jitter(),
                    p[2] * r,
                ]
            })
            .collect();
        let k = 9;
        let features = curvature_features(&points, k).unwrap();
        let pca = pca_normals_and_curvature(&points, k).unwrap();
        assert_eq!(features.curvature, pca.curvature);
        assert_eq!(features.normals, pca.normals);
        let d2 = |a: [f32; 3], b: [f32; 3]| -> f64 {
            (0..3).map(|i| f64::from(a[i] - b[i]).powi(2)).sum()
        };
        // Brute-force neighbourhoods: sort all other points by distance.
        let hoods: Vec<Vec<usize>> = (0..points.len())
            .map(|i| {
                let mut others: Vec<usize> = (0..points.len()).filter(|&j| j != i).collect();
                others.sort_by(|&a, &b| {
                    d2(points[a], points[i]).total_cmp(&d2(points[b], points[i]))
                });
                others.truncate(k);
                others
            })
            .collect();
        let h = hoods
            .iter()
            .enumerate()
            .flat_map(|(i, hood)| hood.iter().map(move |&j| (i, j)))
            .map(|(i, j)| d2(points[i], points[j]))
            .sum::<f64>()
            / (points.len() * k) as f64;
        assert!((features.h - h).abs() < 1e-6 * h);
        for (i, hood) in hoods.iter().enumerate() {
            let w: Vec<f64> = hood
                .iter()
                .map(|&j| (-d2(points[i], points[j]) / h).exp())
                .collect();
            let mean = hood
                .iter()
                .zip(&w)
                .map(|(&j, w)| w * f64::from(features.curvature[j]))
                .sum::<f64>()
                / w.iter().sum::<f64>();
            assert!((f64::from(features.mean_curvature[i]) - mean).abs() < 1e-6);
            let rough = (f64::from(features.curvature[i]) - mean).abs();
            assert!((f64::from(features.roughness[i]) - rough).abs() < 1e-6);
        }
    }

    #[test]
    fn smooth_sphere_is_not_rough_and_scale_invariant() {
        let points = icosphere(4).vertices().to_vec();
        let a = curvature_features(&points, 10).unwrap();
        let max_rough = a.roughness.iter().fold(0.0f32, |m, &r| m.max(r));
        let max_curv = a.curvature.iter().fold(0.0f32, |m, &r| m.max(r));
        assert!(max_rough < 0.25 * max_curv, "{max_rough} vs {max_curv}");
        let scaled: Vec<[f32; 3]> = points.iter().map(|p| p.map(|x| x * 8.0)).collect();
        let b = curvature_features(&scaled, 10).unwrap();
        for (x, y) in a.mean_curvature.iter().zip(&b.mean_curvature) {
            assert!((x - y).abs() < 1e-4 * x.abs().max(1e-3));
        }
    }

    #[test]
    fn identical_and_collinear_clouds_of_200k_points_are_flat() {
        // Degenerate inputs in O(n log n): all neighbours coincide (covariance 0) or lie on
        // one line (rank 1), so every curvature is 0.
        let n = 200_000;
        let same = vec![[0.5f32, -1.0, 2.0]; n];
        let f = curvature_features(&same, 16).unwrap();
        assert!(
            f.curvature
                .iter()
                .chain(&f.mean_curvature)
                .all(|&c| c == 0.0)
        );
        let line: Vec<[f32; 3]> = (0..n).map(|i| [i as f32 * 0.25, 0.0, 0.0]).collect();
        let f = curvature_features(&line, 16).unwrap();
        assert!(f.curvature.iter().chain(&f.roughness).all(|&c| c == 0.0));
    }
}
