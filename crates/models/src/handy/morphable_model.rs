//! The interface every registered-shape model shares, so evaluation, sampling and fitting
//! work the same for the spiral autoencoder and the PCA baseline (thesis ch. 3.4).

use candle_core::Tensor;
use meshgnn_geometry::TriMesh;

use crate::Result;

/// A generative model of shapes registered to one template: latent codes in, vertex positions
/// out, in the units of the training data (millimetres for the synthetic hands).
pub trait MorphableModel {
    /// Size Z of a latent code.
    fn latent_size(&self) -> usize;

    /// The template whose topology (faces) every encoded or decoded shape shares.
    fn template(&self) -> &TriMesh;

    /// vertices: (B, V, 3) → latent codes (B, Z).
    fn encode(&self, vertices: &Tensor) -> Result<Tensor>;

    /// latents: (B, Z) → vertices (B, V, 3).
    fn decode(&self, latents: &Tensor) -> Result<Tensor>;
}
