//! # meshgnn-losses
//!
//! The training losses and evaluation metrics of the thesis "Advances of Graph Neural
//! Networks for 3D shape learning and analysis": reconstruction and temporal coherence (ch. 4,
//! eq. 4.2), Chamfer, adaptive Chamfer and curvature preservation (ch. 5, eq. 5.6-5.9),
//! probabilistic Chamfer and surface distances, triangle collision, edge crossings and overlap
//! (ch. 6, eq. 6.8-6.14) as differentiable candle tensors; and the metrics CD, Hausdorff, NC,
//! CE, RE, SDM (ch. 5.4), NE, WA, LE (ch. 6.5) and per-vertex error, compactness,
//! generalisation and specificity (ch. 3.4) as plain Rust. `docs/losses.md` lists every
//! definition choice and unit.
//!
//! # Conventions
//! - Points are `[f32; 3]`; every metric accumulates in `f64`, in parallel with a fixed
//!   summation order, so results are identical for any thread count.
//! - Nearest neighbours come from `meshgnn_geometry::SpatialIndex`; in the losses they are computed outside
//!   the autograd graph and gathered with `index_select`, so losses are differentiable in the
//!   positions and probabilities (piecewise, as the correspondences are fixed).
//! - Every fallible function returns [`Error`], naming the input, element and problem.
#![cfg_attr(not(test), warn(clippy::unwrap_used, clippy::expect_used))]

mod deterministic_sum;
mod error;
#[cfg(feature = "candle")]
pub mod losses;
pub mod metrics;
mod morton_order;
mod point_index;
pub mod predicates;
mod validate;

pub use error::{Error, Result};
