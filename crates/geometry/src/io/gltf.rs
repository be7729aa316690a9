//! glTF 2.0 reader (JSON `.gltf` and binary `.glb`) and GLB writer.
//!
//! Reading uses the `gltf` crate for the JSON document and its validation, but parses the
//! GLB container and every accessor itself with checked arithmetic (the crate's accessor
//! iterators trust offsets and types and can panic on hostile files). All triangle
//! primitives of the default scene (all scenes when none is marked default, all meshes when
//! there are no scenes) are merged, node transforms applied down the hierarchy, normals by
//! the inverse-transpose, winding flipped under a mirroring transform. `TriangleStrip` and
//! `TriangleFan` are converted to triangles; points and lines are an error for a mesh.
//! Buffers: the GLB binary chunk, base64 `data:` URIs, and (from a file only) external
//! files inside the `.gltf`'s own folder, resolved by [`GltfBuffers`] (never the crate's
//! `import`, which follows any path).
//!
//! The pieces are shared with the morph-animation reader and writer
//! ([`super::morph_animation`]): [`load_document`], [`read_primitive`], [`append_primitive`],
//! [`ElementBudget`], [`read_floats`] and, for writing, [`add_primitive`].

use super::format_error::format_error;
use super::glb_builder::{BIN_CHUNK, GlbBuilder, JSON_CHUNK, ViewTarget};
use super::gltf_buffers::GltfBuffers;
use super::mesh_data::MeshData;
use crate::error::Result;
use gltf::Semantic;
use gltf::accessor::{DataType, Dimensions};
use gltf::json::validation::Checked;
use gltf::mesh::Mode;
use std::path::Path;

/// Most node instances visited; guards against cycles and exponential instancing.
const MAX_NODE_VISITS: usize = 1 << 20;
/// Deepest node hierarchy followed.
pub(crate) const MAX_DEPTH: usize = 256;
/// Most accessor elements (vertices, attributes and indices, over all instances) read per
/// byte of buffer data. A file without reuse reads at most one element per byte (u8 indices;
/// a float position takes 12); instancing and accessors sharing bytes repeat data, which
/// this caps at 16 times so that a kilobyte of nodes cannot expand one mesh into terabytes:
/// memory stays proportional to the input.
pub(crate) const MAX_ELEMENTS_PER_BUFFER_BYTE: usize = 16;

/// A column-major 4×4 transform (`m[column][row]`, glTF's layout, §5.25 `node.matrix`).
pub(crate) type Matrix = [[f64; 4]; 4];

/// The identity transform.
pub(crate) const IDENTITY: Matrix = [
    [1.0, 0.0, 0.0, 0.0],
    [0.0, 1.0, 0.0, 0.0],
    [0.0, 0.0, 1.0, 0.0],
    [0.0, 0.0, 0.0, 1.0],
];

/// Splits a GLB container into its JSON chunk and optional binary chunk.
pub(crate) fn split_glb<'a>(bytes: &'a [u8], path: &Path) -> Result<(&'a [u8], Option<&'a [u8]>)> {
    let word = |at: usize| -> Option<u32> {
        bytes
            .get(at..at + 4)
            .and_then(|b| b.try_into().ok())
            .map(u32::from_le_bytes)
    };
    let header = |message: &str| format_error(path, "GLB header", message.to_string());
    if bytes.get(..4) != Some(b"glTF") {
        return Err(header("missing `glTF` magic"));
    }
    if word(4) != Some(2) {
        return Err(header("only glTF version 2 is supported"));
    }
    let length = word(8).ok_or_else(|| header("truncated"))? as usize;
    if length > bytes.len() || length < 12 {
        return Err(header(&format!(
            "declares {length} bytes, file has {}",
            bytes.len()
        )));
    }
    let mut chunks = Vec::new();
    let mut at = 12usize;
    while at < length {
        let element = format!("GLB chunk {}", chunks.len());
        let (Some(size), Some(kind)) = (word(at), word(at + 4)) else {
            return Err(format_error(path, element, "truncated chunk header"));
        };
        let start = at + 8;
        let end = start
            .checked_add(size as usize)
            .filter(|&e| e <= length)
            .ok_or_else(|| {
                format_error(
                    path,
                    element.clone(),
                    format!("chunk of {size} bytes runs past the end"),
                )
            })?;
        chunks.push((kind, bytes.get(start..end).unwrap_or_default()));
        at = end;
    }
    match chunks.as_slice() {
        [(JSON_CHUNK, json), rest @ ..] => {
            let bin = rest.iter().find(|(k, _)| *k == BIN_CHUNK).map(|(_, b)| *b);
            Ok((json, bin))
        }
        _ => Err(format_error(
            path,
            "GLB chunk 0",
            "first chunk must be JSON",
        )),
    }
}

/// Parses glTF or GLB `bytes` into the validated document and the bytes of its buffers.
/// `base` is the glTF file's folder, the only place external buffers may come from (`None`:
/// bytes from memory, external buffers are an error).
pub(crate) fn load_document<'a>(
    bytes: &'a [u8],
    path: &Path,
    base: Option<&Path>,
) -> Result<(gltf::Document, GltfBuffers<'a>)> {
    let (json, blob) = if bytes.starts_with(b"glTF") {
        split_glb(bytes, path)?
    } else {
        (bytes, None)
    };
    let root = gltf::json::Root::from_slice(json)
        .map_err(|e| format_error(path, "glTF document", e.to_string()))?;
    check_unvalidated_references(&root, path)?;
    let document = gltf::Document::from_json(root)
        .map_err(|e| format_error(path, "glTF document", e.to_string()))?;
    let buffers = GltfBuffers::load(&document, blob, path, base)?;
    Ok((document, buffers))
}

/// Checks the references that `gltf` would follow into a panic on a hostile file: gltf-json's
/// validation indexes `accessors[POSITION]` before checking the index, and it does not check
/// an animation channel's target at all (`Target::node` and `Target::property` unwrap it).
fn check_unvalidated_references(root: &gltf::json::Root, path: &Path) -> Result<()> {
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let position = primitive
                .attributes
                .get(&Checked::Valid(Semantic::Positions));
            if let Some(index) = position.filter(|i| i.value() >= root.accessors.len()) {
                return Err(format_error(
                    path,
                    format!("primitive {p} of mesh {m}"),
                    format!("POSITION accessor {} does not exist", index.value()),
                ));
            }
        }
    }
    for (a, animation) in root.animations.iter().enumerate() {
        for (c, channel) in animation.channels.iter().enumerate() {
            let refuse = |message: String| {
                format_error(path, format!("channel {c} of animation {a}"), message)
            };
            let node = channel.target.node.value();
            if node >= root.nodes.len() {
                return Err(refuse(format!("target node {node} does not exist")));
            }
            if channel.target.path == Checked::Invalid {
                return Err(refuse(
                    "target path is none of translation, rotation, scale, weights".into(),
                ));
            }
        }
    }
    Ok(())
}

/// Reads glTF or GLB bytes. `base` is the glTF file's folder, the only place external
/// buffers may come from (`None`: bytes from memory, external buffers are an error). With
/// `points_ok`, non-triangle primitives contribute their vertices instead of failing (for
/// point clouds).
pub(crate) fn read_gltf(
    bytes: &[u8],
    path: &Path,
    base: Option<&Path>,
    points_ok: bool,
) -> Result<MeshData> {
    let (document, buffers) = load_document(bytes, path, base)?;
    let mut budget = ElementBudget::new(&buffers);
    let mut instances: Vec<(gltf::Mesh, Matrix)> = Vec::new();
    let scenes: Vec<gltf::Scene> = match document.default_scene() {
        Some(scene) => vec![scene],
        None => document.scenes().collect(),
    };
    if scenes.is_empty() {
        instances.extend(document.meshes().map(|m| (m, IDENTITY)));
    }
    let mut visits = 0usize;
    for scene in scenes {
        let mut stack: Vec<(gltf::Node, Matrix, usize)> =
            scene.nodes().map(|n| (n, IDENTITY, 0)).collect();
        while let Some((node, parent, depth)) = stack.pop() {
            visits += 1;
            if visits > MAX_NODE_VISITS || depth > MAX_DEPTH {
                return Err(format_error(
                    path,
                    format!("node {}", node.index()),
                    "node hierarchy too deep or too many instances (a cycle?)",
                ));
            }
            let world = multiply(&parent, &local_transform(&node));
            if let Some(mesh) = node.mesh() {
                instances.push((mesh, world));
            }
            // Reverse so children come out in document order.
            let children: Vec<_> = node.children().collect();
            stack.extend(children.into_iter().rev().map(|c| (c, world, depth + 1)));
        }
    }
    let mut merged = None;
    for (mesh, world) in &instances {
        for primitive in mesh.primitives() {
            let fail = |message| format_error(path, primitive_element(&primitive, mesh), message);
            budget.charge_primitive(&primitive).map_err(fail)?;
            let part = read_primitive(&primitive, mesh, &buffers, world, points_ok, path)?;
            append_primitive(&mut merged, part).map_err(fail)?;
        }
    }
    Ok(merged.unwrap_or_default())
}

/// `primitive P of mesh M`, how errors name a primitive.
pub(crate) fn primitive_element(primitive: &gltf::Primitive, mesh: &gltf::Mesh) -> String {
    format!("primitive {} of mesh {}", primitive.index(), mesh.index())
}

/// The accessor elements a reader may still read, charged before each read: at most
/// [`MAX_ELEMENTS_PER_BUFFER_BYTE`] per byte of buffer data, so that instancing, accessors
/// sharing bytes or keyframes reusing morph targets cannot make memory outgrow the input.
#[derive(Debug)]
pub(crate) struct ElementBudget {
    limit: usize,
    spent: usize,
}

impl ElementBudget {
    /// The budget of a document whose buffers are `buffers`.
    pub(crate) fn new(buffers: &GltfBuffers<'_>) -> Self {
        Self {
            limit: buffers
                .total_len()
                .saturating_mul(MAX_ELEMENTS_PER_BUFFER_BYTE),
            spent: 0,
        }
    }

    /// Charges `elements` about to be read or produced; over the limit, the error message,
    /// naming `what` is being read.
    pub(crate) fn charge(
        &mut self,
        elements: usize,
        what: &str,
    ) -> std::result::Result<(), String> {
        self.spent = self.spent.saturating_add(elements);
        if self.spent > self.limit {
            return Err(format!(
                "{what} read over {} elements, {MAX_ELEMENTS_PER_BUFFER_BYTE} per byte of \
                 buffer data",
                self.limit
            ));
        }
        Ok(())
    }

    /// Charges every accessor [`read_primitive`] reads of `primitive`.
    pub(crate) fn charge_primitive(
        &mut self,
        primitive: &gltf::Primitive,
    ) -> std::result::Result<(), String> {
        let accessors = [
            primitive.get(&Semantic::Positions),
            primitive.get(&Semantic::Normals),
            primitive.get(&Semantic::TexCoords(0)),
            primitive.get(&Semantic::Colors(0)),
            primitive.indices(),
        ];
        let elements = accessors
            .iter()
            .flatten()
            .fold(0usize, |sum, a| sum.saturating_add(a.count()));
        self.charge(elements, "instancing and shared accessors")
    }
}

/// Reads one primitive of `mesh` placed by `world`: positions transformed, normals by the
/// inverse-transpose, uvs and colours as they are (`TEXCOORD_0`, `COLOR_0`), strips and fans
/// converted to triangles, winding flipped under a mirroring transform. Vertices keep the
/// order of the `POSITION` accessor. A non-triangle mode is an error unless `points_ok` (then
/// the primitive gives its vertices and no triangles). Errors name `primitive P of mesh M`.
pub(crate) fn read_primitive(
    primitive: &gltf::Primitive,
    mesh: &gltf::Mesh,
    buffers: &GltfBuffers<'_>,
    world: &Matrix,
    points_ok: bool,
    path: &Path,
) -> Result<MeshData> {
    let fail = |message: String| format_error(path, primitive_element(primitive, mesh), message);
    let mode = primitive.mode();
    let triangles_mode = matches!(
        mode,
        Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
    );
    if !triangles_mode && !points_ok {
        return Err(fail(format!("mode {mode:?} is not a triangle mode")));
    }
    let positions_accessor = primitive
        .get(&Semantic::Positions)
        .ok_or_else(|| fail("has no POSITION attribute".into()))?;
    let positions: Vec<[f32; 3]> =
        read_floats(&positions_accessor, buffers).map_err(|m| fail(format!("POSITION: {m}")))?;
    let count = positions.len();
    let mut part = MeshData {
        vertices: positions
            .iter()
            .map(|p| transform_point(world, p))
            .collect(),
        ..MeshData::default()
    };
    if let Some(a) = primitive.get(&Semantic::Normals) {
        let n: Vec<[f32; 3]> =
            read_floats(&a, buffers).map_err(|m| fail(format!("NORMAL: {m}")))?;
        check_count(n.len(), count).map_err(|m| fail(format!("NORMAL: {m}")))?;
        part.normals = Some(n.iter().map(|n| transform_normal(world, n)).collect());
    }
    if let Some(a) = primitive.get(&Semantic::TexCoords(0)) {
        let t: Vec<[f32; 2]> =
            read_floats(&a, buffers).map_err(|m| fail(format!("TEXCOORD_0: {m}")))?;
        check_count(t.len(), count).map_err(|m| fail(format!("TEXCOORD_0: {m}")))?;
        part.uvs = Some(t);
    }
    if let Some(a) = primitive.get(&Semantic::Colors(0)) {
        let c: Vec<[f32; 3]> = if a.dimensions() == Dimensions::Vec4 {
            let c4: Vec<[f32; 4]> =
                read_floats(&a, buffers).map_err(|m| fail(format!("COLOR_0: {m}")))?;
            c4.into_iter().map(|c| [c[0], c[1], c[2]]).collect()
        } else {
            read_floats(&a, buffers).map_err(|m| fail(format!("COLOR_0: {m}")))?
        };
        check_count(c.len(), count).map_err(|m| fail(format!("COLOR_0: {m}")))?;
        part.colors = Some(c);
    }
    if !triangles_mode {
        return Ok(part);
    }
    let indices: Vec<u32> = match primitive.indices() {
        Some(a) => read_indices(&a, buffers).map_err(|m| fail(format!("indices: {m}")))?,
        None => (0..u32::try_from(count).map_err(|_| fail("too many vertices".into()))?).collect(),
    };
    if let Some(bad) = indices.iter().find(|&&i| i as usize >= count) {
        return Err(fail(format!("index {bad} out of range ({count} vertices)")));
    }
    let mirrored = determinant3(world) < 0.0;
    let triangles = &mut part.triangles;
    let mut push = |a: u32, b: u32, c: u32| {
        triangles.push(if mirrored { [a, c, b] } else { [a, b, c] });
    };
    match mode {
        Mode::TriangleStrip => {
            for (i, w) in indices.windows(3).enumerate() {
                if let [a, b, c] = *w {
                    if i % 2 == 0 {
                        push(a, b, c)
                    } else {
                        push(b, a, c)
                    }
                }
            }
        }
        Mode::TriangleFan => {
            if let Some((&first, rest)) = indices.split_first() {
                for w in rest.windows(2) {
                    if let [b, c] = *w {
                        push(first, b, c);
                    }
                }
            }
        }
        _ => {
            if !indices.len().is_multiple_of(3) {
                return Err(fail(format!(
                    "{} indices is not a multiple of 3",
                    indices.len()
                )));
            }
            for t in indices.chunks_exact(3) {
                if let [a, b, c] = *t {
                    push(a, b, c);
                }
            }
        }
    }
    Ok(part)
}

/// Appends one primitive's content to `merged` (`None` before the first): its vertices, its
/// triangles renumbered past the vertices already there, and each attribute kept only while
/// every primitive has it.
pub(crate) fn append_primitive(
    merged: &mut Option<MeshData>,
    part: MeshData,
) -> std::result::Result<(), String> {
    let Some(out) = merged else {
        *merged = Some(part);
        return Ok(());
    };
    let too_many = || "the primitives hold more than 2^32 vertices".to_string();
    let total = out.vertices.len().checked_add(part.vertices.len());
    total
        .and_then(|total| u32::try_from(total).ok())
        .ok_or_else(too_many)?;
    // `offset + index` stays below the total, which fits in u32.
    let offset = u32::try_from(out.vertices.len()).map_err(|_| too_many())?;
    out.vertices.extend(part.vertices);
    out.triangles
        .extend(part.triangles.iter().map(|t| t.map(|v| v + offset)));
    out.normals = concatenated(out.normals.take(), part.normals);
    out.uvs = concatenated(out.uvs.take(), part.uvs);
    out.colors = concatenated(out.colors.take(), part.colors);
    Ok(())
}

/// `a` followed by `b` when both exist.
fn concatenated<T>(a: Option<Vec<T>>, b: Option<Vec<T>>) -> Option<Vec<T>> {
    match (a, b) {
        (Some(mut a), Some(b)) => {
            a.extend(b);
            Some(a)
        }
        _ => None,
    }
}

fn check_count(got: usize, expected: usize) -> std::result::Result<(), String> {
    if got == expected {
        Ok(())
    } else {
        Err(format!("{got} entries for {expected} positions"))
    }
}

/// The bytes of an accessor's elements: `(data, stride, element size)`, bounds checked.
fn accessor_bytes<'b>(
    accessor: &gltf::Accessor,
    buffers: &'b GltfBuffers<'_>,
) -> std::result::Result<(&'b [u8], usize, usize), String> {
    if accessor.sparse().is_some() {
        return Err(format!(
            "accessor {} is sparse (not supported)",
            accessor.index()
        ));
    }
    let view = accessor
        .view()
        .ok_or_else(|| format!("accessor {} has no buffer view", accessor.index()))?;
    let component = accessor.data_type().size();
    let element = component * accessor.dimensions().multiplicity();
    let stride = view.stride().unwrap_or(element);
    if stride < element {
        return Err(format!(
            "buffer view {} stride {stride} below element size {element}",
            view.index()
        ));
    }
    let buffer = buffers
        .get(view.buffer().index())
        .ok_or_else(|| format!("buffer {} is missing", view.buffer().index()))?;
    let view_bytes = view
        .offset()
        .checked_add(view.length())
        .and_then(|end| buffer.get(view.offset()..end))
        .ok_or_else(|| {
            format!(
                "buffer view {} runs past buffer {}",
                view.index(),
                view.buffer().index()
            )
        })?;
    let count = accessor.count();
    let needed = match count {
        0 => Some(0),
        n => (n - 1)
            .checked_mul(stride)
            .and_then(|s| s.checked_add(element)),
    };
    let data = needed
        .and_then(|n| accessor.offset().checked_add(n))
        .and_then(|end| view_bytes.get(accessor.offset()..end))
        .ok_or_else(|| {
            format!(
                "accessor {} runs past buffer view {}",
                accessor.index(),
                view.index()
            )
        })?;
    Ok((data, stride, element))
}

/// Reads an accessor of `N`-vectors of floats (or normalised unsigned integers).
pub(crate) fn read_floats<const N: usize>(
    accessor: &gltf::Accessor,
    buffers: &GltfBuffers<'_>,
) -> std::result::Result<Vec<[f32; N]>, String> {
    if accessor.dimensions().multiplicity() != N {
        return Err(format!(
            "accessor {} has {:?}, expected {N} components",
            accessor.index(),
            accessor.dimensions()
        ));
    }
    let kind = accessor.data_type();
    let scale = match (kind, accessor.normalized()) {
        (DataType::F32, _) => 1.0,
        (DataType::U8, true) => 255.0,
        (DataType::U16, true) => 65535.0,
        _ => {
            return Err(format!(
                "accessor {} has component type {kind:?}, expected float",
                accessor.index()
            ));
        }
    };
    let (data, stride, _) = accessor_bytes(accessor, buffers)?;
    let size = kind.size();
    let count = accessor.count();
    let mut out = Vec::with_capacity(count);
    for i in 0..count {
        let mut v = [0f32; N];
        for (c, slot) in v.iter_mut().enumerate() {
            let at = i * stride + c * size;
            let b = data.get(at..at + size).unwrap_or_default();
            *slot = match kind {
                DataType::F32 => b.try_into().map(f32::from_le_bytes).unwrap_or(f32::NAN),
                DataType::U16 => {
                    b.try_into()
                        .map(u16::from_le_bytes)
                        .map_or(f32::NAN, f32::from)
                        / scale
                }
                _ => b.first().map_or(f32::NAN, |&x| f32::from(x)) / scale,
            };
        }
        out.push(v);
    }
    Ok(out)
}

/// Reads an index accessor (scalar u8, u16 or u32).
fn read_indices(
    accessor: &gltf::Accessor,
    buffers: &GltfBuffers<'_>,
) -> std::result::Result<Vec<u32>, String> {
    if accessor.dimensions() != Dimensions::Scalar {
        return Err(format!("accessor {} must be SCALAR", accessor.index()));
    }
    let kind = accessor.data_type();
    if !matches!(kind, DataType::U8 | DataType::U16 | DataType::U32) {
        return Err(format!(
            "accessor {} has component type {kind:?}, expected an unsigned integer",
            accessor.index()
        ));
    }
    let (data, stride, size) = accessor_bytes(accessor, buffers)?;
    Ok((0..accessor.count())
        .map(|i| {
            let b = data.get(i * stride..i * stride + size).unwrap_or_default();
            match kind {
                DataType::U8 => b.first().map_or(u32::MAX, |&x| u32::from(x)),
                DataType::U16 => b
                    .try_into()
                    .map_or(u32::MAX, |b| u32::from(u16::from_le_bytes(b))),
                _ => b.try_into().map_or(u32::MAX, u32::from_le_bytes),
            }
        })
        .collect())
}

/// A node's own transform (its `matrix`, or translation · rotation · scale), §3.5.3.
pub(crate) fn local_transform(node: &gltf::Node) -> Matrix {
    node.transform().matrix().map(|c| c.map(f64::from))
}

/// `a · b` for column-major 4×4 matrices (`m[column][row]`, glTF's layout).
pub(crate) fn multiply(a: &Matrix, b: &Matrix) -> Matrix {
    std::array::from_fn(|col| {
        std::array::from_fn(|row| (0..4).map(|k| a[k][row] * b[col][k]).sum())
    })
}

/// `m · (p, 1)`: a position placed by `m`.
pub(crate) fn transform_point(m: &Matrix, p: &[f32; 3]) -> [f32; 3] {
    let p = p.map(f64::from);
    std::array::from_fn(|row| {
        (m[0][row] * p[0] + m[1][row] * p[1] + m[2][row] * p[2] + m[3][row]) as f32
    })
}

/// `m · (v, 0)`: a displacement placed by `m` (its 3×3 part; no translation).
pub(crate) fn transform_vector(m: &Matrix, v: &[f32; 3]) -> [f32; 3] {
    let v = v.map(f64::from);
    std::array::from_fn(|row| (m[0][row] * v[0] + m[1][row] * v[1] + m[2][row] * v[2]) as f32)
}

/// The 3×3 part's determinant (negative for a mirroring transform).
fn determinant3(m: &Matrix) -> f64 {
    let e = |r: usize, c: usize| m[c][r];
    e(0, 0) * (e(1, 1) * e(2, 2) - e(1, 2) * e(2, 1))
        - e(0, 1) * (e(1, 0) * e(2, 2) - e(1, 2) * e(2, 0))
        + e(0, 2) * (e(1, 0) * e(2, 1) - e(1, 1) * e(2, 0))
}

/// Transforms a normal by the inverse-transpose of the 3×3 part (the cofactor matrix, up to
/// the determinant's positive scale and sign) and renormalises it.
fn transform_normal(m: &Matrix, n: &[f32; 3]) -> [f32; 3] {
    let e = |r: usize, c: usize| m[c][r];
    // cof[r][c] = cofactor of entry (r, c).
    let cof = |r: usize, c: usize| {
        let (r1, r2) = ((r + 1) % 3, (r + 2) % 3);
        let (c1, c2) = ((c + 1) % 3, (c + 2) % 3);
        e(r1, c1) * e(r2, c2) - e(r1, c2) * e(r2, c1)
    };
    let sign = if determinant3(m) < 0.0 { -1.0 } else { 1.0 };
    let n = n.map(f64::from);
    let out: [f64; 3] =
        std::array::from_fn(|r| sign * (0..3).map(|c| cof(r, c) * n[c]).sum::<f64>());
    let length = out.iter().map(|x| x * x).sum::<f64>().sqrt();
    if length > 0.0 {
        out.map(|x| (x / length) as f32)
    } else {
        [0.0; 3]
    }
}

/// Adds `mesh`'s vertex data to `glb` and returns the JSON members of its primitive:
/// `attributes` (`POSITION` f32 with min/max, and `NORMAL`, `TEXCOORD_0`, `COLOR_0` when the
/// mesh has them), `indices` (u32) and `mode` (`TRIANGLES`, or `POINTS` without faces).
/// `mesh` has at least one vertex.
pub(crate) fn add_primitive(glb: &mut GlbBuilder, mesh: &MeshData) -> Vec<String> {
    let mut attributes = Vec::new();
    let p = glb.add_floats(&mesh.vertices, true, ViewTarget::Vertices);
    attributes.push(format!(r#""POSITION":{p}"#));
    if let Some(normals) = &mesh.normals {
        let n = glb.add_floats(normals, false, ViewTarget::Vertices);
        attributes.push(format!(r#""NORMAL":{n}"#));
    }
    if let Some(uvs) = &mesh.uvs {
        let t = glb.add_floats(uvs, false, ViewTarget::Vertices);
        attributes.push(format!(r#""TEXCOORD_0":{t}"#));
    }
    if let Some(colors) = &mesh.colors {
        let c = glb.add_floats(colors, false, ViewTarget::Vertices);
        attributes.push(format!(r#""COLOR_0":{c}"#));
    }
    let mut members = vec![format!(r#""attributes":{{{}}}"#, attributes.join(","))];
    if mesh.triangles.is_empty() {
        members.push(r#""mode":0"#.to_owned());
    } else {
        let i = glb.add_indices(&mesh.triangles);
        members.push(format!(r#""indices":{i}"#));
        members.push(r#""mode":4"#.to_owned());
    }
    members
}

/// Encodes a mesh as GLB: one node, one primitive (see [`add_primitive`]); a mesh without
/// vertices is a scene with one empty node. Fails (with the reason) beyond the 4 GiB a GLB
/// can hold.
pub(crate) fn write_glb_bytes(mesh: &MeshData) -> std::result::Result<Vec<u8>, String> {
    let mut glb = GlbBuilder::default();
    let mut members = vec![
        r#""scene":0"#.to_owned(),
        r#""scenes":[{"nodes":[0]}]"#.to_owned(),
    ];
    if mesh.vertices.is_empty() {
        members.push(r#""nodes":[{}]"#.to_owned());
    } else {
        let primitive = add_primitive(&mut glb, mesh).join(",");
        members.push(r#""nodes":[{"mesh":0}]"#.to_owned());
        members.push(format!(r#""meshes":[{{"primitives":[{{{primitive}}}]}}]"#));
    }
    glb.finish(&members)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Error;

    fn base64(bytes: &[u8]) -> String {
        const TABLE: &[u8; 64] =
            b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
        let mut out = String::new();
        for chunk in bytes.chunks(3) {
            let b = [
                chunk[0],
                *chunk.get(1).unwrap_or(&0),
                *chunk.get(2).unwrap_or(&0),
            ];
            let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
            for i in 0..4 {
                if i <= chunk.len() {
                    out.push(TABLE[((n >> (18 - 6 * i)) & 63) as usize] as char);
                } else {
                    out.push('=');
                }
            }
        }
        out
    }

    /// A strip of 4 vertices under a translated parent and a mirroring, scaling child.
    fn document(mode: u32, count: usize, uri: Option<&str>) -> String {
        let mut buffer = Vec::new();
        for p in [
            [0.0f32, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [1.0, 1.0, 1.0],
        ] {
            p.iter().for_each(|x| buffer.extend(x.to_le_bytes()));
        }
        for _ in 0..4 {
            [0.0f32, 0.0, 1.0]
                .iter()
                .for_each(|x| buffer.extend(x.to_le_bytes()));
        }
        [0u16, 1, 2, 3]
            .iter()
            .for_each(|i| buffer.extend(i.to_le_bytes()));
        let uri = uri.map_or_else(
            || format!("data:application/octet-stream;base64,{}", base64(&buffer)),
            str::to_string,
        );
        format!(
            r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
            "nodes":[{{"translation":[10,0,0],"children":[1]}},{{"scale":[2,2,-2],"mesh":0}}],
            "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"NORMAL":1}},"indices":2,"mode":{mode}}}]}}],
            "buffers":[{{"byteLength":104,"uri":"{uri}"}}],
            "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":96}},{{"buffer":0,"byteOffset":96,"byteLength":8}}],
            "accessors":[
              {{"bufferView":0,"componentType":5126,"count":{count},"type":"VEC3","min":[0,0,0],"max":[1,1,1]}},
              {{"bufferView":0,"byteOffset":48,"componentType":5126,"count":4,"type":"VEC3"}},
              {{"bufferView":1,"componentType":5123,"count":4,"type":"SCALAR"}}]}}"#
        )
    }

    fn read(json: &str, points_ok: bool) -> Result<MeshData> {
        read_gltf(json.as_bytes(), Path::new("t.gltf"), None, points_ok)
    }

    #[test]
    fn strip_under_nested_mirroring_transforms() {
        let mesh = read(&document(5, 4, None), false).unwrap();
        assert_eq!(
            mesh.vertices,
            vec![
                [10.0, 0.0, 0.0],
                [12.0, 0.0, 0.0],
                [10.0, 2.0, 0.0],
                [12.0, 2.0, -2.0]
            ]
        );
        // Strip (0 1 2), (2 1 3), flipped by the mirror.
        assert_eq!(mesh.triangles, vec![[0, 2, 1], [2, 3, 1]]);
        assert_eq!(mesh.normals, Some(vec![[0.0, 0.0, -1.0]; 4]));
    }

    #[test]
    fn fan_is_converted() {
        let mesh = read(&document(6, 4, None), false).unwrap();
        assert_eq!(mesh.triangles, vec![[0, 2, 1], [0, 3, 2]]);
    }

    #[test]
    fn points_are_an_error_for_meshes_and_vertices_for_clouds() {
        match read(&document(0, 4, None), false) {
            Err(Error::Format {
                element, message, ..
            }) => {
                assert_eq!(element, "primitive 0 of mesh 0");
                assert!(message.contains("Points"), "{message}");
            }
            other => panic!("expected an error, got {other:?}"),
        }
        assert_eq!(read(&document(0, 4, None), true).unwrap().vertices.len(), 4);
    }

    #[test]
    fn out_of_range_accessor_and_missing_buffer_are_errors() {
        match read(&document(4, 100, None), false) {
            Err(Error::Format {
                element, message, ..
            }) => {
                assert_eq!(element, "primitive 0 of mesh 0");
                assert!(message.contains("runs past"), "{message}");
            }
            other => panic!("expected an error, got {other:?}"),
        }
        match read(&document(4, 4, Some("missing.bin")), false) {
            Err(Error::Format {
                element, message, ..
            }) => {
                assert_eq!(element, r#"buffer 0 (uri "missing.bin")"#);
                assert!(message.contains("from memory have no folder"), "{message}");
            }
            other => panic!("expected an error, got {other:?}"),
        }
        let dir = tempfile::tempdir().unwrap();
        let from_file = read_gltf(
            document(4, 4, Some("missing.bin")).as_bytes(),
            &dir.path().join("t.gltf"),
            Some(dir.path()),
            false,
        );
        match from_file {
            Err(Error::Format {
                element, message, ..
            }) => {
                assert_eq!(element, r#"buffer 0 (uri "missing.bin")"#);
                assert!(message.contains("cannot resolve missing.bin"), "{message}");
            }
            other => panic!("expected an error, got {other:?}"),
        }
    }

    #[test]
    fn dangling_position_accessor_is_an_error_not_a_panic() {
        // gltf-json's own validation would index accessors[7] and panic.
        let json = document(4, 4, None).replace(r#""POSITION":0"#, r#""POSITION":7"#);
        match read(&json, false) {
            Err(Error::Format {
                element, message, ..
            }) => {
                assert_eq!(element, "primitive 0 of mesh 0");
                assert!(message.contains("POSITION accessor 7"), "{message}");
            }
            other => panic!("expected an error, got {other:?}"),
        }
    }

    #[test]
    fn glb_writer_layout_and_read_back() {
        let mesh = MeshData {
            vertices: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 2.0, -1.0]],
            triangles: vec![[0, 1, 2]],
            normals: Some(vec![[0.0, 0.0, 1.0]; 3]),
            ..MeshData::default()
        };
        let glb = write_glb_bytes(&mesh).unwrap();
        assert_eq!(&glb[..4], b"glTF");
        assert_eq!(glb.len() % 4, 0);
        assert_eq!(
            u32::from_le_bytes(glb[8..12].try_into().unwrap()) as usize,
            glb.len()
        );
        let (json, bin) = split_glb(&glb, Path::new("t.glb")).unwrap();
        let json = std::str::from_utf8(json).unwrap();
        assert!(
            json.contains(r#""min":[0.0,0.0,-1.0],"max":[1.0,2.0,0.0]"#),
            "{json}"
        );
        assert_eq!(bin.unwrap().len(), 36 + 36 + 12);
        assert_eq!(
            read_gltf(&glb, Path::new("t.glb"), None, false).unwrap(),
            mesh
        );
    }

    #[test]
    fn bad_glb_headers_are_errors() {
        let glb = write_glb_bytes(&MeshData {
            vertices: vec![[0.0; 3]; 3],
            triangles: vec![[0, 1, 2]],
            ..MeshData::default()
        })
        .unwrap();
        let mut short = glb.clone();
        short[8..12].copy_from_slice(&4u32.to_le_bytes());
        let mut long = glb.clone();
        long[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
        for bytes in [&glb[..10], &short[..], &long[..], &glb[..glb.len() - 4]] {
            assert!(matches!(
                read_gltf(bytes, Path::new("t.glb"), None, false),
                Err(Error::Format { .. })
            ));
        }
    }
}
