//! Stanford PLY reader and writer: ASCII, binary little endian and binary big endian.
//!
//! Reads the `vertex` element's `x y z` (any numeric type) and, when present, `nx ny nz`,
//! `red green blue` (integers scaled by their type's maximum, floats as is), and `u v`,
//! `s t` or `texture_u texture_v`; the `face` element's `vertex_indices` or `vertex_index`
//! list of any polygon size and any count/index types, fan-triangulated. Every other element
//! and property is skipped. A file without faces reads as a mesh with no triangles (a cloud).
//!
//! Speed: the file is parsed from one byte slice; binary vertex rows are fixed-size and
//! converted in parallel (`par_chunks_exact`); binary faces take a parallel fast path when
//! every face is a `uchar 3` followed by 32-bit indices; ASCII element blocks are split into
//! line-aligned chunks parsed in parallel. Reservations are capped by what the remaining
//! bytes can hold, so a hostile element count cannot allocate up front.

use super::ascii_scan::{end_of_rows, fields, lines, parse_f32, parse_f64, parse_i64, parse_rows};
use super::format_error::format_error;
use super::mesh_data::MeshData;
use crate::error::Result;
use rayon::prelude::*;
use std::path::Path;

/// How a PLY file's body is encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum PlyEncoding {
    /// Human-readable text, one element per line.
    Ascii,
    /// Packed binary, little endian (what [`crate::write_mesh`] writes: compact and fast).
    #[default]
    BinaryLittleEndian,
    /// Packed binary, big endian (old SGI files).
    BinaryBigEndian,
}

/// A PLY scalar type.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &[u8]) -> Option<Self> {
        Some(match name {
            b"char" | b"int8" => Self::I8,
            b"uchar" | b"uint8" => Self::U8,
            b"short" | b"int16" => Self::I16,
            b"ushort" | b"uint16" => Self::U16,
            b"int" | b"int32" => Self::I32,
            b"uint" | b"uint32" => Self::U32,
            b"float" | b"float32" => Self::F32,
            b"double" | b"float64" => Self::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::F64 => 8,
        }
    }

    /// The value that maps to 1.0 when a colour of this type is normalised.
    fn color_scale(self) -> f64 {
        match self {
            Self::I8 => 127.0,
            Self::U8 => 255.0,
            Self::I16 => 32767.0,
            Self::U16 => 65535.0,
            Self::I32 => 2_147_483_647.0,
            Self::U32 => 4_294_967_295.0,
            Self::F32 | Self::F64 => 1.0,
        }
    }

    /// Reads one value from the start of `bytes` (which must hold `self.size()` bytes).
    fn read(self, bytes: &[u8], big_endian: bool) -> Option<f64> {
        macro_rules! get {
            ($t:ty, $n:expr) => {{
                let raw: [u8; $n] = bytes.get(..$n)?.try_into().ok()?;
                if big_endian {
                    <$t>::from_be_bytes(raw)
                } else {
                    <$t>::from_le_bytes(raw)
                }
            }};
        }
        Some(match self {
            Self::I8 => f64::from(get!(i8, 1)),
            Self::U8 => f64::from(get!(u8, 1)),
            Self::I16 => f64::from(get!(i16, 2)),
            Self::U16 => f64::from(get!(u16, 2)),
            Self::I32 => f64::from(get!(i32, 4)),
            Self::U32 => f64::from(get!(u32, 4)),
            Self::F32 => f64::from(get!(f32, 4)),
            Self::F64 => get!(f64, 8),
        })
    }

    /// Reads one integer value (list counts and indices); floats must be whole numbers.
    fn read_int(self, bytes: &[u8], big_endian: bool) -> Option<i64> {
        let value = self.read(bytes, big_endian)?;
        // Every integer type fits f64 exactly; reject fractional or huge floats.
        (value.fract() == 0.0 && value.abs() < 9.0e15).then_some(value as i64)
    }
}

/// A property of an element: a scalar or a list.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Debug, Clone)]
struct Property {
    name: Vec<u8>,
    kind: Kind,
}

#[derive(Debug, Clone)]
struct Element {
    name: Vec<u8>,
    count: u64,
    properties: Vec<Property>,
}

impl Element {
    /// Byte size of one row when every property is a scalar.
    fn fixed_row_size(&self) -> Option<usize> {
        self.properties
            .iter()
            .map(|p| match p.kind {
                Kind::Scalar(s) => Some(s.size()),
                Kind::List { .. } => None,
            })
            .sum()
    }

    /// Fewest bytes one binary row can take (lists empty).
    fn min_row_size(&self) -> usize {
        self.properties
            .iter()
            .map(|p| match p.kind {
                Kind::Scalar(s) => s.size(),
                Kind::List { count, .. } => count.size(),
            })
            .sum::<usize>()
            .max(1)
    }

    fn find(&self, names: &[&[u8]]) -> Option<usize> {
        self.properties
            .iter()
            .position(|p| names.contains(&p.name.as_slice()))
    }
}

struct Header {
    encoding: PlyEncoding,
    elements: Vec<Element>,
    body: usize,
}

/// Parses the header; `body` is the offset of the first byte after `end_header`.
fn parse_header(bytes: &[u8], path: &Path) -> Result<Header> {
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut offset = 0usize;
    for (number, line) in lines(bytes) {
        let element = || format!("header line {number}");
        let rest = bytes.get(offset..).unwrap_or_default();
        let line_len = memchr::memchr(b'\n', rest).map_or(rest.len(), |e| e + 1);
        offset += line_len;
        let mut words = fields(line);
        let keyword = words.next();
        if number == 1 {
            if keyword != Some(b"ply") || words.next().is_some() {
                return Err(format_error(
                    path,
                    element(),
                    "not a PLY file: must start with `ply`",
                ));
            }
            continue;
        }
        match keyword {
            None => {}
            Some(b"comment" | b"obj_info") => {}
            Some(b"format") => {
                encoding = Some(match words.next() {
                    Some(b"ascii") => PlyEncoding::Ascii,
                    Some(b"binary_little_endian") => PlyEncoding::BinaryLittleEndian,
                    Some(b"binary_big_endian") => PlyEncoding::BinaryBigEndian,
                    other => {
                        return Err(format_error(
                            path,
                            element(),
                            format!("unknown format `{}`", show(other)),
                        ));
                    }
                });
            }
            Some(b"element") => {
                let (Some(name), Some(count), None) = (words.next(), words.next(), words.next())
                else {
                    return Err(format_error(
                        path,
                        element(),
                        "expected `element NAME COUNT`",
                    ));
                };
                let count = parse_i64(count)
                    .and_then(|c| u64::try_from(c).ok())
                    .ok_or_else(|| {
                        format_error(
                            path,
                            element(),
                            "element count is not a non-negative integer",
                        )
                    })?;
                elements.push(Element {
                    name: name.to_vec(),
                    count,
                    properties: Vec::new(),
                });
            }
            Some(b"property") => {
                let Some(current) = elements.last_mut() else {
                    return Err(format_error(path, element(), "property before any element"));
                };
                let words: Vec<&[u8]> = words.collect();
                let bad_type = |t: &[u8]| {
                    format_error(
                        path,
                        element(),
                        format!("unknown property type `{}`", show(Some(t))),
                    )
                };
                let property = match words.as_slice() {
                    [b"list", count, item, name] => Property {
                        name: name.to_vec(),
                        kind: Kind::List {
                            count: Scalar::parse(count).ok_or_else(|| bad_type(count))?,
                            item: Scalar::parse(item).ok_or_else(|| bad_type(item))?,
                        },
                    },
                    [ty, name] if *ty != b"list" => Property {
                        name: name.to_vec(),
                        kind: Kind::Scalar(Scalar::parse(ty).ok_or_else(|| bad_type(ty))?),
                    },
                    _ => {
                        return Err(format_error(
                            path,
                            element(),
                            "expected `property TYPE NAME` or `property list COUNT_TYPE ITEM_TYPE NAME`",
                        ));
                    }
                };
                current.properties.push(property);
            }
            Some(b"end_header") => {
                let encoding = encoding.ok_or_else(|| {
                    format_error(path, element(), "no `format` line before `end_header`")
                })?;
                return Ok(Header {
                    encoding,
                    elements,
                    body: offset,
                });
            }
            Some(other) => {
                return Err(format_error(
                    path,
                    element(),
                    format!("unknown header keyword `{}`", show(Some(other))),
                ));
            }
        }
    }
    Err(format_error(
        path,
        "header",
        "missing `end_header` (file truncated or not PLY)",
    ))
}

/// A byte string for an error message.
fn show(word: Option<&[u8]>) -> String {
    word.map_or_else(String::new, |w| {
        String::from_utf8_lossy(&w[..w.len().min(40)]).into_owned()
    })
}

/// Where each vertex attribute sits among the vertex properties.
struct VertexLayout {
    position: [usize; 3],
    normal: Option<[usize; 3]>,
    color: Option<([usize; 3], f64)>,
    uv: Option<[usize; 2]>,
}

impl VertexLayout {
    fn new(element: &Element, path: &Path) -> Result<Self> {
        let scalar = |names: &[&[u8]]| -> Result<Option<usize>> {
            match element.find(names) {
                Some(i) => match element.properties.get(i).map(|p| p.kind) {
                    Some(Kind::Scalar(_)) => Ok(Some(i)),
                    _ => Err(format_error(
                        path,
                        "vertex element",
                        format!(
                            "property `{}` must be a scalar, not a list",
                            show(names.first().copied())
                        ),
                    )),
                },
                None => Ok(None),
            }
        };
        let triple = |a: &[&[u8]], b: &[&[u8]], c: &[&[u8]]| -> Result<Option<[usize; 3]>> {
            Ok(match (scalar(a)?, scalar(b)?, scalar(c)?) {
                (Some(x), Some(y), Some(z)) => Some([x, y, z]),
                _ => None,
            })
        };
        let position = triple(&[b"x"], &[b"y"], &[b"z"])?
            .ok_or_else(|| format_error(path, "vertex element", "needs properties x, y and z"))?;
        let normal = triple(&[b"nx"], &[b"ny"], &[b"nz"])?;
        let color = triple(
            &[b"red", b"r", b"diffuse_red"],
            &[b"green", b"g", b"diffuse_green"],
            &[b"blue", b"b", b"diffuse_blue"],
        )?
        .map(|c| {
            let scale = match element.properties.get(c[0]).map(|p| p.kind) {
                Some(Kind::Scalar(s)) => s.color_scale(),
                _ => 1.0,
            };
            (c, scale)
        });
        let uv = match (
            scalar(&[b"u", b"s", b"texture_u", b"texture_s"])?,
            scalar(&[b"v", b"t", b"texture_v", b"texture_t"])?,
        ) {
            (Some(u), Some(v)) => Some([u, v]),
            _ => None,
        };
        Ok(Self {
            position,
            normal,
            color,
            uv,
        })
    }

    /// Splits row-major property values (`values: #rows×stride`) into the attribute arrays.
    fn assemble(&self, values: &[f64], stride: usize) -> MeshData {
        let rows = values.par_chunks_exact(stride.max(1));
        let pick3 = |row: &[f64], idx: [usize; 3], scale: f64| -> [f32; 3] {
            idx.map(|i| (row.get(i).copied().unwrap_or(0.0) / scale) as f32)
        };
        MeshData {
            vertices: rows.clone().map(|r| pick3(r, self.position, 1.0)).collect(),
            normals: self
                .normal
                .map(|n| rows.clone().map(|r| pick3(r, n, 1.0)).collect()),
            colors: self
                .color
                .map(|(c, s)| rows.clone().map(|r| pick3(r, c, s)).collect()),
            uvs: self.uv.map(|uv| {
                rows.clone()
                    .map(|r| uv.map(|i| r.get(i).copied().unwrap_or(0.0) as f32))
                    .collect()
            }),
            triangles: Vec::new(),
        }
    }
}

/// Fan-triangulates one polygon `(p0, p1, ..., pn)` into `(p0, pi, pi+1)`, checking indices.
fn push_fan(
    polygon: impl Iterator<Item = Option<i64>>,
    vertex_count: u64,
    triangles: &mut Vec<[u32; 3]>,
) -> std::result::Result<(), String> {
    let mut first = None;
    let mut previous = None;
    let mut corners = 0usize;
    for value in polygon {
        let index = value.ok_or("vertex index is not an integer")?;
        let index = u32::try_from(index)
            .ok()
            .filter(|&i| u64::from(i) < vertex_count)
            .ok_or_else(|| {
                format!("vertex index {index} out of range (there are {vertex_count} vertices)")
            })?;
        if let (true, Some(a), Some(b)) = (corners >= 2, first, previous) {
            triangles.push([a, b, index]);
        }
        first = first.or(Some(index));
        previous = Some(index);
        corners += 1;
    }
    if corners < 3 {
        return Err(format!("has {corners} vertices, a face needs at least 3"));
    }
    Ok(())
}

/// Reads a PLY file's bytes; `path` is used in error messages only.
pub(crate) fn read_ply(bytes: &[u8], path: &Path) -> Result<MeshData> {
    let header = parse_header(bytes, path)?;
    let vertex_count = header
        .elements
        .iter()
        .find(|e| e.name == b"vertex")
        .map_or(0, |e| e.count);
    let mut mesh = MeshData::default();
    let mut position = header.body;
    for element in &header.elements {
        let body = bytes.get(position..).unwrap_or_default();
        let consumed = match header.encoding {
            PlyEncoding::Ascii => read_ascii_element(body, element, vertex_count, &mut mesh, path)?,
            PlyEncoding::BinaryLittleEndian => {
                read_binary_element(body, element, false, vertex_count, &mut mesh, path)?
            }
            PlyEncoding::BinaryBigEndian => {
                read_binary_element(body, element, true, vertex_count, &mut mesh, path)?
            }
        };
        position += consumed;
    }
    Ok(mesh)
}

/// Parses one element of an ASCII body; returns the bytes consumed.
fn read_ascii_element(
    body: &[u8],
    element: &Element,
    vertex_count: u64,
    mesh: &mut MeshData,
    path: &Path,
) -> Result<usize> {
    let name = String::from_utf8_lossy(&element.name).into_owned();
    let end = end_of_rows(body, element.count).map_err(|found| {
        format_error(
            path,
            format!("{name} {found}"),
            format!("file ends after {found} of {} rows", element.count),
        )
    })?;
    let block = &body[..end];
    let at = |(row, message): (u64, String)| format_error(path, format!("{name} {row}"), message);
    if element.name == b"vertex" {
        let layout = VertexLayout::new(element, path)?;
        let values = parse_rows(block, |line, out: &mut Vec<f64>| {
            ascii_row_values(line, element, out)
        })
        .map_err(at)?;
        let faces = std::mem::take(&mut mesh.triangles);
        *mesh = layout.assemble(&values, element.properties.len());
        mesh.triangles = faces;
    } else if element.name == b"face" {
        let Some(list) = element.find(&[b"vertex_indices", b"vertex_index"]) else {
            return Ok(end);
        };
        let triangles = parse_rows(block, |line, out: &mut Vec<[u32; 3]>| {
            ascii_face(line, element, list, vertex_count, out)
        })
        .map_err(at)?;
        mesh.triangles = triangles;
    }
    Ok(end)
}

/// Appends all property values of one ASCII row to `out` (a list gives 0). Float
/// properties parse as `f32` directly so written `f32` values read back bit for bit.
fn ascii_row_values(
    line: &[u8],
    element: &Element,
    out: &mut Vec<f64>,
) -> std::result::Result<(), String> {
    let mut words = fields(line);
    for property in &element.properties {
        let word = words.next().ok_or_else(|| {
            format!(
                "missing value for property `{}`",
                show(Some(&property.name))
            )
        })?;
        let not_number = || format!("`{}` is not a number", show(Some(word)));
        match property.kind {
            Kind::Scalar(Scalar::F32) => {
                out.push(f64::from(parse_f32(word).ok_or_else(not_number)?));
            }
            Kind::Scalar(_) => out.push(parse_f64(word).ok_or_else(not_number)?),
            Kind::List { .. } => {
                let count = parse_i64(word)
                    .and_then(|c| usize::try_from(c).ok())
                    .ok_or("list count is not a non-negative integer")?;
                if (&mut words).take(count).count() < count {
                    return Err("row ends inside a list".into());
                }
                out.push(0.0);
            }
        }
    }
    Ok(())
}

/// The polygon of one ASCII face row, fan-triangulated into `out`.
fn ascii_face(
    line: &[u8],
    element: &Element,
    list: usize,
    vertex_count: u64,
    out: &mut Vec<[u32; 3]>,
) -> std::result::Result<(), String> {
    let mut words = fields(line);
    for (i, property) in element.properties.iter().enumerate() {
        match property.kind {
            Kind::Scalar(_) => {
                words.next().ok_or("row ends early")?;
            }
            Kind::List { .. } => {
                let count = words
                    .next()
                    .and_then(parse_i64)
                    .and_then(|c| usize::try_from(c).ok())
                    .ok_or("list count is not a non-negative integer")?;
                if i == list {
                    let mut taken = 0usize;
                    let polygon = (&mut words).take(count).map(|w| {
                        taken += 1;
                        parse_i64(w)
                    });
                    push_fan(polygon, vertex_count, out)?;
                    if taken < count {
                        return Err(format!("row ends after {taken} of {count} indices"));
                    }
                } else if (&mut words).take(count).count() < count {
                    return Err("row ends early".into());
                }
            }
        }
    }
    Ok(())
}

/// Parses one element of a binary body; returns the bytes consumed.
fn read_binary_element(
    body: &[u8],
    element: &Element,
    big_endian: bool,
    vertex_count: u64,
    mesh: &mut MeshData,
    path: &Path,
) -> Result<usize> {
    let name = String::from_utf8_lossy(&element.name).into_owned();
    let truncated = |row: u64| {
        format_error(
            path,
            format!("{name} {row}"),
            format!(
                "file ends early (truncated binary data, {} rows declared)",
                element.count
            ),
        )
    };
    if element.name == b"vertex" {
        let layout = VertexLayout::new(element, path)?;
        if let Some(row_size) = element.fixed_row_size() {
            let needed = usize::try_from(element.count)
                .ok()
                .and_then(|c| c.checked_mul(row_size))
                .filter(|&n| n <= body.len())
                .ok_or_else(|| truncated((body.len() / row_size.max(1)) as u64))?;
            let faces = std::mem::take(&mut mesh.triangles);
            *mesh = binary_vertices(&body[..needed], element, row_size, &layout, big_endian);
            mesh.triangles = faces;
            return Ok(needed);
        }
        // Vertex rows with list properties: walk row by row.
        let stride = element.properties.len();
        let mut values = Vec::with_capacity(capacity(element, body.len()) * stride);
        let mut offset = 0usize;
        for row in 0..element.count {
            offset += binary_row_values(
                body.get(offset..).unwrap_or_default(),
                element,
                big_endian,
                &mut values,
            )
            .ok_or_else(|| truncated(row))?;
        }
        let faces = std::mem::take(&mut mesh.triangles);
        *mesh = layout.assemble(&values, stride);
        mesh.triangles = faces;
        return Ok(offset);
    }
    let list = (element.name == b"face")
        .then(|| element.find(&[b"vertex_indices", b"vertex_index"]))
        .flatten();
    if let Some(list) = list {
        if let Some((triangles, used)) = binary_triangle_fast_path(body, element, big_endian) {
            if let Some(face) = triangles
                .par_iter()
                .position_first(|t| t.iter().any(|&v| u64::from(v) >= vertex_count))
            {
                return Err(format_error(
                    path,
                    format!("face {face}"),
                    format!("vertex index out of range (there are {vertex_count} vertices)"),
                ));
            }
            mesh.triangles = triangles;
            return Ok(used);
        }
        let mut triangles = Vec::with_capacity(capacity(element, body.len()));
        let mut offset = 0usize;
        for face in 0..element.count {
            offset += binary_face(
                body.get(offset..).unwrap_or_default(),
                element,
                list,
                big_endian,
                vertex_count,
                &mut triangles,
            )
            .map_err(|message| {
                if message.is_empty() {
                    truncated(face)
                } else {
                    format_error(path, format!("face {face}"), message)
                }
            })?;
        }
        mesh.triangles = triangles;
        return Ok(offset);
    }
    // Any other element: skip it.
    if let Some(row_size) = element.fixed_row_size() {
        return usize::try_from(element.count)
            .ok()
            .and_then(|c| c.checked_mul(row_size))
            .filter(|&n| n <= body.len())
            .ok_or_else(|| truncated((body.len() / row_size.max(1)) as u64));
    }
    let mut offset = 0usize;
    for row in 0..element.count {
        offset += skip_binary_row(body.get(offset..).unwrap_or_default(), element, big_endian)
            .ok_or_else(|| truncated(row))?;
    }
    Ok(offset)
}

/// Rows to reserve: the declared count, capped by how many rows the remaining bytes hold.
fn capacity(element: &Element, remaining: usize) -> usize {
    let fit = remaining / element.min_row_size();
    usize::try_from(element.count).map_or(fit, |c| c.min(fit))
}

/// Converts fixed-size vertex rows in parallel.
fn binary_vertices(
    block: &[u8],
    element: &Element,
    row_size: usize,
    layout: &VertexLayout,
    big_endian: bool,
) -> MeshData {
    let mut offsets = Vec::with_capacity(element.properties.len());
    let mut types = Vec::with_capacity(element.properties.len());
    let mut at = 0usize;
    for property in &element.properties {
        if let Kind::Scalar(s) = property.kind {
            offsets.push(at);
            types.push(s);
            at += s.size();
        }
    }
    let read = |row: &[u8], i: usize| -> f64 {
        match (offsets.get(i), types.get(i)) {
            (Some(&o), Some(&t)) => row
                .get(o..)
                .and_then(|b| t.read(b, big_endian))
                .unwrap_or(0.0),
            _ => 0.0,
        }
    };
    let float3 = |idx: [usize; 3]| {
        types.get(idx[0]) == Some(&Scalar::F32)
            && idx.iter().all(|&i| types.get(i) == Some(&Scalar::F32))
    };
    let rows = block.par_chunks_exact(row_size.max(1));
    let triple = |idx: [usize; 3], scale: f64| -> Vec<[f32; 3]> {
        if float3(idx) && scale == 1.0 {
            // Fast path: three f32 read directly.
            let o = idx.map(|i| offsets.get(i).copied().unwrap_or(0));
            rows.clone()
                .map(|row| {
                    o.map(|o| {
                        let raw: [u8; 4] = row
                            .get(o..o + 4)
                            .and_then(|b| b.try_into().ok())
                            .unwrap_or_default();
                        if big_endian {
                            f32::from_be_bytes(raw)
                        } else {
                            f32::from_le_bytes(raw)
                        }
                    })
                })
                .collect()
        } else {
            rows.clone()
                .map(|row| idx.map(|i| (read(row, i) / scale) as f32))
                .collect()
        }
    };
    MeshData {
        vertices: triple(layout.position, 1.0),
        normals: layout.normal.map(|n| triple(n, 1.0)),
        colors: layout.color.map(|(c, s)| triple(c, s)),
        uvs: layout.uv.map(|uv| {
            rows.clone()
                .map(|row| uv.map(|i| read(row, i) as f32))
                .collect()
        }),
        triangles: Vec::new(),
    }
}

/// Faces stored as `uchar 3` + three 32-bit indices and nothing else: checked and converted
/// in parallel. `None` when the layout or any count differs (then the general path runs).
fn binary_triangle_fast_path(
    body: &[u8],
    element: &Element,
    big_endian: bool,
) -> Option<(Vec<[u32; 3]>, usize)> {
    let [property] = element.properties.as_slice() else {
        return None;
    };
    let Kind::List {
        count: Scalar::U8,
        item: item @ (Scalar::I32 | Scalar::U32),
    } = property.kind
    else {
        return None;
    };
    let used = usize::try_from(element.count).ok()?.checked_mul(13)?;
    let block = body.get(..used)?;
    if !block
        .par_chunks_exact(13)
        .all(|row| row.first() == Some(&3))
    {
        return None;
    }
    let triangles = block
        .par_chunks_exact(13)
        .map(|row| {
            [1usize, 5, 9].map(|o| {
                let raw: [u8; 4] = row
                    .get(o..o + 4)
                    .and_then(|b| b.try_into().ok())
                    .unwrap_or_default();
                let value = if big_endian {
                    u32::from_be_bytes(raw)
                } else {
                    u32::from_le_bytes(raw)
                };
                // A negative i32 becomes >= 2^31 here and fails the range check.
                if item == Scalar::I32 && value > i32::MAX as u32 {
                    u32::MAX
                } else {
                    value
                }
            })
        })
        .collect();
    Some((triangles, used))
}

/// One general binary face row; returns its byte size, or a message (empty = truncated).
fn binary_face(
    row: &[u8],
    element: &Element,
    list: usize,
    big_endian: bool,
    vertex_count: u64,
    out: &mut Vec<[u32; 3]>,
) -> std::result::Result<usize, String> {
    let mut offset = 0usize;
    for (i, property) in element.properties.iter().enumerate() {
        match property.kind {
            Kind::Scalar(s) => offset += s.size(),
            Kind::List { count, item } => {
                let n = row
                    .get(offset..)
                    .and_then(|b| count.read_int(b, big_endian))
                    .ok_or_else(String::new)?;
                let n = usize::try_from(n).map_err(|_| format!("negative list length {n}"))?;
                offset += count.size();
                let bytes = n.checked_mul(item.size()).ok_or_else(String::new)?;
                let items = row.get(offset..offset + bytes).ok_or_else(String::new)?;
                if i == list {
                    let polygon = items
                        .chunks_exact(item.size())
                        .map(|b| item.read_int(b, big_endian));
                    push_fan(polygon, vertex_count, out)?;
                }
                offset += bytes;
            }
        }
    }
    if offset > row.len() {
        return Err(String::new());
    }
    Ok(offset)
}

/// Appends all property values of one binary row to `out` (a list gives 0); returns the
/// row's byte size, or `None` when the data ends inside it.
fn binary_row_values(
    row: &[u8],
    element: &Element,
    big_endian: bool,
    out: &mut Vec<f64>,
) -> Option<usize> {
    let mut offset = 0usize;
    for property in &element.properties {
        match property.kind {
            Kind::Scalar(s) => {
                out.push(s.read(row.get(offset..)?, big_endian)?);
                offset += s.size();
            }
            Kind::List { count, item } => {
                let n = usize::try_from(count.read_int(row.get(offset..)?, big_endian)?).ok()?;
                offset = offset
                    .checked_add(count.size())?
                    .checked_add(n.checked_mul(item.size())?)?;
                out.push(0.0);
            }
        }
    }
    (offset <= row.len()).then_some(offset)
}

/// The byte size of one binary row of an element being skipped.
fn skip_binary_row(row: &[u8], element: &Element, big_endian: bool) -> Option<usize> {
    let mut scratch = Vec::with_capacity(element.properties.len());
    binary_row_values(row, element, big_endian, &mut scratch)
}

/// Encodes a mesh (or, with no triangles, a cloud) as PLY.
pub(crate) fn write_ply_bytes(mesh: &MeshData, encoding: PlyEncoding) -> Vec<u8> {
    let mut header = String::from("ply\n");
    header += match encoding {
        PlyEncoding::Ascii => "format ascii 1.0\n",
        PlyEncoding::BinaryLittleEndian => "format binary_little_endian 1.0\n",
        PlyEncoding::BinaryBigEndian => "format binary_big_endian 1.0\n",
    };
    header += "comment written by meshgnn-geometry\n";
    header += &format!("element vertex {}\n", mesh.vertices.len());
    header += "property float x\nproperty float y\nproperty float z\n";
    if mesh.normals.is_some() {
        header += "property float nx\nproperty float ny\nproperty float nz\n";
    }
    if mesh.colors.is_some() {
        header += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
    }
    if mesh.uvs.is_some() {
        header += "property float s\nproperty float t\n";
    }
    if !mesh.triangles.is_empty() {
        header += &format!(
            "element face {}\nproperty list uchar int vertex_indices\n",
            mesh.triangles.len()
        );
    }
    header += "end_header\n";
    let to_byte = |c: f32| (c.clamp(0.0, 1.0) * 255.0).round() as u8;
    let mut out = header.into_bytes();
    if encoding == PlyEncoding::Ascii {
        use std::fmt::Write;
        let mut text = String::with_capacity(mesh.vertices.len() * 40 + mesh.triangles.len() * 24);
        for (i, v) in mesh.vertices.iter().enumerate() {
            let _ = write!(text, "{} {} {}", v[0], v[1], v[2]);
            if let Some(n) = mesh.normals.as_ref().and_then(|n| n.get(i)) {
                let _ = write!(text, " {} {} {}", n[0], n[1], n[2]);
            }
            if let Some(c) = mesh.colors.as_ref().and_then(|c| c.get(i)) {
                let _ = write!(
                    text,
                    " {} {} {}",
                    to_byte(c[0]),
                    to_byte(c[1]),
                    to_byte(c[2])
                );
            }
            if let Some(t) = mesh.uvs.as_ref().and_then(|t| t.get(i)) {
                let _ = write!(text, " {} {}", t[0], t[1]);
            }
            text.push('\n');
        }
        for t in &mesh.triangles {
            let _ = writeln!(text, "3 {} {} {}", t[0], t[1], t[2]);
        }
        out.extend_from_slice(text.as_bytes());
        return out;
    }
    let big = encoding == PlyEncoding::BinaryBigEndian;
    let f = |x: f32| {
        if big {
            x.to_be_bytes()
        } else {
            x.to_le_bytes()
        }
    };
    let row = 12
        + 12 * usize::from(mesh.normals.is_some())
        + 3 * usize::from(mesh.colors.is_some())
        + 8 * usize::from(mesh.uvs.is_some());
    out.reserve(mesh.vertices.len() * row + mesh.triangles.len() * 13);
    for (i, v) in mesh.vertices.iter().enumerate() {
        v.iter().for_each(|&x| out.extend_from_slice(&f(x)));
        if let Some(n) = mesh.normals.as_ref().and_then(|n| n.get(i)) {
            n.iter().for_each(|&x| out.extend_from_slice(&f(x)));
        }
        if let Some(c) = mesh.colors.as_ref().and_then(|c| c.get(i)) {
            out.extend(c.iter().map(|&x| to_byte(x)));
        }
        if let Some(t) = mesh.uvs.as_ref().and_then(|t| t.get(i)) {
            t.iter().for_each(|&x| out.extend_from_slice(&f(x)));
        }
    }
    for t in &mesh.triangles {
        out.push(3);
        for &v in t {
            out.extend_from_slice(&if big {
                v.to_be_bytes()
            } else {
                v.to_le_bytes()
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Error;

    fn read(bytes: &[u8]) -> Result<MeshData> {
        read_ply(bytes, Path::new("t.ply"))
    }

    /// The `(element, message)` of a format error.
    fn element_of(result: Result<MeshData>) -> (String, String) {
        match result {
            Err(Error::Format {
                element, message, ..
            }) => (element, message),
            other => panic!("expected a format error, got {other:?}"),
        }
    }

    const ASCII: &str = "ply\r\nformat ascii 1.0\r\ncomment quad, pentagon, extra data\r\n\
        element vertex 5\r\nproperty float x\r\nproperty float y\r\nproperty float z\r\n\
        property float confidence\r\nproperty list uchar int tags\r\n\
        element face 2\r\nproperty uchar flags\r\nproperty list uchar int vertex_indices\r\n\
        property list uchar float texcoord\r\n\
        element edge 1\r\nproperty int vertex1\r\nproperty int vertex2\r\nend_header\r\n\
        0 0 0 0.5 2 7 8\r\n1 0 0 0.5 0\r\n1 1 0 0.5 0\r\n0 1 0 0.5 1 9\r\n0.5 2 0.25 1 0\r\n\
        \r\n0 4 0 1 2 3 0\r\n1 5 0 1 4 2 3 2 0.5 0.5\r\n0 1\r\n";

    #[test]
    fn ascii_quads_and_pentagons_fan_triangulate_skipping_extra_data() {
        let mesh = read(ASCII.as_bytes()).unwrap();
        assert_eq!(
            mesh.vertices,
            vec![
                [0.0; 3],
                [1.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.5, 2.0, 0.25]
            ]
        );
        assert_eq!(
            mesh.triangles,
            vec![[0, 1, 2], [0, 2, 3], [0, 1, 4], [0, 4, 2], [0, 2, 3]]
        );
        assert!(mesh.normals.is_none() && mesh.colors.is_none());
    }

    #[test]
    fn binary_general_layout_with_doubles_shorts_and_skipped_elements() {
        // element material (list, skipped), vertex as double + uchar colours, face with
        // ushort count and uint indices plus a trailing float.
        let mut bytes = b"ply\nformat binary_little_endian 1.0\n\
            element material 2\nproperty list uchar float data\n\
            element vertex 4\nproperty double x\nproperty double y\nproperty double z\n\
            property uchar red\nproperty uchar green\nproperty uchar blue\n\
            element face 1\nproperty list ushort uint vertex_index\nproperty float quality\n\
            end_header\n"
            .to_vec();
        bytes.extend([1u8]);
        bytes.extend(1.5f32.to_le_bytes());
        bytes.extend([2u8]);
        bytes.extend(2.5f32.to_le_bytes());
        bytes.extend(3.5f32.to_le_bytes());
        let positions = [
            [0.0f64, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [2.0, 2.0, 0.0],
            [0.0, 2.0, -1.0],
        ];
        for (i, p) in positions.iter().enumerate() {
            p.iter().for_each(|x| bytes.extend(x.to_le_bytes()));
            bytes.extend([255u8, 0, (i * 85) as u8]);
        }
        bytes.extend(4u16.to_le_bytes());
        [3u32, 2, 1, 0]
            .iter()
            .for_each(|i| bytes.extend(i.to_le_bytes()));
        bytes.extend(0.25f32.to_le_bytes());
        let mesh = read(&bytes).unwrap();
        assert_eq!(mesh.vertices[3], [0.0, 2.0, -1.0]);
        assert_eq!(mesh.triangles, vec![[3, 2, 1], [3, 1, 0]]);
        assert_eq!(mesh.colors.unwrap()[3], [1.0, 0.0, 1.0]);
    }

    #[test]
    fn hand_written_big_endian_file_reads_with_normals() {
        let mut bytes = b"ply\nformat binary_big_endian 1.0\nelement vertex 3\n\
            property float x\nproperty float y\nproperty float z\n\
            property float nx\nproperty float ny\nproperty float nz\n\
            element face 1\nproperty list uchar int vertex_indices\nend_header\n"
            .to_vec();
        for p in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, -3.5, 0.0]] {
            p.iter().for_each(|x| bytes.extend(x.to_be_bytes()));
            [0.0f32, 0.0, 1.0]
                .iter()
                .for_each(|x| bytes.extend(x.to_be_bytes()));
        }
        bytes.push(3);
        [0i32, 1, 2]
            .iter()
            .for_each(|i| bytes.extend(i.to_be_bytes()));
        let mesh = read(&bytes).unwrap();
        assert_eq!(
            mesh.vertices,
            vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, -3.5, 0.0]]
        );
        assert_eq!(mesh.normals, Some(vec![[0.0, 0.0, 1.0]; 3]));
        assert_eq!(mesh.triangles, vec![[0, 1, 2]]);
    }

    #[test]
    fn header_only_and_faceless_files_are_point_clouds() {
        let empty = read(b"ply\nformat ascii 1.0\nend_header\n").unwrap();
        assert!(empty.vertices.is_empty() && empty.triangles.is_empty());
        let cloud = read(
            b"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n\
              property float z\nend_header\n1 2 3\n4 5 6\n",
        )
        .unwrap();
        assert_eq!(cloud.vertices, vec![[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]);
        assert!(cloud.triangles.is_empty());
    }

    #[test]
    fn written_files_round_trip_in_all_encodings() {
        let mesh = MeshData {
            vertices: vec![
                [0.1, 0.2, 0.3],
                [1e-7, -2.5e6, 3.0],
                [0.0, 1.0, f32::MIN_POSITIVE],
            ],
            triangles: vec![[0, 1, 2], [2, 1, 0]],
            normals: Some(vec![[0.0, 0.0, 1.0]; 3]),
            uvs: Some(vec![[0.25, 0.75]; 3]),
            colors: Some(vec![[1.0, 0.0, 51.0 / 255.0]; 3]),
        };
        for encoding in [
            PlyEncoding::Ascii,
            PlyEncoding::BinaryLittleEndian,
            PlyEncoding::BinaryBigEndian,
        ] {
            assert_eq!(
                read(&write_ply_bytes(&mesh, encoding)).unwrap(),
                mesh,
                "{encoding:?}"
            );
        }
    }

    #[test]
    fn errors_name_the_element() {
        let head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n\
            property float y\nproperty float z\nelement face 1\n\
            property list uchar int vertex_indices\nend_header\n";
        let cases = [
            (
                format!("{head}0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n"),
                "face 0",
                "out of range",
            ),
            (
                format!("{head}0 0 0\n1 0 0\n0 1 0\n2 0 1\n"),
                "face 0",
                "at least 3",
            ),
            (
                format!("{head}0 0 0\n1 0 0\n0 x 0\n3 0 1 2\n"),
                "vertex 2",
                "not a number",
            ),
            (format!("{head}0 0 0\n1 0 0\n"), "vertex 2", "ends"),
            (
                head.replace("ascii", "utf8"),
                "header line 2",
                "unknown format",
            ),
            (
                head.replace("element face", "elephant face"),
                "header line 7",
                "unknown header keyword",
            ),
            (
                head.replace("int vertex", "int24 vertex"),
                "header line 8",
                "unknown property type",
            ),
            (head.replace("end_header\n", ""), "header", "end_header"),
            ("plx\n".to_string(), "header line 1", "PLY"),
        ];
        for (text, element, message) in cases {
            let (e, m) = element_of(read(text.as_bytes()));
            let got = if e.starts_with("vertex") || e.starts_with("face") || e.starts_with("header")
            {
                e.clone()
            } else {
                String::new()
            };
            assert_eq!(got, element, "{text}");
            assert!(m.contains(message), "{m} lacks {message}");
        }
    }

    #[test]
    fn nan_is_named_by_the_mesh_conversion() {
        let head = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\n\
            property float y\nproperty float z\nend_header\n0 0 0\n0 inf 0\n";
        let err = read(head.as_bytes())
            .unwrap()
            .into_mesh(Path::new("t.ply"))
            .unwrap_err();
        assert!(
            matches!(err, Error::Format { ref element, .. } if element == "vertex 1"),
            "{err}"
        );
    }

    #[test]
    fn truncated_binary_names_the_row_and_hostile_counts_do_not_allocate() {
        let mut bytes = b"ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\n\
            property float x\nproperty float y\nproperty float z\nend_header\n"
            .to_vec();
        bytes.extend([0u8; 30]);
        let (element, message) = element_of(read(&bytes));
        assert_eq!(element, "vertex 2");
        assert!(message.contains("truncated"));
        let faces = b"ply\nformat binary_big_endian 1.0\nelement face 4000000000\n\
            property list uchar int vertex_indices\nend_header\n\x03\0\0\0\0";
        let (element, _) = element_of(read(faces));
        assert_eq!(element, "face 0");
        let ascii = b"ply\nformat ascii 1.0\nelement face 4000000000\n\
            property list uchar int vertex_indices\nend_header\n";
        assert_eq!(element_of(read(ascii)).0, "face 0");
    }

    #[test]
    fn binary_fast_path_checks_index_range() {
        let mut bytes = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\n\
            property float x\nproperty float y\nproperty float z\nelement face 2\n\
            property list uchar int vertex_indices\nend_header\n"
            .to_vec();
        bytes.extend([0u8; 36]);
        for t in [[0i32, 1, 2], [0, -1, 2]] {
            bytes.push(3);
            t.iter().for_each(|i| bytes.extend(i.to_le_bytes()));
        }
        assert_eq!(element_of(read(&bytes)).0, "face 1");
    }
}
