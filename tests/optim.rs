//! Tests of the optimisers on analytic functions: Adam's documented step rules, convergence on
//! Rosenbrock, the memetic algorithm on mixed discrete/continuous and multimodal problems, its
//! budget, its determinism across thread counts and its refusal of bad set-ups.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "a test binary: a failed step should stop it loudly"
)]

use procfit::optim::{
    Adam, AdamConfig, Domain, Memetic, MemeticConfig, Objective, Var, adam_search,
};

/// A closure-backed objective with an analytic gradient.
struct Analytic<F: Fn(&[f64], Option<&mut [f64]>) -> f64 + Sync> {
    f: F,
    gradient: bool,
}

impl<F: Fn(&[f64], Option<&mut [f64]>) -> f64 + Sync> Objective for Analytic<F> {
    fn value(&self, x: &[f64]) -> f64 {
        (self.f)(x, None)
    }
    fn has_gradient(&self) -> bool {
        self.gradient
    }
    fn value_grad(&self, x: &[f64], grad: &mut [f64]) -> f64 {
        grad.fill(0.0);
        if self.gradient {
            (self.f)(x, Some(grad))
        } else {
            (self.f)(x, None)
        }
    }
}

fn with_grad<F: Fn(&[f64], Option<&mut [f64]>) -> f64 + Sync>(f: F) -> Analytic<F> {
    Analytic { f, gradient: true }
}

fn rosenbrock(x: &[f64], g: Option<&mut [f64]>) -> f64 {
    let (a, b) = (x[0], x[1]);
    if let Some(g) = g {
        g[0] = -2.0 * (1.0 - a) - 400.0 * a * (b - a * a);
        g[1] = 200.0 * (b - a * a);
    }
    (1.0 - a).powi(2) + 100.0 * (b - a * a).powi(2)
}

fn rastrigin(x: &[f64], g: Option<&mut [f64]>) -> f64 {
    use std::f64::consts::TAU;
    if let Some(g) = g {
        for (gi, &xi) in g.iter_mut().zip(x) {
            *gi = 2.0 * xi + 10.0 * TAU * (TAU * xi).sin();
        }
    }
    x.iter()
        .map(|&xi| xi * xi - 10.0 * (TAU * xi).cos() + 10.0)
        .sum()
}

/// Continuous targets 0..4 with a gradient; discrete variables 4..7 are scored without one (a
/// wrong whole number costs 1 each, like a wrong floor count costs silhouette area).
const CONT_TARGET: [f64; 4] = [1.5, -2.0, 0.25, 3.0];
const DISC_TARGET: [f64; 3] = [7.0, 0.0, 3.0];

fn mixed(x: &[f64], g: Option<&mut [f64]>) -> f64 {
    let mut f = 0.0;
    for i in 0..4 {
        f += (x[i] - CONT_TARGET[i]).powi(2);
    }
    for i in 0..3 {
        f += if x[4 + i] == DISC_TARGET[i] { 0.0 } else { 1.0 };
    }
    if let Some(g) = g {
        for i in 0..4 {
            g[i] = 2.0 * (x[i] - CONT_TARGET[i]);
        }
    }
    f
}

fn mixed_domain() -> Domain {
    let mut vars = vec![Var::continuous(-5.0, 5.0); 4];
    vars.extend([
        Var::discrete(0.0, 9.0),
        Var::discrete(0.0, 1.0),
        Var::discrete(1.0, 4.0),
    ]);
    Domain::new(vars).unwrap()
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
}

#[test]
fn adam_first_step_is_lr_times_range_and_clamped() {
    let domain = Domain::new(vec![
        Var::continuous(0.0, 10.0),
        Var::continuous(-1.0, 1.0),
        Var::discrete(0.0, 5.0),
    ])
    .unwrap();
    let mut adam = Adam::new(
        &domain,
        &AdamConfig {
            lr: 0.05,
            ..AdamConfig::default()
        },
    );
    let mut x = vec![5.0, 0.99, 2.0];
    // Gradient scales differ by 10⁶: Adam's first step is lr × range whatever the scale.
    let moved = adam.step(&domain, &mut x, &[1e3, -1e-3, 7.0]);
    assert_eq!(moved, 2);
    assert!((x[0] - (5.0 - 0.5)).abs() < 1e-9, "x0 {}", x[0]);
    assert_eq!(x[1], 1.0, "clamped at the top of its range");
    assert_eq!(x[2], 2.0, "discrete variables are never moved by Adam");
}

#[test]
fn adam_leaves_variables_without_gradient_alone() {
    let domain = Domain::new(vec![Var::continuous(-1.0, 1.0); 2]).unwrap();
    let mut adam = Adam::new(&domain, &AdamConfig::default());
    let mut x = vec![0.0, 0.0];
    for _ in 0..5 {
        adam.step(&domain, &mut x, &[1.0, 1.0]);
    }
    let x1 = x[1];
    // From now on variable 1 gets no gradient (exactly zero, then NaN): its momentum must not
    // carry it on.
    for k in 0..10 {
        let g1 = if k % 2 == 0 { 0.0 } else { f64::NAN };
        assert_eq!(adam.step(&domain, &mut x, &[1.0, g1]), 1);
    }
    assert_eq!(x[1], x1);
    assert!(x[0] < x1);
}

#[test]
fn adam_finds_rosenbrock_minimum() {
    let domain = Domain::new(vec![Var::continuous(-2.0, 2.0); 2]).unwrap();
    let config = AdamConfig {
        iterations: 6000,
        lr: 0.002,
        ..AdamConfig::default()
    };
    let (best, evals) = adam_search(&with_grad(rosenbrock), &domain, &[-1.2, 1.0], &config);
    assert_eq!(evals, 6000);
    assert!(
        (best.x[0] - 1.0).abs() < 0.05 && (best.x[1] - 1.0).abs() < 0.1,
        "ended at {:?} with {}",
        best.x,
        best.value
    );
}

/// Runs the memetic algorithm and checks the best value found.
fn check_memetic<O: Objective>(
    objective: &O,
    domain: Domain,
    seeds: &[Vec<f64>],
    config: MemeticConfig,
    max_value: f64,
) -> Vec<f64> {
    let mut m = Memetic::new(domain, seeds, config).unwrap();
    let best = m.run(objective).unwrap().clone();
    let status = m.status();
    assert!(status.done);
    assert!(
        status.evaluations <= config.max_evaluations,
        "spent {} of {}",
        status.evaluations,
        config.max_evaluations
    );
    assert!(
        best.value <= max_value,
        "best {} > {max_value} at {:?}",
        best.value,
        best.x
    );
    best.x
}

#[test]
fn memetic_recovers_discrete_and_continuous_variables() {
    let config = MemeticConfig {
        max_evaluations: 3000,
        seed: 3,
        ..MemeticConfig::default()
    };
    let x = check_memetic(
        &with_grad(mixed),
        mixed_domain(),
        &[vec![-4.0, 4.0, -4.0, -4.0, 1.0, 1.0, 1.0]],
        config,
        1e-3,
    );
    assert_eq!(&x[4..], &DISC_TARGET);
}

#[test]
fn memetic_escapes_rastrigin_local_minima() {
    let domain = Domain::new(vec![Var::continuous(-5.12, 5.12); 4]).unwrap();
    let seed = vec![3.0, -3.0, 2.0, 4.0];
    // Adam alone from the seed settles in a local minimum far from 0 …
    let (local, _) = adam_search(
        &with_grad(rastrigin),
        &domain,
        &seed,
        &AdamConfig {
            iterations: 2000,
            lr: 0.001,
            ..AdamConfig::default()
        },
    );
    assert!(
        local.value > 10.0,
        "local search alone reached {}",
        local.value
    );
    // … the memetic algorithm finds the global basin.
    let config = MemeticConfig {
        max_evaluations: 5000,
        seed: 11,
        ..MemeticConfig::default()
    };
    check_memetic(&with_grad(rastrigin), domain, &[seed], config, 1e-2);
}

#[test]
fn memetic_without_gradient_is_a_genetic_algorithm() {
    let objective = Analytic {
        f: mixed,
        gradient: false,
    };
    let config = MemeticConfig {
        max_evaluations: 4000,
        seed: 5,
        ..MemeticConfig::default()
    };
    let x = check_memetic(&objective, mixed_domain(), &[], config, 0.05);
    assert_eq!(&x[4..], &DISC_TARGET);
}

#[test]
fn memetic_screens_surplus_seeds_and_keeps_the_budget() {
    // 100 seeds for 24 places, a budget that ends inside a local search.
    let seeds: Vec<Vec<f64>> = (0..100)
        .map(|i| {
            let t = f64::from(i) / 100.0;
            vec![-4.0 + 8.0 * t, 4.0 - 8.0 * t, 0.0, 0.0, 1.0, 1.0, 1.0]
        })
        .collect();
    for budget in [1, 57, 1001] {
        let config = MemeticConfig {
            max_evaluations: budget,
            ..MemeticConfig::default()
        };
        let mut m = Memetic::new(mixed_domain(), &seeds, config).unwrap();
        m.run(&with_grad(mixed));
        assert_eq!(m.status().evaluations, budget);
        assert!(m.status().done);
        assert!(m.best().is_some());
    }
}

#[test]
fn memetic_survives_failing_evaluations() {
    // Half the box fails (NaN / ∞), as a generator might for absurd parameters.
    let objective = with_grad(|x: &[f64], g: Option<&mut [f64]>| {
        if x[0] < 0.0 {
            return if x[1] < 0.0 { f64::NAN } else { f64::INFINITY };
        }
        mixed(x, g)
    });
    let config = MemeticConfig {
        max_evaluations: 2000,
        seed: 9,
        ..MemeticConfig::default()
    };
    check_memetic(&objective, mixed_domain(), &[], config, 1e-2);
}

#[test]
fn memetic_is_deterministic_for_a_seed_on_1_and_2_threads() {
    let run = |threads: usize, seed: u64| {
        pool(threads).install(|| {
            let config = MemeticConfig {
                max_evaluations: 1500,
                seed,
                ..MemeticConfig::default()
            };
            let mut m = Memetic::new(mixed_domain(), &[vec![0.0; 7]], config).unwrap();
            let best = m.run(&with_grad(rastrigin_mixed)).unwrap().clone();
            (best, m.status())
        })
    };
    let one = run(1, 42);
    let two = run(2, 42);
    assert_eq!(one, two);
    let other = run(2, 43);
    assert_ne!(
        one.0.x, other.0.x,
        "a different seed should explore differently"
    );
}

/// Rastrigin on the continuous variables plus the discrete penalty: multimodal enough that
/// runs with different seeds end in different places.
fn rastrigin_mixed(x: &[f64], g: Option<&mut [f64]>) -> f64 {
    let mut gc = [0.0; 4];
    let f = rastrigin(&x[..4], Some(&mut gc)) + mixed(x, None) - mixed_continuous(x);
    if let Some(g) = g {
        g[..4].copy_from_slice(&gc);
    }
    f
}

fn mixed_continuous(x: &[f64]) -> f64 {
    (0..4).map(|i| (x[i] - CONT_TARGET[i]).powi(2)).sum()
}

#[test]
fn bad_setups_are_refused() {
    let check = |config: MemeticConfig, seeds: &[Vec<f64>]| {
        assert!(Memetic::new(mixed_domain(), seeds, config).is_err());
    };
    let ok = MemeticConfig::default();
    check(
        MemeticConfig {
            population: 1,
            ..ok
        },
        &[],
    );
    check(
        MemeticConfig {
            max_evaluations: 0,
            ..ok
        },
        &[],
    );
    check(
        MemeticConfig {
            mutation_rate: 1.5,
            ..ok
        },
        &[],
    );
    check(
        MemeticConfig {
            mutation_sigma: f64::NAN,
            ..ok
        },
        &[],
    );
    check(ok, &[vec![0.0; 6]]);
    check(ok, &[vec![f64::INFINITY; 7]]);
    assert!(Domain::new(vec![]).is_err());
    assert!(Domain::new(vec![Var::continuous(1.0, 0.0)]).is_err());
    assert!(Domain::new(vec![Var::continuous(0.0, f64::INFINITY)]).is_err());
    assert!(Domain::new(vec![Var::discrete(0.2, 0.8)]).is_err());
}

#[test]
fn memetic_restarts_when_the_population_collapses() {
    // A smooth bowl pulls every individual to one point; with a diversity floor the run must
    // restart (keeping its elite) and still solve the continuous part (the discrete needles of
    // `mixed` from an all-zero seed are luck, not the point here).
    let config = MemeticConfig {
        max_evaluations: 3000,
        min_diversity: 0.02,
        seed: 2,
        ..MemeticConfig::default()
    };
    let mut m = Memetic::new(mixed_domain(), &[vec![0.0; 7]], config).unwrap();
    let best = m.run(&with_grad(mixed)).unwrap().clone();
    assert!(m.status().restarts > 0, "no restart: {:?}", m.status());
    let continuous: f64 = (0..4).map(|i| (best.x[i] - CONT_TARGET[i]).powi(2)).sum();
    assert!(continuous < 1e-3, "best {:?}", best);
    // Without the floor it does not restart.
    let mut calm = Memetic::new(
        mixed_domain(),
        &[vec![0.0; 7]],
        MemeticConfig {
            min_diversity: 0.0,
            ..config
        },
    )
    .unwrap();
    calm.run(&with_grad(mixed));
    assert_eq!(calm.status().restarts, 0);
}

/// A memetic run on [`mixed`] from `seeds`, finished.
fn run_mixed(seeds: &[Vec<f64>], config: MemeticConfig) -> Memetic {
    let mut m = Memetic::new(mixed_domain(), seeds, config).unwrap();
    m.run(&with_grad(mixed));
    m
}

/// Extra seeds (a cup's saucer) change nothing when none beats the best regular seed — the
/// same best point, the same evaluation count — and join the run when one does.
#[test]
fn extra_seeds_join_only_when_better_than_every_seed() {
    let seeds: Vec<Vec<f64>> = (0..100)
        .map(|i| {
            let t = f64::from(i) / 100.0;
            vec![-4.0 + 8.0 * t, 4.0 - 8.0 * t, 0.0, 0.0, 1.0, 1.0, 1.0]
        })
        .collect();
    let config = MemeticConfig {
        max_evaluations: 600,
        ..MemeticConfig::default()
    };
    let plain = run_mixed(&seeds, config);
    let worse = vec![vec![4.0, 4.0, 1.0, 1.0, 0.0, 1.0, 1.0]; 3];
    let best_seed = seeds
        .iter()
        .map(|s| mixed(s, None))
        .fold(f64::INFINITY, f64::min);
    assert!(worse.iter().all(|w| mixed(w, None) > best_seed));
    let mut m = Memetic::new(mixed_domain(), &seeds, config)
        .unwrap()
        .with_extra_seeds(&worse, 0..0)
        .unwrap();
    m.run(&with_grad(mixed));
    assert_eq!(m.status().evaluations, plain.status().evaluations);
    assert_eq!(m.best().unwrap().x, plain.best().unwrap().x);
    // A better extra joins: the run's best is at least as good as that extra.
    let optimum: Vec<f64> = CONT_TARGET.iter().chain(&DISC_TARGET).copied().collect();
    let mut m = Memetic::new(mixed_domain(), &seeds, config)
        .unwrap()
        .with_extra_seeds(std::slice::from_ref(&optimum), 0..0)
        .unwrap();
    m.run(&with_grad(mixed));
    assert!(m.best().unwrap().value <= mixed(&optimum, None) + 1e-12);
}

/// A variable left to local search ([`Memetic::with_unmutated`]: a hip roof's ridge length)
/// changes nothing for the others — the same random numbers, the same best point and
/// evaluation count as a run without it — stays at its seeds' value where it has no gradient,
/// and is fitted by the Adam steps where it has one.
#[test]
fn unmutated_variables_are_left_to_local_search() {
    let seeds = vec![vec![0.0; 7], vec![1.0, 1.0, 1.0, 1.0, 3.0, 1.0, 2.0]];
    let config = MemeticConfig {
        max_evaluations: 600,
        ..MemeticConfig::default()
    };
    let plain = run_mixed(&seeds, config);
    let mut vars = mixed_domain().vars().to_vec();
    vars.push(Var::continuous(0.0, 4.0));
    let domain = Domain::new(vars).unwrap();
    let longer: Vec<Vec<f64>> = seeds
        .iter()
        .map(|s| s.iter().copied().chain([0.5]).collect())
        .collect();
    // The eighth variable moves nothing.
    let idle = |x: &[f64], g: Option<&mut [f64]>| match g {
        Some(g) => mixed(&x[..7], Some(&mut g[..7])),
        None => mixed(&x[..7], None),
    };
    let mut m = Memetic::new(domain.clone(), &longer, config)
        .unwrap()
        .with_unmutated(&[7])
        .unwrap();
    m.run(&with_grad(idle));
    assert_eq!(m.status().evaluations, plain.status().evaluations);
    assert_eq!(m.best().unwrap().x[..7], plain.best().unwrap().x[..]);
    assert!(m.population().iter().all(|i| i.x[7] == 0.5));
    // With a gradient the local searches fit it.
    let pulled = |x: &[f64], g: Option<&mut [f64]>| {
        let d = x[7] - 2.5;
        match g {
            Some(g) => {
                g[7] = 2.0 * d;
                mixed(&x[..7], Some(&mut g[..7])) + d * d
            }
            None => mixed(&x[..7], None) + d * d,
        }
    };
    let long = MemeticConfig {
        max_evaluations: 3000,
        ..config
    };
    let mut m = Memetic::new(domain, &longer, long)
        .unwrap()
        .with_unmutated(&[7])
        .unwrap();
    let best = m.run(&with_grad(pulled)).unwrap().clone();
    assert!((best.x[7] - 2.5).abs() < 0.05, "best {:?}", best.x);
}
