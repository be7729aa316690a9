//! The one training loop of every model in this crate: a model says what it trains through
//! [`Trainable`] (its parameters, the loss of a batch, a validation figure, its checkpoint) and
//! [`train`] runs it — seeded data order, Adam with an exponential learning-rate decay per
//! epoch, a progress callback after every step and epoch, validation on held-out data with the
//! best epoch kept, and a checkpoint after every epoch from which a resumed run continues
//! bit-identically.

mod trainable;
mod training_loop;

pub use trainable::{BatchLoss, StepContext, Trainable, batch_mean};
pub use training_loop::{TrainingConfig, TrainingProgress, TrainingRun, epoch_order, train};
