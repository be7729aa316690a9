//! Normals and point curvature of a point cloud by covariance analysis, thesis eq. 5.1-5.2
//! (Pauly, Gross and Kobbelt, "Efficient simplification of point-sampled surfaces", IEEE
//! Visualization 2002).
//!
//! # Conventions
//! - `N_i` is the `k` nearest points other than `p_i` (kd-tree, see the crate's k-NN notes).
//! - Eq. 5.1 as written: the covariance is centred at `p_i` itself, `C = Σ_j (p_j − p_i)(p_j − p_i)ᵀ`
//!   (not at the neighbourhood mean as in PCL/Open3D), accumulated in `f64`.
//! - The normal is the unit eigenvector of the smallest eigenvalue `λ0`; the curvature is
//!   `λ0 / (λ0 + λ1 + λ2)` in `[0, 1/3]` (0 when all neighbours coincide with `p_i`).
//! - Orientation: normals point away from the cloud's centroid (`n · (p_i − c) ≥ 0`), which is
//!   outward for star-shaped closed surfaces; it is arbitrary where `p_i − c` lies in the
//!   tangent plane (e.g. a flat patch centred on `c`).

use rayon::prelude::*;

use crate::curvature_neighbourhoods::curvature_neighbourhoods;
use crate::error::Result;
use crate::normalization::centroid;
use crate::symmetric_eigen3::symmetric_eigen3;
use crate::vec3::{dot, sub, to_f64};

/// Per-point normals and curvature of eq. 5.1-5.2.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PcaFeatures {
    /// Unit normals `#P×3`, oriented away from the centroid.
    pub normals: Vec<[f32; 3]>,
    /// Point curvature `κ = λ0 / (λ0 + λ1 + λ2)`, `#P`.
    pub curvature: Vec<f32>,
}

/// Eq. 5.1-5.2: normal and curvature of every point of `points: #P×3` from its `k` nearest
/// neighbours. Fails on an empty cloud, a non-finite point, or `k` outside `2..#P`.
///
/// ```
/// use meshgnn_geometry::pca_normals_and_curvature;
/// let grid: Vec<[f32; 3]> = (0..100).map(|i| [(i % 10) as f32, (i / 10) as f32, 0.0]).collect();
/// let features = pca_normals_and_curvature(&grid, 8)?;
/// assert!(features.curvature.iter().all(|&c| c.abs() < 1e-6));
/// assert!(features.normals.iter().all(|n| n[2].abs() == 1.0));
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn pca_normals_and_curvature(points: &[[f32; 3]], k: usize) -> Result<PcaFeatures> {
    let neighbours = curvature_neighbourhoods(points, k)?;
    let center = centroid(points);
    let (normals, curvature) = (points.par_iter(), neighbours.indices.par_chunks(k))
        .into_par_iter()
        .map(|(&p, row)| {
            let mut covariance = CovarianceAt::new(p);
            for &j in row {
                covariance.add(points[j as usize]);
            }
            covariance.normal_and_curvature(center)
        })
        .unzip();
    Ok(PcaFeatures { normals, curvature })
}

/// The covariance of eq. 5.1 centred at `p_i`, accumulated neighbour by neighbour.
pub(crate) struct CovarianceAt {
    origin: [f64; 3],
    sums: [f64; 6],
}

impl CovarianceAt {
    /// An empty accumulator centred at `origin = p_i`.
    pub(crate) fn new(origin: [f32; 3]) -> Self {
        Self {
            origin: to_f64(origin),
            sums: [0.0; 6],
        }
    }

    /// Adds the neighbour `p_j`.
    #[inline]
    pub(crate) fn add(&mut self, point: [f32; 3]) {
        let d = sub(to_f64(point), self.origin);
        let s = &mut self.sums;
        s[0] += d[0] * d[0];
        s[1] += d[0] * d[1];
        s[2] += d[0] * d[2];
        s[3] += d[1] * d[1];
        s[4] += d[1] * d[2];
        s[5] += d[2] * d[2];
    }

    /// Eq. 5.2: the unit normal (oriented away from `center`) and `λ0 / (λ0 + λ1 + λ2)`.
    pub(crate) fn normal_and_curvature(&self, center: [f64; 3]) -> ([f32; 3], f32) {
        let s = self.sums;
        let (values, vectors) =
            symmetric_eigen3([[s[0], s[1], s[2]], [s[1], s[3], s[4]], [s[2], s[4], s[5]]]);
        let values = values.map(|v| v.max(0.0));
        let total = values[0] + values[1] + values[2];
        let curvature = if total > 0.0 { values[0] / total } else { 0.0 };
        let mut normal = vectors[0];
        if dot(normal, sub(self.origin, center)) < 0.0 {
            normal = normal.map(|x| -x);
        }
        (normal.map(|x| x as f32), curvature as f32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Error, grid_plane, icosphere};

    #[test]
    fn sphere_normals_are_radial_outward_and_curvature_constant_and_small() {
        let sphere = icosphere(4);
        let features = pca_normals_and_curvature(sphere.vertices(), 12).unwrap();
        for (p, n) in sphere.vertices().iter().zip(&features.normals) {
            let cos = dot(to_f64(*p), to_f64(*n));
            assert!(cos > 0.999, "{cos}");
        }
        let (lo, hi) = features
            .curvature
            .iter()
            .fold((f32::MAX, f32::MIN), |(lo, hi), &c| (lo.min(c), hi.max(c)));
        // Neighbourhoods of radius r ≈ 0.08 lie ≈ r²/2 below the tangent plane: κ ≈ 1e-3.
        assert!(hi < 0.01, "max curvature {hi}");
        assert!(lo > 0.0 && hi < 2.0 * lo, "curvature range {lo}..{hi}");
    }

    #[test]
    fn plane_has_zero_curvature_and_vertical_normals() {
        let plane = grid_plane(20, 20);
        let features = pca_normals_and_curvature(plane.vertices(), 10).unwrap();
        assert!(features.curvature.iter().all(|&c| c.abs() < 1e-7));
        assert!(
            features
                .normals
                .iter()
                .all(|n| (n[2].abs() - 1.0).abs() < 1e-6)
        );
    }

    #[test]
    fn same_result_for_any_thread_count() {
        let points = icosphere(3).vertices().to_vec();
        let reference = pca_normals_and_curvature(&points, 15).unwrap();
        for threads in [1, 3] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let again = pool.install(|| pca_normals_and_curvature(&points, 15).unwrap());
            assert_eq!(reference, again);
        }
    }

    #[test]
    fn invalid_inputs_are_errors() {
        let points = [[0.0f32; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        assert!(matches!(
            pca_normals_and_curvature(&points, 3),
            Err(Error::InvalidParameter { name: "k", .. })
        ));
        assert!(matches!(
            pca_normals_and_curvature(&[], 3),
            Err(Error::Empty { .. })
        ));
        let nan = [[f32::NAN, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        assert!(matches!(
            pca_normals_and_curvature(&nan, 2),
            Err(Error::NonFinite { index: 0, .. })
        ));
        // Coincident points: curvature 0, no panic.
        let same = [[1.0f32; 3]; 5];
        assert_eq!(
            pca_normals_and_curvature(&same, 3).unwrap().curvature,
            vec![0.0; 5]
        );
    }
}
