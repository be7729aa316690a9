//! Moving between candle tensors and the plain point lists the k-d tree needs. Values are
//! read detached from the autograd graph: correspondences are constants of the loss.

use crate::point_index::PointIndex;
use crate::validate::check_finite;
use crate::{Error, Result};
use candle_core::{DType, Device, Tensor};

/// The rows of `points: (N, 3)` as `f32` triples (any float dtype), detached.
pub(crate) fn points_of(what: &'static str, points: &Tensor) -> Result<Vec<[f32; 3]>> {
    let dims = points.dims();
    if dims.len() != 2 || dims.get(1) != Some(&3) {
        return Err(Error::Shape {
            what,
            expected: "(N, 3)",
            actual: dims.to_vec(),
        });
    }
    if dims.first() == Some(&0) {
        return Err(Error::Empty { what });
    }
    let rows: Vec<Vec<f32>> = points.detach().to_dtype(DType::F32)?.to_vec2()?;
    let out: Vec<[f32; 3]> = rows
        .into_iter()
        .map(|r| match r.as_slice() {
            &[x, y, z] => Ok([x, y, z]),
            _ => Err(Error::Shape {
                what,
                expected: "(N, 3)",
                actual: vec![r.len()],
            }),
        })
        .collect::<Result<_>>()?;
    check_finite(what, &out)?;
    Ok(out)
}

/// Checks that `values` is a vector `(len)`.
pub(crate) fn check_vector(what: &'static str, values: &Tensor, len: usize) -> Result<()> {
    if values.dims() == [len] {
        Ok(())
    } else {
        Err(Error::Shape {
            what,
            expected: "(N) matching the points",
            actual: values.dims().to_vec(),
        })
    }
}

/// An index tensor `(len)` of `u32` on `device`.
pub(crate) fn index_tensor(indices: Vec<u32>, device: &Device) -> Result<Tensor> {
    let n = indices.len();
    Ok(Tensor::from_vec(indices, n, device)?)
}

/// Row `i` of a squared-distance computation: `‖a − b‖²` per row of two `(N, 3)` tensors.
pub(crate) fn row_squared_distances(a: &Tensor, b: &Tensor) -> Result<Tensor> {
    Ok(a.sub(b)?.sqr()?.sum(1)?)
}

/// For every query point, the index of its nearest target point, as a `u32` tensor `(Q)`.
pub(crate) fn nearest_index_tensor(
    queries: &[[f32; 3]],
    targets: &[[f32; 3]],
    device: &Device,
) -> Result<Tensor> {
    let tree = PointIndex::new(targets);
    let nn = tree
        .nearest_all(queries)
        .into_iter()
        .map(|(j, _)| j as u32)
        .collect();
    index_tensor(nn, device)
}
