//! [`read_mesh`] and [`read_mesh_bytes`]: any supported file into a validated [`TriMesh`].

use super::format::MeshFormat;
use super::format_error::MEMORY;
use super::mesh_data::MeshData;
use super::{gltf, obj, off, ply, xyz};
use crate::TriMesh;
use crate::error::{Error, Result};
use std::path::Path;

/// Parses `bytes` of `format`; `path` names the source in errors, `base` is where external
/// glTF buffers live. Non-triangle glTF primitives are accepted only with `points_ok`.
pub(crate) fn parse_bytes(
    bytes: &[u8],
    format: MeshFormat,
    path: &Path,
    base: Option<&Path>,
    points_ok: bool,
) -> Result<MeshData> {
    match format {
        MeshFormat::Obj => obj::read_obj(bytes, path),
        MeshFormat::Ply => ply::read_ply(bytes, path),
        MeshFormat::Off => off::read_off(bytes, path),
        MeshFormat::Gltf | MeshFormat::Glb => gltf::read_gltf(bytes, path, base, points_ok),
        MeshFormat::Xyz => xyz::read_xyz(bytes, path),
    }
}

/// Reads the whole file at `path` (one `std::fs::read`).
pub(crate) fn read_file(path: &Path) -> Result<Vec<u8>> {
    std::fs::read(path).map_err(|source| Error::Io {
        path: path.to_path_buf(),
        error: source,
    })
}

/// Reads a triangle mesh from an `.obj`, `.ply`, `.off`, `.gltf`, `.glb` (or `.xyz`, which
/// gives a mesh without faces), chosen by extension. Polygons are fan-triangulated; per-vertex
/// normals, uvs and colours are kept when the file has them.
///
/// Errors: [`Error::Io`] when the file cannot be read, [`Error::UnsupportedFormat`] for an
/// unknown extension, [`Error::Format`] naming the file and element for malformed content
/// (bad header, truncated data, out-of-range index, NaN coordinate, non-triangle primitive).
///
/// ```
/// # let dir = tempfile::tempdir()?;
/// let path = dir.path().join("quad.obj");
/// std::fs::write(&path, "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n")?;
/// let mesh = meshgnn_geometry::read_mesh(&path)?;
/// assert_eq!(mesh.triangles(), &[[0, 1, 2], [0, 2, 3]]);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn read_mesh(path: impl AsRef<Path>) -> Result<TriMesh> {
    let path = path.as_ref();
    let format = MeshFormat::from_path(path)?;
    let bytes = read_file(path)?;
    parse_bytes(&bytes, format, path, path.parent(), false)?.into_mesh(path)
}

/// Parses a mesh from bytes already in memory (tests, fuzzing, network input); errors name
/// the source `<memory>`. A `.gltf` whose buffers are external files cannot be read this way
/// (there is no directory to find them in); GLB and data-URI glTF can.
///
/// ```
/// use meshgnn_geometry::{read_mesh_bytes, MeshFormat};
/// let off = b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
/// let mesh = read_mesh_bytes(off, MeshFormat::Off)?;
/// assert_eq!((mesh.vertex_count(), mesh.face_count()), (3, 1));
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn read_mesh_bytes(bytes: &[u8], format: MeshFormat) -> Result<TriMesh> {
    let path = Path::new(MEMORY);
    parse_bytes(bytes, format, path, None, false)?.into_mesh(path)
}
