//! DevConv's inner maximum (eq. 6.1) per channel, `d_i = max_{j∈N(i)} (y_i − y_j) = y_i −
//! min_{j∈N(i)} y_j`, as one fused operation over each point's neighbour slots. A gather
//! followed by a reduction materialises `N·W·C` values (1.5 GB for the 6-NN graph of a
//! 1M-point cloud at 64 channels, twice over for the subtraction); this reads the neighbour
//! rows in place and writes `N·C` once (the minimum and the difference as separate tensors
//! wrote it twice).
//!
//! The forward pass is exact: `y_i − y_j` rounds monotonically in `y_j`, so `y_i − min_j y_j`
//! equals the maximum of the rounded differences bit for bit. The backward pass sends each
//! output gradient to the point itself and, negated, to the neighbour that attained the
//! minimum (the first listed, on a tie). Empty slots ([`super::NeighbourSlots`]: index `N`)
//! are skipped; a row without a real slot (which `NeighbourSlots` never builds) gives 0.

use candle_core::{CpuStorage, CustomOp2, Layout, Shape, Tensor};
use rayon::prelude::*;

use super::op_operands::{Real, contiguous, host_f64};

/// The name in error messages.
const NAME: &str = "neighbour deviation maximum";

/// Rows per parallel task: large enough to amortise the scheduling, small enough to balance.
const ROWS_PER_TASK: usize = 4096;

/// `neighbour_deviation_maximum(values (N, C), slots (N·W) u32) → (N, C)` (module docs).
pub fn neighbour_deviation_maximum(values: &Tensor, slots: &Tensor) -> candle_core::Result<Tensor> {
    values
        .contiguous()?
        .apply_op2(&slots.contiguous()?, NeighbourDeviationMaximum)
}

struct NeighbourDeviationMaximum;

/// `(N, C, W)` of the operands, checked.
fn dimensions(values: &Shape, slot_count: usize) -> candle_core::Result<(usize, usize, usize)> {
    let (n, c) = values.dims2()?;
    if n == 0 || !slot_count.is_multiple_of(n) {
        candle_core::bail!("{NAME}: {slot_count} slots for {n} points");
    }
    Ok((n, c, slot_count / n))
}

/// Row `i` of the minimum (module docs) into `out_row`, which holds the point's own row on
/// entry, and, into `from`, the point whose value each channel took (the first on a tie): the
/// backward pass's argmin.
fn minimum_row<T: Real>(values: &[T], row: &[u32], out_row: &mut [T], from: &mut [usize]) {
    let channels = out_row.len();
    if channels == 0 {
        return;
    }
    let n = values.len() / channels;
    let mut first = true;
    for &j in row {
        let j = j as usize;
        if j >= n {
            continue;
        }
        let neighbour = &values[j * channels..(j + 1) * channels];
        for (channel, (out, &v)) in out_row.iter_mut().zip(neighbour).enumerate() {
            if first || v < *out {
                *out = v;
                from[channel] = j;
            }
        }
        first = false;
    }
}

fn deviation_maximum<T: Real>(
    values: &[T],
    slots: &[u32],
    channels: usize,
    width: usize,
) -> Vec<T> {
    let mut out = vec![T::ZERO; values.len()];
    if channels == 0 {
        return out;
    }
    let n = values.len() / channels;
    out.par_chunks_mut(ROWS_PER_TASK * channels)
        .enumerate()
        .for_each(|(task, rows)| {
            let mut least = vec![T::ZERO; channels];
            for (offset, out_row) in rows.chunks_mut(channels).enumerate() {
                let i = task * ROWS_PER_TASK + offset;
                let own = &values[i * channels..(i + 1) * channels];
                let mut real = slots[i * width..(i + 1) * width]
                    .iter()
                    .map(|&j| j as usize)
                    .filter(|&j| j < n);
                match real.next() {
                    Some(j) => least.copy_from_slice(&values[j * channels..(j + 1) * channels]),
                    None => least.copy_from_slice(own),
                }
                // A branch-free minimum per channel, so the loop vectorises.
                for j in real {
                    for (m, &v) in least.iter_mut().zip(&values[j * channels..]) {
                        *m = if v < *m { v } else { *m };
                    }
                }
                // Written once: a fresh output page read before it is written is first mapped
                // to the shared zero page, then copied, with a TLB flush on every core.
                for ((o, &y), &m) in out_row.iter_mut().zip(own).zip(&least) {
                    *o = y - m;
                }
            }
        });
    out
}

impl CustomOp2 for NeighbourDeviationMaximum {
    fn name(&self) -> &'static str {
        "neighbour-deviation-maximum"
    }

    fn cpu_fwd(
        &self,
        s1: &CpuStorage,
        l1: &Layout,
        s2: &CpuStorage,
        l2: &Layout,
    ) -> candle_core::Result<(CpuStorage, Shape)> {
        let CpuStorage::U32(slots) = s2 else {
            candle_core::bail!("{NAME}: slots must be u32");
        };
        let slots = contiguous(slots, l2, NAME)?;
        let (_, c, w) = dimensions(l1.shape(), slots.len())?;
        let out = match s1 {
            CpuStorage::F32(v) => {
                CpuStorage::F32(deviation_maximum(contiguous(v, l1, NAME)?, slots, c, w))
            }
            CpuStorage::F64(v) => {
                CpuStorage::F64(deviation_maximum(contiguous(v, l1, NAME)?, slots, c, w))
            }
            _ => candle_core::bail!("{NAME}: values must be f32 or f64"),
        };
        Ok((out, l1.shape().clone()))
    }

    fn bwd(
        &self,
        values: &Tensor,
        slots: &Tensor,
        _result: &Tensor,
        grad: &Tensor,
    ) -> candle_core::Result<(Option<Tensor>, Option<Tensor>)> {
        // f32 → f64 is exact and keeps the order, so the argmin is the forward pass's.
        let y = host_f64(values)?;
        let g = host_f64(grad)?;
        let slot_list: Vec<u32> = slots.flatten_all()?.to_vec1()?;
        let (n, c, w) = dimensions(values.shape(), slot_list.len())?;
        let mut input_grad = vec![0f64; n * c];
        let mut out_row = vec![0f64; c];
        let mut from = vec![0usize; c];
        for (i, row) in slot_list.chunks(w).enumerate() {
            out_row.copy_from_slice(&y[i * c..(i + 1) * c]);
            from.fill(i);
            minimum_row(&y, row, &mut out_row, &mut from);
            for (channel, &j) in from.iter().enumerate() {
                input_grad[i * c + channel] += g[i * c + channel];
                input_grad[j * c + channel] -= g[i * c + channel];
            }
        }
        let input_grad = Tensor::from_vec(input_grad, (n, c), values.device())?;
        Ok((Some(input_grad.to_dtype(values.dtype())?), None))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh_simplifier::NeighbourSlots;
    use candle_core::{D, DType, Device};
    use meshgnn_losses::losses::gradient_disagreement;

    /// The gather-and-reduce formulation the op replaces, empty slots reading `+∞`: `y_i`
    /// minus the neighbours' minimum.
    fn gathered(values: &Tensor, slots: &NeighbourSlots) -> Tensor {
        let (n, c) = values.dims2().unwrap();
        let empty = Tensor::full(f64::INFINITY, (1, c), &Device::Cpu)
            .unwrap()
            .to_dtype(values.dtype())
            .unwrap();
        Tensor::cat(&[values, &empty], 0)
            .unwrap()
            .index_select(slots.indices(), 0)
            .unwrap()
            .reshape((n, slots.width(), c))
            .unwrap()
            .min(D::Minus2)
            .and_then(|least| values - least)
            .unwrap()
    }

    #[test]
    fn equals_the_gathered_formula_with_padding_and_isolated_points() {
        let rows = [vec![1, 2, 4], vec![0], vec![], vec![4, 1], vec![3]];
        let slots = NeighbourSlots::from_rows(&rows, &Device::Cpu).unwrap();
        let values = Tensor::new(
            &[
                [0.5f32, -1.0],
                [2.0, 3.0],
                [-4.0, 0.25],
                [1.0, 1.0],
                [0.75, -2.0],
            ],
            &Device::Cpu,
        )
        .unwrap();
        let got: Vec<Vec<f32>> = neighbour_deviation_maximum(&values, slots.indices())
            .unwrap()
            .to_vec2()
            .unwrap();
        let expected: Vec<Vec<f32>> = gathered(&values, &slots).to_vec2().unwrap();
        assert_eq!(got, expected);
        // Point 0 over {1, 2, 4}: (0.5, −1) − (−4, −2); point 2 is isolated and lists itself.
        assert_eq!(got[0], vec![4.5, 1.0]);
        assert_eq!(got[2], vec![0.0, 0.0]);
    }

    #[test]
    fn many_rows_across_tasks_equal_the_gathered_formula() {
        let n = 3 * ROWS_PER_TASK + 17;
        let rows: Vec<Vec<u32>> = (0..n)
            .map(|i| {
                (1..=(i % 5) as u32)
                    .map(|d| (i as u32 * 7 + d * 13) % n as u32)
                    .collect()
            })
            .collect();
        let slots = NeighbourSlots::from_rows(&rows, &Device::Cpu).unwrap();
        let values: Vec<f32> = (0..n * 3)
            .map(|k| ((k * 2_654_435_761) % 1000) as f32 / 7.0 - 60.0)
            .collect();
        let values = Tensor::from_vec(values, (n, 3), &Device::Cpu).unwrap();
        let got: Vec<Vec<f32>> = neighbour_deviation_maximum(&values, slots.indices())
            .unwrap()
            .to_vec2()
            .unwrap();
        assert_eq!(got, gathered(&values, &slots).to_vec2::<f32>().unwrap());
    }

    #[test]
    fn gradient_matches_finite_differences() {
        let rows = [vec![1, 2, 3], vec![0, 2], vec![3], vec![0, 1, 2], vec![]];
        let slots = NeighbourSlots::from_rows(&rows, &Device::Cpu).unwrap();
        let values = Tensor::new(
            &[
                [0.1f64, -0.3, 0.7],
                [0.9, 0.2, -0.4],
                [-0.6, 0.5, 0.3],
                [0.25, -0.8, 0.45],
                [0.3, 0.6, -0.9],
            ],
            &Device::Cpu,
        )
        .unwrap();
        let weights = Tensor::arange(1f64, 16.0, &Device::Cpu)
            .unwrap()
            .reshape((5, 3))
            .unwrap();
        let worst = gradient_disagreement(&values, |x| -> crate::Result<Tensor> {
            Ok((neighbour_deviation_maximum(x, slots.indices())? * &weights)?.sum_all()?)
        })
        .unwrap();
        assert!(worst.relative_error <= 1e-6, "{worst:?}");
        assert!(worst.largest_gradient > 1.0, "{worst:?}");
    }

    #[test]
    fn mismatched_operands_are_errors() {
        let values = Tensor::zeros((3, 2), DType::F32, &Device::Cpu).unwrap();
        let slots = Tensor::new(&[0u32, 1, 2, 0], &Device::Cpu).unwrap();
        assert!(neighbour_deviation_maximum(&values, &slots).is_err());
        let float_slots = Tensor::zeros(3, DType::F32, &Device::Cpu).unwrap();
        assert!(neighbour_deviation_maximum(&values, &float_slots).is_err());
    }
}
