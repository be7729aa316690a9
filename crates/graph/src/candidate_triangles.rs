//! Candidate triangles of a sparse adjacency: every 3-clique, the face proposals of the neural
//! mesh simplifier ("a candidate face set was constructed simply by connecting the triplet of
//! points that share edges", thesis ch. 6.3, from `A_s` of eq. 6.3-6.4; Potamias et al. 2022,
//! "Neural mesh simplification", CVPR).
//!
//! # Conventions
//! Each triangle is `[a, b, c]` with `a < b < c` (no orientation: the face classifier and the
//! final repair decide it), listed once, sorted lexicographically. Self-loops are ignored.

use rayon::prelude::*;

use crate::{CsrMatrix, Error, Result};

/// All 3-cliques of the symmetric `adjacency: #V×#V`, each exactly once, by intersecting
/// sorted neighbour lists: O(Σ over edges of min-degree sums) ≈ O(E·d), parallel over
/// vertices, deterministic.
///
/// Errors when the matrix is not square or not symmetric (naming an unmatched entry).
///
/// ```
/// use meshgnn_graph::{adjacency_from_edges, candidate_triangles};
/// // K4: every triple of its 4 vertices is a triangle.
/// let k4 = adjacency_from_edges(4, &[[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]])?;
/// assert_eq!(candidate_triangles(&k4)?, vec![[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]]);
/// # Ok::<(), meshgnn_graph::Error>(())
/// ```
pub fn candidate_triangles(adjacency: &CsrMatrix) -> Result<Vec<[u32; 3]>> {
    let n = adjacency.rows();
    if adjacency.cols() != n {
        return Err(Error::ShapeMismatch {
            what: "columns of the adjacency (must be square)",
            expected: n,
            actual: adjacency.cols(),
        });
    }
    if let Some((i, j)) = (0..n).into_par_iter().find_map_first(|i| {
        adjacency.row(i).0.iter().find_map(|&j| {
            let back = adjacency
                .row(j as usize)
                .0
                .binary_search(&(i as u32))
                .is_ok();
            (!back).then_some((i, j))
        })
    }) {
        return Err(Error::InvalidParameter {
            name: "adjacency",
            message: format!("not symmetric: entry ({i}, {j}) has no ({j}, {i})"),
        });
    }
    let per_vertex: Vec<Vec<[u32; 3]>> = (0..n)
        .into_par_iter()
        .map(|a| {
            let a32 = a as u32;
            let na = adjacency.row(a).0;
            let higher_a = &na[na.partition_point(|&x| x <= a32)..];
            let mut found = Vec::new();
            for (pos, &b) in higher_a.iter().enumerate() {
                let nb = adjacency.row(b as usize).0;
                // c > b in both lists: merge the tails.
                let mut x = &higher_a[pos + 1..];
                let mut y = &nb[nb.partition_point(|&c| c <= b)..];
                while let (Some(&cx), Some(&cy)) = (x.first(), y.first()) {
                    match cx.cmp(&cy) {
                        std::cmp::Ordering::Less => x = &x[1..],
                        std::cmp::Ordering::Greater => y = &y[1..],
                        std::cmp::Ordering::Equal => {
                            found.push([a32, b, cx]);
                            x = &x[1..];
                            y = &y[1..];
                        }
                    }
                }
            }
            found
        })
        .collect();
    Ok(per_vertex.concat())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{adjacency_from_edges, vertex_adjacency};
    use meshgnn_geometry::{icosphere, subdivided_cube};

    fn sorted_faces(mesh: &meshgnn_geometry::TriMesh) -> Vec<[u32; 3]> {
        let mut faces: Vec<[u32; 3]> = mesh
            .triangles()
            .iter()
            .map(|t| {
                let mut s = *t;
                s.sort_unstable();
                s
            })
            .collect();
        faces.sort_unstable();
        faces
    }

    #[test]
    fn triangles_of_icosphere_adjacency_are_its_faces() {
        // On icosphere(1) every 3-cycle bounds a face (no separating triangles).
        let mesh = icosphere(1);
        let got = candidate_triangles(&vertex_adjacency(&mesh).unwrap()).unwrap();
        assert_eq!(got, sorted_faces(&mesh));
        assert_eq!(got.len(), 80);
    }

    #[test]
    fn matches_brute_force_on_a_random_graph() {
        use rand::{Rng, SeedableRng, rngs::StdRng};
        let mut rng = StdRng::seed_from_u64(1);
        let n = 40;
        let edges: Vec<[u32; 2]> = (0..300)
            .map(|_| [rng.random_range(0..n), rng.random_range(0..n)])
            .collect();
        let a = adjacency_from_edges(n as usize, &edges).unwrap();
        let mut brute = Vec::new();
        for i in 0..n as usize {
            for j in i + 1..n as usize {
                for k in j + 1..n as usize {
                    if a.get(i, j) > 0.0 && a.get(j, k) > 0.0 && a.get(i, k) > 0.0 {
                        brute.push([i as u32, j as u32, k as u32]);
                    }
                }
            }
        }
        assert_eq!(candidate_triangles(&a).unwrap(), brute);
        // The cube's diagonal-split faces also give exactly its faces.
        let cube = subdivided_cube(2);
        let got = candidate_triangles(&vertex_adjacency(&cube).unwrap()).unwrap();
        assert_eq!(got, sorted_faces(&cube));
    }

    #[test]
    fn asymmetric_input_is_an_error() {
        let m = CsrMatrix::from_triplets(3, 3, &[(0, 1, 1.0)]).unwrap();
        assert!(matches!(
            candidate_triangles(&m),
            Err(Error::InvalidParameter { .. })
        ));
    }
}
