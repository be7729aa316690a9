//! Surface reconstruction of a point cloud by Delaunay triangulation of local tangent charts:
//! the re-triangulation step of the thesis' mesh route (ch. 5.5.3, "the remaining vertices are
//! re-triangulated using an off-the-shelf triangulation algorithm such as Ball Pivoting";
//! "Delaunay, alpha shapes or Voronoi diagrams could also be used").
//!
//! Method: Gopi, Krishnan and Silva, "Surface reconstruction based on lower dimensional
//! localized Delaunay triangulation", Eurographics 2000, with Hoppe et al.'s normal
//! orientation (SIGGRAPH 1992). Each point's `k` nearest neighbours are projected onto its
//! tangent plane (PCA normal of eq. 5.1-5.2), triangulated there with spade's exact 2-D
//! Delaunay, and the triangles around the point are its vote; triangles are then accepted
//! most-voted first under an oriented-manifold rule, and small holes are closed.
//!
//! # Why not ball pivoting
//! Ball pivoting needs one ball radius for the whole cloud. The learned simplifier and TCP
//! keep points densely at sharp features and sparsely on flat parts, so any single radius
//! either tears the flat parts or bridges the dense ones (the thesis itself notes in ch. 6.6
//! that ball pivoting "requires careful hyperparameter tuning"). Local Delaunay charts adapt
//! to the local spacing through the k-NN, have no radius, and spade's exact predicates make
//! each chart robust.
//!
//! # Conventions
//! - Normals: PCA normals of the same `k` neighbours; with `normals` given, each PCA normal is
//!   flipped to agree with the given one; otherwise orientation propagates along a minimum
//!   spanning tree of the k-NN graph (weight `1 − |n_i·n_j|`) from the point farthest from the
//!   centroid, whose normal points away from it (outward on closed surfaces).
//! - Output faces are counter-clockwise seen from the side the normals point to, and the mesh
//!   is oriented-edge-manifold: every directed edge is used at most once, so every edge has at
//!   most two faces and they agree in orientation.
//! - Vote ties are broken by the shorter longest edge, then by vertex indices: deterministic
//!   for any thread count.
//! - Every input point is an output vertex (possibly unreferenced, counted in the result).

use std::collections::HashSet;

use rayon::prelude::*;
use spade::{DelaunayTriangulation, Point2, Triangulation};

use crate::boundary_loops::boundary_loops;
use crate::curvature_neighbourhoods::curvature_neighbourhoods;
use crate::error::{Error, Result};
use crate::normalization::centroid;
use crate::pca_normals::CovarianceAt;
use crate::tri_mesh::{TriMesh, check_finite, check_len};
use crate::vec3::{cross, dot, norm, sub, to_f64, triangle_cross};

/// Options of [`tangent_chart_triangulation`]; update with `..Default::default()`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TangentChartOptions {
    /// Neighbours per chart (and for the PCA normals); capped at `#P − 1`.
    pub neighbours: usize,
    /// Boundary loops with at most this many edges are closed (0 keeps every hole).
    pub max_hole_edges: usize,
}

impl Default for TangentChartOptions {
    fn default() -> Self {
        Self {
            neighbours: 12,
            max_hole_edges: 8,
        }
    }
}

/// The result of [`tangent_chart_triangulation`].
#[derive(Debug, Clone, PartialEq)]
pub struct Reconstruction {
    /// The mesh: every input point as a vertex, oriented faces.
    pub mesh: TriMesh,
    /// Boundary loops left open (0 for a watertight result).
    pub holes: usize,
    /// Small holes closed by [`TangentChartOptions::max_hole_edges`].
    pub filled_holes: usize,
    /// Input points no face uses.
    pub unreferenced_points: usize,
    /// The oriented unit normals used for the charts, `#P×3`.
    pub normals: Vec<[f32; 3]>,
}

/// Ch. 5.5.3 (mesh route): triangulates `points: #P×3` (optionally with `normals: #P×3` that
/// fix the orientation) by local Delaunay triangulations in tangent charts.
///
/// Fails on fewer than 3 points, non-finite values, a normals length other than `#P`, or
/// `options.neighbours < 3`.
///
/// ```
/// use meshgnn_geometry::{TangentChartOptions, icosphere, is_watertight, tangent_chart_triangulation};
/// let sphere = icosphere(2);
/// let r = tangent_chart_triangulation(sphere.vertices(), None, &TangentChartOptions::default())?;
/// assert_eq!(r.holes, 0);
/// assert!(is_watertight(&r.mesh));
/// assert_eq!(r.mesh.face_count(), sphere.face_count());
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn tangent_chart_triangulation(
    points: &[[f32; 3]],
    normals: Option<&[[f32; 3]]>,
    options: &TangentChartOptions,
) -> Result<Reconstruction> {
    let n = points.len();
    if n < 3 {
        return Err(Error::InvalidParameter {
            name: "points",
            message: format!("need at least 3 points to triangulate, got {n}"),
        });
    }
    check_finite("point", points)?;
    if let Some(given) = normals {
        check_len("point normals", n, given.len())?;
        check_finite("normal", given)?;
    }
    if options.neighbours < 3 {
        return Err(Error::InvalidParameter {
            name: "neighbours",
            message: format!("need at least 3 per chart, got {}", options.neighbours),
        });
    }
    let k = options.neighbours.min(n - 1).max(2);
    let neighbours = curvature_neighbourhoods(points, k)?.indices;
    let mut oriented = pca_normals(points, &neighbours, k);
    match normals {
        Some(given) => {
            for (normal, hint) in oriented.iter_mut().zip(given) {
                if dot(*normal, to_f64(*hint)) < 0.0 {
                    *normal = normal.map(|x| -x);
                }
            }
        }
        None => propagate_orientation(points, &neighbours, k, &mut oriented),
    }
    let votes = chart_votes(points, &neighbours, k, &oriented);
    let mut faces = accept(points, votes);
    if normals.is_none() {
        orient_outward(points, &mut faces);
    }
    let mut mesh = TriMesh::new(points.to_vec(), faces)?;
    let filled_holes = fill_small_holes(&mut mesh, options.max_hole_edges)?;
    let holes = boundary_loops(&mesh).len();
    let mut used = vec![false; n];
    for t in mesh.triangles() {
        for &v in t {
            used[v as usize] = true;
        }
    }
    Ok(Reconstruction {
        holes,
        filled_holes,
        unreferenced_points: used.iter().filter(|&&u| !u).count(),
        normals: oriented.iter().map(|v| v.map(|x| x as f32)).collect(),
        mesh,
    })
}

/// Row `i` of the flat neighbour lists, without padding.
fn row(neighbours: &[u32], k: usize, i: usize) -> impl Iterator<Item = usize> + '_ {
    neighbours[i * k..(i + 1) * k]
        .iter()
        .filter(|&&j| j != u32::MAX)
        .map(|&j| j as usize)
}

/// Eq. 5.1-5.2 normals from the stored neighbour lists, oriented away from the centroid.
fn pca_normals(points: &[[f32; 3]], neighbours: &[u32], k: usize) -> Vec<[f64; 3]> {
    let center = centroid(points);
    (0..points.len())
        .into_par_iter()
        .map(|i| {
            let mut covariance = CovarianceAt::new(points[i]);
            for j in row(neighbours, k, i) {
                covariance.add(points[j]);
            }
            covariance.normal_and_curvature(center).0.map(f64::from)
        })
        .collect()
}

/// Hoppe et al. 1992: flips normals so they agree along a minimum spanning tree of the k-NN
/// graph (Prim, weight `1 − |n_i·n_j|`), one tree per k-NN component, each seeded at its point
/// farthest from the centroid with the normal pointing away from the centroid.
fn propagate_orientation(
    points: &[[f32; 3]],
    neighbours: &[u32],
    k: usize,
    normals: &mut [[f64; 3]],
) {
    use std::cmp::Reverse;
    use std::collections::BinaryHeap;

    let center = centroid(points);
    let mut by_distance: Vec<(u64, u32)> = points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let d = sub(to_f64(*p), center);
            (dot(d, d).to_bits(), i as u32)
        })
        .collect();
    by_distance.sort_unstable_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(&b.1)));
    let mut visited = vec![false; points.len()];
    // (weight bits, node, parent): non-negative f64 bits order like the values.
    let mut heap: BinaryHeap<Reverse<(u64, u32, u32)>> = BinaryHeap::new();
    for &(_, seed) in &by_distance {
        let seed = seed as usize;
        if visited[seed] {
            continue;
        }
        let outward = sub(to_f64(points[seed]), center);
        if dot(normals[seed], outward) < 0.0 {
            normals[seed] = normals[seed].map(|x| -x);
        }
        visited[seed] = true;
        push_edges(&mut heap, neighbours, k, normals, &visited, seed);
        while let Some(Reverse((_, node, parent))) = heap.pop() {
            let (node, parent) = (node as usize, parent as usize);
            if visited[node] {
                continue;
            }
            visited[node] = true;
            if dot(normals[node], normals[parent]) < 0.0 {
                normals[node] = normals[node].map(|x| -x);
            }
            push_edges(&mut heap, neighbours, k, normals, &visited, node);
        }
    }
}

/// Pushes the unvisited neighbours of `from` with their MST weights.
fn push_edges(
    heap: &mut std::collections::BinaryHeap<std::cmp::Reverse<(u64, u32, u32)>>,
    neighbours: &[u32],
    k: usize,
    normals: &[[f64; 3]],
    visited: &[bool],
    from: usize,
) {
    for j in row(neighbours, k, from) {
        if !visited[j] {
            let weight = (1.0 - dot(normals[from], normals[j]).abs()).max(0.0);
            heap.push(std::cmp::Reverse((weight.to_bits(), j as u32, from as u32)));
        }
    }
}

/// A triangle in canonical rotation (smallest index first, winding kept).
fn canonical([a, b, c]: [u32; 3]) -> [u32; 3] {
    if a < b && a < c {
        [a, b, c]
    } else if b < c {
        [b, c, a]
    } else {
        [c, a, b]
    }
}

/// The triangles around each point in the Delaunay triangulation of its tangent chart,
/// counter-clockwise about its normal, canonical; all charts concatenated.
fn chart_votes(
    points: &[[f32; 3]],
    neighbours: &[u32],
    k: usize,
    normals: &[[f64; 3]],
) -> Vec<[u32; 3]> {
    (0..points.len())
        .into_par_iter()
        .flat_map_iter(|i| chart_star(points, neighbours, k, normals, i))
        .collect()
}

/// The star of point `i` in its chart's Delaunay triangulation.
fn chart_star(
    points: &[[f32; 3]],
    neighbours: &[u32],
    k: usize,
    normals: &[[f64; 3]],
    i: usize,
) -> Vec<[u32; 3]> {
    let normal = normals[i];
    if norm(normal) == 0.0 {
        return Vec::new();
    }
    // Tangent basis: u ⟂ n built from the axis least aligned with n, v = n × u.
    let axis = if normal[0].abs() <= normal[1].abs() && normal[0].abs() <= normal[2].abs() {
        [1.0, 0.0, 0.0]
    } else if normal[1].abs() <= normal[2].abs() {
        [0.0, 1.0, 0.0]
    } else {
        [0.0, 0.0, 1.0]
    };
    let u = cross(normal, axis);
    let u = u.map(|x| x / norm(u));
    let v = cross(normal, u);
    let origin = to_f64(points[i]);
    let mut chart: DelaunayTriangulation<Point2<f64>> = DelaunayTriangulation::new();
    // Spade vertex index → point index (duplicates in the chart merge into one vertex).
    let mut ids: Vec<u32> = Vec::with_capacity(k + 1);
    for j in std::iter::once(i).chain(row(neighbours, k, i)) {
        let d = sub(to_f64(points[j]), origin);
        let Ok(handle) = chart.insert(Point2::new(dot(d, u), dot(d, v))) else {
            continue;
        };
        if handle.index() == ids.len() {
            ids.push(j as u32);
        }
    }
    let mut star = Vec::new();
    for face in chart.inner_faces() {
        let corners = face.vertices().map(|h| h.fix().index());
        if !corners.contains(&0) {
            continue;
        }
        let (Some(&a), Some(&b), Some(&c)) = (
            ids.get(corners[0]),
            ids.get(corners[1]),
            ids.get(corners[2]),
        ) else {
            continue;
        };
        // Spade's inner faces are counter-clockwise in (u, v), i.e. about n = u × v.
        star.push(canonical([a, b, c]));
    }
    star
}

/// Longest squared edge of a triangle.
fn longest_edge(points: &[[f32; 3]], t: [u32; 3]) -> f64 {
    let p = t.map(|v| to_f64(points[v as usize]));
    (0..3)
        .map(|e| {
            let d = sub(p[(e + 1) % 3], p[e]);
            dot(d, d)
        })
        .fold(0.0, f64::max)
}

/// The directed edges of a triangle.
fn edges([a, b, c]: [u32; 3]) -> [(u32, u32); 3] {
    [(a, b), (b, c), (c, a)]
}

/// The growing oriented-manifold surface: used directed edges and vertices with faces.
struct Surface {
    used: HashSet<(u32, u32)>,
    has_face: Vec<bool>,
    faces: Vec<[u32; 3]>,
}

impl Surface {
    /// Edges of `t` already faced from the other side.
    fn shared(&self, t: [u32; 3]) -> usize {
        edges(t)
            .iter()
            .filter(|&&(a, b)| self.used.contains(&(b, a)))
            .count()
    }

    /// `t` reuses a directed edge (it would overlap a face on the same side): never valid.
    fn conflicts(&self, t: [u32; 3]) -> bool {
        edges(t).iter().any(|e| self.used.contains(e))
    }

    /// `t` touches a vertex with faces other than along an edge: it would pinch two fans
    /// together there (valid later, once the gap between them is filled).
    fn pinches(&self, t: [u32; 3]) -> bool {
        (0..3).any(|c| {
            let (prev, v, next) = (t[(c + 2) % 3], t[c], t[(c + 1) % 3]);
            self.has_face[v as usize]
                && !self.used.contains(&(v, prev))
                && !self.used.contains(&(next, v))
        })
    }

    fn add(&mut self, t: [u32; 3]) {
        self.used.extend(edges(t));
        for v in t {
            self.has_face[v as usize] = true;
        }
        self.faces.push(t);
    }
}

/// Accepts voted triangles under the oriented-manifold rule (no directed edge twice): first
/// every triangle two or three charts agree on, most votes then shorter longest edge first;
/// then one-vote triangles (charts of co-circular or unevenly spaced points disagree on
/// diagonals) grown from the accepted surface, those closing notches first, never pinching a
/// vertex; a new seed (best-ranked) only when no candidate touches the surface.
fn accept(points: &[[f32; 3]], mut votes: Vec<[u32; 3]>) -> Vec<[u32; 3]> {
    use std::cmp::Reverse;
    use std::collections::BinaryHeap;

    votes.par_sort_unstable();
    let mut ranked: Vec<(usize, u64, [u32; 3])> = Vec::new();
    let mut start = 0;
    while start < votes.len() {
        let t = votes[start];
        let end = start + votes[start..].iter().take_while(|&&x| x == t).count();
        ranked.push((end - start, longest_edge(points, t).to_bits(), t));
        start = end;
    }
    ranked.sort_unstable_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
    let mut surface = Surface {
        used: HashSet::with_capacity(ranked.len() * 3),
        has_face: vec![false; points.len()],
        faces: Vec::new(),
    };
    let agreed = ranked.partition_point(|r| r.0 >= 2);
    for &(_, _, t) in &ranked[..agreed] {
        if !surface.conflicts(t) {
            surface.add(t);
        }
    }
    // One-vote candidates by rank; undirected edge → candidates, for growing the surface.
    let ones: Vec<[u32; 3]> = ranked[agreed..].iter().map(|r| r.2).collect();
    let mut by_edge: Vec<((u32, u32), u32)> = ones
        .iter()
        .enumerate()
        .flat_map(|(c, &t)| edges(t).map(|(a, b)| ((a.min(b), a.max(b)), c as u32)))
        .collect();
    by_edge.par_sort_unstable();
    let mut done = vec![false; ones.len()];
    // (shared edges, Reverse(rank)): most shared first, then best rank.
    let mut heap: BinaryHeap<(usize, Reverse<u32>)> = BinaryHeap::new();
    let push_around = |heap: &mut BinaryHeap<(usize, Reverse<u32>)>,
                       surface: &Surface,
                       done: &[bool],
                       t: [u32; 3]| {
        for (a, b) in edges(t) {
            let key = (a.min(b), a.max(b));
            let from = by_edge.partition_point(|e| e.0 < key);
            for &(_, c) in by_edge[from..].iter().take_while(|e| e.0 == key) {
                if !done[c as usize] {
                    heap.push((surface.shared(ones[c as usize]), Reverse(c)));
                }
            }
        }
    };
    for &t in surface.faces.clone().iter() {
        push_around(&mut heap, &surface, &done, t);
    }
    let mut next_seed = 0;
    loop {
        let candidate = match heap.pop() {
            Some((shared, Reverse(c))) => {
                if done[c as usize] || shared != surface.shared(ones[c as usize]) {
                    continue; // stale entry; a fresher one was pushed
                }
                c as usize
            }
            None => {
                // No candidate touches the surface: seed at the best-ranked remaining one.
                while next_seed < ones.len()
                    && (done[next_seed]
                        || surface.conflicts(ones[next_seed])
                        || surface.pinches(ones[next_seed]))
                {
                    next_seed += 1;
                }
                if next_seed == ones.len() {
                    break;
                }
                next_seed
            }
        };
        let t = ones[candidate];
        if surface.conflicts(t) {
            done[candidate] = true;
            continue;
        }
        if surface.pinches(t) {
            continue; // re-pushed when a neighbouring face arrives
        }
        done[candidate] = true;
        surface.add(t);
        push_around(&mut heap, &surface, &done, t);
    }
    surface.faces
}

/// Flips every face when the faces point towards the centroid on the whole: the flux
/// `Σ_f (c_f − c) · area-normal_f` is 3× the enclosed volume for a closed outward surface.
fn orient_outward(points: &[[f32; 3]], faces: &mut [[u32; 3]]) {
    let center = centroid(points);
    let flux: f64 = faces
        .par_iter()
        .map(|t| {
            let corners = t.map(|v| points[v as usize]);
            let c = corners.map(to_f64);
            let mid = [0, 1, 2].map(|d| (c[0][d] + c[1][d] + c[2][d]) / 3.0);
            dot(sub(mid, center), triangle_cross(corners))
        })
        .collect::<Vec<_>>()
        .iter()
        .sum();
    if flux < 0.0 {
        for t in faces {
            t.swap(1, 2);
        }
    }
}

/// Closes boundary loops of at most `max_edges` edges by cutting the ear with the shortest
/// diagonal until a triangle is left, never reusing a directed edge (so the result stays
/// oriented-edge-manifold); a loop through a vertex twice is split there into simple loops
/// first; loops with no valid ear stay open. Returns the number of loops closed.
fn fill_small_holes(mesh: &mut TriMesh, max_edges: usize) -> Result<usize> {
    if max_edges < 3 {
        return Ok(0);
    }
    let points = mesh.vertices().to_vec();
    let mut faces = mesh.triangles().to_vec();
    let mut used: HashSet<(u32, u32)> = faces.iter().flat_map(|&t| edges(t)).collect();
    let mut filled = 0;
    for mut hole in boundary_loops(mesh).into_iter().flat_map(simple_cycles) {
        if hole.len() < 3 || hole.len() > max_edges {
            continue;
        }
        // The loop runs along its faces' winding; new faces run against it.
        let mut patch = Vec::new();
        while hole.len() >= 3 {
            let m = hole.len();
            let ear_face = |i: usize| [hole[(i + 1) % m], hole[i], hole[(i + m - 1) % m]];
            let Some(ear) = (0..m)
                .filter(|&i| {
                    edges(ear_face(i))
                        .iter()
                        .all(|e| !used.contains(e) && !patch.iter().any(|&t| edges(t).contains(e)))
                })
                .min_by(|&a, &b| {
                    diagonal(&points, &hole, a)
                        .total_cmp(&diagonal(&points, &hole, b))
                        .then(a.cmp(&b))
                })
            else {
                patch.clear();
                break;
            };
            patch.push(ear_face(ear));
            if m == 3 {
                break;
            }
            hole.remove(ear);
        }
        if !patch.is_empty() {
            used.extend(patch.iter().flat_map(|&t| edges(t)));
            faces.extend(patch);
            filled += 1;
        }
    }
    *mesh = TriMesh::new(points, faces)?;
    Ok(filled)
}

/// Splits a closed walk into simple cycles at repeated vertices (each keeps the walk's
/// direction): `[a, b, c, a, d, e]` → `[a, b, c]`, `[a, d, e]`.
fn simple_cycles(walk: Vec<u32>) -> Vec<Vec<u32>> {
    let mut cycles = Vec::new();
    let mut stack: Vec<u32> = Vec::with_capacity(walk.len());
    for v in walk {
        if let Some(at) = stack.iter().position(|&w| w == v) {
            cycles.push(stack.split_off(at));
        }
        stack.push(v);
    }
    if !stack.is_empty() {
        cycles.push(stack);
    }
    cycles
}

/// Squared length of the diagonal that cutting ear `i` of `hole` creates.
fn diagonal(points: &[[f32; 3]], hole: &[u32], i: usize) -> f64 {
    let m = hole.len();
    let a = to_f64(points[hole[(i + m - 1) % m] as usize]);
    let b = to_f64(points[hole[(i + 1) % m] as usize]);
    let d = sub(a, b);
    dot(d, d)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{
        edge_topology, face_normals, grid_plane, icosphere, is_edge_manifold, is_watertight,
    };

    /// `n` points on the unit sphere, Fibonacci lattice (irregular triangles, no symmetry).
    fn fibonacci_sphere(n: usize) -> Vec<[f32; 3]> {
        let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        (0..n)
            .map(|i| {
                let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
                let r = (1.0 - z * z).sqrt();
                let t = golden * i as f64;
                [(r * t.cos()) as f32, (r * t.sin()) as f32, z as f32]
            })
            .collect()
    }

    fn assert_radial_outward(mesh: &TriMesh) {
        for (f, n) in face_normals(mesh).iter().enumerate() {
            let c = mesh.triangle_positions(f).map(to_f64);
            let mid = [0, 1, 2].map(|d| c[0][d] + c[1][d] + c[2][d]);
            let cos = dot(to_f64(*n), mid) / norm(mid);
            assert!(cos > 0.9, "face {f}: cos to radial {cos}");
        }
    }

    #[test]
    fn fibonacci_sphere_is_closed_manifold_and_outward() {
        let points = fibonacci_sphere(1500);
        let r =
            tangent_chart_triangulation(&points, None, &TangentChartOptions::default()).unwrap();
        assert_eq!(r.unreferenced_points, 0);
        assert!(is_edge_manifold(&r.mesh));
        assert_radial_outward(&r.mesh);
        assert_eq!(r.holes, 0, "open loops: {:?}", boundary_loops(&r.mesh));
        assert!(is_watertight(&r.mesh));
        // Euler: a closed genus-0 triangulation of V points has 2V − 4 faces.
        assert_eq!(r.mesh.face_count(), 2 * points.len() - 4);
    }

    #[test]
    fn inward_normals_given_flip_the_output() {
        let sphere = icosphere(3);
        let inward: Vec<[f32; 3]> = sphere.vertices().iter().map(|p| p.map(|x| -x)).collect();
        let r = tangent_chart_triangulation(
            sphere.vertices(),
            Some(&inward),
            &TangentChartOptions::default(),
        )
        .unwrap();
        assert_eq!(r.holes, 0);
        for (f, n) in face_normals(&r.mesh).iter().enumerate() {
            let c = r.mesh.triangle_positions(f)[0];
            assert!(dot(to_f64(*n), to_f64(c)) < 0.0, "face {f}");
        }
    }

    #[test]
    fn plane_grid_gives_a_disk_with_one_boundary() {
        // A jittered 30×30 grid (exact grids have co-circular quads; both diagonals are fine).
        let grid = grid_plane(29, 29);
        let points: Vec<[f32; 3]> = grid
            .vertices()
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let j = ((i * 7919) % 101) as f32 / 101.0 - 0.5;
                [p[0] + 0.01 * j, p[1] - 0.008 * j, p[2]]
            })
            .collect();
        let r =
            tangent_chart_triangulation(&points, None, &TangentChartOptions::default()).unwrap();
        assert!(is_edge_manifold(&r.mesh));
        assert_eq!(r.unreferenced_points, 0);
        assert_eq!(r.holes, 1, "only the outer rim");
        let z: Vec<f32> = face_normals(&r.mesh).iter().map(|n| n[2]).collect();
        assert!(z.iter().all(|&z| z > 0.99) || z.iter().all(|&z| z < -0.99));
        // Euler for a disk: F = 2V − B − 2 with B boundary vertices.
        let topology = edge_topology(&r.mesh);
        let boundary = topology.valences().filter(|&v| v == 1).count();
        assert_eq!(r.mesh.face_count(), 2 * points.len() - boundary - 2);
    }

    #[test]
    fn exact_grid_is_covered_without_overlaps() {
        let grid = grid_plane(9, 9);
        let r = tangent_chart_triangulation(grid.vertices(), None, &TangentChartOptions::default())
            .unwrap();
        assert!(is_edge_manifold(&r.mesh));
        let area: f64 = crate::face_areas(&r.mesh).iter().sum();
        let expected: f64 = crate::face_areas(&grid).iter().sum();
        assert!(
            (area - expected).abs() < 1e-4 * expected,
            "{area} vs {expected}"
        );
    }

    #[test]
    fn uneven_density_stays_manifold_outward_and_deterministic() {
        // The upper hemisphere 8× denser than the lower, as a feature-aware simplifier leaves.
        let dense = fibonacci_sphere(4000);
        let sparse = fibonacci_sphere(500);
        let points: Vec<[f32; 3]> = dense
            .iter()
            .filter(|p| p[2] > 0.0)
            .chain(sparse.iter().filter(|p| p[2] <= 0.0))
            .copied()
            .collect();
        let opts = TangentChartOptions::default();
        let r = tangent_chart_triangulation(&points, None, &opts).unwrap();
        assert!(is_edge_manifold(&r.mesh));
        assert_radial_outward(&r.mesh);
        assert_eq!(r.unreferenced_points, 0);
        assert!(r.holes <= 2, "{} holes", r.holes);
        let one_thread = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| tangent_chart_triangulation(&points, None, &opts).unwrap());
        assert_eq!(one_thread, r);
    }

    #[test]
    fn walks_split_into_simple_cycles() {
        assert_eq!(
            simple_cycles(vec![0, 1, 2, 0, 3, 4]),
            vec![vec![0, 1, 2], vec![0, 3, 4]]
        );
        assert_eq!(
            simple_cycles(vec![5, 1, 2, 3, 2, 4]),
            vec![vec![2, 3], vec![5, 1, 2, 4]]
        );
        assert_eq!(simple_cycles(vec![1, 2, 3]), vec![vec![1, 2, 3]]);
    }

    #[test]
    fn rejects_bad_input() {
        let opts = TangentChartOptions::default();
        assert!(tangent_chart_triangulation(&[[0.0; 3]; 2], None, &opts).is_err());
        let mut points = icosphere(1).vertices().to_vec();
        assert!(tangent_chart_triangulation(&points, Some(&[[0.0; 3]]), &opts).is_err());
        points[3][1] = f32::NAN;
        assert!(tangent_chart_triangulation(&points, None, &opts).is_err());
        let few = TangentChartOptions {
            neighbours: 2,
            ..opts
        };
        assert!(tangent_chart_triangulation(icosphere(1).vertices(), None, &few).is_err());
    }
}
