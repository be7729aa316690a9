//! Nearest-seed regions made connected. [`nearest_seed_regions`] gives each vertex to its
//! nearest seed in space, so where the surface folds back near itself (a thin leg, a curled
//! antenna, a wing's two rims) a region can hold *pieces* joined to its seed only through
//! other regions. Each such piece puts an edge of the dual into faces on both sides of it,
//! and the dual is no surface there. Two remedies, used together by the neural mesh
//! simplifier: [`island_seeds`] gives every sizeable cut-off piece a seed of its own (a thin
//! feature that carries one seed keeps a triangle instead of vanishing), and
//! [`connected_nearest_seed_regions`] hands what is still cut off to a neighbouring region.
//!
//! A piece is a maximal set of vertices of one region joined by mesh edges inside the region
//! or by equal positions (a UV seam splits no piece); vertices no face uses belong to none.

use std::collections::{HashMap, VecDeque};

use petgraph::unionfind::UnionFind;

use crate::error::Result;
use crate::tri_mesh::TriMesh;
use crate::vec3::{norm, sub, to_f64};
use crate::vertex_neighbours::VertexNeighbours;
use crate::voronoi_dual::nearest_seed_regions;

/// The seeds followed by one more seed for every piece of their [`nearest_seed_regions`]
/// that does not hold its region's seed and has at least `min_vertices` vertices: the
/// piece's vertex nearest its centroid (the first in index order on a tie), pieces in the
/// order of their lowest vertex. Errors as [`nearest_seed_regions`].
///
/// ```
/// use meshgnn_geometry::{icosphere, island_seeds};
/// // Seeds spread evenly over a sphere leave no piece cut off.
/// let seeds: Vec<u32> = (0..42).collect();
/// assert_eq!(island_seeds(&icosphere(3), &seeds, 1)?, seeds);
/// # Ok::<(), meshgnn_geometry::Error>(())
/// ```
pub fn island_seeds(mesh: &TriMesh, seeds: &[u32], min_vertices: usize) -> Result<Vec<u32>> {
    let region = nearest_seed_regions(mesh, seeds)?;
    let pieces = RegionPieces::new(mesh, &region, seeds);
    let n = mesh.vertex_count();
    let mut size = vec![0usize; n];
    let mut centroid_sum = vec![[0.0f64; 3]; n];
    for (i, p) in mesh.vertices().iter().enumerate() {
        if !pieces.referenced[i] {
            continue;
        }
        let root = pieces.root[i] as usize;
        size[root] += 1;
        let p = to_f64(*p);
        for k in 0..3 {
            centroid_sum[root][k] += p[k];
        }
    }
    // Per piece root: (distance to the centroid, vertex), and the first vertex seen.
    let mut nearest = vec![(f64::INFINITY, u32::MAX); n];
    let mut order = Vec::new();
    for (i, p) in mesh.vertices().iter().enumerate() {
        let root = pieces.root[i] as usize;
        if !pieces.referenced[i] || pieces.holds_its_seed(i) || size[root] < min_vertices.max(1) {
            continue;
        }
        if nearest[root].1 == u32::MAX {
            order.push(root);
        }
        let centroid = centroid_sum[root].map(|c| c / size[root] as f64);
        let distance = norm(sub(to_f64(*p), centroid));
        if distance < nearest[root].0 {
            nearest[root] = (distance, i as u32);
        }
    }
    let mut out = seeds.to_vec();
    out.extend(order.iter().map(|&root| nearest[root].1));
    Ok(out)
}

/// [`nearest_seed_regions`] with every vertex of a piece that does not hold its region's seed
/// handed, breadth first along mesh edges, to the region of the vertex that reaches it first
/// (the queue starts with every vertex whose piece holds its seed, in index order). A piece
/// no path joins to such a vertex keeps its nearest seed. Errors as [`nearest_seed_regions`].
pub fn connected_nearest_seed_regions(mesh: &TriMesh, seeds: &[u32]) -> Result<Vec<u32>> {
    let mut region = nearest_seed_regions(mesh, seeds)?;
    let pieces = RegionPieces::new(mesh, &region, seeds);
    let n = mesh.vertex_count();
    let mut settled: Vec<bool> = (0..n).map(|i| pieces.holds_its_seed(i)).collect();
    let neighbours = VertexNeighbours::new(mesh);
    let mut queue: VecDeque<u32> = (0..n as u32).filter(|&i| settled[i as usize]).collect();
    while let Some(u) = queue.pop_front() {
        for &w in neighbours.of(u) {
            if !settled[w as usize] {
                settled[w as usize] = true;
                region[w as usize] = region[u as usize];
                queue.push_back(w);
            }
        }
    }
    Ok(region)
}

/// The pieces of a partition: each vertex's piece representative, whether a face uses the
/// vertex, and whether a vertex's piece holds the seed of its region.
struct RegionPieces {
    root: Vec<u32>,
    referenced: Vec<bool>,
    holds_seed: Vec<bool>,
}

impl RegionPieces {
    fn new(mesh: &TriMesh, region: &[u32], seeds: &[u32]) -> Self {
        let n = mesh.vertex_count();
        let mut sets = UnionFind::<u32>::new(n);
        let mut referenced = vec![false; n];
        for t in mesh.triangles() {
            for k in 0..3 {
                referenced[t[k] as usize] = true;
                let (a, b) = (t[k], t[(k + 1) % 3]);
                if region[a as usize] == region[b as usize] {
                    sets.union(a, b);
                }
            }
        }
        let mut first_at: HashMap<[u32; 3], u32> = HashMap::new();
        for (i, p) in mesh.vertices().iter().enumerate() {
            let first = *first_at.entry(p.map(f32::to_bits)).or_insert(i as u32);
            if region[first as usize] == region[i] {
                sets.union(first, i as u32);
            }
        }
        let root = sets.into_labeling();
        let mut holds_seed = vec![false; n];
        for &s in seeds {
            holds_seed[root[s as usize] as usize] = true;
        }
        Self {
            root,
            referenced,
            holds_seed,
        }
    }

    /// Whether vertex `i`'s piece holds its region's seed (every region has exactly one seed
    /// and pieces never span two regions, so any seed in the piece is its region's).
    fn holds_its_seed(&self, i: usize) -> bool {
        self.holds_seed[self.root[i] as usize]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A flat U of unit cells facing +z: the lower arm (rows y = 0, 1) and the upper arm
    /// (rows y = 2, 3) run along x from 0 to 11, joined only by the cell column x ∈ [10, 11];
    /// the arms face each other one unit apart across an empty row of cells. Returns the
    /// mesh and the vertex at (x, y).
    fn hairpin() -> (TriMesh, impl Fn(u32, u32) -> u32) {
        let grid = crate::grid_plane(11, 3);
        let vertices = grid
            .vertices()
            .iter()
            .map(|p| [11.0 * p[0], 3.0 * p[1], 0.0]);
        // Cell (i, j) holds triangles 2(11j + i) and the one after.
        let faces = grid.triangles().iter().enumerate().filter(|(t, _)| {
            let (i, j) = ((t / 2) % 11, t / 22);
            j != 1 || i >= 10
        });
        let mesh = TriMesh::new(vertices.collect(), faces.map(|(_, f)| *f).collect());
        (mesh.unwrap(), |x: u32, y: u32| 12 * y + x)
    }

    #[test]
    fn a_piece_cut_off_from_its_seed_gets_a_seed_or_joins_its_neighbour() {
        let (mesh, at) = hairpin();
        let (a, b) = (at(0, 0), at(11, 3));
        // In space, the upper arm's x ≤ 5 is nearer a ((5, 3): 5.83 against 6.00), yet along
        // the surface it reaches a only through b's connector: a piece of a's region cut off.
        let region = nearest_seed_regions(&mesh, &[a, b]).unwrap();
        let island: Vec<u32> = (0..=5).flat_map(|x| [at(x, 2), at(x, 3)]).collect();
        assert!(island.iter().all(|&v| region[v as usize] == 0));
        assert_eq!(region[at(6, 2) as usize], 1);
        // Its 12 vertices' centroid is (2.5, 2.5); (2, 2) is the first of the four nearest.
        assert_eq!(
            island_seeds(&mesh, &[a, b], 12).unwrap(),
            vec![a, b, at(2, 2)]
        );
        assert_eq!(island_seeds(&mesh, &[a, b], 13).unwrap(), vec![a, b]);
        // Without a seed of its own the piece joins b, its only neighbouring region; the
        // lower arm's x ≤ 5 stays with a.
        let connected = connected_nearest_seed_regions(&mesh, &[a, b]).unwrap();
        assert!(island.iter().all(|&v| connected[v as usize] == 1));
        assert!((0..=5).all(|x| connected[at(x, 0) as usize] == 0));
        for (v, (&before, &after)) in region.iter().zip(&connected).enumerate() {
            if !island.contains(&(v as u32)) {
                assert_eq!(before, after, "vertex {v}");
            }
        }
        // With the third seed the upper arm's x ≤ 5 is that seed's region; the lower arm's
        // vertices it wins across the gap ((2, 1) is 1 from it) go to a or b.
        let seeds = [a, b, at(2, 2)];
        let nearest = nearest_seed_regions(&mesh, &seeds).unwrap();
        assert_eq!(nearest[at(2, 1) as usize], 2);
        let connected = connected_nearest_seed_regions(&mesh, &seeds).unwrap();
        assert!(island.iter().all(|&v| connected[v as usize] == 2));
        assert!(!(0..=5).any(|x| connected[at(x, 1) as usize] == 2));
        for seeds in [&[a, b][..], &seeds] {
            let connected = connected_nearest_seed_regions(&mesh, seeds).unwrap();
            assert!(every_region_joins_its_seed(&mesh, seeds, &connected));
        }
        assert!(!every_region_joins_its_seed(&mesh, &seeds, &nearest));
    }

    /// Whether every vertex reaches its region's seed along mesh edges inside its region.
    fn every_region_joins_its_seed(mesh: &TriMesh, seeds: &[u32], region: &[u32]) -> bool {
        let neighbours = VertexNeighbours::new(mesh);
        let mut reached = vec![false; mesh.vertex_count()];
        let mut stack: Vec<u32> = seeds.to_vec();
        for &s in seeds {
            reached[s as usize] = true;
        }
        while let Some(u) = stack.pop() {
            for &w in neighbours.of(u) {
                if !reached[w as usize] && region[w as usize] == region[u as usize] {
                    reached[w as usize] = true;
                    stack.push(w);
                }
            }
        }
        reached.iter().all(|&r| r)
    }

    #[test]
    fn a_seam_does_not_cut_a_piece() {
        // The hairpin's upper-arm cells at x < 5 on copies of their corners (the originals
        // at x < 5 unused, those at x = 5 still used by the cell beside): the seam at x = 5
        // joins by position, so the island is one piece of 14 used vertices, not 12 + 2.
        let (mesh, at) = hairpin();
        let mut vertices = mesh.vertices().to_vec();
        let mut copy = HashMap::new();
        let faces: Vec<[u32; 3]> = mesh
            .triangles()
            .iter()
            .map(|t| {
                let upper_left = t.iter().all(|&c| c >= at(0, 2) && c % 12 <= 5);
                let upper_left = upper_left && t.iter().any(|&c| c % 12 < 5);
                if !upper_left {
                    return *t;
                }
                t.map(|c| {
                    *copy.entry(c).or_insert_with(|| {
                        vertices.push(mesh.vertices()[c as usize]);
                        vertices.len() as u32 - 1
                    })
                })
            })
            .collect();
        let seamed = TriMesh::new(vertices, faces).unwrap();
        let (a, b) = (at(0, 0), at(11, 3));
        assert_eq!(island_seeds(&seamed, &[a, b], 14).unwrap().len(), 3);
        assert_eq!(island_seeds(&seamed, &[a, b], 15).unwrap().len(), 2);
    }
}
