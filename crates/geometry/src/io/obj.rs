//! Wavefront OBJ reader and writer.
//!
//! Reads `v x y z [w]` (or `v x y z r g b`, the common vertex-colour extension), `vt`, `vn`
//! and `f` records with `v`, `v/vt`, `v//vn` or `v/vt/vn` corners, positive (1-based) or
//! negative (relative) indices; polygons are fan-triangulated and every group/object is
//! merged into one mesh (indices are global in OBJ, so no offsets are needed). Other records
//! (`g o s usemtl mtllib l p`...) are ignored. Normals and texture coordinates become per
//! vertex: a vertex used with two different `vt`/`vn` pairs is split (a seam), and vertex
//! order is the file's order, unreferenced vertices kept, so a round trip is exact.
//!
//! Hand-written rather than `tobj`: tobj's single-index mode renumbers vertices in order of
//! first use and drops unreferenced ones (breaking round trips and point clouds), and it
//! allocates a `String` per line; this parser works on the byte slice with `fast-float2`.

use super::ascii_scan::{fields, lines, parse_f32, parse_i64};
use super::format_error::format_error;
use super::mesh_data::MeshData;
use crate::error::Result;
use std::collections::HashMap;
use std::path::Path;

/// Resolves a 1-based or negative OBJ index against `count` defined elements.
fn resolve(field: &[u8], count: usize) -> std::result::Result<u32, String> {
    let raw = parse_i64(field).ok_or_else(|| {
        format!(
            "index `{}` is not an integer",
            String::from_utf8_lossy(field)
        )
    })?;
    let resolved = match raw {
        0 => return Err("index 0 (OBJ indices start at 1)".into()),
        r if r > 0 => r - 1,
        r => i64::try_from(count).unwrap_or(i64::MAX) + r,
    };
    usize::try_from(resolved)
        .ok()
        .filter(|&i| i < count)
        .and_then(|i| u32::try_from(i).ok())
        .ok_or_else(|| format!("index {raw} out of range ({count} defined so far)"))
}

/// Reads an OBJ file's bytes; `path` is used in error messages only.
pub(crate) fn read_obj(bytes: &[u8], path: &Path) -> Result<MeshData> {
    let mut positions: Vec<[f32; 3]> = Vec::with_capacity(bytes.len() / 64);
    let mut colors: Vec<[f32; 3]> = Vec::new();
    let mut texcoords: Vec<[f32; 2]> = Vec::new();
    let mut normals: Vec<[f32; 3]> = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::with_capacity(bytes.len() / 64);
    // Per triangle corner: (vt + 1, vn + 1), 0 = none; only filled once a corner has one.
    let mut corner_attributes: Vec<[[u32; 2]; 3]> = Vec::new();
    let mut faces = 0usize;
    let mut polygon: Vec<(u32, [u32; 2])> = Vec::with_capacity(8);
    for (number, line) in lines(bytes) {
        let mut words = fields(line);
        let Some(keyword) = words.next() else {
            continue;
        };
        let at_line = |message: String| format_error(path, format!("line {number}"), message);
        match keyword {
            b"v" => {
                let mut values = [0f32; 7];
                let mut n = 0usize;
                for word in words {
                    let value = parse_f32(word).ok_or_else(|| {
                        format_error(
                            path,
                            format!("vertex {} (line {number})", positions.len()),
                            format!("`{}` is not a number", String::from_utf8_lossy(word)),
                        )
                    })?;
                    if let Some(slot) = values.get_mut(n) {
                        *slot = value;
                    }
                    n += 1;
                }
                if n < 3 {
                    return Err(format_error(
                        path,
                        format!("vertex {} (line {number})", positions.len()),
                        format!("has {n} coordinates, needs 3"),
                    ));
                }
                if n == 6 || n == 7 {
                    colors.resize(positions.len(), [0.0; 3]);
                    colors.push([values[3], values[4], values[5]]);
                }
                positions.push([values[0], values[1], values[2]]);
            }
            b"vt" => {
                let u = words.next().and_then(parse_f32);
                let v = words.next().map_or(Some(0.0), parse_f32);
                match (u, v) {
                    (Some(u), Some(v)) => texcoords.push([u, v]),
                    _ => return Err(at_line("texture coordinate is not a number".into())),
                }
            }
            b"vn" => {
                let mut n = [0f32; 3];
                for slot in &mut n {
                    *slot = words
                        .next()
                        .and_then(parse_f32)
                        .ok_or_else(|| at_line("normal needs 3 numbers".into()))?;
                }
                normals.push(n);
            }
            b"f" => {
                polygon.clear();
                let face_error = |message: String| {
                    format_error(path, format!("face {faces} (line {number})"), message)
                };
                for corner in words {
                    let mut parts = corner.split(|&b| b == b'/');
                    let v = resolve(parts.next().unwrap_or_default(), positions.len())
                        .map_err(|m| face_error(format!("vertex {m}")))?;
                    let mut attribute = [0u32; 2];
                    for (slot, count, what) in [
                        (0usize, texcoords.len(), "texture coordinate"),
                        (1, normals.len(), "normal"),
                    ] {
                        match parts.next() {
                            Some(field) if !field.is_empty() => {
                                let i = resolve(field, count)
                                    .map_err(|m| face_error(format!("{what} {m}")))?;
                                if let Some(a) = attribute.get_mut(slot) {
                                    *a = i + 1;
                                }
                            }
                            _ => {}
                        }
                    }
                    polygon.push((v, attribute));
                }
                if polygon.len() < 3 {
                    return Err(face_error(format!(
                        "has {} vertices, a face needs at least 3",
                        polygon.len()
                    )));
                }
                let has_attributes = polygon.iter().any(|(_, a)| *a != [0, 0]);
                if has_attributes && corner_attributes.len() < triangles.len() {
                    corner_attributes.resize(triangles.len(), [[0; 2]; 3]);
                }
                if let Some((&first, rest)) = polygon.split_first() {
                    for pair in rest.windows(2) {
                        if let [b, c] = pair {
                            triangles.push([first.0, b.0, c.0]);
                            if has_attributes || !corner_attributes.is_empty() {
                                corner_attributes.push([first.1, b.1, c.1]);
                            }
                        }
                    }
                }
                faces += 1;
            }
            _ => {}
        }
    }
    let colors = (!colors.is_empty()).then(|| {
        colors.resize(positions.len(), [0.0; 3]);
        colors
    });
    if corner_attributes.is_empty() {
        // No corner names a vt/vn: attributes are per vertex when their counts match.
        let faceless = triangles.is_empty();
        return Ok(MeshData {
            normals: (normals.len() == positions.len() && (faceless || !normals.is_empty()))
                .then_some(normals)
                .filter(|n| !n.is_empty()),
            uvs: (texcoords.len() == positions.len())
                .then_some(texcoords)
                .filter(|t| !t.is_empty()),
            vertices: positions,
            triangles,
            colors,
        });
    }
    corner_attributes.resize(triangles.len(), [[0; 2]; 3]);
    Ok(split_seams(
        positions,
        colors,
        &texcoords,
        &normals,
        triangles,
        &corner_attributes,
    ))
}

/// Makes corner attributes per vertex, duplicating a vertex for each extra `(vt, vn)` pair
/// it is used with. Duplicates are appended after the original vertices, in first-use order.
fn split_seams(
    mut positions: Vec<[f32; 3]>,
    mut colors: Option<Vec<[f32; 3]>>,
    texcoords: &[[f32; 2]],
    normals: &[[f32; 3]],
    mut triangles: Vec<[u32; 3]>,
    corner_attributes: &[[[u32; 2]; 3]],
) -> MeshData {
    let original = positions.len();
    let mut assigned: Vec<Option<[u32; 2]>> = vec![None; original];
    let mut splits: HashMap<(u32, [u32; 2]), u32> = HashMap::new();
    let mut attribute_of: Vec<[u32; 2]> = Vec::new();
    for (triangle, attributes) in triangles.iter_mut().zip(corner_attributes) {
        for (v, &a) in triangle.iter_mut().zip(attributes) {
            let Some(slot) = assigned.get_mut(*v as usize) else {
                continue;
            };
            match slot {
                None => *slot = Some(a),
                Some(existing) if *existing == a => {}
                Some(_) => {
                    let next = u32::try_from(positions.len()).unwrap_or(u32::MAX);
                    let index = *splits.entry((*v, a)).or_insert_with(|| {
                        let source = *v as usize;
                        positions.push(positions.get(source).copied().unwrap_or_default());
                        if let Some(c) = colors.as_mut() {
                            c.push(c.get(source).copied().unwrap_or_default());
                        }
                        attribute_of.push(a);
                        next
                    });
                    *v = index;
                }
            }
        }
    }
    let all: Vec<[u32; 2]> = assigned
        .into_iter()
        .map(Option::unwrap_or_default)
        .chain(attribute_of)
        .collect();
    let uvs = all.iter().any(|a| a[0] != 0).then(|| {
        all.iter()
            .map(|a| {
                texcoords
                    .get((a[0] as usize).wrapping_sub(1))
                    .copied()
                    .unwrap_or_default()
            })
            .collect()
    });
    let normals = all.iter().any(|a| a[1] != 0).then(|| {
        all.iter()
            .map(|a| {
                normals
                    .get((a[1] as usize).wrapping_sub(1))
                    .copied()
                    .unwrap_or_default()
            })
            .collect()
    });
    MeshData {
        vertices: positions,
        triangles,
        normals,
        uvs,
        colors,
    }
}

/// Encodes a mesh (no triangles: a cloud) as OBJ; normals and uvs share the vertex index.
pub(crate) fn write_obj_bytes(mesh: &MeshData) -> Vec<u8> {
    use std::fmt::Write;
    let mut text = String::with_capacity(mesh.vertices.len() * 40 + mesh.triangles.len() * 30);
    text.push_str("# written by meshgnn-geometry\n");
    for (i, v) in mesh.vertices.iter().enumerate() {
        let _ = write!(text, "v {} {} {}", v[0], v[1], v[2]);
        if let Some(c) = mesh.colors.as_ref().and_then(|c| c.get(i)) {
            let _ = write!(text, " {} {} {}", c[0], c[1], c[2]);
        }
        text.push('\n');
    }
    for t in mesh.uvs.iter().flatten() {
        let _ = writeln!(text, "vt {} {}", t[0], t[1]);
    }
    for n in mesh.normals.iter().flatten() {
        let _ = writeln!(text, "vn {} {} {}", n[0], n[1], n[2]);
    }
    let (uv, normal) = (mesh.uvs.is_some(), mesh.normals.is_some());
    for t in &mesh.triangles {
        text.push('f');
        for &i in t {
            let i = u64::from(i) + 1;
            let _ = match (uv, normal) {
                (false, false) => write!(text, " {i}"),
                (true, false) => write!(text, " {i}/{i}"),
                (false, true) => write!(text, " {i}//{i}"),
                (true, true) => write!(text, " {i}/{i}/{i}"),
            };
        }
        text.push('\n');
    }
    text.into_bytes()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Error;

    fn read(text: &str) -> Result<MeshData> {
        read_obj(text.as_bytes(), Path::new("t.obj"))
    }

    fn element_of(result: Result<MeshData>) -> String {
        match result {
            Err(Error::Format { element, .. }) => element,
            other => panic!("expected a format error, got {other:?}"),
        }
    }

    #[test]
    fn groups_merge_polygons_fan_and_negative_indices_resolve() {
        let text = "# comment\nmtllib a.mtl\no first\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n\
            g quad\nusemtl red\nf 1 2 3 4\no second\nv 2 0 0\nv 3 0 0\nv 3 1 0\nv 2.5 2 0\nv 2 1 0\n\
            s 1\nf -5 -4 -3 -2 -1\nl 1 2\n";
        let mesh = read(text).unwrap();
        assert_eq!(mesh.vertices.len(), 9);
        assert_eq!(mesh.vertices[7], [2.5, 2.0, 0.0]);
        assert_eq!(
            mesh.triangles,
            vec![[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7], [4, 7, 8]]
        );
        assert!(mesh.normals.is_none() && mesh.uvs.is_none());
    }

    #[test]
    fn corner_attributes_become_per_vertex_splitting_seams() {
        // Vertex 1 (index 0) is used with two different uvs: it is split once.
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvt 0.5 0.5\n\
            vn 0 0 1\nf 1/1/1 2/2/1 3/3/1\nf 2/2/1 4/4/1 1/4/1\n";
        let mesh = read(text).unwrap();
        assert_eq!(mesh.vertices.len(), 5);
        assert_eq!(mesh.vertices[4], [0.0, 0.0, 0.0]);
        assert_eq!(mesh.triangles, vec![[0, 1, 2], [1, 3, 4]]);
        assert_eq!(
            mesh.uvs,
            Some(vec![
                [0.0, 0.0],
                [1.0, 0.0],
                [0.0, 1.0],
                [0.5, 0.5],
                [0.5, 0.5]
            ])
        );
        assert_eq!(mesh.normals, Some(vec![[0.0, 0.0, 1.0]; 5]));
    }

    #[test]
    fn vertex_colours_and_faceless_normals_are_read() {
        let mesh = read("v 0 0 0 1 0 0\nv 1 2 3 0 0.5 1\nvn 0 0 1\nvn 0 1 0\n").unwrap();
        assert_eq!(mesh.colors, Some(vec![[1.0, 0.0, 0.0], [0.0, 0.5, 1.0]]));
        assert_eq!(mesh.normals, Some(vec![[0.0, 0.0, 1.0], [0.0, 1.0, 0.0]]));
    }

    #[test]
    fn errors_name_the_face_or_vertex_and_line() {
        let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
        assert_eq!(
            element_of(read(&format!("{tri}f 1 2 4\n"))),
            "face 0 (line 4)"
        );
        assert_eq!(
            element_of(read(&format!("{tri}f 1 2 3\nf 0 1 2\n"))),
            "face 1 (line 5)"
        );
        assert_eq!(
            element_of(read(&format!("{tri}f 1 2\n"))),
            "face 0 (line 4)"
        );
        assert_eq!(
            element_of(read(&format!("{tri}f -4 1 2\n"))),
            "face 0 (line 4)"
        );
        assert_eq!(
            element_of(read(&format!("{tri}f 1/2 2 3\n"))),
            "face 0 (line 4)"
        );
        assert_eq!(element_of(read("v 0 0 0\nv 1 x 0\n")), "vertex 1 (line 2)");
        assert_eq!(element_of(read("v 0 0\n")), "vertex 0 (line 1)");
        let nan = read("v 0 0 0\nv nan 0 0\n")
            .unwrap()
            .into_mesh(Path::new("t.obj"));
        assert!(matches!(nan, Err(Error::Format { element, .. }) if element == "vertex 1"));
    }

    #[test]
    fn writer_output_reads_back_identically() {
        let mesh = MeshData {
            vertices: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.5]],
            triangles: vec![[0, 1, 2], [1, 3, 2]],
            normals: Some(vec![[0.0, 0.0, 1.0]; 4]),
            uvs: Some(vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]),
            colors: None,
        };
        assert_eq!(
            read_obj(&write_obj_bytes(&mesh), Path::new("t.obj")).unwrap(),
            mesh
        );
    }
}
