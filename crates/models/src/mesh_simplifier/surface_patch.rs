//! Whether a hole's patch lies along the input's surface: the test by which the neural mesh
//! simplifier closes the cracks of its output (beyond the thesis, ch. 6.4) and leaves the
//! openings of the input open. A crack is surface the network's faces missed, so under each
//! patch triangle the input has faces, standing for the hole's corners, one of them facing the
//! triangle's way. A patch across an opening has none: the faces under a pot's opening are a
//! lid's, which other selected vertices stand for, and beside a cap across a thin part's open
//! end the input's faces stand across the cap.

use std::collections::HashMap;

use meshgnn_geometry::vec3::{cross, dot, norm, sub, to_f64};
use meshgnn_geometry::{TriMesh, connected_components, geodesic_voronoi_regions, squared_distance};
use meshgnn_graph::ClosestFace;

/// How far from an input face the centroid of a patch triangle may lie, in units of the
/// triangle's mean edge length. The network's own faces reach 0.30 on a 5 % creature
/// (median 0.05, 99th percentile 0.27); a patch across an opening, a fraction of the
/// opening's width.
pub const SURFACE_PATCH_TOLERANCE: f64 = 0.25;

/// The least |cosine| between a patch triangle's normal and that of an input face near it for
/// the face to lie under it (60°): beside a cap across a thin part's open end the input's
/// faces stand at about 90° to it. Unsigned, since inputs stored as patches need not be
/// oriented consistently (the airplane's faces under a crack point either way). 0.4 and 0.6
/// measured: the real set's WA after the pass and CD move by at most 0.13 and 0.01.
pub const SURFACE_PATCH_NORMAL_AGREEMENT: f64 = 0.5;

/// The input's surface, indexed per part (vertices joined by faces) as holes ask for it,
/// with the geodesic regions of the selected vertices (docs/mesh_simplifier_model.md,
/// "Cracks beside the border closed along the surface").
pub(crate) struct InputSurface<'a> {
    input: &'a TriMesh,
    /// `vertex_map[i]`: the input vertex selected vertex `i` stands for.
    vertex_map: &'a [u32],
    part_of: Vec<u32>,
    part_faces: Vec<Vec<u32>>,
    indexed: HashMap<u32, Option<ClosestFace<'a>>>,
    /// The selected vertex whose geodesic region holds each input vertex; computed at the
    /// first patch.
    region: Option<Vec<u32>>,
    scratch: Vec<(f32, u32)>,
}

impl<'a> InputSurface<'a> {
    /// Nothing is indexed until a patch is judged.
    pub(crate) fn new(input: &'a TriMesh, vertex_map: &'a [u32]) -> Self {
        let (parts, part_of) = connected_components(input);
        let mut part_faces = vec![Vec::new(); parts];
        for (f, t) in input.triangles().iter().enumerate() {
            part_faces[part_of[t[0] as usize] as usize].push(f as u32);
        }
        Self {
            input,
            vertex_map,
            part_of,
            part_faces,
            indexed: HashMap::new(),
            region: None,
            scratch: Vec::new(),
        }
    }

    /// Whether `patch` (triangles over selected vertices at `positions`) lies along the
    /// surface of the one input part its corners stand for. For every triangle, the face of
    /// that part closest to its centroid lies within [`SURFACE_PATCH_TOLERANCE`] and has a
    /// corner in the geodesic region of one of the patch's corners, and so does a face within
    /// that distance facing the triangle's way ([`SURFACE_PATCH_NORMAL_AGREEMENT`]): on a thin
    /// tube a coarse triangle stands askew to the face closest to it, but the faces around the
    /// tube face every way. False for a patch with a vertex that stands for none (a centre
    /// vertex).
    pub(crate) fn lies_along(&mut self, patch: &[[u32; 3]], positions: &[[f32; 3]]) -> bool {
        let stands_for = |v: u32| self.vertex_map.get(v as usize).copied();
        let part = |v: u32| stands_for(v).map(|i| self.part_of[i as usize]);
        let Some(first) = patch.first().and_then(|t| part(t[0])) else {
            return false;
        };
        if !patch.iter().flatten().all(|&v| part(v) == Some(first)) {
            return false;
        }
        let input = self.input;
        let part_faces = &mut self.part_faces;
        let Some(closest) = self
            .indexed
            .entry(first)
            .or_insert_with(|| {
                ClosestFace::among(input, std::mem::take(&mut part_faces[first as usize])).ok()
            })
            .as_ref()
        else {
            return false;
        };
        let region = self
            .region
            .get_or_insert_with(|| {
                geodesic_voronoi_regions(input, self.vertex_map).unwrap_or_default()
            })
            .as_slice();
        let scratch = &mut self.scratch;
        let stands_for_corner = |face: u32| {
            input.triangles()[face as usize].iter().any(|&c| {
                region
                    .get(c as usize)
                    .is_some_and(|r| patch.iter().flatten().any(|v| v == r))
            })
        };
        patch.iter().all(|t| {
            let corners = t.map(|v| positions[v as usize]);
            let centroid: [f32; 3] =
                std::array::from_fn(|k| corners.iter().map(|c| c[k]).sum::<f32>() / 3.0);
            let mean_edge = (0..3)
                .map(|i| f64::from(squared_distance(&corners[i], &corners[(i + 1) % 3])).sqrt())
                .sum::<f64>()
                / 3.0;
            let tolerance = SURFACE_PATCH_TOLERANCE * mean_edge;
            let nearest = closest.query(&centroid, scratch);
            if nearest.squared_distance > tolerance * tolerance || !stands_for_corner(nearest.face)
            {
                return false;
            }
            // A triangle without area (along a straight stretch of the rim) faces no way.
            let Some(normal) = unit_normal(&corners) else {
                return true;
            };
            closest.within(&centroid, tolerance, scratch).any(|hit| {
                let face =
                    input.triangles()[hit.face as usize].map(|c| input.vertices()[c as usize]);
                unit_normal(&face)
                    .is_some_and(|n| dot(n, normal).abs() >= SURFACE_PATCH_NORMAL_AGREEMENT)
                    && stands_for_corner(hit.face)
            })
        })
    }
}

/// The unit normal of a triangle given by its corners; `None` when it has no area.
fn unit_normal(t: &[[f32; 3]; 3]) -> Option<[f64; 3]> {
    let [p, q, r] = t.map(to_f64);
    let n = cross(sub(q, p), sub(r, p));
    let length = norm(n);
    (length > 0.0).then(|| n.map(|x| x / length))
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshgnn_geometry::{boundary_loops, fill_holes_where, grid_plane, torus};

    /// `mesh` (a `torus(_, _, _, across)`) less the faces of each cell `(i, j)` that `cut`
    /// names (cell `(i, j)` holds faces `2·(i·across + j)` and the next).
    fn without_cells(mesh: &TriMesh, across: u32, cut: impl Fn(u32, u32) -> bool) -> TriMesh {
        let faces = mesh
            .triangles()
            .iter()
            .enumerate()
            .filter(|&(f, _)| {
                let cell = f as u32 / 2;
                !cut(cell / across, cell % across)
            })
            .map(|(_, t)| *t)
            .collect();
        TriMesh::new(mesh.vertices().to_vec(), faces).unwrap()
    }

    /// `selected` (every vertex of `input` selected) with each hole whose least-area patch
    /// lies along `input` filled.
    fn filled_along(input: &TriMesh, selected: &TriMesh) -> TriMesh {
        let every: Vec<u32> = (0..input.vertex_count() as u32).collect();
        let mut surface = InputSurface::new(input, &every);
        fill_holes_where(selected, 32, |patch| {
            surface.lies_along(patch, selected.vertices())
        })
        .unwrap()
    }

    #[test]
    fn unit_normals_by_hand() {
        let flat = [[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 3.0, 0.0]];
        let turned = [[0.0, 0.0, 0.0], [0.0, 3.0, 0.0], [2.0, 0.0, 0.0]];
        // Tilted by 60° about the x axis: the normals' cosine is 0.5, the least agreement.
        let (sin, cos) = 60f32.to_radians().sin_cos();
        let tilted = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, cos, sin]];
        let needle = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]];
        assert_eq!(unit_normal(&flat), Some([0.0, 0.0, 1.0]));
        assert_eq!(unit_normal(&turned), Some([0.0, 0.0, -1.0]));
        let n = unit_normal(&tilted).unwrap();
        assert!(
            (n[2] - SURFACE_PATCH_NORMAL_AGREEMENT).abs() < 1e-6,
            "{n:?}"
        );
        assert_eq!(unit_normal(&needle), None);
    }

    #[test]
    fn a_crack_in_a_thin_tube_closes_and_a_cap_across_its_open_end_does_not() {
        // A torus flattened to a tube 0.1 thick and 2 wide.
        let (around, across) = (48, 24);
        let round = torus(3.0, 1.0, around, across);
        let vertices = round
            .vertices()
            .iter()
            .map(|&[x, y, z]| [x, y, 0.05 * z])
            .collect();
        let flat = TriMesh::new(vertices, round.triangles().to_vec()).unwrap();
        // Three by two cells of its upper side missing: a hole of ten edges, closed.
        let cracked = without_cells(&flat, across, |i, j| {
            (10..13).contains(&i) && (5..7).contains(&j)
        });
        assert_eq!(
            boundary_loops(&cracked)
                .iter()
                .map(Vec::len)
                .collect::<Vec<_>>(),
            vec![10]
        );
        assert!(boundary_loops(&filled_along(&flat, &cracked)).is_empty());
        // A tube cut across is open in the input: the patches of its two ends would cap the
        // tube within half its thickness of its sides, but facing across them. They stay.
        let cut = without_cells(&flat, across, |i, _| i == 30);
        assert_eq!(boundary_loops(&cut).len(), 2);
        assert_eq!(filled_along(&cut, &cut).triangles(), cut.triangles());
    }

    #[test]
    fn a_triangle_over_a_lid_does_not_lie_along_the_surface() {
        // A plane with a 2 × 2-cell opening around its vertex (6, 6), under a lid a hundredth
        // above the whole plane, joined to it at a corner (one part, as a teapot's lid may
        // touch its pot); every vertex selected. A triangle across the opening, on corners of
        // its rim, is closest to the lid, which other selected vertices stand for, though
        // faces of the plane around the opening lie within reach of it, facing its way.
        let n = 12;
        let plane = grid_plane(n, n);
        let at = |i: u32, j: u32| j * (n + 1) + i;
        let around_opening = |t: &[u32; 3]| {
            t.iter().all(|&v| {
                let (i, j) = (v % (n + 1), v / (n + 1));
                (5..=7).contains(&i) && (5..=7).contains(&j)
            })
        };
        let count = plane.vertex_count() as u32;
        let mut vertices = plane.vertices().to_vec();
        vertices.extend(plane.vertices().iter().map(|p| [p[0], p[1], p[2] + 0.01]));
        let lid = plane
            .triangles()
            .iter()
            .map(|t| t.map(|v| if v == 0 { 0 } else { v + count }));
        let pot = plane
            .triangles()
            .iter()
            .filter(|t| !around_opening(t))
            .copied();
        let input = TriMesh::new(vertices.clone(), pot.clone().chain(lid).collect()).unwrap();
        let every: Vec<u32> = (0..2 * count).collect();
        let across = [at(5, 5), at(7, 5), at(7, 6)];
        let mut surface = InputSurface::new(&input, &every);
        assert!(!surface.lies_along(&[across], &vertices));
        // Without the lid the plane's faces around the opening are the closest and it does.
        let open_pot = TriMesh::new(vertices.clone(), pot.collect()).unwrap();
        assert!(InputSurface::new(&open_pot, &every).lies_along(&[across], &vertices));
    }

    #[test]
    fn a_patch_through_a_vertex_standing_for_none_is_refused() {
        let ring = torus(3.0, 1.0, 12, 6);
        let every: Vec<u32> = (0..ring.vertex_count() as u32).collect();
        let mut surface = InputSurface::new(&ring, &every);
        let mut positions = ring.vertices().to_vec();
        assert!(surface.lies_along(&[ring.triangles()[0]], &positions));
        // A centre vertex, past the selected ones, at the face's centroid.
        let [a, b, c] = ring.triangles()[0];
        let centroid = std::array::from_fn(|k| {
            [a, b, c]
                .iter()
                .map(|&v| positions[v as usize][k])
                .sum::<f32>()
                / 3.0
        });
        positions.push(centroid);
        let centre = every.len() as u32;
        assert!(!surface.lies_along(&[[a, b, centre]], &positions));
    }
}
