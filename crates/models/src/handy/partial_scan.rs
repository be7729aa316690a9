//! Synthetic partial, noisy scans of a mesh for the fitting experiment (thesis ch. 3.4.4,
//! Table 3.5, made harder): a single-view scanner sees only the side of the surface facing
//! it, and measures it with noise.
//!
//! # Conventions
//! Back-face culling only: a surface sample is kept when its face normal points towards the
//! camera (`n · d > 0`, `d` the direction from the object to the camera); self-occlusion
//! (e.g. a finger in front of the palm) is not modelled. Noise is isotropic Gaussian with
//! standard deviation `noise` in input units (mm), seeded.

use meshgnn_geometry::{TriMesh, sample_surface};
use rand::SeedableRng;
use rand::rngs::StdRng;
use rand_distr::{Distribution, Normal};

use crate::{Error, Result};

/// A one-sided noisy scan of `mesh`: `samples` area-uniform surface points (seeded), of which
/// those facing `camera_direction` are kept (about half for a closed surface), each moved by
/// `N(0, noise²)` per coordinate. Returns `#P×3`.
///
/// ```
/// use meshgnn_geometry::icosphere;
/// use meshgnn_models::partial_scan;
/// let scan = partial_scan(&icosphere(3), [0.0, 0.0, 1.0], 2000, 0.0, 1)?;
/// assert!(scan.iter().all(|p| p[2] > -0.05)); // only the upper half of the sphere
/// assert!(scan.len() > 800 && scan.len() < 1200);
/// # Ok::<(), meshgnn_models::Error>(())
/// ```
pub fn partial_scan(
    mesh: &TriMesh,
    camera_direction: [f32; 3],
    samples: usize,
    noise: f64,
    seed: u64,
) -> Result<Vec<[f32; 3]>> {
    let len = camera_direction
        .iter()
        .map(|&c| f64::from(c).powi(2))
        .sum::<f64>()
        .sqrt();
    if len.is_nan() || len <= 0.0 || !len.is_finite() {
        return Err(Error::Invalid {
            what: "camera direction".into(),
            reason: format!("{camera_direction:?} must be finite and non-zero"),
        });
    }
    if !(noise >= 0.0 && noise.is_finite()) {
        return Err(Error::Invalid {
            what: "scan noise".into(),
            reason: format!("{noise}: must be finite and ≥ 0"),
        });
    }
    let normal = Normal::new(0.0, noise).map_err(|e| Error::Invalid {
        what: "scan noise".into(),
        reason: format!("{noise}: {e}"),
    })?;
    let s = sample_surface(mesh, samples, seed)?;
    let mut rng = StdRng::seed_from_u64(seed ^ 0x5CA7_0000_0000_0001);
    let facing = |n: &[f32; 3]| -> bool {
        n.iter()
            .zip(&camera_direction)
            .map(|(a, b)| f64::from(*a) * f64::from(*b))
            .sum::<f64>()
            > 0.0
    };
    let scan: Vec<[f32; 3]> = s
        .points
        .iter()
        .zip(&s.normals)
        .filter(|(_, n)| facing(n))
        .map(|(p, _)| p.map(|c| (f64::from(c) + normal.sample(&mut rng)) as f32))
        .collect();
    if scan.is_empty() {
        return Err(Error::Invalid {
            what: "partial scan".into(),
            reason: "no surface faces the camera".into(),
        });
    }
    Ok(scan)
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshgnn_geometry::icosphere;

    #[test]
    fn noise_has_the_requested_spread_and_is_seeded() {
        let m = icosphere(3);
        let clean = partial_scan(&m, [1.0, 0.0, 0.0], 5000, 0.0, 4).unwrap();
        let noisy = partial_scan(&m, [1.0, 0.0, 0.0], 5000, 0.01, 4).unwrap();
        assert_eq!(clean.len(), noisy.len());
        let var: f64 = clean
            .iter()
            .zip(&noisy)
            .flat_map(|(a, b)| (0..3).map(move |k| f64::from(a[k] - b[k]).powi(2)))
            .sum::<f64>()
            / (3 * clean.len()) as f64;
        assert!((var.sqrt() - 0.01).abs() < 0.001, "{}", var.sqrt());
        assert_eq!(
            noisy,
            partial_scan(&m, [1.0, 0.0, 0.0], 5000, 0.01, 4).unwrap()
        );
        assert!(partial_scan(&m, [0.0; 3], 10, 0.0, 0).is_err());
        assert!(partial_scan(&m, [1.0, 0.0, 0.0], 10, -1.0, 0).is_err());
    }
}
