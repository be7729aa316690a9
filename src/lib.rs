//! # meshgnn
//!
//! Graph neural networks for 3D shapes, and the classical operators they stand on. This facade
//! re-exports the workspace crates so one dependency brings them all; each is usable alone.
//!
//! | module | crate | what |
//! |---|---|---|
//! | [`geometry`] | `meshgnn-geometry` | meshes, point clouds, I/O, normals, curvature, Laplacians |
//! | [`graph`] | `meshgnn-graph` | sparse matrices, k-NN, spirals, QEM, FPS, weighted sampling |
//! | [`losses`] | `meshgnn-losses` | differentiable losses (candle) and evaluation metrics |

pub use meshgnn_geometry as geometry;
pub use meshgnn_graph as graph;
pub use meshgnn_losses as losses;
