//! PNG contact sheets of generated meshes: a small software rasteriser (z-buffer, Lambert
//! shading with interpolated vertex normals, orthographic view fitted to each mesh), so a user
//! can check a synthetic dataset at a glance without a 3D viewer.
//!
//! # Conventions
//! - Images are 8-bit RGB, row major, top row first.
//! - The view looks along the camera's −z; `yaw` rotates the mesh about +y, then `pitch` about
//!   +x, before the projection onto the camera's x (right) and y (up) axes.

use std::path::Path;

use meshgnn_geometry::{TriMesh, vertex_normals};
use rayon::prelude::*;

use crate::count_bounds::MAX_PREVIEW_PIXELS;
use crate::error::{Error, Result, invalid};
use crate::vec3::{M3, V3, axis_angle, dot, mul_m, mul_v, normalize, to_f64};
use meshgnn_geometry::atomic_write;

/// An 8-bit RGB image.
#[derive(Debug, Clone, PartialEq)]
pub struct RgbImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `height × width × 3` bytes, top row first.
    pub pixels: Vec<u8>,
}

/// How [`render_mesh`] draws: the camera orientation, in degrees, and whether the triangle
/// edges show.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct View {
    /// Rotation about +y applied first.
    pub yaw: f64,
    /// Rotation about +x applied second.
    pub pitch: f64,
    /// Darken the pixels within [`WIREFRAME_PIXELS`] of a visible triangle's edge, when the
    /// mesh's median triangle is at least three line widths high on screen (a denser mesh
    /// stays shaded instead of turning black).
    pub wireframe: bool,
}

/// Half-width of a wireframe line, pixels.
pub const WIREFRAME_PIXELS: f64 = 1.0;

impl Default for View {
    /// A three-quarter view from the front-right, slightly above.
    fn default() -> Self {
        Self {
            yaw: -25.0,
            pitch: 15.0,
            wireframe: false,
        }
    }
}

pub(crate) const BACKGROUND: [u8; 3] = [250, 250, 250];

/// Refuses tiles outside `8..=8192` pixels.
pub(crate) fn check_tile_size(size: u32) -> Result<()> {
    if (8..=8192).contains(&size) {
        Ok(())
    } else {
        Err(invalid(
            "size",
            size,
            "tile size must be in 8..=8192 pixels",
        ))
    }
}

/// The orthographic projection of a tile: `view`'s rotation, then the rotated points' 2D
/// bounding box fitted into `size` pixels with a 6 % margin, `y` up.
pub(crate) struct Projection {
    pub(crate) rotation: M3,
    centre: [f64; 2],
    pixels_per_unit: f64,
    size: f64,
    extent: f64,
}

impl Projection {
    /// The projection of `view` that fits `points` into a `size`-pixel tile.
    pub(crate) fn fitted(points: &[[f32; 3]], size: u32, view: View) -> Self {
        let rotation: M3 = mul_m(
            &axis_angle([1.0, 0.0, 0.0], view.pitch.to_radians()),
            &axis_angle([0.0, 1.0, 0.0], view.yaw.to_radians()),
        );
        let (mut lo, mut hi) = ([f64::MAX; 2], [f64::MIN; 2]);
        for &p in points {
            let q = mul_v(&rotation, to_f64(p));
            for k in 0..2 {
                lo[k] = lo[k].min(q[k]);
                hi[k] = hi[k].max(q[k]);
            }
        }
        let extent = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1e-12);
        let size = f64::from(size);
        Self {
            rotation,
            centre: [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])],
            pixels_per_unit: 0.88 * size / extent,
            size,
            extent,
        }
    }

    /// The larger side of the framed points' 2D bounding box (data units).
    pub(crate) fn extent(&self) -> f64 {
        self.extent
    }

    /// Pixel `x`, `y` (top row 0) and depth (larger is nearer) of `p`.
    pub(crate) fn to_screen(&self, p: [f32; 3]) -> V3 {
        let q = mul_v(&self.rotation, to_f64(p));
        [
            0.5 * self.size + (q[0] - self.centre[0]) * self.pixels_per_unit,
            0.5 * self.size - (q[1] - self.centre[1]) * self.pixels_per_unit,
            q[2],
        ]
    }
}

/// The median over `mesh`'s triangles of their smallest on-screen height (pixels; 0 for a
/// mesh without faces).
fn median_height(mesh: &TriMesh, screen: &[V3]) -> f64 {
    let mut heights: Vec<f64> = mesh
        .triangles()
        .iter()
        .filter_map(|t| {
            let [a, b, c] = t.map(|v| screen.get(v as usize));
            let (a, b, c) = (a?, b?, c?);
            let twice_area = ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])).abs();
            let longest = [(a, b), (b, c), (c, a)]
                .iter()
                .map(|(p, q)| (p[0] - q[0]).hypot(p[1] - q[1]))
                .fold(1e-12, f64::max);
            Some(twice_area / longest)
        })
        .collect();
    if heights.is_empty() {
        return 0.0;
    }
    let middle = heights.len() / 2;
    *heights.select_nth_unstable_by(middle, f64::total_cmp).1
}

/// Renders `mesh` into a `size × size` tile: orthographic, fitted with a 6 % margin,
/// two-sided Lambert shading of interpolated vertex normals under a light from the viewer's
/// upper left, mixed with 25 % ambient, tinted by `color` (RGB in `[0, 1]`); with
/// `view.wireframe`, edges drawn dark over the shading.
///
/// ```
/// use meshgnn_data::{View, render_mesh};
/// use meshgnn_geometry::icosphere;
/// let img = render_mesh(&icosphere(2), 32, View::default(), [1.0, 1.0, 1.0])?;
/// assert_eq!(img.pixels.len(), 32 * 32 * 3);
/// // The centre is lit sphere, the corner background.
/// let px = |x: usize, y: usize| img.pixels[(y * 32 + x) * 3];
/// assert!(px(16, 16) < 250 && px(16, 16) > 100);
/// assert_eq!(px(0, 0), 250);
/// # Ok::<(), meshgnn_data::Error>(())
/// ```
pub fn render_mesh(mesh: &TriMesh, size: u32, view: View, color: [f64; 3]) -> Result<RgbImage> {
    check_tile_size(size)?;
    if mesh.vertex_count() == 0 || mesh.face_count() == 0 {
        return Err(invalid("mesh", "empty", "nothing to render"));
    }
    let projection = Projection::fitted(mesh.vertices(), size, view);
    let mut layer = Layer::new(size);
    layer.draw_mesh(mesh, &projection, color, view.wireframe);
    Ok(layer.into_image())
}

/// A tile being drawn: per pixel the nearest depth so far and its colour (RGB in `[0, 1]`).
pub(crate) struct Layer {
    size: u32,
    pub(crate) depth: Vec<f64>,
    pub(crate) color: Vec<Option<[f64; 3]>>,
}

impl Layer {
    /// An empty `size × size` tile.
    pub(crate) fn new(size: u32) -> Self {
        let n = size as usize;
        Self {
            size,
            depth: vec![f64::NEG_INFINITY; n * n],
            color: vec![None; n * n],
        }
    }

    /// Pixels per side.
    pub(crate) fn side(&self) -> usize {
        self.size as usize
    }

    /// Draws `mesh` through `projection` (z-buffered, two-sided Lambert shading of
    /// interpolated vertex normals, light from the viewer's upper left, 25 % ambient, tinted
    /// by `color`).
    pub(crate) fn draw_mesh(
        &mut self,
        mesh: &TriMesh,
        projection: &Projection,
        color: [f64; 3],
        wireframe: bool,
    ) {
        let screen: Vec<V3> = mesh
            .vertices()
            .par_iter()
            .map(|&p| projection.to_screen(p))
            .collect();
        let normals: Vec<V3> = vertex_normals(mesh)
            .into_par_iter()
            .map(|n| mul_v(&projection.rotation, to_f64(n)))
            .collect();
        let n = self.side();
        let light = normalize([-0.4, 0.5, 0.77]);
        let wireframe = wireframe && median_height(mesh, &screen) >= 3.0 * WIREFRAME_PIXELS;
        for tri in mesh.triangles() {
            let [a, b, c] = tri.map(|v| v as usize);
            let (Some(pa), Some(pb), Some(pc)) = (screen.get(a), screen.get(b), screen.get(c))
            else {
                continue;
            };
            let area = (pb[0] - pa[0]) * (pc[1] - pa[1]) - (pb[1] - pa[1]) * (pc[0] - pa[0]);
            if area.abs() < 1e-12 {
                continue;
            }
            let x0 = pa[0].min(pb[0]).min(pc[0]).floor().max(0.0) as usize;
            let x1 = (pa[0].max(pb[0]).max(pc[0]).ceil() as usize).min(n.saturating_sub(1));
            let y0 = pa[1].min(pb[1]).min(pc[1]).floor().max(0.0) as usize;
            let y1 = (pa[1].max(pb[1]).max(pc[1]).ceil() as usize).min(n.saturating_sub(1));
            let (na, nb, nc) = (normals[a], normals[b], normals[c]);
            // Pixel heights of the triangle over each edge: a corner's weight times the height
            // over the opposite edge is the distance to that edge.
            let length = |p: &V3, q: &V3| (p[0] - q[0]).hypot(p[1] - q[1]).max(1e-12);
            let heights = [
                area.abs() / length(pb, pc),
                area.abs() / length(pc, pa),
                area.abs() / length(pa, pb),
            ];
            for y in y0..=y1 {
                for x in x0..=x1 {
                    let (qx, qy) = (x as f64 + 0.5, y as f64 + 0.5);
                    let w0 = ((pb[0] - qx) * (pc[1] - qy) - (pb[1] - qy) * (pc[0] - qx)) / area;
                    let w1 = ((pc[0] - qx) * (pa[1] - qy) - (pc[1] - qy) * (pa[0] - qx)) / area;
                    let w2 = 1.0 - w0 - w1;
                    if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                        continue;
                    }
                    let z = w0 * pa[2] + w1 * pb[2] + w2 * pc[2];
                    let i = y * n + x;
                    if z > self.depth[i] {
                        self.depth[i] = z;
                        let nrm = normalize([
                            w0 * na[0] + w1 * nb[0] + w2 * nc[0],
                            w0 * na[1] + w1 * nb[1] + w2 * nc[1],
                            w0 * na[2] + w1 * nb[2] + w2 * nc[2],
                        ]);
                        let lum = 0.25 + 0.75 * dot(nrm, light).abs();
                        let on_edge = wireframe
                            && [w0, w1, w2]
                                .iter()
                                .zip(&heights)
                                .any(|(w, h)| w * h < WIREFRAME_PIXELS);
                        let lum = if on_edge { 0.3 * lum } else { lum };
                        self.color[i] = Some(color.map(|c| lum * c));
                    }
                }
            }
        }
    }

    /// The finished tile: the background where nothing was drawn.
    pub(crate) fn into_image(self) -> RgbImage {
        let mut pixels = Vec::with_capacity(self.color.len() * 3);
        for c in &self.color {
            match c {
                None => pixels.extend_from_slice(&BACKGROUND),
                Some(c) => {
                    pixels.extend(c.map(|v| (255.0 * v.clamp(0.0, 1.0)).round() as u8));
                }
            }
        }
        RgbImage {
            width: self.size,
            height: self.size,
            pixels,
        }
    }
}

/// A grid of `tile × tile` renders of `meshes`, `columns` per row (rendered in parallel).
///
/// ```
/// use meshgnn_data::{View, contact_sheet};
/// use meshgnn_geometry::{icosphere, subdivided_cube};
/// let sheet = contact_sheet(&[icosphere(1), subdivided_cube(2), icosphere(2)], 2, 16, View::default())?;
/// assert_eq!((sheet.width, sheet.height), (32, 32));
/// # Ok::<(), meshgnn_data::Error>(())
/// ```
pub fn contact_sheet(meshes: &[TriMesh], columns: u32, tile: u32, view: View) -> Result<RgbImage> {
    if meshes.is_empty() || columns == 0 {
        return Err(invalid(
            "meshes",
            meshes.len(),
            "need at least one mesh and one column",
        ));
    }
    let columns = columns.min(meshes.len() as u32);
    let rows = (meshes.len() as u32).div_ceil(columns);
    let pixels = u64::from(columns) * u64::from(rows) * u64::from(tile) * u64::from(tile);
    if pixels > MAX_PREVIEW_PIXELS as u64 {
        return Err(invalid(
            "meshes",
            meshes.len(),
            &format!(
                "a {columns}×{rows} sheet of {tile}-pixel tiles is {pixels} pixels, above the \
                 {MAX_PREVIEW_PIXELS} of MAX_PREVIEW_PIXELS: preview fewer meshes"
            ),
        ));
    }
    let tints = [
        [0.95, 0.80, 0.68],
        [0.75, 0.85, 0.95],
        [0.85, 0.92, 0.78],
        [0.92, 0.85, 0.95],
    ];
    let tiles = meshes
        .par_iter()
        .enumerate()
        .map(|(i, m)| render_mesh(m, tile, view, tints[i % tints.len()]))
        .collect::<Result<Vec<_>>>()?;
    Ok(tile_images(&tiles, columns, tile))
}

/// `tiles` of `tile × tile` pixels laid out `columns` per row, in order.
pub(crate) fn tile_images(tiles: &[RgbImage], columns: u32, tile: u32) -> RgbImage {
    let columns = columns.max(1);
    let rows = (tiles.len() as u32).div_ceil(columns);
    let (w, h) = ((columns * tile) as usize, (rows * tile) as usize);
    let mut pixels = vec![BACKGROUND[0]; w * h * 3];
    let t = tile as usize;
    for (i, img) in tiles.iter().enumerate() {
        let (cx, cy) = (i % columns as usize, i / columns as usize);
        for y in 0..t {
            let src = y * t * 3;
            let dst = ((cy * t + y) * w + cx * t) * 3;
            if let (Some(d), Some(s)) = (
                pixels.get_mut(dst..dst + t * 3),
                img.pixels.get(src..src + t * 3),
            ) {
                d.copy_from_slice(s);
            }
        }
    }
    RgbImage {
        width: w as u32,
        height: h as u32,
        pixels,
    }
}

/// Encodes `image` as PNG bytes.
pub fn encode_png(image: &RgbImage) -> std::result::Result<Vec<u8>, String> {
    let mut bytes = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut bytes, image.width, image.height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().map_err(|e| e.to_string())?;
        writer
            .write_image_data(&image.pixels)
            .map_err(|e| e.to_string())?;
    }
    Ok(bytes)
}

/// Writes `image` to `path` as a PNG, atomically.
///
/// ```
/// use meshgnn_data::{RgbImage, write_png};
/// let dir = tempfile::tempdir()?;
/// let path = dir.path().join("a.png");
/// write_png(&path, &RgbImage { width: 2, height: 1, pixels: vec![0; 6] })?;
/// assert_eq!(&std::fs::read(&path)?[1..4], b"PNG");
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn write_png(path: impl AsRef<Path>, image: &RgbImage) -> Result<()> {
    let path = path.as_ref();
    let expected = image.width as usize * image.height as usize * 3;
    if image.pixels.len() != expected {
        return Err(invalid(
            "image",
            image.pixels.len(),
            "pixel buffer is not width × height × 3",
        ));
    }
    let bytes = encode_png(image).map_err(|message| Error::Png {
        path: path.to_path_buf(),
        message,
    })?;
    Ok(atomic_write(path, &bytes)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshgnn_geometry::grid_plane;

    /// Distance of `q` from the segment `a`–`b` (2D).
    fn segment_distance(q: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let t = (((q[0] - a[0]) * dx + (q[1] - a[1]) * dy) / (dx * dx + dy * dy)).clamp(0.0, 1.0);
        (q[0] - a[0] - t * dx).hypot(q[1] - a[1] - t * dy)
    }

    #[test]
    fn the_wireframe_darkens_exactly_the_pixels_along_the_edges() {
        let square = grid_plane(1, 1); // two triangles sharing a diagonal
        let front = View {
            yaw: 0.0,
            pitch: 0.0,
            wireframe: false,
        };
        let size = 64;
        let plain = render_mesh(&square, size, front, [1.0; 3]).unwrap();
        let wired = render_mesh(
            &square,
            size,
            View {
                wireframe: true,
                ..front
            },
            [1.0; 3],
        )
        .unwrap();
        let projection = Projection::fitted(square.vertices(), size, front);
        let screen: Vec<[f64; 2]> = square
            .vertices()
            .iter()
            .map(|&p| {
                let s = projection.to_screen(p);
                [s[0], s[1]]
            })
            .collect();
        let mut darkened = 0;
        for y in 0..size as usize {
            for x in 0..size as usize {
                let i = (y * size as usize + x) * 3;
                if wired.pixels[i] == plain.pixels[i] {
                    continue;
                }
                assert!(wired.pixels[i] < plain.pixels[i]);
                darkened += 1;
                let q = [x as f64 + 0.5, y as f64 + 0.5];
                let nearest = square
                    .triangles()
                    .iter()
                    .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
                    .map(|(a, b)| segment_distance(q, screen[a as usize], screen[b as usize]))
                    .fold(f64::INFINITY, f64::min);
                assert!(
                    nearest < WIREFRAME_PIXELS + 1e-9,
                    "({x}, {y}) is {nearest} px away"
                );
            }
        }
        // The square's side spans 0.88 of the tile: four sides and a diagonal of lines.
        let side = 0.88 * f64::from(size);
        assert!(
            f64::from(darkened) > 4.0 * side,
            "{darkened} pixels darkened"
        );
    }
}
