//! The attention logits of eq. 6.2 as one fused operation: `l_{i,s} = q_{j(i,s)} · k_i` for
//! every neighbour slot `s` of point `i` ([`super::NeighbourSlots`]), 0 on an empty slot.
//! Gathering the queries first materialises `N·W·H` values (W is the widest extended
//! neighbourhood, often 40 or more: 0.8 GB for 100k vertices at H = 64); this reads each
//! query row in place and writes `N·W`.
//!
//! The backward pass gives `k_i` the sum over its slots and `q_j` the sum over the slots that
//! read it (through the slots reversed), each row written by one task, in a fixed order.

use candle_core::{CpuStorage, CustomOp2, Layout, Shape, Tensor};
use rayon::prelude::*;

use super::incoming_links::IncomingLinks;
use super::op_operands::{Real, contiguous, host_f64};

/// The name in error messages.
const NAME: &str = "slot dot products";

/// Points per parallel task.
const ROWS_PER_TASK: usize = 1024;

/// `slot_dot_products(query (N, H), key (N, H), slots (N·W) u32) → (N, W)` (module docs);
/// gradients reach `query` and `key`.
pub fn slot_dot_products(
    query: &Tensor,
    key: &Tensor,
    slots: &Tensor,
) -> candle_core::Result<Tensor> {
    query.contiguous()?.apply_op2(
        &key.contiguous()?,
        SlotDotProducts {
            slots: slots.contiguous()?,
        },
    )
}

struct SlotDotProducts {
    slots: Tensor,
}

impl SlotDotProducts {
    /// `(N, W, H)`, checked, and the slots on the host.
    fn operands(
        &self,
        query: &Shape,
        key: &Shape,
    ) -> candle_core::Result<(usize, usize, usize, Vec<u32>)> {
        let (n, h) = query.dims2()?;
        let slots: Vec<u32> = self.slots.to_vec1()?;
        if key.dims2()? != (n, h) || n == 0 || !slots.len().is_multiple_of(n) {
            candle_core::bail!(
                "slot dot products: query {query:?}, key {key:?}, {} slots",
                slots.len()
            );
        }
        if let Some(bad) = slots.iter().find(|&&j| j as usize > n) {
            candle_core::bail!("slot dot products: slot {bad} of {n} points");
        }
        Ok((n, slots.len() / n, h, slots))
    }
}

fn forward<T: Real>(query: &[T], key: &[T], slots: &[u32], width: usize, h: usize) -> Vec<T> {
    let n = key.len() / h.max(1);
    let mut out = vec![T::ZERO; n * width];
    if h == 0 || width == 0 {
        return out;
    }
    out.par_chunks_mut(ROWS_PER_TASK * width)
        .enumerate()
        .for_each(|(task, rows)| {
            for (offset, row) in rows.chunks_mut(width).enumerate() {
                let i = task * ROWS_PER_TASK + offset;
                let k = &key[i * h..(i + 1) * h];
                for (o, &j) in row.iter_mut().zip(&slots[i * width..(i + 1) * width]) {
                    let j = j as usize;
                    if j < n {
                        let q = &query[j * h..(j + 1) * h];
                        *o = q.iter().zip(k).fold(T::ZERO, |sum, (&a, &b)| sum + a * b);
                    }
                }
            }
        });
    out
}

impl CustomOp2 for SlotDotProducts {
    fn name(&self) -> &'static str {
        "slot-dot-products"
    }

    fn cpu_fwd(
        &self,
        s1: &CpuStorage,
        l1: &Layout,
        s2: &CpuStorage,
        l2: &Layout,
    ) -> candle_core::Result<(CpuStorage, Shape)> {
        let (n, w, h, slots) = self.operands(l1.shape(), l2.shape())?;
        let out = match (s1, s2) {
            (CpuStorage::F32(q), CpuStorage::F32(k)) => CpuStorage::F32(forward(
                contiguous(q, l1, NAME)?,
                contiguous(k, l2, NAME)?,
                &slots,
                w,
                h,
            )),
            (CpuStorage::F64(q), CpuStorage::F64(k)) => CpuStorage::F64(forward(
                contiguous(q, l1, NAME)?,
                contiguous(k, l2, NAME)?,
                &slots,
                w,
                h,
            )),
            _ => candle_core::bail!("slot dot products: operands must both be f32 or f64"),
        };
        Ok((out, Shape::from((n, w))))
    }

    fn bwd(
        &self,
        query: &Tensor,
        key: &Tensor,
        _result: &Tensor,
        grad: &Tensor,
    ) -> candle_core::Result<(Option<Tensor>, Option<Tensor>)> {
        let (n, w, h, slots) = self.operands(query.shape(), key.shape())?;
        let (q, k, g) = (host_f64(query)?, host_f64(key)?, host_f64(grad)?);
        let mut key_grad = vec![0.0; n * h];
        let mut query_grad = vec![0.0; n * h];
        if h > 0 && w > 0 {
            key_grad.par_chunks_mut(h).enumerate().for_each(|(i, row)| {
                for (s, &j) in slots[i * w..(i + 1) * w].iter().enumerate() {
                    let j = j as usize;
                    if j < n {
                        for (o, &qv) in row.iter_mut().zip(&q[j * h..(j + 1) * h]) {
                            *o += g[i * w + s] * qv;
                        }
                    }
                }
            });
            let incoming = IncomingLinks::new(&slots, n);
            query_grad
                .par_chunks_mut(h)
                .enumerate()
                .for_each(|(j, row)| {
                    for &position in incoming.of(j) {
                        let i = position as usize / w;
                        for (o, &kv) in row.iter_mut().zip(&k[i * h..(i + 1) * h]) {
                            *o += g[position as usize] * kv;
                        }
                    }
                });
        }
        let back = |values: Vec<f64>, like: &Tensor| -> candle_core::Result<Tensor> {
            Tensor::from_vec(values, (n, h), like.device())?.to_dtype(like.dtype())
        };
        Ok((Some(back(query_grad, query)?), Some(back(key_grad, key)?)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh_simplifier::NeighbourSlots;
    use candle_core::{D, DType, Device};
    use meshgnn_losses::losses::gradient_disagreement;

    fn operands() -> (Tensor, Tensor, NeighbourSlots) {
        let cpu = &Device::Cpu;
        let wave = |n: usize, a: usize, b: usize| -> Vec<f64> {
            (0..n)
                .map(|i| (((i * a + b) % 13) as f64 - 6.0) * 0.11)
                .collect()
        };
        let query = Tensor::from_vec(wave(5 * 4, 7, 2), (5, 4), cpu).unwrap();
        let key = Tensor::from_vec(wave(5 * 4, 5, 3), (5, 4), cpu).unwrap();
        let rows = [
            vec![0, 1, 2],
            vec![1, 0],
            vec![2, 4, 3, 1],
            vec![3],
            vec![4, 2],
        ];
        (query, key, NeighbourSlots::from_rows(&rows, cpu).unwrap())
    }

    #[test]
    fn equals_the_gathered_products_with_zeros_on_empty_slots() {
        let (q, k, slots) = operands();
        let (n, h) = q.dims2().unwrap();
        let padded =
            Tensor::cat(&[&q, &q.zeros_like().unwrap().narrow(0, 0, 1).unwrap()], 0).unwrap();
        let expected: Vec<Vec<f64>> = padded
            .index_select(slots.indices(), 0)
            .unwrap()
            .reshape((n, slots.width(), h))
            .unwrap()
            .broadcast_mul(&k.unsqueeze(1).unwrap())
            .unwrap()
            .sum(D::Minus1)
            .unwrap()
            .to_vec2()
            .unwrap();
        let got: Vec<Vec<f64>> = slot_dot_products(&q, &k, slots.indices())
            .unwrap()
            .to_vec2()
            .unwrap();
        for (a, b) in expected.iter().flatten().zip(got.iter().flatten()) {
            assert!((a - b).abs() <= 1e-12, "{a} vs {b}");
        }
        assert_eq!(got[3][1..], [0.0, 0.0, 0.0]);
    }

    #[test]
    fn gradients_match_finite_differences() {
        let (q, k, slots) = operands();
        let scale = Tensor::arange(1f64, 21.0, &Device::Cpu)
            .unwrap()
            .reshape((5, 4))
            .unwrap();
        let loss = |q: &Tensor, k: &Tensor| -> crate::Result<Tensor> {
            Ok((slot_dot_products(q, k, slots.indices())? * &scale)?.sum_all()?)
        };
        for worst in [
            gradient_disagreement(&q, |q| loss(q, &k)).unwrap(),
            gradient_disagreement(&k, |k| loss(&q, k)).unwrap(),
        ] {
            assert!(worst.relative_error <= 1e-6, "{worst:?}");
            assert!(worst.largest_gradient > 0.1, "{worst:?}");
        }
    }

    #[test]
    fn mismatched_operands_are_errors() {
        let (q, k, slots) = operands();
        let cpu = &Device::Cpu;
        assert!(slot_dot_products(&q, &k.narrow(0, 0, 4).unwrap(), slots.indices()).is_err());
        assert!(slot_dot_products(&q, &k, &Tensor::new(&[0u32, 1, 2], cpu).unwrap()).is_err());
        assert!(slot_dot_products(&q, &k, &Tensor::new(&[9u32; 5], cpu).unwrap()).is_err());
        let single = k.to_dtype(DType::F32).unwrap();
        assert!(slot_dot_products(&q, &single, slots.indices()).is_err());
    }
}
