//! The blendshape baseline of thesis ch. 4.4.2: "PCA was applied to the motion deformations
//! [frame − the subject's neutral face] to reduce each expression to a latent vector ... the
//! same latent size was used for both the baseline and the proposed method". The LSTM's
//! latent `z_t` drives the blendshape weights through one linear layer; the blendshapes are
//! the principal components of the training displacements (eq. 3.2), fixed, not trained.
//!
//! # Conventions
//! - Displacements are `#V×3` in data units (mm); the decoder maps `(N, H)` latents to
//!   `(N, V, 3)` displacements `d = μ + Σ_k w_k σ_k u_k`, `w = W z + b` (parameters
//!   `coefficients.{weight,bias}`), so `w` is in standard deviations of each component.

use candle_core::{Device, Tensor};
use candle_nn::{Linear, Module, VarBuilder};
use meshgnn_geometry::TriMesh;

use crate::{Error, MorphableModel, Pca, Result};

/// Most training displacements the PCA is fitted on (a Gram matrix of this size); more are
/// subsampled evenly.
pub const MAX_BLENDSHAPE_FRAMES: usize = 3000;

/// The blendshapes: mean displacement `(1, 3V)` and components scaled by their standard
/// deviations `(K, 3V)`.
#[derive(Debug, Clone)]
pub struct Blendshapes {
    mean: Tensor,
    basis: Tensor,
}

impl Blendshapes {
    /// Eq. 3.2 on `displacements: #N × (#V×3)` (at most [`MAX_BLENDSHAPE_FRAMES`] of them, taken
    /// evenly), keeping `components` of them; when the displacements have fewer components of
    /// non-zero variance, the rest are zero (they add nothing, the latent size stays).
    ///
    /// ```
    /// use meshgnn_geometry::TriMesh;
    /// use meshgnn_models::expression::Blendshapes;
    /// let t = TriMesh::new(vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], vec![[0, 1, 2]])?;
    /// // the first vertex moves along x by 0, 1, 2
    /// let d: Vec<Vec<[f32; 3]>> = (0..3).map(|i| vec![[i as f32, 0.0, 0.0], [0.0; 3], [0.0; 3]]).collect();
    /// let b = Blendshapes::fit(&t, &d, 1)?;
    /// assert_eq!(b.components(), 1);
    /// assert_eq!(b.mean().flatten_all()?.to_vec1::<f32>()?[0], 1.0);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn fit(
        template: &TriMesh,
        displacements: &[Vec<[f32; 3]>],
        components: usize,
    ) -> Result<Self> {
        let stride = displacements.len().div_ceil(MAX_BLENDSHAPE_FRAMES).max(1);
        let kept: Vec<Vec<[f32; 3]>> = displacements.iter().step_by(stride).cloned().collect();
        let pca = Pca::fit_at_most(template, &kept, components)?;
        let flat = |v: Vec<[f32; 3]>| v.into_iter().flatten().collect::<Vec<f32>>();
        let dim = 3 * template.vertex_count();
        let mut basis = Vec::with_capacity(components * dim);
        for (k, variance) in pca.variances().iter().take(pca.latent_size()).enumerate() {
            let u = pca.component(k).ok_or_else(|| Error::Invalid {
                what: "blendshapes".into(),
                reason: format!("component {k} missing"),
            })?;
            let sigma = variance.sqrt() as f32;
            basis.extend(flat(u).into_iter().map(|x| x * sigma));
        }
        basis.resize(components * dim, 0.0);
        Self::from_tensors(
            Tensor::from_vec(flat(pca.mean_shape()), (1, dim), &Device::Cpu)?,
            Tensor::from_vec(basis, (components, dim), &Device::Cpu)?,
        )
    }

    /// Blendshapes from their tensors (`mean: (1, 3V)`, `basis: (K, 3V)`), as stored in a model
    /// file.
    pub fn from_tensors(mean: Tensor, basis: Tensor) -> Result<Self> {
        match (mean.dims(), basis.dims()) {
            ([1, d], [k, e]) if d == e && *k > 0 && *d > 0 && d % 3 == 0 => {
                Ok(Self { mean, basis })
            }
            (m, b) => Err(Error::Invalid {
                what: "blendshapes".into(),
                reason: format!("mean {m:?} and basis {b:?}, expected (1, 3V) and (K, 3V)"),
            }),
        }
    }

    /// Number of blendshapes `K`.
    pub fn components(&self) -> usize {
        self.basis.dims()[0]
    }

    /// Vertex count `V`.
    pub fn vertex_count(&self) -> usize {
        self.mean.dims()[1] / 3
    }

    /// The mean displacement `(1, 3V)`.
    pub fn mean(&self) -> &Tensor {
        &self.mean
    }

    /// The components scaled by their standard deviations, `(K, 3V)`.
    pub fn basis(&self) -> &Tensor {
        &self.basis
    }

    /// The same blendshapes on `device`.
    pub fn to_device(&self, device: &Device) -> Result<Self> {
        Ok(Self {
            mean: self.mean.to_device(device)?,
            basis: self.basis.to_device(device)?,
        })
    }
}

/// Latents `(N, H)` → displacements `(N, V, 3)` through fixed blendshapes.
#[derive(Debug, Clone)]
pub struct BlendshapeDecoder {
    coefficients: Linear,
    blendshapes: Blendshapes,
}

impl BlendshapeDecoder {
    /// The linear layer `coefficients` (`H → K`) from `vb` over `blendshapes`.
    pub fn new(vb: VarBuilder, latent_size: usize, blendshapes: Blendshapes) -> Result<Self> {
        Ok(Self {
            coefficients: candle_nn::linear(
                latent_size,
                blendshapes.components(),
                vb.pp("coefficients"),
            )?,
            blendshapes,
        })
    }

    /// `z: (N, H)` → `(N, V, 3)` displacements in data units.
    pub fn forward(&self, z: &Tensor) -> Result<Tensor> {
        let w = self.coefficients.forward(z)?;
        let d = w
            .matmul(&self.blendshapes.basis)?
            .broadcast_add(&self.blendshapes.mean)?;
        Ok(d.reshape((z.dim(0)?, self.blendshapes.vertex_count(), 3))?)
    }
}
