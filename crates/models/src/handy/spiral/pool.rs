//! Mesh pooling `D` as a tensor operation (thesis ch. 3.3.4; COMA, Ranjan et al., ECCV 2018):
//! the coarse level keeps a subset of the fine vertices (QEM decimation with original
//! positions), so `D · X` is a row selection, computed with one `index_select` — never a dense
//! `M×N` matrix.

use candle_core::{Device, Tensor};

use crate::{Error, Result};

/// Down-sampling `D: M×N` stored as the kept fine vertices (`meshgnn_graph::Downsampling`).
#[derive(Debug, Clone)]
pub struct Pool {
    kept: Tensor,
    fine_vertices: usize,
}

impl Pool {
    /// `kept: #M` fine-vertex indices (each `< fine_vertices`), one per coarse vertex.
    ///
    /// ```
    /// use candle_core::{Device, Tensor};
    /// use meshgnn_models::spiral::Pool;
    /// let pool = Pool::new(&[2, 0], 3, &Device::Cpu)?;
    /// let x = Tensor::new(&[[[1.0f32], [2.0], [3.0]]], &Device::Cpu)?; // (1, 3, 1)
    /// assert_eq!(pool.forward(&x)?.flatten_all()?.to_vec1::<f32>()?, vec![3.0, 1.0]);
    /// # Ok::<(), meshgnn_models::Error>(())
    /// ```
    pub fn new(kept: &[u32], fine_vertices: usize, device: &Device) -> Result<Self> {
        if let Some((j, &i)) = kept
            .iter()
            .enumerate()
            .find(|&(_, &i)| i as usize >= fine_vertices)
        {
            return Err(Error::Invalid {
                what: format!("pooling: coarse vertex {j}"),
                reason: format!("keeps fine vertex {i}, but the fine level has {fine_vertices}"),
            });
        }
        if kept.is_empty() {
            return Err(Error::Invalid {
                what: "pooling".into(),
                reason: "keeps no vertex".into(),
            });
        }
        Ok(Self {
            kept: Tensor::from_slice(kept, kept.len(), device)?,
            fine_vertices,
        })
    }

    /// Fine vertex count `N`.
    pub fn fine_vertices(&self) -> usize {
        self.fine_vertices
    }

    /// Coarse vertex count `M`.
    pub fn coarse_vertices(&self) -> usize {
        self.kept.elem_count()
    }

    /// The kept indices `(M)` `u32`.
    pub fn kept(&self) -> &Tensor {
        &self.kept
    }

    /// `D · X` per batch item: `x: (B, N, C)` → `(B, M, C)`.
    pub fn forward(&self, x: &Tensor) -> Result<Tensor> {
        check_vertices("pooling input", x, self.fine_vertices)?;
        Ok(x.index_select(&self.kept, 1)?)
    }
}

/// Errors unless `x` is `(B, expected, C)`.
pub(crate) fn check_vertices(what: &str, x: &Tensor, expected: usize) -> Result<()> {
    match x.dims() {
        [_, v, _] if *v == expected => Ok(()),
        dims => Err(Error::Invalid {
            what: what.into(),
            reason: format!("shape {dims:?}, expected (B, {expected}, C)"),
        }),
    }
}
