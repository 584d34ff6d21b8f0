//! The memetic algorithm of the paper's §3.4: a steady-state genetic algorithm over mixed
//! discrete/continuous variables whose individuals are improved by Adam local searches.
//!
//! - **Start**: the population comes from given seed vectors (the fit passes presets × camera
//!   guesses). With more seeds than places, every seed is evaluated once and the best are kept;
//!   with fewer, the rest is filled with mutated copies of the seeds. Each starting individual
//!   is polished by a short Adam run ([`MemeticConfig::polish`]).
//! - **Generation**: a batch of children, each from two parents picked by tournament, one-point
//!   crossover and Gaussian mutation inside the ranges. Discrete variables change only here
//!   (Adam never moves them): a mutated discrete gene takes a rounded Gaussian step of at least
//!   one unit. A fraction of the children get an Adam local search. Each child replaces the
//!   worst individual if it is better.
//! - **Restart**: when the population has collapsed (mean standard deviation per variable, as a
//!   fraction of its unit, below [`MemeticConfig::min_diversity`]), all but the elite are
//!   replaced by strongly mutated copies of the elite and of the seeds, polished again.
//!
//! **Determinism.** All random choices are made sequentially from one seeded [`Rng`] before a
//! batch is evaluated; the batch is then evaluated in parallel with rayon (order-preserving
//! `collect`), and the results are inserted sequentially. For a deterministic objective the run
//! is therefore identical for any thread count.
//!
//! **Bounded work.** [`Memetic::step`] does one batch (a chunk of the start, or one generation)
//! and never spends more than the remaining evaluation budget, so a caller (the page's session)
//! can interleave steps with progress reports and stop at any time.

use super::{AdamConfig, Domain, Objective, OptimError, Rng, adam_search, loss_key};
use rayon::prelude::*;

/// A point and its loss.
#[derive(Clone, Debug, PartialEq)]
pub struct Individual {
    /// The point, inside the domain.
    pub x: Vec<f64>,
    /// Its loss (`+∞` when the evaluation failed).
    pub value: f64,
}

/// Settings of the memetic algorithm. Defaults follow the reference notes ("Optimisers and
/// schedule"): population 24, mutation 0.2 of the range, ~10 % local searches of 40 Adam
/// iterations at lr 0.01, starting individuals polished by 25 iterations, 5000 evaluations.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MemeticConfig {
    /// Individuals kept (≥ 2).
    pub population: usize,
    /// Individuals drawn per tournament; the best of them becomes a parent (≥ 1).
    pub tournament: usize,
    /// Children made (and evaluated in parallel) per generation (≥ 1).
    pub batch: usize,
    /// Probability that a child is a one-point crossover of its parents rather than a copy of
    /// the first.
    pub crossover_rate: f64,
    /// Probability that each gene of a child is mutated.
    pub mutation_rate: f64,
    /// Standard deviation of a mutation, as a fraction of the variable's unit (its range for
    /// discrete variables).
    pub mutation_sigma: f64,
    /// Fraction of children that get an Adam local search.
    pub local_search_rate: f64,
    /// The local search.
    pub local_search: AdamConfig,
    /// The Adam run that polishes each starting individual.
    pub polish: AdamConfig,
    /// Total evaluation budget (≥ 1).
    pub max_evaluations: usize,
    /// Restart when the population's diversity falls below this.
    pub min_diversity: f64,
    /// Best individuals kept through a restart.
    pub elite: usize,
    /// Seed of the random choices.
    pub seed: u64,
}

impl Default for MemeticConfig {
    fn default() -> Self {
        MemeticConfig {
            population: 24,
            tournament: 4,
            batch: 8,
            crossover_rate: 0.8,
            mutation_rate: 0.2,
            mutation_sigma: 0.2,
            local_search_rate: 0.1,
            local_search: AdamConfig::default(),
            polish: AdamConfig {
                iterations: 25,
                ..AdamConfig::default()
            },
            max_evaluations: 5000,
            min_diversity: 0.01,
            elite: 2,
            seed: 0,
        }
    }
}

impl MemeticConfig {
    fn validate(&self) -> Result<(), OptimError> {
        let prob = |name: &str, p: f64| {
            if (0.0..=1.0).contains(&p) {
                Ok(())
            } else {
                Err(OptimError(format!("{name} {p} is not a probability")))
            }
        };
        if self.population < 2 {
            return Err(OptimError(
                "the population needs at least 2 individuals".into(),
            ));
        }
        if self.tournament == 0 || self.batch == 0 || self.max_evaluations == 0 {
            return Err(OptimError(
                "tournament size, batch and evaluation budget must be at least 1".into(),
            ));
        }
        prob("crossover rate", self.crossover_rate)?;
        prob("mutation rate", self.mutation_rate)?;
        prob("local search rate", self.local_search_rate)?;
        if !(self.mutation_sigma.is_finite() && self.mutation_sigma > 0.0) {
            return Err(OptimError(format!(
                "mutation sigma {} must be positive",
                self.mutation_sigma
            )));
        }
        if !self.min_diversity.is_finite() || self.min_diversity < 0.0 {
            return Err(OptimError("minimum diversity must be ≥ 0".into()));
        }
        for (name, a) in [("local search", self.local_search), ("polish", self.polish)] {
            let valid = a.lr.is_finite()
                && a.lr >= 0.0
                && (0.0..1.0).contains(&a.beta1)
                && (0.0..1.0).contains(&a.beta2)
                && a.eps.is_finite()
                && a.eps > 0.0;
            if !valid {
                return Err(OptimError(format!("{name} Adam settings are invalid")));
            }
        }
        Ok(())
    }
}

/// Where a run stands after a [`Memetic::step`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MemeticStatus {
    /// Evaluations spent so far.
    pub evaluations: usize,
    /// Generations completed (the start phase is generation 0).
    pub generation: usize,
    /// Restarts so far.
    pub restarts: usize,
    /// Best loss so far (`+∞` before the first evaluation).
    pub best_value: f64,
    /// The budget is spent; further steps do nothing.
    pub done: bool,
}

/// One unit of parallel work.
struct Job {
    x: Vec<f64>,
    /// Adam iterations (0 = evaluate once).
    iterations: usize,
    /// Adam settings when `iterations > 0`.
    adam: AdamConfig,
}

/// A memetic run in progress.
#[derive(Clone, Debug)]
pub struct Memetic {
    domain: Domain,
    config: MemeticConfig,
    rng: Rng,
    seeds: Vec<Vec<f64>>,
    /// Seeds still to be screened (only when there are more seeds than places).
    to_screen: Vec<Vec<f64>>,
    screened: Vec<Individual>,
    /// Extra seeds ([`Memetic::with_extra_seeds`]), screened after the others.
    extras: Vec<Vec<f64>>,
    /// The variables mutation, crossover and random restarts change: all of them, or while
    /// extra seeds are pending or were dropped, those not frozen at the regular seeds' shared
    /// value (so the random stream is the one a run without the extras' variables draws).
    active: Vec<usize>,
    /// The frozen variables' values (empty when nothing is frozen).
    frozen: Vec<(usize, f64)>,
    /// Variables that mutation and random points never change ([`Memetic::with_unmutated`]);
    /// never in `active`.
    unmutated: Vec<usize>,
    /// Starting individuals still to be polished and inserted.
    to_polish: Vec<Vec<f64>>,
    population: Vec<Individual>,
    best: Option<Individual>,
    evaluations: usize,
    generation: usize,
    restarts: usize,
}

impl Memetic {
    /// A run over `domain` starting from `seeds` (each clamped into the domain; none is
    /// allowed: the population then starts uniformly random). Nothing is evaluated yet. Errors
    /// on invalid settings and on seeds of the wrong length or with non-finite values.
    pub fn new(
        domain: Domain,
        seeds: &[Vec<f64>],
        config: MemeticConfig,
    ) -> Result<Memetic, OptimError> {
        Memetic::build(domain, seeds, config, Vec::new())
    }

    /// [`Memetic::new`] with `unmutated` ([`Memetic::with_unmutated`]) out of the search from
    /// the first starting point on.
    fn build(
        domain: Domain,
        seeds: &[Vec<f64>],
        config: MemeticConfig,
        unmutated: Vec<usize>,
    ) -> Result<Memetic, OptimError> {
        config.validate()?;
        let seeds = seeds
            .iter()
            .map(|s| domain.check(s))
            .collect::<Result<Vec<_>, _>>()?;
        let n_vars = domain.vars().len();
        let mut m = Memetic {
            domain,
            config,
            rng: Rng::new(config.seed),
            seeds: seeds.clone(),
            to_screen: Vec::new(),
            screened: Vec::new(),
            extras: Vec::new(),
            active: (0..n_vars).filter(|i| !unmutated.contains(i)).collect(),
            frozen: Vec::new(),
            unmutated,
            to_polish: Vec::new(),
            population: Vec::new(),
            best: None,
            evaluations: 0,
            generation: 0,
            restarts: 0,
        };
        if seeds.len() > config.population {
            m.to_screen = seeds;
            // Screened in order; reversed so that `pop` takes them first to last.
            m.to_screen.reverse();
        } else {
            let fill = m.fill(&seeds, config.population - seeds.len(), 2.0);
            m.to_polish = seeds.into_iter().chain(fill).rev().collect();
        }
        Ok(m)
    }

    /// Seeds with something no regular seed has (a cup's saucer), and the variables only they
    /// use (`own`): the extras are screened after the regular seeds and join only when one of
    /// them is better than every regular seed. Until then, and for good when none is, `own`
    /// stays at the regular seeds' values and out of mutation and crossover, the extras'
    /// evaluations are not counted, and the run draws the same random numbers as a run over
    /// the other variables alone. With no more seeds than places (no screening), the extras
    /// simply join the seeds. Errors on extras of the wrong length or with non-finite values.
    pub fn with_extra_seeds(
        mut self,
        extras: &[Vec<f64>],
        own: std::ops::Range<usize>,
    ) -> Result<Memetic, OptimError> {
        let extras = extras
            .iter()
            .map(|s| self.domain.check(s))
            .collect::<Result<Vec<_>, _>>()?;
        if extras.is_empty() {
            return Ok(self);
        }
        if self.to_screen.is_empty() {
            let mut seeds = self.seeds.clone();
            seeds.extend(extras);
            return Memetic::build(self.domain, &seeds, self.config, self.unmutated);
        }
        // The extras' own variables stay at the regular seeds' value unless an extra joins.
        let first = &self.seeds[0];
        let own = own.start.min(first.len())..own.end.min(first.len());
        let frozen: Vec<(usize, f64)> = own.clone().map(|i| (i, first[i])).collect();
        self.active = (0..first.len())
            .filter(|i| !own.contains(i) && !self.unmutated.contains(i))
            .collect();
        self.frozen = frozen;
        self.extras = extras;
        Ok(self)
    }

    /// Leaves `vars` to local search: mutation never changes them (a random starting point has
    /// each at its lower bound) and crossover passes them on from a parent, while the Adam
    /// polish and local searches move them like the others. For a refinement of shapes the
    /// seeds already make (a hip roof's ridge length) that would only add a dimension to the
    /// random search.
    /// The other variables draw the same random numbers as a run without `vars` would. Call it
    /// before [`Memetic::with_extra_seeds`] (it starts the run afresh). Errors as
    /// [`Memetic::new`].
    pub fn with_unmutated(self, vars: &[usize]) -> Result<Memetic, OptimError> {
        Memetic::build(self.domain, &self.seeds, self.config, vars.to_vec())
    }

    /// `count` new starting points: mutated copies of `from` (cycled), mutation rate and sigma
    /// multiplied by `strength`; uniformly random points when `from` is empty.
    fn fill(&mut self, from: &[Vec<f64>], count: usize, strength: f64) -> Vec<Vec<f64>> {
        (0..count)
            .map(|i| {
                if from.is_empty() {
                    let vars = self.domain.vars().to_vec();
                    let mut x: Vec<f64> = vars.iter().map(|v| v.min).collect();
                    for &i in &self.active {
                        x[i] = vars[i].clamp(self.rng.range(vars[i].min, vars[i].max));
                    }
                    for &(i, v) in &self.frozen {
                        x[i] = v;
                    }
                    x
                } else {
                    let mut x = from[i % from.len()].clone();
                    self.mutate(&mut x, strength);
                    x
                }
            })
            .collect()
    }

    /// Gaussian mutation inside the ranges; at least one gene changes if any can.
    fn mutate(&mut self, x: &mut [f64], strength: f64) {
        let rate = (self.config.mutation_rate * strength).min(1.0);
        let sigma = self.config.mutation_sigma * strength;
        let mut changed = false;
        for k in 0..self.active.len() {
            if self.rng.chance(rate) {
                changed |= self.mutate_gene(x, self.active[k], sigma);
            }
        }
        if !changed && !self.active.is_empty() {
            let i = self.active[self.rng.below(self.active.len())];
            self.mutate_gene(x, i, sigma);
        }
    }

    fn mutate_gene(&mut self, x: &mut [f64], i: usize, sigma: f64) -> bool {
        let var = self.domain.vars()[i];
        let before = x[i];
        let unit = if var.discrete { var.range() } else { var.unit };
        let step = self.rng.normal() * sigma * unit;
        x[i] = if var.discrete {
            // A rounded Gaussian step of at least one unit, so a discrete mutation always does
            // something (bounces off the end of the range).
            let mut k = step.round();
            if k == 0.0 {
                k = if self.rng.chance(0.5) { 1.0 } else { -1.0 };
            }
            let up = var.clamp(before + k);
            if up != before {
                up
            } else {
                var.clamp(before - k)
            }
        } else {
            var.clamp(before + step)
        };
        x[i] != before
    }

    /// Index of a tournament winner.
    fn tournament(&mut self) -> usize {
        let n = self.population.len();
        let mut best = self.rng.below(n);
        for _ in 1..self.config.tournament {
            let c = self.rng.below(n);
            if self.population[c].value < self.population[best].value {
                best = c;
            }
        }
        best
    }

    /// Mean over variables of the population's standard deviation divided by the variable's unit
    /// (its range unless the domain sets one).
    pub fn diversity(&self) -> f64 {
        let n = self.population.len();
        if n < 2 {
            return f64::INFINITY;
        }
        let vars = self.domain.vars();
        let mut total = 0.0;
        let mut counted = 0usize;
        for (i, v) in vars.iter().enumerate() {
            let unit = if v.discrete { v.range() } else { v.unit };
            if v.range() <= 0.0 || unit <= 0.0 {
                continue;
            }
            let mean = self.population.iter().map(|p| p.x[i]).sum::<f64>() / n as f64;
            let var = self
                .population
                .iter()
                .map(|p| (p.x[i] - mean).powi(2))
                .sum::<f64>()
                / n as f64;
            total += var.sqrt() / unit;
            counted += 1;
        }
        if counted == 0 {
            f64::INFINITY
        } else {
            total / counted as f64
        }
    }

    fn remaining(&self) -> usize {
        self.config.max_evaluations.saturating_sub(self.evaluations)
    }

    fn run_jobs<O: Objective + ?Sized>(
        &mut self,
        objective: &O,
        jobs: Vec<Job>,
    ) -> Vec<Individual> {
        let domain = &self.domain;
        let results: Vec<(Individual, usize)> = jobs
            .into_par_iter()
            .map(|job| {
                let adam = AdamConfig {
                    iterations: job.iterations,
                    ..job.adam
                };
                adam_search(objective, domain, &job.x, &adam)
            })
            .collect();
        results
            .into_iter()
            .map(|(ind, evals)| {
                self.evaluations += evals;
                if self.best.as_ref().is_none_or(|b| ind.value < b.value) {
                    self.best = Some(ind.clone());
                }
                ind
            })
            .collect()
    }

    /// Plans `iterations` of `adam` on `x` within the remaining budget (`planned` already
    /// promised to earlier jobs of the batch); `None` when the budget is spent.
    fn plan(&self, x: Vec<f64>, adam: AdamConfig, gradient: bool, planned: usize) -> Option<Job> {
        let left = self.remaining().saturating_sub(planned);
        if left == 0 {
            return None;
        }
        let iterations = if gradient {
            adam.iterations.min(left)
        } else {
            0
        };
        Some(Job {
            x,
            iterations,
            adam,
        })
    }

    fn cost(job: &Job) -> usize {
        job.iterations.max(1)
    }

    /// Inserts `ind`: appended while the population is not full, else it replaces the worst
    /// individual if it is better.
    fn insert(&mut self, ind: Individual) {
        if self.population.len() < self.config.population {
            self.population.push(ind);
            return;
        }
        let worst = (0..self.population.len())
            .max_by(|&a, &b| {
                self.population[a]
                    .value
                    .total_cmp(&self.population[b].value)
            })
            .unwrap_or(0);
        if ind.value < self.population[worst].value {
            self.population[worst] = ind;
        }
    }

    /// Does one bounded slice of work (a chunk of the start phase, or one generation) and
    /// reports where the run stands.
    pub fn step<O: Objective + ?Sized>(&mut self, objective: &O) -> MemeticStatus {
        if self.remaining() > 0 {
            let gradient = objective.has_gradient();
            if !self.to_screen.is_empty() {
                self.step_screen(objective);
            } else if !self.to_polish.is_empty() {
                self.step_polish(objective, gradient);
            } else {
                self.step_generation(objective, gradient);
            }
        }
        self.status()
    }

    fn step_screen<O: Objective + ?Sized>(&mut self, objective: &O) {
        let take = (4 * self.config.batch)
            .min(self.to_screen.len())
            .min(self.remaining());
        let jobs = (0..take)
            .filter_map(|_| self.to_screen.pop())
            .map(|x| Job {
                x,
                iterations: 0,
                adam: self.config.polish,
            })
            .collect();
        let done = self.run_jobs(objective, jobs);
        self.screened.extend(done);
        if self.to_screen.is_empty() && !self.extras.is_empty() {
            let best = self
                .screened
                .iter()
                .map(|i| i.value)
                .fold(f64::INFINITY, f64::min);
            let before = self.evaluations;
            let jobs = std::mem::take(&mut self.extras)
                .into_iter()
                .map(|x| Job {
                    x,
                    iterations: 0,
                    adam: self.config.polish,
                })
                .collect();
            let extras = self.run_jobs(objective, jobs);
            if extras.iter().any(|i| i.value < best) {
                self.screened.extend(extras);
                self.active = (0..self.domain.vars().len())
                    .filter(|i| !self.unmutated.contains(i))
                    .collect();
                self.frozen.clear();
            } else {
                // Dropped: as if never evaluated (`best` did not change, none was better).
                self.evaluations = before;
            }
        }
        if self.to_screen.is_empty() {
            // Keep the best `population` seeds (stable sort: ties keep seed order) and polish.
            let mut screened = std::mem::take(&mut self.screened);
            screened.sort_by(|a, b| a.value.total_cmp(&b.value));
            screened.truncate(self.config.population);
            self.to_polish = screened.into_iter().map(|i| i.x).rev().collect();
        }
    }

    fn step_polish<O: Objective + ?Sized>(&mut self, objective: &O, gradient: bool) {
        let mut jobs = Vec::new();
        let mut planned = 0;
        while jobs.len() < self.config.batch {
            let Some(x) = self.to_polish.pop() else { break };
            match self.plan(x, self.config.polish, gradient, planned) {
                Some(job) => {
                    planned += Self::cost(&job);
                    jobs.push(job);
                }
                None => break,
            }
        }
        for ind in self.run_jobs(objective, jobs) {
            self.insert(ind);
        }
    }

    fn step_generation<O: Objective + ?Sized>(&mut self, objective: &O, gradient: bool) {
        if self.population.is_empty() {
            // Only reachable when the budget ran out during the start; nothing to breed.
            return;
        }
        let mut jobs = Vec::new();
        let mut planned = 0;
        for _ in 0..self.config.batch {
            let a = self.tournament();
            let b = self.tournament();
            let mut child = self.population[a].x.clone();
            if self.rng.chance(self.config.crossover_rate) && self.active.len() > 1 {
                // One-point crossover: genes before the cut from the first parent, the rest
                // from the second (the cut drawn among the active genes; frozen ones are the
                // same in every individual).
                let cut = self.active[1 + self.rng.below(self.active.len() - 1)];
                child[cut..].copy_from_slice(&self.population[b].x[cut..]);
            }
            self.mutate(&mut child, 1.0);
            let search = self.rng.chance(self.config.local_search_rate);
            let adam = if search {
                self.config.local_search
            } else {
                AdamConfig {
                    iterations: 0,
                    ..self.config.local_search
                }
            };
            match self.plan(child, adam, gradient, planned) {
                Some(job) => {
                    planned += Self::cost(&job);
                    jobs.push(job);
                }
                None => break,
            }
        }
        for ind in self.run_jobs(objective, jobs) {
            self.insert(ind);
        }
        self.generation += 1;
        if self.population.len() >= self.config.population
            && self.diversity() < self.config.min_diversity
        {
            self.restart();
        }
    }

    /// Keeps the elite and queues strongly mutated copies of the elite and the seeds.
    fn restart(&mut self) {
        self.restarts += 1;
        self.population.sort_by(|a, b| a.value.total_cmp(&b.value));
        self.population
            .truncate(self.config.elite.clamp(1, self.config.population));
        let elite: Vec<Vec<f64>> = self.population.iter().map(|p| p.x.clone()).collect();
        let mut sources = elite;
        sources.extend(self.seeds.iter().cloned());
        let count = self.config.population - self.population.len();
        self.to_polish = self.fill(&sources, count, 2.0);
        self.to_polish.reverse();
    }

    /// Adds `extra` evaluations to the budget (a finished run can go on).
    pub fn extend_budget(&mut self, extra: usize) {
        self.config.max_evaluations = self.config.max_evaluations.saturating_add(extra);
    }

    /// Where the run stands.
    pub fn status(&self) -> MemeticStatus {
        MemeticStatus {
            evaluations: self.evaluations,
            generation: self.generation,
            restarts: self.restarts,
            best_value: self
                .best
                .as_ref()
                .map_or(f64::INFINITY, |b| loss_key(b.value)),
            done: self.remaining() == 0,
        }
    }

    /// Steps until the budget is spent; returns the best individual (`None` only if nothing
    /// could be evaluated).
    pub fn run<O: Objective + ?Sized>(&mut self, objective: &O) -> Option<&Individual> {
        loop {
            let before = self.evaluations;
            let status = self.step(objective);
            // The second test is a guard: every step with budget left spends some of it.
            if status.done || self.evaluations == before {
                break;
            }
        }
        self.best.as_ref()
    }

    /// The best individual evaluated so far.
    pub fn best(&self) -> Option<&Individual> {
        self.best.as_ref()
    }

    /// The current population (unordered).
    pub fn population(&self) -> &[Individual] {
        &self.population
    }

    /// The domain searched.
    pub fn domain(&self) -> &Domain {
        &self.domain
    }
}
