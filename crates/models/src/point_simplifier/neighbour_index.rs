//! The fixed-width neighbour lists the projector's GNN layer (thesis eq. 5.4) aggregates over:
//! a k-NN graph (k = 7, ch. 5.6) or a mesh adjacency padded to its largest degree.
//!
//! # Conventions
//! - `indices` is `(N·W)` `u32`, row-major: row `i` holds the `W` neighbour slots of point `i`.
//! - `weights` is `(N, W, 1)` `f32`: `1 / |N_i|` for a real neighbour and `0` for a padding slot,
//!   so `Σ_slots weight · f_slot` is exactly the mean `1/|N_i| Σ_{j∈N_i} f_j` of eq. 5.4.
//! - Padding (mesh adjacencies, whose degrees vary): a row shorter than `W` is filled with the
//!   point's own index and weight 0. A point with no neighbour (isolated vertex) gets a zero
//!   mean, i.e. `f'_i = W_c f_i`.

use std::sync::{Arc, OnceLock};

use candle_core::{Device, Tensor};
use meshgnn_geometry::SpatialIndex;
use meshgnn_graph::{CsrMatrix, Neighbours};
use rayon::prelude::*;

use crate::{Error, Result};

/// Neighbour slots and mean weights of every point, `indices: (N·W)`, `weights: (N, W, 1)`.
#[derive(Clone, Debug)]
pub struct NeighbourIndex {
    /// The slots of every point: given at construction, or built at first use for a k-NN
    /// graph over `knn_index` (inference reads only some rows: [`NeighbourIndex::mean_rows`]).
    slots: OnceLock<Slots>,
    len: usize,
    width: usize,
    device: Device,
    /// The kd-tree of [`NeighbourIndex::from_knn_index`]: the source of the rows, reused for
    /// the Lloyd steps and AttRef's eq. 5.5 queries over the same points.
    knn_index: Option<Arc<SpatialIndex>>,
}

/// The slot tensors and their sparse mean.
#[derive(Clone, Debug)]
struct Slots {
    indices: Tensor,
    weights: Tensor,
    mean: CsrMatrix,
}

impl NeighbourIndex {
    /// From rows of neighbour indices (`rows[i]` = the neighbours of point `i`, any lengths;
    /// each index `< rows.len()`), padded to the longest row as described in the module docs.
    ///
    /// ```
    /// use candle_core::Device;
    /// use meshgnn_models::point_simplifier::NeighbourIndex;
    /// let g = NeighbourIndex::from_rows(&[vec![1, 2], vec![0], vec![]], &Device::Cpu)?;
    /// assert_eq!((g.len(), g.width()), (3, 2));
    /// let w: Vec<f32> = g.weights()?.flatten_all()?.to_vec1()?;
    /// assert_eq!(w, vec![0.5, 0.5, 1.0, 0.0, 0.0, 0.0]);
    /// # Ok::<(), meshgnn_models::Error>(())
    /// ```
    pub fn from_rows(rows: &[Vec<u32>], device: &Device) -> Result<Self> {
        let n = rows.len();
        let width = rows.iter().map(Vec::len).max().unwrap_or(0).max(1);
        let mut indices = Vec::with_capacity(n * width);
        let mut weights = Vec::with_capacity(n * width);
        for (i, row) in rows.iter().enumerate() {
            if let Some(&bad) = row.iter().find(|&&j| j as usize >= n) {
                return Err(Error::Invalid {
                    what: format!("neighbour {bad} of point {i}"),
                    reason: format!("out of range for {n} points"),
                });
            }
            let w = if row.is_empty() {
                0.0
            } else {
                1.0 / row.len() as f32
            };
            indices.extend_from_slice(row);
            weights.extend(std::iter::repeat_n(w, row.len()));
            let pad = width - row.len();
            indices.extend(std::iter::repeat_n(i as u32, pad));
            weights.extend(std::iter::repeat_n(0.0f32, pad));
        }
        Self::from_flat(indices, weights, n, width, device)
    }

    /// From a k-NN graph (`neighbours.indices: #N×k`, e.g. [`meshgnn_graph::knn_graph`] with
    /// k = 7): every row is full, weights `1/k`.
    ///
    /// ```
    /// use candle_core::Device;
    /// use meshgnn_graph::knn_graph;
    /// use meshgnn_models::point_simplifier::NeighbourIndex;
    /// let pts = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [3.0, 0.0, 0.0]];
    /// let g = NeighbourIndex::from_knn(&knn_graph(&pts, 2)?, &Device::Cpu)?;
    /// assert_eq!((g.len(), g.width()), (3, 2));
    /// # Ok::<(), meshgnn_models::Error>(())
    /// ```
    pub fn from_knn(neighbours: &Neighbours, device: &Device) -> Result<Self> {
        let n = neighbours.len();
        let k = neighbours.k;
        if let Some(&bad) = neighbours.indices.iter().find(|&&j| j as usize >= n) {
            return Err(Error::Invalid {
                what: format!("k-NN neighbour {bad}"),
                reason: format!("out of range for {n} points"),
            });
        }
        let w = 1.0 / k.max(1) as f32;
        Self::from_flat(neighbours.indices.clone(), vec![w; n * k], n, k, device)
    }

    /// The eq. 5.4 k-NN graph (`k` nearest other points, weights `1/k`) of the points a
    /// prebuilt `index` holds. Rows are found when first read, and only those read:
    /// [`NeighbourIndex::mean_rows`] queries just the rows asked, the slot tensors query all.
    /// The index is kept for [`super::PointSimplifier::forward`]'s other queries over the same
    /// points. Errors when `k == 0` or `k >= N`.
    ///
    /// ```
    /// use candle_core::Device;
    /// use meshgnn_geometry::SpatialIndex;
    /// use meshgnn_models::point_simplifier::NeighbourIndex;
    /// let pts = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [3.0, 0.0, 0.0]];
    /// let g = NeighbourIndex::from_knn_index(SpatialIndex::new(&pts)?, 1, &Device::Cpu)?;
    /// let idx: Vec<u32> = g.indices()?.to_vec1()?;
    /// assert_eq!(idx, vec![1, 0, 1]);
    /// assert_eq!(g.knn_index().map(SpatialIndex::len), Some(3));
    /// # Ok::<(), meshgnn_models::Error>(())
    /// ```
    pub fn from_knn_index(index: SpatialIndex, k: usize, device: &Device) -> Result<Self> {
        let n = index.len();
        if k == 0 || k >= n {
            return Err(Error::Invalid {
                what: "k-NN graph".into(),
                reason: format!("k must be in 1..{n} for {n} points, got {k}"),
            });
        }
        Ok(Self {
            slots: OnceLock::new(),
            len: n,
            width: k,
            device: device.clone(),
            knn_index: Some(Arc::new(index)),
        })
    }

    /// The k-NN index kept by [`NeighbourIndex::from_knn_index`] (`None` otherwise).
    pub fn knn_index(&self) -> Option<&SpatialIndex> {
        self.knn_index.as_deref()
    }

    /// From a mesh adjacency `adjacency: #V×#V` (e.g. [`meshgnn_graph::vertex_adjacency`]);
    /// the stored columns of row `i` are its neighbours (values ignored), padded to the largest
    /// degree as described in the module docs.
    pub fn from_adjacency(adjacency: &CsrMatrix, device: &Device) -> Result<Self> {
        Self::from_rows(&adjacency.off_diagonal_rows()?, device)
    }

    fn from_flat(
        indices: Vec<u32>,
        weights: Vec<f32>,
        len: usize,
        width: usize,
        device: &Device,
    ) -> Result<Self> {
        Ok(Self {
            slots: OnceLock::from(Slots::new(indices, weights, len, width, device)?),
            len,
            width,
            device: device.clone(),
            knn_index: None,
        })
    }

    /// The slots, built from the k-NN index at first use.
    fn slots(&self) -> Result<&Slots> {
        if let Some(slots) = self.slots.get() {
            return Ok(slots);
        }
        let index = self.knn_index.as_deref().ok_or_else(|| Error::Invalid {
            what: "neighbour index".into(),
            reason: "has neither slots nor a k-NN index".into(),
        })?;
        let k = self.width;
        let nn = index.knn_graph(k)?;
        let weights = vec![1.0 / k as f32; nn.indices.len()];
        let built = Slots::new(nn.indices, weights, self.len, k, &self.device)?;
        Ok(self.slots.get_or_init(|| built))
    }

    /// The same means as a row-stochastic sparse matrix `#N×#N` (row `i`: `1/|N_i|` at each
    /// neighbour), for inference without autograd: `mean = A · F`.
    pub fn mean_matrix(&self) -> Result<&CsrMatrix> {
        Ok(&self.slots()?.mean)
    }

    /// [`NeighbourIndex::mean_matrix`] restricted to the points `rows` (distinct, each `< N`):
    /// `#rows × N`, row `r` equal to row `rows[r]` of the full matrix. A k-NN graph whose rows
    /// were not needed yet queries only these (inference reads the embeddings of the points
    /// AttRef looks at, not of all).
    pub fn mean_rows(&self, rows: &[u32]) -> Result<CsrMatrix> {
        if let (None, Some(index)) = (self.slots.get(), self.knn_index.as_deref()) {
            let k = self.width;
            let nn = index.knn_rows(rows, k)?;
            let weights = vec![1.0 / k as f32; nn.indices.len()];
            return mean_matrix(&nn.indices, &weights, rows.len(), self.len, k);
        }
        let full = &self.slots()?.mean;
        let mut offsets = Vec::with_capacity(rows.len() + 1);
        offsets.push(0);
        let (mut cols, mut vals) = (Vec::new(), Vec::new());
        for &r in rows {
            if r as usize >= self.len {
                return Err(Error::Invalid {
                    what: format!("row {r}"),
                    reason: format!("out of range for {} points", self.len),
                });
            }
            let (c, v) = full.row(r as usize);
            cols.extend_from_slice(c);
            vals.extend_from_slice(v);
            offsets.push(cols.len());
        }
        Ok(CsrMatrix::from_parts(
            rows.len(),
            self.len,
            offsets,
            cols,
            vals,
        )?)
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

    /// Neighbour slots `(N·W)` `u32`.
    pub fn indices(&self) -> Result<&Tensor> {
        Ok(&self.slots()?.indices)
    }

    /// Mean weights `(N, W, 1)`.
    pub fn weights(&self) -> Result<&Tensor> {
        Ok(&self.slots()?.weights)
    }
}

impl Slots {
    fn new(
        indices: Vec<u32>,
        weights: Vec<f32>,
        len: usize,
        width: usize,
        device: &Device,
    ) -> Result<Self> {
        let mean = mean_matrix(&indices, &weights, len, len, width)?;
        Ok(Self {
            indices: Tensor::from_vec(indices, len * width, device)?,
            weights: Tensor::from_vec(weights, (len, width, 1), device)?,
            mean,
        })
    }
}

/// The CSR form (`rows × cols`) of `rows` rows of `width` slots: real neighbours (weight > 0)
/// sorted by index, duplicates merged.
fn mean_matrix(
    indices: &[u32],
    weights: &[f32],
    rows: usize,
    cols: usize,
    width: usize,
) -> Result<CsrMatrix> {
    // each row's slots sorted by index in place (rows in parallel), then one pass that drops
    // padding (weight 0) and merges repeated neighbours
    let width = width.max(1);
    let mut slots: Vec<(u32, f32)> = indices
        .par_iter()
        .copied()
        .zip(weights.par_iter().copied())
        .collect();
    slots
        .par_chunks_mut(width)
        .for_each(|row| row.sort_unstable_by_key(|&(i, _)| i));
    // rows of `width` distinct real neighbours (every k-NN row) are already CSR rows
    let complete = slots
        .par_chunks(width)
        .all(|row| row.iter().all(|&(_, w)| w > 0.0) && row.windows(2).all(|p| p[0].0 != p[1].0));
    if complete {
        let (columns, vals): (Vec<u32>, Vec<f32>) = slots.into_par_iter().unzip();
        let offsets = (0..=rows).map(|r| r * width).collect();
        return Ok(CsrMatrix::from_parts(rows, cols, offsets, columns, vals)?);
    }
    let mut offsets = Vec::with_capacity(rows + 1);
    offsets.push(0);
    let mut columns: Vec<u32> = Vec::with_capacity(slots.len());
    let mut vals: Vec<f32> = Vec::with_capacity(slots.len());
    for row in slots.chunks(width) {
        let row_start = columns.len();
        for &(i, w) in row.iter().filter(|&&(_, w)| w > 0.0) {
            match (columns.last(), vals.last_mut()) {
                (Some(&last), Some(v)) if columns.len() > row_start && last == i => *v += w,
                _ => {
                    columns.push(i);
                    vals.push(w);
                }
            }
        }
        offsets.push(columns.len());
    }
    Ok(CsrMatrix::from_parts(rows, cols, offsets, columns, vals)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn adjacency_rows_are_padded_with_self_and_zero_weight() {
        let adj =
            CsrMatrix::from_triplets(3, 3, &[(0, 1, 1.0), (0, 2, 1.0), (1, 0, 1.0), (2, 0, 1.0)])
                .unwrap();
        let g = NeighbourIndex::from_adjacency(&adj, &Device::Cpu).unwrap();
        assert_eq!(g.width(), 2);
        let idx: Vec<u32> = g.indices().unwrap().to_vec1().unwrap();
        assert_eq!(idx, vec![1, 2, 0, 1, 0, 2]);
        let w: Vec<f32> = g
            .weights()
            .unwrap()
            .flatten_all()
            .unwrap()
            .to_vec1()
            .unwrap();
        assert_eq!(w, vec![0.5, 0.5, 1.0, 0.0, 1.0, 0.0]);
        let a = g.mean_matrix().unwrap();
        assert_eq!(
            (a.get(0, 1), a.get(0, 2), a.get(1, 0), a.get(1, 1)),
            (0.5, 0.5, 1.0, 0.0)
        );
        assert!(NeighbourIndex::from_rows(&[vec![3]], &Device::Cpu).is_err());
    }
}
