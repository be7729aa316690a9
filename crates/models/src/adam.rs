//! Adam (Kingma & Ba, "Adam: A Method for Stochastic Optimization", ICLR 2015), the optimiser
//! of every trainer in this crate (thesis ch. 3.3.4 and 5.6), with its moment estimates exposed
//! as named tensors so a checkpoint holds them and a resumed run continues bit-exactly.
//!
//! # Conventions
//! - Step `t` (1-based): `g ← ∇θ + λθ` (weight decay `λ`, PyTorch's `Adam(weight_decay=λ)`,
//!   the thesis' ch. 4 setting), `m ← β₁m + (1−β₁)g`, `v ← β₂v + (1−β₂)g²`,
//!   `θ ← θ − lr · (m / (1−β₁ᵗ)) / (√(v / (1−β₂ᵗ)) + ε)`.
//! - Parameters are kept in the order given (callers pass them sorted by name); a parameter
//!   without a gradient is left unchanged, its moments too.
//! - State tensors are named `<prefix>m.<name>` and `<prefix>v.<name>`; the step count is not a
//!   tensor: callers store it with their training position and pass it back to
//!   [`Adam::restore`].

use std::collections::HashMap;

use candle_core::backprop::GradStore;
use candle_core::{Tensor, Var};
use candle_nn::VarMap;

use crate::{Error, Result};

/// Adam hyper-parameters; defaults are the paper's (lr 1e-3, β = (0.9, 0.999), ε = 1e-8).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdamConfig {
    /// Step size `lr`.
    pub learning_rate: f64,
    /// Decay of the first-moment estimate `β₁`.
    pub beta1: f64,
    /// Decay of the second-moment estimate `β₂`.
    pub beta2: f64,
    /// Denominator guard `ε`.
    pub epsilon: f64,
    /// Weight decay `λ` added to every gradient as `λθ`. Default 0.
    pub weight_decay: f64,
}

impl Default for AdamConfig {
    fn default() -> Self {
        Self {
            learning_rate: 1e-3,
            beta1: 0.9,
            beta2: 0.999,
            epsilon: 1e-8,
            weight_decay: 0.0,
        }
    }
}

/// Adam over named parameters, with its state (moments and step count) saveable.
#[derive(Debug)]
pub struct Adam {
    config: AdamConfig,
    names: Vec<String>,
    vars: Vec<Var>,
    first_moments: Vec<Tensor>,
    second_moments: Vec<Tensor>,
    steps: u64,
}

impl Adam {
    /// Adam over `params: [(name, var)]` with zero moments and step 0. Errors when the config
    /// is not `lr > 0, 0 ≤ β < 1, ε > 0, λ ≥ 0` (all finite) or a name repeats.
    ///
    /// ```
    /// use candle_core::{Device, Tensor, Var};
    /// use meshgnn_models::{Adam, AdamConfig};
    /// let x = Var::new(&[1.0f32], &Device::Cpu)?;
    /// let mut adam = Adam::new(vec![("x".into(), x.clone())], AdamConfig::default())?;
    /// adam.backward_step(&x.as_tensor().sqr()?.sum_all()?)?;
    /// // The first step moves every coordinate by ≈ lr against its gradient's sign.
    /// assert!((x.as_tensor().to_vec1::<f32>()?[0] - 0.999).abs() < 1e-6);
    /// assert_eq!(adam.steps(), 1);
    /// # Ok::<(), meshgnn_models::Error>(())
    /// ```
    pub fn new(params: Vec<(String, Var)>, config: AdamConfig) -> Result<Self> {
        let beta = |b: f64| b.is_finite() && (0.0..1.0).contains(&b);
        let positive = |x: f64| x.is_finite() && x > 0.0;
        let decay = config.weight_decay.is_finite() && config.weight_decay >= 0.0;
        if !positive(config.learning_rate)
            || !beta(config.beta1)
            || !beta(config.beta2)
            || !positive(config.epsilon)
            || !decay
        {
            return Err(Error::Invalid {
                what: "Adam config".into(),
                reason: format!("{config:?}: needs lr > 0, 0 ≤ β < 1, ε > 0 and λ ≥ 0"),
            });
        }
        let mut seen = std::collections::HashSet::new();
        for (name, _) in &params {
            if !seen.insert(name.as_str()) {
                return Err(Error::Invalid {
                    what: format!("Adam parameter {name:?}"),
                    reason: "appears twice".into(),
                });
            }
        }
        let (names, vars): (Vec<String>, Vec<Var>) = params.into_iter().unzip();
        let zeros = vars
            .iter()
            .map(|v| Ok(v.as_tensor().zeros_like()?))
            .collect::<Result<Vec<_>>>()?;
        Ok(Self {
            config,
            names,
            vars,
            first_moments: zeros.clone(),
            second_moments: zeros,
            steps: 0,
        })
    }

    /// The hyper-parameters (with the current learning rate).
    pub fn config(&self) -> AdamConfig {
        self.config
    }

    /// Current step size.
    pub fn learning_rate(&self) -> f64 {
        self.config.learning_rate
    }

    /// Sets the step size (e.g. the per-epoch exponential decay `lr · decay^epoch`).
    pub fn set_learning_rate(&mut self, learning_rate: f64) {
        self.config.learning_rate = learning_rate;
    }

    /// Steps taken (the `t` of the bias correction).
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// One Adam update of every parameter that has a gradient in `grads` (from
    /// `loss.backward()`); see the module conventions for the formula.
    pub fn step(&mut self, grads: &GradStore) -> Result<()> {
        self.steps += 1;
        let t = i32::try_from(self.steps).unwrap_or(i32::MAX);
        let AdamConfig {
            learning_rate: lr,
            beta1,
            beta2,
            epsilon,
            weight_decay,
        } = self.config;
        let c1 = 1.0 - beta1.powi(t);
        let c2 = 1.0 - beta2.powi(t);
        for ((var, m), v) in self
            .vars
            .iter()
            .zip(self.first_moments.iter_mut())
            .zip(self.second_moments.iter_mut())
        {
            let Some(g) = grads.get(var.as_tensor()) else {
                continue;
            };
            let decayed;
            let g = if weight_decay > 0.0 {
                decayed = g.add(&var.as_detached_tensor().affine(weight_decay, 0.0)?)?;
                &decayed
            } else {
                g
            };
            *m = m.affine(beta1, 0.0)?.add(&g.affine(1.0 - beta1, 0.0)?)?;
            *v = v
                .affine(beta2, 0.0)?
                .add(&g.sqr()?.affine(1.0 - beta2, 0.0)?)?;
            let update = m
                .affine(1.0 / c1, 0.0)?
                .div(&v.affine(1.0 / c2, 0.0)?.sqrt()?.affine(1.0, epsilon)?)?
                .affine(lr, 0.0)?;
            var.set(&var.as_detached_tensor().sub(&update)?)?;
        }
        Ok(())
    }

    /// Back-propagates the 0-d `loss` and takes one [`Adam::step`].
    pub fn backward_step(&mut self, loss: &Tensor) -> Result<()> {
        let grads = loss.backward()?;
        self.step(&grads)
    }

    /// The moment estimates as `(<prefix>m.<name>, m)` and `(<prefix>v.<name>, v)` pairs, in
    /// parameter order (each tensor has its parameter's shape).
    pub fn state_tensors(&self, prefix: &str) -> Vec<(String, Tensor)> {
        let named = |kind: &str, moments: &[Tensor]| -> Vec<(String, Tensor)> {
            self.names
                .iter()
                .zip(moments)
                .map(|(n, t)| (format!("{prefix}{kind}.{n}"), t.clone()))
                .collect()
        };
        let mut out = named("m", &self.first_moments);
        out.extend(named("v", &self.second_moments));
        out
    }

    /// Restores the state written by [`Adam::state_tensors`] with `prefix`, and the step count
    /// `steps`. Returns `false` (moments left at zero) when `tensors` holds no tensor under
    /// `prefix` — a checkpoint from before the state was saved; errors when only some moments
    /// are present or one has the wrong shape.
    pub fn restore(
        &mut self,
        tensors: &HashMap<String, Tensor>,
        prefix: &str,
        steps: u64,
    ) -> Result<bool> {
        self.steps = steps;
        if !tensors.keys().any(|k| k.starts_with(prefix)) {
            return Ok(false);
        }
        for (kind, moments) in [
            ("m", &mut self.first_moments),
            ("v", &mut self.second_moments),
        ] {
            for ((name, var), moment) in self.names.iter().zip(&self.vars).zip(moments.iter_mut()) {
                let key = format!("{prefix}{kind}.{name}");
                let t = tensors.get(&key).ok_or_else(|| Error::Invalid {
                    what: format!("optimiser tensor {key:?}"),
                    reason: "missing from the checkpoint".into(),
                })?;
                if t.dims() != var.dims() {
                    return Err(Error::Invalid {
                        what: format!("optimiser tensor {key:?}"),
                        reason: format!("has shape {:?}, the parameter {:?}", t.dims(), var.dims()),
                    });
                }
                *moment = t.to_device(var.device())?.to_dtype(var.dtype())?;
            }
        }
        Ok(true)
    }
}

/// The variables of `varmap` sorted by name (a deterministic parameter order).
pub fn sorted_vars(varmap: &VarMap) -> Vec<(String, Var)> {
    let data = match varmap.data().lock() {
        Ok(d) => d,
        Err(poisoned) => poisoned.into_inner(),
    };
    let mut all: Vec<(String, Var)> = data.iter().map(|(k, v)| (k.clone(), v.clone())).collect();
    all.sort_by(|a, b| a.0.cmp(&b.0));
    all
}

#[cfg(test)]
mod tests {
    use super::*;
    use candle_core::Device;

    #[test]
    fn one_step_on_a_scalar_matches_the_hand_computation() {
        // f(x) = x³ at x = 2: g = 12. Step 1: m = 0.1·12 = 1.2, v = 0.001·144 = 0.144,
        // m̂ = 12, v̂ = 144, x ← 2 − 0.1·12/(12 + 1e-8) = 1.9 (to f32 precision).
        let x = Var::new(&[2.0f32], &Device::Cpu).unwrap();
        let config = AdamConfig {
            learning_rate: 0.1,
            ..Default::default()
        };
        let mut adam = Adam::new(vec![("x".into(), x.clone())], config).unwrap();
        adam.backward_step(&x.as_tensor().powf(3.0).unwrap().sum_all().unwrap())
            .unwrap();
        assert!((x.as_tensor().to_vec1::<f32>().unwrap()[0] - 1.9).abs() < 1e-6);
        let state: HashMap<String, Tensor> = adam.state_tensors("opt.").into_iter().collect();
        let m = state["opt.m.x"].to_vec1::<f32>().unwrap()[0];
        let v = state["opt.v.x"].to_vec1::<f32>().unwrap()[0];
        assert!(
            (m - 1.2).abs() < 1e-6 && (v - 0.144).abs() < 1e-6,
            "{m} {v}"
        );
        // Step 2 at x = 1.9: g = 3·1.9² = 10.83; m = 0.9·1.2 + 0.1·10.83 = 2.163,
        // v = 0.999·0.144 + 0.001·117.2889 = 0.2611449; m̂ = 2.163/0.19 = 11.384210…,
        // v̂ = 0.2611449/0.001999 = 130.637769…, x ← 1.9 − 0.1·11.384210/11.429688 = 1.800398.
        adam.backward_step(&x.as_tensor().powf(3.0).unwrap().sum_all().unwrap())
            .unwrap();
        let x2 = x.as_tensor().to_vec1::<f32>().unwrap()[0];
        assert!((x2 - 1.800_398).abs() < 2e-5, "{x2}");
        assert_eq!(adam.steps(), 2);
    }

    #[test]
    fn weight_decay_adds_lambda_theta_to_the_gradient() {
        // f(x) = x² at x = 3 with λ = 2: g = 6 + 2·3 = 12, as f = x³ at x = 2 above, so the
        // first step is the same −lr·sign(g); the second differs from λ = 0's.
        let step = |weight_decay: f64| {
            let x = Var::new(&[3.0f32], &Device::Cpu).unwrap();
            let config = AdamConfig {
                learning_rate: 0.1,
                weight_decay,
                ..Default::default()
            };
            let mut adam = Adam::new(vec![("x".into(), x.clone())], config).unwrap();
            let loss = |x: &Var| x.as_tensor().sqr().unwrap().sum_all().unwrap();
            adam.backward_step(&loss(&x)).unwrap();
            let state: HashMap<String, Tensor> = adam.state_tensors("o.").into_iter().collect();
            let m = state["o.m.x"].to_vec1::<f32>().unwrap()[0];
            (x.as_tensor().to_vec1::<f32>().unwrap()[0], m)
        };
        let (x, m) = step(2.0);
        assert!((x - 2.9).abs() < 1e-6 && (m - 1.2).abs() < 1e-6, "{x} {m}");
        let (_, m0) = step(0.0);
        assert!((m0 - 0.6).abs() < 1e-6, "{m0}");
        let bad = AdamConfig {
            weight_decay: -1.0,
            ..Default::default()
        };
        assert!(Adam::new(vec![], bad).is_err());
    }

    #[test]
    fn restored_state_continues_bit_exactly() {
        let loss = |x: &Var| x.as_tensor().sqr().unwrap().sum_all().unwrap();
        let x = Var::new(&[1.0f32, -3.0, 0.5], &Device::Cpu).unwrap();
        let mut a = Adam::new(vec![("x".into(), x.clone())], AdamConfig::default()).unwrap();
        for _ in 0..3 {
            a.backward_step(&loss(&x)).unwrap();
        }
        let saved: HashMap<String, Tensor> = a.state_tensors("o.").into_iter().collect();
        let y = Var::from_tensor(x.as_tensor()).unwrap();
        let mut b = Adam::new(vec![("x".into(), y.clone())], AdamConfig::default()).unwrap();
        assert!(b.restore(&saved, "o.", a.steps()).unwrap());
        for _ in 0..3 {
            a.backward_step(&loss(&x)).unwrap();
            b.backward_step(&loss(&y)).unwrap();
        }
        assert_eq!(
            x.as_tensor().to_vec1::<f32>().unwrap(),
            y.as_tensor().to_vec1::<f32>().unwrap()
        );
        // No state under the prefix: moments stay zero; partial state is an error.
        assert!(!b.restore(&HashMap::new(), "o.", 0).unwrap());
        let mut partial = saved.clone();
        partial.remove("o.v.x");
        assert!(b.restore(&partial, "o.", 3).is_err());
        let bad = AdamConfig {
            beta1: 1.0,
            ..Default::default()
        };
        assert!(Adam::new(vec![], bad).is_err());
    }
}
