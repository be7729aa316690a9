//! Registered meshes as one tensor: the input format of the spiral autoencoder.

use candle_core::{Device, Tensor};

use crate::Result;
use crate::handy::spiral::vertex_normalization::check_meshes;

/// Stacks `meshes: #B × (#V×3)` (same vertex count, finite coordinates) into `(B, V, 3)`.
///
/// ```
/// use candle_core::Device;
/// use meshgnn_models::spiral::mesh_batch;
/// let t = mesh_batch(&[vec![[1.0, 2.0, 3.0]], vec![[4.0, 5.0, 6.0]]], &Device::Cpu)?;
/// assert_eq!(t.dims(), &[2, 1, 3]);
/// assert!(mesh_batch(&[vec![[1.0, 2.0, 3.0]], vec![]], &Device::Cpu).is_err());
/// # Ok::<(), meshgnn_models::Error>(())
/// ```
pub fn mesh_batch(meshes: &[Vec<[f32; 3]>], device: &Device) -> Result<Tensor> {
    let v = check_meshes("meshes", meshes, None)?;
    let flat: Vec<f32> = meshes.iter().flatten().flatten().copied().collect();
    Ok(Tensor::from_vec(flat, (meshes.len(), v, 3), device)?)
}
