//! k-rings and k-disks of a vertex (thesis eq. 2.27, after Bouritsas et al. 2019, "Neural
//! 3D morphable models: spiral convolutional networks", ICCV):
//! `0-ring(v) = {v}`, `(k+1)-ring(v) = N(k-ring(v)) − k-disk(v)`,
//! `k-disk(v) = ∪_{i ≤ k} i-ring(v)`, where `N(V)` is every vertex adjacent to one in `V`.
//!
//! # Conventions
//! The graph is a symmetric adjacency [`CsrMatrix`] (e.g. [`crate::vertex_adjacency`]); each
//! ring is returned sorted by vertex index (the *ordered* rings are [`crate::spiral_sequences`]).

use crate::{CsrMatrix, Error, Result};

/// Rings `0..=k` around `v` in the graph `adjacency: #V×#V` (eq. 2.27); rings past the
/// vertex's connected component are empty. O(size of the k-disk × valence).
///
/// Errors when `v` is out of range or the matrix is not square.
///
/// ```
/// use meshgnn_graph::{k_rings, vertex_adjacency};
/// let a = vertex_adjacency(&meshgnn_geometry::grid_plane(4, 4))?;
/// let rings = k_rings(&a, 0, 2)?;
/// assert_eq!(rings, vec![vec![0], vec![1, 5, 6], vec![2, 7, 10, 11, 12]]);
/// # Ok::<(), meshgnn_graph::Error>(())
/// ```
pub fn k_rings(adjacency: &CsrMatrix, v: u32, k: usize) -> Result<Vec<Vec<u32>>> {
    let n = adjacency.rows();
    if adjacency.cols() != n {
        return Err(Error::ShapeMismatch {
            what: "columns of the adjacency (must be square)",
            expected: n,
            actual: adjacency.cols(),
        });
    }
    if v as usize >= n {
        return Err(Error::IndexOutOfRange {
            what: "centre vertex",
            index: v as usize,
            len: n,
        });
    }
    let mut in_disk = std::collections::HashSet::new();
    in_disk.insert(v);
    let mut rings = vec![vec![v]];
    for _ in 0..k {
        let mut next: Vec<u32> = Vec::new();
        if let Some(last) = rings.last() {
            for &u in last {
                for &w in adjacency.row(u as usize).0 {
                    if in_disk.insert(w) {
                        next.push(w);
                    }
                }
            }
        }
        next.sort_unstable();
        rings.push(next);
    }
    Ok(rings)
}

/// The k-disk of `v`: the union of rings `0..=k` (eq. 2.27), sorted by index.
///
/// ```
/// use meshgnn_graph::{k_disk, vertex_adjacency};
/// let a = vertex_adjacency(&meshgnn_geometry::grid_plane(4, 4))?;
/// assert_eq!(k_disk(&a, 0, 1)?, vec![0, 1, 5, 6]);
/// # Ok::<(), meshgnn_graph::Error>(())
/// ```
pub fn k_disk(adjacency: &CsrMatrix, v: u32, k: usize) -> Result<Vec<u32>> {
    let mut disk: Vec<u32> = k_rings(adjacency, v, k)?.into_iter().flatten().collect();
    disk.sort_unstable();
    Ok(disk)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vertex_adjacency;
    use meshgnn_geometry::{grid_plane, icosphere};

    #[test]
    fn rings_on_grid_follow_the_hexagonal_metric() {
        // On grid_plane the diagonals run (i, j)–(i+1, j+1): the graph distance from (2, 2)
        // to (i, j) is max(|di|, |dj|) when di·dj ≥ 0 and |di| + |dj| otherwise.
        let a = vertex_adjacency(&grid_plane(4, 4)).unwrap();
        let rings = k_rings(&a, 12, 4).unwrap();
        for (r, ring) in rings.iter().enumerate() {
            for &w in ring {
                let (di, dj) = ((w % 5) as i32 - 2, (w / 5) as i32 - 2);
                let d = if di * dj >= 0 {
                    di.abs().max(dj.abs())
                } else {
                    di.abs() + dj.abs()
                };
                assert_eq!(d as usize, r, "vertex {w}");
            }
        }
        assert_eq!(rings.iter().map(Vec::len).sum::<usize>(), 25);
        assert_eq!(rings[1], vec![6, 7, 11, 13, 17, 18]);
    }

    #[test]
    fn disk_sizes_on_icosahedron() {
        let a = vertex_adjacency(&icosphere(0)).unwrap();
        let sizes: Vec<usize> = (0..4).map(|k| k_disk(&a, 3, k).unwrap().len()).collect();
        assert_eq!(sizes, vec![1, 6, 11, 12]); // vertex, 5 neighbours, 5 more, the antipode
        assert!(k_rings(&a, 12, 1).is_err());
    }
}
