//! The default weights of the point simplifier, trained on the synthetic shape set's training
//! families (boxes, gears, creatures-a), the epoch with the lowest held-out loss, embedded in the
//! binary; the command, seed, time and losses are in `docs/pcsimplify_model.md`.

use std::path::Path;

use super::PointSimplifier;
use crate::Result;

/// The bundled checkpoint (safetensors, weights only), `crates/models/weights/point_simplifier.safetensors`.
pub const PRETRAINED_WEIGHTS: &[u8] = include_bytes!("../../weights/point_simplifier.safetensors");

impl PointSimplifier {
    /// The model with the bundled default weights, ready for [`PointSimplifier::simplify`].
    ///
    /// ```
    /// use meshgnn_models::point_simplifier::PointSimplifier;
    /// let model = PointSimplifier::pretrained()?;
    /// assert_eq!(model.config().hidden, 64);
    /// # Ok::<(), meshgnn_models::Error>(())
    /// ```
    pub fn pretrained() -> Result<Self> {
        Self::from_safetensors(
            PRETRAINED_WEIGHTS,
            Path::new("<embedded>/point_simplifier.safetensors"),
        )
    }
}
