//! # meshgnn-geometry
//!
//! Triangle meshes and point clouds for the rest of meshgnn: the [`TriMesh`] and
//! [`PointCloud`] types, reading and writing OBJ, PLY, OFF, glTF/GLB and XYZ, and the
//! geometric operators the thesis builds on (normals, curvature of eq. 5.1-5.3, graph and
//! cotangent Laplacians of eq. 2.13-2.14, Laplacian eigenvectors, surface sampling,
//! normalisation and validity checks). One operation per module, named after what it computes.
//!
//! # Conventions
//! - Positions are stored as `[f32; 3]`; numerically sensitive code accumulates in `f64`.
//! - Triangles are counter-clockwise seen from outside; indices are `u32`.
//! - Laplacians are positive semi-definite: `L = D − W`.
//! - Every fallible function returns [`Error`], which names the file, element and problem.
#![cfg_attr(not(test), warn(clippy::unwrap_used, clippy::expect_used))]

mod error;
mod point_cloud;
mod primitives;
mod tri_mesh;

pub use error::{Error, Result};
pub use point_cloud::PointCloud;
pub use primitives::{grid_plane, icosphere, subdivided_cube};
pub use tri_mesh::TriMesh;
