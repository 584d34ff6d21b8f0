//! The tree-structured genetic algorithm of the paper (§3.5.2, Fig. 8), generic over a fitness
//! closure `Fn(&[f64]) -> f64` on genomes in `[0, 1]^N`, so it is tested on synthetic functions
//! and used for trees with the tree similarity.
//!
//! Elementary GAs are the nodes of a tree with [`GaConfig::levels`] levels and
//! [`GaConfig::children`] children a node. Leaf GAs start from random genomes; every other GA
//! starts from the best individuals of its children's last populations. Each generation the
//! weaker half is killed, parents are chosen fitness-proportionally from the survivors, a child
//! is their one-point crossover, mutated with chance [`GaConfig::mutation_chance`] either by a
//! plain Gaussian or by Algorithm 3 ([`super::mutation::MutationStats`]).
//!
//! Determinism: all random numbers come from one seeded stream per node, drawn on the calling
//! thread; only fitness evaluation runs in parallel (rayon, order-preserving), so a seed gives
//! the same result on any number of threads.

use super::TreeError;
use super::mutation::MutationStats;
use procfit_generators::rng::SplitMix64;
use rayon::prelude::*;

/// The GA's random draws, on the shared SplitMix64 stream (a seed gives the same run anywhere).
#[derive(Clone, Debug)]
pub struct Rng(SplitMix64);

impl Rng {
    /// A stream for a seed.
    pub fn new(seed: u64) -> Rng {
        Rng(SplitMix64::from_state(seed ^ 0x5DEE_CE66_D1CE_4E5B))
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0.next_u64()
    }

    /// Uniform in `[0, 1)`.
    pub fn unit(&mut self) -> f64 {
        self.0.unit_f64()
    }

    /// Uniform in `0..n` (`n` > 0).
    pub fn below(&mut self, n: usize) -> usize {
        ((self.unit() * n as f64) as usize).min(n.saturating_sub(1))
    }

    /// Standard normal (Box–Muller).
    pub fn normal(&mut self) -> f64 {
        let u1 = self.unit().max(1e-300);
        let u2 = self.unit();
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }

    /// `k` distinct indices out of `0..n` (partial Fisher–Yates).
    pub fn choose(&mut self, n: usize, k: usize) -> Vec<usize> {
        let mut all: Vec<usize> = (0..n).collect();
        let k = k.min(n);
        for i in 0..k {
            let j = i + self.below(n - i);
            all.swap(i, j);
        }
        all.truncate(k);
        all
    }
}

/// How children are mutated.
#[derive(Clone, Copy, Debug)]
pub enum Mutation<'a> {
    /// Add `Normal(0, σ²)` to randomly chosen genes.
    Gaussian,
    /// Algorithm 3: of many Gaussian candidates keep the one of best estimated quality.
    Quality(&'a MutationStats),
}

/// Settings of the tree-structured GA. The defaults spend about 4 700 evaluations (the
/// authors' usual budget is ~5 000).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GaConfig {
    /// Individuals in each elementary GA.
    pub population: usize,
    /// Generations each elementary GA runs.
    pub generations: usize,
    /// Levels of the population tree (1 = a single GA).
    pub levels: usize,
    /// Children of each non-leaf GA.
    pub children: usize,
    /// Chance that a child is mutated (paper: `M_chance`).
    pub mutation_chance: f64,
    /// Share of the genes a mutation changes (paper: `M_genes`), at least one gene.
    pub mutation_genes: f64,
    /// Standard deviation of a gene's Gaussian change (genes live in `[0, 1]`).
    pub sigma: f64,
    /// Candidates Algorithm 3 tries per mutation (paper: 500).
    pub quality_steps: usize,
    /// Seed of every random choice.
    pub seed: u64,
}

impl Default for GaConfig {
    fn default() -> Self {
        GaConfig {
            population: 32,
            generations: 40,
            levels: 3,
            children: 2,
            mutation_chance: 0.3,
            mutation_genes: 0.15,
            sigma: 0.2,
            quality_steps: 500,
            seed: 1,
        }
    }
}

impl GaConfig {
    /// Number of elementary GAs in the tree.
    pub fn nodes(&self) -> usize {
        (0..self.levels).map(|l| self.children.pow(l as u32)).sum()
    }

    /// Number of fitness evaluations a run makes.
    pub fn evaluations(&self) -> usize {
        let leaves = self.children.pow(self.levels.saturating_sub(1) as u32);
        let offspring = self.population / 2;
        leaves * self.population + self.nodes() * self.generations * offspring
    }

    fn check(&self, n_genes: usize) -> Result<(), TreeError> {
        let bad = |m: String| Err(TreeError(m));
        if n_genes == 0 {
            return bad("the genome has no genes".into());
        }
        if !(2..=100_000).contains(&self.population) {
            return bad(format!(
                "population {} is not in 2..=100000",
                self.population
            ));
        }
        if self.levels == 0 || self.levels > 8 || self.children == 0 || self.children > 16 {
            return bad(format!(
                "a population tree of {} levels × {} children is not allowed (1–8 levels, 1–16 children)",
                self.levels, self.children
            ));
        }
        if self.evaluations() > 100_000_000 {
            return bad(format!("{} evaluations is too many", self.evaluations()));
        }
        for (name, v) in [
            ("mutation chance", self.mutation_chance),
            ("mutation genes", self.mutation_genes),
        ] {
            if !(0.0..=1.0).contains(&v) {
                return bad(format!("{name} {v} is not in [0, 1]"));
            }
        }
        if !(self.sigma.is_finite() && self.sigma > 0.0) {
            return bad(format!("sigma {} must be positive", self.sigma));
        }
        Ok(())
    }
}

/// A genome and its fitness.
#[derive(Clone, Debug, PartialEq)]
pub struct Individual {
    /// Genes in `[0, 1]`.
    pub genome: Vec<f64>,
    /// Fitness (≥ 0; NaN or negative values from the closure count as 0).
    pub fitness: f64,
}

/// What a GA run found.
#[derive(Clone, Debug)]
pub struct GaResult {
    /// The best individual seen.
    pub best: Individual,
    /// The last population of the root GA, best first (the paper's "small set of the best
    /// species at the topmost level").
    pub top: Vec<Individual>,
    /// Fitness evaluations made.
    pub evaluations: usize,
    /// `(evaluations so far, best fitness so far)` after every generation of every GA.
    pub history: Vec<(usize, f64)>,
}

struct Run<'a, F> {
    n: usize,
    fitness: &'a F,
    cfg: &'a GaConfig,
    mutation: Mutation<'a>,
    evaluations: usize,
    best: Option<Individual>,
    history: Vec<(usize, f64)>,
}

impl<F: Fn(&[f64]) -> f64 + Sync> Run<'_, F> {
    fn evaluate(&mut self, genomes: Vec<Vec<f64>>) -> Vec<Individual> {
        let f = self.fitness;
        let out: Vec<Individual> = genomes
            .into_par_iter()
            .map(|genome| {
                let v = f(&genome);
                let fitness = if v.is_finite() && v > 0.0 { v } else { 0.0 };
                Individual { genome, fitness }
            })
            .collect();
        self.evaluations += out.len();
        for ind in &out {
            if self.best.as_ref().is_none_or(|b| ind.fitness > b.fitness) {
                self.best = Some(ind.clone());
            }
        }
        out
    }

    fn note(&mut self) {
        let b = self.best.as_ref().map_or(0.0, |b| b.fitness);
        self.history.push((self.evaluations, b));
    }

    fn mutate(&self, g: &mut Vec<f64>, rng: &mut Rng) {
        let m = ((self.cfg.mutation_genes * self.n as f64).round() as usize).clamp(1, self.n);
        match self.mutation {
            Mutation::Gaussian => {
                for k in rng.choose(self.n, m) {
                    g[k] = (g[k] + self.cfg.sigma * rng.normal()).clamp(0.0, 1.0);
                }
            }
            Mutation::Quality(stats) => {
                *g = stats.mutate(g, m, self.cfg.sigma, self.cfg.quality_steps, rng);
            }
        }
    }

    /// One elementary GA from an evaluated population; returns its last population, best first.
    fn evolve(&mut self, mut pop: Vec<Individual>, rng: &mut Rng) -> Vec<Individual> {
        let size = self.cfg.population;
        for _ in 0..self.cfg.generations {
            sort_best_first(&mut pop);
            // Kill the weaker half.
            pop.truncate(size - size / 2);
            let total: f64 = pop.iter().map(|i| i.fitness).sum();
            let pick = |rng: &mut Rng| -> usize {
                // Fitness-proportional (roulette) choice; uniform when nobody scores.
                if total <= 0.0 {
                    return rng.below(pop.len());
                }
                let mut x = rng.unit() * total;
                for (i, ind) in pop.iter().enumerate() {
                    x -= ind.fitness;
                    if x < 0.0 {
                        return i;
                    }
                }
                pop.len() - 1
            };
            let mut children = Vec::with_capacity(size - pop.len());
            while pop.len() + children.len() < size {
                let a = &pop[pick(rng)].genome;
                let b = &pop[pick(rng)].genome;
                // One-point crossover.
                let cut = 1 + rng.below(self.n.max(2) - 1);
                let mut child: Vec<f64> = a[..cut.min(self.n)]
                    .iter()
                    .chain(&b[cut.min(self.n)..])
                    .copied()
                    .collect();
                if rng.unit() < self.cfg.mutation_chance {
                    self.mutate(&mut child, rng);
                }
                children.push(child);
            }
            let evaluated = self.evaluate(children);
            pop.extend(evaluated);
            self.note();
        }
        sort_best_first(&mut pop);
        pop
    }

    /// The GA at a node of the population tree `level` levels above the leaves.
    fn node(&mut self, level: usize, seed: u64) -> Vec<Individual> {
        let mut rng = Rng::new(seed);
        let size = self.cfg.population;
        let pop = if level == 0 {
            let genomes = (0..size)
                .map(|_| (0..self.n).map(|_| rng.unit()).collect())
                .collect();
            self.evaluate(genomes)
        } else {
            // Parents start from the best of each child's last population.
            let k = self.cfg.children;
            let share = size.div_ceil(k);
            let mut pop = Vec::with_capacity(share * k);
            for c in 0..k {
                let child_seed = rng.next_u64() ^ c as u64;
                let last = self.node(level - 1, child_seed);
                pop.extend(last.into_iter().take(share));
            }
            sort_best_first(&mut pop);
            pop.truncate(size);
            pop
        };
        self.evolve(pop, &mut rng)
    }
}

fn sort_best_first(pop: &mut [Individual]) {
    // Stable, so ties keep their order and runs stay deterministic.
    pop.sort_by(|a, b| b.fitness.total_cmp(&a.fitness));
}

/// Maximises `fitness` over `[0, 1]^n_genes` with the tree-structured GA.
pub fn tree_ga<F>(
    n_genes: usize,
    fitness: &F,
    cfg: &GaConfig,
    mutation: Mutation<'_>,
) -> Result<GaResult, TreeError>
where
    F: Fn(&[f64]) -> f64 + Sync,
{
    cfg.check(n_genes)?;
    if let Mutation::Quality(stats) = mutation
        && stats.genes() != n_genes
    {
        return Err(TreeError(format!(
            "mutation statistics are for {} genes, the genome has {n_genes}",
            stats.genes()
        )));
    }
    let mut run = Run {
        n: n_genes,
        fitness,
        cfg,
        mutation,
        evaluations: 0,
        best: None,
        history: Vec::new(),
    };
    let top = run.node(cfg.levels - 1, cfg.seed);
    let best = run
        .best
        .clone()
        .ok_or_else(|| TreeError("the GA evaluated nothing".into()))?;
    Ok(GaResult {
        best,
        top,
        evaluations: run.evaluations,
        history: run.history,
    })
}
