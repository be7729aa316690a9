//! Finite-difference gradient checks: how far autograd's gradient of a scalar function is from
//! central differences. Every differentiable loss and layer of the workspace is tested with it.

use candle_core::{Tensor, Var};

/// The coordinate where autograd and central differences disagree most.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GradientDisagreement {
    /// Flat index of the coordinate in `x`.
    pub index: usize,
    /// Autograd's partial derivative there.
    pub autograd: f64,
    /// The central difference `(f(x + h) − f(x − h)) / 2h`, `h = 1e-6`.
    pub finite_difference: f64,
    /// `|autograd − finite_difference| / (1 + |finite_difference|)`: the largest over `x`.
    pub relative_error: f64,
    /// The largest `|autograd|` over `x`: a check of an all-zero gradient proves nothing.
    pub largest_gradient: f64,
}

/// Compares the gradient of the scalar `f(x)` with respect to `x` (an `F64` tensor) with
/// central differences, coordinate by coordinate; returns the worst coordinate (index 0 with
/// zero error for an empty `x`). `f` is evaluated `2·len(x) + 1` times.
///
/// ```
/// use candle_core::{Device, Tensor};
/// use meshgnn_losses::losses::gradient_disagreement;
/// let x = Tensor::new(&[0.5f64, -1.0, 2.0], &Device::Cpu)?;
/// let d = gradient_disagreement(&x, |x| (x * x)?.sum_all())?;
/// assert!(d.relative_error < 1e-8, "{d:?}");
/// assert_eq!(d.largest_gradient, 4.0); // d(x²)/dx at x = 2
/// # Ok::<(), candle_core::Error>(())
/// ```
pub fn gradient_disagreement<E>(
    x: &Tensor,
    f: impl Fn(&Tensor) -> Result<Tensor, E>,
) -> Result<GradientDisagreement, E>
where
    E: From<candle_core::Error>,
{
    let var = Var::from_tensor(x)?;
    let grads = f(var.as_tensor())?.backward()?;
    let analytic: Vec<f64> = match grads.get(var.as_tensor()) {
        Some(g) => g.flatten_all()?.to_vec1()?,
        None => vec![0.0; x.elem_count()],
    };
    let base: Vec<f64> = x.flatten_all()?.to_vec1()?;
    let h = 1e-6;
    let largest_gradient = analytic.iter().fold(0.0f64, |m, g| m.max(g.abs()));
    let mut worst = GradientDisagreement {
        index: 0,
        autograd: analytic.first().copied().unwrap_or(0.0),
        finite_difference: analytic.first().copied().unwrap_or(0.0),
        relative_error: 0.0,
        largest_gradient,
    };
    for (index, &autograd) in analytic.iter().enumerate() {
        let at = |delta: f64| -> Result<f64, E> {
            let mut v = base.clone();
            v[index] += delta;
            let shifted = Tensor::from_vec(v, x.dims(), x.device())?;
            Ok(f(&shifted)?.to_scalar::<f64>()?)
        };
        let finite_difference = (at(h)? - at(-h)?) / (2.0 * h);
        let relative_error = (autograd - finite_difference).abs() / (1.0 + finite_difference.abs());
        if relative_error > worst.relative_error {
            worst = GradientDisagreement {
                index,
                autograd,
                finite_difference,
                relative_error,
                largest_gradient,
            };
        }
    }
    Ok(worst)
}

/// Test helper: panics unless [`gradient_disagreement`] stays within `tol`.
#[cfg(test)]
pub(crate) fn assert_gradient_matches<F>(x: &Tensor, f: F, tol: f64)
where
    F: Fn(&Tensor) -> crate::Result<Tensor>,
{
    let worst = gradient_disagreement(x, f).unwrap();
    assert!(worst.relative_error <= tol, "{worst:?}");
}
