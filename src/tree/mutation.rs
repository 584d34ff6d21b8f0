//! Algorithm 3 of the paper (§3.5.2): genome quality estimation from statistics pre-collected
//! over random genomes, and the mutation that keeps, of many Gaussian candidates, the one of
//! best estimated quality.
//!
//! For gene `i` and bucket `j` (of `B` equal buckets of `[0, 1]`), `P_ij` is how often a random
//! genome whose gene `i` falls in bucket `j` scores above `ε`, and `P_0` how often any genome
//! does; the bucket's mark is `Q_ij = sign(P_ij − P_0) · max(P_ij, P_0) / min(P_ij, P_0)` and a
//! genome's quality is the sum of its genes' marks. `P_ij` is smoothed towards `P_0` by two
//! pseudo-samples so an empty or unlucky bucket gets a finite mark (the paper's ratio is
//! infinite when `P_ij = 0`).
//!
//! The statistics for the tree generator are stored in `mutation_stats.json` next to this file
//! ([`MutationStats::tree`]), made by `procfit tree-stats` ([`tree_stats`]); a test regenerates
//! them and fails when the generator has changed without them.

use super::ga::Rng;
use super::{TreeError, genome_to_params};
use crate::generators::tree::{self as treegen, Skeleton};
use crate::generators::{Generator, Lod};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Per-gene, per-bucket marks of Algorithm 3.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MutationStats {
    /// What the statistics were collected for (e.g. `tree v1, skeleton proxy`).
    pub source: String,
    /// Buckets per gene (paper: `B` = 16).
    pub buckets: usize,
    /// Fitness above which a genome counts as good (paper: `ε` = 0.001).
    pub eps: f64,
    /// Number of random genomes the statistics come from.
    pub samples: usize,
    /// Seed of the random genomes.
    pub seed: u64,
    /// Share of good genomes overall (`P_0`).
    pub p0: f64,
    /// `marks[i][j]`: the mark `Q_ij` of bucket `j` of gene `i`.
    pub marks: Vec<Vec<f64>>,
}

/// Pseudo-samples pulling a bucket's rate towards `P_0`.
const PRIOR: f64 = 2.0;

impl MutationStats {
    /// Statistics from evaluated genomes (all of the same length, genes in `[0, 1]`).
    pub fn from_samples(
        source: &str,
        genomes: &[Vec<f64>],
        values: &[f64],
        buckets: usize,
        eps: f64,
        seed: u64,
    ) -> Result<MutationStats, TreeError> {
        let n = genomes.first().map_or(0, Vec::len);
        if genomes.is_empty() || n == 0 {
            return Err(TreeError("no genomes to collect statistics from".into()));
        }
        if genomes.len() != values.len() {
            return Err(TreeError(format!(
                "{} genomes but {} fitness values",
                genomes.len(),
                values.len()
            )));
        }
        if !(1..=1024).contains(&buckets) {
            return Err(TreeError(format!("{buckets} buckets; use 1..=1024")));
        }
        if genomes.iter().any(|g| g.len() != n) {
            return Err(TreeError("genomes of different lengths".into()));
        }
        let good = |v: f64| v.is_finite() && v > eps;
        let total = genomes.len() as f64;
        let p0 = values.iter().filter(|&&v| good(v)).count() as f64 / total;
        let mut hits = vec![vec![0.0; buckets]; n];
        let mut counts = vec![vec![0.0; buckets]; n];
        for (g, &v) in genomes.iter().zip(values) {
            for (i, &x) in g.iter().enumerate() {
                let j = bucket(x, buckets);
                counts[i][j] += 1.0;
                if good(v) {
                    hits[i][j] += 1.0;
                }
            }
        }
        let marks = hits
            .iter()
            .zip(&counts)
            .map(|(h, c)| {
                h.iter()
                    .zip(c)
                    .map(|(&h, &c)| {
                        let p = (h + PRIOR * p0) / (c + PRIOR);
                        mark(p, p0)
                    })
                    .collect()
            })
            .collect();
        Ok(MutationStats {
            source: source.to_string(),
            buckets,
            eps,
            samples: genomes.len(),
            seed,
            p0,
            marks,
        })
    }

    /// Evaluates `f` on `samples` random genomes (in parallel, deterministic for `seed`) and
    /// collects their statistics.
    pub fn collect<F>(
        source: &str,
        n_genes: usize,
        samples: usize,
        seed: u64,
        buckets: usize,
        eps: f64,
        f: &F,
    ) -> Result<MutationStats, TreeError>
    where
        F: Fn(&[f64]) -> f64 + Sync,
    {
        let genomes = random_genomes(n_genes, samples, seed);
        let values: Vec<f64> = genomes.par_iter().map(|g| f(g)).collect();
        MutationStats::from_samples(source, &genomes, &values, buckets, eps, seed)
    }

    /// Number of genes the statistics describe.
    pub fn genes(&self) -> usize {
        self.marks.len()
    }

    /// QualityEst of Algorithm 3: the sum of the genome's bucket marks.
    pub fn quality(&self, genome: &[f64]) -> f64 {
        genome
            .iter()
            .zip(&self.marks)
            .map(|(&x, m)| m[bucket(x, self.buckets)])
            .sum()
    }

    /// Mutation of Algorithm 3: `steps` times, change `m_genes` random genes of `genome` by
    /// `Normal(0, σ²)` (clamped to `[0, 1]`) and keep the candidate of highest estimated
    /// quality (ties go to the later one, as in the paper's `Q' ≥ Q_best`).
    pub fn mutate(
        &self,
        genome: &[f64],
        m_genes: usize,
        sigma: f64,
        steps: usize,
        rng: &mut Rng,
    ) -> Vec<f64> {
        let n = genome.len();
        let mut best = genome.to_vec();
        let mut q_best = self.quality(genome);
        let mut cand = genome.to_vec();
        for _ in 0..steps {
            cand.copy_from_slice(genome);
            for k in rng.choose(n, m_genes) {
                cand[k] = (cand[k] + sigma * rng.normal()).clamp(0.0, 1.0);
            }
            let q = self.quality(&cand);
            if q >= q_best {
                q_best = q;
                best.copy_from_slice(&cand);
            }
        }
        best
    }

    /// JSON text of the statistics.
    pub fn to_json(&self) -> String {
        // A struct of numbers and strings always serialises.
        serde_json::to_string(self).unwrap_or_default()
    }

    /// Statistics from JSON text, checked for shape.
    pub fn from_json(text: &str) -> Result<MutationStats, TreeError> {
        let s: MutationStats = serde_json::from_str(text)
            .map_err(|e| TreeError(format!("mutation statistics JSON: {e}")))?;
        if s.marks.is_empty()
            || s.marks.iter().any(|m| m.len() != s.buckets)
            || s.marks.iter().flatten().any(|v| !v.is_finite())
        {
            return Err(TreeError(
                "mutation statistics: every gene needs one finite mark per bucket".into(),
            ));
        }
        Ok(s)
    }

    /// The stored statistics of the tree generator.
    pub fn tree() -> Result<MutationStats, TreeError> {
        MutationStats::from_json(STORED_TREE_STATS)
    }
}

/// The stored statistics file of the tree generator, as text.
pub const STORED_TREE_STATS: &str = include_str!("mutation_stats.json");

fn bucket(x: f64, buckets: usize) -> usize {
    // ⌊G_i · B⌋ of Algorithm 3, with G_i = 1 in the last bucket.
    ((x.clamp(0.0, 1.0) * buckets as f64) as usize).min(buckets - 1)
}

fn mark(p: f64, p0: f64) -> f64 {
    let (lo, hi) = (p.min(p0), p.max(p0));
    if lo <= 0.0 || (p - p0).abs() < 1e-12 {
        0.0
    } else {
        (p - p0).signum() * hi / lo
    }
}

/// `count` genomes with genes uniform in `[0, 1)`, from `seed`.
pub fn random_genomes(n_genes: usize, count: usize, seed: u64) -> Vec<Vec<f64>> {
    let mut rng = Rng::new(seed);
    (0..count)
        .map(|_| (0..n_genes).map(|_| rng.unit()).collect())
        .collect()
}

/// Characteristics of a tree that need no rendering: height, horizontal extent, leaf area,
/// wood volume and branch-graph vertex count.
pub fn skeleton_characteristics(sk: &Skeleton) -> [f64; 5] {
    let mut lo = glam::Vec3::splat(f32::MAX);
    let mut hi = glam::Vec3::splat(f32::MIN);
    for s in &sk.stems {
        for &p in &s.points {
            lo = lo.min(p);
            hi = hi.max(p);
        }
    }
    for &(p, d, _) in &sk.leaves {
        for q in [p, p + d * sk.leaf_dims.x] {
            lo = lo.min(q);
            hi = hi.max(q);
        }
    }
    if sk.stems.is_empty() {
        return [0.0; 5];
    }
    let ext = hi - lo;
    let leaf_area = sk.leaves.len() as f64 * f64::from(sk.leaf_dims.x * sk.leaf_dims.y);
    let wood: f64 = sk
        .stems
        .iter()
        .map(|s| f64::from(s.length * s.radii[0] * s.radii[0]))
        .sum();
    [
        f64::from(ext.y),
        f64::from(ext.x.max(ext.z)),
        leaf_area,
        wood,
        sk.graph_vertices() as f64,
    ]
}

/// Settings of the stored tree statistics: samples, seed, buckets `B` and `ε` (the paper's
/// `B` = 16, `ε` = 0.001; with it about a third of random genomes count as good).
pub const TREE_STATS_SETTINGS: (usize, u64, usize, f64) = (10_000, 2024, 16, 0.001);

/// The objective family the stored statistics are collected over, until trees are rendered to
/// label images: genome `k` is scored against preset `k mod 6` by the product of
/// `min/max` ratios of [`skeleton_characteristics`] (the same regularisation factors as
/// eq. 3, on the 3D tree instead of its impostor). It tells the same thing Algorithm 3 needs:
/// which regions of each gene tend to give trees that resemble some real species at all.
pub fn tree_stats() -> Result<MutationStats, TreeError> {
    let g = &treegen::TreeGenerator;
    let spec = g.params();
    let refs: Vec<[f64; 5]> = g
        .presets()
        .iter()
        .map(|p| treegen::skeleton(&p.values, Lod::Low).map(|s| skeleton_characteristics(&s)))
        .collect::<Result<_, _>>()?;
    let (samples, seed, buckets, eps) = TREE_STATS_SETTINGS;
    let genomes = random_genomes(spec.len(), samples, seed);
    let values: Vec<f64> = genomes
        .par_iter()
        .enumerate()
        .map(|(k, genome)| {
            let Ok(params) = genome_to_params(spec, genome) else {
                return 0.0;
            };
            let Ok(sk) = treegen::skeleton(&params, Lod::Low) else {
                return 0.0;
            };
            let c = skeleton_characteristics(&sk);
            let r = &refs[k % refs.len()];
            c.iter()
                .zip(r)
                .map(|(&a, &b)| super::similarity::ratio_factor(a, b))
                .product()
        })
        .collect();
    let source = format!(
        "{} v{}: skeleton characteristics against presets",
        g.name(),
        g.version()
    );
    MutationStats::from_samples(&source, &genomes, &values, buckets, eps, seed)
}
