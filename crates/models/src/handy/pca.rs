//! The PCA hand model "Handy" of thesis ch. 3.3.3, eq. 3.2: a mean shape plus an orthonormal
//! basis of the leading principal components of registered shapes (Blanz & Vetter 1999,
//! SIGGRAPH; Romero et al. 2017, MANO). The linear baseline of the spiral autoencoder.
//!
//! # Conventions
//! - Latent codes are *whitened*: `z_k = β_k / σ_k` with `β_k` the coefficient of eq. 3.2 and
//!   `σ_k² = λ_k` the k-th eigenvalue, so latents of the training set have zero mean and unit
//!   variance and `N(0, I)` samples the model's Gaussian shape distribution.
//! - The fit never forms the `3V×3V` covariance: it eigen-decomposes the `S×S` Gram matrix of
//!   the centred shapes (`S` shapes, `V` vertices) in `f64`, O(S²·V), and maps its eigenvectors
//!   back to `3V` space. Every sum runs in a fixed order, so the result is bit-identical for
//!   any thread count.
//! - Eigenvalues are the sample variances (divided by `S − 1`), in squared input units.

use std::path::Path;

use candle_core::{Device, Tensor};
use faer::Side;
use meshgnn_geometry::{TriMesh, atomic_write};
use meshgnn_losses::metrics::{CentredShapes, centred_shapes};
use rayon::prelude::*;

use crate::handy::morphable_model::MorphableModel;
use crate::tensor_file::{
    Array, check_shape, flatten_points, parse, read_f32, read_f64, read_u32, serialize_arrays,
    unflatten_points,
};
use crate::{CheckpointHeader, Error, LoadCheckpoint, Result};

/// The model's name in checkpoints.
pub const PCA_MODEL_NAME: &str = "pca";

/// A PCA shape model (eq. 3.2): `B(z) = T + Σ_k U_k σ_k z_k` with mean `T` (`3V`), orthonormal
/// components `U_k` (`3V` each) and standard deviations `σ_k`.
#[derive(Debug, Clone)]
pub struct Pca {
    template: TriMesh,
    mean: Vec<f32>,
    components: Vec<f32>,
    variances: Vec<f64>,
    mean_t: Tensor,
    encoder_t: Tensor,
    decoder_t: Tensor,
}

fn invalid(what: &str, reason: impl Into<String>) -> Error {
    Error::Invalid {
        what: what.to_string(),
        reason: reason.into(),
    }
}

impl Pca {
    /// Eq. 3.2: fits the mean and the leading `latent` components of `shapes` (`S` shapes,
    /// each `#V×3`, registered to `template`). Needs `S ≥ 2` and `latent` ≤ the number of
    /// components with non-zero variance (at most `S − 1`).
    ///
    /// ```
    /// use meshgnn_geometry::TriMesh;
    /// use meshgnn_models::{MorphableModel, Pca};
    /// let t = TriMesh::new(vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], vec![[0, 1, 2]])?;
    /// // three shapes that differ only by a shift of the first vertex along x
    /// let shapes: Vec<Vec<[f32; 3]>> = (0..3)
    ///     .map(|i| vec![[i as f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    ///     .collect();
    /// let pca = Pca::fit(&t, &shapes, 1)?;
    /// assert_eq!(pca.latent_size(), 1);
    /// assert!((pca.variances()[0] - 1.0).abs() < 1e-9); // variance of {0, 1, 2}
    /// assert!((pca.explained_variance_ratio()[0] - 1.0).abs() < 1e-9);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn fit(template: &TriMesh, shapes: &[Vec<[f32; 3]>], latent: usize) -> Result<Self> {
        Self::fit_components(template, shapes, latent, false)
    }

    /// [`Pca::fit`] keeping at most `latent` components: fewer when the shapes have fewer
    /// components of non-zero variance.
    pub(crate) fn fit_at_most(
        template: &TriMesh,
        shapes: &[Vec<[f32; 3]>],
        latent: usize,
    ) -> Result<Self> {
        Self::fit_components(template, shapes, latent, true)
    }

    fn fit_components(
        template: &TriMesh,
        shapes: &[Vec<[f32; 3]>],
        latent: usize,
        at_most: bool,
    ) -> Result<Self> {
        let v = template.vertex_count();
        let s = shapes.len();
        if s < 2 {
            return Err(invalid(
                "training shapes",
                format!("PCA needs at least 2 shapes, got {s}"),
            ));
        }
        if latent == 0 {
            return Err(invalid("latent size", "must be at least 1"));
        }
        for (i, shape) in shapes.iter().enumerate() {
            if shape.len() != v {
                return Err(invalid(
                    &format!("training shape {i}"),
                    format!("{} vertices, the template has {v}", shape.len()),
                ));
            }
            if shape.iter().flatten().any(|c| !c.is_finite()) {
                return Err(invalid(
                    &format!("training shape {i}"),
                    "non-finite coordinate",
                ));
            }
        }
        let dim = 3 * v;
        let CentredShapes {
            mean,
            centred,
            gram,
        } = centred_shapes(shapes)?;
        let denom = (s - 1) as f64;
        let eig = gram.self_adjoint_eigen(Side::Lower).map_err(|e| {
            invalid(
                "training shapes",
                format!("eigen-decomposition failed: {e:?}"),
            )
        })?;
        let u = eig.U();
        let eigenvalues = eig.S().column_vector();
        // Largest first, at most S − 1 (the centred data has rank ≤ S − 1).
        let order: Vec<usize> = (0..s).rev().take(s - 1).collect();
        let variances: Vec<f64> = order.iter().map(|&k| eigenvalues[k].max(0.0)).collect();
        let top = variances.first().copied().unwrap_or(0.0);
        let rank = variances
            .iter()
            .take_while(|&&l| l > 1e-12 * top && l > 0.0)
            .count();
        let latent = if at_most {
            latent.min(rank).max(1)
        } else {
            latent
        };
        if latent > rank {
            return Err(invalid(
                "latent size",
                format!(
                    "{latent} exceeds the {rank} components with non-zero variance of the {s} training shapes"
                ),
            ));
        }
        // U_k = Xᵀ v_k / ‖Xᵀ v_k‖ with ‖Xᵀ v_k‖² = (S − 1) λ_k.
        let components: Vec<f32> = order
            .iter()
            .take(latent)
            .zip(&variances)
            .flat_map(|(&k, &lambda)| {
                let norm = (denom * lambda).sqrt();
                let coef: Vec<f64> = (0..s).map(|i| u[(i, k)] / norm).collect();
                (0..dim)
                    .into_par_iter()
                    .map(|d| {
                        centred
                            .iter()
                            .zip(&coef)
                            .map(|(x, c)| x.get(d).copied().unwrap_or(0.0) * c)
                            .sum::<f64>() as f32
                    })
                    .collect::<Vec<f32>>()
            })
            .collect();
        let mean: Vec<f32> = mean.iter().map(|&m| m as f32).collect();
        Self::from_parts(template.clone(), mean, components, variances)
    }

    /// Builds a model from its parts: `mean: 3V`, `components: Z×3V` (row-major, orthonormal
    /// rows), `variances`: the spectrum, largest first, at least `Z` entries.
    fn from_parts(
        template: TriMesh,
        mean: Vec<f32>,
        components: Vec<f32>,
        variances: Vec<f64>,
    ) -> Result<Self> {
        let dim = 3 * template.vertex_count();
        if dim == 0 || mean.len() != dim || !components.len().is_multiple_of(dim) {
            return Err(invalid(
                "PCA model",
                "mean or components do not match the template",
            ));
        }
        let z = components.len() / dim;
        if z == 0
            || variances.len() < z
            || variances.iter().take(z).any(|&l| l.is_nan() || l <= 0.0)
        {
            return Err(invalid(
                "PCA model",
                "needs at least one component with positive variance",
            ));
        }
        let dev = Device::Cpu;
        let sigma: Vec<f32> = variances.iter().take(z).map(|l| l.sqrt() as f32).collect();
        let basis = Tensor::from_vec(components.clone(), (z, dim), &dev)?;
        let sigma_t = Tensor::from_vec(sigma, (z, 1), &dev)?;
        let decoder_t = basis.broadcast_mul(&sigma_t)?;
        let encoder_t = basis.broadcast_div(&sigma_t)?.t()?.contiguous()?;
        let mean_t = Tensor::from_vec(mean.clone(), (1, dim), &dev)?;
        Ok(Self {
            template,
            mean,
            components,
            variances,
            mean_t,
            encoder_t,
            decoder_t,
        })
    }

    /// The mean shape `T` of eq. 3.2, `#V×3`.
    pub fn mean_shape(&self) -> Vec<[f32; 3]> {
        unflatten_points(&self.mean)
    }

    /// Component `k` (`U_k` of eq. 3.2, unit length) as `#V×3` displacements, if `k < Z`.
    pub fn component(&self, k: usize) -> Option<Vec<[f32; 3]>> {
        let dim = self.mean.len();
        self.components
            .get(k * dim..(k + 1) * dim)
            .map(unflatten_points)
    }

    /// The whole PCA spectrum of the training set, largest first (`S − 1` variances `λ_k`,
    /// squared input units); the first `Z` belong to the model's components.
    pub fn variances(&self) -> &[f64] {
        &self.variances
    }

    /// Compactness (thesis Figure 3.11): `ratio[c]` = fraction of the training variance
    /// explained by the first `c + 1` components, for every component of the spectrum.
    pub fn explained_variance_ratio(&self) -> Vec<f64> {
        let total: f64 = self.variances.iter().sum();
        let mut acc = 0.0;
        self.variances
            .iter()
            .map(|l| {
                acc += l;
                if total > 0.0 { acc / total } else { 1.0 }
            })
            .collect()
    }

    /// Whitened latent code of one shape (`#V×3`): `z_k = U_k·(x − T) / σ_k`.
    pub fn project(&self, shape: &[[f32; 3]]) -> Result<Vec<f32>> {
        let v = self.template.vertex_count();
        if shape.len() != v {
            return Err(invalid(
                "shape",
                format!("{} vertices, the model has {v}", shape.len()),
            ));
        }
        let x = Tensor::from_vec(flatten_points(shape), (1, 1, v * 3), &Device::Cpu)?
            .reshape((1, v, 3))?;
        Ok(self.encode(&x)?.flatten_all()?.to_vec1()?)
    }

    /// The checkpoint ([`crate::Checkpoint`] layout, model [`PCA_MODEL_NAME`], config
    /// `{latent}`) as safetensors bytes: `pca.mean` (3V), `pca.components` (Z, 3V),
    /// `pca.variances` (S − 1, f64), `template.vertices` (V, 3), `template.triangles` (F, 3).
    pub fn to_bytes(&self) -> Result<Vec<u8>> {
        let dim = self.mean.len();
        let z = self.latent_size();
        let (tv, tf) = (self.template.vertices(), self.template.triangles());
        let arrays = [
            Array::f32("pca.mean", vec![dim], &self.mean),
            Array::f32("pca.components", vec![z, dim], &self.components),
            Array::f64("pca.variances", vec![self.variances.len()], &self.variances),
            Array::f32("template.vertices", vec![tv.len(), 3], &flatten_points(tv)),
            Array::u32(
                "template.triangles",
                vec![tf.len(), 3],
                &tf.iter().flatten().copied().collect::<Vec<_>>(),
            ),
        ];
        let config = serde_json::Map::from_iter([("latent".to_string(), z.into())]);
        let meta = CheckpointHeader::new(PCA_MODEL_NAME, config).to_metadata()?;
        serialize_arrays(&arrays, meta, Path::new("<pca>"))
    }

    /// Reads a checkpoint written by [`Pca::to_bytes`] (or by the earlier `meshgnn-pca`
    /// layout); `source` names it in errors.
    pub fn from_bytes(bytes: &[u8], source: &Path) -> Result<Self> {
        CheckpointHeader::from_bytes(bytes, source)?.expect_model(PCA_MODEL_NAME, source)?;
        let st = parse(bytes, source)?;
        let (vs, verts) = read_f32(&st, "template.vertices", source)?;
        let (fs, tris) = read_u32(&st, "template.triangles", source)?;
        let nv = vs.first().copied().unwrap_or(0);
        check_shape("template.vertices", &vs, &[nv, 3], source)?;
        check_shape(
            "template.triangles",
            &fs,
            &[fs.first().copied().unwrap_or(0), 3],
            source,
        )?;
        let template = TriMesh::new(
            unflatten_points(&verts),
            tris.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
        )?;
        let (ms, mean) = read_f32(&st, "pca.mean", source)?;
        check_shape("pca.mean", &ms, &[3 * nv], source)?;
        let (cs, components) = read_f32(&st, "pca.components", source)?;
        check_shape(
            "pca.components",
            &cs,
            &[cs.first().copied().unwrap_or(0), 3 * nv],
            source,
        )?;
        let (_, variances) = read_f64(&st, "pca.variances", source)?;
        Self::from_parts(template, mean, components, variances).map_err(|e| Error::Checkpoint {
            path: source.to_path_buf(),
            reason: e.to_string(),
        })
    }

    /// Writes the checkpoint to `path` atomically.
    pub fn save(&self, path: impl AsRef<Path>) -> Result<()> {
        Ok(atomic_write(path.as_ref(), &self.to_bytes()?)?)
    }

    /// Reads a checkpoint written by [`Pca::save`].
    pub fn load(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let bytes = std::fs::read(path).map_err(|e| Error::Checkpoint {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })?;
        Self::from_bytes(&bytes, path)
    }
}

impl LoadCheckpoint for Pca {
    fn from_checkpoint_bytes(bytes: &[u8], source: &Path) -> Result<Self> {
        Self::from_bytes(bytes, source)
    }
}

impl MorphableModel for Pca {
    fn latent_size(&self) -> usize {
        self.components.len() / self.mean.len().max(1)
    }

    fn template(&self) -> &TriMesh {
        &self.template
    }

    /// vertices: (B, V, 3) → whitened codes (B, Z).
    fn encode(&self, vertices: &Tensor) -> Result<Tensor> {
        let (b, v, c) = vertices.dims3()?;
        if v != self.template.vertex_count() || c != 3 {
            return Err(invalid(
                "vertices",
                format!(
                    "shape ({b}, {v}, {c}), the model expects (B, {}, 3)",
                    self.template.vertex_count()
                ),
            ));
        }
        let x = vertices
            .to_dtype(candle_core::DType::F32)?
            .reshape((b, 3 * v))?
            .broadcast_sub(&self.mean_t)?;
        Ok(x.matmul(&self.encoder_t)?)
    }

    /// latents: (B, Z) → vertices (B, V, 3), eq. 3.2.
    fn decode(&self, latents: &Tensor) -> Result<Tensor> {
        let (b, z) = latents.dims2()?;
        if z != self.latent_size() {
            return Err(invalid(
                "latents",
                format!(
                    "shape ({b}, {z}), the model expects (B, {})",
                    self.latent_size()
                ),
            ));
        }
        let x = latents
            .to_dtype(candle_core::DType::F32)?
            .matmul(&self.decoder_t)?
            .broadcast_add(&self.mean_t)?;
        Ok(x.reshape((b, self.template.vertex_count(), 3))?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshgnn_geometry::icosphere;
    use rand::rngs::StdRng;
    use rand::{Rng, SeedableRng};

    fn random_shapes(base: &TriMesh, count: usize, seed: u64) -> Vec<Vec<[f32; 3]>> {
        let mut rng = StdRng::seed_from_u64(seed);
        (0..count)
            .map(|_| {
                base.vertices()
                    .iter()
                    .map(|p| p.map(|c| c + rng.random_range(-0.2f32..0.2)))
                    .collect()
            })
            .collect()
    }

    fn batch(shapes: &[Vec<[f32; 3]>]) -> Tensor {
        let v = shapes[0].len();
        let flat: Vec<f32> = shapes.iter().flat_map(|s| flatten_points(s)).collect();
        Tensor::from_vec(flat, (shapes.len(), v, 3), &Device::Cpu).unwrap()
    }

    #[test]
    fn full_rank_reconstructs_training_data_exactly() {
        let t = icosphere(1);
        let shapes = random_shapes(&t, 9, 3);
        let pca = Pca::fit(&t, &shapes, 8).unwrap();
        let x = batch(&shapes);
        let rec = pca.decode(&pca.encode(&x).unwrap()).unwrap();
        let err = (rec - &x).unwrap().abs().unwrap().max_all().unwrap();
        assert!(err.to_scalar::<f32>().unwrap() <= 1e-4);
        // one component more than the rank is refused
        assert!(Pca::fit(&t, &shapes, 9).is_err());
        // whitened: training latents have unit variance per component
        let z: Vec<Vec<f32>> = pca.encode(&x).unwrap().to_vec2().unwrap();
        for k in 0..8 {
            let var: f64 = z.iter().map(|r| f64::from(r[k]).powi(2)).sum::<f64>() / 8.0;
            assert!((var - 1.0).abs() < 1e-3, "component {k}: {var}");
        }
    }

    #[test]
    fn finds_a_known_two_dimensional_subspace() {
        let t = icosphere(1);
        let v = t.vertex_count();
        let mut rng = StdRng::seed_from_u64(7);
        // two fixed random directions in 3V space
        let dirs: Vec<Vec<f32>> = (0..2)
            .map(|_| (0..3 * v).map(|_| rng.random_range(-1.0f32..1.0)).collect())
            .collect();
        let shapes: Vec<Vec<[f32; 3]>> = (0..20)
            .map(|_| {
                let (a, b) = (
                    rng.random_range(-3.0f32..3.0),
                    rng.random_range(-1.0f32..1.0),
                );
                let flat: Vec<f32> = flatten_points(t.vertices())
                    .iter()
                    .enumerate()
                    .map(|(d, &c)| c + a * dirs[0][d] + b * dirs[1][d])
                    .collect();
                unflatten_points(&flat)
            })
            .collect();
        let pca = Pca::fit(&t, &shapes, 2).unwrap();
        let ratio = pca.explained_variance_ratio();
        assert!(ratio[1] > 1.0 - 1e-6, "{ratio:?}");
        assert!(ratio[0] < 0.999);
        // a third component has (numerically) zero variance: refused
        assert!(Pca::fit(&t, &shapes, 3).is_err());
        let u0: Vec<f32> = flatten_points(&pca.component(0).unwrap());
        let u1: Vec<f32> = flatten_points(&pca.component(1).unwrap());
        let d = |a: &[f32], b: &[f32]| a.iter().zip(b).map(|(x, y)| f64::from(x * y)).sum::<f64>();
        assert!((d(&u0, &u0) - 1.0).abs() < 1e-5);
        assert!((d(&u1, &u1) - 1.0).abs() < 1e-5);
        assert!(d(&u0, &u1).abs() < 1e-5);
        // the components span the two directions: each direction is reproduced
        for dir in &dirs {
            let n = d(dir, dir).sqrt();
            let c0 = d(dir, &u0) / n;
            let c1 = d(dir, &u1) / n;
            assert!((c0 * c0 + c1 * c1 - 1.0).abs() < 1e-4);
        }
        assert!(pca.component(2).is_none());
    }

    #[test]
    fn checkpoint_round_trip_and_rejections() {
        let t = icosphere(1);
        let shapes = random_shapes(&t, 6, 1);
        let pca = Pca::fit(&t, &shapes, 3).unwrap();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("pca.safetensors");
        pca.save(&path).unwrap();
        let back = Pca::load(&path).unwrap();
        assert_eq!(back.latent_size(), 3);
        assert_eq!(back.variances(), pca.variances());
        assert_eq!(back.template().triangles(), t.triangles());
        assert_eq!(
            back.project(&shapes[2]).unwrap(),
            pca.project(&shapes[2]).unwrap()
        );
        std::fs::write(&path, b"garbage").unwrap();
        let err = Pca::load(&path).unwrap_err().to_string();
        assert!(err.contains("pca.safetensors"), "{err}");
        assert!(pca.project(&shapes[0][..5]).is_err());
        let bad = Tensor::zeros((1, 2), candle_core::DType::F32, &Device::Cpu).unwrap();
        assert!(pca.decode(&bad).is_err());
    }

    #[test]
    fn fit_is_thread_count_independent() {
        let t = icosphere(1);
        let shapes = random_shapes(&t, 12, 5);
        let a = Pca::fit(&t, &shapes, 4).unwrap();
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let b = pool.install(|| Pca::fit(&t, &shapes, 4).unwrap());
        assert_eq!(a.components, b.components);
        assert_eq!(a.variances, b.variances);
    }
}
