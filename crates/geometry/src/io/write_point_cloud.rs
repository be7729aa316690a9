//! [`write_point_cloud`]: a [`PointCloud`] to a file, atomically.

use super::atomic_write::atomic_write;
use super::format::MeshFormat;
use super::mesh_data::MeshData;
use super::write_mesh::encode;
use crate::PointCloud;
use crate::error::Result;
use std::path::Path;

/// Writes `cloud` (points and normals) to `path` by extension: `.ply` (binary little
/// endian, a `vertex` element only), `.xyz`, `.obj` (`v`/`vn` records), `.off` or `.glb`.
///
/// ```
/// use meshgnn_geometry::{read_point_cloud, write_point_cloud, PointCloud};
/// # let dir = tempfile::tempdir()?;
/// let path = dir.path().join("cloud.xyz");
/// let cloud = PointCloud::new(vec![[0.5, 1.0, -2.0]])?.with_normals(vec![[0.0, 1.0, 0.0]])?;
/// write_point_cloud(&path, &cloud)?;
/// assert_eq!(read_point_cloud(&path)?, cloud);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn write_point_cloud(path: impl AsRef<Path>, cloud: &PointCloud) -> Result<()> {
    let path = path.as_ref();
    let format = MeshFormat::from_path(path)?;
    let bytes = encode(&MeshData::from_point_cloud(cloud), format, path)?;
    atomic_write(path, &bytes)
}
