//! What the fused graph operations (`neighbour_deviation_maximum`, `link_message_mean`,
//! `slot_dot_products`) share: the float arithmetic they are generic over and, to read their
//! operands, the contiguous host slice of a storage
//! in the forward pass, and a tensor as `f64` values in the backward pass (every backward pass
//! computes in `f64`; `f32 → f64` is exact and keeps the order of values).

use candle_core::{DType, Layout, Tensor};

/// The slice of `values` that `layout` covers; an error naming `op` unless it is contiguous.
pub(super) fn contiguous<'a, T>(
    values: &'a [T],
    layout: &Layout,
    op: &str,
) -> candle_core::Result<&'a [T]> {
    match layout.contiguous_offsets() {
        Some((start, end)) => Ok(&values[start..end]),
        None => candle_core::bail!("{op}: operands must be contiguous"),
    }
}

/// Every value of `tensor`, row-major, as `f64`.
pub(super) fn host_f64(tensor: &Tensor) -> candle_core::Result<Vec<f64>> {
    tensor.to_dtype(DType::F64)?.flatten_all()?.to_vec1()
}

/// The arithmetic the operations need of both float widths they run in (`f32`, `f64`).
pub(super) trait Real:
    Copy
    + Send
    + Sync
    + PartialOrd
    + std::ops::Add<Output = Self>
    + std::ops::Sub<Output = Self>
    + std::ops::Mul<Output = Self>
    + std::ops::Div<Output = Self>
    + std::ops::AddAssign
{
    const ZERO: Self;
    fn from_count(n: usize) -> Self;
}

impl Real for f32 {
    const ZERO: Self = 0.0;
    fn from_count(n: usize) -> Self {
        n as f32
    }
}

impl Real for f64 {
    const ZERO: Self = 0.0;
    fn from_count(n: usize) -> Self {
        n as f64
    }
}
