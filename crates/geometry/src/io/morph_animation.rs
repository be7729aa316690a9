//! [`MorphAnimation`]: a mesh animated by per-frame vertex positions (one topology), written and
//! read as a glTF 2.0 morph-target animation (GLB) that plays in any glTF viewer.
//!
//! Source: the glTF 2.0 specification (Khronos Group, 2021), §3.7.2.2 "Morph Targets", §3.11
//! "Animations" and §4.4 "Binary glTF Layout". The layout written, what the reader accepts and
//! the limits are documented on [`MorphAnimation`], where users of the crate see them. The GLB
//! container is the crate's one GLB writer ([`super::glb_builder`]); the reader shares document
//! loading, primitive reading, the accessor parser and the element budget with `read_mesh`
//! ([`super::gltf`]).

use super::atomic_write::atomic_write;
use super::format::MeshFormat;
use super::format_error::format_error;
use super::glb_builder::{FLOAT, GlbBuilder, ViewTarget};
use super::gltf::{
    ElementBudget, IDENTITY, MAX_DEPTH, Matrix, add_primitive, append_primitive, load_document,
    local_transform, multiply, primitive_element, read_floats, read_primitive, transform_vector,
};
use super::gltf_buffers::GltfBuffers;
use super::mesh_data::MeshData;
use super::read_mesh::read_file;
use crate::error::{Error, Result};
use crate::vec3::first_non_finite;
use crate::{TriMesh, vertex_normals};
use gltf::animation::{Interpolation, Property};
use rayon::prelude::*;
use std::path::Path;

/// Most floats one animation may hold, written or read: 2^28 (268 435 456 f32, 1 GiB).
const MAX_ANIMATION_FLOATS: usize = 1 << 28;

/// Most `weight × displacement` vertex updates one read may do (non-zero keyframe weights ×
/// vertices), about 4·10⁹: seconds of work, which bounds the time a small file can take.
const MAX_BLEND_TERMS: u64 = 1 << 32;

/// A mesh animated by per-frame vertex positions (one topology), as a glTF morph-target
/// animation: [`write_morph_animation`] writes it as GLB, [`read_morph_animation`] reads it.
///
/// The fields are public; [`MorphAnimation::new`] checks them, and so does every writer.
///
/// # Conventions
/// `frames: #frames × #V×3` absolute positions in the rest mesh's vertex order; times in
/// seconds, frame k at `k / fps`.
///
/// # GLB layout written
/// Sections are those of the glTF 2.0 specification.
/// - One scene, one node (`mesh: 0`), one mesh with one `TRIANGLES` primitive (§3.7.2):
///   `POSITION` the rest pose (f32, with `min`/`max`), `NORMAL` the rest mesh's normals (its
///   area-weighted [`crate::vertex_normals()`] when it has none), `TEXCOORD_0` and `COLOR_0`
///   when the mesh has them, `u32` indices.
/// - One morph target per frame (§3.7.2.2): its `POSITION` accessor holds the displacement
///   `frame − rest` (f32, with the `min`/`max` the specification requires on every `POSITION`
///   accessor). Normals are not morphed: every frame is shaded with the rest normals.
/// - `mesh.weights` all zero, so a viewer that does not play the animation shows the rest
///   pose, and `mesh.extras.targetNames` = `frame_000`, `frame_001`, ... (the names Blender
///   and three.js show; more digits past 1000 frames).
/// - One animation (§3.11) with one sampler and one channel: the input holds the keyframe
///   times `k / fps` seconds (f32 `SCALAR` with `min`/`max`), the output the weights,
///   `#frames × #frames` floats whose row k is the one-hot of target k, interpolation
///   `LINEAR`; the channel targets node 0, path `weights`. Between keyframes k and k+1 a viewer
///   blends targets k and k+1, which interpolates the two frames' positions linearly.
/// - Each accessor has its own buffer view starting on a 4-byte boundary in the GLB's binary
///   chunk (§4.4).
///
/// # Reading
/// [`read_morph_animation`] takes the first animation channel (animations, then channels, in
/// document order) whose path is `weights` and the mesh of the node it targets; the rest mesh
/// is that mesh's triangle primitives merged and placed by the node's world transform (as
/// [`crate::read_mesh`] places them), the displacements by the transform's 3×3 part. Keyframe k
/// is `rest + Σ_j w_kj Δ_j`, with `w_k` the sampler's output at its k-th input time (the
/// keyframe value for `LINEAR` and `STEP`, the middle of the three `CUBICSPLINE` values), so
/// files whose keyframes blend several targets read too. The frame rate is the inverse of the
/// keyframe spacing: times must increase and be evenly spaced (to 1% of the spacing), and a
/// rate with at most 6 decimals whose `k / fps` reproduces every time exactly is returned as
/// that number (24, 29.97). The first keyframe's time is not kept. Buffers are resolved as for
/// [`crate::read_mesh`] (GLB chunk, `data:` URIs, files inside the `.gltf`'s own folder only),
/// and accessors are read by the same bounds-checked code; sparse accessors are not supported.
///
/// # Limits
/// - Written: at least one triangle, at least 2 frames (a frame rate is a spacing of keyframe
///   times), `fps` finite and positive, every frame `#V` finite positions whose displacements
///   are finite in f32, and at most 2^28 floats (1 GiB) of data: `#frames × #V × 3`
///   displacements, `#frames²` weights, `#frames` times, `#V × 6` rest positions and normals.
///   A 5 023-vertex face (FLAME) fits about 10 500 frames (5.8 minutes at 30 fps); the one-hot
///   weights grow as `#frames²`, which is what caps long clips.
/// - Read: the keyframe positions produced (`#keyframes × #V × 3` floats) are at most 2^28
///   and, with every accessor element read, at most 16 per byte of buffer data (the bound of
///   [`crate::read_mesh`]), so memory stays proportional to the file; the blending work
///   (non-zero keyframe weights × `#V`) is at most 2^32 vertex updates.
///
/// ```
/// use meshgnn_geometry::{MorphAnimation, grid_plane};
/// let plane = grid_plane(2, 2);
/// let rest = plane.vertices().to_vec();
/// let lifted: Vec<[f32; 3]> = rest.iter().map(|p| [p[0], p[1], 0.5]).collect();
/// let animation = MorphAnimation::new(plane.clone(), vec![rest, lifted], 25.0)?;
/// assert_eq!(animation.frames.len(), 2);
/// assert!(MorphAnimation::new(plane, vec![], 25.0).is_err()); // no frames
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct MorphAnimation {
    /// The rest pose: topology, and the positions every frame is stored relative to.
    pub mesh: TriMesh,
    /// Absolute vertex positions of each frame: #frames × (#V×3).
    pub frames: Vec<Vec<[f32; 3]>>,
    /// Frames per second (> 0).
    pub fps: f64,
}

impl MorphAnimation {
    /// An animation of `mesh` through `frames: #frames × #V×3` at `fps` frames per second,
    /// checked as the writers check it: at least one triangle, at least 2 frames of `#V`
    /// finite positions, `fps` finite and positive, within the size limit (see
    /// [`MorphAnimation`]). Errors are [`Error::InvalidParameter`] naming the frame, vertex or
    /// limit.
    ///
    /// ```
    /// use meshgnn_geometry::{MorphAnimation, icosphere};
    /// let sphere = icosphere(0);
    /// let still = vec![sphere.vertices().to_vec(); 3];
    /// assert_eq!(MorphAnimation::new(sphere.clone(), still.clone(), 30.0)?.fps, 30.0);
    /// let error = MorphAnimation::new(sphere, still, 0.0).unwrap_err();
    /// assert_eq!(error.to_string(), "invalid animation: fps 0 is not a positive finite number");
    /// # Ok::<(), meshgnn_geometry::Error>(())
    /// ```
    pub fn new(mesh: TriMesh, frames: Vec<Vec<[f32; 3]>>, fps: f64) -> Result<Self> {
        let animation = Self { mesh, frames, fps };
        animation.check().map_err(invalid_animation)?;
        Ok(animation)
    }

    /// Why this animation cannot be written, if it cannot.
    fn check(&self) -> std::result::Result<(), String> {
        let vertices = self.mesh.vertex_count();
        if self.mesh.face_count() == 0 {
            return Err(
                "the rest mesh has no triangles (a glTF triangle primitive needs one)".into(),
            );
        }
        if !(self.fps.is_finite() && self.fps > 0.0) {
            return Err(format!("fps {} is not a positive finite number", self.fps));
        }
        let count = self.frames.len();
        if count < 2 {
            return Err(format!(
                "{count} frame(s): an animation needs at least 2 (its frame rate is the spacing \
                 of the keyframe times)"
            ));
        }
        let floats = stored_floats(vertices, count);
        if floats.is_none_or(|floats| floats > MAX_ANIMATION_FLOATS) {
            return Err(format!(
                "{count} frames of {vertices} vertices need over {MAX_ANIMATION_FLOATS} floats \
                 (#frames × #V × 3 + #frames² + #frames + #V × 6, 1 GiB), the most one \
                 animation may hold; write shorter clips"
            ));
        }
        let rest = self.mesh.vertices();
        for (k, frame) in self.frames.iter().enumerate() {
            if frame.len() != vertices {
                return Err(format!(
                    "frame {k} has {} positions, the mesh has {vertices} vertices",
                    frame.len()
                ));
            }
            if let Some(i) = first_non_finite(frame) {
                return Err(format!("frame {k}: vertex {i} has a non-finite position"));
            }
            let overflow = frame
                .iter()
                .zip(rest)
                .position(|(p, r)| (0..3).any(|c| !(p[c] - r[c]).is_finite()));
            if let Some(i) = overflow {
                return Err(format!(
                    "frame {k}: vertex {i} moves further from the rest pose than f32 can hold"
                ));
            }
        }
        let times = keyframe_times(count, self.fps);
        if times
            .windows(2)
            .any(|w| !(w[1][0] > w[0][0] && w[1][0].is_finite()))
        {
            return Err(format!(
                "fps {} gives keyframe times k / fps that f32 cannot tell apart",
                self.fps
            ));
        }
        Ok(())
    }
}

/// Floats stored for `frames` frames of `vertices` vertices: displacements, one-hot weights,
/// times, rest positions and normals; `None` past `usize`.
fn stored_floats(vertices: usize, frames: usize) -> Option<usize> {
    let displacements = frames.checked_mul(vertices)?.checked_mul(3)?;
    let weights = frames.checked_mul(frames)?;
    let rest = vertices.checked_mul(6)?;
    displacements
        .checked_add(weights)?
        .checked_add(frames)?
        .checked_add(rest)
}

/// Keyframe k at `k / fps` seconds, as stored (f32).
fn keyframe_times(frames: usize, fps: f64) -> Vec<[f32; 1]> {
    (0..frames).map(|k| [(k as f64 / fps) as f32]).collect()
}

/// A refusal of the writer or the constructor.
fn invalid_animation(message: String) -> Error {
    Error::InvalidParameter {
        name: "animation",
        message,
    }
}

/// Writes `animation` to `path` as a GLB morph-target animation (layout: [`MorphAnimation`]),
/// atomically ([`crate::atomic_write`]: temporary file in the same folder, then rename).
///
/// The path must end in `.glb`. Errors: [`Error::InvalidParameter`] naming the file and the
/// problem (another extension, a frame of the wrong length, a non-finite position, fewer than
/// 2 frames, `fps` not positive, over the size limit), [`Error::Io`] when the file cannot be
/// written. Like [`crate::write_mesh`], it writes where it is told: a command builds an
/// [`crate::OutputGuard`] over its inputs and checks its output with it before any work, so
/// that no input is ever overwritten.
///
/// ```
/// use meshgnn_geometry::{MorphAnimation, OutputGuard, icosphere};
/// use meshgnn_geometry::{read_morph_animation, write_morph_animation};
/// # let dir = tempfile::tempdir()?;
/// let sphere = icosphere(1);
/// let scaled = |s: f32| sphere.vertices().iter().map(|p| p.map(|x| x * s)).collect();
/// let frames: Vec<Vec<[f32; 3]>> = (0..4).map(|k| scaled(1.0 + 0.1 * k as f32)).collect();
/// let animation = MorphAnimation::new(sphere, frames, 24.0)?;
/// let input = dir.path().join("template.obj");
/// let output = dir.path().join("breathing.glb");
/// OutputGuard::new([&input]).check(&output)?;
/// write_morph_animation(&output, &animation)?;
/// let read = read_morph_animation(&output)?;
/// assert_eq!(read.fps, 24.0);
/// assert!((read.frames[3][0][0] - animation.frames[3][0][0]).abs() < 1e-6);
/// assert!(write_morph_animation(dir.path().join("breathing.gltf"), &animation).is_err());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn write_morph_animation(path: impl AsRef<Path>, animation: &MorphAnimation) -> Result<()> {
    let path = path.as_ref();
    let refuse = |message: String| invalid_animation(format!("{}: {message}", path.display()));
    if MeshFormat::from_path(path).ok() != Some(MeshFormat::Glb) {
        return Err(refuse(
            "a morph animation is written as GLB: name the file .glb".into(),
        ));
    }
    let bytes = encode(animation).map_err(refuse)?;
    atomic_write(path, &bytes)
}

/// The GLB bytes [`write_morph_animation`] writes (layout: [`MorphAnimation`]); errors are
/// [`Error::InvalidParameter`] naming the problem.
///
/// ```
/// use meshgnn_geometry::{MeshFormat, MorphAnimation, grid_plane};
/// use meshgnn_geometry::{morph_animation_glb_bytes, read_mesh_bytes};
/// let plane = grid_plane(3, 3);
/// let rest = plane.vertices().to_vec();
/// let raised: Vec<[f32; 3]> = rest.iter().map(|p| [p[0], p[1], p[0] * p[1]]).collect();
/// let animation = MorphAnimation::new(plane.clone(), vec![rest, raised], 10.0)?;
/// let glb = morph_animation_glb_bytes(&animation)?;
/// assert_eq!(&glb[..4], b"glTF");
/// assert_eq!(glb.len() % 4, 0);
/// // a mesh reader sees the rest pose (with the normals the writer adds)
/// assert_eq!(read_mesh_bytes(&glb, MeshFormat::Glb)?.vertices(), plane.vertices());
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn morph_animation_glb_bytes(animation: &MorphAnimation) -> Result<Vec<u8>> {
    encode(animation).map_err(invalid_animation)
}

/// Encodes `animation` as GLB, or says why it cannot.
fn encode(animation: &MorphAnimation) -> std::result::Result<Vec<u8>, String> {
    animation.check()?;
    let mesh = &animation.mesh;
    let mut rest = MeshData::from_mesh(mesh);
    if rest.normals.is_none() {
        rest.normals = Some(vertex_normals(mesh));
    }
    let mut glb = GlbBuilder::default();
    let mut primitive = add_primitive(&mut glb, &rest);
    let mut displacement = Vec::with_capacity(rest.vertices.len());
    let mut targets = Vec::with_capacity(animation.frames.len());
    for frame in &animation.frames {
        displacement.clear();
        displacement.extend(
            frame
                .iter()
                .zip(&rest.vertices)
                .map(|(p, r)| [p[0] - r[0], p[1] - r[1], p[2] - r[2]]),
        );
        let accessor = glb.add_floats(&displacement, true, ViewTarget::Vertices);
        targets.push(format!(r#"{{"POSITION":{accessor}}}"#));
    }
    primitive.push(format!(r#""targets":[{}]"#, targets.join(",")));
    let count = animation.frames.len();
    let input = glb.add_floats(
        &keyframe_times(count, animation.fps),
        true,
        ViewTarget::None,
    );
    let one_hot = (0..count)
        .flat_map(move |k| (0..count).map(move |j| if j == k { 1.0f32 } else { 0.0 }))
        .flat_map(f32::to_le_bytes);
    let output = glb.add(
        one_hot,
        &format!(
            r#""componentType":{FLOAT},"count":{},"type":"SCALAR""#,
            count * count
        ),
        ViewTarget::None,
    );
    let width = (count - 1).to_string().len().max(3);
    let names: Vec<String> = (0..count)
        .map(|k| format!(r#""frame_{k:0width$}""#))
        .collect();
    let weights = vec!["0"; count].join(",");
    let members = [
        r#""scene":0"#.to_owned(),
        r#""scenes":[{"nodes":[0]}]"#.to_owned(),
        r#""nodes":[{"mesh":0}]"#.to_owned(),
        format!(
            r#""meshes":[{{"primitives":[{{{}}}],"weights":[{weights}],"extras":{{"targetNames":[{}]}}}}]"#,
            primitive.join(","),
            names.join(",")
        ),
        format!(
            r#""animations":[{{"channels":[{{"sampler":0,"target":{{"node":0,"path":"weights"}}}}],"samplers":[{{"input":{input},"interpolation":"LINEAR","output":{output}}}]}}]"#
        ),
    ];
    glb.finish(&members)
}

/// Reads a morph-target animation from a `.glb` or `.gltf` file (what is read and the limits:
/// [`MorphAnimation`]); the inverse of [`write_morph_animation`].
///
/// Errors: [`Error::Io`] when the file cannot be read, [`Error::InvalidParameter`] for another
/// extension, and one-line [`Error::Format`] naming the file, the element (`channel 0 of
/// animation 0`, `primitive 0 of mesh 0`, `keyframe 3`) and the problem: no animation of
/// morph-target weights, weights of the wrong count, times not increasing or not evenly
/// spaced, malformed or truncated content, refused buffers, over the limits.
///
/// ```
/// use meshgnn_geometry::{MorphAnimation, grid_plane, read_morph_animation, write_morph_animation};
/// # let dir = tempfile::tempdir()?;
/// let plane = grid_plane(2, 2);
/// let wave: Vec<Vec<[f32; 3]>> = (0..3)
///     .map(|k| plane.vertices().iter().map(|p| [p[0], p[1], 0.25 * k as f32]).collect())
///     .collect();
/// let path = dir.path().join("wave.glb");
/// write_morph_animation(&path, &MorphAnimation::new(plane, wave, 12.5)?)?;
/// let read = read_morph_animation(&path)?;
/// assert_eq!((read.frames.len(), read.fps), (3, 12.5));
/// assert_eq!(read.frames[2][0][2], 0.5);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn read_morph_animation(path: impl AsRef<Path>) -> Result<MorphAnimation> {
    let path = path.as_ref();
    if !matches!(
        MeshFormat::from_path(path),
        Ok(MeshFormat::Glb | MeshFormat::Gltf)
    ) {
        return Err(Error::InvalidParameter {
            name: "path",
            message: format!(
                "{}: a morph animation is read from a .glb or .gltf file",
                path.display()
            ),
        });
    }
    let bytes = read_file(path)?;
    parse_morph_animation(&bytes, path, path.parent())
}

/// Parses glTF or GLB `bytes` into an animation; `path` names the source in errors, `base` is
/// the folder external buffers may come from (`None`: bytes from memory, none may).
pub(crate) fn parse_morph_animation(
    bytes: &[u8],
    path: &Path,
    base: Option<&Path>,
) -> Result<MorphAnimation> {
    let (document, buffers) = load_document(bytes, path, base)?;
    let mut budget = ElementBudget::new(&buffers);
    let channel = document
        .animations()
        .flat_map(|animation| animation.channels())
        .find(|channel| channel.target().property() == Property::MorphTargetWeights)
        .ok_or_else(|| {
            format_error(
                path,
                "glTF document",
                "no animation channel targets morph-target weights (path \"weights\")",
            )
        })?;
    let channel_element = format!(
        "channel {} of animation {}",
        channel.index(),
        channel.animation().index()
    );
    let channel_error = |message: String| format_error(path, channel_element.clone(), message);
    let node = channel.target().node();
    let mesh = node.mesh().ok_or_else(|| {
        channel_error(format!("targets node {}, which has no mesh", node.index()))
    })?;
    let world = world_transform(&document, node.index())
        .map_err(|message| format_error(path, format!("node {}", node.index()), message))?;
    let (rest, displacements) = read_morph_targets(&mesh, &buffers, &world, &mut budget, path)?;
    let rest = rest.into_mesh(path)?;

    let sampler = channel.sampler();
    let sampler_error = |message: String| {
        format_error(
            path,
            format!(
                "sampler {} of animation {}",
                sampler.index(),
                channel.animation().index()
            ),
            message,
        )
    };
    let input = sampler.input();
    budget
        .charge(input.count(), "keyframe times")
        .map_err(sampler_error)?;
    let times: Vec<[f32; 1]> =
        read_floats(&input, &buffers).map_err(|m| sampler_error(format!("input: {m}")))?;
    let fps = frame_rate(&times).map_err(sampler_error)?;
    let keyframes = times.len();
    let targets = displacements.len();
    let (values_per_keyframe, value_at) = match sampler.interpolation() {
        Interpolation::CubicSpline => (3, 1),
        Interpolation::Linear | Interpolation::Step => (1, 0),
    };
    let output = sampler.output();
    let expected = keyframes
        .checked_mul(targets)
        .and_then(|n| n.checked_mul(values_per_keyframe));
    if expected != Some(output.count()) {
        let per = if values_per_keyframe == 3 {
            " × 3 (CUBICSPLINE)"
        } else {
            ""
        };
        return Err(sampler_error(format!(
            "output accessor {} holds {} weights, expected {keyframes} keyframes × {targets} \
             morph targets{per}",
            output.index(),
            output.count()
        )));
    }
    budget
        .charge(output.count(), "animation weights")
        .map_err(sampler_error)?;
    let weights: Vec<[f32; 1]> =
        read_floats(&output, &buffers).map_err(|m| sampler_error(format!("output: {m}")))?;
    let rows: Vec<&[[f32; 1]]> = (0..keyframes)
        .map(|k| {
            let start = (k * values_per_keyframe + value_at) * targets;
            weights.get(start..start + targets).unwrap_or_default()
        })
        .collect();

    let vertices = rest.vertex_count();
    let positions = keyframes.saturating_mul(vertices);
    budget
        .charge(positions, "morph targets and keyframe positions")
        .map_err(channel_error)?;
    if positions.saturating_mul(3) > MAX_ANIMATION_FLOATS {
        return Err(channel_error(format!(
            "{keyframes} keyframes of {vertices} vertices are over {MAX_ANIMATION_FLOATS} floats, \
             the most one animation may hold"
        )));
    }
    let non_zero = rows
        .iter()
        .flat_map(|row| row.iter())
        .filter(|w| w[0] != 0.0);
    let terms = (non_zero.count() as u64).saturating_mul(vertices as u64);
    if terms > MAX_BLEND_TERMS {
        return Err(channel_error(format!(
            "blending the keyframes takes {terms} weight × displacement updates, over the \
             limit of {MAX_BLEND_TERMS}"
        )));
    }
    let frames: Vec<Vec<[f32; 3]>> = rows
        .par_iter()
        .map(|row| blend(rest.vertices(), &displacements, row))
        .collect();
    for (k, frame) in frames.iter().enumerate() {
        if let Some(i) = first_non_finite(frame) {
            return Err(format_error(
                path,
                format!("keyframe {k}"),
                format!("vertex {i}: the weighted morph targets give a non-finite position"),
            ));
        }
    }
    Ok(MorphAnimation {
        mesh: rest,
        frames,
        fps,
    })
}

/// The rest pose of `mesh` (its triangle primitives merged, placed by `world`) and each morph
/// target's displacements over all primitives, `#targets × #V×3`, placed by `world`'s 3×3 part.
fn read_morph_targets(
    mesh: &gltf::Mesh,
    buffers: &GltfBuffers<'_>,
    world: &Matrix,
    budget: &mut ElementBudget,
    path: &Path,
) -> Result<(MeshData, Vec<Vec<[f32; 3]>>)> {
    let mut merged = None;
    let mut displacements: Option<Vec<Vec<[f32; 3]>>> = None;
    for primitive in mesh.primitives() {
        let element = primitive_element(&primitive, mesh);
        let fail = |message: String| format_error(path, element.clone(), message);
        budget.charge_primitive(&primitive).map_err(fail)?;
        let part = read_primitive(&primitive, mesh, buffers, world, false, path)?;
        let count = part.vertices.len();
        let targets: Vec<gltf::mesh::MorphTarget> = primitive.morph_targets().collect();
        let all = displacements.get_or_insert_with(|| vec![Vec::new(); targets.len()]);
        if all.len() != targets.len() {
            return Err(fail(format!(
                "{} morph targets, the mesh's first primitive has {} (glTF 2.0 §3.7.2.2: all \
                 primitives of a mesh have the same number)",
                targets.len(),
                all.len()
            )));
        }
        for (j, (target, out)) in targets.iter().zip(all.iter_mut()).enumerate() {
            budget.charge(count, "morph targets").map_err(fail)?;
            let Some(accessor) = target.positions() else {
                // a target without POSITION does not move the vertices
                out.extend(std::iter::repeat_n([0.0; 3], count));
                continue;
            };
            let moved: Vec<[f32; 3]> = read_floats(&accessor, buffers)
                .map_err(|m| fail(format!("morph target {j} POSITION: {m}")))?;
            if moved.len() != count {
                return Err(fail(format!(
                    "morph target {j} POSITION: {} displacements for {count} positions",
                    moved.len()
                )));
            }
            out.extend(moved.iter().map(|d| transform_vector(world, d)));
        }
        append_primitive(&mut merged, part).map_err(fail)?;
    }
    let no_primitive = || format_error(path, format!("mesh {}", mesh.index()), "has no primitives");
    let merged = merged.ok_or_else(no_primitive)?;
    let displacements = displacements.unwrap_or_default();
    if displacements.is_empty() {
        return Err(format_error(
            path,
            format!("mesh {}", mesh.index()),
            "has no morph targets, so its weights animate nothing",
        ));
    }
    Ok((merged, displacements))
}

/// `rest + Σ_j w_j Δ_j` for one keyframe (`row: #targets`, `displacements: #targets × #V×3`),
/// accumulated in f64; zero weights are skipped.
fn blend(rest: &[[f32; 3]], displacements: &[Vec<[f32; 3]>], row: &[[f32; 1]]) -> Vec<[f32; 3]> {
    let mut sum: Vec<[f64; 3]> = rest.iter().map(|p| p.map(f64::from)).collect();
    for (&[w], target) in row.iter().zip(displacements) {
        if w == 0.0 {
            continue;
        }
        let w = f64::from(w);
        for (s, d) in sum.iter_mut().zip(target) {
            for c in 0..3 {
                s[c] += w * f64::from(d[c]);
            }
        }
    }
    sum.into_iter().map(|s| s.map(|x| x as f32)).collect()
}

/// The transform placing node `index` in the scene: its ancestors' transforms, root first,
/// then its own (§3.5.3 "Transformations"). A node listed as a child twice (invalid glTF)
/// takes the first parent; a chain deeper than `MAX_DEPTH` (a cycle) is an error.
fn world_transform(document: &gltf::Document, index: usize) -> std::result::Result<Matrix, String> {
    let nodes: Vec<gltf::Node> = document.nodes().collect();
    let mut parent: Vec<Option<usize>> = vec![None; nodes.len()];
    for node in &nodes {
        for child in node.children() {
            if let Some(slot @ None) = parent.get_mut(child.index()) {
                *slot = Some(node.index());
            }
        }
    }
    let mut chain = vec![index];
    let mut at = index;
    while let Some(&Some(up)) = parent.get(at) {
        if chain.len() > MAX_DEPTH {
            return Err(format!(
                "node hierarchy deeper than {MAX_DEPTH} above the animated node (a cycle?)"
            ));
        }
        chain.push(up);
        at = up;
    }
    Ok(chain
        .iter()
        .rev()
        .filter_map(|&n| nodes.get(n))
        .fold(IDENTITY, |world, node| {
            multiply(&world, &local_transform(node))
        }))
}

/// The frame rate of keyframe `times` (seconds), or why they give none: at least two, finite,
/// increasing and evenly spaced to 1% of the spacing (plus f32 rounding). Times starting at 0
/// that are exactly `k / r` in f32 for a rate `r` with at most 6 decimals give that `r`;
/// otherwise the inverse of the mean spacing.
fn frame_rate(times: &[[f32; 1]]) -> std::result::Result<f64, String> {
    let t: Vec<f64> = times.iter().map(|&[x]| f64::from(x)).collect();
    let (Some(&first), Some(&last)) = (t.first(), t.last()) else {
        return Err("no keyframes".into());
    };
    if t.len() < 2 {
        return Err("one keyframe: a frame rate needs the spacing of at least two".into());
    }
    if let Some(k) = t.iter().position(|x| !x.is_finite()) {
        return Err(format!("keyframe {k}'s time is not finite"));
    }
    if let Some(k) = t.windows(2).position(|w| w[1] <= w[0]) {
        return Err(format!(
            "keyframe times do not increase: {} s at keyframe {k}, then {} s",
            t[k],
            t[k + 1]
        ));
    }
    let spacing = (last - first) / (t.len() - 1) as f64;
    for (k, &x) in t.iter().enumerate() {
        let expected = first + k as f64 * spacing;
        let rounding = 4.0 * f64::from(f32::EPSILON) * x.abs().max(expected.abs());
        if (x - expected).abs() > 0.01 * spacing + rounding {
            return Err(format!(
                "keyframe times are not evenly spaced: keyframe {k} at {x} s, expected \
                 {expected} s ({spacing} s apart from {first} s)"
            ));
        }
    }
    let rate = 1.0 / spacing;
    if first == 0.0 {
        for decimals in 0..=6 {
            let scale = 10f64.powi(decimals);
            let candidate = (rate * scale).round() / scale;
            let exact = candidate > 0.0
                && t.iter()
                    .enumerate()
                    .all(|(k, &x)| (k as f64 / candidate) as f32 == x as f32);
            if exact {
                return Ok(candidate);
            }
        }
    }
    Ok(rate)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::format_error::MEMORY;
    use crate::io::glb_builder::glb_container;
    use crate::io::gltf::split_glb;
    use crate::{icosphere, read_mesh};
    use proptest::prelude::*;

    /// `parse_morph_animation` on bytes from memory.
    fn parse_bytes(bytes: &[u8]) -> Result<MorphAnimation> {
        parse_morph_animation(bytes, Path::new(MEMORY), None)
    }

    /// An icosphere whose vertices move by a known function of the frame over 5 frames.
    fn moving_sphere() -> MorphAnimation {
        let sphere = icosphere(2);
        let frames = (0..5)
            .map(|k| {
                let t = k as f32 * 0.25;
                sphere
                    .vertices()
                    .iter()
                    .map(|p| {
                        [
                            p[0] * (1.0 + 0.3 * t),
                            p[1] + 0.2 * (t * p[0]).sin(),
                            p[2] - t,
                        ]
                    })
                    .collect()
            })
            .collect();
        MorphAnimation::new(sphere, frames, 24.0).unwrap()
    }

    fn assert_close(read: &MorphAnimation, written: &MorphAnimation) {
        assert_eq!(read.frames.len(), written.frames.len());
        for (k, (a, b)) in read.frames.iter().zip(&written.frames).enumerate() {
            assert_eq!(a.len(), b.len());
            for (i, (p, q)) in a.iter().zip(b).enumerate() {
                for c in 0..3 {
                    assert!(
                        (p[c] - q[c]).abs() <= 1e-6,
                        "frame {k} vertex {i}: {p:?} {q:?}"
                    );
                }
            }
        }
    }

    /// The JSON chunk and the binary chunk of a GLB this crate wrote.
    fn chunks(glb: &[u8]) -> (String, Vec<u8>) {
        let (json, bin) = split_glb(glb, Path::new(MEMORY)).unwrap();
        (
            String::from_utf8(json.to_vec()).unwrap(),
            bin.unwrap().to_vec(),
        )
    }

    /// A GLB of `json` and `bin`.
    fn glb_of(json: &str, bin: &[u8]) -> Vec<u8> {
        glb_container(json.as_bytes(), bin).unwrap()
    }

    /// A triangle with two morph targets (+x and +y), under a node translated by (0, 0, 10),
    /// animated by `weights` (rows of 2) at `times` with `interpolation`.
    fn two_target_triangle(times: &[f32], weights: &[f32], interpolation: &str) -> Vec<u8> {
        let mut glb = GlbBuilder::default();
        let rest = MeshData {
            vertices: vec![[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            triangles: vec![[0, 1, 2]],
            ..MeshData::default()
        };
        let primitive = add_primitive(&mut glb, &rest).join(",");
        let x = glb.add_floats(&[[1.0f32, 0.0, 0.0]; 3], true, ViewTarget::Vertices);
        let y = glb.add_floats(&[[0.0f32, 1.0, 0.0]; 3], true, ViewTarget::Vertices);
        let times: Vec<[f32; 1]> = times.iter().map(|&t| [t]).collect();
        let input = glb.add_floats(&times, true, ViewTarget::None);
        let weights: Vec<[f32; 1]> = weights.iter().map(|&w| [w]).collect();
        let output = glb.add_floats(&weights, false, ViewTarget::None);
        glb.finish(&[
            r#""scene":0,"scenes":[{"nodes":[0]}]"#.to_owned(),
            r#""nodes":[{"children":[1]},{"mesh":0,"translation":[0,0,10]}]"#.to_owned(),
            format!(
                r#""meshes":[{{"primitives":[{{{primitive},"targets":[{{"POSITION":{x}}},{{"POSITION":{y}}}]}}]}}]"#
            ),
            format!(
                r#""animations":[{{"channels":[{{"sampler":0,"target":{{"node":1,"path":"weights"}}}}],"samplers":[{{"input":{input},"output":{output},"interpolation":"{interpolation}"}}]}}]"#
            ),
        ])
        .unwrap()
    }

    fn format_message(result: Result<MorphAnimation>) -> (String, String) {
        match result {
            Err(Error::Format {
                element, message, ..
            }) => (element, message),
            other => panic!("expected a format error, got {other:?}"),
        }
    }

    #[test]
    fn round_trip_of_a_moving_icosphere() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("moving.glb");
        let written = moving_sphere();
        write_morph_animation(&path, &written).unwrap();
        let read = read_morph_animation(&path).unwrap();
        assert_eq!(read.fps, written.fps);
        assert_eq!(read.mesh.vertices(), written.mesh.vertices());
        assert_eq!(read.mesh.triangles(), written.mesh.triangles());
        assert_eq!(
            read.mesh.normals(),
            Some(&vertex_normals(&written.mesh)[..])
        );
        assert_close(&read, &written);
        // a mesh with its own normals reads back equal, normals included
        let with_normals = MorphAnimation {
            mesh: written
                .mesh
                .clone()
                .with_normals(vertex_normals(&written.mesh))
                .unwrap(),
            ..written
        };
        write_morph_animation(&path, &with_normals).unwrap();
        let read = read_morph_animation(&path).unwrap();
        assert_eq!(read.mesh, with_normals.mesh);
        assert_close(&read, &with_normals);
    }

    #[test]
    fn read_mesh_on_the_written_glb_gives_the_rest_mesh() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("moving.glb");
        let animation = moving_sphere();
        write_morph_animation(&path, &animation).unwrap();
        let rest = read_mesh(&path).unwrap();
        assert_eq!(rest.vertices(), animation.mesh.vertices());
        assert_eq!(rest.triangles(), animation.mesh.triangles());
    }

    #[test]
    fn layout_names_targets_zeroes_weights_and_animates_them_linearly() {
        let animation = moving_sphere();
        let glb = morph_animation_glb_bytes(&animation).unwrap();
        assert_eq!(glb.len() % 4, 0);
        let (json, bin) = chunks(&glb);
        assert_eq!(bin.len() % 4, 0);
        for expected in [
            r#""targetNames":["frame_000","frame_001","frame_002","frame_003","frame_004"]"#,
            r#""weights":[0,0,0,0,0]"#,
            r#""target":{"node":0,"path":"weights"}"#,
            r#""interpolation":"LINEAR""#,
            r#""targets":[{"POSITION":3},{"POSITION":4},"#,
            // keyframe times k / 24 with their bounds, then 25 one-hot weights
            r#""count":5,"type":"SCALAR","min":[0.0],"max":[0.16666667]}"#,
            r#""count":25,"type":"SCALAR"}"#,
        ] {
            assert!(json.contains(expected), "{expected} missing from {json}");
        }
        // every POSITION accessor (rest and the 5 targets) has min and max
        assert_eq!(json.matches(r#""type":"VEC3","min""#).count(), 6);
        // the last target's bounds are those of `frame 4 − rest`
        let mut max = [f32::NEG_INFINITY; 3];
        for (p, r) in animation.frames[4].iter().zip(animation.mesh.vertices()) {
            for c in 0..3 {
                max[c] = max[c].max(p[c] - r[c]);
            }
        }
        let bounds = format!(r#""max":[{:?},{:?},{:?}]}}"#, max[0], max[1], max[2]);
        assert!(json.contains(&bounds), "{bounds} missing from {json}");
    }

    #[test]
    fn keyframes_blending_several_targets_under_a_transform() {
        let weights = [1.0, 0.0, 0.5, 0.5, 0.0, 2.0];
        let glb = two_target_triangle(&[0.0, 0.5, 1.0], &weights, "LINEAR");
        let read = parse_bytes(&glb).unwrap();
        assert_eq!(read.fps, 2.0);
        assert_eq!(read.mesh.vertices()[1], [1.0, 0.0, 10.0]);
        assert_eq!(read.frames[0][0], [1.0, 0.0, 10.0]);
        assert_eq!(read.frames[1][2], [0.5, 1.5, 10.0]);
        assert_eq!(read.frames[2][1], [1.0, 2.0, 10.0]);
        // CUBICSPLINE: in-tangent, value, out-tangent per keyframe; the value is read
        let cubic: Vec<f32> = weights
            .chunks(2)
            .flat_map(|w| [9.0, 9.0, w[0], w[1], -9.0, -9.0])
            .collect();
        let glb = two_target_triangle(&[0.0, 0.5, 1.0], &cubic, "CUBICSPLINE");
        let spline = parse_bytes(&glb).unwrap();
        assert_eq!(spline.frames, read.frames);
    }

    #[test]
    fn gltf_with_a_buffer_file_in_its_folder_reads_and_one_outside_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let inner = dir.path().join("inner");
        std::fs::create_dir(&inner).unwrap();
        let animation = moving_sphere();
        let (json, bin) = chunks(&morph_animation_glb_bytes(&animation).unwrap());
        let declared = format!(r#""buffers":[{{"byteLength":{}}}]"#, bin.len());
        assert!(json.contains(&declared));
        std::fs::write(inner.join("moving.bin"), &bin).unwrap();
        std::fs::write(dir.path().join("outside.bin"), &bin).unwrap();
        let with_uri = |uri: &str| {
            json.replace(
                &declared,
                &format!(
                    r#""buffers":[{{"byteLength":{},"uri":"{uri}"}}]"#,
                    bin.len()
                ),
            )
        };
        let path = inner.join("moving.gltf");
        std::fs::write(&path, with_uri("moving.bin")).unwrap();
        let read = read_morph_animation(&path).unwrap();
        assert_close(&read, &animation);
        std::fs::write(&path, with_uri("../outside.bin")).unwrap();
        let (element, message) = format_message(read_morph_animation(&path));
        assert_eq!(element, r#"buffer 0 (uri "../outside.bin")"#);
        assert!(message.contains("climbs out"), "{message}");
    }

    #[test]
    fn truncated_files_are_errors() {
        let glb = morph_animation_glb_bytes(&moving_sphere()).unwrap();
        for length in [
            0,
            3,
            11,
            12,
            20,
            100,
            glb.len() / 2,
            glb.len() - 4,
            glb.len() - 1,
        ] {
            assert!(
                matches!(parse_bytes(&glb[..length]), Err(Error::Format { .. })),
                "{length}"
            );
        }
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("cut.glb");
        std::fs::write(&path, &glb[..glb.len() / 3]).unwrap();
        let message = read_morph_animation(&path).unwrap_err().to_string();
        assert!(
            message.starts_with(&path.display().to_string()),
            "{message}"
        );
        assert!(!message.contains('\n'), "{message}");
    }

    #[test]
    fn weights_of_the_wrong_count_are_an_error() {
        let glb = two_target_triangle(&[0.0, 0.5, 1.0], &[1.0, 0.0, 0.5, 0.5, 0.0], "LINEAR");
        let (element, message) = format_message(parse_bytes(&glb));
        assert_eq!(element, "sampler 0 of animation 0");
        assert!(
            message.contains("holds 5 weights, expected 3 keyframes × 2 morph targets"),
            "{message}"
        );
    }

    #[test]
    fn uneven_decreasing_or_single_keyframe_times_are_errors() {
        for (times, expected) in [
            (&[0.0, 0.1, 0.3][..], "not evenly spaced: keyframe 1"),
            (&[0.0, 0.5, 0.5][..], "do not increase"),
            (&[0.0][..], "one keyframe"),
        ] {
            let weights = vec![0.0; times.len() * 2];
            let glb = two_target_triangle(times, &weights, "STEP");
            let (element, message) = format_message(parse_bytes(&glb));
            assert_eq!(element, "sampler 0 of animation 0");
            assert!(message.contains(expected), "{message}");
        }
    }

    #[test]
    fn fps_is_recovered_exactly_or_from_the_mean_spacing() {
        let times = |fps: f64, n: usize| keyframe_times(n, fps);
        for fps in [24.0, 25.0, 29.97, 30.0, 59.94, 60.0, 12.5, 1.0, 0.5, 1000.0] {
            assert_eq!(frame_rate(&times(fps, 1800)).unwrap(), fps);
        }
        let third = 1.0 / 3.0;
        let rate = frame_rate(&times(third, 10)).unwrap();
        assert!((rate - third).abs() < 1e-6, "{rate}");
        // keyframes that do not start at 0 still give their spacing
        let shifted: Vec<[f32; 1]> = (0..4).map(|k| [1.0 + k as f32 * 0.25]).collect();
        assert_eq!(frame_rate(&shifted).unwrap(), 4.0);
    }

    #[test]
    fn no_weights_animation_or_no_mesh_is_an_error() {
        let glb = two_target_triangle(&[0.0, 1.0], &[0.0; 4], "LINEAR");
        let (json, bin) = chunks(&glb);
        let translation = json.replace(r#""path":"weights""#, r#""path":"translation""#);
        let (element, message) = format_message(parse_bytes(&glb_of(&translation, &bin)));
        assert_eq!(element, "glTF document");
        assert!(message.contains("no animation channel"), "{message}");
        let still = morph_animation_glb_bytes(&moving_sphere()).unwrap();
        let (json, bin) = chunks(&still);
        let start = json.find(r#","animations""#).unwrap();
        let end = json[start..].find("]}]").unwrap() + start + 3;
        let unanimated = format!("{}{}", &json[..start], &json[end..]);
        let (_, message) = format_message(parse_bytes(&glb_of(&unanimated, &bin)));
        assert!(message.contains("no animation channel"), "{message}");
        let meshless = json
            .replace(r#""target":{"node":0"#, r#""target":{"node":1"#)
            .replace(r#""nodes":[{"mesh":0}]"#, r#""nodes":[{"mesh":0},{}]"#);
        let (element, message) = format_message(parse_bytes(&glb_of(&meshless, &bin)));
        assert_eq!(element, "channel 0 of animation 0");
        assert!(message.contains("node 1, which has no mesh"), "{message}");
    }

    #[test]
    fn channel_targets_the_gltf_crate_would_unwrap_are_errors_not_panics() {
        let (json, bin) = chunks(&two_target_triangle(&[0.0, 1.0], &[0.0; 4], "LINEAR"));
        for (from, to, expected) in [
            (
                r#""node":1,"path""#,
                r#""node":7,"path""#,
                "target node 7 does not exist",
            ),
            (
                r#""path":"weights""#,
                r#""path":"pointer""#,
                "target path is none of",
            ),
        ] {
            let (element, message) =
                format_message(parse_bytes(&glb_of(&json.replace(from, to), &bin)));
            assert_eq!(element, "channel 0 of animation 0");
            assert!(message.contains(expected), "{message}");
        }
    }

    #[test]
    fn the_writer_refuses_bad_animations_naming_the_file() {
        let good = moving_sphere();
        let vertices = good.mesh.vertex_count();
        let mut short = good.clone();
        short.frames[2].pop();
        let mut nan = good.clone();
        nan.frames[1][7][2] = f32::NAN;
        // f32 holds ±3e38 but not their difference
        let mut far = good.clone();
        let mut far_rest = good.mesh.vertices().to_vec();
        far_rest[3][0] = 3e38;
        far.mesh = TriMesh::new(far_rest, good.mesh.triangles().to_vec()).unwrap();
        far.frames[1][3][0] = -3e38;
        let mut huge = good.clone();
        huge.frames = vec![Vec::new(); 20_000];
        let flat = MorphAnimation {
            mesh: TriMesh::new(good.mesh.vertices().to_vec(), vec![]).unwrap(),
            ..good.clone()
        };
        let cases = [
            (
                MorphAnimation {
                    frames: vec![],
                    ..good.clone()
                },
                "0 frame(s)".to_owned(),
            ),
            (
                MorphAnimation {
                    frames: vec![good.frames[0].clone()],
                    ..good.clone()
                },
                "1 frame(s)".to_owned(),
            ),
            (
                short,
                format!(
                    "frame 2 has {} positions, the mesh has {vertices} vertices",
                    vertices - 1
                ),
            ),
            (
                nan,
                "frame 1: vertex 7 has a non-finite position".to_owned(),
            ),
            (far, "frame 1: vertex 3 moves further".to_owned()),
            (
                MorphAnimation {
                    fps: 0.0,
                    ..good.clone()
                },
                "fps 0 is not".to_owned(),
            ),
            (
                MorphAnimation {
                    fps: -24.0,
                    ..good.clone()
                },
                "fps -24 is not".to_owned(),
            ),
            (
                MorphAnimation {
                    fps: f64::NAN,
                    ..good.clone()
                },
                "fps NaN is not".to_owned(),
            ),
            (
                MorphAnimation {
                    fps: 1e-40,
                    ..good.clone()
                },
                "cannot tell apart".to_owned(),
            ),
            (
                huge,
                "20000 frames of 162 vertices need over 268435456 floats".to_owned(),
            ),
            (flat, "no triangles".to_owned()),
        ];
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bad.glb");
        for (animation, expected) in cases {
            let message = write_morph_animation(&path, &animation)
                .unwrap_err()
                .to_string();
            assert!(
                message.starts_with(&format!("invalid animation: {}: ", path.display())),
                "{message}"
            );
            assert!(message.contains(&expected), "{expected}: {message}");
            assert!(MorphAnimation::new(animation.mesh, animation.frames, animation.fps).is_err());
        }
        assert!(!path.exists());
        let message = write_morph_animation(dir.path().join("a.obj"), &good).unwrap_err();
        assert!(
            message.to_string().contains("name the file .glb"),
            "{message}"
        );
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }

    #[test]
    fn the_size_limit_counts_displacements_weights_times_and_the_rest_pose() {
        assert_eq!(stored_floats(10, 4), Some(4 * 30 + 16 + 4 + 60));
        // a 5 023-vertex face fits 10 000 frames, not 11 000
        assert!(stored_floats(5023, 10_000).unwrap() <= MAX_ANIMATION_FLOATS);
        assert!(stored_floats(5023, 11_000).unwrap() > MAX_ANIMATION_FLOATS);
        assert_eq!(stored_floats(usize::MAX / 2, 3), None);
    }

    /// `vertices` points (one triangle) whose single morph target is the POSITION accessor
    /// itself, animated over `keyframes` keyframes with `weight`.
    fn shared_target_mesh(vertices: usize, keyframes: usize, weight: f32) -> Vec<u8> {
        let mut glb = GlbBuilder::default();
        let rest = MeshData {
            vertices: (0..vertices)
                .map(|i| [i as f32, (i % 7) as f32, 0.0])
                .collect(),
            triangles: vec![[0, 1, 2]],
            ..MeshData::default()
        };
        let primitive = add_primitive(&mut glb, &rest).join(",");
        let times: Vec<[f32; 1]> = (0..keyframes).map(|k| [k as f32]).collect();
        let input = glb.add_floats(&times, true, ViewTarget::None);
        let output = glb.add_floats(&vec![[weight]; keyframes], false, ViewTarget::None);
        glb.finish(&[
            r#""scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}]"#.to_owned(),
            format!(r#""meshes":[{{"primitives":[{{{primitive},"targets":[{{"POSITION":0}}]}}]}}]"#),
            format!(
                r#""animations":[{{"channels":[{{"sampler":0,"target":{{"node":0,"path":"weights"}}}}],"samplers":[{{"input":{input},"output":{output}}}]}}]"#
            ),
        ])
        .unwrap()
    }

    #[test]
    fn keyframes_beyond_the_element_budget_are_refused_before_any_allocation() {
        // 100 keyframes of 10 000 vertices: 10^6 positions from ~160 kB, within 16 per byte
        let read = parse_bytes(&shared_target_mesh(10_000, 100, 0.5)).unwrap();
        assert_eq!(read.frames[99][4], [6.0, 6.0, 0.0]);
        // 10 000 keyframes: 10^8 positions from ~200 kB
        let (element, message) =
            format_message(parse_bytes(&shared_target_mesh(10_000, 10_000, 0.5)));
        assert_eq!(element, "channel 0 of animation 0");
        assert!(
            message.contains("keyframe positions read over"),
            "{message}"
        );
    }

    #[test]
    fn non_finite_blends_are_errors_naming_the_keyframe() {
        let glb = two_target_triangle(&[0.0, 1.0], &[0.0, 0.0, f32::NAN, 0.0], "LINEAR");
        let (element, message) = format_message(parse_bytes(&glb));
        assert_eq!(element, "keyframe 1");
        assert!(
            message.contains("vertex 0: the weighted morph targets give a non-finite"),
            "{message}"
        );
    }

    /// Random edits to a valid file: bit flips, truncation, overwritten and inserted bytes.
    #[derive(Debug, Clone)]
    enum Mutation {
        Flip(usize, u8),
        Truncate(usize),
        Overwrite(usize, u8),
        Insert(usize, Vec<u8>),
    }

    fn mutation() -> impl Strategy<Value = Mutation> {
        prop_oneof![
            (any::<usize>(), 0u8..8).prop_map(|(i, b)| Mutation::Flip(i, b)),
            any::<usize>().prop_map(Mutation::Truncate),
            (any::<usize>(), any::<u8>()).prop_map(|(i, b)| Mutation::Overwrite(i, b)),
            (any::<usize>(), prop::collection::vec(any::<u8>(), 1..8))
                .prop_map(|(i, b)| Mutation::Insert(i, b)),
        ]
    }

    fn mutate(bytes: &mut Vec<u8>, mutations: &[Mutation]) {
        for m in mutations {
            let len = bytes.len().max(1);
            match m {
                Mutation::Flip(i, bit) => {
                    if let Some(b) = bytes.get_mut(i % len) {
                        *b ^= 1 << bit;
                    }
                }
                Mutation::Truncate(i) => bytes.truncate(i % len),
                Mutation::Overwrite(i, v) => {
                    if let Some(b) = bytes.get_mut(i % len) {
                        *b = *v;
                    }
                }
                Mutation::Insert(i, v) => {
                    let at = (i % len).min(bytes.len());
                    bytes.splice(at..at, v.iter().copied());
                }
            }
        }
    }

    /// A small valid animation: icosphere(0), 3 frames.
    fn seed() -> &'static (String, Vec<u8>, Vec<u8>) {
        static SEED: std::sync::OnceLock<(String, Vec<u8>, Vec<u8>)> = std::sync::OnceLock::new();
        SEED.get_or_init(|| {
            let sphere = icosphere(0);
            let frames = (0..3)
                .map(|k| {
                    sphere
                        .vertices()
                        .iter()
                        .map(|p| p.map(|x| x * (1.0 + k as f32)))
                        .collect()
                })
                .collect();
            let glb =
                morph_animation_glb_bytes(&MorphAnimation::new(sphere, frames, 30.0).unwrap())
                    .unwrap();
            let (json, bin) = chunks(&glb);
            (json, bin, glb)
        })
    }

    /// Numbers a hostile JSON may put anywhere: indices just out of range, counts and offsets
    /// that overflow, negative and fractional values.
    const HOSTILE_NUMBERS: [&str; 12] = [
        "0",
        "1",
        "2",
        "3",
        "7",
        "12",
        "-1",
        "0.5",
        "65535",
        "4294967295",
        "18446744073709551616",
        "1e30",
    ];

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]

        /// Mutated bytes of a valid GLB read as Ok or Err, never a panic.
        #[test]
        fn mutated_glb_never_panics(mutations in prop::collection::vec(mutation(), 1..6)) {
            let mut bytes = seed().2.clone();
            mutate(&mut bytes, &mutations);
            let _ = parse_bytes(&bytes);
        }

        /// A valid GLB with numbers of its JSON replaced (container lengths kept right, so
        /// the edit reaches the accessors, samplers and channels): Ok or Err, never a panic.
        #[test]
        fn glb_with_hostile_json_numbers_never_panics(
            edits in prop::collection::vec((any::<usize>(), prop::sample::select(HOSTILE_NUMBERS.to_vec())), 1..4),
        ) {
            let (json, bin, _) = seed();
            let mut json = json.clone();
            for (which, number) in edits {
                let digits: Vec<(usize, usize)> = number_spans(&json);
                let (start, end) = digits[which % digits.len()];
                json.replace_range(start..end, number);
            }
            let _ = parse_bytes(&glb_of(&json, bin));
        }
    }

    /// Byte ranges of the unsigned integers in `json` (outside strings).
    fn number_spans(json: &str) -> Vec<(usize, usize)> {
        let bytes = json.as_bytes();
        let mut spans = Vec::new();
        let mut in_string = false;
        let mut i = 0;
        while i < bytes.len() {
            match bytes[i] {
                b'"' => in_string = !in_string,
                b'0'..=b'9' if !in_string => {
                    let start = i;
                    while i < bytes.len() && bytes[i].is_ascii_digit() {
                        i += 1;
                    }
                    spans.push((start, i));
                    continue;
                }
                _ => {}
            }
            i += 1;
        }
        spans
    }
}
