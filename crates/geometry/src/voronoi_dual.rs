//! The triangulation dual to a geodesic Voronoi partition of a mesh's vertices: each vertex
//! joins the region of its nearest seed along mesh edges (multi-source Dijkstra, ties to the
//! lower seed), and every face whose three corners lie in three different regions becomes the
//! triangle of those three seeds, oriented as the face. This is the restricted Delaunay
//! triangulation that clustering remeshers (ACVD) output; the neural mesh simplifier trains its
//! edge predictor and face classifier to propose it among the sampled vertices, where the
//! probabilities of eq. 6.14 alone collapse to an empty mesh.
//!
//! For a dense, evenly spread set of seeds the dual is a closed manifold of the input's
//! topology; for sparse or clumped seeds a region may not be a disc and the dual can carry
//! non-manifold edges or holes (the neural simplifier's manifold pass removes those).
//!
//! The *nearest-seed* partition instead gives each vertex to its nearest seed in space (the
//! Euclidean Voronoi diagram of the seeds, restricted to the mesh's vertices) among those
//! facing the same side. Its dual is decided by the seeds' positions and normals alone, up to
//! the input's resolution, where the geodesic partition's dual also depends on the paths along
//! the input's edges: where four seeds are nearly cocircular the two pick different diagonals
//! (docs/mesh_simplifier_model.md). Its dual is taken over the partition made connected
//! (`connected_regions`): a region's piece cut off from its seed would put a dual edge into
//! faces on both sides of it.

use std::collections::HashMap;

use rayon::prelude::*;

use crate::connected_regions::connected_nearest_seed_regions;
use crate::error::{Error, Result};
use crate::radix_heap::RadixHeap;
use crate::spatial_index::SpatialIndex;
use crate::tri_mesh::TriMesh;
use crate::vec3::{dot, norm, sub, to_f64};
use crate::vertex_neighbours::VertexNeighbours;
use crate::vertex_normals::vertex_normals;

/// The region (index into `seeds`) of every vertex; `u32::MAX` for vertices no seed reaches.
/// Errors when a seed is out of range or repeated.
pub fn geodesic_voronoi_regions(mesh: &TriMesh, seeds: &[u32]) -> Result<Vec<u32>> {
    let n = mesh.vertex_count();
    let mut region = seed_of_vertex(n, seeds)?;
    let neighbours = VertexNeighbours::new(mesh);
    let v = mesh.vertices();
    let mut distance = vec![f64::INFINITY; n];
    // Keys are (distance bits, seed): non-negative f64 order as their bit patterns, and the
    // seed breaks ties. A vertex is settled by its least key, and the entries of one key
    // offer their neighbours only keys no lower, so the partition does not depend on the
    // order in which entries of equal key pop.
    let mut heap = RadixHeap::new();
    for (s, &seed) in seeds.iter().enumerate() {
        distance[seed as usize] = 0.0;
        heap.push(0, s as u32, seed);
    }
    while let Some((bits, s, u)) = heap.pop() {
        let d = f64::from_bits(bits);
        if d > distance[u as usize] || region[u as usize] != s {
            continue;
        }
        for &w in neighbours.of(u) {
            let step = norm(sub(to_f64(v[w as usize]), to_f64(v[u as usize])));
            let candidate = d + step;
            let better = candidate < distance[w as usize]
                || (candidate == distance[w as usize] && s < region[w as usize]);
            if better {
                distance[w as usize] = candidate;
                region[w as usize] = s;
                heap.push(candidate.to_bits(), s, w);
            }
        }
    }
    Ok(region)
}

/// The dual triangles of [`geodesic_voronoi_regions`] in seed numbering (`[a, b, c]` indexes
/// `seeds`), each once (the first face that produces it sets its orientation), in face order.
///
/// ```
/// use meshgnn_geometry::{icosphere, voronoi_dual_triangles};
/// let sphere = icosphere(2);
/// // Every vertex a seed: the dual is the mesh itself.
/// let all: Vec<u32> = (0..sphere.vertex_count() as u32).collect();
/// assert_eq!(voronoi_dual_triangles(&sphere, &all)?, sphere.triangles());
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn voronoi_dual_triangles(mesh: &TriMesh, seeds: &[u32]) -> Result<Vec<[u32; 3]>> {
    Ok(dual_triangles(
        mesh,
        &geodesic_voronoi_regions(mesh, seeds)?,
    ))
}

/// The dual edges of [`geodesic_voronoi_regions`]: the pairs of seeds (`[a, b]` indexes
/// `seeds`, `a < b`) whose regions meet across an edge of the mesh, sorted. Two seeds so joined
/// are connected by the surface between them; across a hole or a gap they are not.
///
/// ```
/// use meshgnn_geometry::{icosphere, voronoi_dual_edges};
/// let sphere = icosphere(1);
/// // Every vertex a seed: the dual edges are the mesh's edges, 120 for an icosphere(1).
/// let all: Vec<u32> = (0..sphere.vertex_count() as u32).collect();
/// let edges = voronoi_dual_edges(&sphere, &all)?;
/// assert_eq!(edges.len(), 120);
/// assert!(sphere.triangles().iter().all(|&[a, b, _]| edges.contains(&[a.min(b), a.max(b)])));
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn voronoi_dual_edges(mesh: &TriMesh, seeds: &[u32]) -> Result<Vec<[u32; 2]>> {
    let region = geodesic_voronoi_regions(mesh, seeds)?;
    let mut edges: Vec<[u32; 2]> = mesh
        .triangles()
        .iter()
        .flat_map(|&[a, b, c]| [(a, b), (b, c), (c, a)])
        .map(|(a, b)| (region[a as usize], region[b as usize]))
        .filter(|&(ra, rb)| ra != rb && ra != u32::MAX && rb != u32::MAX)
        .map(|(ra, rb)| [ra.min(rb), ra.max(rb)])
        .collect();
    edges.sort_unstable();
    edges.dedup();
    Ok(edges)
}

/// Seeds nearest a vertex among which [`nearest_seed_regions`] looks for one facing its way.
const FACING_CANDIDATES: usize = 8;

/// The region (index into `seeds`) of every vertex: the nearest seed in space whose vertex
/// normal points to the same side as the vertex's (positive dot product) among its
/// `FACING_CANDIDATES` nearest, else the nearest; ties to the lower index. The normal test
/// keeps the two sides of a thin part (a limb, a plate) in regions of their own, as paths
/// along the surface would. Errors when a seed is out of range or repeated, or a position is
/// not finite.
pub fn nearest_seed_regions(mesh: &TriMesh, seeds: &[u32]) -> Result<Vec<u32>> {
    seed_of_vertex(mesh.vertex_count(), seeds)?;
    let v = mesh.vertices();
    let normals = vertex_normals(mesh);
    let positions: Vec<[f32; 3]> = seeds.iter().map(|&s| v[s as usize]).collect();
    let seed_normals: Vec<[f64; 3]> = seeds.iter().map(|&s| to_f64(normals[s as usize])).collect();
    let index = SpatialIndex::new(&positions)?;
    Ok(v.par_iter()
        .zip(&normals)
        .map_init(Vec::new, |out, (p, n)| {
            let n = to_f64(*n);
            let faces_n = |&&(_, s): &&(f32, u32)| dot(n, seed_normals[s as usize]) > 0.0;
            // The nearest seed alone first: it faces the vertex's way almost everywhere, and
            // the candidates come in (distance, index) order, so it is their first.
            index.nearest(p, 1, None, out);
            if out.first().is_some_and(|nearest| faces_n(&nearest)) {
                return out[0].1;
            }
            index.nearest(p, FACING_CANDIDATES, None, out);
            let facing = out.iter().find(faces_n);
            facing.or(out.first()).map_or(u32::MAX, |&(_, s)| s)
        })
        .collect())
}

/// The dual triangles of [`connected_nearest_seed_regions`] (the nearest-seed partition with
/// the pieces cut off from their seed handed to a neighbour), as [`voronoi_dual_triangles`]
/// gives those of the geodesic partition.
///
/// ```
/// use meshgnn_geometry::{icosphere, nearest_seed_dual_triangles};
/// let sphere = icosphere(2);
/// let all: Vec<u32> = (0..sphere.vertex_count() as u32).collect();
/// assert_eq!(nearest_seed_dual_triangles(&sphere, &all)?, sphere.triangles());
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn nearest_seed_dual_triangles(mesh: &TriMesh, seeds: &[u32]) -> Result<Vec<[u32; 3]>> {
    Ok(dual_triangles(
        mesh,
        &connected_nearest_seed_regions(mesh, seeds)?,
    ))
}

/// Per vertex of a mesh of `n` vertices, the index of the seed on it, `u32::MAX` elsewhere:
/// the regions before any vertex joins one. Errors when a seed is out of range or repeated.
///
/// ```
/// let seed_of = meshgnn_geometry::seed_of_vertex(4, &[2, 0])?;
/// assert_eq!(seed_of, vec![1, u32::MAX, 0, u32::MAX]);
/// assert!(meshgnn_geometry::seed_of_vertex(4, &[2, 2]).is_err());
/// assert!(meshgnn_geometry::seed_of_vertex(4, &[4]).is_err());
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn seed_of_vertex(n: usize, seeds: &[u32]) -> Result<Vec<u32>> {
    let mut region = vec![u32::MAX; n];
    for (s, &v) in seeds.iter().enumerate() {
        let slot = region.get_mut(v as usize).ok_or(Error::IndexOutOfRange {
            element: "seed",
            index: s,
            target: "vertex",
            value: u64::from(v),
            count: n,
        })?;
        if *slot != u32::MAX {
            return Err(Error::InvalidParameter {
                name: "seeds",
                message: format!("vertex {v} given twice"),
            });
        }
        *slot = s as u32;
    }
    Ok(region)
}

/// Every face whose corners lie in three different regions, as the triangle of those regions,
/// each once (the first face sets its orientation), in face order.
fn dual_triangles(mesh: &TriMesh, region: &[u32]) -> Vec<[u32; 3]> {
    let mut seen = HashMap::new();
    let mut triangles = Vec::new();
    for t in mesh.triangles() {
        let r = t.map(|c| region[c as usize]);
        if r.contains(&u32::MAX) || r[0] == r[1] || r[1] == r[2] || r[0] == r[2] {
            continue;
        }
        let mut key = r;
        key.sort_unstable();
        seen.entry(key).or_insert_with(|| {
            triangles.push(r);
        });
    }
    triangles
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{icosphere, is_edge_manifold, is_watertight};

    #[test]
    fn a_strip_of_four_regions_gives_two_triangles() {
        // A 4×2 grid of vertices, two triangles per cell; seeds at the four corners.
        let v: Vec<[f32; 3]> = (0..2)
            .flat_map(|y| (0..4).map(move |x| [x as f32, y as f32, 0.0]))
            .collect();
        let mut f = Vec::new();
        for x in 0..3u32 {
            f.push([x, x + 1, x + 5]);
            f.push([x, x + 5, x + 4]);
        }
        let mesh = TriMesh::new(v, f).unwrap();
        let seeds = [0, 3, 4, 7];
        let region = geodesic_voronoi_regions(&mesh, &seeds).unwrap();
        // Vertex 1 is 1 from seed 0 and 2 from seed 1; vertex 2 the other way; the lower
        // row likewise (vertex 5 via the diagonal to 0 costs √2 > 1 from 4).
        assert_eq!(region, vec![0, 0, 1, 1, 2, 2, 3, 3]);
        // The faces meeting three regions: [1, 2, 6] (0, 1, 3) and [1, 6, 5] (0, 3, 2).
        assert_eq!(
            voronoi_dual_triangles(&mesh, &seeds).unwrap(),
            vec![[0, 1, 3], [0, 3, 2]]
        );
        // Their five edges; seeds 1 and 2 (vertices 3 and 4) are not joined.
        assert_eq!(
            voronoi_dual_edges(&mesh, &seeds).unwrap(),
            vec![[0, 1], [0, 2], [0, 3], [1, 3], [2, 3]]
        );
        // Without the first cell, vertices 0 and 4 are in no face: seeds 0 and 2 are joined
        // to nothing, and the rest of the strip is split between seeds 1 and 3.
        let cut = TriMesh::new(mesh.vertices().to_vec(), mesh.triangles()[2..].to_vec()).unwrap();
        assert_eq!(voronoi_dual_edges(&cut, &seeds).unwrap(), vec![[1, 3]]);
    }

    #[test]
    fn evenly_spread_seeds_on_a_sphere_give_a_closed_manifold() {
        let fine = icosphere(4);
        // The vertices of icosphere(2) are the first 162 of icosphere(4) (subdivision keeps
        // the old vertices first).
        let seeds: Vec<u32> = (0..162).collect();
        let corners: Vec<[f32; 3]> = seeds.iter().map(|&s| fine.vertices()[s as usize]).collect();
        for dual in [voronoi_dual_triangles, nearest_seed_dual_triangles] {
            let mesh = TriMesh::new(corners.clone(), dual(&fine, &seeds).unwrap()).unwrap();
            assert!(is_edge_manifold(&mesh));
            assert_eq!(mesh.face_count(), 320);
            assert!(is_watertight(&mesh));
        }
    }

    #[test]
    fn the_two_sides_of_a_thin_sheet_never_share_a_nearest_seed() {
        // Two 4×2 grids 0.1 apart: the lower one faces −z (vertices 0-7), the upper one +z
        // (vertices 8-15); vertex 4y + x sits at (x, y). Seed A is the lower (0, 0), seed B
        // the upper (3, 0). The lower (3, 0) is 0.1 from B and 3 from A, yet faces away from
        // B: every lower vertex joins A, every upper one B, as paths along the sheets say.
        let grid = |z: f32| (0..2).flat_map(move |y| (0..4).map(move |x| [x as f32, y as f32, z]));
        let v: Vec<[f32; 3]> = grid(0.0).chain(grid(0.1)).collect();
        let mut f = Vec::new();
        for x in 0..3u32 {
            f.push([x, x + 5, x + 1]);
            f.push([x, x + 4, x + 5]);
            f.push([8 + x, 9 + x, 13 + x]);
            f.push([8 + x, 13 + x, 12 + x]);
        }
        let sheet = TriMesh::new(v, f).unwrap();
        let regions = nearest_seed_regions(&sheet, &[0, 11]).unwrap();
        assert_eq!(regions, [[0; 8], [1; 8]].concat());
        // In space alone the lower (2, y) and (3, y) would be nearer B.
        assert_eq!(
            geodesic_voronoi_regions(&sheet, &[0, 11]).unwrap()[..8],
            [0; 8]
        );
    }

    #[test]
    fn bad_seeds_are_errors_and_unreached_vertices_have_no_region() {
        let sphere = icosphere(1);
        assert!(geodesic_voronoi_regions(&sphere, &[0, 0]).is_err());
        assert!(geodesic_voronoi_regions(&sphere, &[42]).is_err());
        assert!(nearest_seed_regions(&sphere, &[3, 3]).is_err());
        assert!(nearest_seed_regions(&sphere, &[42]).is_err());
        let mut v = sphere.vertices().to_vec();
        v.push([5.0, 0.0, 0.0]);
        let lonely = TriMesh::new(v, sphere.triangles().to_vec()).unwrap();
        let region = geodesic_voronoi_regions(&lonely, &[0]).unwrap();
        assert_eq!(region[42], u32::MAX);
        assert!(region[..42].iter().all(|&r| r == 0));
    }
}
