//! [`write_mesh`] and [`write_ply`]: a [`TriMesh`] to a file, atomically.

use super::atomic_write::atomic_write;
use super::format::MeshFormat;
use super::mesh_data::MeshData;
use super::ply::PlyEncoding;
use super::{gltf, obj, off, ply, xyz};
use crate::TriMesh;
use crate::error::{Error, Result};
use std::path::Path;

/// Encodes mesh content in `format` (PLY as binary little endian).
pub(crate) fn encode(mesh: &MeshData, format: MeshFormat, path: &Path) -> Result<Vec<u8>> {
    Ok(match format {
        MeshFormat::Obj => obj::write_obj_bytes(mesh),
        MeshFormat::Ply => ply::write_ply_bytes(mesh, PlyEncoding::BinaryLittleEndian),
        MeshFormat::Off => off::write_off_bytes(mesh),
        MeshFormat::Glb => {
            gltf::write_glb_bytes(mesh).map_err(|message| Error::InvalidParameter {
                name: "mesh",
                message: format!("{}: {message}", path.display()),
            })?
        }
        MeshFormat::Xyz => xyz::write_xyz_bytes(mesh),
        MeshFormat::Gltf => {
            return Err(Error::InvalidParameter {
                name: "path",
                message: format!(
                    "{}: writing JSON .gltf is not supported, use .glb",
                    path.display()
                ),
            });
        }
    })
}

/// Writes `mesh` to `path` in the format its extension names: `.ply` (binary little endian),
/// `.obj`, `.off`, `.glb`, or `.xyz` (vertices and normals only). Normals, uvs and colours
/// are written where the format holds them. The write is atomic (temporary file + rename).
///
/// ```
/// use meshgnn_geometry::{icosphere, read_mesh, write_mesh};
/// # let dir = tempfile::tempdir()?;
/// let path = dir.path().join("sphere.ply");
/// let sphere = icosphere(1);
/// write_mesh(&path, &sphere)?;
/// assert_eq!(read_mesh(&path)?, sphere);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn write_mesh(path: impl AsRef<Path>, mesh: &TriMesh) -> Result<()> {
    let path = path.as_ref();
    let format = MeshFormat::from_path(path)?;
    let bytes = encode(&MeshData::from_mesh(mesh), format, path)?;
    atomic_write(path, &bytes)
}

/// Writes `mesh` as PLY with the chosen encoding, whatever `path`'s extension.
///
/// ```
/// use meshgnn_geometry::{grid_plane, read_mesh, write_ply, PlyEncoding};
/// # let dir = tempfile::tempdir()?;
/// let path = dir.path().join("plane.ply");
/// let plane = grid_plane(3, 2);
/// write_ply(&path, &plane, PlyEncoding::Ascii)?;
/// assert!(std::fs::read_to_string(&path)?.starts_with("ply\nformat ascii 1.0\n"));
/// assert_eq!(read_mesh(&path)?, plane);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn write_ply(path: impl AsRef<Path>, mesh: &TriMesh, encoding: PlyEncoding) -> Result<()> {
    let path = path.as_ref();
    atomic_write(
        path,
        &ply::write_ply_bytes(&MeshData::from_mesh(mesh), encoding),
    )
}
