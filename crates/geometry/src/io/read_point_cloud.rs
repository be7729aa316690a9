//! [`read_point_cloud`]: the points (and normals) of any supported file.

use super::format::MeshFormat;
use super::format_error::MEMORY;
use super::read_mesh::{parse_bytes, read_file};
use crate::PointCloud;
use crate::error::Result;
use std::path::Path;

/// Reads a point cloud: PLY with or without faces, OBJ `v` records (with `vn` when there is
/// one per vertex), XYZ, and the vertices of any mesh format (glTF point primitives
/// included). Faces, when present, are ignored.
///
/// ```
/// # let dir = tempfile::tempdir()?;
/// let path = dir.path().join("scan.xyz");
/// std::fs::write(&path, "# two points\n0 0 0\n1 2 3\n")?;
/// let cloud = meshgnn_geometry::read_point_cloud(&path)?;
/// assert_eq!(cloud.points(), &[[0.0, 0.0, 0.0], [1.0, 2.0, 3.0]]);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn read_point_cloud(path: impl AsRef<Path>) -> Result<PointCloud> {
    let path = path.as_ref();
    let format = MeshFormat::from_path(path)?;
    let bytes = read_file(path)?;
    parse_bytes(&bytes, format, path, path.parent(), true)?.into_point_cloud(path)
}

/// [`read_point_cloud`] from bytes in memory; errors name the source `<memory>`.
///
/// ```
/// use meshgnn_geometry::{read_point_cloud_bytes, MeshFormat};
/// let cloud = read_point_cloud_bytes(b"1 2 3 0 0 1\n", MeshFormat::Xyz)?;
/// assert_eq!(cloud.normals(), Some(&[[0.0, 0.0, 1.0]][..]));
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn read_point_cloud_bytes(bytes: &[u8], format: MeshFormat) -> Result<PointCloud> {
    let path = Path::new(MEMORY);
    parse_bytes(bytes, format, path, None, true)?.into_point_cloud(path)
}
