//! Pooling `D` and unpooling `U` between a mesh and its QEM decimation, COMA style (Ranjan et
//! al., "Generating 3D faces using convolutional mesh autoencoders", ECCV 2018; thesis ch. 3.3.4:
//! "barycentric coordinates of the vertices that were discarded during downsampling procedure
//! are stored and used as the new vertex coordinates of the upsampling matrices").
//!
//! # Conventions
//! - `D` is `M×N` (coarse × fine) and selects the kept vertices: row `j` has a single 1 at
//!   column `kept[j]`.
//! - `U` is `N×M` with at most 3 non-zeros per row: the barycentric coordinates of each fine
//!   vertex projected onto its closest coarse face (a kept vertex gets weight 1 on itself).
//!   Rows sum to 1, weights lie in `[0, 1]`, and `U·D` restricted to kept vertices is the
//!   identity.
//! - Features are row-major `(N, C)` slices, as in [`crate::CsrMatrix::mul_dense`].

use meshgnn_geometry::TriMesh;
use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::{ClosestFace, CsrMatrix, Decimation};

/// Down-sampling `D: M×N`, stored as the selected fine vertices.
#[derive(Debug, Clone, PartialEq)]
pub struct Downsampling {
    /// `#M`: the fine vertex kept as coarse vertex `j`.
    pub kept: Vec<u32>,
    /// `N`, the fine vertex count.
    pub fine_vertices: usize,
}

/// Up-sampling `U: N×M`, stored as three weighted gathers per fine vertex.
#[derive(Debug, Clone, PartialEq)]
pub struct Upsampling {
    /// `#N×3`: coarse vertices of the face each fine vertex projects onto.
    pub indices: Vec<[u32; 3]>,
    /// `#N×3`: barycentric weights (in `[0, 1]`, summing to 1).
    pub weights: Vec<[f32; 3]>,
    /// `M`, the coarse vertex count.
    pub coarse_vertices: usize,
}

/// `D` and `U` between two levels of a hierarchy.
#[derive(Debug, Clone, PartialEq)]
pub struct PoolingMatrices {
    /// Fine → coarse.
    pub down: Downsampling,
    /// Coarse → fine.
    pub up: Upsampling,
}

impl Downsampling {
    /// `D · features`: `features: (N, C)` row-major → `(M, C)`.
    pub fn apply(&self, features: &[f32], channels: usize) -> Result<Vec<f32>> {
        check_len(
            "fine features",
            self.fine_vertices * channels,
            features.len(),
        )?;
        let mut out = Vec::with_capacity(self.kept.len() * channels);
        for (j, &i) in self.kept.iter().enumerate() {
            let start = i as usize * channels;
            let row =
                features
                    .get(start..start + channels)
                    .ok_or_else(|| Error::InvalidParameter {
                        name: "kept",
                        message: format!(
                            "coarse vertex {j} selects fine vertex {i} >= {}",
                            self.fine_vertices
                        ),
                    })?;
            out.extend_from_slice(row);
        }
        Ok(out)
    }

    /// `D` as an `M×N` [`CsrMatrix`].
    pub fn to_csr(&self) -> Result<CsrMatrix> {
        let triplets: Vec<(u32, u32, f32)> = self
            .kept
            .iter()
            .enumerate()
            .map(|(j, &i)| (j as u32, i, 1.0))
            .collect();
        CsrMatrix::from_triplets(self.kept.len(), self.fine_vertices, &triplets)
    }
}

impl Upsampling {
    /// `U · features`: `features: (M, C)` row-major → `(N, C)`, accumulated in `f64`.
    pub fn apply(&self, features: &[f32], channels: usize) -> Result<Vec<f32>> {
        check_len(
            "coarse features",
            self.coarse_vertices * channels,
            features.len(),
        )?;
        if let Some(i) = self
            .indices
            .iter()
            .position(|idx| idx.iter().any(|&k| k as usize >= self.coarse_vertices))
        {
            return Err(Error::InvalidParameter {
                name: "indices",
                message: format!(
                    "fine vertex {i} gathers a coarse vertex >= {}",
                    self.coarse_vertices
                ),
            });
        }
        check_len("upsampling weights", self.indices.len(), self.weights.len())?;
        let mut out = vec![0.0f32; self.indices.len() * channels];
        out.par_chunks_mut(channels.max(1))
            .zip(self.indices.par_iter().zip(self.weights.par_iter()))
            .for_each(|(row, (idx, w))| {
                for (c, value) in row.iter_mut().enumerate() {
                    let sum: f64 = (0..3)
                        .map(|k| {
                            f64::from(w[k]) * f64::from(features[idx[k] as usize * channels + c])
                        })
                        .sum();
                    *value = sum as f32;
                }
            });
        Ok(out)
    }

    /// `U` as an `N×M` [`CsrMatrix`] (zero weights dropped, repeated indices summed).
    pub fn to_csr(&self) -> Result<CsrMatrix> {
        let triplets: Vec<(u32, u32, f32)> = self
            .indices
            .iter()
            .zip(&self.weights)
            .enumerate()
            .flat_map(|(i, (idx, w))| {
                (0..3)
                    .filter(|&k| w[k] != 0.0)
                    .map(move |k| (i as u32, idx[k], w[k]))
            })
            .collect();
        CsrMatrix::from_triplets(self.indices.len(), self.coarse_vertices, &triplets)
    }
}

fn check_len(what: &'static str, expected: usize, actual: usize) -> Result<()> {
    if expected == actual {
        Ok(())
    } else {
        Err(Error::ShapeMismatch {
            what,
            expected,
            actual,
        })
    }
}

/// COMA `D` and `U` (thesis ch. 3.3.4) from `fine` and its decimation made with
/// `keep_original_positions` (each coarse vertex sits at a fine vertex).
///
/// The closest coarse face of each fine vertex is found exactly with a kd-tree over face
/// centroids: the nearest centroid's face distance `d₀` bounds the search to centroids within
/// `d₀ + R` (`R` the largest centroid-to-corner distance). O(N log M) for evenly sized faces.
///
/// ```
/// use meshgnn_geometry::icosphere;
/// use meshgnn_graph::{decimate, pooling_matrices, DecimationOptions, Target};
/// let fine = icosphere(2);
/// let options = DecimationOptions { target: Target::Ratio(0.25), keep_original_positions: true, ..Default::default() };
/// let pool = pooling_matrices(&fine, &decimate(&fine, &options)?)?;
/// let x: Vec<f32> = (0..fine.vertex_count()).map(|i| i as f32).collect();
/// let coarse = pool.down.apply(&x, 1)?;
/// assert_eq!(coarse.len(), pool.down.kept.len());
/// let back = pool.up.apply(&coarse, 1)?;
/// for &i in &pool.down.kept { assert_eq!(back[i as usize], i as f32); }
/// # Ok::<(), meshgnn_graph::Error>(())
/// ```
pub fn pooling_matrices(fine: &TriMesh, decimation: &Decimation) -> Result<PoolingMatrices> {
    let coarse = &decimation.mesh;
    let map = &decimation.vertex_map;
    check_len("decimation vertex map", fine.vertex_count(), map.len())?;
    if coarse.face_count() == 0 {
        return Err(Error::Empty {
            what: "coarse mesh (no triangles)",
        });
    }
    let m = coarse.vertex_count();
    let mut kept = vec![u32::MAX; m];
    for (i, &j) in map.iter().enumerate() {
        let j = j as usize;
        if j < m && kept[j] == u32::MAX && fine.vertices()[i] == coarse.vertices()[j] {
            kept[j] = i as u32;
        }
    }
    if let Some(j) = kept.iter().position(|&k| k == u32::MAX) {
        return Err(Error::UnusableMesh {
            what: "decimation for pooling".into(),
            message: format!(
                "coarse vertex {j} is not at an original vertex position; decimate with \
                 keep_original_positions = true"
            ),
        });
    }

    let faces = coarse.triangles();
    let closest = ClosestFace::new(coarse)?;
    let coarse_of: Vec<u32> = {
        let mut inverse = vec![u32::MAX; fine.vertex_count()];
        for (j, &i) in kept.iter().enumerate() {
            inverse[i as usize] = j as u32;
        }
        inverse
    };

    let rows: Vec<([u32; 3], [f32; 3])> = fine
        .vertices()
        .par_iter()
        .enumerate()
        .map_init(Vec::new, |found, (i, p)| {
            if let Some(&j) = coarse_of.get(i).filter(|&&j| j != u32::MAX) {
                return ([j; 3], [1.0, 0.0, 0.0]);
            }
            let hit = closest.query(p, found);
            let w = hit.weights.map(|x| x.clamp(0.0, 1.0) as f32);
            let sum: f32 = w.iter().sum();
            let w = if sum > 0.0 {
                w.map(|x| x / sum)
            } else {
                [1.0, 0.0, 0.0]
            };
            (faces[hit.face as usize], w)
        })
        .collect();
    let (indices, weights) = rows.into_iter().unzip();
    Ok(PoolingMatrices {
        down: Downsampling {
            kept,
            fine_vertices: fine.vertex_count(),
        },
        up: Upsampling {
            indices,
            weights,
            coarse_vertices: m,
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::closest_point_on_triangle::closest_point_on_triangle;
    use crate::{DecimationOptions, Target, decimate};
    use meshgnn_geometry::{grid_plane, icosphere};

    fn pool(mesh: &TriMesh, ratio: f64) -> PoolingMatrices {
        let options = DecimationOptions {
            target: Target::Ratio(ratio),
            keep_original_positions: true,
            ..Default::default()
        };
        pooling_matrices(mesh, &decimate(mesh, &options).unwrap()).unwrap()
    }

    #[test]
    fn up_after_down_is_identity_on_kept_and_rows_are_convex() {
        let mesh = icosphere(3);
        let p = pool(&mesh, 0.2);
        let n = mesh.vertex_count();
        assert_eq!(p.up.indices.len(), n);
        let x: Vec<f32> = (0..n * 2).map(|i| (i as f32 * 0.37).sin()).collect();
        let back = p.up.apply(&p.down.apply(&x, 2).unwrap(), 2).unwrap();
        for &i in &p.down.kept {
            let i = i as usize;
            assert_eq!(&back[2 * i..2 * i + 2], &x[2 * i..2 * i + 2]);
        }
        for w in &p.up.weights {
            assert!(w.iter().all(|&x| (0.0..=1.0).contains(&x)));
            assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-6);
        }
        // The sparse forms agree with the gathers.
        let d = p.down.to_csr().unwrap();
        let u = p.up.to_csr().unwrap();
        assert_eq!(d.mul_dense(&x, 2).unwrap(), p.down.apply(&x, 2).unwrap());
        let coarse = p.down.apply(&x, 2).unwrap();
        let a = u.mul_dense(&coarse, 2).unwrap();
        let b = p.up.apply(&coarse, 2).unwrap();
        assert!(a.iter().zip(&b).all(|(x, y)| (x - y).abs() < 1e-6));
        assert!(u.row_sums().iter().all(|s| (s - 1.0).abs() < 1e-6));
    }

    #[test]
    fn upsampling_reproduces_linear_functions_on_a_plane() {
        // On a flat grid the projection is exact, so U interpolates x and y exactly.
        let mesh = grid_plane(10, 10);
        let p = pool(&mesh, 0.1);
        let coarse: Vec<f32> = p
            .down
            .kept
            .iter()
            .flat_map(|&i| {
                let v = mesh.vertices()[i as usize];
                [v[0], v[1]]
            })
            .collect();
        let fine = p.up.apply(&coarse, 2).unwrap();
        for (i, v) in mesh.vertices().iter().enumerate() {
            assert!((fine[2 * i] - v[0]).abs() < 1e-5 && (fine[2 * i + 1] - v[1]).abs() < 1e-5);
        }
    }

    #[test]
    fn brute_force_agrees_on_closest_face() {
        let mesh = icosphere(3);
        let options = DecimationOptions {
            target: Target::Ratio(0.1),
            keep_original_positions: true,
            ..Default::default()
        };
        let dec = decimate(&mesh, &options).unwrap();
        let p = pooling_matrices(&mesh, &dec).unwrap();
        let cv = dec.mesh.vertices();
        for (i, v) in mesh.vertices().iter().enumerate() {
            let q = v.map(f64::from);
            let best = dec
                .mesh
                .triangles()
                .iter()
                .map(|f| {
                    let t = f.map(|k| cv[k as usize].map(f64::from));
                    closest_point_on_triangle(q, t[0], t[1], t[2]).1
                })
                .fold(f64::INFINITY, f64::min);
            let f = p.up.indices[i].map(|k| cv[k as usize].map(f64::from));
            let got = closest_point_on_triangle(q, f[0], f[1], f[2]).1;
            assert!(got <= best + 1e-9, "vertex {i}: {got} vs {best}");
        }
    }

    #[test]
    fn rejects_decimation_that_moved_vertices() {
        let mesh = icosphere(2);
        let dec = decimate(
            &mesh,
            &DecimationOptions {
                target: Target::Ratio(0.3),
                ..Default::default()
            },
        )
        .unwrap();
        assert!(matches!(
            pooling_matrices(&mesh, &dec),
            Err(Error::UnusableMesh { .. })
        ));
        assert!(matches!(
            pooling_matrices(&icosphere(1), &dec),
            Err(Error::ShapeMismatch { .. })
        ));
    }
}
