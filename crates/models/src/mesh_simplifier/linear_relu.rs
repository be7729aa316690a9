//! `ReLU(x Wᵀ + b)`, a linear layer and its non-linearity, with the bias and the ReLU fused
//! into one pass over the product. Unfused, candle writes the product, the biased product and
//! the rectified one: one `(N, C)` tensor more than needed per layer (256 MB for a 1M-point
//! cloud at 64 channels), written, read back and freshly faulted in. The output is
//! bit-identical to `linear.forward(x)?.relu()?`.
//!
//! The backward pass of the fused part: the gradient passes where the output is positive, to
//! the product and, summed over the rows, to the bias.

use candle_core::{CpuStorage, CustomOp2, Layout, Shape, Tensor};
use candle_nn::Linear;
use rayon::prelude::*;

use super::op_operands::{Real, contiguous};

/// The name in error messages.
const NAME: &str = "bias ReLU";

/// Rows per parallel task.
const ROWS_PER_TASK: usize = 4096;

/// `ReLU(x Wᵀ + b)` of `linear` on `x: (N, C_in)` → `(N, C_out)` (module docs). Takes `x`
/// by value: where nothing else holds it, its memory is free before the output is allocated.
pub fn linear_relu(x: Tensor, linear: &Linear) -> candle_core::Result<Tensor> {
    let product = x.matmul(&linear.weight().t()?)?;
    drop(x);
    match linear.bias() {
        Some(bias) => product.apply_op2(&bias.contiguous()?, BiasRelu),
        None => product.relu(),
    }
}

struct BiasRelu;

fn bias_relu<T: Real>(product: &[T], bias: &[T]) -> Vec<T> {
    let channels = bias.len();
    let mut out = vec![T::ZERO; product.len()];
    out.par_chunks_mut(ROWS_PER_TASK * channels)
        .zip(product.par_chunks(ROWS_PER_TASK * channels))
        .for_each(|(out, product)| {
            for (out_row, row) in out.chunks_mut(channels).zip(product.chunks(channels)) {
                // Written once: a fresh page read before it is written is first mapped to
                // the shared zero page, then copied.
                for ((o, &p), &b) in out_row.iter_mut().zip(row).zip(bias) {
                    let v = p + b;
                    *o = if v > T::ZERO { v } else { T::ZERO };
                }
            }
        });
    out
}

impl CustomOp2 for BiasRelu {
    fn name(&self) -> &'static str {
        "bias-relu"
    }

    fn cpu_fwd(
        &self,
        s1: &CpuStorage,
        l1: &Layout,
        s2: &CpuStorage,
        l2: &Layout,
    ) -> candle_core::Result<(CpuStorage, Shape)> {
        let (_, c) = l1.shape().dims2()?;
        if l2.shape().dims() != [c] {
            candle_core::bail!("{NAME}: bias {:?} for {c} channels", l2.shape());
        }
        if c == 0 {
            candle_core::bail!("{NAME}: no channels");
        }
        let out = match (s1, s2) {
            (CpuStorage::F32(p), CpuStorage::F32(b)) => CpuStorage::F32(bias_relu(
                contiguous(p, l1, NAME)?,
                contiguous(b, l2, NAME)?,
            )),
            (CpuStorage::F64(p), CpuStorage::F64(b)) => CpuStorage::F64(bias_relu(
                contiguous(p, l1, NAME)?,
                contiguous(b, l2, NAME)?,
            )),
            _ => candle_core::bail!("{NAME}: product and bias must both be f32 or f64"),
        };
        Ok((out, l1.shape().clone()))
    }

    fn bwd(
        &self,
        _product: &Tensor,
        _bias: &Tensor,
        result: &Tensor,
        grad: &Tensor,
    ) -> candle_core::Result<(Option<Tensor>, Option<Tensor>)> {
        let passed = (grad * result.gt(0.0)?.to_dtype(grad.dtype())?)?;
        let bias_grad = passed.sum(0)?;
        Ok((Some(passed), Some(bias_grad)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use candle_core::{DType, Device};
    use meshgnn_losses::losses::gradient_disagreement;

    fn layer(dtype: DType) -> Linear {
        let w: Vec<f64> = (0..12).map(|i| ((i * 7 % 11) as f64 - 5.0) * 0.3).collect();
        let weight = Tensor::from_slice(&w, (4, 3), &Device::Cpu).unwrap();
        let bias = Tensor::new(&[0.5f64, -1.0, 0.0, 2.0], &Device::Cpu).unwrap();
        Linear::new(
            weight.to_dtype(dtype).unwrap(),
            Some(bias.to_dtype(dtype).unwrap()),
        )
    }

    fn input(dtype: DType) -> Tensor {
        let x: Vec<f64> = (0..15).map(|i| ((i * 5 % 9) as f64 - 4.0) * 0.45).collect();
        Tensor::from_slice(&x, (5, 3), &Device::Cpu)
            .unwrap()
            .to_dtype(dtype)
            .unwrap()
    }

    #[test]
    fn equals_the_unfused_layer_bit_for_bit() {
        for dtype in [DType::F32, DType::F64] {
            let (x, linear) = (input(dtype), layer(dtype));
            let expected = candle_nn::Module::forward(&linear, &x)
                .unwrap()
                .relu()
                .unwrap();
            let got = linear_relu(x.clone(), &linear).unwrap();
            let values = |t: &Tensor| -> Vec<f64> {
                t.to_dtype(DType::F64)
                    .unwrap()
                    .flatten_all()
                    .unwrap()
                    .to_vec1()
                    .unwrap()
            };
            let bits = |t: &Tensor| -> Vec<u64> { values(t).iter().map(|v| v.to_bits()).collect() };
            assert_eq!(bits(&got), bits(&expected), "{dtype:?}");
            // Both signs occur, so the test sees the cut.
            let v = values(&got);
            assert!(v.contains(&0.0) && v.iter().any(|&v| v > 0.0));
        }
        let unbiased = Linear::new(layer(DType::F32).weight().clone(), None);
        let x = input(DType::F32);
        let expected = x
            .matmul(&unbiased.weight().t().unwrap())
            .unwrap()
            .relu()
            .unwrap();
        let got = linear_relu(x.clone(), &unbiased).unwrap();
        assert_eq!(
            got.to_vec2::<f32>().unwrap(),
            expected.to_vec2::<f32>().unwrap()
        );
    }

    #[test]
    fn gradients_match_finite_differences() {
        let linear = layer(DType::F64);
        let weights = Tensor::arange(1f64, 21.0, &Device::Cpu)
            .unwrap()
            .reshape((5, 4))
            .unwrap();
        let x = input(DType::F64);
        let worst = gradient_disagreement(&x, |x| -> candle_core::Result<Tensor> {
            (linear_relu(x.clone(), &linear)? * &weights)?.sum_all()
        })
        .unwrap();
        assert!(worst.relative_error <= 1e-6, "{worst:?}");
        assert!(worst.largest_gradient > 1e-3, "{worst:?}");
        // The bias gradient: the weights summed over the rows where the unit is active.
        let bias = candle_core::Var::from_tensor(linear.bias().unwrap()).unwrap();
        let with_var = Linear::new(linear.weight().clone(), Some(bias.as_tensor().clone()));
        let out = linear_relu(x.clone(), &with_var).unwrap();
        let grads = (&out * &weights)
            .unwrap()
            .sum_all()
            .unwrap()
            .backward()
            .unwrap();
        let got: Vec<f64> = grads.get(bias.as_tensor()).unwrap().to_vec1().unwrap();
        let active: Vec<Vec<f64>> = out
            .gt(0.0)
            .unwrap()
            .to_dtype(DType::F64)
            .unwrap()
            .to_vec2()
            .unwrap();
        let w: Vec<Vec<f64>> = weights.to_vec2().unwrap();
        for c in 0..4 {
            let expected: f64 = (0..5).map(|r| active[r][c] * w[r][c]).sum();
            assert!(
                (got[c] - expected).abs() < 1e-12,
                "channel {c}: {} vs {expected}",
                got[c]
            );
        }
    }

    #[test]
    fn a_bias_of_the_wrong_width_is_refused() {
        let linear = Linear::new(
            layer(DType::F32).weight().clone(),
            Some(Tensor::zeros(3, DType::F32, &Device::Cpu).unwrap()),
        );
        assert!(linear_relu(input(DType::F32), &linear).is_err());
    }
}
