//! Per-vertex standardisation of registered meshes (thesis ch. 3.3.4; the data preparation of
//! COMA and Neural3DMM): the network sees `(x − μ_v) / σ_v`, with the mean and standard
//! deviation of each vertex coordinate over the training meshes, so that every vertex
//! contributes on the same scale whatever the size of the shape.

use candle_core::{Device, Tensor};
use rayon::prelude::*;

use crate::{Error, Result};

/// Mean and standard deviation `(V, 3)` of every vertex coordinate of a training set.
#[derive(Debug, Clone)]
pub struct VertexNormalization {
    mean: Tensor,
    std: Tensor,
}

impl VertexNormalization {
    /// Fits the statistics of `meshes: #S × (#V×3)` in `f64` (population standard deviation).
    /// A standard deviation below `1e-6 ·` the largest one (or every one when all are zero,
    /// e.g. a single training mesh) is raised to that floor (or to 1), so constant coordinates
    /// neither divide by zero nor amplify noise.
    ///
    /// ```
    /// use candle_core::Device;
    /// use meshgnn_models::spiral::VertexNormalization;
    /// let meshes = vec![vec![[0.0f32, 1.0, 2.0]], vec![[2.0, 1.0, 2.0]]];
    /// let n = VertexNormalization::fit(&meshes, &Device::Cpu)?;
    /// assert_eq!(n.mean().flatten_all()?.to_vec1::<f32>()?, vec![1.0, 1.0, 2.0]);
    /// assert_eq!(n.std().flatten_all()?.to_vec1::<f32>()?, vec![1.0, 1e-6, 1e-6]);
    /// # Ok::<(), meshgnn_models::Error>(())
    /// ```
    pub fn fit(meshes: &[Vec<[f32; 3]>], device: &Device) -> Result<Self> {
        let v = check_meshes("training meshes", meshes, None)?;
        let count = meshes.len() as f64;
        let (mean, std): (Vec<f64>, Vec<f64>) = (0..v * 3)
            .into_par_iter()
            .map(|k| {
                let (i, c) = (k / 3, k % 3);
                let mean = meshes.iter().map(|m| f64::from(m[i][c])).sum::<f64>() / count;
                let var = meshes
                    .iter()
                    .map(|m| (f64::from(m[i][c]) - mean).powi(2))
                    .sum::<f64>()
                    / count;
                (mean, var.sqrt())
            })
            .unzip();
        let largest = std.iter().copied().fold(0.0f64, f64::max);
        let floor = if largest > 0.0 { 1e-6 * largest } else { 1.0 };
        let mean: Vec<f32> = mean.into_iter().map(|m| m as f32).collect();
        let std: Vec<f32> = std.into_iter().map(|s| s.max(floor) as f32).collect();
        Self::from_tensors(
            Tensor::from_vec(mean, (v, 3), device)?,
            Tensor::from_vec(std, (v, 3), device)?,
        )
    }

    /// From stored statistics `mean`, `std`: `(V, 3)` `f32`, every `std` positive and finite.
    pub fn from_tensors(mean: Tensor, std: Tensor) -> Result<Self> {
        let (v, c) = mean.dims2()?;
        if c != 3 || std.dims() != mean.dims() {
            return Err(Error::Invalid {
                what: "vertex normalisation".into(),
                reason: format!(
                    "mean {:?} and std {:?}: both must be (V, 3)",
                    mean.dims(),
                    std.dims()
                ),
            });
        }
        let values = std.flatten_all()?.to_vec1::<f32>()?;
        if let Some(k) = values.iter().position(|s| !(s.is_finite() && *s > 0.0)) {
            return Err(Error::Invalid {
                what: format!("vertex normalisation: std of vertex {} of {v}", k / 3),
                reason: format!("{} is not positive and finite", values[k]),
            });
        }
        Ok(Self { mean, std })
    }

    /// Mean `(V, 3)`.
    pub fn mean(&self) -> &Tensor {
        &self.mean
    }

    /// Standard deviation `(V, 3)`.
    pub fn std(&self) -> &Tensor {
        &self.std
    }

    /// `(x − μ) / σ`: `x: (B, V, 3)` in data units → normalised.
    pub fn normalize(&self, x: &Tensor) -> Result<Tensor> {
        Ok(x.broadcast_sub(&self.mean)?.broadcast_div(&self.std)?)
    }

    /// `x · σ + μ`: normalised `(B, V, 3)` → data units.
    pub fn denormalize(&self, x: &Tensor) -> Result<Tensor> {
        Ok(x.broadcast_mul(&self.std)?.broadcast_add(&self.mean)?)
    }

    /// Mean per-vertex Euclidean distance in data units between normalised `predicted` and
    /// `target` `(B, V, 3)`: `mean_{b,v} ‖σ_v ⊙ (p − t)‖`.
    pub fn euclidean_error(&self, predicted: &Tensor, target: &Tensor) -> Result<Tensor> {
        Ok(predicted
            .sub(target)?
            .broadcast_mul(&self.std)?
            .sqr()?
            .sum(2)?
            .sqrt()?
            .mean_all()?)
    }
}

/// Checks `meshes` is non-empty, every mesh has the same vertex count (`expected` when given)
/// and finite coordinates; returns the vertex count.
pub(crate) fn check_meshes(
    what: &str,
    meshes: &[Vec<[f32; 3]>],
    expected: Option<usize>,
) -> Result<usize> {
    let first = meshes.first().ok_or_else(|| Error::Invalid {
        what: what.into(),
        reason: "no mesh given".into(),
    })?;
    let v = expected.unwrap_or(first.len());
    if v == 0 {
        return Err(Error::Invalid {
            what: what.into(),
            reason: "meshes have no vertex".into(),
        });
    }
    for (s, mesh) in meshes.iter().enumerate() {
        if mesh.len() != v {
            return Err(Error::Invalid {
                what: format!("{what}: mesh {s}"),
                reason: format!("has {} vertices, expected {v}", mesh.len()),
            });
        }
        if let Some(i) = meshgnn_geometry::vec3::first_non_finite(mesh) {
            return Err(Error::Invalid {
                what: format!("{what}: mesh {s}, vertex {i}"),
                reason: format!("non-finite coordinate {:?}", mesh[i]),
            });
        }
    }
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fit_normalize_denormalize() {
        let meshes = vec![
            vec![[0.0f32, 0.0, 1.0], [1.0, 5.0, 2.0]],
            vec![[2.0, 4.0, 1.0], [3.0, 5.0, 2.0]],
        ];
        let n = VertexNormalization::fit(&meshes, &Device::Cpu).unwrap();
        let mean = n.mean().to_vec2::<f32>().unwrap();
        let std = n.std().to_vec2::<f32>().unwrap();
        assert_eq!(mean, vec![vec![1.0, 2.0, 1.0], vec![2.0, 5.0, 2.0]]);
        // Population std 1 and 2; constant coordinates get the floor 1e-6 · 2.
        assert_eq!(std, vec![vec![1.0, 2.0, 2e-6], vec![1.0, 2e-6, 2e-6]]);
        let x = crate::handy::spiral::mesh_batch(&meshes, &Device::Cpu).unwrap();
        let z = n.normalize(&x).unwrap();
        assert_eq!(z.to_vec3::<f32>().unwrap()[0][0], vec![-1.0, -1.0, 0.0]);
        let back = n.denormalize(&z).unwrap().to_vec3::<f32>().unwrap();
        assert_eq!(back, x.to_vec3::<f32>().unwrap());
        // Euclidean error in data units: shift vertex 0 of item 0 by (0.5σ, 0, 0) → 0.5 / 4.
        let mut moved = z.to_vec3::<f32>().unwrap();
        moved[0][0][0] += 0.5;
        let moved = Tensor::new(moved, &Device::Cpu).unwrap();
        let e = n
            .euclidean_error(&moved, &z)
            .unwrap()
            .to_scalar::<f32>()
            .unwrap();
        assert!((e - 0.125).abs() < 1e-6);
    }

    #[test]
    fn rejects_bad_input() {
        assert!(VertexNormalization::fit(&[], &Device::Cpu).is_err());
        assert!(VertexNormalization::fit(&[vec![[0.0, 0.0, 0.0]], vec![]], &Device::Cpu).is_err());
        assert!(VertexNormalization::fit(&[vec![[f32::NAN, 0.0, 0.0]]], &Device::Cpu).is_err());
        let m = Tensor::zeros((2, 3), candle_core::DType::F32, &Device::Cpu).unwrap();
        assert!(VertexNormalization::from_tensors(m.clone(), m).is_err());
        let single = VertexNormalization::fit(&[vec![[1.0, 2.0, 3.0]]], &Device::Cpu).unwrap();
        assert_eq!(
            single
                .std()
                .flatten_all()
                .unwrap()
                .to_vec1::<f32>()
                .unwrap(),
            vec![1.0; 3]
        );
    }
}
