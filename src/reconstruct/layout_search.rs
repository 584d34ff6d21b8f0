//! The building layout search of the stage-1 hand-over, run when views carry window labels
//! ([`super::windows`]): the silhouette cannot tell some layouts apart (six storeys of 2.7 m
//! from four of 4.05 m), the window labels can, but only by value — the window term has no
//! gradient. So discrete parameters are swept one at a time ([`window_sweep`]) and continuous
//! ones only the windows show are tried across their range ([`line_sweep`]).

use super::objective::FitObjective;
use super::views::ViewSlot;
use crate::generators::{ParamKind, ParamSpec};
use crate::optim::{AdamConfig, Domain, Objective};
use rayon::prelude::*;

/// Adam iterations that repair the silhouette after a [`window_sweep`] move (15 were too few for
/// a changed entrance count to grow its stripes back to the outline).
const SWEEP_REPAIR: usize = 30;

/// A sweep move whose loss before repair is above this multiple of the current loss is dropped
/// (measured on the page's building sample: 3 dropped the move to the true entrance count).
const SWEEP_HOPELESS: f64 = 5.0;

/// Planned work of a [`window_sweep`] in 128²-evaluation equivalents, for the progress bar
/// (measured: 3500–5000 evaluations, most of them with a gradient).
pub(super) const SWEEP_WORK: f64 = 6000.0;

/// Most passes of [`window_sweep`] (it stops early when a pass gains nothing).
const SWEEP_PASSES: usize = 3;

/// A point and its loss.
type Point = (Vec<f64>, f64);

/// Largest number of values a discrete parameter may have to be swept.
const SWEEP_MAX_VALUES: f64 = 12.0;

/// The hand-over's layout sweep, run when views carry window labels. The silhouette cannot tell
/// six storeys of 2.7 m from four of 4.05 m, nor three window stripes from two wider ones;
/// stage 1's mutations rarely make the joint move (a count *and* the size that keeps the
/// outline). So every discrete parameter, one at a time (a greedy coordinate sweep), is set to
/// each of its other values. A count going from n to m is also tried with each metre-valued
/// parameter in turn × n/m (the m units fill what the n did: the storey height for the floor
/// count, the stripe width for a stripe count), the whole model rescaled — metre-valued
/// parameters × g, the view's scale ÷ g, which leaves the picture unchanged — when that takes
/// the parameter out of its range; the variant whose outline changed least is kept. A short
/// Adam run then repairs the outline, and the best move of each parameter is kept when it
/// lowers the loss (silhouette + windows). Moves that change nothing (a code of a stripe that
/// does not exist) are skipped after one evaluation. Returns the point and the evaluations
/// spent.
pub(super) fn window_sweep(
    objective: &FitObjective,
    domain: &Domain,
    specs: &[ParamSpec],
    mut x: Vec<f64>,
) -> (Vec<f64>, usize) {
    let layout = objective.layout().clone();
    let repair = AdamConfig {
        iterations: SWEEP_REPAIR,
        lr: 0.02,
        ..AdamConfig::default()
    };
    let metric: Vec<usize> = (0..specs.len()).filter(|&j| specs[j].is_length()).collect();
    let mut spent = 1;
    let mut current = objective.value(&x);
    spent += line_sweep(objective, domain, specs, &mut x, &mut current);
    for _pass in 0..SWEEP_PASSES {
        let before = current;
        for (i, s) in specs.iter().enumerate() {
            if s.kind.is_continuous() || s.max - s.min >= SWEEP_MAX_VALUES {
                continue;
            }
            // The other values, each tried (and repaired) from the same point: in parallel,
            // then taken in order, so the result does not depend on the threads. The label
            // render of the window term is sequential; without this, a run's sweep kept one
            // core while the other runs had finished theirs.
            let old = x[i];
            let values: Vec<f64> = (0..)
                .map(|k| s.min + k as f64)
                .take_while(|&v| v <= s.max + 1e-9)
                .filter(|&v| (v - old).abs() >= 0.5)
                .collect();
            let tried: Vec<(Option<Point>, usize)> = values
                .par_iter()
                .map(|&v| {
                    let mut spent = 0;
                    let mut plain = x.clone();
                    plain[i] = v;
                    domain.clamp(&mut plain);
                    let mut raw = objective.value(&plain);
                    spent += 1;
                    if raw == current {
                        // The parameter does nothing here.
                        return (None, spent);
                    }
                    let mut cand = plain;
                    if matches!(s.kind, ParamKind::Integer) && old >= 1.0 && v >= 1.0 {
                        for &j in &metric {
                            let mut c = x.clone();
                            c[i] = v;
                            let want = c[j] * old / v;
                            let g = specs[j].min.max(want.min(specs[j].max)) / want;
                            c[j] = want;
                            if g != 1.0 {
                                for &k in &metric {
                                    c[k] *= g;
                                }
                                for view in 0..layout.n_views {
                                    c[layout.slot(view, ViewSlot::LogScale)] -= g.ln();
                                }
                            }
                            domain.clamp(&mut c);
                            let value = objective.value(&c);
                            spent += 1;
                            if value < raw {
                                (cand, raw) = (c, value);
                            }
                        }
                    }
                    if raw > SWEEP_HOPELESS * current {
                        // Too far off for a short repair (measured: winners start within 2× the
                        // loss).
                        return (None, spent);
                    }
                    let (ind, evals) = crate::optim::adam_search(objective, domain, &cand, &repair);
                    spent += evals;
                    let found = if ind.value < raw {
                        (ind.x, ind.value)
                    } else {
                        (cand, raw)
                    };
                    (Some(found), spent)
                })
                .collect();
            let mut best: Option<Point> = None;
            for (found, n) in tried {
                spent += n;
                if let Some((cx, cv)) = found
                    && cv < best.as_ref().map_or(current, |b| b.1)
                {
                    best = Some((cx, cv));
                }
            }
            if let Some((bx, bv)) = best {
                x = bx;
                current = bv;
            }
        }
        spent += line_sweep(objective, domain, specs, &mut x, &mut current);
        if current >= before {
            break;
        }
    }
    (x, spent)
}

/// Values tried per continuous parameter by [`line_sweep`], as fractions of its range.
const LINE_STEPS: [f64; 6] = [0.05, 0.2, 0.35, 0.5, 0.65, 0.8];

/// A coordinate search over the continuous parameters, value only: the window term has no
/// gradient, so parameters only windows show (window width, height, sill) are never moved by
/// Adam; here each is tried at a few values across its range and the best kept. Returns the
/// evaluations spent.
fn line_sweep(
    objective: &FitObjective,
    domain: &Domain,
    specs: &[ParamSpec],
    x: &mut [f64],
    current: &mut f64,
) -> usize {
    let mut spent = 0;
    for (i, s) in specs.iter().enumerate() {
        if !s.kind.is_continuous() {
            continue;
        }
        // In parallel, taken in order (as in `window_sweep`).
        let tried: Vec<(f64, f64)> = LINE_STEPS
            .par_iter()
            .map(|&t| {
                let mut c = x.to_vec();
                c[i] = s.min + t * (s.max - s.min);
                domain.clamp(&mut c);
                (c[i], objective.value(&c))
            })
            .collect();
        let mut best: Option<(f64, f64)> = None;
        for (ci, v) in tried {
            spent += 1;
            if v < best.map_or(*current, |b| b.1) {
                best = Some((ci, v));
            }
        }
        if let Some((vi, v)) = best {
            x[i] = vi;
            *current = v;
        }
    }
    spent
}
