//! The simplification shape set (thesis ch. 5.5 and 6.5): closed meshes from signed distance
//! functions, noisy-scan variants and LiDAR-like point clouds, with shape-family-disjoint
//! splits (the zero-shot claim of ch. 5 and 6).

mod lidar_scene;
mod marching_tetrahedra;
mod noisy_scan;
mod sdf;
mod shape_family;

pub use lidar_scene::{LidarConfig, lidar_scene};
pub use marching_tetrahedra::marching_tetrahedra;
pub use noisy_scan::{gaussian_noise, noisy_scan};
pub use shape_family::{ShapeFamily, shape_mesh};
