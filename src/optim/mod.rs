//! Optimisers for the fit: Adam with steps in parameter units ([`adam`]), the memetic algorithm
//! that mixes a genetic search over discrete and continuous parameters with Adam local searches
//! ([`memetic`], paper §3.4), and the seeded random numbers both rely on ([`rng`]).
//!
//! Everything here is generic over an [`Objective`] (a loss and, where available, its gradient)
//! on a box [`Domain`] of continuous and discrete variables; nothing knows about meshes or
//! cameras. The reconstruction pipeline (`crate::reconstruct`) builds the objective.
//!
//! Conventions shared by both optimisers:
//! - A point is always inside its domain: continuous values clamped to `[min, max]`, discrete
//!   values whole numbers in range ([`Domain::clamp`]).
//! - A failed or non-finite evaluation counts as `+∞` (worse than everything), so a generator
//!   that cannot build a mesh for some parameters steers the search away instead of aborting it.
//! - A gradient entry that is exactly zero or not finite means "no gradient" for that variable
//!   in that evaluation: Adam leaves the variable (and its moment estimates) untouched. A
//!   silhouette loss gives exactly zero to parameters whose geometry is hidden or absent (a
//!   handle that is switched off), and momentum from earlier steps must not drift them.
//! - One evaluation = one call of [`Objective::value`] or [`Objective::value_grad`]; budgets
//!   count these.

pub mod adam;
pub mod memetic;
pub mod rng;

pub use adam::{Adam, AdamConfig, adam_search};
pub use memetic::{Individual, Memetic, MemeticConfig, MemeticStatus};
pub use rng::Rng;

use crate::generators::ParamSpec;
use std::fmt;

/// An optimiser set-up that cannot be used (bad domain, seeds of the wrong length, …).
#[derive(Clone, Debug, PartialEq)]
pub struct OptimError(pub String);

impl fmt::Display for OptimError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for OptimError {}

/// The function being minimised.
///
/// `Sync` because the memetic algorithm evaluates a population in parallel (rayon). It must be
/// deterministic (same point → same value and gradient, whichever thread asks) for the
/// optimisers to be deterministic for a seed.
pub trait Objective: Sync {
    /// The loss at `x` (inside the domain). A failed evaluation returns `f64::INFINITY`.
    fn value(&self, x: &[f64]) -> f64;

    /// Whether [`Objective::value_grad`] gives real gradients. Without them the optimisers do
    /// no Adam steps (the memetic algorithm becomes a plain genetic algorithm).
    fn has_gradient(&self) -> bool {
        false
    }

    /// The loss at `x`, with its gradient written into `grad` (same length as `x`; every entry
    /// overwritten). Entries that are exactly zero mean "no gradient" (see the module doc).
    fn value_grad(&self, x: &[f64], grad: &mut [f64]) -> f64 {
        grad.fill(0.0);
        self.value(x)
    }
}

/// One optimisation variable: a closed range, continuous or whole-numbered.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Var {
    /// Smallest value.
    pub min: f64,
    /// Largest value.
    pub max: f64,
    /// Whole numbers only; changed by mutation and crossover, never by Adam.
    pub discrete: bool,
    /// The variable's natural step: Adam's step is `lr × unit` and a mutation's standard
    /// deviation `sigma × unit`. The constructors set it to the range (the paper's "steps in
    /// parameter units", per-parameter rates by range); [`Var::with_unit`] sets it for
    /// variables whose range says little about their scale (camera parameters).
    pub unit: f64,
}

impl Var {
    /// A continuous variable in `[min, max]`.
    pub fn continuous(min: f64, max: f64) -> Var {
        Var {
            min,
            max,
            discrete: false,
            unit: max - min,
        }
    }

    /// A whole-numbered variable in `[min, max]`.
    pub fn discrete(min: f64, max: f64) -> Var {
        Var {
            min,
            max,
            discrete: true,
            unit: max - min,
        }
    }

    /// The same variable with another step unit.
    pub fn with_unit(self, unit: f64) -> Var {
        Var { unit, ..self }
    }

    /// `max − min`.
    pub fn range(&self) -> f64 {
        self.max - self.min
    }

    /// `v` moved into the range (and rounded if discrete). NaN goes to the middle of the range
    /// so a broken value never escapes into a parameter vector.
    pub fn clamp(&self, v: f64) -> f64 {
        let v = if v.is_nan() {
            0.5 * (self.min + self.max)
        } else {
            v
        };
        let v = v.clamp(self.min, self.max);
        if self.discrete {
            v.round().clamp(self.min, self.max)
        } else {
            v
        }
    }
}

/// The box an optimiser searches: one [`Var`] per coordinate.
#[derive(Clone, Debug, PartialEq)]
pub struct Domain {
    vars: Vec<Var>,
}

impl Domain {
    /// A domain from its variables. Errors when it is empty, a bound is not finite, `min >
    /// max`, or a discrete variable has no whole number in its range.
    pub fn new(vars: Vec<Var>) -> Result<Domain, OptimError> {
        if vars.is_empty() {
            return Err(OptimError("the domain has no variables".into()));
        }
        for (i, v) in vars.iter().enumerate() {
            if !(v.min.is_finite() && v.max.is_finite()) || v.min > v.max {
                return Err(OptimError(format!(
                    "variable {i} has an invalid range [{}, {}]",
                    v.min, v.max
                )));
            }
            if !(v.unit.is_finite() && v.unit >= 0.0) {
                return Err(OptimError(format!(
                    "variable {i} has an invalid unit {}",
                    v.unit
                )));
            }
            if v.discrete && v.min.ceil() > v.max.floor() {
                return Err(OptimError(format!(
                    "discrete variable {i} has no whole number in [{}, {}]",
                    v.min, v.max
                )));
            }
        }
        Ok(Domain { vars })
    }

    /// The domain of a generator's parameters (every non-continuous kind is discrete).
    pub fn from_specs(specs: &[ParamSpec]) -> Result<Domain, OptimError> {
        Domain::new(
            specs
                .iter()
                .map(|s| {
                    if s.kind.is_continuous() {
                        Var::continuous(s.min, s.max)
                    } else {
                        Var::discrete(s.min, s.max)
                    }
                })
                .collect(),
        )
    }

    /// The variables.
    pub fn vars(&self) -> &[Var] {
        &self.vars
    }

    /// Number of variables.
    pub fn len(&self) -> usize {
        self.vars.len()
    }

    /// Always false: a domain has at least one variable.
    pub fn is_empty(&self) -> bool {
        self.vars.is_empty()
    }

    /// Moves every coordinate of `x` into its range (discrete ones rounded).
    pub fn clamp(&self, x: &mut [f64]) {
        for (v, s) in x.iter_mut().zip(&self.vars) {
            *v = s.clamp(*v);
        }
    }

    /// Checks that `x` has one finite value per variable; returns it clamped into the domain.
    pub fn check(&self, x: &[f64]) -> Result<Vec<f64>, OptimError> {
        if x.len() != self.vars.len() {
            return Err(OptimError(format!(
                "a point has {} values, the domain {}",
                x.len(),
                self.vars.len()
            )));
        }
        if let Some(i) = x.iter().position(|v| !v.is_finite()) {
            return Err(OptimError(format!("value {i} of a point is not finite")));
        }
        let mut x = x.to_vec();
        self.clamp(&mut x);
        Ok(x)
    }
}

/// `v`, with NaN read as `+∞`: the order in which losses are compared everywhere.
pub(crate) fn loss_key(v: f64) -> f64 {
    if v.is_nan() { f64::INFINITY } else { v }
}
