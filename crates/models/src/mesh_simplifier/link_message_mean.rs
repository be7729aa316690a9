//! The inner sum of TriConv (eq. 6.7) as one fused operation:
//! `m_n = 1/K Σ_k ReLU(q_n − q_{l(n,k)} + b)`, where `l(n, k)` is the `k`-th link of triangle
//! `n`, `b` the first MLP layer's bias and `q_n = W [d_n ‖ f_n]` the layer's weights applied
//! once per triangle to its eq. 6.6 descriptor and features (the layer's input on a link,
//! `[d_n − d_m ‖ f_n − f_m]`, is a difference, and the layer is linear in it). Computed with
//! tensor operations, every link's `C`-channel hidden vector is materialised several times
//! over (`F·K·C`: 100M values for 40k candidates at K = 20 and 128 channels); here each lives
//! in one small buffer while its link is summed, and only `F·C` values are written.
//!
//! The backward pass recomputes the hidden vectors instead of keeping them: first per
//! triangle (its own `q_n` and `b`), then per linked triangle through the reversed links
//! (`−q_l`), so that each pass writes only rows it owns and runs in parallel.

use candle_core::{CpuStorage, CustomOp2, Layout, Shape, Tensor};
use rayon::prelude::*;

use super::incoming_links::IncomingLinks;
use super::op_operands::{Real, contiguous, host_f64};

/// The name in error messages.
const NAME: &str = "link message mean";

/// Triangles per parallel task.
const ROWS_PER_TASK: usize = 256;

/// `link_message_mean(values (F, C), bias (C), links (F·K) u32) → (F, C)` (module docs);
/// gradients reach `values` and `bias`.
pub fn link_message_mean(
    values: &Tensor,
    bias: &Tensor,
    links: &Tensor,
) -> candle_core::Result<Tensor> {
    values.contiguous()?.apply_op2(
        &bias.contiguous()?,
        LinkMessageMean {
            links: links.contiguous()?,
        },
    )
}

struct LinkMessageMean {
    links: Tensor,
}

/// The sizes of one call: triangles, links per triangle, channels.
#[derive(Clone, Copy)]
struct Sizes {
    f: usize,
    k: usize,
    c: usize,
}

/// The operands of one call, on the host.
struct Operands<'a, T> {
    values: &'a [T],
    bias: &'a [T],
    links: &'a [u32],
    sizes: Sizes,
}

impl<T: Real> Operands<'_, T> {
    /// The hidden vector of link `(n, slot)` before the ReLU, into `hidden`.
    fn hidden(&self, n: usize, slot: usize, hidden: &mut [T]) {
        let c = self.sizes.c;
        let other = self.links[n * self.sizes.k + slot] as usize;
        let own = &self.values[n * c..(n + 1) * c];
        let theirs = &self.values[other * c..(other + 1) * c];
        for (h, ((&b, &p), &q)) in hidden.iter_mut().zip(self.bias.iter().zip(own).zip(theirs)) {
            *h = p - q + b;
        }
    }
}

fn forward<T: Real>(operands: &Operands<T>) -> Vec<T> {
    let sizes = operands.sizes;
    let Sizes { k, c, .. } = sizes;
    let mut out = vec![T::ZERO; sizes.f * c];
    if c == 0 || k == 0 {
        return out;
    }
    let count = T::from_count(k);
    out.par_chunks_mut(ROWS_PER_TASK * c)
        .enumerate()
        .for_each(|(task, rows)| {
            let mut hidden = vec![T::ZERO; c];
            // Summed here and written once: a fresh output page that is read before it is
            // written is first mapped to the shared zero page, then copied on the write,
            // with a TLB flush on every core.
            let mut sum = vec![T::ZERO; c];
            for (offset, row) in rows.chunks_mut(c).enumerate() {
                let n = task * ROWS_PER_TASK + offset;
                sum.fill(T::ZERO);
                for slot in 0..k {
                    operands.hidden(n, slot, &mut hidden);
                    for (s, &h) in sum.iter_mut().zip(&hidden) {
                        *s += if h > T::ZERO { h } else { T::ZERO };
                    }
                }
                for (o, &s) in row.iter_mut().zip(&sum) {
                    *o = s / count;
                }
            }
        });
    out
}

impl LinkMessageMean {
    /// The sizes of the operands' shapes, checked against each other and the links.
    fn sizes(&self, values: &Shape, bias: &Shape) -> candle_core::Result<Sizes> {
        let (f, c) = values.dims2()?;
        let links = self.links.dims1()?;
        if bias.elem_count() != c || f == 0 || !links.is_multiple_of(f) {
            candle_core::bail!("{NAME}: values {values:?}, bias {bias:?}, {links} links");
        }
        Ok(Sizes { f, k: links / f, c })
    }

    /// The links on the host, each checked to name a triangle.
    fn link_list(&self, sizes: Sizes) -> candle_core::Result<Vec<u32>> {
        let links: Vec<u32> = self.links.to_vec1()?;
        if let Some(bad) = links.iter().find(|&&l| l as usize >= sizes.f) {
            candle_core::bail!("{NAME}: link to {bad} of {} triangles", sizes.f);
        }
        Ok(links)
    }
}

impl CustomOp2 for LinkMessageMean {
    fn name(&self) -> &'static str {
        "link-message-mean"
    }

    fn cpu_fwd(
        &self,
        s1: &CpuStorage,
        l1: &Layout,
        s2: &CpuStorage,
        l2: &Layout,
    ) -> candle_core::Result<(CpuStorage, Shape)> {
        let sizes = self.sizes(l1.shape(), l2.shape())?;
        let links = self.link_list(sizes)?;
        let out = match (s1, s2) {
            (CpuStorage::F32(v), CpuStorage::F32(b)) => CpuStorage::F32(forward(&Operands {
                values: contiguous(v, l1, NAME)?,
                bias: contiguous(b, l2, NAME)?,
                links: &links,
                sizes,
            })),
            (CpuStorage::F64(v), CpuStorage::F64(b)) => CpuStorage::F64(forward(&Operands {
                values: contiguous(v, l1, NAME)?,
                bias: contiguous(b, l2, NAME)?,
                links: &links,
                sizes,
            })),
            _ => candle_core::bail!("{NAME}: operands must both be f32 or both f64"),
        };
        Ok((out, Shape::from((sizes.f, sizes.c))))
    }

    fn bwd(
        &self,
        values: &Tensor,
        bias: &Tensor,
        _result: &Tensor,
        grad: &Tensor,
    ) -> candle_core::Result<(Option<Tensor>, Option<Tensor>)> {
        let sizes = self.sizes(values.shape(), bias.shape())?;
        let links = self.link_list(sizes)?;
        let (v, b, g) = (host_f64(values)?, host_f64(bias)?, host_f64(grad)?);
        let operands = Operands {
            values: &v,
            bias: &b,
            links: &links,
            sizes,
        };
        let (values_grad, bias_grad) = backward(&operands, &g);
        let values_grad = Tensor::from_vec(values_grad, values.shape(), values.device())?;
        let bias_grad = Tensor::from_vec(bias_grad, bias.shape(), bias.device())?;
        Ok((
            Some(values_grad.to_dtype(values.dtype())?),
            Some(bias_grad.to_dtype(bias.dtype())?),
        ))
    }
}

/// The gradients of `values` and `bias` for the output gradient `grad` (module docs).
fn backward(operands: &Operands<f64>, grad: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let Sizes { f, k, c } = operands.sizes;
    let mut values_grad = vec![0.0; f * c];
    if c == 0 || k == 0 {
        return (values_grad, vec![0.0; c]);
    }
    let scale = 1.0 / k as f64;
    // The gradient reaching link (n, slot)'s hidden vector: g_n / K where it passed the ReLU.
    let link_grad = |n: usize, slot: usize, hidden: &mut [f64]| {
        operands.hidden(n, slot, hidden);
        for (h, &gn) in hidden.iter_mut().zip(&grad[n * c..(n + 1) * c]) {
            *h = if *h > 0.0 { gn * scale } else { 0.0 };
        }
    };
    // Per triangle: its own row, and partial sums for the bias, kept per task and added in
    // task order (deterministic).
    let partials: Vec<Vec<f64>> = values_grad
        .par_chunks_mut(ROWS_PER_TASK * c)
        .enumerate()
        .map(|(task, rows)| {
            let mut bias_grad = vec![0.0; c];
            let mut hidden = vec![0.0; c];
            for (offset, row) in rows.chunks_mut(c).enumerate() {
                let n = task * ROWS_PER_TASK + offset;
                for slot in 0..k {
                    link_grad(n, slot, &mut hidden);
                    for ((bg, o), &h) in bias_grad.iter_mut().zip(row.iter_mut()).zip(&hidden) {
                        *bg += h;
                        *o += h;
                    }
                }
            }
            bias_grad
        })
        .collect();
    let mut bias_grad = vec![0.0; c];
    for partial in partials {
        for (total, part) in bias_grad.iter_mut().zip(partial) {
            *total += part;
        }
    }
    // Per linked triangle: `−q_l` through the links reversed.
    let incoming = IncomingLinks::new(operands.links, f);
    values_grad
        .par_chunks_mut(ROWS_PER_TASK * c)
        .enumerate()
        .for_each(|(task, rows)| {
            let mut hidden = vec![0.0; c];
            for (offset, row) in rows.chunks_mut(c).enumerate() {
                let j = task * ROWS_PER_TASK + offset;
                for &link in incoming.of(j) {
                    let link = link as usize;
                    link_grad(link / k, link % k, &mut hidden);
                    for (o, &h) in row.iter_mut().zip(&hidden) {
                        *o -= h;
                    }
                }
            }
        });
    (values_grad, bias_grad)
}

#[cfg(test)]
mod tests {
    use super::*;
    use candle_core::{D, DType, Device};
    use meshgnn_losses::losses::gradient_disagreement;

    /// Four triangles with three links each, channels 5, in `f64`.
    fn operands() -> (Tensor, Tensor, Tensor) {
        let cpu = &Device::Cpu;
        // Incommensurate values, so that no hidden value sits on the ReLU's kink.
        let wave = |n: usize, a: f64, b: f64| -> Vec<f64> {
            (0..n).map(|i| (i as f64 * a + b).sin()).collect()
        };
        let values = Tensor::from_vec(wave(4 * 5, 1.7, 0.3), (4, 5), cpu).unwrap();
        let bias = Tensor::from_vec(wave(5, 2.3, 0.9), 5, cpu).unwrap();
        let links = Tensor::new(&[1u32, 2, 3, 0, 2, 3, 3, 0, 1, 2, 1, 0], cpu).unwrap();
        (values, bias, links)
    }

    /// The formula with tensor operations, every link's hidden vector materialised.
    fn materialised(values: &Tensor, bias: &Tensor, links: &Tensor) -> Tensor {
        let (f, c) = values.dims2().unwrap();
        let k = links.dims1().unwrap() / f;
        let own = values
            .unsqueeze(1)
            .unwrap()
            .broadcast_as((f, k, c))
            .unwrap();
        let theirs = values
            .index_select(links, 0)
            .unwrap()
            .reshape((f, k, c))
            .unwrap();
        (own - theirs)
            .unwrap()
            .broadcast_add(bias)
            .unwrap()
            .relu()
            .unwrap()
            .mean(D::Minus2)
            .unwrap()
    }

    #[test]
    fn equals_the_materialised_formula_in_both_widths() {
        let (v, b, l) = operands();
        let expected: Vec<Vec<f64>> = materialised(&v, &b, &l).to_vec2().unwrap();
        let got: Vec<Vec<f64>> = link_message_mean(&v, &b, &l).unwrap().to_vec2().unwrap();
        for (a, b) in expected.iter().flatten().zip(got.iter().flatten()) {
            assert!((a - b).abs() <= 1e-12, "{a} vs {b}");
        }
        // Some links pass the ReLU and some do not, so both branches are exercised.
        assert!(got.iter().flatten().any(|&v| v > 0.0));
        let single = |t: &Tensor| t.to_dtype(DType::F32).unwrap();
        let got32: Vec<Vec<f32>> = link_message_mean(&single(&v), &single(&b), &l)
            .unwrap()
            .to_vec2()
            .unwrap();
        for (a, b) in expected.iter().flatten().zip(got32.iter().flatten()) {
            assert!((a - f64::from(*b)).abs() <= 1e-6, "{a} vs {b}");
        }
    }

    #[test]
    fn gradients_match_finite_differences() {
        let (v, b, l) = operands();
        let scale = Tensor::arange(1f64, 21.0, &Device::Cpu)
            .unwrap()
            .reshape((4, 5))
            .unwrap();
        let loss = |v: &Tensor, b: &Tensor| -> crate::Result<Tensor> {
            Ok((link_message_mean(v, b, &l)? * &scale)?.sum_all()?)
        };
        for worst in [
            gradient_disagreement(&v, |v| loss(v, &b)).unwrap(),
            gradient_disagreement(&b, |b| loss(&v, b)).unwrap(),
        ] {
            assert!(worst.relative_error <= 1e-6, "{worst:?}");
            assert!(worst.largest_gradient > 0.1, "{worst:?}");
        }
    }

    #[test]
    fn mismatched_operands_are_errors() {
        let (v, b, l) = operands();
        let cpu = &Device::Cpu;
        let short = Tensor::new(&[0u32, 1, 2], cpu).unwrap();
        assert!(link_message_mean(&v, &b, &short).is_err());
        let outside = Tensor::new(&[9u32; 12], cpu).unwrap();
        assert!(link_message_mean(&v, &b, &outside).is_err());
        assert!(link_message_mean(&v, &b.narrow(0, 0, 4).unwrap(), &l).is_err());
        let mixed = b.to_dtype(DType::F32).unwrap();
        assert!(link_message_mean(&v, &mixed, &l).is_err());
    }
}
