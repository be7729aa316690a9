//! "Handy++", the spiral-convolution mesh autoencoder of thesis ch. 3.3.4 (Table 3.1), its
//! layers (spiral convolution eq. 2.28-2.29, pooling and unpooling), template tensors,
//! normalisation, self-contained model checkpoints and what it trains
//! ([`SpiralTraining`], run by [`crate::training::train`]).

mod linear_skip;
mod mesh_batch;
mod pool;
mod seeded_initialization;
mod spiral_autoencoder;
mod spiral_conv;
mod spiral_decoder;
mod spiral_morphable_model;
mod spiral_training;
mod template_tensors;
#[cfg(test)]
pub(crate) mod test_fixtures;
mod unpool;
mod vertex_normalization;

pub use linear_skip::{LINEAR_SKIP_PREFIX, LinearSkip};
pub use mesh_batch::mesh_batch;
pub use pool::Pool;
pub use seeded_initialization::seeded_initialization;
pub use spiral_autoencoder::{Activation, SpiralAutoencoder, SpiralAutoencoderConfig};
pub use spiral_conv::{SpiralConv, SpiralConvConfig, SpiralPadding};
pub use spiral_decoder::SpiralDecoder;
pub use spiral_morphable_model::{SPIRAL_MODEL_NAME, SpiralMorphableModel};
pub use spiral_training::SpiralTraining;
pub use template_tensors::TemplateTensors;
pub use unpool::Unpool;
pub use vertex_normalization::VertexNormalization;
