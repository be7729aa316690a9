//! The k-NN graph over triangle barycentres, the graph the face classifier's TriConv layers
//! run on (thesis ch. 6.3, eq. 6.6-6.7: "the number of the triangle neighbors was set to
//! k=20, selected by their respective distances to their barycenters").
//!
//! # Conventions
//! As [`crate::knn_graph`]: `#F×k` row-major `u32` triangle indices, nearest first, ties to the
//! smaller index, the triangle itself excluded. Barycentres are averaged in `f64`. The graph is
//! [`meshgnn_geometry::SpatialIndex::knn_graph`] of the barycentres.

use meshgnn_geometry::SpatialIndex;

use crate::knn_graph::{check_finite, check_u32_len};
use crate::{Error, Neighbours, Result};

/// Barycentres `#F×3` of `triangles: #F×3` over `vertices: #V×3`.
///
/// ```
/// let b = meshgnn_graph::triangle_barycentres(&[[0.0; 3], [3.0, 0.0, 0.0], [0.0, 3.0, 0.0]], &[[0, 1, 2]])?;
/// assert_eq!(b, vec![[1.0, 1.0, 0.0]]);
/// # Ok::<(), meshgnn_graph::Error>(())
/// ```
pub fn triangle_barycentres(
    vertices: &[[f32; 3]],
    triangles: &[[u32; 3]],
) -> Result<Vec<[f32; 3]>> {
    triangles
        .iter()
        .map(|t| {
            let mut sum = [0.0f64; 3];
            for &v in t {
                let p = vertices.get(v as usize).ok_or(Error::IndexOutOfRange {
                    what: "triangle corner",
                    index: v as usize,
                    len: vertices.len(),
                })?;
                for a in 0..3 {
                    sum[a] += f64::from(p[a]);
                }
            }
            Ok(sum.map(|s| (s / 3.0) as f32))
        })
        .collect()
}

/// For each of the candidate `triangles: #F×3` over `vertices: #V×3`, the `k` triangles with
/// the nearest barycentres (ch. 6.3, k = 20). O(F log F), parallel.
///
/// Errors when `k == 0`, `k >= #F`, a corner index is out of range, or a coordinate is
/// NaN/infinite.
///
/// ```
/// use meshgnn_graph::triangle_knn_graph;
/// let v = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [5.0, 0.0, 0.0], [1.0, 1.0, 0.0]];
/// let g = triangle_knn_graph(&v, &[[0, 1, 2], [1, 3, 4], [1, 4, 2]], 1)?;
/// assert_eq!(g.indices, vec![2, 2, 0]);
/// # Ok::<(), meshgnn_graph::Error>(())
/// ```
pub fn triangle_knn_graph(
    vertices: &[[f32; 3]],
    triangles: &[[u32; 3]],
    k: usize,
) -> Result<Neighbours> {
    if k == 0 || k >= triangles.len() {
        return Err(Error::InvalidParameter {
            name: "k",
            message: format!(
                "must be in 1..{} for {} triangles",
                triangles.len(),
                triangles.len()
            ),
        });
    }
    check_u32_len(triangles.len(), "triangles")?;
    check_finite(vertices, "vertex")?;
    let centres = triangle_barycentres(vertices, triangles)?;
    Ok(SpatialIndex::new(&centres)?.knn_graph(k)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshgnn_geometry::icosphere;
    use meshgnn_geometry::squared_distance;

    #[test]
    fn matches_brute_force_on_icosphere_faces() {
        // Many equal barycentre distances on the symmetric sphere: exercises tie-breaking.
        let mesh = icosphere(2);
        let g = triangle_knn_graph(mesh.vertices(), mesh.triangles(), 20).unwrap();
        let c = triangle_barycentres(mesh.vertices(), mesh.triangles()).unwrap();
        for (i, row) in g.indices.chunks(20).enumerate() {
            let mut all: Vec<(f32, u32)> = (0..c.len())
                .filter(|&j| j != i)
                .map(|j| (squared_distance(&c[j], &c[i]), j as u32))
                .collect();
            all.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            let want: Vec<u32> = all.iter().take(20).map(|x| x.1).collect();
            assert_eq!(row, want.as_slice(), "triangle {i}");
        }
    }

    #[test]
    fn rejects_bad_corners_and_k() {
        let v = [[0.0f32; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        assert!(matches!(
            triangle_knn_graph(&v, &[[0, 1, 2], [0, 1, 3]], 1),
            Err(Error::IndexOutOfRange { index: 3, .. })
        ));
        assert!(triangle_knn_graph(&v, &[[0, 1, 2]], 1).is_err());
    }
}
