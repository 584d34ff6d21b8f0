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
//! The run is resumable ([`TreeGa`]): each [`TreeGa::step`] makes one batch of evaluations (a
//! leaf's first population or one generation), so a fit can report progress and be cancelled
//! between batches. Leaf GAs may be seeded with start genomes (the tree fit uses the presets)
//! besides random ones.
//!
//! Determinism: all random numbers come from one seeded stream per node, drawn on the calling
//! thread; only fitness evaluation runs in parallel (rayon, order-preserving), so a seed gives
//! the same result on any number of threads and however the run is stepped.

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

/// Settings of the tree-structured GA. The defaults spend 4 608 evaluations ([`Self::evaluations`];
/// 4 896 with a tree fit's seed trials and local search; the authors' usual budget is ~5 000).
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

    /// Generations per elementary GA for about `budget` evaluations in all (at least 1).
    pub fn generations_for(&self, budget: usize) -> usize {
        let first = self.children.pow(self.levels.saturating_sub(1) as u32) * self.population;
        let per_generation = (self.nodes() * (self.population / 2)).max(1);
        (budget.saturating_sub(first) / per_generation).max(1)
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

/// How far each gene of a start genome is jittered (standard deviation) when it seeds a leaf
/// GA, so the leaves do not all begin from the same few points.
pub const START_JITTER: f64 = 0.05;

/// One elementary GA of the population tree, while it runs.
struct Frame {
    /// Levels above the leaves.
    level: usize,
    /// Its random stream: child seeds first, then the leaf's genomes, then evolution.
    rng: Rng,
    child_seeds: Vec<u64>,
    next_child: usize,
    pop: Vec<Individual>,
    started: bool,
    generation: usize,
}

impl Frame {
    fn new(level: usize, seed: u64, children: usize) -> Frame {
        let mut rng = Rng::new(seed);
        let child_seeds = if level > 0 {
            (0..children).map(|c| rng.next_u64() ^ c as u64).collect()
        } else {
            Vec::new()
        };
        Frame {
            level,
            rng,
            child_seeds,
            next_child: 0,
            pop: Vec::new(),
            started: false,
            generation: 0,
        }
    }
}

/// The tree-structured GA as a resumable computation: [`TreeGa::step`] does one batch of
/// fitness evaluations (a leaf GA's first population or one generation of one GA) and returns,
/// so a caller can report progress and stop between batches. [`tree_ga`] runs it to the end.
/// The elementary GAs run depth first (children before their parent), exactly as the
/// recursive description; a seed gives the same run however it is stepped.
pub struct TreeGa {
    n: usize,
    cfg: GaConfig,
    stats: Option<MutationStats>,
    start: Vec<Vec<f64>>,
    leaves_started: usize,
    evaluations: usize,
    generations_done: usize,
    best: Option<Individual>,
    history: Vec<(usize, f64)>,
    stack: Vec<Frame>,
    top: Option<Vec<Individual>>,
}

impl TreeGa {
    /// A GA over `n_genes` genes. `start`: genomes (genes in `[0, 1]`) that seed the leaf GAs
    /// besides random ones — up to half of each leaf's population, taken in turn from the
    /// list and jittered by [`START_JITTER`]; empty for the paper's all-random start. Errors on
    /// bad settings, statistics for another genome length or a start genome of another length.
    pub fn new(
        n_genes: usize,
        cfg: &GaConfig,
        mutation: Mutation<'_>,
        start: &[Vec<f64>],
    ) -> Result<TreeGa, TreeError> {
        cfg.check(n_genes)?;
        let stats = match mutation {
            Mutation::Gaussian => None,
            Mutation::Quality(stats) => {
                if stats.genes() != n_genes {
                    return Err(TreeError(format!(
                        "mutation statistics are for {} genes, the genome has {n_genes}",
                        stats.genes()
                    )));
                }
                Some(stats.clone())
            }
        };
        if let Some(g) = start
            .iter()
            .find(|g| g.len() != n_genes || g.iter().any(|x| !x.is_finite()))
        {
            return Err(TreeError(format!(
                "a start genome has {} genes (or a non-finite one), the GA {n_genes}",
                g.len()
            )));
        }
        Ok(TreeGa {
            n: n_genes,
            cfg: *cfg,
            stats,
            start: start.to_vec(),
            leaves_started: 0,
            evaluations: 0,
            generations_done: 0,
            best: None,
            history: Vec::new(),
            stack: vec![Frame::new(cfg.levels - 1, cfg.seed, cfg.children)],
            top: None,
        })
    }

    /// Whether the run is over.
    pub fn done(&self) -> bool {
        self.top.is_some()
    }

    /// Fitness evaluations made so far.
    pub fn evaluations(&self) -> usize {
        self.evaluations
    }

    /// Generations run so far, over all elementary GAs.
    pub fn generations(&self) -> usize {
        self.generations_done
    }

    /// The best individual seen so far.
    pub fn best(&self) -> Option<&Individual> {
        self.best.as_ref()
    }

    /// One batch of evaluations; returns whether the run is over (then a no-op).
    pub fn step<F: Fn(&[f64]) -> f64 + Sync>(&mut self, fitness: &F) -> bool {
        let size = self.cfg.population;
        loop {
            let Some(mut frame) = self.stack.pop() else {
                return true;
            };
            if frame.level > 0 && frame.next_child < frame.child_seeds.len() {
                let seed = frame.child_seeds[frame.next_child];
                let level = frame.level - 1;
                frame.next_child += 1;
                self.stack.push(frame);
                self.stack.push(Frame::new(level, seed, self.cfg.children));
                continue;
            }
            if !frame.started {
                frame.started = true;
                if frame.level == 0 {
                    let genomes = self.leaf_genomes(&mut frame.rng);
                    frame.pop = self.evaluate(genomes, fitness);
                    self.stack.push(frame);
                    return false;
                }
                // Parents start from the best of each child's last population.
                sort_best_first(&mut frame.pop);
                frame.pop.truncate(size);
            }
            if frame.generation < self.cfg.generations {
                self.generation(&mut frame.pop, &mut frame.rng, fitness);
                frame.generation += 1;
                self.generations_done += 1;
                self.note();
                self.stack.push(frame);
                return false;
            }
            sort_best_first(&mut frame.pop);
            match self.stack.last_mut() {
                Some(parent) => {
                    let share = size.div_ceil(self.cfg.children);
                    parent.pop.extend(frame.pop.into_iter().take(share));
                }
                None => {
                    self.top = Some(frame.pop);
                    return true;
                }
            }
        }
    }

    /// What the run found (so far, if it is not over: then `top` is empty).
    pub fn result(&self) -> Result<GaResult, TreeError> {
        let best = self
            .best
            .clone()
            .ok_or_else(|| TreeError("the GA evaluated nothing".into()))?;
        Ok(GaResult {
            best,
            top: self.top.clone().unwrap_or_default(),
            evaluations: self.evaluations,
            history: self.history.clone(),
        })
    }

    /// A leaf GA's first genomes: start genomes (jittered) for up to half, the rest random.
    fn leaf_genomes(&mut self, rng: &mut Rng) -> Vec<Vec<f64>> {
        let size = self.cfg.population;
        let seeded = if self.start.is_empty() { 0 } else { size / 2 };
        let offset = self.leaves_started * seeded;
        self.leaves_started += 1;
        (0..size)
            .map(|i| {
                if i < seeded {
                    let s = &self.start[(offset + i) % self.start.len()];
                    s.iter()
                        .map(|&x| (x + START_JITTER * rng.normal()).clamp(0.0, 1.0))
                        .collect()
                } else {
                    (0..self.n).map(|_| rng.unit()).collect()
                }
            })
            .collect()
    }

    fn evaluate<F: Fn(&[f64]) -> f64 + Sync>(
        &mut self,
        genomes: Vec<Vec<f64>>,
        f: &F,
    ) -> Vec<Individual> {
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
        match &self.stats {
            None => {
                for k in rng.choose(self.n, m) {
                    g[k] = (g[k] + self.cfg.sigma * rng.normal()).clamp(0.0, 1.0);
                }
            }
            Some(stats) => {
                *g = stats.mutate(g, m, self.cfg.sigma, self.cfg.quality_steps, rng);
            }
        }
    }

    /// One generation of an elementary GA: kill the weaker half, refill it with mutated
    /// one-point crossovers of fitness-proportionally chosen survivors.
    fn generation<F: Fn(&[f64]) -> f64 + Sync>(
        &mut self,
        pop: &mut Vec<Individual>,
        rng: &mut Rng,
        fitness: &F,
    ) {
        let size = self.cfg.population;
        sort_best_first(pop);
        // Kill the weaker half.
        pop.truncate(size - size / 2);
        let total: f64 = pop.iter().map(|i| i.fitness).sum();
        let pick = |rng: &mut Rng, pop: &[Individual]| -> usize {
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
            let a = &pop[pick(rng, pop)].genome;
            let b = &pop[pick(rng, pop)].genome;
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
        let evaluated = self.evaluate(children, fitness);
        pop.extend(evaluated);
    }
}

fn sort_best_first(pop: &mut [Individual]) {
    // Stable, so ties keep their order and runs stay deterministic.
    pop.sort_by(|a, b| b.fitness.total_cmp(&a.fitness));
}

/// Maximises `fitness` over `[0, 1]^n_genes` with the tree-structured GA (all leaf GAs start
/// random): [`TreeGa`] run to the end.
pub fn tree_ga<F>(
    n_genes: usize,
    fitness: &F,
    cfg: &GaConfig,
    mutation: Mutation<'_>,
) -> Result<GaResult, TreeError>
where
    F: Fn(&[f64]) -> f64 + Sync,
{
    let mut ga = TreeGa::new(n_genes, cfg, mutation, &[])?;
    while !ga.step(fitness) {}
    ga.result()
}
