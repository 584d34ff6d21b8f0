//! Tree benchmark (not a test): generator time per preset and LOD, impostor render time, GA
//! evaluations per second on 1 and 2 threads, the IoU-64 ceiling (a tree against the same
//! parameters under another seed, and LOW against MEDIUM), and tree reconstructions at the
//! default budget (the default Gaussian against Algorithm 3 mutation) with their similarity,
//! the paper's IoU-64 ([`silhouette_iou64`]: bounding-box normalised, 64 turntable views, 128²,
//! MEDIUM meshes) and wall time on 2 threads. The paper took 29 min; the target is ≤ 60 s.
//!
//! `cargo bench --bench tree` prints markdown tables; `-- --quick` cuts the GA budget by 4 and
//! skips Algorithm 3 for a fast look; `-- --mutation` adds the full comparison of Algorithm 3
//! against Gaussian mutation (27 short fits per setting and 9 default fits per mutation, about
//! ten minutes on 2 cores).
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "a benchmark binary: a failed workload should stop it loudly"
)]

#[path = "../tests/tree_support/mod.rs"]
mod tree_support;

use procfit::generators::tree::{TreeGenerator, idx};
use procfit::generators::{Generator, Lod};
use procfit::tree::ga::GaConfig;
use procfit::tree::impostor::{TreeFitConfig, TreeImpostor, fit_tree, silhouette_iou64, tree_view};
use procfit::tree::mutation::MutationStats;
use procfit::tree::similarity::TreeTraits;
use std::time::Instant;
use tree_support::targets;

fn median_ms(runs: usize, mut f: impl FnMut()) -> f64 {
    let mut t: Vec<f64> = (0..runs)
        .map(|_| {
            let s = Instant::now();
            f();
            s.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    t.sort_by(f64::total_cmp);
    t[runs / 2]
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let quick = std::env::args().any(|a| a == "--quick");
    let mutation_table = std::env::args().any(|a| a == "--mutation");
    let g = TreeGenerator;

    println!("## Generator: milliseconds per tree (median)\n");
    println!("| preset | LOW | MEDIUM | HIGH | ULTRA | triangles LOW / ULTRA |");
    println!("|---|---|---|---|---|---|");
    for p in g.presets() {
        let mut row = format!("| {} |", p.name);
        for lod in Lod::ALL {
            let runs = if lod == Lod::Low { 21 } else { 5 };
            let ms = median_ms(runs, || {
                let _ = g.generate(&p.values, lod);
            });
            row += &format!(" {ms:.2} |");
        }
        let lo = g.generate(&p.values, Lod::Low)?.triangles.len();
        let hi = g.generate(&p.values, Lod::Ultra)?.triangles.len();
        println!("{row} {lo} / {hi} |");
    }

    let size = 128;
    let view = tree_view(size, size, 12.0)?;
    println!("\n## Impostor (two coverage renders, {size}²): milliseconds per tree (median)\n");
    println!("| preset | generate + render |");
    println!("|---|---|");
    let mut imp = TreeImpostor::new(view)?;
    for p in g.presets() {
        let ms = median_ms(11, || {
            if let Ok(m) = g.generate(&p.values, Lod::Low) {
                let _ = imp.render(&m);
            }
        });
        println!("| {} | {ms:.2} |", p.name);
    }

    let stats = MutationStats::tree()?;
    let (name0, truth0) = &targets()[0];
    let reference0 = imp.render(&g.generate(truth0, Lod::Low)?)?;
    println!("\n## GA throughput on `{name0}` ({size}², LOW)\n");
    println!("| threads | evaluations | seconds | evaluations / s |");
    println!("|---|---|---|---|");
    let small = TreeFitConfig {
        ga: GaConfig {
            population: 16,
            generations: 6,
            levels: 2,
            ..GaConfig::default()
        },
        ..TreeFitConfig::default()
    };
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()?;
        let t = Instant::now();
        let fit =
            pool.install(|| fit_tree(&reference0, TreeTraits::default(), view, &small, None))?;
        let s = t.elapsed().as_secs_f64();
        println!(
            "| {threads} | {} | {s:.2} | {:.0} |",
            fit.ga.evaluations,
            fit.ga.evaluations as f64 / s
        );
    }

    println!("\n## IoU-64 ceiling (128², MEDIUM unless said)\n");
    println!("| tree | same params, seed + 123 | LOW vs MEDIUM |");
    println!("|---|---|---|");
    for (name, truth) in targets() {
        let m = g.generate(&truth, Lod::Medium)?;
        let mut other = truth.clone();
        other[idx::SEED] = (truth[idx::SEED] + 123.0) % 999.0;
        let seed_iou = silhouette_iou64(&m, &g.generate(&other, Lod::Medium)?, 128)?;
        let lod_iou = silhouette_iou64(&m, &g.generate(&truth, Lod::Low)?, 128)?;
        println!("| {name} | {seed_iou:.3} | {lod_iou:.3} |");
    }

    let mut cfg = TreeFitConfig::default();
    if quick {
        cfg.ga.generations /= 4;
    }
    println!(
        "\n## Reconstruction ({} evaluations, {size}², 2 threads, IoU-64 at 128² on MEDIUM)\n",
        cfg.evaluations()
    );
    println!("| tree | mutation | similarity | IoU-64 | seconds |");
    println!("|---|---|---|---|---|");
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build()?;
    let mut sums = [(0.0, 0.0); 2];
    for (name, truth) in targets() {
        let reference = imp.render(&g.generate(&truth, Lod::Low)?)?;
        let truth_mesh = g.generate(&truth, Lod::Medium)?;
        let mutations: &[Option<&MutationStats>] = if quick {
            &[None]
        } else {
            &[None, Some(&stats)]
        };
        for (k, &mutation) in mutations.iter().enumerate() {
            let t = Instant::now();
            let fit =
                pool.install(|| fit_tree(&reference, TreeTraits::default(), view, &cfg, mutation))?;
            let s = t.elapsed().as_secs_f64();
            let fit_mesh = g.generate(&fit.params, Lod::Medium)?;
            let iou = silhouette_iou64(&truth_mesh, &fit_mesh, 128)?;
            let label = if k == 0 { "gaussian" } else { "algorithm 3" };
            println!(
                "| {name} | {label} | {:.3} | {iou:.3} | {s:.1} |",
                fit.similarity
            );
            sums[k].0 += fit.similarity / 3.0;
            sums[k].1 += iou / 3.0;
        }
    }
    println!(
        "| **mean** | gaussian | {:.3} | {:.3} | |",
        sums[0].0, sums[0].1
    );
    println!(
        "| **mean** | algorithm 3 | {:.3} | {:.3} | |",
        sums[1].0, sums[1].1
    );
    if mutation_table {
        compare_mutations(&stats)?;
    }
    Ok(())
}

/// Mean and standard error.
fn mean_se(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    (m, (var / n).sqrt())
}

/// Algorithm 3 against Gaussian mutation, over 3 trees × 9 GA seeds at a short budget (the
/// GA alone, 96²) from preset-seeded and from all-random starts, and over 3 trees × 3 seeds
/// at the default budget with the paper's IoU-64.
fn compare_mutations(stats: &MutationStats) -> Result<(), Box<dyn std::error::Error>> {
    let g = TreeGenerator;
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build()?;
    let short = tree_view(96, 96, 12.0)?;
    let mut imp = TreeImpostor::new(short)?;
    let refs: Vec<_> = targets()
        .iter()
        .map(|(_, t)| imp.render(&g.generate(t, Lod::Low)?).map_err(Into::into))
        .collect::<Result<_, Box<dyn std::error::Error>>>()?;
    let arms: [(&str, bool, Option<usize>); 5] = [
        ("from presets", true, None),
        ("from presets", true, Some(500)),
        ("from presets", true, Some(20)),
        ("all random (paper)", false, None),
        ("all random (paper)", false, Some(500)),
    ];
    let mut cfg = TreeFitConfig::default();
    cfg.ga.generations = 5;
    cfg.seed_trials = 0;
    cfg.polish = 0;
    println!(
        "\n## Mutation: best similarity, 3 trees × 9 seeds, {} GA evaluations, 96²\n",
        cfg.evaluations()
    );
    println!("| start | mutation | mean ± s.e. | minus gaussian (paired by tree and seed) |");
    println!("|---|---|---|---|");
    let mut gauss: Vec<f64> = Vec::new();
    for (start, presets, candidates) in arms {
        let mut v = Vec::new();
        for reference in &refs {
            for seed in 1..=9 {
                let mut c = cfg;
                c.start_from_presets = presets;
                c.ga.seed = seed;
                c.ga.quality_steps = candidates.unwrap_or(0);
                let m = candidates.map(|_| stats);
                v.push(
                    pool.install(|| fit_tree(reference, TreeTraits::default(), short, &c, m))?
                        .similarity,
                );
            }
        }
        let label = match candidates {
            None => "gaussian".to_string(),
            Some(k) => format!("algorithm 3, {k} candidates"),
        };
        if candidates.is_none() {
            gauss = v.clone();
        }
        let (m, se) = mean_se(&v);
        let d: Vec<f64> = v.iter().zip(&gauss).map(|(a, b)| a - b).collect();
        let (dm, dse) = mean_se(&d);
        println!("| {start} | {label} | {m:.3} ± {se:.3} | {dm:+.3} ± {dse:.3} |");
    }

    let size = 128;
    let view = tree_view(size, size, 12.0)?;
    let mut imp = TreeImpostor::new(view)?;
    let cfg = TreeFitConfig::default();
    println!(
        "\n## Mutation at the default budget ({} evaluations, {size}²): 3 trees × 3 seeds\n",
        cfg.evaluations()
    );
    println!("| mutation | similarity mean ± s.e. | IoU-64 mean ± s.e. |");
    println!("|---|---|---|");
    for m in [None, Some(stats)] {
        let (mut sim, mut iou) = (Vec::new(), Vec::new());
        for (_, truth) in targets() {
            let reference = imp.render(&g.generate(&truth, Lod::Low)?)?;
            let truth_mesh = g.generate(&truth, Lod::Medium)?;
            for seed in 1..=3 {
                let mut c = cfg;
                c.ga.seed = seed;
                let fit =
                    pool.install(|| fit_tree(&reference, TreeTraits::default(), view, &c, m))?;
                sim.push(fit.similarity);
                iou.push(silhouette_iou64(
                    &truth_mesh,
                    &g.generate(&fit.params, Lod::Medium)?,
                    128,
                )?);
            }
        }
        let ((s, sse), (i, ise)) = (mean_se(&sim), mean_se(&iou));
        let label = if m.is_none() {
            "gaussian"
        } else {
            "algorithm 3"
        };
        println!("| {label} | {s:.3} ± {sse:.3} | {i:.3} ± {ise:.3} |");
    }
    Ok(())
}
