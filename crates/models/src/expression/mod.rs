//! The 4D expression generator of thesis ch. 4 (Potamias et al., ECCV 2020): from a per-frame
//! expression label signal and a subject's neutral face, the animated face (eq. 4.1), with
//! the PCA blendshape baseline it is measured against (Table 4.2), its data, training
//! (eq. 4.2) and evaluation. docs/expression_model.md has the figures.

mod blendshape_decoder;
mod expression_evaluation;
mod expression_generator;
mod expression_model;
mod expression_sequences;
mod expression_training;
mod label_encoder;

pub use blendshape_decoder::{BlendshapeDecoder, Blendshapes, MAX_BLENDSHAPE_FRAMES};
pub use expression_evaluation::{ExpressionEvaluation, evaluate_expressions};
pub use expression_generator::{
    DecoderKind, ExpressionGenerator, ExpressionGeneratorConfig, RESIDUAL_PREFIX,
};
pub use expression_model::{EXPRESSION_MODEL_NAME, ExpressionModel};
pub use expression_sequences::{ExpressionSequence, ExpressionSequences};
pub use expression_training::{ExpressionTraining, expression_loss};
pub use label_encoder::{LABEL_CHANNELS, LabelEncoder};
