//! The coarse-to-fine fit as a resumable session (paper §3.4, notes "Optimisers and
//! schedule"), for the page's worker and the CLI alike:
//!
//! 1. **Stage 1**: the memetic algorithm at 128² and LOW detail, from the generator's seeds ×
//!    camera guesses per view ([`super::views`]). With `auto`, a short stage 1 runs for every
//!    differentiable generator and the best one continues with the rest of the budget.
//! 2. **Stage 2**: Adam at 256² and MEDIUM detail (lr 0.01), with the regulariser.
//! 3. **Stage 3**: Adam at 512² and HIGH detail (lr 0.0075), with the regulariser.
//!
//! [`Session::step`] does one bounded slice of work (one memetic batch, or a few Adam
//! iterations) and returns a [`Progress`]; cancelling is simply not stepping any more, and
//! [`Session::result`] gives the best model so far at any time. The session never reads a
//! clock (library code runs on wasm32); callers time it. A run is deterministic for a seed.

use super::FitError;
use super::objective::{FitObjective, Layout, render_coverage, resample_mask};
use super::views::{DEFAULT_FOV_Y, MaskStats, fit_box, mask_stats, view_domain};
use super::windows::{DEFAULT_WINDOW_WEIGHT, WindowTerm};
use crate::camera::{View, ViewParams};
use crate::generators::{self, Generator, Lod};
use crate::mask::{LabelImage, Mask};
use crate::model::Model;
use crate::optim::{Adam, AdamConfig, Domain, Memetic, MemeticConfig, Objective, Var};
use std::sync::Arc;

/// Stage-1 evaluations at quality 1: the reference schedule's ~5000 at 128² (notes "Optimisers
/// and schedule"). Measured (benches/reconstruct.rs): buildings gain from it (mean IoU-64 0.89 →
/// 0.96 over 2000), dishes are limited by what one view can tell, and one run takes ~2–3 s
/// natively (a fit makes [`FitConfig::restarts`] of them side by side: ~4 s on 2 threads).
pub const DEFAULT_EVALUATIONS: usize = 5000;

/// Largest number of [`FitConfig::restarts`].
pub const MAX_RESTARTS: usize = 16;

/// Largest number of input views.
pub const MAX_VIEWS: usize = 16;

/// Side of the preview silhouette in [`Progress::preview`].
pub const PREVIEW_SIDE: u32 = 128;

/// Adam iterations per [`Session::step`] in stages 2 and 3.
const ADAM_SLICE: usize = 5;

/// What to fit and how hard to try.
#[derive(Clone, Debug, PartialEq)]
pub struct FitConfig {
    /// Generator machine name, or `auto`.
    pub generator: String,
    /// Seed of every random choice.
    pub seed: u64,
    /// Quality/speed knob: multiplies every stage's budget (1 = default; 0.25 a quick preview,
    /// 4 a thorough fit).
    pub quality: f64,
    /// Stage-1 evaluations, overriding `quality`'s for that stage.
    pub budget: Option<usize>,
    /// Vertical field of view per view (from EXIF or the user); missing or `None` entries take
    /// [`DEFAULT_FOV_Y`].
    pub fov_y: Vec<Option<f64>>,
    /// Also fit each view's field of view.
    pub fit_fov: bool,
    /// Weight of the generator's regulariser in stages 2 and 3 (relative to the MSE).
    pub reg_weight: f64,
    /// Weight of the generator's regulariser in stage 1. Larger than `reg_weight`: at 128² a
    /// dish with a pinched rim seen from lower down scores as well as the true open one, and
    /// the prior steers the search away; stages 2 and 3 then fit the details with a light
    /// one. Measured on 8 random dishes, best of 3 runs: mean IoU-64 0.887 with 0, 0.934 with
    /// 0.01 (`cargo test --release --test reconstruct -- --ignored --nocapture` prints the
    /// table for the defaults).
    pub search_reg_weight: f64,
    /// Whole fits (all three stages) from different seeds, stepped side by side; the one with
    /// the lowest final loss is the result. Single-view fits land in different basins from run to run (a handle
    /// turned or shortened, a rim pinched or open) and the lowest loss is mostly the right
    /// one: on the measured mug from 8 cameras, mean IoU-64 0.947 with 1 run, 0.969 with 3.
    pub restarts: usize,
    /// Resolution (longer side) of the stages, coarse to fine.
    pub resolutions: [u32; 3],
    /// Level of detail of the stages.
    pub lods: [Lod; 3],
    /// Generator parameters to start from ("refit from here": the model the user edited). It
    /// joins stage 1's seed population first, with every camera guess, and is polished like
    /// the presets (paper §3.2). Needs a named generator (not `auto`) and its parameter count.
    pub start: Option<Vec<f64>>,
    /// Window labels per view (buildings; [`super::windows`]): missing or `None` entries have
    /// none. Each must be the size of its view's mask.
    pub windows: Vec<Option<LabelImage>>,
    /// Weight of the window term relative to the silhouette MSE.
    pub window_weight: f64,
}

impl Default for FitConfig {
    fn default() -> Self {
        FitConfig {
            generator: "auto".into(),
            seed: 0,
            quality: 1.0,
            budget: None,
            fov_y: Vec::new(),
            fit_fov: false,
            reg_weight: 1e-4,
            search_reg_weight: 1e-2,
            restarts: 3,
            resolutions: [128, 256, 512],
            // The paper runs stage 1 at LOW detail. Our dish's LOW mesh (12 sectors) is so
            // polygonal that, measured on random dishes, the true shape scored worse at 128² than
            // a wrong camera pitch; MEDIUM (24 sectors) does not have that problem.
            lods: [Lod::Low, Lod::Medium, Lod::High],
            start: None,
            windows: Vec::new(),
            window_weight: DEFAULT_WINDOW_WEIGHT,
        }
    }
}

/// Where a session stands after a step.
#[derive(Clone, Debug)]
pub struct Progress {
    /// Stage 1, 2 or 3 (3 and `done` at the end).
    pub stage: u8,
    /// The generator being fitted (during `auto`'s stage 1, the one being tried).
    pub generator: &'static str,
    /// Generation (stage 1) or Adam iteration (stages 2, 3) within the stage.
    pub iteration: usize,
    /// Loss evaluations so far, all stages.
    pub evaluations: usize,
    /// Work done and planned in 128²-evaluation equivalents (for a progress bar / ETA).
    pub work_done: f64,
    /// See `work_done`.
    pub work_total: f64,
    /// Best loss of the current stage (stages use different resolutions, so losses of
    /// different stages do not compare).
    pub best_loss: f64,
    /// Best generator parameters so far.
    pub params: Vec<f64>,
    /// Best camera (object transform and intrinsics) of each view so far.
    pub cameras: Vec<ViewParams>,
    /// The best silhouette seen from view 0, at most [`PREVIEW_SIDE`] a side.
    pub preview: Option<Mask>,
    /// The run (1-based) whose stage, iteration and loss these are, of [`Progress::runs`]
    /// ([`FitConfig::restarts`], stepped side by side): the first unfinished one.
    pub run: usize,
    /// See `run`.
    pub runs: usize,
    /// The fit is finished.
    pub done: bool,
}

/// The outcome of a fit.
#[derive(Clone, Debug)]
pub struct FitResult {
    /// The generator and its parameters (at MEDIUM detail for export by default).
    pub model: Model,
    /// One fitted view per input mask, at the mask's size.
    pub views: Vec<View>,
    /// Loss of the last stage that ran.
    pub loss: f64,
    /// Evaluations spent.
    pub evaluations: usize,
}

/// One generator's stage-1 search.
struct Search {
    generator: &'static dyn Generator,
    objective: FitObjective,
    memetic: Memetic,
}

/// A gradient stage in progress.
struct AdamStage {
    stage: u8,
    objective: FitObjective,
    domain: Domain,
    adam: Adam,
    x: Vec<f64>,
    grad: Vec<f64>,
    best: (Vec<f64>, f64),
    iteration: usize,
    iterations: usize,
    decay: f64,
}

enum Phase {
    Search,
    Adam(Box<AdamStage>),
    Done,
}

/// A best point: its generator, layout, values, loss and the stage that found it.
#[derive(Clone)]
struct Best {
    generator: &'static dyn Generator,
    layout: Layout,
    x: Vec<f64>,
    loss: f64,
    stage: u8,
}

/// One run of the three stages; a [`Session`] makes [`FitConfig::restarts`] of them.
struct Run {
    config: FitConfig,
    masks: Vec<Mask>,
    /// The window term, shared by every stage's objective.
    windows: Option<Arc<WindowTerm>>,
    fov: Vec<f64>,
    searches: Vec<Search>,
    /// Index of the search being stepped; after the `auto` round, the chosen one.
    current: usize,
    /// Stage-1 evaluations each search gets before `auto` picks (all of them when only one).
    short_budget: usize,
    chosen: bool,
    phase: Phase,
    /// Best of the finished stages.
    best: Option<Best>,
    evaluations: usize,
    stage_iterations: [usize; 2],
    work_done: f64,
    work_total: f64,
}

/// Relative cost of one evaluation at `side` compared to 128² (pixels, roughly).
fn work_weight(side: u32) -> f64 {
    let r = f64::from(side) / 128.0;
    r * r
}

impl Run {
    /// Starts a fit of `masks` (one per view, all the same size). Nothing is evaluated yet.
    /// Errors on an unknown or non-differentiable generator, no masks or too many, masks of
    /// different sizes, empty or all-object masks, too small images, and bad settings.
    fn new(config: FitConfig, masks: Vec<Mask>) -> Result<Run, FitError> {
        if masks.is_empty() {
            return Err(FitError("no masks to fit".into()));
        }
        if masks.len() > MAX_VIEWS {
            return Err(FitError(format!(
                "{} views; at most {MAX_VIEWS} are supported",
                masks.len()
            )));
        }
        let (w0, h0) = (masks[0].width(), masks[0].height());
        if let Some((i, m)) = masks
            .iter()
            .enumerate()
            .find(|(_, m)| (m.width(), m.height()) != (w0, h0))
        {
            return Err(FitError(format!(
                "mask {i} is {}×{} but mask 0 is {w0}×{h0}; all views must have the same size",
                m.width(),
                m.height()
            )));
        }
        if !(config.quality.is_finite() && config.quality > 0.0 && config.quality <= 100.0) {
            return Err(FitError(format!(
                "quality {} is not in (0, 100]",
                config.quality
            )));
        }
        if config.budget == Some(0) {
            return Err(FitError("the evaluation budget must be at least 1".into()));
        }
        if !(config.search_reg_weight.is_finite() && config.search_reg_weight >= 0.0) {
            return Err(FitError(
                "the stage-1 regulariser weight must be ≥ 0".into(),
            ));
        }
        if !(1..=MAX_RESTARTS).contains(&config.restarts) {
            return Err(FitError(format!(
                "{} restarts; between 1 and {MAX_RESTARTS} are supported",
                config.restarts
            )));
        }
        if !(config.reg_weight.is_finite() && config.reg_weight >= 0.0) {
            return Err(FitError("the regulariser weight must be ≥ 0".into()));
        }
        if config.resolutions.iter().any(|&r| !(8..=4096).contains(&r)) {
            return Err(FitError("stage resolutions must be within 8..=4096".into()));
        }
        let windows =
            WindowTerm::new(&config.windows, masks.len(), (w0, h0), config.window_weight)?
                .map(Arc::new);
        let stats = masks
            .iter()
            .enumerate()
            .map(|(i, m)| mask_stats(m, i))
            .collect::<Result<Vec<_>, _>>()?;
        let fov = (0..masks.len())
            .map(|i| {
                let f = config
                    .fov_y
                    .get(i)
                    .copied()
                    .flatten()
                    .unwrap_or(DEFAULT_FOV_Y);
                if f.is_finite() && f > 0.05 && f < 3.0 {
                    Ok(f)
                } else {
                    Err(FitError(format!(
                        "field of view {f} rad for view {i} is not in (0.05, 3)"
                    )))
                }
            })
            .collect::<Result<Vec<_>, _>>()?;
        let candidates: Vec<&'static dyn Generator> = if config.generator == "auto" {
            generators::all()
                .into_iter()
                .filter(|g| g.differentiable())
                .collect()
        } else {
            let g = generators::by_name(&config.generator)
                .ok_or_else(|| FitError(format!("unknown generator `{}`", config.generator)))?;
            if !g.differentiable() {
                return Err(FitError(format!(
                    "generator `{}` is not differentiable; it cannot be fitted here",
                    g.name()
                )));
            }
            vec![g]
        };
        if candidates.is_empty() {
            return Err(FitError("no differentiable generator is built in".into()));
        }
        // The start vector belongs to one generator, so `auto` cannot use it.
        let start = match (&config.start, candidates.as_slice()) {
            (None, _) => None,
            (Some(x), [g]) => Some(
                generators::sanitize_params(g.params(), x)
                    .map_err(|e| FitError(format!("start parameters: {e}")))?,
            ),
            (Some(_), _) => {
                return Err(FitError(
                    "start parameters need a named generator, not `auto`".into(),
                ));
            }
        };
        let stage1 = config
            .budget
            .unwrap_or(((DEFAULT_EVALUATIONS as f64) * config.quality).round() as usize)
            .max(1);
        let short_budget = if candidates.len() > 1 {
            (stage1 * 3 / (4 * candidates.len())).max(1)
        } else {
            stage1
        };
        let small: Vec<Mask> = masks
            .iter()
            .map(|m| resample_mask(m, config.resolutions[0]))
            .collect();
        let mut searches = Vec::new();
        for (k, &g) in candidates.iter().enumerate() {
            let (layout, domain, seeds) = start_points(
                g,
                start.as_deref(),
                &stats,
                &fov,
                config.fit_fov,
                windows.is_none(),
            )?;
            let objective = FitObjective::new(
                g,
                config.lods[0],
                layout,
                small.clone(),
                config.search_reg_weight,
                false,
            )
            .with_windows(windows.clone());
            let memetic = Memetic::new(
                domain,
                &seeds,
                MemeticConfig {
                    max_evaluations: short_budget,
                    seed: config.seed.wrapping_add(k as u64),
                    population: if masks.len() == 1 {
                        SINGLE_VIEW_POPULATION
                    } else {
                        MemeticConfig::default().population
                    },
                    ..MemeticConfig::default()
                },
            )
            .map_err(|e| FitError(e.to_string()))?;
            searches.push(Search {
                generator: g,
                objective,
                memetic,
            });
        }
        let q = config.quality;
        let stage_iterations = [
            ((100.0 * q).round() as usize).max(1),
            ((60.0 * q).round() as usize).max(1),
        ];
        let long = w0.max(h0);
        let side = |i: usize| config.resolutions[i].min(long);
        let sweep = if windows.is_some() {
            SWEEP_WORK * work_weight(side(0))
        } else {
            0.0
        };
        let work_total = sweep
            + stage1 as f64 * work_weight(side(0))
            + stage_iterations[0] as f64 * work_weight(side(1)) * 2.0
            + stage_iterations[1] as f64 * work_weight(side(2)) * 2.0;
        Ok(Run {
            config,
            masks,
            windows,
            fov,
            searches,
            current: 0,
            short_budget,
            chosen: candidates.len() == 1,
            phase: Phase::Search,
            best: None,
            evaluations: 0,
            stage_iterations,
            work_done: 0.0,
            work_total,
        })
    }

    fn stage_side(&self, i: usize) -> u32 {
        let long = self.masks[0].width().max(self.masks[0].height());
        self.config.resolutions[i].min(long)
    }

    /// Whether the fit is finished.
    pub fn is_done(&self) -> bool {
        matches!(self.phase, Phase::Done)
    }

    /// Does one bounded slice of work and reports progress. After the end it only reports.
    pub fn step(&mut self) -> Progress {
        match std::mem::replace(&mut self.phase, Phase::Done) {
            Phase::Search => self.step_search(),
            Phase::Adam(stage) => self.step_adam(stage),
            Phase::Done => {}
        }
        self.progress()
    }

    fn step_search(&mut self) {
        let side = self.stage_side(0);
        let search = &mut self.searches[self.current];
        let before = search.memetic.status().evaluations;
        let status = search.memetic.step(&search.objective);
        let spent = status.evaluations - before;
        self.evaluations += spent;
        self.work_done += spent as f64 * work_weight(side);
        self.phase = Phase::Search;
        if !status.done {
            return;
        }
        if !self.chosen {
            if self.current + 1 < self.searches.len() {
                self.current += 1;
                return;
            }
            // `auto`: continue the best generator with the rest of the stage-1 budget.
            let best = (0..self.searches.len())
                .min_by(|&a, &b| {
                    let va = self.searches[a].memetic.status().best_value;
                    let vb = self.searches[b].memetic.status().best_value;
                    va.total_cmp(&vb)
                })
                .unwrap_or(0);
            self.current = best;
            self.chosen = true;
            let total = self
                .config
                .budget
                .unwrap_or(((DEFAULT_EVALUATIONS as f64) * self.config.quality).round() as usize);
            let rest = total.saturating_sub(self.short_budget * self.searches.len());
            if rest > 0 {
                self.searches[best].memetic.extend_budget(rest);
                return;
            }
        }
        let search = &self.searches[self.current];
        let Some(best) = search.memetic.best() else {
            self.phase = Phase::Done;
            return;
        };
        self.best = Some(Best {
            generator: search.generator,
            layout: search.objective.layout().clone(),
            x: best.x.clone(),
            loss: best.value,
            stage: 1,
        });
        // The best few distinct individuals of stage 1 (the best first).
        let mut pop: Vec<&crate::optim::Individual> = search.memetic.population().iter().collect();
        pop.sort_by(|a, b| a.value.total_cmp(&b.value));
        let mut starts: Vec<Vec<f64>> = vec![best.x.clone()];
        for ind in &pop {
            if starts.len() >= PROBES {
                break;
            }
            if !starts.contains(&ind.x) {
                starts.push(ind.x.clone());
            }
        }
        let specs = search.generator.params();
        if search.objective.has_windows() {
            // Window labels can tell layouts that the silhouette cannot (see `window_sweep`).
            let (x, spent) = window_sweep(
                &search.objective,
                search.memetic.domain(),
                specs,
                best.x.clone(),
            );
            self.evaluations += spent;
            // Most of the sweep's evaluations carry a gradient (the repairs).
            self.work_done += 1.75 * spent as f64 * work_weight(side);
            starts.retain(|s| *s != x);
            starts.insert(0, x);
            starts.truncate(PROBES);
        }
        self.phase = self.start_adam(2, starts[0].clone());
        if let Phase::Adam(stage) = &mut self.phase {
            let side =
                self.config.resolutions[1].min(self.masks[0].width().max(self.masks[0].height()));
            let (x, spent) = probe(&stage.objective, &stage.domain, specs, starts);
            stage.x = x;
            self.evaluations += spent;
            self.work_done += 2.0 * spent as f64 * work_weight(side);
        }
    }

    /// Builds gradient stage `stage` (2 or 3) from point `x`.
    fn start_adam(&self, stage: u8, x: Vec<f64>) -> Phase {
        let search = &self.searches[self.current];
        let g = search.generator;
        let i = usize::from(stage - 1);
        let lod = self.config.lods[i];
        let lr = if stage == 2 { 0.01 } else { 0.0075 };
        let masks = self
            .masks
            .iter()
            .map(|m| resample_mask(m, self.config.resolutions[i]))
            .collect();
        let objective = FitObjective::new(
            g,
            lod,
            search.objective.layout().clone(),
            masks,
            self.config.reg_weight,
            true,
        )
        .with_windows(self.windows.clone());
        let domain = search.memetic.domain().clone();
        let adam = Adam::new(
            &domain,
            &AdamConfig {
                lr,
                ..AdamConfig::default()
            },
        );
        let iterations = self.stage_iterations[i - 1];
        let n = x.len();
        Phase::Adam(Box::new(AdamStage {
            stage,
            objective,
            domain,
            adam,
            x,
            grad: vec![0.0; n],
            best: (Vec::new(), f64::INFINITY),
            iteration: 0,
            iterations,
            // The step shrinks to a fifth over the stage, so it ends finer than it starts.
            decay: 0.2f64.powf(1.0 / iterations as f64),
        }))
    }

    fn step_adam(&mut self, mut s: Box<AdamStage>) {
        let side = self.stage_side(usize::from(s.stage - 1));
        let end = (s.iteration + ADAM_SLICE).min(s.iterations);
        while s.iteration < end {
            let value = s.objective.value_grad(&s.x, &mut s.grad);
            self.evaluations += 1;
            self.work_done += 2.0 * work_weight(side);
            if value < s.best.1 {
                s.best = (s.x.clone(), value);
            }
            s.iteration += 1;
            if !value.is_finite() {
                // The point fails at this detail (should not happen for a point the previous
                // stage could render): stop the stage, keeping the best so far.
                s.iteration = s.iterations;
                break;
            }
            s.adam.step(&s.domain, &mut s.x, &s.grad);
            s.adam.scale_rates(s.decay);
        }
        if s.iteration < s.iterations {
            self.phase = Phase::Adam(s);
            return;
        }
        if s.best.1.is_finite()
            && let Some(best) = self.best.as_mut()
        {
            best.x = s.best.0.clone();
            best.loss = s.best.1;
            best.stage = s.stage;
        }
        self.phase = if s.stage == 2 {
            let x = self
                .best
                .as_ref()
                .map_or_else(|| s.x.clone(), |b| b.x.clone());
            self.start_adam(3, x)
        } else {
            Phase::Done
        };
        if matches!(self.phase, Phase::Done) {
            self.work_done = self.work_total;
        }
    }

    /// The best point so far.
    fn current_best(&self) -> Option<Best> {
        match &self.phase {
            Phase::Adam(s) if s.best.1.is_finite() => Some(Best {
                generator: self.searches[self.current].generator,
                layout: s.objective.layout().clone(),
                x: s.best.0.clone(),
                loss: s.best.1,
                stage: s.stage,
            }),
            Phase::Search => {
                let search = &self.searches[self.current];
                search.memetic.best().map(|b| Best {
                    generator: search.generator,
                    layout: search.objective.layout().clone(),
                    x: b.x.clone(),
                    loss: b.value,
                    stage: 1,
                })
            }
            _ => None,
        }
        .or_else(|| self.best.clone())
    }

    /// Where the fit stands (what [`Session::step`] returns).
    pub fn progress(&self) -> Progress {
        let (stage, iteration) = match &self.phase {
            Phase::Search => (1, self.searches[self.current].memetic.status().generation),
            Phase::Adam(s) => (s.stage, s.iteration),
            Phase::Done => (3, self.stage_iterations[1]),
        };
        let best = self.current_best();
        let generator = best
            .as_ref()
            .map_or(self.searches[self.current].generator.name(), |b| {
                b.generator.name()
            });
        let (params, cameras, loss, preview) = match &best {
            Some(b) => {
                let cams = (0..b.layout.n_views)
                    .map(|i| b.layout.view_vars(&b.x, i).params())
                    .collect();
                (
                    b.x[..b.layout.n_gen].to_vec(),
                    cams,
                    b.loss,
                    self.preview(b.generator, &b.layout, &b.x),
                )
            }
            None => (Vec::new(), Vec::new(), f64::INFINITY, None),
        };
        Progress {
            stage,
            generator,
            iteration,
            evaluations: self.evaluations,
            work_done: self.work_done.min(self.work_total),
            work_total: self.work_total,
            best_loss: loss,
            params,
            cameras,
            preview,
            run: 1,
            runs: 1,
            done: self.is_done(),
        }
    }

    fn preview(&self, g: &'static dyn Generator, layout: &Layout, x: &[f64]) -> Option<Mask> {
        let small = resample_mask(&self.masks[0], PREVIEW_SIDE);
        let view = layout.view_vars(x, 0).view(small.width(), small.height());
        let mesh = g.generate(&x[..layout.n_gen], Lod::Low).ok()?;
        let coverage = render_coverage(&mesh, &view).ok()?;
        Mask::new(view.width, view.height, coverage).ok()
    }

    /// The best model and cameras so far (the final result once done). Errors only when
    /// nothing could be evaluated.
    pub fn result(&self) -> Result<FitResult, FitError> {
        let Best {
            generator: g,
            layout,
            x,
            loss,
            ..
        } = self
            .current_best()
            .ok_or_else(|| FitError("nothing was evaluated yet".into()))?;
        let mut model = Model::new(g.name(), &x[..layout.n_gen], Lod::Medium)
            .map_err(|e| FitError(e.to_string()))?;
        model.seed = Some(self.config.seed);
        let (w, h) = (self.masks[0].width(), self.masks[0].height());
        let views = (0..layout.n_views)
            .map(|v| layout.view_vars(&x, v).view(w, h))
            .collect();
        Ok(FitResult {
            model,
            views,
            loss,
            evaluations: self.evaluations,
        })
    }

    /// The fields of view used for the views.
    pub fn fov(&self) -> &[f64] {
        &self.fov
    }
}

/// Tolerance of [`simplify`]: how much worse (relative) a simpler model may fit.
const SIMPLER_TOLERANCE: f64 = 0.005;

/// Occam's step between stage 1 and stage 2: every Boolean parameter that is on (a mug's
/// handle) is switched off when that fits the views as well, within [`SIMPLER_TOLERANCE`]. A
/// part hidden from every view costs nothing in eq. 1, so stage 1 keeps it or not at random;
/// the evaluation — and the user — see it from all sides. Returns the evaluations spent.
fn simplify(
    objective: &FitObjective,
    specs: &[crate::generators::ParamSpec],
    x: &mut [f64],
) -> usize {
    let mut spent = 1;
    let mut current = objective.value(x);
    for (i, s) in specs.iter().enumerate() {
        if !matches!(s.kind, crate::generators::ParamKind::Boolean) || x[i] < 0.5 {
            continue;
        }
        x[i] = 0.0;
        let off = objective.value(x);
        spent += 1;
        if off <= current * (1.0 + SIMPLER_TOLERANCE) {
            current = off.min(current);
        } else {
            x[i] = 1.0;
        }
    }
    spent
}

/// Stage-1 individuals tried at stage-2 resolution before stage 2 commits to one.
const PROBES: usize = 4;

/// Adam iterations of each probe.
const PROBE_ITERATIONS: usize = 12;

/// The hand-over from stage 1 to stage 2. At 128² and coarse detail a wrong basin (another
/// camera elevation with a compensating shape) can score a hair better than the right one, so
/// the best few distinct individuals are each simplified ([`simplify`]) and given a short Adam
/// run at stage 2's resolution; the best goes on. Returns it and the evaluations
/// spent.
fn probe(
    objective: &FitObjective,
    domain: &Domain,
    specs: &[crate::generators::ParamSpec],
    starts: Vec<Vec<f64>>,
) -> (Vec<f64>, usize) {
    let adam = AdamConfig {
        iterations: PROBE_ITERATIONS,
        lr: 0.01,
        ..AdamConfig::default()
    };
    // Sequential: each evaluation already renders in parallel, and nesting the two would let
    // rayon interleave evaluations on one thread.
    let results: Vec<(Vec<f64>, f64, usize)> = starts
        .into_iter()
        .map(|mut x| {
            let spent = simplify(objective, specs, &mut x);
            let (ind, evals) = crate::optim::adam_search(objective, domain, &x, &adam);
            (ind.x, ind.value, spent + evals)
        })
        .collect();
    let spent = results.iter().map(|r| r.2).sum();
    let best = results
        .into_iter()
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|r| r.0)
        .unwrap_or_default();
    (best, spent)
}

/// Stage 1's population from a single view: larger than the memetic default (24, kept for
/// several views), so the yaw-turned seeds ([`YAW_TURNS`]) do not crowd out the other shapes. Measured on the measured mug from 8
/// random cameras (quality 1): mean IoU-64 0.840 without turns, 0.905 with turns at 24, 0.947
/// with turns at 36.
const SINGLE_VIEW_POPULATION: usize = 36;

/// Adam iterations that repair the silhouette after a [`window_sweep`] move (15 were too few for
/// a changed entrance count to grow its stripes back to the outline).
const SWEEP_REPAIR: usize = 30;

/// A sweep move whose loss before repair is above this multiple of the current loss is dropped
/// (measured on the page's building sample: 3 dropped the move to the true entrance count).
const SWEEP_HOPELESS: f64 = 5.0;

/// Planned work of a [`window_sweep`] in 128²-evaluation equivalents, for the progress bar
/// (measured: 3500–5000 evaluations, most of them with a gradient).
const SWEEP_WORK: f64 = 6000.0;

/// Most passes of [`window_sweep`] (it stops early when a pass gains nothing).
const SWEEP_PASSES: usize = 3;

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
fn window_sweep(
    objective: &FitObjective,
    domain: &Domain,
    specs: &[crate::generators::ParamSpec],
    mut x: Vec<f64>,
) -> (Vec<f64>, usize) {
    use crate::generators::ParamKind;
    let layout = objective.layout().clone();
    let repair = AdamConfig {
        iterations: SWEEP_REPAIR,
        lr: 0.02,
        ..AdamConfig::default()
    };
    let metric: Vec<usize> = (0..specs.len())
        .filter(|&j| specs[j].unit == "m" && specs[j].kind.is_continuous())
        .collect();
    let mut spent = 1;
    let mut current = objective.value(&x);
    spent += line_sweep(objective, domain, specs, &mut x, &mut current);
    for _pass in 0..SWEEP_PASSES {
        let before = current;
        for (i, s) in specs.iter().enumerate() {
            if s.kind.is_continuous() || s.max - s.min >= SWEEP_MAX_VALUES {
                continue;
            }
            let mut best: Option<(Vec<f64>, f64)> = None;
            let mut v = s.min;
            while v <= s.max + 1e-9 {
                let old = x[i];
                v += 1.0;
                if (v - 1.0 - old).abs() < 0.5 {
                    continue;
                }
                let v = v - 1.0;
                let mut plain = x.clone();
                plain[i] = v;
                domain.clamp(&mut plain);
                let mut raw = objective.value(&plain);
                spent += 1;
                if raw == current {
                    // The parameter does nothing here.
                    continue;
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
                                c[layout.view_offset(view) + 5] -= g.ln();
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
                    // Too far off for a short repair (measured: winners start within 2× the loss).
                    continue;
                }
                let (ind, evals) = crate::optim::adam_search(objective, domain, &cand, &repair);
                spent += evals;
                let (cx, cv) = if ind.value < raw {
                    (ind.x, ind.value)
                } else {
                    (cand, raw)
                };
                if cv < best.as_ref().map_or(current, |b| b.1) {
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
    specs: &[crate::generators::ParamSpec],
    x: &mut [f64],
    current: &mut f64,
) -> usize {
    let mut spent = 0;
    for (i, s) in specs.iter().enumerate() {
        if !s.kind.is_continuous() {
            continue;
        }
        let mut best: Option<(f64, f64)> = None;
        for t in LINE_STEPS {
            let mut c = x.to_vec();
            c[i] = s.min + t * (s.max - s.min);
            domain.clamp(&mut c);
            let v = objective.value(&c);
            spent += 1;
            if v < best.map_or(*current, |b| b.1) {
                best = Some((c[i], v));
            }
        }
        if let Some((vi, v)) = best {
            x[i] = vi;
            *current = v;
        }
    }
    spent
}

/// Camera pitch candidates (radians; positive looks down on the object).
const PITCHES: [f64; 3] = [0.15, 0.45, 0.8];

/// Yaw turns of the seeds whose shape is not turn-symmetric (radians, about the side-on
/// guess). One silhouette barely tells a mug's handle turned 35° towards the camera from a
/// shorter one seen side-on, and neither Adam nor the memetic steps cross from one to the
/// other, so stage 1 starts from both.
const YAW_TURNS: [f64; 3] = [0.0, -0.6, 0.6];

/// Whether a mesh looks alike from every side, as far as its extent tells: equal widths along
/// X and Z (within 2 %), centred on the Y axis. A mug's handle breaks it, a bare bowl does not.
fn symmetric_about_y(mesh: &crate::generators::Mesh) -> bool {
    let Some((lo, hi)) = mesh.bounds() else {
        return true;
    };
    let size = hi - lo;
    let tol = 0.02 * size.max_element();
    (size.x - size.z).abs() <= tol && (lo.x + hi.x).abs() <= tol && (lo.z + hi.z).abs() <= tol
}

/// The layout, the domain and the seed points of a generator's stage 1: `start` (if any) and
/// then each of the generator's seeds, × each camera candidate (yaw turns too when `turn`),
/// with scale and translation solved per view from the mask's bounding box.
fn start_points(
    g: &'static dyn Generator,
    start: Option<&[f64]>,
    stats: &[MaskStats],
    fov: &[f64],
    fit_fov: bool,
    turn: bool,
) -> Result<(Layout, Domain, Vec<Vec<f64>>), FitError> {
    let layout = Layout {
        n_gen: g.params().len(),
        n_views: stats.len(),
        fit_fov,
        fov_y: fov.to_vec(),
    };
    let mut seeds = Vec::new();
    let (mut ls_lo, mut ls_hi) = (f64::INFINITY, f64::NEG_INFINITY);
    // The start first: with more seeds than places, screening keeps seed order on ties.
    for seed in start.map(<[f64]>::to_vec).into_iter().chain(g.seeds()) {
        let Ok(mesh) = g.generate(&seed, Lod::Low) else {
            continue;
        };
        // Turning a shape that looks the same from every side adds nothing but copies; with
        // more than one view, the others tell the turn, and so does a façade's window grid
        // (measured: with window labels the turned seeds only crowded the population, the
        // window test's final loss 0.0245 with them against 0.0076 without).
        let turns = if !turn || stats.len() > 1 || symmetric_about_y(&mesh) {
            &YAW_TURNS[..1]
        } else {
            &YAW_TURNS[..]
        };
        for yaw_flip in [false, true] {
            for (&pitch, &turn) in PITCHES
                .iter()
                .flat_map(|p| turns.iter().map(move |t| (p, t)))
            {
                let mut x = seed.clone();
                x.resize(layout.len(), 0.0);
                let mut ok = true;
                for (v, st) in stats.iter().enumerate() {
                    let yaw =
                        st.handle_yaw() + turn + if yaw_flip { std::f64::consts::PI } else { 0.0 };
                    let yaw = if yaw > std::f64::consts::PI {
                        yaw - std::f64::consts::TAU
                    } else {
                        yaw
                    };
                    match fit_box(&mesh.positions, st, yaw, pitch, fov[v]) {
                        Some(vars) => {
                            ls_lo = ls_lo.min(vars.log_scale);
                            ls_hi = ls_hi.max(vars.log_scale);
                            layout.set_view_vars(&mut x, v, &vars);
                        }
                        None => ok = false,
                    }
                }
                if ok {
                    seeds.push(x);
                }
            }
        }
    }
    if seeds.is_empty() {
        return Err(FitError(format!(
            "no seed of generator `{}` can be placed in the views",
            g.name()
        )));
    }
    let mut vars: Vec<Var> = Domain::from_specs(g.params())
        .map_err(|e| FitError(e.to_string()))?
        .vars()
        .to_vec();
    for (v, st) in stats.iter().enumerate() {
        let aspect = f64::from(st.width) / f64::from(st.height);
        vars.extend(view_domain(ls_lo, ls_hi, fov[v], fit_fov, aspect));
    }
    let domain = Domain::new(vars).map_err(|e| FitError(e.to_string()))?;
    Ok((layout, domain, seeds))
}

/// A fit in progress: [`FitConfig::restarts`] runs of the three stages from seeds far apart,
/// stepped side by side (in parallel with rayon: each run is deterministic on its own, so the
/// fit is too); the result is the run with the lowest final loss (the lower index on a tie).
pub struct Session {
    config: FitConfig,
    runs: Vec<Run>,
    /// The best finished run: its index, its result and its last progress.
    best: Option<(usize, FitResult, Progress)>,
}

/// Seed of run `k` of a fit seeded with `seed` (run 0 keeps it).
fn run_seed(seed: u64, k: usize) -> u64 {
    seed.wrapping_add((k as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15))
}

impl Session {
    /// Starts a fit of `masks` (one per view, all the same size). Nothing is evaluated yet.
    /// Errors on an unknown or non-differentiable generator, no masks or too many, masks of
    /// different sizes, empty or all-object masks, too small images, and bad settings.
    pub fn new(config: FitConfig, masks: Vec<Mask>) -> Result<Session, FitError> {
        let first = Run::new(config.clone(), masks.clone())?;
        let mut runs = vec![first];
        for k in 1..config.restarts {
            let c = FitConfig {
                seed: run_seed(config.seed, k),
                ..config.clone()
            };
            runs.push(Run::new(c, masks.clone())?);
        }
        Ok(Session {
            config,
            runs,
            best: None,
        })
    }

    /// Whether the fit is finished.
    pub fn is_done(&self) -> bool {
        self.runs.iter().all(Run::is_done)
    }

    /// Does one bounded slice of work in every unfinished run and reports progress. After the
    /// end it only reports.
    pub fn step(&mut self) -> Progress {
        use rayon::prelude::*;
        let finished: Vec<Option<Progress>> = self
            .runs
            .par_iter_mut()
            .map(|r| {
                if r.is_done() {
                    return None;
                }
                let p = r.step();
                p.done.then_some(p)
            })
            .collect();
        for (k, last) in finished.into_iter().enumerate() {
            let Some(last) = last else { continue };
            if let Ok(result) = self.runs[k].result()
                && self.best.as_ref().is_none_or(|(j, b, _)| {
                    result.loss < b.loss || (result.loss == b.loss && k < *j)
                })
            {
                self.best = Some((k, result, last));
            }
        }
        self.progress()
    }

    /// Steps until done and returns the result.
    pub fn run(&mut self) -> Result<FitResult, FitError> {
        while !self.step().done {}
        self.result()
    }

    /// The run whose stage, iteration and loss [`Session::progress`] shows: the first
    /// unfinished one (the last one once all are done).
    fn lead(&self) -> usize {
        self.runs
            .iter()
            .position(|r| !r.is_done())
            .unwrap_or(self.runs.len() - 1)
    }

    /// Where the fit stands (what [`Session::step`] returns). Stage, iteration and loss are
    /// the lead run's ([`Progress::run`]); evaluations and work add up all runs; the
    /// parameters, cameras and preview are the best finished run's once there is one (an
    /// early stage of another run is no better to look at).
    pub fn progress(&self) -> Progress {
        let lead = self.lead();
        let mut p = self.runs[lead].progress();
        p.evaluations = self.runs.iter().map(|r| r.evaluations).sum();
        p.work_total = self.runs.iter().map(|r| r.work_total).sum();
        p.work_done = self
            .runs
            .iter()
            .map(|r| {
                if r.is_done() {
                    r.work_total
                } else {
                    r.work_done
                }
            })
            .sum::<f64>()
            .min(p.work_total);
        if let Some((_, _, best)) = &self.best {
            p.generator = best.generator;
            p.params = best.params.clone();
            p.cameras = best.cameras.clone();
            p.preview = best.preview.clone();
        }
        p.run = lead + 1;
        p.runs = self.runs.len();
        p.done = self.is_done();
        p
    }

    /// The best model and cameras so far (the final result once done): the best finished
    /// run's, or the lead run's before any has finished. Errors only when nothing could be
    /// evaluated.
    pub fn result(&self) -> Result<FitResult, FitError> {
        let evaluations = self.runs.iter().map(|r| r.evaluations).sum();
        match &self.best {
            Some((_, r, _)) => Ok(r.clone()),
            None => self.runs[self.lead()].result(),
        }
        .map(|mut r| {
            r.evaluations = evaluations;
            // The fit's seed, not the run's: it reproduces the whole fit.
            r.model.seed = Some(self.config.seed);
            r
        })
    }

    /// The fields of view used for the views.
    pub fn fov(&self) -> &[f64] {
        self.runs[0].fov()
    }
}
