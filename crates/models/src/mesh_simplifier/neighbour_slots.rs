//! The fixed-width neighbour lists that DevConv (thesis eq. 6.1) takes its maximum over: a
//! mesh adjacency or a k-NN graph, every row padded to the widest with an empty slot.
//!
//! # Conventions
//! - `indices` is `(N·W)` `u32`, row-major: row `i` holds the `W` neighbour slots of point `i`.
//! - An empty slot holds [`NeighbourSlots::len`] (= N), one past the last point: the fused
//!   operations that read the slots ([`super::neighbour_deviation_maximum`], [`super::slot_dot_products`])
//!   skip it, so it never counts as a neighbour. (A mean layer pads differently,
//!   [`crate::point_simplifier::NeighbourIndex`], weight 0.)
//! - A point with no neighbour (an isolated vertex) lists itself once, so its relative
//!   features are zero; otherwise a point never lists itself (mesh adjacencies with a diagonal
//!   are cleaned).

use candle_core::{Device, Tensor};
use meshgnn_geometry::SpatialIndex;
use meshgnn_graph::CsrMatrix;

use crate::{Error, Result};

/// Neighbour slots of every point for a max aggregation, `indices: (N·W)`.
#[derive(Clone, Debug)]
pub struct NeighbourSlots {
    indices: Tensor,
    len: usize,
    width: usize,
}

impl NeighbourSlots {
    /// From rows of neighbour indices (`rows[i]`: the neighbours of point `i`, any lengths,
    /// each `< rows.len()`), padded as the module docs describe.
    ///
    /// ```
    /// use candle_core::Device;
    /// use meshgnn_models::mesh_simplifier::NeighbourSlots;
    /// let slots = NeighbourSlots::from_rows(&[vec![1, 2], vec![0], vec![]], &Device::Cpu)?;
    /// assert_eq!((slots.len(), slots.width()), (3, 2));
    /// let idx: Vec<u32> = slots.indices().to_vec1()?;
    /// assert_eq!(idx, vec![1, 2, 0, 3, 2, 3]); // 3: an empty slot; 2 has no neighbour
    /// # Ok::<(), meshgnn_models::Error>(())
    /// ```
    pub fn from_rows(rows: &[Vec<u32>], device: &Device) -> Result<Self> {
        let len = rows.len();
        let width = rows.iter().map(Vec::len).max().unwrap_or(0).max(1);
        let mut indices = Vec::with_capacity(len * width);
        for (i, row) in rows.iter().enumerate() {
            if let Some(&bad) = row.iter().find(|&&j| j as usize >= len) {
                return Err(Error::Invalid {
                    what: format!("neighbour {bad} of point {i}"),
                    reason: format!("out of range for {len} points"),
                });
            }
            let row: &[u32] = if row.is_empty() { &[i as u32] } else { row };
            indices.extend_from_slice(row);
            indices.extend(std::iter::repeat_n(len as u32, width - row.len()));
        }
        Ok(Self {
            indices: Tensor::from_vec(indices, len * width, device)?,
            len,
            width,
        })
    }

    /// From a mesh's vertex adjacency ([`meshgnn_graph::vertex_adjacency`]), diagonal dropped.
    pub fn from_adjacency(adjacency: &CsrMatrix, device: &Device) -> Result<Self> {
        Self::from_rows(&adjacency.off_diagonal_rows()?, device)
    }

    /// The `k` nearest other points of every point (ties by index), for point clouds. Errors
    /// unless `1 ≤ k < N`, or on non-finite coordinates.
    pub fn from_knn(points: &[[f32; 3]], k: usize, device: &Device) -> Result<Self> {
        let graph = SpatialIndex::new(points)?.knn_graph(k)?;
        Ok(Self {
            indices: Tensor::from_vec(graph.indices, points.len() * k, device)?,
            len: points.len(),
            width: k,
        })
    }

    /// The slots, `(N·W)` `u32`.
    pub fn indices(&self) -> &Tensor {
        &self.indices
    }

    /// Number of points N.
    pub fn len(&self) -> usize {
        self.len
    }

    /// True when there are no points.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Slots per point W.
    pub fn width(&self) -> usize {
        self.width
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshgnn_graph::vertex_adjacency;

    #[test]
    fn adjacency_rows_are_the_one_ring_padded_by_repetition() {
        let mesh = meshgnn_geometry::icosphere(0); // 12 vertices of degree 5
        let adjacency = vertex_adjacency(&mesh).unwrap();
        let slots = NeighbourSlots::from_adjacency(&adjacency, &Device::Cpu).unwrap();
        assert_eq!((slots.len(), slots.width()), (12, 5));
        let idx: Vec<u32> = slots.indices().to_vec1().unwrap();
        for (i, row) in idx.chunks(5).enumerate() {
            let mut row = row.to_vec();
            row.sort_unstable();
            row.dedup();
            assert_eq!(row.len(), 5, "vertex {i}");
            assert!(!row.contains(&(i as u32)));
        }
    }

    #[test]
    fn knn_rows_hold_k_other_points_and_bad_rows_are_errors() {
        let points: Vec<[f32; 3]> = (0..10).map(|i| [i as f32, 0.0, 0.0]).collect();
        let slots = NeighbourSlots::from_knn(&points, 2, &Device::Cpu).unwrap();
        let idx: Vec<u32> = slots.indices().to_vec1().unwrap();
        assert_eq!(&idx[..2], &[1, 2]); // the first point's nearest others
        assert_eq!(&idx[10..12], &[4, 6]); // point 5: both at distance 1, ties by index
        assert!(NeighbourSlots::from_knn(&points, 10, &Device::Cpu).is_err());
        assert!(NeighbourSlots::from_rows(&[vec![3]], &Device::Cpu).is_err());
    }
}
