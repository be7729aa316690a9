//! Noisy-scan variants (thesis ch. 5.5.7, Table 5.5: inputs distorted by Gaussian noise).
//! The noise is isotropic Gaussian on every vertex with σ a fraction of the bounding-box
//! diagonal, so the level is comparable across shapes of any scale.

use meshgnn_geometry::TriMesh;
use rand::SeedableRng;
use rand::rngs::StdRng;
use rand_distr::{Distribution, Normal};

use crate::error::{Result, invalid};

/// `mesh` with every coordinate displaced by `N(0, (sigma · diagonal)²)`, same topology;
/// deterministic from `seed`. `sigma` in `[0, 1]`.
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
/// let diag = 2.0 * 3f64.sqrt(); // icosphere of radius 1
/// assert!((rms / diag - 0.01).abs() < 0.002);
/// # Ok::<(), meshgnn_data::Error>(())
/// ```
pub fn noisy_scan(mesh: &TriMesh, sigma: f64, seed: u64) -> Result<TriMesh> {
    if !(0.0..=1.0).contains(&sigma) {
        return Err(invalid(
            "sigma",
            sigma,
            "must be in [0, 1] (fraction of the diagonal)",
        ));
    }
    let mut lo = [f64::MAX; 3];
    let mut hi = [f64::MIN; 3];
    for p in mesh.vertices() {
        for k in 0..3 {
            lo[k] = lo[k].min(f64::from(p[k]));
            hi[k] = hi[k].max(f64::from(p[k]));
        }
    }
    let diag = (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt();
    let normal = Normal::new(0.0, (sigma * diag).max(0.0))
        .map_err(|e| invalid("sigma", sigma, &e.to_string()))?;
    let mut rng = StdRng::seed_from_u64(seed);
    let vertices = mesh
        .vertices()
        .iter()
        .map(|p| p.map(|c| (f64::from(c) + normal.sample(&mut rng)) as f32))
        .collect();
    Ok(mesh.clone().with_vertices(vertices)?)
}
