//! # meshgnn-graph
//!
//! The classical graph operators every meshgnn model stands on, usable on their own: sparse
//! matrices, k-NN and mesh-adjacency graphs, k-rings and spiral sequences (thesis eq.
//! 2.27-2.28), QEM edge-collapse decimation (Garland & Heckbert 1997) with the pooling
//! matrices of a mesh hierarchy, farthest point sampling, and weighted sampling without
//! replacement. One operator per module, named after what it computes.
#![cfg_attr(not(test), warn(clippy::unwrap_used, clippy::expect_used))]

mod error;

pub use error::{Error, Result};
