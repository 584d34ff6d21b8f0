//! "Refit from here" for trees ([`TreeSession::with_start`]): a fit started from a tree keeps
//! that tree's seed and never ends less similar than it — from the truth it keeps the truth,
//! which a fit from scratch on the same budget does not find — and a start that is not a
//! tree's parameters is refused, not a panic.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "a test binary: a failed step should stop it loudly"
)]

use procfit::generators::tree::{TreeGenerator, idx};
use procfit::generators::{Generator, Lod};
use procfit::mask::LabelImage;
use procfit::tree::ga::GaConfig;
use procfit::tree::impostor::{
    TreeFit, TreeFitConfig, TreeImpostor, TreeSession, start_photo_fit, tree_view,
};
use procfit::tree::similarity::{TreeReference, TreeTraits};

const SIZE: u32 = 64;

fn preset(name: &str) -> Vec<f64> {
    TreeGenerator.preset(name).expect("preset").values
}

/// Not a preset: an oak with another seed and proportions.
fn truth() -> Vec<f64> {
    let mut t = preset("oak");
    t[idx::SEED] = 77.0;
    t[idx::HEIGHT] = 10.0;
    t[idx::SHAPE] = 1.0;
    t
}

fn render(values: &[f64]) -> LabelImage {
    let view = tree_view(SIZE, SIZE, 12.0).expect("view");
    let mut imp = TreeImpostor::new(view).expect("impostor");
    imp.render(&TreeGenerator.generate(values, Lod::Low).expect("tree"))
        .expect("renders")
}

/// A small fit: 2 leaf GAs of 8 for 3 generations, the seed trials, 32 local-search steps.
fn small() -> TreeFitConfig {
    TreeFitConfig {
        ga: GaConfig {
            population: 8,
            generations: 3,
            levels: 2,
            seed: 3,
            ..GaConfig::default()
        },
        polish: 32,
        ..TreeFitConfig::default()
    }
}

/// The similarity of `values`' impostor to `reference`, computed here, not by the session.
fn similarity(reference: &LabelImage, values: &[f64]) -> f64 {
    TreeReference::new(reference, TreeTraits::default(), small().similarity)
        .expect("reference")
        .similarity(&render(values), &TreeTraits::default())
        .expect("similarity")
}

/// Runs a session to the end; also checks that its reported best never drops below `floor`
/// after the first step, that it counts its evaluations as it announced them, and that it
/// reports the start's similarity as `floor` (the caller's own computation).
fn run(reference: &LabelImage, start: Option<&[f64]>, floor: f64) -> TreeFit {
    let view = tree_view(SIZE, SIZE, 12.0).expect("view");
    let mut s = TreeSession::with_start(
        reference,
        TreeTraits::default(),
        view,
        &small(),
        None,
        start,
    )
    .expect("session");
    let mut last = s.step();
    assert!(
        last.best_similarity >= floor,
        "{} < {floor}",
        last.best_similarity
    );
    while !s.done() {
        last = s.step();
        assert!(
            last.best_similarity >= floor,
            "{} < {floor}",
            last.best_similarity
        );
    }
    assert_eq!(last.evaluations, last.total_evaluations);
    let fit = s.result().expect("result");
    assert_eq!(fit.ga.evaluations, last.evaluations);
    match start {
        Some(_) => assert_eq!(s.start_similarity(), Some(floor)),
        None => assert_eq!(s.start_similarity(), None),
    }
    fit
}

#[test]
fn refit_from_the_truth_keeps_it() {
    let truth = truth();
    let reference = render(&truth);
    let start = similarity(&reference, &truth);
    let fit = run(&reference, Some(&truth), start);
    assert!(
        fit.similarity >= start,
        "refit ended at {} below its start {start}",
        fit.similarity
    );
    assert_eq!(
        fit.params[idx::SEED],
        truth[idx::SEED],
        "the start's seed was not kept"
    );
    // The reported similarity is the returned tree's.
    assert_eq!(similarity(&reference, &fit.params), fit.similarity);
    // What the start is for: the same budget from scratch does not find the truth.
    let scratch = run(&reference, None, 0.0);
    assert!(
        scratch.similarity < start,
        "a fit from scratch found the truth ({} ≥ {start}): this test no longer shows the start matters",
        scratch.similarity
    );
}

#[test]
fn refit_from_another_tree_is_never_worse_and_keeps_its_seed() {
    let reference = render(&truth());
    let mut from = preset("birch");
    from[idx::SEED] = 12.0;
    let start = similarity(&reference, &from);
    let fit = run(&reference, Some(&from), start);
    assert!(fit.similarity >= start, "{} < {start}", fit.similarity);
    assert_eq!(fit.params[idx::SEED], 12.0);
    // The genome of the result carries the seed too (it maps back to the parameters).
    let params =
        procfit::tree::genome_to_params(TreeGenerator.params(), &fit.ga.best.genome).expect("ok");
    assert_eq!(params, fit.params);
}

#[test]
fn refit_refuses_a_start_that_is_not_a_tree() {
    let reference = render(&truth());
    let view = tree_view(SIZE, SIZE, 12.0).expect("view");
    let short = [1.0; 3];
    let mut nan = truth();
    nan[idx::HEIGHT] = f64::NAN;
    for bad in [&short[..], &nan[..]] {
        let err = TreeSession::with_start(
            &reference,
            TreeTraits::default(),
            view,
            &small(),
            None,
            Some(bad),
        )
        .err()
        .expect("a bad start is refused");
        assert!(err.0.starts_with("the start tree"), "{}", err.0);
        assert!(start_photo_fit(&reference, 1, Some(200), Some(bad)).is_err());
    }
    // Out-of-range values are clamped like any parameters, not refused.
    let mut wild = truth();
    wild[idx::SEED] = 1e9;
    wild[idx::HEIGHT] = -5.0;
    assert!(start_photo_fit(&reference, 1, Some(200), Some(&wild)).is_ok());
}
