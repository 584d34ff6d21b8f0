//! Tree recovery (issue 8): the tree fit at its default budget recovers trees made from
//! parameter sets that are not presets, from one view, to the paper's metric (IoU-64 over
//! bounding-box-normalised turntable views, [`silhouette_iou64`]); and the resumable
//! [`TreeSession`] is deterministic however it is stepped.
//!
//! The recovery test runs three default fits of 4 896 evaluations each (about 2 minutes on 2
//! cores); measured: similarity 0.721 / 0.824 / 0.725, IoU-64 0.646 / 0.636 / 0.586 (before the
//! leaf-cluster generator and the preset-seeded, fixed-seed fit: IoU-64 ≈ 0.21). The mutation
//! comparison runs 18 small fits (about 1.5 minutes).
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "a test binary: a failed step should stop it loudly"
)]

mod tree_support;

use procfit::generators::tree::TreeGenerator;
use procfit::generators::{Generator, Lod};
use procfit::mask::LabelImage;
use procfit::tree::impostor::{
    TreeFitConfig, TreeImpostor, TreeSession, fit_tree, silhouette_iou64, tree_view,
};
use procfit::tree::mutation::MutationStats;
use procfit::tree::similarity::TreeTraits;
use tree_support::targets;

fn reference(truth: &[f64], size: u32) -> LabelImage {
    let view = tree_view(size, size, 12.0).expect("view");
    let mut imp = TreeImpostor::new(view).expect("impostor");
    imp.render(&TreeGenerator.generate(truth, Lod::Low).expect("tree"))
        .expect("renders")
}

#[test]
fn default_fit_recovers_non_preset_trees() {
    let g = TreeGenerator;
    let view = tree_view(128, 128, 12.0).expect("view");
    let cfg = TreeFitConfig::default();
    for (name, truth) in targets() {
        // The default fit: Gaussian mutation (see the last test).
        let fit = fit_tree(
            &reference(&truth, 128),
            TreeTraits::default(),
            view,
            &cfg,
            None,
        )
        .expect("fits");
        let iou = silhouette_iou64(
            &g.generate(&truth, Lod::Medium).expect("truth"),
            &g.generate(&fit.params, Lod::Medium).expect("fit"),
            128,
        )
        .expect("iou");
        println!("{name}: similarity {:.3}, IoU-64 {iou:.3}", fit.similarity);
        assert_eq!(fit.ga.evaluations, cfg.evaluations());
        assert!(
            fit.similarity >= 0.6,
            "{name}: similarity {}",
            fit.similarity
        );
        assert!(iou >= 0.55, "{name}: IoU-64 {iou}");
    }
}

#[test]
fn session_is_deterministic_however_stepped() {
    let truth = &targets()[1].1;
    let view = tree_view(64, 64, 12.0).expect("view");
    let reference = reference(truth, 64);
    let mut cfg = TreeFitConfig::default();
    cfg.ga.population = 8;
    cfg.ga.generations = 3;
    cfg.ga.levels = 2;
    cfg.seed_trials = 4;
    cfg.polish = 32;
    let stats = MutationStats::tree().expect("stats");
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool")
            .install(|| {
                let mut s =
                    TreeSession::new(&reference, TreeTraits::default(), view, &cfg, Some(&stats))
                        .expect("starts");
                let mut steps = Vec::new();
                loop {
                    let p = s.step();
                    assert!(p.evaluations <= p.total_evaluations);
                    assert!(p.preview.iter().all(|l| l.width() == 64));
                    steps.push((p.stage, p.evaluations, p.best_similarity));
                    if p.done {
                        break;
                    }
                }
                (steps, s.result().expect("result"))
            })
    };
    let (a, fa) = run(1);
    let (b, fb) = run(2);
    assert_eq!(a, b);
    assert_eq!(fa.params, fb.params);
    // Progress only climbs, every stage shows up, the count is the configured one.
    assert!(a.windows(2).all(|w| w[1].2 >= w[0].2 && w[1].1 >= w[0].1));
    for stage in 1..=3 {
        assert!(a.iter().any(|s| s.0 == stage), "stage {stage} missing");
    }
    assert_eq!(fa.ga.evaluations, cfg.evaluations());
    let same = fit_tree(&reference, TreeTraits::default(), view, &cfg, Some(&stats)).expect("fits");
    assert_eq!(same.params, fa.params);
    assert_eq!(same.similarity, fa.similarity);
}

/// Issue 8 asks whether Algorithm 3 mutation beats plain Gaussian mutation on the real tree
/// fit. Measured here (3 trees × 3 seeds, 5 generations ≈ 650 GA evaluations, 96², no seed
/// trials or local search): it does not — mean best similarity Gaussian 0.620, Algorithm 3
/// 0.583. Over 9 seeds (`cargo bench --bench tree -- --mutation`) the paired difference is
/// −0.011 ± 0.010 from presets and −0.028 ± 0.012 from all-random starts; the variants tried
/// are listed in `procfit::tree::mutation`'s module doc. So the fit's default is Gaussian, and
/// this test fails if that stops being the better choice.
#[test]
fn gaussian_mutation_is_the_better_default_on_trees() {
    let view = tree_view(96, 96, 12.0).expect("view");
    let stats = MutationStats::tree().expect("stats");
    let (mut gauss, mut quality) = (0.0, 0.0);
    let mut runs = 0.0;
    for (_, truth) in targets() {
        let reference = reference(&truth, 96);
        for seed in 1..=3 {
            let mut cfg = TreeFitConfig::default();
            cfg.ga.generations = 5;
            cfg.ga.seed = seed;
            cfg.seed_trials = 0;
            cfg.polish = 0;
            let fit = |m| {
                fit_tree(&reference, TreeTraits::default(), view, &cfg, m)
                    .expect("fits")
                    .similarity
            };
            gauss += fit(None);
            quality += fit(Some(&stats));
            runs += 1.0;
        }
    }
    let (gauss, quality) = (gauss / runs, quality / runs);
    println!("mean best similarity: gaussian {gauss:.4}, algorithm 3 {quality:.4}");
    assert!(
        gauss >= quality,
        "algorithm 3 ({quality:.4}) now beats gaussian ({gauss:.4}): make it the default"
    );
}
