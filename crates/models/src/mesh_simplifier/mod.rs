//! The neural mesh simplifier of thesis ch. 6 (a learnable point sampler, an edge predictor
//! and a face classifier, trained end to end). This module holds the parts built so far: the
//! DevConv layer (eq. 6.1) on fixed-width neighbour slots and the point sampler (ch. 6.3.1).

mod dev_conv;
mod neighbour_slots;
mod point_sampler;

pub use dev_conv::{DevConv, DevConvConfig};
pub use neighbour_slots::NeighbourSlots;
pub use point_sampler::{PointSampler, PointSamplerConfig, SampledPoints};
