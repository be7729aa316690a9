//! The inner sum of TriConv (eq. 6.7) as one fused operation:
//! `m_n = 1/K Σ_k ReLU(r_{n,k} W + b + p_n − p_{l(n,k)})`, where `r` is the eq. 6.6 encoding
//! of each link, `W` the first MLP layer's columns for it, `p = W_f f` the projected triangle
//! features and `l(n, k)` the `k`-th link of triangle `n`. Computed with tensor operations,
//! every link's `C`-channel hidden vector is materialised several times over (`F·K·C`: 100M
//! values for 40k candidates at K = 20 and 128 channels); here each lives in one small buffer
//! while its link is summed, and only `F·C` values are written.
//!
//! `weight` stacks `W` (9 rows) over `b` (one row), so that one operand carries both and their
//! gradients. The backward pass recomputes the hidden vectors instead of keeping them: first
//! per triangle (its own `p_n`, `W` and `b`), then per linked triangle through the reversed
//! links (`−p_l`), so that each pass writes only rows it owns and runs in parallel.

use candle_core::{CpuStorage, CustomOp3, Layout, Shape, Tensor};
use rayon::prelude::*;

use super::incoming_links::IncomingLinks;
use super::op_operands::{contiguous, host_f64};

/// The name in error messages.
const NAME: &str = "link message mean";

/// Relative-position channels of a link (eq. 6.6).
const RELATIVE: usize = 9;

/// Triangles per parallel task.
const ROWS_PER_TASK: usize = 256;

/// `link_message_mean(relative (F·K, 9), weight (10, C), projected (F, C), links (F·K) u32)
/// → (F, C)` (module docs); gradients reach `weight` and `projected`.
pub fn link_message_mean(
    relative: &Tensor,
    weight: &Tensor,
    projected: &Tensor,
    links: &Tensor,
) -> candle_core::Result<Tensor> {
    relative.contiguous()?.apply_op3(
        &weight.contiguous()?,
        &projected.contiguous()?,
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

/// The arithmetic both float widths need.
trait Real:
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

/// The operands of one call, on the host.
struct Operands<'a, T> {
    relative: &'a [T],
    weight: &'a [T],
    projected: &'a [T],
    links: &'a [u32],
    sizes: Sizes,
}

impl<T: Real> Operands<'_, T> {
    /// The hidden vector of link `(n, slot)` before the ReLU, into `hidden`.
    fn hidden(&self, n: usize, slot: usize, hidden: &mut [T]) {
        let c = self.sizes.c;
        let link = n * self.sizes.k + slot;
        let other = self.links[link] as usize;
        let own = &self.projected[n * c..(n + 1) * c];
        let theirs = &self.projected[other * c..(other + 1) * c];
        let bias = &self.weight[RELATIVE * c..(RELATIVE + 1) * c];
        for (h, ((&b, &p), &q)) in hidden.iter_mut().zip(bias.iter().zip(own).zip(theirs)) {
            *h = b + p - q;
        }
        let encoding = &self.relative[link * RELATIVE..(link + 1) * RELATIVE];
        for (d, &r) in encoding.iter().enumerate() {
            for (h, &w) in hidden.iter_mut().zip(&self.weight[d * c..(d + 1) * c]) {
                *h += r * w;
            }
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
            for (offset, row) in rows.chunks_mut(c).enumerate() {
                let n = task * ROWS_PER_TASK + offset;
                for slot in 0..k {
                    operands.hidden(n, slot, &mut hidden);
                    for (o, &h) in row.iter_mut().zip(&hidden) {
                        *o += if h > T::ZERO { h } else { T::ZERO };
                    }
                }
                for o in row.iter_mut() {
                    *o = *o / count;
                }
            }
        });
    out
}

impl LinkMessageMean {
    /// The sizes of the operands' shapes, checked against each other and the links.
    fn sizes(
        &self,
        relative: &Shape,
        weight: &Shape,
        projected: &Shape,
    ) -> candle_core::Result<Sizes> {
        let (links, r) = relative.dims2()?;
        let (w, c) = weight.dims2()?;
        let (f, pc) = projected.dims2()?;
        if r != RELATIVE || w != RELATIVE + 1 || pc != c || self.links.dims1()? != links {
            candle_core::bail!(
                "link message mean: relative {relative:?}, weight {weight:?}, projected \
                 {projected:?}, {:?} links",
                self.links.dims()
            );
        }
        if f == 0 || !links.is_multiple_of(f) {
            candle_core::bail!("link message mean: {links} links for {f} triangles");
        }
        Ok(Sizes { f, k: links / f, c })
    }

    /// The links on the host, each checked to name a triangle.
    fn link_list(&self, sizes: Sizes) -> candle_core::Result<Vec<u32>> {
        let links: Vec<u32> = self.links.to_vec1()?;
        if let Some(bad) = links.iter().find(|&&l| l as usize >= sizes.f) {
            candle_core::bail!("link message mean: link to {bad} of {} triangles", sizes.f);
        }
        Ok(links)
    }
}

impl CustomOp3 for LinkMessageMean {
    fn name(&self) -> &'static str {
        "link-message-mean"
    }

    fn cpu_fwd(
        &self,
        s1: &CpuStorage,
        l1: &Layout,
        s2: &CpuStorage,
        l2: &Layout,
        s3: &CpuStorage,
        l3: &Layout,
    ) -> candle_core::Result<(CpuStorage, Shape)> {
        let sizes = self.sizes(l1.shape(), l2.shape(), l3.shape())?;
        let links = self.link_list(sizes)?;
        let out = match (s1, s2, s3) {
            (CpuStorage::F32(r), CpuStorage::F32(w), CpuStorage::F32(p)) => {
                CpuStorage::F32(forward(&Operands {
                    relative: contiguous(r, l1, NAME)?,
                    weight: contiguous(w, l2, NAME)?,
                    projected: contiguous(p, l3, NAME)?,
                    links: &links,
                    sizes,
                }))
            }
            (CpuStorage::F64(r), CpuStorage::F64(w), CpuStorage::F64(p)) => {
                CpuStorage::F64(forward(&Operands {
                    relative: contiguous(r, l1, NAME)?,
                    weight: contiguous(w, l2, NAME)?,
                    projected: contiguous(p, l3, NAME)?,
                    links: &links,
                    sizes,
                }))
            }
            _ => candle_core::bail!("link message mean: operands must all be f32 or all f64"),
        };
        Ok((out, Shape::from((sizes.f, sizes.c))))
    }

    fn bwd(
        &self,
        relative: &Tensor,
        weight: &Tensor,
        projected: &Tensor,
        _result: &Tensor,
        grad: &Tensor,
    ) -> candle_core::Result<(Option<Tensor>, Option<Tensor>, Option<Tensor>)> {
        let sizes = self.sizes(relative.shape(), weight.shape(), projected.shape())?;
        let links = self.link_list(sizes)?;
        let (r, w, p, g) = (
            host_f64(relative)?,
            host_f64(weight)?,
            host_f64(projected)?,
            host_f64(grad)?,
        );
        let operands = Operands {
            relative: &r,
            weight: &w,
            projected: &p,
            links: &links,
            sizes,
        };
        let (weight_grad, projected_grad) = backward(&operands, &g);
        let weight_grad = Tensor::from_vec(weight_grad, weight.shape(), weight.device())?;
        let projected_grad =
            Tensor::from_vec(projected_grad, projected.shape(), projected.device())?;
        Ok((
            None,
            Some(weight_grad.to_dtype(weight.dtype())?),
            Some(projected_grad.to_dtype(projected.dtype())?),
        ))
    }
}

/// The gradients of `weight` and `projected` for the output gradient `grad` (module docs).
fn backward(operands: &Operands<f64>, grad: &[f64]) -> (Vec<f64>, Vec<f64>) {
    let Sizes { f, k, c } = operands.sizes;
    let (relative, links) = (operands.relative, operands.links);
    let scale = 1.0 / k as f64;
    // The gradient reaching link (n, slot)'s hidden vector: g_n / K where it passed the ReLU.
    let link_grad = |n: usize, slot: usize, hidden: &mut [f64]| {
        operands.hidden(n, slot, hidden);
        for (h, &gn) in hidden.iter_mut().zip(&grad[n * c..(n + 1) * c]) {
            *h = if *h > 0.0 { gn * scale } else { 0.0 };
        }
    };
    let mut projected_grad = vec![0.0; f * c];
    if c == 0 || k == 0 {
        return (vec![0.0; (RELATIVE + 1) * c], projected_grad);
    }
    // Per triangle: its own row of `projected`, and partial sums for `weight`, kept per task
    // and added in task order (deterministic).
    let partials: Vec<Vec<f64>> = projected_grad
        .par_chunks_mut(ROWS_PER_TASK * c)
        .enumerate()
        .map(|(task, rows)| {
            let mut weight_grad = vec![0.0; (RELATIVE + 1) * c];
            let mut hidden = vec![0.0; c];
            for (offset, row) in rows.chunks_mut(c).enumerate() {
                let n = task * ROWS_PER_TASK + offset;
                for slot in 0..k {
                    link_grad(n, slot, &mut hidden);
                    let link = n * k + slot;
                    for (d, &r) in relative[link * RELATIVE..(link + 1) * RELATIVE]
                        .iter()
                        .enumerate()
                    {
                        for (wg, &h) in weight_grad[d * c..(d + 1) * c].iter_mut().zip(&hidden) {
                            *wg += r * h;
                        }
                    }
                    for ((wg, o), &h) in weight_grad[RELATIVE * c..]
                        .iter_mut()
                        .zip(row.iter_mut())
                        .zip(&hidden)
                    {
                        *wg += h;
                        *o += h;
                    }
                }
            }
            weight_grad
        })
        .collect();
    let mut weight_grad = vec![0.0; (RELATIVE + 1) * c];
    for partial in partials {
        for (total, part) in weight_grad.iter_mut().zip(partial) {
            *total += part;
        }
    }
    // Per linked triangle: `−p_l` through the links reversed.
    let incoming = IncomingLinks::new(links, f);
    projected_grad
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
    (weight_grad, projected_grad)
}

#[cfg(test)]
mod tests {
    use super::*;
    use candle_core::{D, DType, Device};
    use meshgnn_losses::losses::gradient_disagreement;

    /// Four triangles with three links each, channels 5, in `f64`.
    fn operands() -> (Tensor, Tensor, Tensor, Tensor) {
        let cpu = &Device::Cpu;
        let wave = |n: usize, a: usize, b: usize| -> Vec<f64> {
            (0..n)
                .map(|i| (((i * a + b) % 11) as f64 - 5.0) * 0.13)
                .collect()
        };
        let relative = Tensor::from_vec(wave(12 * 9, 7, 3), (12, 9), cpu).unwrap();
        let weight = Tensor::from_vec(wave(10 * 5, 5, 1), (10, 5), cpu).unwrap();
        let projected = Tensor::from_vec(wave(4 * 5, 3, 2), (4, 5), cpu).unwrap();
        let links = Tensor::new(&[1u32, 2, 3, 0, 2, 3, 3, 0, 1, 2, 1, 0], cpu).unwrap();
        (relative, weight, projected, links)
    }

    /// The formula with tensor operations, every link's hidden vector materialised.
    fn materialised(
        relative: &Tensor,
        weight: &Tensor,
        projected: &Tensor,
        links: &Tensor,
    ) -> Tensor {
        let (f, c) = projected.dims2().unwrap();
        let k = links.dims1().unwrap() / f;
        let w = weight.narrow(0, 0, 9).unwrap();
        let b = weight.narrow(0, 9, 1).unwrap();
        let own = projected
            .unsqueeze(1)
            .unwrap()
            .broadcast_as((f, k, c))
            .unwrap();
        let theirs = projected
            .index_select(links, 0)
            .unwrap()
            .reshape((f, k, c))
            .unwrap();
        let hidden = relative
            .matmul(&w)
            .unwrap()
            .broadcast_add(&b)
            .unwrap()
            .reshape((f, k, c))
            .unwrap()
            .add(&own)
            .unwrap()
            .sub(&theirs)
            .unwrap();
        hidden.relu().unwrap().mean(D::Minus2).unwrap()
    }

    #[test]
    fn equals_the_materialised_formula_in_both_widths() {
        let (r, w, p, l) = operands();
        let expected: Vec<Vec<f64>> = materialised(&r, &w, &p, &l).to_vec2().unwrap();
        let got: Vec<Vec<f64>> = link_message_mean(&r, &w, &p, &l)
            .unwrap()
            .to_vec2()
            .unwrap();
        for (a, b) in expected.iter().flatten().zip(got.iter().flatten()) {
            assert!((a - b).abs() <= 1e-12, "{a} vs {b}");
        }
        // Some links pass the ReLU and some do not, so both branches are exercised.
        assert!(got.iter().flatten().any(|&v| v > 0.0));
        let single = |t: &Tensor| t.to_dtype(DType::F32).unwrap();
        let got32: Vec<Vec<f32>> = link_message_mean(&single(&r), &single(&w), &single(&p), &l)
            .unwrap()
            .to_vec2()
            .unwrap();
        for (a, b) in expected.iter().flatten().zip(got32.iter().flatten()) {
            assert!((a - f64::from(*b)).abs() <= 1e-5, "{a} vs {b}");
        }
    }

    #[test]
    fn gradients_match_finite_differences() {
        let (r, w, p, l) = operands();
        let scale = Tensor::arange(1f64, 21.0, &Device::Cpu)
            .unwrap()
            .reshape((4, 5))
            .unwrap();
        let loss = |w: &Tensor, p: &Tensor| -> crate::Result<Tensor> {
            Ok((link_message_mean(&r, w, p, &l)? * &scale)?.sum_all()?)
        };
        for worst in [
            gradient_disagreement(&w, |w| loss(w, &p)).unwrap(),
            gradient_disagreement(&p, |p| loss(&w, p)).unwrap(),
        ] {
            assert!(worst.relative_error <= 1e-6, "{worst:?}");
            assert!(worst.largest_gradient > 0.1, "{worst:?}");
        }
    }

    #[test]
    fn mismatched_operands_are_errors() {
        let (r, w, p, l) = operands();
        let cpu = &Device::Cpu;
        let short = Tensor::new(&[0u32, 1, 2], cpu).unwrap();
        assert!(link_message_mean(&r, &w, &p, &short).is_err());
        let outside = Tensor::new(&[9u32; 12], cpu).unwrap();
        assert!(link_message_mean(&r, &w, &p, &outside).is_err());
        assert!(link_message_mean(&r, &w.narrow(0, 0, 9).unwrap(), &p, &l).is_err());
        let mixed = p.to_dtype(DType::F32).unwrap();
        assert!(link_message_mean(&r, &w, &mixed, &l).is_err());
    }
}
