//! A multivariate Gaussian over latent codes, fitted to a model's training latents: the
//! sampler of the specificity experiment (thesis ch. 3.4.1, 1000 random shapes per model) and
//! of `handy sample`, and the Mahalanobis prior of scan fitting (ch. 3.4.4).
//!
//! # Conventions
//! Full covariance (autoencoder latents are correlated), sample estimate with `n − 1`, plus a
//! ridge of `1e-9 · trace / Z` so the Cholesky factor exists for rank-deficient sets. Sampling
//! draws standard normals from `StdRng::seed_from_u64(seed)` in a fixed order: `μ + L ε`.

use rand::SeedableRng;
use rand::rngs::StdRng;
use rand_distr::{Distribution, StandardNormal};

use crate::{Error, Result};

/// `N(μ, L Lᵀ)` over latent codes of size `Z`, with the modes of the codes it was fitted to.
#[derive(Debug, Clone, PartialEq)]
pub struct LatentGaussian {
    mean: Vec<f64>,
    /// Lower-triangular Cholesky factor `L`, `Z×Z` row-major.
    cholesky: Vec<f64>,
    /// Means of the k-means clusters of the fitted codes (see [`LatentGaussian::modes`]).
    modes: Vec<Vec<f64>>,
}

/// Number of k-means clusters [`LatentGaussian::fit`] keeps as modes.
pub const LATENT_MODES: usize = 16;

fn invalid(what: &str, reason: impl Into<String>) -> Error {
    Error::Invalid {
        what: what.to_string(),
        reason: reason.into(),
    }
}

/// Cholesky factor of the symmetric positive definite `a: n×n` (row-major), in `f64`.
fn cholesky(a: &[f64], n: usize) -> Result<Vec<f64>> {
    let mut l = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..=i {
            let s: f64 = (0..j).map(|k| l[i * n + k] * l[j * n + k]).sum();
            let v = a[i * n + j] - s;
            if i == j {
                if v.is_nan() || v <= 0.0 {
                    return Err(invalid(
                        "latent covariance",
                        format!("not positive definite at dimension {i}"),
                    ));
                }
                l[i * n + i] = v.sqrt();
            } else {
                l[i * n + j] = v / l[j * n + j];
            }
        }
    }
    Ok(l)
}

impl LatentGaussian {
    /// The standard normal `N(0, I)` of size `latent` (the prior of a whitened PCA model).
    pub fn standard(latent: usize) -> Self {
        let mut cholesky = vec![0.0; latent * latent];
        for i in 0..latent {
            cholesky[i * latent + i] = 1.0;
        }
        Self {
            mean: vec![0.0; latent],
            cholesky,
            modes: Vec::new(),
        }
    }

    /// Fits mean and covariance to `latents` (`N` codes of size `Z`, `N ≥ 2`), and keeps the
    /// means of [`LATENT_MODES`] k-means clusters of them as modes.
    ///
    /// ```
    /// use meshgnn_models::LatentGaussian;
    /// let g = LatentGaussian::fit(&[vec![1.0, 0.0], vec![3.0, 0.0], vec![2.0, 1.0], vec![2.0, -1.0]])?;
    /// assert_eq!(g.mean(), &[2.0, 0.0]);
    /// assert!((g.std()[0] - (2.0f64 / 3.0).sqrt()).abs() < 1e-6);
    /// # Ok::<(), meshgnn_models::Error>(())
    /// ```
    pub fn fit(latents: &[Vec<f32>]) -> Result<Self> {
        let n = latents.len();
        let z = latents.first().map_or(0, Vec::len);
        if n < 2 || z == 0 {
            return Err(invalid(
                "latents",
                format!("need at least 2 non-empty codes, got {n} of size {z}"),
            ));
        }
        if let Some(i) = latents.iter().position(|l| l.len() != z) {
            return Err(invalid(
                &format!("latent {i}"),
                format!("size differs from the first ({z})"),
            ));
        }
        if latents.iter().flatten().any(|c| !c.is_finite()) {
            return Err(invalid("latents", "non-finite value"));
        }
        let mean: Vec<f64> = (0..z)
            .map(|k| latents.iter().map(|l| f64::from(l[k])).sum::<f64>() / n as f64)
            .collect();
        let mut cov = vec![0.0; z * z];
        for l in latents {
            for i in 0..z {
                let di = f64::from(l[i]) - mean[i];
                for j in 0..=i {
                    cov[i * z + j] += di * (f64::from(l[j]) - mean[j]);
                }
            }
        }
        let trace: f64 = (0..z).map(|i| cov[i * z + i]).sum::<f64>() / (n - 1) as f64;
        let ridge = (1e-9 * trace / z as f64).max(1e-30);
        for i in 0..z {
            for j in 0..=i {
                let c = cov[i * z + j] / (n - 1) as f64 + if i == j { ridge } else { 0.0 };
                cov[i * z + j] = c;
                cov[j * z + i] = c;
            }
        }
        Ok(Self {
            modes: k_means(latents, &mean, LATENT_MODES),
            mean,
            cholesky: cholesky(&cov, z)?,
        })
    }

    /// Builds a Gaussian (without modes) from `mean: Z` and its lower Cholesky factor
    /// `cholesky: Z×Z` (row-major), e.g. as read from a model file.
    pub fn from_parts(mean: Vec<f64>, cholesky: Vec<f64>) -> Result<Self> {
        let z = mean.len();
        if z == 0 || cholesky.len() != z * z {
            return Err(invalid(
                "latent Gaussian",
                format!(
                    "mean of size {z} with a factor of {} entries",
                    cholesky.len()
                ),
            ));
        }
        if (0..z).any(|i| cholesky[i * z + i].is_nan() || cholesky[i * z + i] <= 0.0)
            || mean.iter().chain(&cholesky).any(|c| !c.is_finite())
        {
            return Err(invalid(
                "latent Gaussian",
                "the factor needs a positive diagonal and finite entries",
            ));
        }
        Ok(Self {
            mean,
            cholesky,
            modes: Vec::new(),
        })
    }

    /// The means of k-means clusters of the codes the Gaussian was fitted to, `K×Z`: where
    /// the training shapes gather (for hands, the pose clusters: fists, pinches, open hands),
    /// which a unimodal Gaussian blurs into one mean. Scan fitting starts from them (see
    /// `ScanFitOptions::global_init`). Empty when built from parts or read from a file
    /// written before modes were kept.
    pub fn modes(&self) -> &[Vec<f64>] {
        &self.modes
    }

    /// Size `Z` of the codes.
    pub fn latent_size(&self) -> usize {
        self.mean.len()
    }

    /// The mean `μ`, `Z`.
    pub fn mean(&self) -> &[f64] {
        &self.mean
    }

    /// The lower Cholesky factor `L` of the covariance, `Z×Z` row-major.
    pub fn cholesky(&self) -> &[f64] {
        &self.cholesky
    }

    /// Marginal standard deviations `sqrt(Σ_kk)`, `Z`.
    pub fn std(&self) -> Vec<f64> {
        let z = self.mean.len();
        (0..z)
            .map(|i| {
                (0..=i)
                    .map(|k| self.cholesky[i * z + k].powi(2))
                    .sum::<f64>()
                    .sqrt()
            })
            .collect()
    }

    /// `L⁻¹`, `Z×Z` row-major (lower triangular): `‖L⁻¹ (z − μ)‖²` is the squared
    /// Mahalanobis distance of a code.
    pub fn whitening(&self) -> Vec<f64> {
        let z = self.mean.len();
        let l = &self.cholesky;
        let mut inv = vec![0.0; z * z];
        for col in 0..z {
            for i in col..z {
                let rhs = if i == col { 1.0 } else { 0.0 };
                let s: f64 = (col..i).map(|k| l[i * z + k] * inv[k * z + col]).sum();
                inv[i * z + col] = (rhs - s) / l[i * z + i];
            }
        }
        inv
    }

    /// `count` codes `μ + L ε`, `ε ~ N(0, I)`, deterministic from `seed`: `count × Z`.
    ///
    /// ```
    /// use meshgnn_models::LatentGaussian;
    /// let g = LatentGaussian::standard(3);
    /// let a = g.sample(2000, 7);
    /// assert_eq!(a, g.sample(2000, 7));
    /// let mean0 = a.iter().map(|z| z[0] as f64).sum::<f64>() / 2000.0;
    /// assert!(mean0.abs() < 0.1);
    /// ```
    pub fn sample(&self, count: usize, seed: u64) -> Vec<Vec<f32>> {
        let z = self.mean.len();
        let mut rng = StdRng::seed_from_u64(seed);
        (0..count)
            .map(|_| {
                let eps: Vec<f64> = (0..z).map(|_| StandardNormal.sample(&mut rng)).collect();
                (0..z)
                    .map(|i| {
                        let s: f64 = (0..=i).map(|k| self.cholesky[i * z + k] * eps[k]).sum();
                        (self.mean[i] + s) as f32
                    })
                    .collect()
            })
            .collect()
    }

    /// The Gaussian as JSON `{"cholesky": [..], "mean": [..], "modes": [[..], ..]}` (how a
    /// hand model file stores it: the entry [`crate::LATENT_GAUSSIAN_KEY`]).
    pub fn to_json(&self) -> String {
        serde_json::json!({"mean": self.mean, "cholesky": self.cholesky, "modes": self.modes})
            .to_string()
    }

    /// Reads [`LatentGaussian::to_json`]'s text (`modes` may be absent); errors name the
    /// missing or malformed key.
    ///
    /// ```
    /// use meshgnn_models::LatentGaussian;
    /// let g = LatentGaussian::standard(2);
    /// assert_eq!(LatentGaussian::from_json(&g.to_json())?, g);
    /// assert!(LatentGaussian::from_json(r#"{"mean": [0.0]}"#).is_err());
    /// # Ok::<(), meshgnn_models::Error>(())
    /// ```
    pub fn from_json(text: &str) -> Result<Self> {
        let value: serde_json::Value = serde_json::from_str(text)
            .map_err(|e| invalid("latent Gaussian", format!("not JSON: {e}")))?;
        let list = |key: &str| -> Result<Vec<f64>> {
            value
                .get(key)
                .and_then(serde_json::Value::as_array)
                .ok_or_else(|| invalid("latent Gaussian", format!("`{key}` missing")))?
                .iter()
                .map(|x| {
                    x.as_f64().ok_or_else(|| {
                        invalid("latent Gaussian", format!("`{key}` holds a non-number"))
                    })
                })
                .collect()
        };
        let gaussian = Self::from_parts(list("mean")?, list("cholesky")?)?;
        let modes: Vec<Vec<f64>> = match value.get("modes") {
            None => Vec::new(),
            Some(m) => serde_json::from_value(m.clone())
                .map_err(|e| invalid("latent Gaussian", format!("`modes`: {e}")))?,
        };
        let z = gaussian.latent_size();
        if modes
            .iter()
            .any(|m| m.len() != z || m.iter().any(|c| !c.is_finite()))
        {
            return Err(invalid(
                "latent Gaussian",
                format!("`modes` must hold finite codes of size {z}"),
            ));
        }
        Ok(Self { modes, ..gaussian })
    }
}

/// The means of `k` clusters of `codes` (fewer when there are fewer distinct codes) by Lloyd's
/// k-means: started from the code nearest `mean` and then, one by one, the code farthest from
/// the centres so far (deterministic), 50 iterations at most.
fn k_means(codes: &[Vec<f32>], mean: &[f64], k: usize) -> Vec<Vec<f64>> {
    let points: Vec<Vec<f64>> = codes
        .iter()
        .map(|c| c.iter().map(|&x| f64::from(x)).collect())
        .collect();
    let distance =
        |a: &[f64], b: &[f64]| -> f64 { a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum() };
    let nearest_to = |target: &[f64], from: &[Vec<f64>]| -> (usize, f64) {
        from.iter()
            .map(|c| distance(target, c))
            .enumerate()
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap_or((0, 0.0))
    };
    let mut centres = vec![points[nearest_to(mean, &points).0].clone()];
    while centres.len() < k {
        let (farthest, gap) = points
            .iter()
            .map(|p| nearest_to(p, &centres).1)
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap_or((0, 0.0));
        if gap <= 0.0 {
            break;
        }
        centres.push(points[farthest].clone());
    }
    for _ in 0..50 {
        let mut sums = vec![vec![0.0; mean.len()]; centres.len()];
        let mut counts = vec![0usize; centres.len()];
        for p in &points {
            let c = nearest_to(p, &centres).0;
            counts[c] += 1;
            for (s, x) in sums[c].iter_mut().zip(p) {
                *s += x;
            }
        }
        let moved: Vec<Vec<f64>> = sums
            .into_iter()
            .zip(&counts)
            .zip(&centres)
            .map(|((s, &n), old)| {
                if n == 0 {
                    old.clone()
                } else {
                    s.into_iter().map(|x| x / n as f64).collect()
                }
            })
            .collect();
        if moved == centres {
            break;
        }
        centres = moved;
    }
    centres
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn modes_are_the_centres_of_well_separated_clusters() {
        // Three tight clusters in 2-d (sizes 30, 20, 10) around known centres.
        let centres = [[0.0f32, 0.0], [10.0, 0.0], [0.0, 10.0]];
        let codes: Vec<Vec<f32>> = [30, 20, 10]
            .iter()
            .zip(centres)
            .flat_map(|(&n, c)| {
                (0..n).map(move |i| {
                    let t = i as f32;
                    vec![c[0] + 0.1 * (t * 0.7).sin(), c[1] + 0.1 * (t * 1.3).cos()]
                })
            })
            .collect();
        let mean = [10.0 * 20.0 / 60.0, 10.0 * 10.0 / 60.0];
        let modes = k_means(&codes, &mean, 3);
        assert_eq!(modes.len(), 3);
        for c in centres {
            let nearest = modes
                .iter()
                .map(|m| {
                    ((m[0] - f64::from(c[0])).powi(2) + (m[1] - f64::from(c[1])).powi(2)).sqrt()
                })
                .fold(f64::MAX, f64::min);
            assert!(nearest < 0.1, "{c:?} {modes:?}");
        }
        // Fewer distinct codes than clusters: one mode per code.
        assert_eq!(
            k_means(&[vec![1.0], vec![1.0], vec![2.0]], &[1.3], 8).len(),
            2
        );
        let g = LatentGaussian::fit(&codes).unwrap();
        assert_eq!(g.modes().len(), LATENT_MODES);
        // JSON keeps the modes (to the last bits of the decimal text).
        let back = LatentGaussian::from_json(&g.to_json()).unwrap();
        for (a, b) in back
            .modes()
            .iter()
            .flatten()
            .zip(g.modes().iter().flatten())
        {
            assert!((a - b).abs() <= 1e-14 * b.abs().max(1.0), "{a} {b}");
        }
    }

    #[test]
    fn sample_covariance_matches_the_fit() {
        // correlated 2-d codes: y = 0.5 x + small
        let codes: Vec<Vec<f32>> = (0..200)
            .map(|i| {
                let x = (i as f32 * 0.37).sin() * 2.0;
                vec![x, 0.5 * x + 0.1 * (i as f32 * 1.3).cos()]
            })
            .collect();
        let g = LatentGaussian::fit(&codes).unwrap();
        let s = g.sample(20000, 1);
        let h = LatentGaussian::fit(&s).unwrap();
        for (a, b) in g.std().iter().zip(h.std()) {
            assert!((a - b).abs() / a < 0.05, "{a} vs {b}");
        }
        // L⁻¹ L = I
        let w = g.whitening();
        let l = g.cholesky();
        for i in 0..2 {
            for j in 0..2 {
                let p: f64 = (0..2).map(|k| w[i * 2 + k] * l[k * 2 + j]).sum();
                assert!((p - if i == j { 1.0 } else { 0.0 }).abs() < 1e-9);
            }
        }
    }

    #[test]
    fn rejects_bad_input() {
        assert!(LatentGaussian::fit(&[vec![1.0]]).is_err());
        assert!(LatentGaussian::fit(&[vec![1.0], vec![1.0, 2.0]]).is_err());
        assert!(LatentGaussian::fit(&[vec![f32::NAN], vec![1.0]]).is_err());
        assert!(LatentGaussian::from_parts(vec![0.0], vec![0.0]).is_err());
        assert!(LatentGaussian::from_parts(vec![0.0, 1.0], vec![1.0]).is_err());
    }
}
