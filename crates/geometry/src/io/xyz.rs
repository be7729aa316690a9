//! XYZ point files: one `x y z` or `x y z nx ny nz` per line, `#` starts a comment.

use super::ascii_scan::{fields, lines, parse_f32};
use super::format_error::format_error;
use super::mesh_data::MeshData;
use crate::error::Result;
use std::path::Path;

/// Reads an XYZ file's bytes; every line must have the same layout (3 or 6 numbers).
pub(crate) fn read_xyz(bytes: &[u8], path: &Path) -> Result<MeshData> {
    let mut points: Vec<[f32; 3]> = Vec::with_capacity(bytes.len() / 32);
    let mut normals: Vec<[f32; 3]> = Vec::new();
    let mut with_normals = None;
    for (number, line) in lines(bytes) {
        let content = line.split(|&b| b == b'#').next().unwrap_or_default();
        let element = || format!("point {} (line {number})", points.len());
        let mut values = [0f32; 6];
        let mut n = 0usize;
        for word in fields(content) {
            let slot = values
                .get_mut(n)
                .ok_or_else(|| format_error(path, element(), "more than 6 values"))?;
            *slot = parse_f32(word).ok_or_else(|| {
                format_error(
                    path,
                    element(),
                    format!("`{}` is not a number", String::from_utf8_lossy(word)),
                )
            })?;
            n += 1;
        }
        match (n, with_normals) {
            (0, _) => continue,
            (3, None | Some(false)) => with_normals = Some(false),
            (6, None | Some(true)) => with_normals = Some(true),
            (3 | 6, Some(expected)) => {
                return Err(format_error(
                    path,
                    element(),
                    format!(
                        "has {n} values but earlier points have {}",
                        if expected { 6 } else { 3 }
                    ),
                ));
            }
            _ => {
                return Err(format_error(
                    path,
                    element(),
                    format!("has {n} values, expected 3 or 6"),
                ));
            }
        }
        points.push([values[0], values[1], values[2]]);
        if n == 6 {
            normals.push([values[3], values[4], values[5]]);
        }
    }
    Ok(MeshData {
        vertices: points,
        normals: (with_normals == Some(true)).then_some(normals),
        ..MeshData::default()
    })
}

/// Encodes points (and normals when present) as XYZ text.
pub(crate) fn write_xyz_bytes(mesh: &MeshData) -> Vec<u8> {
    use std::fmt::Write;
    let mut text = String::with_capacity(mesh.vertices.len() * 40);
    for (i, p) in mesh.vertices.iter().enumerate() {
        let _ = write!(text, "{} {} {}", p[0], p[1], p[2]);
        if let Some(n) = mesh.normals.as_ref().and_then(|n| n.get(i)) {
            let _ = write!(text, " {} {} {}", n[0], n[1], n[2]);
        }
        text.push('\n');
    }
    text.into_bytes()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Error;

    #[test]
    fn comments_blank_lines_and_normals() {
        let text = b"# scan\n1 2 3 0 0 1\n\n  4 5 6   1 0 0 # trailing\n";
        let cloud = read_xyz(text, Path::new("t.xyz")).unwrap();
        assert_eq!(cloud.vertices, vec![[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]);
        assert_eq!(cloud.normals, Some(vec![[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]));
    }

    #[test]
    fn inconsistent_or_malformed_lines_name_the_point() {
        for (text, element) in [
            (&b"1 2 3\n1 2 3 0 0 1\n"[..], "point 1 (line 2)"),
            (b"1 2\n", "point 0 (line 1)"),
            (b"0 0 0\n\n1 2 z\n", "point 1 (line 3)"),
            (b"1 2 3 4 5 6 7\n", "point 0 (line 1)"),
        ] {
            match read_xyz(text, Path::new("t.xyz")) {
                Err(Error::Format { element: e, .. }) => assert_eq!(e, element),
                other => panic!("expected an error, got {other:?}"),
            }
        }
    }
}
