//! Object File Format (OFF) reader and writer, with the `C` (colour), `N` (normal) and `ST`
//! (texture) prefixes of Geomview: `[ST][C][N]OFF`, then `#V #F [#E]`, `#V` vertex lines
//! `x y z [nx ny nz] [r g b [a]] [s t]`, and `#F` face lines `n i0 ... i(n-1) [colour]`.
//! Polygons are fan-triangulated; `#` starts a comment.

use super::ascii_scan::{fields, is_blank, lines, parse_f32, parse_i64};
use super::format_error::format_error;
use super::mesh_data::MeshData;
use crate::error::Result;
use std::path::Path;

/// Reads an OFF file's bytes; `path` is used in error messages only.
pub(crate) fn read_off(bytes: &[u8], path: &Path) -> Result<MeshData> {
    let mut content = lines(bytes)
        .map(|(n, line)| (n, line.split(|&b| b == b'#').next().unwrap_or_default()))
        .filter(|(_, line)| !is_blank(line));
    let (number, first) = content
        .next()
        .ok_or_else(|| format_error(path, "header", "empty file"))?;
    let mut words = fields(first);
    let keyword = words.next().unwrap_or_default();
    let prefix = keyword.strip_suffix(b"OFF").ok_or_else(|| {
        format_error(
            path,
            format!("header line {number}"),
            "must start with OFF, COFF, NOFF or STCNOFF",
        )
    })?;
    let texture = prefix.starts_with(b"ST");
    let rest = prefix.strip_prefix(b"ST").unwrap_or(prefix);
    let (color, normal) = match rest {
        b"" => (false, false),
        b"C" => (true, false),
        b"N" => (false, true),
        b"CN" | b"NC" => (true, true),
        _ => {
            return Err(format_error(
                path,
                format!("header line {number}"),
                format!("unknown keyword `{}`", String::from_utf8_lossy(keyword)),
            ));
        }
    };
    // Counts follow on the same line or the next content line.
    let mut counts: Vec<i64> = words
        .map(parse_i64)
        .collect::<Option<_>>()
        .unwrap_or_default();
    let mut count_line = number;
    if counts.is_empty() {
        let (n, line) = content
            .next()
            .ok_or_else(|| format_error(path, "header", "missing vertex and face counts"))?;
        count_line = n;
        counts = fields(line)
            .map(parse_i64)
            .collect::<Option<_>>()
            .unwrap_or_default();
    }
    let (Some(&v), Some(&f)) = (counts.first(), counts.get(1)) else {
        return Err(format_error(
            path,
            format!("header line {count_line}"),
            "expected `#vertices #faces [#edges]`",
        ));
    };
    let (Ok(vertex_count), Ok(face_count)) = (usize::try_from(v), usize::try_from(f)) else {
        return Err(format_error(
            path,
            format!("header line {count_line}"),
            "negative count",
        ));
    };
    // Each line takes at least 2 bytes: cap reservations for hostile counts.
    let cap = bytes.len() / 2;
    let mut mesh = MeshData {
        vertices: Vec::with_capacity(vertex_count.min(cap)),
        normals: normal.then(|| Vec::with_capacity(vertex_count.min(cap))),
        colors: color.then(|| Vec::with_capacity(vertex_count.min(cap))),
        uvs: texture.then(|| Vec::with_capacity(vertex_count.min(cap))),
        triangles: Vec::with_capacity(face_count.min(cap)),
    };
    for index in 0..vertex_count {
        let element = || format!("vertex {index}");
        let (_, line) = content.next().ok_or_else(|| {
            format_error(
                path,
                element(),
                format!("file ends after {index} of {vertex_count} vertices"),
            )
        })?;
        let values: Vec<&[u8]> = fields(line).collect();
        let number = |i: usize| {
            values.get(i).and_then(|w| parse_f32(w)).ok_or_else(|| {
                format_error(
                    path,
                    element(),
                    format!("value {} missing or not a number", i + 1),
                )
            })
        };
        mesh.vertices.push([number(0)?, number(1)?, number(2)?]);
        let mut next = 3;
        if let Some(normals) = mesh.normals.as_mut() {
            normals.push([number(3)?, number(4)?, number(5)?]);
            next = 6;
        }
        if let Some(colors) = mesh.colors.as_mut() {
            let raw = [number(next)?, number(next + 1)?, number(next + 2)?];
            // Integer colours are 0..255, float colours 0..1.
            let integer = (0..3).all(|i| values.get(next + i).is_some_and(|w| !w.contains(&b'.')));
            colors.push(if integer { raw.map(|c| c / 255.0) } else { raw });
            // An optional alpha follows when the line has room for it.
            let after_rgb = next + 3;
            let expected_rest = if texture { 2 } else { 0 };
            next = if values.len() >= after_rgb + 1 + expected_rest {
                after_rgb + 1
            } else {
                after_rgb
            };
        }
        if let Some(uvs) = mesh.uvs.as_mut() {
            uvs.push([number(next)?, number(next + 1)?]);
        }
    }
    for face in 0..face_count {
        let element = || format!("face {face}");
        let (_, line) = content.next().ok_or_else(|| {
            format_error(
                path,
                element(),
                format!("file ends after {face} of {face_count} faces"),
            )
        })?;
        let mut words = fields(line);
        let n = words
            .next()
            .and_then(parse_i64)
            .ok_or_else(|| format_error(path, element(), "vertex count is not an integer"))?;
        if n < 3 {
            return Err(format_error(
                path,
                element(),
                format!("has {n} vertices, a face needs at least 3"),
            ));
        }
        let mut first = None;
        let mut previous = None;
        for corner in 0..n {
            let index = words.next().and_then(parse_i64).ok_or_else(|| {
                format_error(
                    path,
                    element(),
                    format!("index {corner} of {n} missing or not an integer"),
                )
            })?;
            let index = u32::try_from(index)
                .ok()
                .filter(|&i| (i as usize) < vertex_count)
                .ok_or_else(|| {
                    format_error(
                        path,
                        element(),
                        format!(
                            "vertex index {index} out of range (there are {vertex_count} vertices)"
                        ),
                    )
                })?;
            if let (true, Some(a), Some(b)) = (corner >= 2, first, previous) {
                mesh.triangles.push([a, b, index]);
            }
            first = first.or(Some(index));
            previous = Some(index);
        }
    }
    Ok(mesh)
}

/// Encodes a mesh as OFF (`NOFF` when it has normals, `COFF` with colours).
pub(crate) fn write_off_bytes(mesh: &MeshData) -> Vec<u8> {
    use std::fmt::Write;
    let mut text = String::with_capacity(mesh.vertices.len() * 40 + mesh.triangles.len() * 24);
    let keyword = match (mesh.colors.is_some(), mesh.normals.is_some()) {
        (false, false) => "OFF",
        (true, false) => "COFF",
        (false, true) => "NOFF",
        (true, true) => "CNOFF",
    };
    let _ = writeln!(
        text,
        "{keyword}\n{} {} 0",
        mesh.vertices.len(),
        mesh.triangles.len()
    );
    for (i, v) in mesh.vertices.iter().enumerate() {
        let _ = write!(text, "{} {} {}", v[0], v[1], v[2]);
        if let Some(n) = mesh.normals.as_ref().and_then(|n| n.get(i)) {
            let _ = write!(text, " {} {} {}", n[0], n[1], n[2]);
        }
        if let Some(c) = mesh.colors.as_ref().and_then(|c| c.get(i)) {
            let byte = |x: f32| (x.clamp(0.0, 1.0) * 255.0).round() as u8;
            let _ = write!(text, " {} {} {} 255", byte(c[0]), byte(c[1]), byte(c[2]));
        }
        text.push('\n');
    }
    for t in &mesh.triangles {
        let _ = writeln!(text, "3 {} {} {}", t[0], t[1], t[2]);
    }
    text.into_bytes()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Error;

    fn read(text: &str) -> Result<MeshData> {
        read_off(text.as_bytes(), Path::new("t.off"))
    }

    fn element_of(result: Result<MeshData>) -> String {
        match result {
            Err(Error::Format { element, .. }) => element,
            other => panic!("expected a format error, got {other:?}"),
        }
    }

    #[test]
    fn comments_quads_and_counts_on_the_keyword_line() {
        let text = "OFF 5 2 0 # counts here\n# a comment\n0 0 0\n1 0 0\n\n1 1 0\n0 1 0\n0.5 2 0\n\
            4 0 1 2 3\n5 0 1 4 2 3 255 0 0\n";
        let mesh = read(text).unwrap();
        assert_eq!(mesh.vertices[4], [0.5, 2.0, 0.0]);
        assert_eq!(
            mesh.triangles,
            vec![[0, 1, 2], [0, 2, 3], [0, 1, 4], [0, 4, 2], [0, 2, 3]]
        );
    }

    #[test]
    fn colour_and_normal_variants() {
        let coff =
            read("COFF\n3 1 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n0 1 0 0 0 255 255\n3 0 1 2\n")
                .unwrap();
        assert_eq!(coff.colors.unwrap()[1], [0.0, 1.0, 0.0]);
        let noff = read("NOFF\n3 1 0\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n").unwrap();
        assert_eq!(noff.normals, Some(vec![[0.0, 0.0, 1.0]; 3]));
        let float_colors = read("COFF\n1 0 0\n0 0 0 0.5 0.25 1.0 1.0\n").unwrap();
        assert_eq!(float_colors.colors, Some(vec![[0.5, 0.25, 1.0]]));
    }

    #[test]
    fn errors_name_the_element() {
        assert_eq!(element_of(read("PLY\n")), "header line 1");
        assert_eq!(element_of(read("OFF\n3 1\n0 0 0\n1 0 0\n")), "vertex 2");
        assert_eq!(
            element_of(read("OFF\n3 1\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n")),
            "face 0"
        );
        assert_eq!(
            element_of(read("OFF\n3 2\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n2 0 1\n")),
            "face 1"
        );
        assert_eq!(
            element_of(read("OFF\n3 1\n0 0 0\n1 0 0\n0 1\n")),
            "vertex 2"
        );
        assert_eq!(element_of(read("OFF\nx y\n")), "header line 2");
        assert!(read("OFF\n18446744073709551615 1\n").is_err());
    }

    #[test]
    fn writer_output_reads_back_identically() {
        let mesh = MeshData {
            vertices: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            triangles: vec![[0, 1, 2]],
            normals: Some(vec![[0.0, 0.0, 1.0]; 3]),
            colors: Some(vec![[1.0, 0.0, 0.2]; 3]),
            uvs: None,
        };
        assert_eq!(
            read_off(&write_off_bytes(&mesh), Path::new("t.off")).unwrap(),
            mesh
        );
    }
}
