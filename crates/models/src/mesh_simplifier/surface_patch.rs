//! Whether a hole's patch lies along the input's surface: the test by which the neural mesh
//! simplifier closes the cracks of its output (beyond the thesis, ch. 6.4) and leaves the
//! openings of the input open. A crack is surface the network's faces missed, so under each
//! patch triangle the input has faces, standing for the hole's corners, one of them facing the
//! triangle's way. A patch across an opening has none: the faces under a pot's opening are a
//! lid's, which other selected vertices stand for, and beside a cap across a thin part's open
//! end the input's faces stand across the cap. Where a crack runs into an opening, the
//! triangles over the crack are added and the opening stays ([`crack_triangles`]).

use std::collections::HashMap;

use meshgnn_geometry::vec3::{cross, dot, norm, sub, to_f64};
use meshgnn_geometry::{TriMesh, connected_components, geodesic_voronoi_regions, squared_distance};
use meshgnn_graph::{ClosestFace, FacePoint};

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
    /// Each input vertex's part and each part's faces ([`faces_per_part`]); computed at the
    /// first patch.
    parts: Option<(Vec<u32>, Vec<Vec<u32>>)>,
    indexed: HashMap<u32, Option<ClosestFace<'a>>>,
    /// The selected vertex whose geodesic region holds each input vertex; computed at the
    /// first patch.
    region: Option<Vec<u32>>,
    scratch: Vec<(f32, u32)>,
}

impl<'a> InputSurface<'a> {
    /// Nothing is indexed until a patch is judged.
    pub(crate) fn new(input: &'a TriMesh, vertex_map: &'a [u32]) -> Self {
        Self {
            input,
            vertex_map,
            parts: None,
            indexed: HashMap::new(),
            region: None,
            scratch: Vec::new(),
        }
    }

    /// Which triangles of `patch` (triangles over selected vertices at `positions`) lie along
    /// the surface of the one input part the patch's corners stand for: the face of that part
    /// closest to the triangle's centroid lies within [`SURFACE_PATCH_TOLERANCE`] and has a
    /// corner in the geodesic region of one of the patch's corners, and so does a face within
    /// that distance facing the triangle's way ([`SURFACE_PATCH_NORMAL_AGREEMENT`]): on a thin
    /// tube a coarse triangle stands askew to the face closest to it, but the faces around the
    /// tube face every way. None for a patch with a vertex that stands for none (a centre
    /// vertex) or corners on several parts.
    pub(crate) fn triangles_along(
        &mut self,
        patch: &[[u32; 3]],
        positions: &[[f32; 3]],
    ) -> Vec<bool> {
        let none = vec![false; patch.len()];
        let input = self.input;
        let (part_of, part_faces) = self.parts.get_or_insert_with(|| faces_per_part(input));
        let stands_for = |v: u32| self.vertex_map.get(v as usize).copied();
        let part = |v: u32| stands_for(v).map(|i| part_of[i as usize]);
        let Some(first) = patch.first().and_then(|t| part(t[0])) else {
            return none;
        };
        if !patch.iter().flatten().all(|&v| part(v) == Some(first)) {
            return none;
        }
        let Some(closest) = self
            .indexed
            .entry(first)
            .or_insert_with(|| {
                ClosestFace::among(input, std::mem::take(&mut part_faces[first as usize])).ok()
            })
            .as_ref()
        else {
            return none;
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
        patch
            .iter()
            .map(|t| {
                let corners = t.map(|v| positions[v as usize]);
                let centroid: [f32; 3] =
                    std::array::from_fn(|k| corners.iter().map(|c| c[k]).sum::<f32>() / 3.0);
                let mean_edge = (0..3)
                    .map(|i| f64::from(squared_distance(&corners[i], &corners[(i + 1) % 3])).sqrt())
                    .sum::<f64>()
                    / 3.0;
                let tolerance = SURFACE_PATCH_TOLERANCE * mean_edge;
                // A triangle without area (along a straight stretch of the rim) faces no way.
                let normal = unit_normal(&corners);
                let mut nearest: Option<FacePoint> = None;
                let mut faces_its_way = normal.is_none();
                // One search: the faces within reach, the closest among them (the lowest index
                // among equally close ones, as `ClosestFace::query` picks).
                for hit in closest.within(&centroid, tolerance, scratch) {
                    if nearest.is_none_or(|n| {
                        (hit.squared_distance, hit.face) < (n.squared_distance, n.face)
                    }) {
                        nearest = Some(hit);
                    }
                    faces_its_way = faces_its_way
                        || normal.is_some_and(|normal| {
                            let face = input.triangles()[hit.face as usize]
                                .map(|c| input.vertices()[c as usize]);
                            unit_normal(&face).is_some_and(|n| {
                                dot(n, normal).abs() >= SURFACE_PATCH_NORMAL_AGREEMENT
                            }) && stands_for_corner(hit.face)
                        });
                }
                faces_its_way && nearest.is_some_and(|n| stands_for_corner(n.face))
            })
            .collect()
    }
}

/// Each vertex's part (vertices joined by faces) and each part's faces.
fn faces_per_part(input: &TriMesh) -> (Vec<u32>, Vec<Vec<u32>>) {
    let (parts, part_of) = connected_components(input);
    let mut part_faces = vec![Vec::new(); parts];
    for (f, t) in input.triangles().iter().enumerate() {
        part_faces[part_of[t[0] as usize] as usize].push(f as u32);
    }
    (part_of, part_faces)
}

/// The triangles of a hole's `patch` to add, given which of them lie `along` the input's
/// surface ([`InputSurface::triangles_along`]): all when all do; else, for a hole with a corner
/// off the input's border (`on_border`), those that do when every edge the patch would then
/// leave open (a rim edge whose triangle is left out, a diagonal with one of its two triangles)
/// runs between corners standing for the border: a crack that runs into an opening of the
/// input closes and the opening stays, bounded by the border. Otherwise none: a part of a patch
/// left beside other open edges (between a teapot's lid and its pot) would stand as a loose
/// flap, and part of the patch of an opening (all its corners on the border) may fold back
/// over the surface beside it.
pub(crate) fn crack_triangles(
    patch: &[[u32; 3]],
    along: Vec<bool>,
    on_border: impl Fn(u32) -> bool,
) -> Vec<bool> {
    if along.iter().all(|&a| a) {
        return along;
    }
    // A hole all of whose corners stand for the border is an opening of the input (its patch
    // may fold back over the surface beside it), not a crack that runs into one.
    if patch.iter().flatten().all(|&v| on_border(v)) {
        return vec![false; patch.len()];
    }
    // Per undirected patch edge: the triangles holding it, and how many of them are kept.
    let mut edges: HashMap<(u32, u32), (u32, u32)> = HashMap::new();
    for (t, &kept) in patch.iter().zip(&along) {
        for i in 0..3 {
            let (u, w) = (t[i], t[(i + 1) % 3]);
            let counts = edges.entry((u.min(w), u.max(w))).or_default();
            counts.0 += 1;
            counts.1 += u32::from(kept);
        }
    }
    let opening_only = edges.iter().all(|(&(u, w), &(holding, kept))| {
        let left_open = (holding == 1 && kept == 0) || (holding == 2 && kept == 1);
        !left_open || (on_border(u) && on_border(w))
    });
    if opening_only {
        along
    } else {
        vec![false; patch.len()]
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
    use meshgnn_geometry::{boundary_loops, fill_holes_partly, grid_plane, torus};

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

    /// `selected` (every vertex of `input` selected) with the triangles of each hole's
    /// least-area patch that lie along `input` added.
    fn filled_along(input: &TriMesh, selected: &TriMesh) -> TriMesh {
        let every: Vec<u32> = (0..input.vertex_count() as u32).collect();
        let mut surface = InputSurface::new(input, &every);
        fill_holes_partly(selected, 32, |patch| {
            surface.triangles_along(patch, selected.vertices())
        })
        .unwrap()
    }

    /// Whether `p` lies in the xy-projection of one of `mesh`'s faces.
    fn covered(mesh: &TriMesh, p: [f32; 2]) -> bool {
        let side = |a: [f32; 3], b: [f32; 3]| {
            (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])
        };
        (0..mesh.face_count()).any(|f| {
            let [a, b, c] = mesh.triangle_positions(f);
            let s = [side(a, b), side(b, c), side(c, a)];
            s.iter().all(|&x| x >= 0.0) || s.iter().all(|&x| x <= 0.0)
        })
    }

    #[test]
    fn the_crack_beside_an_opening_closes_and_the_opening_stays() {
        // A 12 × 12-cell plane with a 2 × 2-cell opening (cells 5-6 × 5-6); the selection also
        // misses the 2 × 2 cells to its right (7-8 × 5-6): one hole of twelve edges, half
        // crack, half opening. Its patch as a whole does not lie along the plane; the
        // triangles over the crack do.
        let n = 12;
        let plane = grid_plane(n, n);
        let cell = |t: &[u32; 3], range_i: std::ops::Range<u32>| {
            let centroid = |k: usize| {
                t.iter()
                    .map(|&v| plane.vertices()[v as usize][k])
                    .sum::<f32>()
                    / 3.0
            };
            let (i, j) = (
                (centroid(0) * n as f32) as u32,
                (centroid(1) * n as f32) as u32,
            );
            range_i.contains(&i) && (5..7).contains(&j)
        };
        let keep = |range_i: std::ops::Range<u32>| {
            let faces = plane
                .triangles()
                .iter()
                .filter(|t| !cell(t, range_i.clone()));
            TriMesh::new(plane.vertices().to_vec(), faces.copied().collect()).unwrap()
        };
        let (input, selected) = (keep(5..7), keep(5..9));
        let hole: Vec<usize> = boundary_loops(&selected).iter().map(Vec::len).collect();
        assert_eq!(hole, vec![48, 12]);
        let every: Vec<u32> = (0..input.vertex_count() as u32).collect();
        let mut surface = InputSurface::new(&input, &every);
        let border: Vec<u32> = boundary_loops(&input).concat();
        let mut whole_patch_along = None;
        let filled = fill_holes_partly(&selected, 12, |patch| {
            let along = surface.triangles_along(patch, selected.vertices());
            whole_patch_along = Some(along.iter().all(|&a| a));
            crack_triangles(patch, along, |v| border.contains(&v))
        })
        .unwrap();
        assert_eq!(whole_patch_along, Some(false));
        let unit = |x: f32| x / n as f32;
        assert!(!covered(&selected, [unit(8.0), unit(6.0)]));
        assert!(
            covered(&filled, [unit(8.0), unit(6.0)]),
            "the crack's centre"
        );
        assert!(
            !covered(&filled, [unit(6.0), unit(6.0)]),
            "the opening's centre"
        );
    }

    #[test]
    fn part_of_a_patch_is_added_only_when_what_stays_open_runs_along_the_border() {
        // The square a-b-c-d as two triangles over the diagonal (a, c).
        let [a, b, c, d] = [0, 1, 2, 3];
        let patch = [[a, b, c], [a, c, d]];
        let border_at = |on: Vec<u32>| move |v: u32| on.contains(&v);
        // Both lie along: both, whatever the border.
        assert_eq!(
            crack_triangles(&patch, vec![true; 2], border_at(vec![])),
            [true, true]
        );
        // The first only: (c, d), (d, a) and the diagonal (a, c) stay open. On the border
        // they bound an opening and the first triangle closes the crack beside it.
        let first = vec![true, false];
        assert_eq!(
            crack_triangles(&patch, first.clone(), border_at(vec![a, c, d])),
            [true, false]
        );
        // With d off the border the triangle would stand beside open surface: none.
        assert_eq!(
            crack_triangles(&patch, first, border_at(vec![a, b, c])),
            [false, false]
        );
        // Every corner on the border: an opening of the input, not a crack; none.
        assert_eq!(
            crack_triangles(&patch, vec![true, false], border_at(vec![a, b, c, d])),
            [false, false]
        );
        // Neither lies along: none.
        assert_eq!(
            crack_triangles(&patch, vec![false; 2], border_at(vec![a, b, c, d])),
            [false, false]
        );
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
        assert_eq!(surface.triangles_along(&[across], &vertices), [false]);
        // Without the lid the plane's faces around the opening are the closest and it does.
        let open_pot = TriMesh::new(vertices.clone(), pot.collect()).unwrap();
        let mut surface = InputSurface::new(&open_pot, &every);
        assert_eq!(surface.triangles_along(&[across], &vertices), [true]);
    }

    #[test]
    fn a_patch_through_a_vertex_standing_for_none_is_refused() {
        let ring = torus(3.0, 1.0, 12, 6);
        let every: Vec<u32> = (0..ring.vertex_count() as u32).collect();
        let mut surface = InputSurface::new(&ring, &every);
        let mut positions = ring.vertices().to_vec();
        assert_eq!(
            surface.triangles_along(&[ring.triangles()[0]], &positions),
            [true]
        );
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
        assert_eq!(
            surface.triangles_along(&[[a, b, centre]], &positions),
            [false]
        );
    }
}
