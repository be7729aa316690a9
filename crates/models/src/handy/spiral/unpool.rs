//! Mesh unpooling `U` as a tensor operation (thesis ch. 3.3.4: "barycentric coordinates of the
//! vertices that were discarded during downsampling procedure are stored and used as the new
//! vertex coordinates of the upsampling matrices"; COMA, Ranjan et al., ECCV 2018): every fine
//! vertex is `Σ_{j<3} w_j · coarse[idx_j]`, computed with one `index_select` of the `3·N`
//! corners and a weighted sum — never a dense `N×M` matrix.

use candle_core::{Device, Tensor};

use crate::handy::spiral::pool::check_vertices;
use crate::{Error, Result};

/// Up-sampling `U: N×M` stored as three weighted gathers per fine vertex
/// (`meshgnn_graph::Upsampling`).
#[derive(Debug, Clone)]
pub struct Unpool {
    /// `(3·N)` `u32`: the corners of fine vertex `i` are entries `3i..3i+3`.
    indices: Tensor,
    /// `(1, N, 3, 1)` `f32` barycentric weights, broadcast over batch and channels.
    weights: Tensor,
    fine_vertices: usize,
    coarse_vertices: usize,
}

impl Unpool {
    /// `indices: #N×3` coarse vertices (each `< coarse_vertices`), `weights: #N×3` (finite).
    ///
    /// ```
    /// use candle_core::{Device, Tensor};
    /// use meshgnn_models::spiral::Unpool;
    /// // Fine vertex 0 is coarse 1; fine vertex 1 is the midpoint of coarse 0 and 1.
    /// let up = Unpool::new(&[[1, 0, 0], [0, 1, 0]], &[[1.0, 0.0, 0.0], [0.5, 0.5, 0.0]], 2, &Device::Cpu)?;
    /// let x = Tensor::new(&[[[2.0f32], [4.0]]], &Device::Cpu)?; // (1, 2, 1)
    /// assert_eq!(up.forward(&x)?.flatten_all()?.to_vec1::<f32>()?, vec![4.0, 3.0]);
    /// # Ok::<(), meshgnn_models::Error>(())
    /// ```
    pub fn new(
        indices: &[[u32; 3]],
        weights: &[[f32; 3]],
        coarse_vertices: usize,
        device: &Device,
    ) -> Result<Self> {
        if indices.len() != weights.len() || indices.is_empty() {
            return Err(Error::Invalid {
                what: "unpooling".into(),
                reason: format!(
                    "{} index rows and {} weight rows: need the same positive count",
                    indices.len(),
                    weights.len()
                ),
            });
        }
        if let Some(i) = indices
            .iter()
            .position(|row| row.iter().any(|&k| k as usize >= coarse_vertices))
        {
            return Err(Error::Invalid {
                what: format!("unpooling: fine vertex {i}"),
                reason: format!(
                    "gathers coarse vertex {:?}, but the coarse level has {coarse_vertices}",
                    indices[i]
                ),
            });
        }
        if let Some(i) = weights
            .iter()
            .position(|row| row.iter().any(|w| !w.is_finite()))
        {
            return Err(Error::Invalid {
                what: format!("unpooling: fine vertex {i}"),
                reason: format!("non-finite weights {:?}", weights[i]),
            });
        }
        let n = indices.len();
        let flat_indices: Vec<u32> = indices.iter().flatten().copied().collect();
        let flat_weights: Vec<f32> = weights.iter().flatten().copied().collect();
        Ok(Self {
            indices: Tensor::from_vec(flat_indices, 3 * n, device)?,
            weights: Tensor::from_vec(flat_weights, (1, n, 3, 1), device)?,
            fine_vertices: n,
            coarse_vertices,
        })
    }

    /// Fine vertex count `N`.
    pub fn fine_vertices(&self) -> usize {
        self.fine_vertices
    }

    /// Coarse vertex count `M`.
    pub fn coarse_vertices(&self) -> usize {
        self.coarse_vertices
    }

    /// `U · X` per batch item: `x: (B, M, C)` → `(B, N, C)`.
    pub fn forward(&self, x: &Tensor) -> Result<Tensor> {
        check_vertices("unpooling input", x, self.coarse_vertices)?;
        let (batch, _, channels) = x.dims3()?;
        let corners =
            x.index_select(&self.indices, 1)?
                .reshape((batch, self.fine_vertices, 3, channels))?;
        Ok(corners
            .broadcast_mul(&self.weights.to_dtype(x.dtype())?)?
            .sum(2)?)
    }
}

#[cfg(test)]
mod tests {
    use crate::handy::spiral::TemplateTensors;
    use candle_core::{Device, Tensor};
    use meshgnn_graph::HierarchyOptions;

    #[test]
    fn pool_unpool_shapes_identity_and_reference() {
        let options = HierarchyOptions {
            factors: vec![4.0],
            spiral_lengths: vec![9; 2],
            dilations: vec![1; 2],
        };
        let t =
            TemplateTensors::new(&meshgnn_geometry::icosphere(2), &options, &Device::Cpu).unwrap();
        let (pool, unpool) = (t.pool(0).unwrap(), t.unpool(0).unwrap());
        let (n, m) = (pool.fine_vertices(), pool.coarse_vertices());
        assert_eq!(
            (n, m, unpool.fine_vertices(), unpool.coarse_vertices()),
            (162, 42, 162, 42)
        );
        let values: Vec<f32> = (0..2 * n * 4).map(|k| (k as f32 * 0.37).sin()).collect();
        let x = Tensor::from_vec(values.clone(), (2, n, 4), &Device::Cpu).unwrap();
        let coarse = pool.forward(&x).unwrap();
        assert_eq!(coarse.dims(), &[2, m, 4]);
        let back = unpool.forward(&coarse).unwrap();
        assert_eq!(back.dims(), &[2, n, 4]);
        let back = back.to_vec3::<f32>().unwrap();
        let x3 = x.to_vec3::<f32>().unwrap();
        // U∘D is the identity on kept vertices.
        let p = &t.hierarchy().pooling[0];
        for &i in &p.down.kept {
            for b in 0..2 {
                for (c, value) in back[b][i as usize].iter().enumerate() {
                    assert!((value - x3[b][i as usize][c]).abs() < 1e-6);
                }
            }
        }
        // Tensor path = the graph crate's plain reference, per batch item.
        for (b, item) in values.chunks(n * 4).enumerate() {
            let reference = p.up.apply(&p.down.apply(item, 4).unwrap(), 4).unwrap();
            let got: Vec<f32> = back[b].iter().flatten().copied().collect();
            for (r, g) in reference.iter().zip(&got) {
                assert!((r - g).abs() < 1e-5);
            }
        }
        // Wrong vertex count is an error, not a panic.
        assert!(pool.forward(&coarse).is_err());
        assert!(unpool.forward(&x).is_err());
    }

    #[test]
    fn rejects_out_of_range_indices() {
        assert!(super::Unpool::new(&[[0, 1, 5]], &[[0.2, 0.3, 0.5]], 3, &Device::Cpu).is_err());
        assert!(
            super::Unpool::new(&[[0, 1, 2]], &[[f32::NAN, 0.3, 0.5]], 3, &Device::Cpu).is_err()
        );
        assert!(crate::handy::spiral::Pool::new(&[0, 3], 3, &Device::Cpu).is_err());
    }
}
