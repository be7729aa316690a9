//! Deterministic parameter initialisation: candle draws its initial weights from an unseeded
//! generator, so a model with a `seed` overwrites them, in sorted name order, with PyTorch's
//! default for linear layers (`U(−1/√fan_in, 1/√fan_in)` for weights and biases; the fan-in of
//! `x.bias` is read from `x.weight`).

use candle_core::Tensor;
use candle_nn::VarMap;
use rand::{Rng, SeedableRng, rngs::StdRng};

use crate::{Error, Result};

/// Re-initialises every variable of `vars` from `seed`: the same seed gives the same weights
/// bit for bit. Weights are `(out, fan_in)`; a bias `(out)` uses its weight's fan-in.
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
    let data = vars.data().lock().map_err(|_| Error::Invalid {
        what: "model variables".into(),
        reason: "lock poisoned by a panic in another thread".into(),
    })?;
    let mut names: Vec<&String> = data.keys().collect();
    names.sort();
    let mut rng = StdRng::seed_from_u64(seed);
    for name in names {
        let Some(var) = data.get(name) else { continue };
        let dims = var.dims().to_vec();
        let fan_in = match dims.as_slice() {
            [_, fan_in] => *fan_in,
            _ => name
                .strip_suffix("bias")
                .and_then(|stem| data.get(&format!("{stem}weight")))
                .and_then(|w| w.dims().get(1).copied())
                .unwrap_or(1),
        };
        let bound = 1.0 / (fan_in.max(1) as f32).sqrt();
        let values: Vec<f32> = (0..var.elem_count())
            .map(|_| rng.random_range(-bound..=bound))
            .collect();
        let tensor =
            Tensor::from_vec(values, dims.as_slice(), var.device())?.to_dtype(var.dtype())?;
        var.set(&tensor)?;
    }
    Ok(())
}
