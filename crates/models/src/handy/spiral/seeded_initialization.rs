//! Deterministic parameter initialisation, the one every model of this crate uses: candle
//! draws its initial weights from an unseeded generator, so a model with a `seed` overwrites
//! them, in sorted name order, with PyTorch's default for linear layers
//! (`kaiming_uniform_(a = √5)`, whose bound `gain·√(3/fan_in)` with `gain = √(2/(1 + a²))` is
//! `1/√fan_in`, drawn from the half-open `U[−1/√fan_in, 1/√fan_in)` as `torch.nn.init.uniform_`
//! does, for weights and biases; the fan-in of `x.bias` is read from `x.weight`). Variables that
//! are not a linear layer's `weight (out, fan_in)` or its `bias` (batch-norm scale and shift)
//! keep their constructor values. Recurrent layers in PyTorch's naming (`weight_ih_l0`,
//! `weight_hh_l0`, `bias_ih_l0`, `bias_hh_l0` of an LSTM) get PyTorch's `U[−1/√H, 1/√H)` for
//! all four, `H` the hidden size (`weight_hh_l0`'s second dimension).

use candle_core::Tensor;
use candle_nn::VarMap;
use rand::{Rng, SeedableRng, rngs::StdRng};

use crate::Result;

/// Re-initialises every linear weight and bias of `vars` from `seed`: the same seed gives the
/// same weights bit for bit. Weights are `(out, fan_in)`; a bias `(out)` uses its weight's
/// fan-in; other variables are left as they are.
///
/// ```
/// use candle_core::{DType, Device};
/// use candle_nn::{VarBuilder, VarMap};
/// use meshgnn_models::spiral::seeded_initialization;
/// let vars = VarMap::new();
/// let vb = VarBuilder::from_varmap(&vars, DType::F32, &Device::Cpu);
/// let layer = candle_nn::linear(4, 2, vb.pp("fc"))?;
/// seeded_initialization(&vars, 7)?;
/// let w = layer.weight().flatten_all()?.to_vec1::<f32>()?;
/// assert!(w.iter().all(|x| x.abs() <= 0.5)); // 1/√4
/// seeded_initialization(&vars, 7)?;
/// assert_eq!(layer.weight().flatten_all()?.to_vec1::<f32>()?, w);
/// # Ok::<(), meshgnn_models::Error>(())
/// ```
pub fn seeded_initialization(vars: &VarMap, seed: u64) -> Result<()> {
    let data = crate::checkpoint::lock(vars)?;
    let mut names: Vec<&String> = data.keys().collect();
    names.sort();
    let mut rng = StdRng::seed_from_u64(seed);
    for name in names {
        let Some(var) = data.get(name) else { continue };
        let weight = match recurrent_stem(name) {
            Some((stem, layer)) => data.get(&format!("{stem}weight_hh_{layer}")),
            None => name
                .strip_suffix(".bias")
                .or(name.strip_suffix(".weight"))
                .and_then(|stem| data.get(&format!("{stem}.weight"))),
        };
        let Some(&[_, fan_in]) = weight.map(|w| w.dims()) else {
            continue;
        };
        let bound = 1.0 / (fan_in.max(1) as f64).sqrt();
        let values: Vec<f32> = (0..var.elem_count())
            .map(|_| rng.random_range(-bound..bound) as f32)
            .collect();
        let tensor = Tensor::from_vec(values, var.dims(), var.device())?.to_dtype(var.dtype())?;
        var.set(&tensor)?;
    }
    Ok(())
}

/// `(prefix, "l0")` of a recurrent layer's parameter `prefix{weight,bias}_{ih,hh}_l0`.
fn recurrent_stem(name: &str) -> Option<(&str, &str)> {
    let (head, layer) = name.rsplit_once('_')?;
    let stem = ["weight_ih", "weight_hh", "bias_ih", "bias_hh"]
        .iter()
        .find_map(|kind| head.strip_suffix(kind))?;
    layer.starts_with('l').then_some((stem, layer))
}
