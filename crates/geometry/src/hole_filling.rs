//! Closes small holes: every boundary loop of at most `max_edges` edges is triangulated with
//! the least total area (Barequet & Sharir's dynamic programme, the area weight of Liepa 2003,
//! "Filling holes in meshes"), the way MeshLab's "Close Holes" filter bounds the hole size in
//! edges. The neural mesh simplifier's `--fill-holes` runs it after its manifold pass.
//!
//! The new faces run every loop edge against its face, so an oriented mesh stays oriented; a
//! diagonal that is already an edge of the mesh (or of a hole filled before) is never used, so
//! an edge-manifold mesh stays edge-manifold. A loop that passes a vertex twice (two holes
//! meeting at a vertex) is split there into simple loops, each filled on its own. A loop with
//! no triangulation of its own vertices under those rules (every diagonal already an edge, as
//! across a fold) gets one new vertex at the mean of its corners and a fan of triangles to
//! it, whose new edges cannot exist yet (Liepa's method adds vertices to every patch; this
//! adds one only where nothing else closes the hole). A chain that does not close is left open.

use std::collections::{HashMap, HashSet};

use crate::edge_topology::edge_topology;
use crate::error::{Error, Result};
use crate::vec3::{norm, triangle_cross};
use crate::{TriMesh, boundary_loops::boundary_loops_in};

/// The largest hole [`fill_holes`] accepts to close: the programme takes `O(k³)` time and
/// `O(k²)` memory for a loop of `k` edges.
pub const MAX_FILLED_HOLE_EDGES: usize = 1000;

/// `mesh` with every boundary loop of 3 to `max_edges` edges closed (module docs); the
/// vertices are kept (a loop with no triangulation of its own corners adds one after them),
/// the new faces follow the old ones. Errors when `max_edges` exceeds
/// [`MAX_FILLED_HOLE_EDGES`].
///
/// ```
/// use meshgnn_geometry::{boundary_loops, fill_holes, icosphere, TriMesh};
/// let sphere = icosphere(2);
/// let mut faces = sphere.triangles().to_vec();
/// faces.truncate(faces.len() - 3); // three faces off: one hole
/// let open = TriMesh::new(sphere.vertices().to_vec(), faces)?;
/// assert_eq!(boundary_loops(&open).len(), 1);
/// let closed = fill_holes(&open, 30)?;
/// assert!(boundary_loops(&closed).is_empty());
/// assert!(meshgnn_geometry::is_watertight(&closed));
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn fill_holes(mesh: &TriMesh, max_edges: usize) -> Result<TriMesh> {
    fill(mesh, max_edges, &mut |patch| vec![true; patch.len()], false)
}

/// [`fill_holes`] leaving open every hole whose patch `closable` refuses (its triangles; a
/// centre vertex has the index after the last vertex), and every hole whose least-area patch would
/// repeat a face on the same corners (the rim of a lone face or of two faces on an edge:
/// filled, a flat two-sided pillow): a simplifier closes the cracks it made and keeps the
/// input's borders.
///
/// ```
/// use meshgnn_geometry::{boundary_loops, fill_holes_where, icosphere, TriMesh};
/// let sphere = icosphere(2);
/// let mut faces = sphere.triangles().to_vec();
/// let hole = faces.pop().unwrap();
/// let open = TriMesh::new(sphere.vertices().to_vec(), faces)?;
/// assert!(boundary_loops(&fill_holes_where(&open, 30, |_| true)?).is_empty());
/// let away_from_corner = |patch: &[[u32; 3]]| patch.iter().all(|t| !t.contains(&hole[0]));
/// assert_eq!(boundary_loops(&fill_holes_where(&open, 30, away_from_corner)?).len(), 1);
/// // A lone face is left: its patch would be the same face turned over.
/// let lone = TriMesh::new(sphere.vertices().to_vec(), vec![hole])?;
/// assert_eq!(fill_holes_where(&lone, 30, |_| true)?.face_count(), 1);
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn fill_holes_where(
    mesh: &TriMesh,
    max_edges: usize,
    mut closable: impl FnMut(&[[u32; 3]]) -> bool,
) -> Result<TriMesh> {
    fill(
        mesh,
        max_edges,
        &mut |patch| vec![closable(patch); patch.len()],
        true,
    )
}

/// [`fill_holes_where`] adding, of each hole's patch, the triangles `keep` marks (one flag per
/// triangle): where a hole joins a crack to an opening that should stay, the crack's part of
/// the patch closes and the opening stays, its rim now running along the patch's diagonals.
/// Every edge still has at most two faces (a diagonal is never an existing edge).
///
/// ```
/// use meshgnn_geometry::{boundary_loops, fill_holes_partly, icosphere, TriMesh};
/// let sphere = icosphere(2);
/// let mut faces = sphere.triangles().to_vec();
/// faces.truncate(faces.len() - 4); // four faces off: one hole of six edges
/// let open = TriMesh::new(sphere.vertices().to_vec(), faces)?;
/// // Of its four patch triangles, the first two.
/// let half = fill_holes_partly(&open, 30, |patch| (0..patch.len()).map(|i| i < 2).collect())?;
/// assert_eq!(half.face_count(), open.face_count() + 2);
/// assert_eq!(boundary_loops(&half).len(), 1);
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn fill_holes_partly(
    mesh: &TriMesh,
    max_edges: usize,
    mut keep: impl FnMut(&[[u32; 3]]) -> Vec<bool>,
) -> Result<TriMesh> {
    fill(mesh, max_edges, &mut keep, true)
}

/// The filling of [`fill_holes`], [`fill_holes_where`] and [`fill_holes_partly`]: of each
/// hole's patch the triangles `keep` marks are added; with `refuse_pillows` a hole whose
/// least-area patch repeats an existing face's corners stays open.
fn fill(
    mesh: &TriMesh,
    max_edges: usize,
    keep: &mut dyn FnMut(&[[u32; 3]]) -> Vec<bool>,
    refuse_pillows: bool,
) -> Result<TriMesh> {
    if max_edges > MAX_FILLED_HOLE_EDGES {
        return Err(Error::InvalidParameter {
            name: "max_edges",
            message: format!(
                "{max_edges} is more than the {MAX_FILLED_HOLE_EDGES} boundary edges a hole \
                 may have to be filled"
            ),
        });
    }
    let topology = edge_topology(mesh);
    let key = |a: u32, b: u32| (a.min(b), a.max(b));
    let mut edges: HashSet<(u32, u32)> = topology.edges().iter().map(|&[a, b]| key(a, b)).collect();
    let boundary: HashSet<(u32, u32)> = (0..topology.edge_count())
        .filter(|&e| topology.valence(e) == 1)
        .map(|e| {
            let [a, b] = topology.edges()[e];
            key(a, b)
        })
        .collect();
    let mut faces = mesh.triangles().to_vec();
    let mut vertices = mesh.vertices().to_vec();
    let corner_sets: HashSet<[u32; 3]> = if refuse_pillows {
        faces.iter().map(|&t| sorted(t)).collect()
    } else {
        HashSet::new()
    };
    let loops = boundary_loops_in(&topology);
    for hole in loops.iter().flat_map(|hole| simple_loops(hole)) {
        let k = hole.len();
        let closes = (0..k).all(|i| boundary.contains(&key(hole[i], hole[(i + 1) % k])));
        if !(3..=max_edges).contains(&k) || !closes {
            continue;
        }
        let (patch, centre) = match least_area_triangulation(&vertices, &hole, &edges) {
            Some(patch) if patch.iter().any(|t| corner_sets.contains(&sorted(*t))) => continue,
            Some(patch) => (patch, None),
            None => centre_fan(&vertices, &hole),
        };
        let marks = keep(&patch);
        let kept: Vec<[u32; 3]> = patch
            .iter()
            .zip(marks.iter().chain(std::iter::repeat(&false)))
            .filter_map(|(&t, &kept)| kept.then_some(t))
            .collect();
        let centre_index = vertices.len() as u32;
        if kept.iter().flatten().any(|&v| v == centre_index) {
            vertices.extend(centre);
        }
        for &[a, b, c] in &kept {
            edges.extend([key(a, b), key(b, c), key(c, a)]);
        }
        faces.extend(kept);
    }
    TriMesh::new(vertices, faces)
}

/// The corners of `t` in increasing order.
fn sorted(mut t: [u32; 3]) -> [u32; 3] {
    t.sort_unstable();
    t
}

/// The fan of triangles from a new vertex at the mean of the corners of the closed polygon
/// `hole`, each running its polygon side backwards (like [`least_area_triangulation`]'s), and
/// that vertex, to be appended to `vertices`.
fn centre_fan(vertices: &[[f32; 3]], hole: &[u32]) -> (Vec<[u32; 3]>, Option<[f32; 3]>) {
    let k = hole.len();
    let sum = hole.iter().fold([0.0f64; 3], |s, &v| {
        let p = vertices[v as usize];
        std::array::from_fn(|i| s[i] + f64::from(p[i]))
    });
    let centre = vertices.len() as u32;
    let fan = (0..k)
        .map(|i| [hole[(i + 1) % k], hole[i], centre])
        .collect();
    (fan, Some(sum.map(|x| (x / k as f64) as f32)))
}

/// The closed walk `hole` cut into simple loops at every vertex it passes twice, each in the
/// walk's direction: `a b c a d e` becomes `a b c` and `a d e`.
fn simple_loops(hole: &[u32]) -> Vec<Vec<u32>> {
    let mut loops = Vec::new();
    let mut walk: Vec<u32> = Vec::with_capacity(hole.len());
    let mut position: HashMap<u32, usize> = HashMap::new();
    for &v in hole {
        if let Some(&p) = position.get(&v) {
            // The walk came back to v: what it went round since is a loop.
            let cycle = walk.split_off(p);
            for u in &cycle {
                position.remove(u);
            }
            loops.push(cycle);
        }
        position.insert(v, walk.len());
        walk.push(v);
    }
    loops.push(walk);
    loops
}

/// The triangulation of the closed polygon `hole` with the least total area whose diagonals
/// are not in `edges`, each triangle running the polygon backwards; `None` when every
/// triangulation needs an existing edge.
fn least_area_triangulation(
    vertices: &[[f32; 3]],
    hole: &[u32],
    edges: &HashSet<(u32, u32)>,
) -> Option<Vec<[u32; 3]>> {
    let k = hole.len();
    let corner = |i: usize| vertices[hole[i] as usize];
    let usable = |i: usize, j: usize| {
        // Polygon sides (consecutive, or the closing pair) are the hole's own edges.
        let (a, b) = (hole[i], hole[j]);
        j == i + 1 || (i == 0 && j == k - 1) || !edges.contains(&(a.min(b), a.max(b)))
    };
    // cost[i][j]: least area of the polygon i, i+1, …, j closed by the chord (i, j);
    // split[i][j]: the apex m of the triangle on that chord.
    let mut cost = vec![f64::INFINITY; k * k];
    let mut split = vec![0usize; k * k];
    for i in 0..k - 1 {
        cost[i * k + i + 1] = 0.0;
    }
    for span in 2..k {
        for i in 0..k - span {
            let j = i + span;
            if !usable(i, j) {
                continue;
            }
            for m in i + 1..j {
                let area = 0.5 * norm(triangle_cross([corner(i), corner(m), corner(j)]));
                let total = cost[i * k + m] + cost[m * k + j] + area;
                if total < cost[i * k + j] {
                    cost[i * k + j] = total;
                    split[i * k + j] = m;
                }
            }
        }
    }
    if !cost[k - 1].is_finite() {
        return None;
    }
    let mut triangles = Vec::with_capacity(k - 2);
    let mut stack = vec![(0, k - 1)];
    while let Some((i, j)) = stack.pop() {
        if j < i + 2 {
            continue;
        }
        let m = split[i * k + j];
        triangles.push([hole[j], hole[m], hole[i]]);
        stack.extend([(i, m), (m, j)]);
    }
    Some(triangles)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{boundary_loops, grid_plane, icosphere, is_edge_manifold, is_watertight};

    /// `mesh` without the faces `drop`.
    fn without(mesh: &TriMesh, drop: &[usize]) -> TriMesh {
        let faces = (0..mesh.face_count())
            .filter(|f| !drop.contains(f))
            .map(|f| mesh.triangles()[f])
            .collect();
        TriMesh::new(mesh.vertices().to_vec(), faces).unwrap()
    }

    fn area(mesh: &TriMesh, from: usize) -> f64 {
        (from..mesh.face_count())
            .map(|f| 0.5 * norm(triangle_cross(mesh.triangle_positions(f))))
            .sum()
    }

    #[test]
    fn a_square_hole_gets_two_triangles_of_its_area_oriented_like_the_rest() {
        // 3×3 grid of unit squares; the two faces of the centre square removed.
        let grid = grid_plane(3, 3);
        let centre: Vec<usize> = (0..grid.face_count())
            .filter(|&f| {
                let c = grid.triangle_positions(f);
                let x = (c[0][0] + c[1][0] + c[2][0]) / 3.0;
                let y = (c[0][1] + c[1][1] + c[2][1]) / 3.0;
                let (lo, hi) = (grid.vertices()[5][0], grid.vertices()[10][0]);
                x > lo && x < hi && y > grid.vertices()[5][1] && y < grid.vertices()[10][1]
            })
            .collect();
        assert_eq!(centre.len(), 2);
        let open = without(&grid, &centre);
        assert_eq!(boundary_loops(&open).len(), 2);
        let closed = fill_holes(&open, 4).unwrap();
        assert_eq!(closed.face_count(), grid.face_count());
        // The outer rim (12 edges) is longer than 4 and stays; the hole is gone.
        assert_eq!(boundary_loops(&closed).len(), 1);
        let side = f64::from(grid.vertices()[1][0] - grid.vertices()[0][0]);
        assert!((area(&closed, open.face_count()) - side * side).abs() < 1e-6);
        // Same winding as the grid: every new face's normal points like the old ones.
        let up = triangle_cross(grid.triangle_positions(0))[2].signum();
        for f in open.face_count()..closed.face_count() {
            assert_eq!(triangle_cross(closed.triangle_positions(f))[2].signum(), up);
        }
        assert!(is_edge_manifold(&closed));
    }

    #[test]
    fn a_walk_through_a_vertex_twice_splits_into_simple_loops() {
        assert_eq!(
            simple_loops(&[0, 1, 2, 0, 3, 4]),
            vec![vec![0, 1, 2], vec![0, 3, 4]]
        );
        assert_eq!(simple_loops(&[5, 6, 7]), vec![vec![5, 6, 7]]);
        // Nested: 1 is passed twice inside the loop through 0.
        assert_eq!(
            simple_loops(&[0, 1, 2, 3, 1, 4, 5]),
            vec![vec![1, 2, 3], vec![0, 1, 4, 5]]
        );
    }

    #[test]
    fn two_holes_meeting_at_a_vertex_are_both_filled() {
        // A 4×4 grid: the two faces of cell (1, 2) and of cell (2, 1) off. The cells touch at
        // one corner, so their boundaries form one walk through it.
        let grid = grid_plane(4, 4);
        // Cell (i, j) of the grid over the unit square, by the faces' barycentres.
        let square = |i: f32, j: f32| -> Vec<usize> {
            (0..grid.face_count())
                .filter(|&f| {
                    let c = grid.triangle_positions(f);
                    let x = (c[0][0] + c[1][0] + c[2][0]) / 3.0;
                    let y = (c[0][1] + c[1][1] + c[2][1]) / 3.0;
                    (x * 4.0).floor() == i && (y * 4.0).floor() == j
                })
                .collect()
        };
        let mut drop = square(1.0, 2.0);
        drop.extend(square(2.0, 1.0));
        assert_eq!(drop.len(), 4);
        let open = without(&grid, &drop);
        assert_eq!(boundary_loops(&open).len(), 2);
        // 8 edges: the two 4-edge holes, not the 16-edge rim.
        let closed = fill_holes(&open, 8).unwrap();
        assert_eq!(closed.face_count(), grid.face_count());
        assert!(is_edge_manifold(&closed));
        // Only the outer rim is left.
        assert_eq!(boundary_loops(&closed).len(), 1);
    }

    #[test]
    fn the_least_area_triangulation_of_a_folded_quad_takes_the_short_diagonal() {
        // A quad folded along (1, 3): the diagonal (0, 2) spans the fold, giving more area.
        let v = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 1.0],
            [0.0, 1.0, 0.0],
        ];
        let (a1, a2) = (
            0.5 * norm(triangle_cross([v[0], v[1], v[3]]))
                + 0.5 * norm(triangle_cross([v[1], v[2], v[3]])),
            0.5 * norm(triangle_cross([v[0], v[1], v[2]]))
                + 0.5 * norm(triangle_cross([v[0], v[2], v[3]])),
        );
        assert!(a1 < a2);
        let fill = least_area_triangulation(&v, &[0, 1, 2, 3], &HashSet::new()).unwrap();
        let diagonal_13 = fill.iter().all(|t| t.contains(&1) && t.contains(&3));
        assert!(diagonal_13, "{fill:?}");
        // With (1, 3) already an edge, the other diagonal is the only choice.
        let fill = least_area_triangulation(&v, &[0, 1, 2, 3], &HashSet::from([(1, 3)])).unwrap();
        assert!(fill.iter().all(|t| t.contains(&0) && t.contains(&2)));
        // With both, no triangulation exists.
        let both = HashSet::from([(1, 3), (0, 2)]);
        assert!(least_area_triangulation(&v, &[0, 1, 2, 3], &both).is_none());
    }

    /// A tetrahedron 0-1-2-3 without the two faces on (0, 2): the hole 0-1-2-3 has (1, 3) as
    /// an inner edge; a second tetrahedron 0-2-4-5 holds (0, 2). No triangulation of the four
    /// corners avoids both.
    fn hole_with_both_diagonals_taken() -> (Vec<[f32; 3]>, TriMesh) {
        let v = vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.5, 0.9, 0.0],
            [0.5, 0.3, 0.8],
            [-0.5, 0.5, -0.5],
            [0.2, 0.6, -0.9],
        ];
        let faces = vec![
            [0, 3, 1],
            [1, 3, 2],
            [0, 2, 4],
            [0, 5, 2],
            [0, 4, 5],
            [2, 5, 4],
        ];
        (v.clone(), TriMesh::new(v, faces).unwrap())
    }

    #[test]
    fn a_hole_whose_diagonals_are_both_edges_closes_with_a_centre_vertex() {
        let (v, open) = hole_with_both_diagonals_taken();
        assert!(is_edge_manifold(&open));
        assert_eq!(boundary_loops(&open).len(), 1);
        let closed = fill_holes(&open, 30).unwrap();
        assert!(is_watertight(&closed) && is_edge_manifold(&closed));
        assert_eq!(closed.vertex_count(), v.len() + 1);
        assert_eq!(closed.face_count(), open.face_count() + 4);
        // Where every hole may close, the same: a fan repeats no face's corners.
        let away = fill_holes_where(&open, 30, |_| true).unwrap();
        assert_eq!(away.vertices(), closed.vertices());
        assert_eq!(away.triangles(), closed.triangles());
        let centre = closed.vertices()[v.len()];
        for (i, c) in centre.iter().enumerate() {
            let mean = (0..4).map(|k| v[k][i]).sum::<f32>() / 4.0;
            assert!((c - mean).abs() < 1e-6);
        }
        // Every new face has the centre and a side of the hole, run against its old face.
        for f in open.face_count()..closed.face_count() {
            let [a, b, c] = closed.triangles()[f];
            assert_eq!(c as usize, v.len());
            assert!(
                open.triangles()
                    .iter()
                    .any(|t| { (0..3).any(|i| t[i] == b && t[(i + 1) % 3] == a) })
            );
        }
    }

    #[test]
    fn a_partly_kept_patch_adds_only_its_marked_triangles() {
        // Cells (1, 1) and (2, 1) of a 4×4 grid off: one hole of six edges, four patch
        // triangles (the outer rim, 16 edges, stays open).
        let grid = grid_plane(4, 4);
        let cell = |f: usize| {
            let c = grid.triangle_positions(f);
            let side = grid.vertices()[1][0] - grid.vertices()[0][0];
            let lo = grid.vertices()[0];
            let at = |k: usize| ((c[0][k] + c[1][k] + c[2][k]) / 3.0 - lo[k]) / side;
            (at(0) as u32, at(1) as u32)
        };
        let cut: Vec<usize> = (0..grid.face_count())
            .filter(|&f| matches!(cell(f), (1, 1) | (2, 1)))
            .collect();
        assert_eq!(cut.len(), 4);
        let open = without(&grid, &cut);
        let mut seen = Vec::new();
        let every_other = fill_holes_partly(&open, 6, |patch| {
            seen = patch.to_vec();
            (0..patch.len()).map(|i| i % 2 == 0).collect()
        })
        .unwrap();
        assert_eq!(seen.len(), 4);
        let added = &every_other.triangles()[open.face_count()..];
        assert_eq!(added, [seen[0], seen[2]]);
        assert_eq!(every_other.vertex_count(), open.vertex_count());
        assert!(is_edge_manifold(&every_other));
        let up = triangle_cross(grid.triangle_positions(0))[2].signum();
        for f in open.face_count()..every_other.face_count() {
            assert_eq!(
                triangle_cross(every_other.triangle_positions(f))[2].signum(),
                up
            );
        }
        // All marked: the same as `fill_holes`; none marked: unchanged.
        let all = fill_holes_partly(&open, 6, |patch| vec![true; patch.len()]).unwrap();
        assert_eq!(all.triangles(), fill_holes(&open, 6).unwrap().triangles());
        let none = fill_holes_partly(&open, 6, |patch| vec![false; patch.len()]).unwrap();
        assert_eq!(none.triangles(), open.triangles());
    }

    #[test]
    fn a_centre_vertex_is_added_only_when_a_kept_triangle_uses_it() {
        let (v, open) = hole_with_both_diagonals_taken();
        let one = fill_holes_partly(&open, 30, |patch| {
            (0..patch.len()).map(|i| i == 0).collect()
        })
        .unwrap();
        assert_eq!(one.vertex_count(), v.len() + 1);
        assert_eq!(one.face_count(), open.face_count() + 1);
        assert!(is_edge_manifold(&one));
        let none = fill_holes_partly(&open, 30, |patch| vec![false; patch.len()]).unwrap();
        assert_eq!(none.vertex_count(), v.len());
    }

    #[test]
    fn holes_in_a_sphere_close_into_a_watertight_mesh_and_long_ones_stay_open() {
        let sphere = icosphere(3);
        // Faces around vertex 0 and around a far vertex: two separate holes.
        let around = |v: u32| -> Vec<usize> {
            (0..sphere.face_count())
                .filter(|&f| sphere.triangles()[f].contains(&v))
                .collect()
        };
        let far = (0..sphere.vertex_count() as u32)
            .max_by(|&a, &b| {
                let d = |v: u32| {
                    crate::vec3::squared_distance_f64(
                        &sphere.vertices()[0],
                        &sphere.vertices()[v as usize],
                    )
                };
                d(a).total_cmp(&d(b))
            })
            .unwrap();
        let mut drop = around(0);
        drop.extend(around(far));
        let open = without(&sphere, &drop);
        assert_eq!(boundary_loops(&open).len(), 2);
        let closed = fill_holes(&open, 30).unwrap();
        assert!(is_watertight(&closed));
        assert!(is_edge_manifold(&closed));
        let kept = fill_holes(&open, 4).unwrap();
        assert_eq!(kept, open);
    }

    #[test]
    fn too_large_a_bound_is_an_error_and_a_closed_mesh_is_unchanged() {
        let sphere = icosphere(1);
        assert!(fill_holes(&sphere, MAX_FILLED_HOLE_EDGES + 1).is_err());
        assert_eq!(fill_holes(&sphere, 30).unwrap(), sphere);
    }
}
