//! The PCA path beside Handy++'s spiral layers (beyond the thesis): with
//! `SpiralAutoencoderConfig::linear_skip`, the encoder outputs the whitened PCA coefficients
//! of eq. 3.2 plus the spiral encoder's output, and the decoder the PCA reconstruction plus
//! the spiral decoder's output. The spiral layers' last maps start at zero, so a fresh model
//! *is* the PCA model of its training set and training only has to learn the non-linear
//! remainder — the autoencoder starts from the linear baseline's error instead of far above
//! it (docs/handy.md).
//!
//! # Conventions
//! - The network works on normalised coordinates `x_n = (x − μ) / s` (per vertex coordinate,
//!   [`VertexNormalization`]); the PCA was fitted in data units. Both maps are therefore
//!   affine in normalised coordinates: with `U` the orthonormal components, `σ` their
//!   standard deviations and `T` the PCA mean,
//!   `z = x_n · A + c`, `A = diag(s) Uᵀ diag(1/σ)`, `c = (μ − T) Uᵀ diag(1/σ)`, and
//!   `x̂_n = z · B + d`, `B = diag(σ) U diag(1/s)`, `d = (T − μ) / s`,
//!   so `decode(encode(x))` in data units is exactly the PCA reconstruction.
//! - Tensors (fixed, not trained): `skip.encode_weight (3V, Z)`, `skip.encode_bias (1, Z)`,
//!   `skip.decode_weight (Z, 3V)`, `skip.decode_bias (1, 3V)`.

use std::collections::HashMap;

use candle_core::{DType, Device, Tensor};

use crate::handy::spiral::VertexNormalization;
use crate::{Error, MorphableModel, Pca, Result};

/// Name prefix of the skip's tensors in a model file.
pub const LINEAR_SKIP_PREFIX: &str = "skip.";

const NAMES: [&str; 4] = [
    "encode_weight",
    "encode_bias",
    "decode_weight",
    "decode_bias",
];

/// The fixed affine maps of the PCA path (see the module docs).
#[derive(Debug, Clone)]
pub struct LinearSkip {
    encode_weight: Tensor,
    encode_bias: Tensor,
    decode_weight: Tensor,
    decode_bias: Tensor,
}

impl LinearSkip {
    /// The PCA path of `pca` for a network normalised by `normalization` (same vertices).
    pub fn from_pca(pca: &Pca, normalization: &VertexNormalization) -> Result<Self> {
        let device = normalization.mean().device().clone();
        let flat = |t: &Tensor| -> Result<Vec<f64>> {
            Ok(t.flatten_all()?.to_dtype(DType::F64)?.to_vec1::<f64>()?)
        };
        let (mu, s) = (flat(normalization.mean())?, flat(normalization.std())?);
        let mean: Vec<f64> = pca
            .mean_shape()
            .into_iter()
            .flatten()
            .map(f64::from)
            .collect();
        let (dim, z) = (mean.len(), pca.latent_size());
        if mu.len() != dim {
            return Err(Error::Invalid {
                what: "linear skip".into(),
                reason: format!(
                    "a PCA of {} vertices for a normalisation of {}",
                    dim / 3,
                    mu.len() / 3
                ),
            });
        }
        let mut encode_weight = vec![0f32; dim * z];
        let mut encode_bias = vec![0f32; z];
        let mut decode_weight = vec![0f32; z * dim];
        for k in 0..z {
            let sigma = pca.variances()[k].sqrt().max(f64::MIN_POSITIVE);
            let u: Vec<f64> = pca
                .component(k)
                .ok_or_else(|| Error::Invalid {
                    what: "linear skip".into(),
                    reason: format!("PCA component {k} missing"),
                })?
                .into_iter()
                .flatten()
                .map(f64::from)
                .collect();
            let mut bias = 0.0;
            for j in 0..dim {
                encode_weight[j * z + k] = (s[j] * u[j] / sigma) as f32;
                decode_weight[k * dim + j] = (sigma * u[j] / s[j]) as f32;
                bias += (mu[j] - mean[j]) * u[j];
            }
            encode_bias[k] = (bias / sigma) as f32;
        }
        let decode_bias: Vec<f32> = (0..dim)
            .map(|j| ((mean[j] - mu[j]) / s[j]) as f32)
            .collect();
        Self::from_tensors(
            Tensor::from_vec(encode_weight, (dim, z), &device)?,
            Tensor::from_vec(encode_bias, (1, z), &device)?,
            Tensor::from_vec(decode_weight, (z, dim), &device)?,
            Tensor::from_vec(decode_bias, (1, dim), &device)?,
        )
    }

    fn from_tensors(
        encode_weight: Tensor,
        encode_bias: Tensor,
        decode_weight: Tensor,
        decode_bias: Tensor,
    ) -> Result<Self> {
        match (
            encode_weight.dims(),
            encode_bias.dims(),
            decode_weight.dims(),
            decode_bias.dims(),
        ) {
            ([d, z], [1, z2], [z3, d2], [1, d3])
                if z == z2 && z == z3 && d == d2 && d == d3 && *d > 0 && d % 3 == 0 && *z > 0 =>
            {
                Ok(Self {
                    encode_weight,
                    encode_bias,
                    decode_weight,
                    decode_bias,
                })
            }
            (a, b, c, d) => Err(Error::Invalid {
                what: "linear skip".into(),
                reason: format!(
                    "tensors of shapes {a:?}, {b:?}, {c:?}, {d:?}; expected (3V, Z), (1, Z), \
                     (Z, 3V), (1, 3V)"
                ),
            }),
        }
    }

    /// The skip stored under [`LINEAR_SKIP_PREFIX`] in `tensors`, on `device`.
    pub fn from_named_tensors(tensors: &HashMap<String, Tensor>, device: &Device) -> Result<Self> {
        let [a, b, c, d] = NAMES.map(|name| {
            let key = format!("{LINEAR_SKIP_PREFIX}{name}");
            tensors
                .get(&key)
                .ok_or_else(|| Error::Invalid {
                    what: format!("tensor `{key}`"),
                    reason: "missing from the model file".into(),
                })
                .and_then(|t| Ok(t.to_dtype(DType::F32)?.to_device(device)?))
        });
        Self::from_tensors(a?, b?, c?, d?)
    }

    /// The tensors, named as in a model file, on the CPU.
    pub fn to_named_tensors(&self) -> Result<HashMap<String, Tensor>> {
        let tensors = [
            &self.encode_weight,
            &self.encode_bias,
            &self.decode_weight,
            &self.decode_bias,
        ];
        NAMES
            .iter()
            .zip(tensors)
            .map(|(name, t)| {
                Ok((
                    format!("{LINEAR_SKIP_PREFIX}{name}"),
                    t.to_device(&Device::Cpu)?,
                ))
            })
            .collect()
    }

    /// Latent size `Z`.
    pub fn latent_size(&self) -> usize {
        self.encode_weight.dims()[1]
    }

    /// Vertex count `V`.
    pub fn vertex_count(&self) -> usize {
        self.encode_weight.dims()[0] / 3
    }

    /// Normalised `x: (B, V, 3)` → whitened PCA coefficients `(B, Z)`.
    pub fn encode(&self, x: &Tensor) -> Result<Tensor> {
        let flat = x.reshape((x.dim(0)?, 3 * self.vertex_count()))?;
        Ok(flat
            .matmul(&self.encode_weight)?
            .broadcast_add(&self.encode_bias)?)
    }

    /// Whitened coefficients `z: (B, Z)` → the normalised PCA reconstruction `(B, V, 3)`.
    pub fn decode(&self, z: &Tensor) -> Result<Tensor> {
        let flat = z
            .matmul(&self.decode_weight)?
            .broadcast_add(&self.decode_bias)?;
        Ok(flat.reshape((z.dim(0)?, self.vertex_count(), 3))?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::handy::spiral::mesh_batch;
    use crate::handy::spiral::test_fixtures::varied_shapes;

    #[test]
    fn the_skip_is_the_pca_model_in_normalised_coordinates() {
        let sphere = meshgnn_geometry::icosphere(2);
        let shapes = varied_shapes(&sphere, 6);
        let pca = Pca::fit(&sphere, &shapes, 3).unwrap();
        let norm = VertexNormalization::fit(&shapes, &Device::Cpu).unwrap();
        let skip = LinearSkip::from_pca(&pca, &norm).unwrap();
        let x = mesh_batch(&shapes, &Device::Cpu).unwrap();
        let z = skip.encode(&norm.normalize(&x).unwrap()).unwrap();
        let expected = pca.encode(&x).unwrap();
        let gap = |a: &Tensor, b: &Tensor| -> f32 {
            a.sub(b)
                .unwrap()
                .abs()
                .unwrap()
                .max_all()
                .unwrap()
                .to_scalar()
                .unwrap()
        };
        assert!(
            gap(&z, &expected) < 1e-3,
            "latents differ by {}",
            gap(&z, &expected)
        );
        let back = norm.denormalize(&skip.decode(&z).unwrap()).unwrap();
        let pca_back = pca.decode(&expected).unwrap();
        assert!(
            gap(&back, &pca_back) < 1e-4,
            "reconstructions differ by {}",
            gap(&back, &pca_back)
        );
        // stored and read back bit-identically; a missing tensor is named
        let mut named = skip.to_named_tensors().unwrap();
        let again = LinearSkip::from_named_tensors(&named, &Device::Cpu).unwrap();
        let values = |t: &Tensor| t.flatten_all().unwrap().to_vec1::<f32>().unwrap();
        assert_eq!(
            values(&again.decode(&z).unwrap()),
            values(&skip.decode(&z).unwrap())
        );
        named.remove("skip.decode_bias");
        let err = LinearSkip::from_named_tensors(&named, &Device::Cpu).unwrap_err();
        assert!(err.to_string().contains("skip.decode_bias"), "{err}");
    }
}
