//! # meshgnn
//!
//! Graph neural networks for 3D shapes, and the classical operators they stand on. This facade
//! re-exports the workspace crates so one dependency brings them all; each is usable alone.
//!
//! | module | crate | what |
//! |---|---|---|
//! | [`geometry`] | `meshgnn-geometry` | meshes, point clouds, I/O, normals, curvature, Laplacians |

pub use meshgnn_geometry as geometry;
