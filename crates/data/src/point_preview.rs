//! PNG previews of point clouds: round splats in a z-buffer, coloured per point and darkened
//! with depth, so a user sees at a glance which points a simplification kept (the
//! `pcsimplify simplify --preview` sheet: input and kept points side by side, coloured by
//! curvature) or how a fitted mesh lies on a scan (`handy fit --preview`).
//!
//! # Conventions
//! - Views, tiles and images as in the mesh previews ([`crate::render_mesh`]).
//! - Every tile of one sheet uses the first cloud's framing, so kept points sit exactly where
//!   they are in the input's tile.
//! - Splat radius: half the mean spacing of `#P` points spread over the tile, 1-6 pixels, so a
//!   dense cloud reads as a surface and a sparse one as dots.

use rayon::prelude::*;

use crate::count_bounds::MAX_PREVIEW_PIXELS;
use crate::error::{Result, invalid};
use meshgnn_geometry::TriMesh;

use crate::preview::{Layer, Projection, RgbImage, View, check_tile_size, tile_images};

/// Points `#P×3` with one RGB colour (in `[0, 1]`) each.
#[derive(Debug, Clone, Copy)]
pub struct ColoredPoints<'a> {
    /// Positions.
    pub points: &'a [[f32; 3]],
    /// One colour per point.
    pub colors: &'a [[f64; 3]],
}

/// Stops of the viridis colour map (dark blue → green → yellow), evenly spaced.
const VIRIDIS: [[f64; 3]; 5] = [
    [0.267, 0.005, 0.329],
    [0.229, 0.322, 0.546],
    [0.128, 0.567, 0.551],
    [0.369, 0.789, 0.383],
    [0.993, 0.906, 0.144],
];

/// Colours for non-negative `values` (curvature, say): viridis from 0 (dark blue) to the
/// values' 98th percentile and above (yellow), so a few extreme points do not wash out the
/// rest. Non-finite values get the lowest colour.
///
/// ```
/// use meshgnn_data::value_colors;
/// let c = value_colors(&[0.0, 0.5, 1.0, f32::NAN]);
/// assert_eq!(c[3], c[0]);
/// assert!(c[2][0] > 0.9 && c[0][2] > 0.3); // yellow top, blue bottom
/// ```
pub fn value_colors(values: &[f32]) -> Vec<[f64; 3]> {
    let mut sorted: Vec<f32> = values.iter().copied().filter(|v| v.is_finite()).collect();
    sorted.sort_by(f32::total_cmp);
    let top = sorted
        .get((sorted.len() * 98 / 100).min(sorted.len().saturating_sub(1)))
        .map_or(1.0, |&v| f64::from(v));
    values
        .iter()
        .map(|&v| {
            let t = if v.is_finite() && top > 0.0 {
                (f64::from(v) / top).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let x = t * (VIRIDIS.len() - 1) as f64;
            let i = (x.floor() as usize).min(VIRIDIS.len() - 2);
            let f = x - i as f64;
            std::array::from_fn(|c| VIRIDIS[i][c] * (1.0 - f) + VIRIDIS[i + 1][c] * f)
        })
        .collect()
}

impl Layer {
    /// Draws `cloud` through `projection` as round splats (radius in the module docs),
    /// darkened with depth; a splat wins a pixel when it is nearer than what is there by
    /// `-bias` (a positive bias lets points on a drawn surface show through it).
    pub(crate) fn draw_splats(&mut self, cloud: ColoredPoints, projection: &Projection, bias: f64) {
        let n = self.side();
        let spacing = 0.88 * n as f64 / (cloud.points.len().max(1) as f64).sqrt();
        let radius = (0.5 * spacing).clamp(1.0, 6.0);
        let screen: Vec<[f64; 3]> = cloud
            .points
            .par_iter()
            .map(|&p| projection.to_screen(p))
            .collect();
        let (near, far) = screen.iter().fold((f64::MIN, f64::MAX), |(hi, lo), p| {
            (hi.max(p[2]), lo.min(p[2]))
        });
        let reach = radius.ceil() as isize;
        for (p, c) in screen.iter().zip(cloud.colors) {
            let shade = match near - far {
                span if span > 1e-12 => 0.55 + 0.45 * ((p[2] - far) / span).clamp(0.0, 1.0),
                _ => 1.0,
            };
            let (cx, cy) = (p[0].floor() as isize, p[1].floor() as isize);
            for y in cy - reach..=cy + reach {
                for x in cx - reach..=cx + reach {
                    if x < 0 || y < 0 || x >= n as isize || y >= n as isize {
                        continue;
                    }
                    let (dx, dy) = (x as f64 + 0.5 - p[0], y as f64 + 0.5 - p[1]);
                    let i = y as usize * n + x as usize;
                    if dx * dx + dy * dy <= radius * radius && p[2] + bias > self.depth[i] {
                        self.depth[i] = p[2] + bias;
                        self.color[i] = Some(c.map(|v| shade * v));
                    }
                }
            }
        }
    }
}

/// `clouds` side by side in `tile`-pixel tiles, all framed like the first (see the module
/// docs). Fails on no clouds, an empty first cloud, a colour count that differs from the
/// point count, or a sheet above `MAX_PREVIEW_PIXELS`.
///
/// ```
/// use meshgnn_data::{ColoredPoints, View, point_cloud_sheet};
/// let points = [[0.0, 0.0, 0.0], [1.0, 1.0, 0.0]];
/// let colors = [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]];
/// let all = ColoredPoints { points: &points, colors: &colors };
/// let first = ColoredPoints { points: &points[..1], colors: &colors[..1] };
/// let sheet = point_cloud_sheet(&[all, first], 32, View { yaw: 0.0, pitch: 0.0, wireframe: false })?;
/// assert_eq!((sheet.width, sheet.height), (64, 32));
/// # Ok::<(), meshgnn_data::Error>(())
/// ```
pub fn point_cloud_sheet(clouds: &[ColoredPoints], tile: u32, view: View) -> Result<RgbImage> {
    check_tile_size(tile)?;
    let Some(first) = clouds.first().filter(|c| !c.points.is_empty()) else {
        return Err(invalid("clouds", clouds.len(), "nothing to render"));
    };
    if let Some(bad) = clouds.iter().find(|c| c.colors.len() != c.points.len()) {
        return Err(invalid(
            "colors",
            bad.colors.len(),
            &format!("one colour per point needed, {} points", bad.points.len()),
        ));
    }
    let pixels = clouds.len() as u64 * u64::from(tile) * u64::from(tile);
    if pixels > MAX_PREVIEW_PIXELS as u64 {
        return Err(invalid(
            "tile",
            tile,
            &format!("{pixels} pixels, above the {MAX_PREVIEW_PIXELS} of MAX_PREVIEW_PIXELS"),
        ));
    }
    let projection = Projection::fitted(first.points, tile, view);
    let tiles: Vec<RgbImage> = clouds
        .par_iter()
        .map(|&c| {
            let mut layer = Layer::new(tile);
            layer.draw_splats(c, &projection, 0.0);
            layer.into_image()
        })
        .collect();
    Ok(tile_images(&tiles, clouds.len() as u32, tile))
}

/// Colour of the points in [`points_on_mesh_sheet`] (orange), beside the mesh's blue-grey.
const OVERLAY_POINTS: [f64; 3] = [0.95, 0.45, 0.1];
const OVERLAY_MESH: [f64; 3] = [0.75, 0.82, 0.92];

/// `points` (a scan, say) drawn over `mesh` (a model fitted to it), one `tile`-pixel tile per
/// view, side by side, each framed on both. Points in front of the surface and up to 1 % of
/// the framing's extent behind it show; points further behind are hidden.
///
/// ```
/// use meshgnn_data::{View, points_on_mesh_sheet};
/// let sphere = meshgnn_geometry::icosphere(2);
/// let views = [View { yaw: 0.0, pitch: 0.0, wireframe: false }, View { yaw: 90.0, pitch: 0.0, wireframe: false }];
/// let sheet = points_on_mesh_sheet(&sphere, sphere.vertices(), &views, 64)?;
/// assert_eq!((sheet.width, sheet.height), (128, 64));
/// # Ok::<(), meshgnn_data::Error>(())
/// ```
pub fn points_on_mesh_sheet(
    mesh: &TriMesh,
    points: &[[f32; 3]],
    views: &[View],
    tile: u32,
) -> Result<RgbImage> {
    check_tile_size(tile)?;
    if mesh.face_count() == 0 || views.is_empty() {
        return Err(invalid(
            "mesh",
            mesh.face_count(),
            "needs faces and at least one view",
        ));
    }
    let pixels = views.len() as u64 * u64::from(tile) * u64::from(tile);
    if pixels > MAX_PREVIEW_PIXELS as u64 {
        return Err(invalid(
            "views",
            views.len(),
            &format!("{pixels} pixels, above the {MAX_PREVIEW_PIXELS} of MAX_PREVIEW_PIXELS"),
        ));
    }
    let both: Vec<[f32; 3]> = mesh.vertices().iter().chain(points).copied().collect();
    let colors = vec![OVERLAY_POINTS; points.len()];
    let tiles: Vec<RgbImage> = views
        .par_iter()
        .map(|&view| {
            let projection = Projection::fitted(&both, tile, view);
            let mut layer = Layer::new(tile);
            layer.draw_mesh(mesh, &projection, OVERLAY_MESH, view.wireframe);
            let cloud = ColoredPoints {
                points,
                colors: &colors,
            };
            layer.draw_splats(cloud, &projection, 0.01 * projection.extent());
            layer.into_image()
        })
        .collect();
    Ok(tile_images(&tiles, views.len() as u32, tile))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::preview::BACKGROUND;

    const FRONT: View = View {
        yaw: 0.0,
        pitch: 0.0,
        wireframe: false,
    };

    fn pixel(img: &RgbImage, x: usize, y: usize) -> [u8; 3] {
        let i = (y * img.width as usize + x) * 3;
        [img.pixels[i], img.pixels[i + 1], img.pixels[i + 2]]
    }

    #[test]
    fn a_nearer_point_hides_a_farther_one_and_the_framing_is_the_first_clouds() {
        // a square's corners frame the tile; two points at its centre, the red one nearer (+z)
        let points = [
            [-1.0, -1.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 0.0, -1.0],
            [0.0, 0.0, 1.0],
        ];
        let colors = [
            [0.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 0.0, 0.0],
        ];
        let all = ColoredPoints {
            points: &points,
            colors: &colors,
        };
        let blue = ColoredPoints {
            points: &points[2..3],
            colors: &colors[2..3],
        };
        let sheet = point_cloud_sheet(&[all, blue], 64, FRONT).unwrap();
        let centre = pixel(&sheet, 32, 32);
        assert!(centre[0] > 200 && centre[2] == 0, "{centre:?}");
        // the blue point alone, in the second tile, at the same place
        let right = pixel(&sheet, 64 + 32, 32);
        assert!(right[2] > 100 && right[0] == 0, "{right:?}");
        // corners: the green corner points sit at the 6 % margin, the tile's corner is empty
        assert_eq!(pixel(&sheet, 0, 0), BACKGROUND);
        assert_eq!(pixel(&sheet, 64 + 63, 63), BACKGROUND);
        let corner = pixel(&sheet, 4, 60);
        assert!(corner[1] > 100, "{corner:?}");
    }

    #[test]
    fn points_on_the_visible_surface_show_and_points_behind_it_do_not() {
        let sphere = meshgnn_geometry::icosphere(3);
        // the view looks along −z: +z is the front of the sphere
        let front = [[0.0f32, 0.0, 1.0]];
        let back = [[0.0f32, 0.0, -1.0]];
        let centre = |points: &[[f32; 3]]| {
            let sheet = points_on_mesh_sheet(&sphere, points, &[FRONT], 64).unwrap();
            pixel(&sheet, 32, 32)
        };
        let shown = centre(&front);
        assert!(shown[0] > 150 && shown[2] < 80, "front point: {shown:?}");
        let hidden = centre(&back);
        assert!(
            hidden[2] > hidden[0],
            "back point hidden by the surface: {hidden:?}"
        );
        let sheet = points_on_mesh_sheet(&sphere, &front, &[FRONT, FRONT, FRONT], 32).unwrap();
        assert_eq!((sheet.width, sheet.height), (96, 32));
        assert!(points_on_mesh_sheet(&sphere, &front, &[], 32).is_err());
    }

    #[test]
    fn colours_run_from_blue_to_yellow_and_bad_sheets_are_refused() {
        let c = value_colors(&[0.0, 1.0, 2.0, 3.0, 100.0]);
        assert_eq!(c[0], VIRIDIS[0]);
        assert_eq!(c[4], VIRIDIS[4]);
        assert!(c[1][1] < c[2][1] && c[2][1] < c[3][1]);
        let points = [[0.0f32; 3]];
        let none: [[f64; 3]; 0] = [];
        let mismatch = ColoredPoints {
            points: &points,
            colors: &none,
        };
        assert!(point_cloud_sheet(&[mismatch], 32, FRONT).is_err());
        assert!(point_cloud_sheet(&[], 32, FRONT).is_err());
        let one = ColoredPoints {
            points: &points,
            colors: &[[1.0; 3]],
        };
        assert!(point_cloud_sheet(&[one], 4, FRONT).is_err());
    }
}
