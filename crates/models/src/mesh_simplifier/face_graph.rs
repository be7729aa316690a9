//! The graph the face classifier works on (thesis ch. 6.3.3): each candidate triangle linked to
//! the `k` candidates with the nearest barycentres (k = 20, ch. 6.4), and the relative position
//! encoding of every link, eq. 6.6:
//! `r_{n,m} = [t_n^min − t_m^min ‖ t_n^max − t_m^max ‖ b_n − b_m]`, where `t^max` (`t^min`) is
//! the per-coordinate maximum (minimum) of the triangle's edge vectors `e_ij = x_i − x_j`,
//! `e_ik`, `e_jk` (corners `i < j < k` as the candidates list them) and `b` its barycentre.
//!
//! The encoding is the difference of one descriptor per triangle, `d_n = [t_n^min ‖ t_n^max ‖
//! b_n]`, so the graph keeps those (`r_{n,m} = d_n − d_m`): a layer linear in `r` applies its
//! weights once per triangle instead of once per link ([`super::TriConv`]). They depend on
//! positions only and are computed once on the host, with the candidates' geometric features
//! ([`super::candidate_features`]).
//!
//! # Conventions
//! - `neighbours`: `(F·K)` `u32`, row-major; `descriptors`: `(F, 9)`.
//! - With fewer than two candidates there are no links: `K = 0`.

use candle_core::{Device, Tensor};
use meshgnn_graph::{triangle_barycentres, triangle_knn_graph};

use super::candidate_features::{CANDIDATE_FEATURES, candidate_features};
use crate::Result;

/// Links between candidate triangles and their eq. 6.6 encodings.
#[derive(Clone, Debug)]
pub struct FaceGraph {
    pub(crate) neighbours: Tensor,
    /// `d_n` of every triangle, `(F, 9)` (module docs).
    pub(crate) descriptors: Tensor,
    /// `(F, CANDIDATE_FEATURES)`.
    pub(crate) features: Tensor,
    len: usize,
    width: usize,
}

/// `[t^min ‖ t^max]` of a triangle: per-coordinate extremes of its three edge vectors.
fn edge_extremes(corners: [[f32; 3]; 3]) -> [f32; 6] {
    let [i, j, k] = corners;
    let edges = [(i, j), (i, k), (j, k)].map(|(a, b)| [a[0] - b[0], a[1] - b[1], a[2] - b[2]]);
    let mut out = [0.0; 6];
    for c in 0..3 {
        out[c] = edges.iter().map(|e| e[c]).fold(f32::INFINITY, f32::min);
        out[c + 3] = edges.iter().map(|e| e[c]).fold(f32::NEG_INFINITY, f32::max);
    }
    out
}

impl FaceGraph {
    /// The graph of `triangles` (indices into `vertices`, whose unit `normals` are the input
    /// surface's there, and whose nearest-seed `dual` over the input is given), each linked
    /// to its `k` nearest (by barycentre; fewer when there are not `k + 1` candidates).
    ///
    /// ```
    /// use candle_core::Device;
    /// use meshgnn_models::mesh_simplifier::FaceGraph;
    /// let v = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 1.0, 0.0]];
    /// let n = [[0.0, 0.0, 1.0]; 4];
    /// let g = FaceGraph::new(&v, &n, &[[0, 1, 2], [1, 2, 3]], &[[0, 1, 2]], 20, &Device::Cpu)?;
    /// assert_eq!((g.len(), g.width()), (2, 1));
    /// # Ok::<(), meshgnn_models::Error>(())
    /// ```
    pub fn new(
        vertices: &[[f32; 3]],
        normals: &[[f32; 3]],
        triangles: &[[u32; 3]],
        dual: &[[u32; 3]],
        k: usize,
        device: &Device,
    ) -> Result<Self> {
        let len = triangles.len();
        let width = k.min(len.saturating_sub(1));
        let centres = triangle_barycentres(vertices, triangles)?;
        let neighbours = match width {
            0 => Vec::new(),
            _ => triangle_knn_graph(vertices, triangles, width)?.indices,
        };
        let descriptors: Vec<f32> = triangles
            .iter()
            .zip(&centres)
            .flat_map(|(t, centre)| {
                let extremes = edge_extremes(t.map(|v| vertices[v as usize]));
                extremes.into_iter().chain(centre.iter().copied())
            })
            .collect();
        let features = candidate_features(vertices, normals, triangles, dual)?;
        Ok(Self {
            neighbours: Tensor::from_vec(neighbours, len * width, device)?,
            descriptors: Tensor::from_vec(descriptors, (len, 9), device)?,
            features: Tensor::from_vec(features, (len, CANDIDATE_FEATURES), device)?,
            len,
            width,
        })
    }

    /// Number of candidate triangles F.
    pub fn len(&self) -> usize {
        self.len
    }

    /// True when there are no candidates.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Links per triangle K.
    pub fn width(&self) -> usize {
        self.width
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn descriptors_and_their_differences_match_a_hand_computation() {
        let v = [
            [0.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [0.0, 2.0, 0.0],
            [0.0, 0.0, 3.0],
        ];
        let n = [[0.0, 0.0, 1.0]; 4];
        let g = FaceGraph::new(&v, &n, &[[0, 1, 2], [0, 1, 3]], &[], 5, &Device::Cpu).unwrap();
        // t0: e01 = (-2,0,0), e02 = (0,-2,0), e12 = (2,-2,0) → min (-2,-2,0), max (2,0,0),
        //     barycentre (2/3, 2/3, 0).
        // t1: e01 = (-2,0,0), e03 = (0,0,-3), e13 = (2,0,-3) → min (-2,0,-3), max (2,0,0),
        //     barycentre (2/3, 0, 1).
        let d: Vec<Vec<f32>> = g.descriptors.to_vec2().unwrap();
        let third = 2.0 / 3.0;
        let expected = [
            [-2.0, -2.0, 0.0, 2.0, 0.0, 0.0, third, third, 0.0],
            [-2.0, 0.0, -3.0, 2.0, 0.0, 0.0, third, 0.0, 1.0],
        ];
        for (got, want) in d.iter().zip(expected) {
            for (a, b) in got.iter().zip(want) {
                assert!((a - b).abs() < 1e-6, "{got:?}");
            }
        }
        // r(0, 1) = d_0 − d_1, the link of triangle 0 to triangle 1.
        let r01: Vec<f32> = d[0].iter().zip(&d[1]).map(|(a, b)| a - b).collect();
        let expected01 = [0.0, -2.0, 3.0, 0.0, 0.0, 0.0, 0.0, 2.0 / 3.0, -1.0];
        for (got, want) in r01.iter().zip(expected01) {
            assert!((got - want).abs() < 1e-6, "{r01:?}");
        }
        let links: Vec<u32> = g.neighbours.to_vec1().unwrap();
        assert_eq!(links, vec![1, 0]);
        let one = FaceGraph::new(&v, &n, &[[0, 1, 2]], &[], 5, &Device::Cpu).unwrap();
        assert_eq!((one.len(), one.width()), (1, 0));
    }
}
