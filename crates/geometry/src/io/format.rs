//! [`MeshFormat`]: which file format a path names, from its extension.

use crate::error::{Error, Result};
use std::path::Path;

/// A file format this crate reads (and, except glTF JSON, writes).
///
/// Chosen by the extension, case-insensitively: `.obj .ply .off .gltf .glb .xyz`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum MeshFormat {
    /// Wavefront OBJ (ASCII): `v`, `vt`, `vn`, `f` records.
    Obj,
    /// Stanford PLY, ASCII or binary (either endianness).
    Ply,
    /// Object File Format (OFF, COFF, NOFF), ASCII.
    Off,
    /// glTF 2.0 JSON with embedded (data URI) or external `.bin` buffers.
    Gltf,
    /// glTF 2.0 binary container (GLB).
    Glb,
    /// Plain ASCII points, one `x y z [nx ny nz]` per line.
    Xyz,
}

impl MeshFormat {
    /// The format named by `path`'s extension; [`Error::UnsupportedFormat`] when unknown.
    ///
    /// ```
    /// use meshgnn_geometry::MeshFormat;
    /// assert_eq!(MeshFormat::from_path("scan.PLY")?, MeshFormat::Ply);
    /// assert!(MeshFormat::from_path("scan.stl").is_err());
    /// # Ok::<(), meshgnn_geometry::Error>(())
    /// ```
    pub fn from_path(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let extension = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .unwrap_or_default();
        match extension.as_str() {
            "obj" => Ok(Self::Obj),
            "ply" => Ok(Self::Ply),
            "off" => Ok(Self::Off),
            "gltf" => Ok(Self::Gltf),
            "glb" => Ok(Self::Glb),
            "xyz" => Ok(Self::Xyz),
            _ => Err(Error::UnsupportedFormat {
                path: path.to_path_buf(),
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_extension_in_any_case() {
        for (name, format) in [
            ("a.obj", MeshFormat::Obj),
            ("dir.x/a.Ply", MeshFormat::Ply),
            ("a.OFF", MeshFormat::Off),
            ("a.gltf", MeshFormat::Gltf),
            ("a.GlB", MeshFormat::Glb),
            ("a.xyz", MeshFormat::Xyz),
        ] {
            assert_eq!(MeshFormat::from_path(name).unwrap(), format, "{name}");
        }
    }

    #[test]
    fn unknown_or_missing_extension_is_unsupported() {
        for name in ["a.stl", "a", "ply", "a.ply.gz"] {
            assert!(matches!(
                MeshFormat::from_path(name),
                Err(Error::UnsupportedFormat { .. })
            ));
        }
    }
}
