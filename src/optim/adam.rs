//! Adam (Kingma & Ba 2015) with steps in parameter units, clamped to the ranges: the paper's
//! gradient stages (§3.4) and the memetic algorithm's local search.
//!
//! Adam's step is roughly `lr` whatever the gradient's scale, so the learning rate is a length
//! in parameter units. Each variable gets `lr × unit`, the unit being `max − min` unless the
//! domain sets another ([`Var::with_unit`](super::Var::with_unit)): a radius in `[0.1, 8]` and a
//! thickness in `[0.025, 0.075]` then move the same fraction of their range per step (the
//! reference schedule: lr ≈ 0.01 at 256², ≈ 0.0075 at 512²). [`Adam::set_rate`] overrides one
//! variable (the fit does this for camera parameters whose ranges say little about scale).
//!
//! A variable whose gradient entry is exactly zero (or not finite) is not moved in that step,
//! and its moments and step count are left alone; discrete variables are never moved. Bias
//! correction uses each variable's own step count, so a variable that starts receiving
//! gradients late gets a full-size first step.

use super::{Domain, Individual, Objective, loss_key};

/// Adam's settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdamConfig {
    /// Evaluations (one gradient each) per run of [`adam_search`].
    pub iterations: usize,
    /// Step length as a fraction of each variable's unit (its range unless set otherwise).
    pub lr: f64,
    /// First-moment decay.
    pub beta1: f64,
    /// Second-moment decay.
    pub beta2: f64,
    /// Denominator guard.
    pub eps: f64,
}

impl Default for AdamConfig {
    fn default() -> Self {
        // The reference schedule's local search: 33–50 iterations at lr 0.01.
        AdamConfig {
            iterations: 40,
            lr: 0.01,
            beta1: 0.9,
            beta2: 0.999,
            eps: 1e-12,
        }
    }
}

/// The state of one Adam run: per-variable step sizes, moments and step counts.
#[derive(Clone, Debug)]
pub struct Adam {
    rate: Vec<f64>,
    m: Vec<f64>,
    v: Vec<f64>,
    t: Vec<i32>,
    beta1: f64,
    beta2: f64,
    eps: f64,
}

impl Adam {
    /// A fresh state for `domain`: step `config.lr × unit` for continuous variables (the unit is
    /// the range unless the domain says otherwise), 0 for discrete ones.
    pub fn new(domain: &Domain, config: &AdamConfig) -> Adam {
        let n = domain.len();
        Adam {
            rate: domain
                .vars()
                .iter()
                .map(|v| {
                    if v.discrete {
                        0.0
                    } else {
                        config.lr * v.range()
                    }
                })
                .collect(),
            m: vec![0.0; n],
            v: vec![0.0; n],
            t: vec![0; n],
            beta1: config.beta1,
            beta2: config.beta2,
            eps: config.eps,
        }
    }

    /// Sets variable `i`'s step length in parameter units (0 freezes it). Out-of-range `i` and
    /// negative or non-finite rates are ignored.
    pub fn set_rate(&mut self, i: usize, rate: f64) {
        if let Some(r) = self.rate.get_mut(i)
            && rate.is_finite()
            && rate >= 0.0
        {
            *r = rate;
        }
    }

    /// The step lengths in parameter units.
    pub fn rates(&self) -> &[f64] {
        &self.rate
    }

    /// Multiplies every step length by `factor` (a schedule's decay).
    pub fn scale_rates(&mut self, factor: f64) {
        if factor.is_finite() && factor >= 0.0 {
            self.rate.iter_mut().for_each(|r| *r *= factor);
        }
    }

    /// One Adam step on `x` (in place, clamped to `domain`) along `-grad`. Returns how many
    /// variables moved. Variables with a zero or non-finite gradient entry, and frozen or
    /// discrete ones, keep their value and state.
    pub fn step(&mut self, domain: &Domain, x: &mut [f64], grad: &[f64]) -> usize {
        let mut moved = 0;
        for i in 0..x.len().min(grad.len()).min(self.rate.len()) {
            let g = grad[i];
            if g == 0.0 || !g.is_finite() || self.rate[i] == 0.0 {
                continue;
            }
            self.t[i] += 1;
            self.m[i] = self.beta1 * self.m[i] + (1.0 - self.beta1) * g;
            self.v[i] = self.beta2 * self.v[i] + (1.0 - self.beta2) * g * g;
            let m_hat = self.m[i] / (1.0 - self.beta1.powi(self.t[i]));
            let v_hat = self.v[i] / (1.0 - self.beta2.powi(self.t[i]));
            let before = x[i];
            x[i] = domain.vars()[i].clamp(x[i] - self.rate[i] * m_hat / (v_hat.sqrt() + self.eps));
            if x[i] != before {
                moved += 1;
            }
        }
        moved
    }
}

/// Runs `config.iterations` Adam iterations from `x0` (clamped into `domain`) and returns the
/// best point evaluated, with the number of evaluations spent. Without gradients (or with 0
/// iterations) it evaluates `x0` once.
pub fn adam_search<O: Objective + ?Sized>(
    objective: &O,
    domain: &Domain,
    x0: &[f64],
    config: &AdamConfig,
) -> (Individual, usize) {
    let mut x = x0.to_vec();
    domain.clamp(&mut x);
    if !objective.has_gradient() || config.iterations == 0 {
        let value = loss_key(objective.value(&x));
        return (Individual { x, value }, 1);
    }
    let mut adam = Adam::new(domain, config);
    let mut grad = vec![0.0; x.len()];
    let mut best = Individual {
        x: x.clone(),
        value: f64::INFINITY,
    };
    let mut evaluations = 0;
    for _ in 0..config.iterations {
        let value = loss_key(objective.value_grad(&x, &mut grad));
        evaluations += 1;
        if value < best.value {
            best.value = value;
            best.x.copy_from_slice(&x);
        }
        if value == f64::INFINITY || adam.step(domain, &mut x, &grad) == 0 {
            // Nowhere to go: a failed evaluation gives no usable gradient, and a step that
            // moves nothing would evaluate the same point again.
            break;
        }
    }
    (best, evaluations)
}
