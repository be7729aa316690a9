//! Test helper: compares autograd gradients with central finite differences in `f64`.

use crate::Result;
use candle_core::{Tensor, Var};

/// Asserts that the gradient of `loss(x)` w.r.t. `x` (an `F64` tensor) matches central
/// differences with step `1e-6`, within absolute-or-relative tolerance `tol`.
pub(crate) fn assert_gradient_matches<F>(x: &Tensor, loss: F, tol: f64)
where
    F: Fn(&Tensor) -> Result<Tensor>,
{
    let var = Var::from_tensor(x).unwrap();
    let value = loss(var.as_tensor()).unwrap();
    let grads = value.backward().unwrap();
    let analytic: Vec<f64> = grads
        .get(var.as_tensor())
        .unwrap()
        .flatten_all()
        .unwrap()
        .to_vec1()
        .unwrap();
    let base: Vec<f64> = x.flatten_all().unwrap().to_vec1().unwrap();
    let h = 1e-6;
    for (i, g) in analytic.iter().enumerate() {
        let eval = |delta: f64| -> f64 {
            let mut v = base.clone();
            v[i] += delta;
            let t = Tensor::from_vec(v, x.dims(), x.device()).unwrap();
            loss(&t).unwrap().to_scalar::<f64>().unwrap()
        };
        let numeric = (eval(h) - eval(-h)) / (2.0 * h);
        let err = (numeric - g).abs();
        assert!(
            err <= tol * (1.0 + numeric.abs()),
            "d loss / d x[{i}]: autograd {g}, finite differences {numeric}"
        );
    }
}
