//! # meshgnn
//!
//! Graph neural networks for 3D shapes, and the classical operators they stand on. This facade
//! re-exports every workspace crate, so one dependency brings them all; each is usable alone.
//!
//! | module | crate | what |
//! |---|---|---|
//! | [`geometry`] | `meshgnn-geometry` | meshes, point clouds, I/O, normals, curvature, Laplacians, the spatial index |
//! | [`graph`] | `meshgnn-graph` | sparse matrices, k-NN, spirals, QEM, FPS, weighted sampling |
//! | [`losses`] | `meshgnn-losses` | differentiable losses (candle) and evaluation metrics |
//! | [`data`] | `meshgnn-data` | synthetic hands, faces and simplification shapes, folder datasets |
//! | [`models`] | `meshgnn-models` | the spiral autoencoder (Handy++), the point-cloud simplifier, training, checkpoints, bundled weights |
//!
//! ```
//! // One path per crate: a mesh from geometry, decimated by graph's QEM.
//! let sphere = meshgnn::geometry::icosphere(2);
//! let options = meshgnn::graph::DecimationOptions {
//!     target: meshgnn::graph::Target::Ratio(0.5),
//!     ..Default::default()
//! };
//! let half = meshgnn::graph::decimate(&sphere, &options)?;
//! assert!(half.mesh.face_count() <= sphere.face_count() / 2 + 1);
//! # Ok::<(), meshgnn::graph::Error>(())
//! ```

pub use meshgnn_data as data;
pub use meshgnn_geometry as geometry;
pub use meshgnn_graph as graph;
pub use meshgnn_losses as losses;
pub use meshgnn_models as models;
