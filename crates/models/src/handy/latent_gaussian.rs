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

/// `N(μ, L Lᵀ)` over latent codes of size `Z`.
#[derive(Debug, Clone, PartialEq)]
pub struct LatentGaussian {
    mean: Vec<f64>,
    /// Lower-triangular Cholesky factor `L`, `Z×Z` row-major.
    cholesky: Vec<f64>,
}

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
        }
    }

    /// Fits mean and covariance to `latents` (`N` codes of size `Z`, `N ≥ 2`).
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
            mean,
            cholesky: cholesky(&cov, z)?,
        })
    }

    /// Builds a Gaussian from `mean: Z` and its lower Cholesky factor `cholesky: Z×Z`
    /// (row-major), e.g. as read from a model file.
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
        Ok(Self { mean, cholesky })
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

    /// The Gaussian as JSON `{"cholesky": [..], "mean": [..]}` (how a hand model file stores
    /// it: the entry [`crate::LATENT_GAUSSIAN_KEY`]).
    pub fn to_json(&self) -> String {
        serde_json::json!({"mean": self.mean, "cholesky": self.cholesky}).to_string()
    }

    /// Reads [`LatentGaussian::to_json`]'s text; errors name the missing or malformed key.
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
        Self::from_parts(list("mean")?, list("cholesky")?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
