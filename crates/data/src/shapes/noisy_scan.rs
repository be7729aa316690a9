//! Noisy-scan variants (thesis ch. 5.5.7, Table 5.5: inputs distorted by Gaussian noise).
//!
//! # Conventions
//! The noise is isotropic Gaussian on every coordinate with standard deviation `σ · r`, `r`
//! the bounding-sphere radius about the centroid ([`unit_sphere_normalization`]). The thesis
//! adds `σ = 1` noise to shapes it evaluates after that same normalisation (the metrics of
//! ch. 5.4 compare shapes scaled to the unit sphere), so `σ` here is the thesis' σ on the
//! normalised shape, and the level is comparable across shapes of any scale. This is the one
//! noise of the workspace: `synth shapes --noise` and `pcsimplify bench --noise` both use it.

use meshgnn_geometry::{TriMesh, unit_sphere_normalization};
use rand::SeedableRng;
use rand::rngs::StdRng;
use rand_distr::{Distribution, Normal};

use crate::error::{Result, invalid};

/// `points: #P×3` with every coordinate displaced by `N(0, (sigma · r)²)`, `r` the
/// bounding-sphere radius about the centroid; deterministic from `seed`. `sigma` finite and
/// `>= 0`.
///
/// ```
/// use meshgnn_data::gaussian_noise;
/// use meshgnn_geometry::icosphere;
/// let sphere = icosphere(4); // bounding-sphere radius 1
/// let noisy = gaussian_noise(sphere.vertices(), 0.01, 3)?;
/// let rms = (noisy.iter().zip(sphere.vertices())
///     .map(|(a, b)| (0..3).map(|k| ((a[k] - b[k]) as f64).powi(2)).sum::<f64>()).sum::<f64>()
///     / (3 * noisy.len()) as f64).sqrt();
/// assert!((rms - 0.01).abs() < 0.0005);
/// assert_eq!(noisy, gaussian_noise(sphere.vertices(), 0.01, 3)?);
/// assert_ne!(noisy, gaussian_noise(sphere.vertices(), 0.01, 4)?);
/// # Ok::<(), meshgnn_data::Error>(())
/// ```
pub fn gaussian_noise(points: &[[f32; 3]], sigma: f64, seed: u64) -> Result<Vec<[f32; 3]>> {
    if !(sigma.is_finite() && sigma >= 0.0) {
        return Err(invalid(
            "sigma",
            sigma,
            "must be finite and >= 0 (fraction of the bounding-sphere radius)",
        ));
    }
    let radius = unit_sphere_normalization(points)?.radius;
    let normal =
        Normal::new(0.0, sigma * radius).map_err(|e| invalid("sigma", sigma, &e.to_string()))?;
    let mut rng = StdRng::seed_from_u64(seed);
    Ok(points
        .iter()
        .map(|p| p.map(|c| (f64::from(c) + normal.sample(&mut rng)) as f32))
        .collect())
}

/// `mesh` with [`gaussian_noise`] on its vertices, same topology; deterministic from `seed`.
/// `sigma` in `[0, 1]` (fraction of the bounding-sphere radius).
///
/// ```
/// use meshgnn_data::noisy_scan;
/// use meshgnn_geometry::icosphere;
/// let m = icosphere(3);
/// let n = noisy_scan(&m, 0.01, 1)?;
/// assert_eq!(n.triangles(), m.triangles());
/// let rms = (n.vertices().iter().zip(m.vertices())
///     .map(|(a, b)| (0..3).map(|k| ((a[k] - b[k]) as f64).powi(2)).sum::<f64>()).sum::<f64>()
///     / (3 * m.vertex_count()) as f64).sqrt();
/// assert!((rms - 0.01).abs() < 0.002); // icosphere of radius 1
/// # Ok::<(), meshgnn_data::Error>(())
/// ```
pub fn noisy_scan(mesh: &TriMesh, sigma: f64, seed: u64) -> Result<TriMesh> {
    if !(0.0..=1.0).contains(&sigma) {
        return Err(invalid(
            "sigma",
            sigma,
            "must be in [0, 1] (fraction of the bounding-sphere radius)",
        ));
    }
    let vertices = gaussian_noise(mesh.vertices(), sigma, seed)?;
    Ok(mesh.clone().with_vertices(vertices)?)
}
