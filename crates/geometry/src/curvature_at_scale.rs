//! Point curvature, mean curvature and roughness (thesis eq. 5.1-5.3) of a cloud at one
//! *physical* scale, evaluated at any query locations: the fields behind the fair curvature
//! metrics of ch. 5.4 (CE, RE, SDM), where an original and a simplified cloud must be measured
//! at the same places and the same radius.
//!
//! # Why not the `k` nearest neighbours
//! [`crate::curvature_features`] takes each point's `k` nearest neighbours, so its scale is the
//! cloud's own spacing: a 5% subsample of a surface has neighbourhoods `1/√0.05 ≈ 4.5×` wider
//! and, since `λ0 / Σλ` of eq. 5.2 grows with the square of the neighbourhood radius on a
//! smooth surface, reads about 20× the curvature of the original at the same place. Here every
//! cloud is measured with one Gaussian kernel of radius `ρ`, so a uniform subsample reads the
//! original's curvature up to sampling noise.
//!
//! # Conventions
//! - Neighbourhood of a location `q` in the cloud: its points within `2ρ` (kernel weight
//!   `e^{-4} ≈ 0.02` at the cut), thinned evenly to at most [`MAX_SCALE_NEIGHBOURS`] where the
//!   cloud is denser ([`SpatialIndex::within_thinned`]: the kernel keeps its radius and the
//!   cost stays bounded). A
//!   location with fewer than [`VOID_NEIGHBOURS`] points within `2ρ` (the cloud leaves a hole
//!   there) takes its [`VOID_NEIGHBOURS`] nearest points instead, weighted relative to the
//!   nearest: it reads the curvature of the closest patch the cloud does have, as the
//!   nearest-neighbour correspondence of eq. 5.8 would.
//! - Weights `w_j = exp(−|p_j − q|²/ρ²)` (eq. 5.3 with `h = ρ²`), shifted by the nearest
//!   distance so a far void does not underflow; every quantity below is a weighted *ratio*,
//!   invariant to a common factor of the weights.
//! - `κ(q)`: eq. 5.2 on the weighted covariance of the neighbourhood, centred at its weighted
//!   mean (eq. 5.1 centres at `p_i`, which is a cloud point there; a query need not be, and
//!   centring at it would read its offset from the cloud as curvature).
//! - `K̄(q)`: eq. 5.3, the weighted mean of `κ` at the neighbourhood's own points.
//! - Roughness `R(q) = |κ(q) − K̄(q)|`.

use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::spatial_index::SpatialIndex;
use crate::symmetric_eigen3::symmetric_eigen3;

/// Most neighbours per location: bounds the cost where a cloud piles points together.
pub const MAX_SCALE_NEIGHBOURS: usize = 256;

/// Fewest neighbours a location uses; below it the nearest this many are taken (module docs).
pub const VOID_NEIGHBOURS: usize = 8;

/// The fields of eq. 5.1-5.3 at the query locations, each `#Q` long.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct CurvatureAtScale {
    /// Point curvature `κ` (eq. 5.2) of the neighbourhood of each location.
    pub curvature: Vec<f32>,
    /// Gaussian-weighted mean curvature `K̄` (eq. 5.3).
    pub mean_curvature: Vec<f32>,
    /// Roughness `|κ − K̄|`.
    pub roughness: Vec<f32>,
}

/// Eq. 5.1-5.3 of `cloud: #P×3` at `queries: #Q×3` with the Gaussian kernel of radius
/// `radius` (module docs). Fails on an empty cloud, non-finite points, a cloud of fewer than
/// 3 points, or a radius that is not positive and finite.
///
/// ```
/// use meshgnn_geometry::{curvature_at_scale, icosphere};
/// let plane: Vec<[f32; 3]> = (0..400).map(|i| [(i % 20) as f32, (i / 20) as f32, 0.0]).collect();
/// let flat = curvature_at_scale(&plane, &[[9.5, 9.5, 0.0]], 2.0)?;
/// assert!(flat.curvature[0].abs() < 1e-6 && flat.roughness[0].abs() < 1e-6);
/// let sphere = icosphere(4);
/// let round = curvature_at_scale(sphere.vertices(), &[[0.0, 0.0, 1.0]], 0.2)?;
/// assert!(round.curvature[0] > 1e-4);
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn curvature_at_scale(
    cloud: &[[f32; 3]],
    queries: &[[f32; 3]],
    radius: f64,
) -> Result<CurvatureAtScale> {
    if !(radius > 0.0 && radius.is_finite()) {
        return Err(Error::InvalidParameter {
            name: "radius",
            message: format!("the kernel radius must be positive and finite, got {radius}"),
        });
    }
    if cloud.is_empty() {
        return Err(Error::Empty {
            what: "point cloud",
        });
    }
    if cloud.len() < 3 {
        return Err(Error::InvalidParameter {
            name: "point cloud",
            message: format!("curvature needs at least 3 points, got {}", cloud.len()),
        });
    }
    crate::tri_mesh::check_finite("query", queries)?;
    let index = SpatialIndex::new(cloud)?;
    let kernel = Kernel {
        index: &index,
        radius,
    };
    let own: Vec<f32> = cloud
        .par_iter()
        .map_init(Vec::new, |hood, p| {
            kernel.neighbourhood(p, hood);
            kernel.curvature(cloud, hood)
        })
        .collect();
    let (curvature, mean_curvature): (Vec<f32>, Vec<f32>) = queries
        .par_iter()
        .map_init(Vec::new, |hood, q| {
            kernel.neighbourhood(q, hood);
            (kernel.curvature(cloud, hood), kernel.mean(&own, hood))
        })
        .unzip();
    let roughness = curvature
        .iter()
        .zip(&mean_curvature)
        .map(|(c, m)| (c - m).abs())
        .collect();
    Ok(CurvatureAtScale {
        curvature,
        mean_curvature,
        roughness,
    })
}

/// The neighbourhood of the location `q` in the indexed cloud for the kernel of radius `radius`
/// (module docs): `(squared distance, index)` into `hood`, in the index's slot order. The
/// differentiable loss `meshgnn_losses::losses::mean_curvature_at_scale` takes its
/// neighbourhoods from this one function, so loss and metric agree by construction.
///
/// ```
/// use meshgnn_geometry::{SpatialIndex, kernel_neighbourhood};
/// let line: Vec<[f32; 3]> = (0..20).map(|i| [i as f32, 0.0, 0.0]).collect();
/// let index = SpatialIndex::new(&line)?;
/// let mut hood = Vec::new();
/// kernel_neighbourhood(&index, &[10.0, 0.0, 0.0], 3.0, &mut hood); // within 2ρ = 6
/// assert_eq!(hood.len(), 13);
/// kernel_neighbourhood(&index, &[100.0, 0.0, 0.0], 3.0, &mut hood); // a void: 8 nearest
/// assert_eq!(hood.len(), 8);
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn kernel_neighbourhood(
    index: &SpatialIndex,
    q: &[f32; 3],
    radius: f64,
    hood: &mut Vec<(f32, u32)>,
) {
    let cut = (4.0 * radius * radius) as f32;
    index.within_thinned(q, cut, MAX_SCALE_NEIGHBOURS, hood);
    if hood.len() < VOID_NEIGHBOURS {
        index.nearest(q, VOID_NEIGHBOURS, None, hood);
    }
}

/// The Gaussian kernel of one radius over one indexed cloud.
struct Kernel<'a> {
    index: &'a SpatialIndex,
    radius: f64,
}

impl Kernel<'_> {
    /// The neighbourhood of `q` as `(weight, index)` into `hood` (module docs).
    fn neighbourhood(&self, q: &[f32; 3], hood: &mut Vec<(f32, u32)>) {
        kernel_neighbourhood(self.index, q, self.radius, hood);
        let nearest = hood.iter().map(|n| n.0).fold(f32::INFINITY, f32::min);
        let (nearest, radius2) = (f64::from(nearest), self.radius * self.radius);
        for n in hood.iter_mut() {
            n.0 = (-(f64::from(n.0) - nearest) / radius2).exp() as f32;
        }
    }

    /// Eq. 5.2 on the weighted covariance of `hood`, centred at its weighted mean.
    fn curvature(&self, cloud: &[[f32; 3]], hood: &[(f32, u32)]) -> f32 {
        let Some(&(_, first)) = hood.first() else {
            return 0.0;
        };
        // Coordinates relative to one neighbour, for precision far from the origin.
        let origin = cloud[first as usize].map(f64::from);
        let (mut total, mut mean, mut second) = (0.0f64, [0.0f64; 3], [0.0f64; 6]);
        for &(w, j) in hood {
            let (w, p) = (f64::from(w), cloud[j as usize]);
            let d = [0, 1, 2].map(|a| f64::from(p[a]) - origin[a]);
            total += w;
            for a in 0..3 {
                mean[a] += w * d[a];
            }
            for (slot, (a, b)) in [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)]
                .into_iter()
                .enumerate()
            {
                second[slot] += w * d[a] * d[b];
            }
        }
        if total <= 0.0 {
            return 0.0;
        }
        let m = mean.map(|x| x / total);
        let c = |slot: usize, a: usize, b: usize| second[slot] / total - m[a] * m[b];
        let covariance = [
            [c(0, 0, 0), c(1, 0, 1), c(2, 0, 2)],
            [c(1, 0, 1), c(3, 1, 1), c(4, 1, 2)],
            [c(2, 0, 2), c(4, 1, 2), c(5, 2, 2)],
        ];
        let (values, _) = symmetric_eigen3(covariance);
        let values = values.map(|v| v.max(0.0));
        let sum = values[0] + values[1] + values[2];
        if sum > 0.0 {
            (values[0] / sum) as f32
        } else {
            0.0
        }
    }

    /// Eq. 5.3: the weighted mean of `field` over `hood`.
    fn mean(&self, field: &[f32], hood: &[(f32, u32)]) -> f32 {
        let (mut weighted, mut total) = (0.0f64, 0.0f64);
        for &(w, j) in hood {
            weighted += f64::from(w) * f64::from(field[j as usize]);
            total += f64::from(w);
        }
        if total > 0.0 {
            (weighted / total) as f32
        } else {
            0.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{icosphere, sample_surface, subdivided_cube};

    fn mean(values: &[f32]) -> f64 {
        values.iter().map(|&v| f64::from(v)).sum::<f64>() / values.len() as f64
    }

    /// A weighted covariance of a hand-made neighbourhood: four points of a unit square in the
    /// plane z = 0 and one at height 1 above its centre, all at distance 1 from the query
    /// (equal weights). Mean (0.5, 0.5, 0.2); the covariance is diagonal with variances
    /// 0.2, 0.2 and 0.16, so κ = 0.16 / 0.56.
    #[test]
    fn curvature_of_a_hand_computed_neighbourhood() {
        let cloud = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.5, 0.5, 1.0],
        ];
        // The query equidistant from all five: (0.5, 0.5, z) with 0.5 + z² = (1 − z)², z = 1/4.
        let q = [0.5, 0.5, 0.25];
        let index = SpatialIndex::new(&cloud).unwrap();
        let kernel = Kernel {
            index: &index,
            radius: 10f64.sqrt(),
        };
        let hood: Vec<(f32, u32)> = (0..5).map(|j| (1.0, j)).collect();
        let kappa = kernel.curvature(&cloud, &hood);
        assert!((f64::from(kappa) - 0.16 / 0.56).abs() < 1e-6, "{kappa}");
        // Through the public function: every point within 2ρ, weights all equal.
        let at = curvature_at_scale(&cloud, &[q], 10f64.sqrt()).unwrap();
        assert!((f64::from(at.curvature[0]) - 0.16 / 0.56).abs() < 1e-6);
    }

    /// On a unit sphere, in the tangent plane at `q` the normal offset is `z ≈ r²/2`; with
    /// `r²` exponential of mean `ρ²` cut at `4ρ²` (the 2-d Gaussian kernel and its cut),
    /// `κ ≈ Var z / E[r²] = (E[r⁴] − E[r²]²) / (4 E[r²])`, i.e. `≈ 0.188 ρ²`.
    #[test]
    fn sphere_curvature_matches_the_kernel_moments() {
        let t = 1.0 - (-4.0f64).exp();
        let r2 = (1.0 - 5.0 * (-4.0f64).exp()) / t;
        let r4 = (2.0 - 26.0 * (-4.0f64).exp()) / t;
        let constant = (r4 - r2 * r2) / (4.0 * r2);
        assert!((constant - 0.188).abs() < 1e-3, "{constant}");
        let cloud = sample_surface(&icosphere(5), 40_000, 8).unwrap().points;
        let queries = sample_surface(&icosphere(5), 300, 9).unwrap().points;
        for radius in [0.05f64, 0.1] {
            let at = curvature_at_scale(&cloud, &queries, radius).unwrap();
            let expected = constant * radius * radius;
            let got = mean(&at.curvature);
            assert!(
                (got / expected - 1.0).abs() < 0.05,
                "ρ {radius}: {got} vs {expected}"
            );
        }
    }

    /// The property the metrics rely on: at a fixed radius a uniform subsample reads the same
    /// curvature as the dense cloud, where the `k`-NN features read about `1/ratio` more.
    #[test]
    fn a_uniform_subsample_reads_the_dense_clouds_curvature() {
        let sphere = icosphere(4);
        let dense = sample_surface(&sphere, 40_000, 1).unwrap().points;
        let sparse = sample_surface(&sphere, 2_000, 2).unwrap().points;
        let queries = sample_surface(&sphere, 500, 3).unwrap().points;
        let radius = 0.15;
        let a = curvature_at_scale(&dense, &queries, radius).unwrap();
        let b = curvature_at_scale(&sparse, &queries, radius).unwrap();
        let (ma, mb) = (mean(&a.mean_curvature), mean(&b.mean_curvature));
        assert!(ma > 1e-4, "{ma}");
        assert!((mb / ma - 1.0).abs() < 0.15, "dense {ma} vs sparse {mb}");
        let knn_dense = crate::curvature_features(&dense, 16).unwrap();
        let knn_sparse = crate::curvature_features(&sparse, 16).unwrap();
        let ratio = mean(&knn_sparse.mean_curvature) / mean(&knn_dense.mean_curvature);
        assert!(ratio > 10.0, "k-NN features drift by {ratio}");
    }

    #[test]
    fn sharp_edges_read_higher_than_faces_and_voids_stay_finite() {
        let cube = subdivided_cube(8);
        let cloud = sample_surface(&cube, 20_000, 4).unwrap().points;
        // the middle of a face, the middle of an edge, and a location far from the cloud
        let queries = [[0.0, 0.0, 1.0], [1.0, 0.0, 1.0], [10.0, 10.0, 10.0]];
        let at = curvature_at_scale(&cloud, &queries, 0.1).unwrap();
        assert!(at.curvature[0] < 0.01, "{}", at.curvature[0]);
        assert!(at.curvature[1] > 0.05, "{}", at.curvature[1]);
        assert!(at.mean_curvature.iter().all(|c| c.is_finite()));
    }

    #[test]
    fn rejects_bad_input() {
        let p = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        assert!(curvature_at_scale(&p, &p, 0.0).is_err());
        assert!(curvature_at_scale(&p, &p, f64::NAN).is_err());
        assert!(curvature_at_scale(&p[..2], &p, 1.0).is_err());
        assert!(curvature_at_scale(&[], &p, 1.0).is_err());
        assert!(curvature_at_scale(&p, &[[f32::NAN, 0.0, 0.0]], 1.0).is_err());
    }
}
