//! What a fit is asked to do ([`FitConfig`]) and its checking, done once per fit: every bad
//! setting or mask is refused here with a one-line message, and what the runs share (fields of
//! view, mask statistics, the generators to try, the start, the window term) comes out as a
//! `Plan`.

use super::FitError;
use super::objective::resample_mask;
use super::rim::{DEFAULT_RIM_WEIGHT, Luma, RimTerm};
use super::views::{DEFAULT_FOV_Y, MaskStats, mask_stats};
use super::windows::{DEFAULT_WINDOW_WEIGHT, WindowTerm};
use crate::generators::{self, Generator, Lod};
use crate::mask::{LabelImage, Mask};
use std::sync::Arc;

/// Stage-1 evaluations at quality 1: the reference schedule's ~5000 at 128² (notes "Optimisers
/// and schedule"). Measured (benches/reconstruct.rs): buildings gain from it (mean IoU-64 0.89 →
/// 0.96 over 2000), dishes are limited by what one view can tell, and one run takes ~2–3 s
/// natively (a fit makes [`FitConfig::restarts`] of them side by side: ~4 s on 2 threads).
pub const DEFAULT_EVALUATIONS: usize = 5000;

/// Largest number of [`FitConfig::restarts`].
pub const MAX_RESTARTS: usize = 16;

/// [`FitConfig::restarts`] by default: the best of three runs (see its doc for the measurement).
pub const DEFAULT_RESTARTS: usize = 3;

/// Largest [`FitConfig::quality`] a fit takes, from the page's slider and the CLI alike (16 ×
/// the default budget is already minutes of work a run).
pub const MAX_QUALITY: f64 = 16.0;

/// Checks a [`FitConfig::quality`] (the page's effort, the CLI's `--quality`, a tree fit's
/// too): finite and in (0, [`MAX_QUALITY`]]. The error says which value and the range.
pub fn check_quality(quality: f64) -> Result<(), String> {
    if quality.is_finite() && quality > 0.0 && quality <= MAX_QUALITY {
        Ok(())
    } else {
        Err(format!("quality {quality} is not in (0, {MAX_QUALITY}]"))
    }
}

/// Below this quality a fit is a quick preview: one run, not the best of several
/// ([`FitConfig::restarts_for`]).
pub const QUICK_QUALITY: f64 = 0.5;

/// Largest number of input views.
pub const MAX_VIEWS: usize = 16;

/// What to fit and how hard to try.
#[derive(Clone, Debug, PartialEq)]
pub struct FitConfig {
    /// Generator machine name, or `auto`.
    pub generator: String,
    /// Seed of every random choice.
    pub seed: u64,
    /// Quality/speed knob: multiplies every stage's budget (1 = default; 0.25 a quick preview,
    /// 4 a thorough fit). More is not better on the Mitsuba dish photos: at 2 the mean IoU-64
    /// at seeds 0 / 1 / 2 falls from 0.930 / 0.934 / 0.926 to 0.907 / 0.901 / 0.886 (the
    /// serving bowl at seed 2 0.930 → 0.517; `cargo bench --bench dish_photo_bench -- --fov
    /// known --seed N --quality 2`): a lower loss from one photo, not a truer model.
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
    /// Weight of the generator's shape prior ([`Generator::shape_prior`]) in stages 2 and 3
    /// (relative to the MSE); stage 1 leaves it out. Measured on the Mitsuba dish photos (mean
    /// IoU-64, lens known, seeds 0 / 1 / 2): 0 → 0.916 / 0.910 / 0.923, 1e-4 0.919 / 0.921 /
    /// 0.918, 1e-3 0.928 / 0.923 / 0.910; in stage 1 too (at its regulariser's 1e-2) 0.933 /
    /// 0.934 / 0.944, but the measured mug from masks (12 cameras) fell from 0.969 (worst 0.952)
    /// to 0.944 (0.890); with 1e-4 in stages 2 and 3 only, 0.964 (0.934). A stage-1 weight of
    /// its own, added to the search's objective: 1e-3 → 0.938 / 0.911 / 0.900 (mug 0.946, worst
    /// 0.758), 3e-3 → 0.923 / 0.910 / 0.937 (0.960, 0.906), 1e-2 → 0.933 / 0.934 (mug 0.944,
    /// 0.890; from 24 cameras 0.939, worst 0.667, against 0.950, worst 0.871, without it). The
    /// dishes' gain does not pay for the mugs' handle turned the wrong way.
    pub prior_weight: f64,
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
    /// The photo of each view, as brightness at its mask's size ([`super::rim`]): missing or
    /// `None` entries (a mask image) have none. A generator with edge rings
    /// ([`Generator::edge_rings`]: a dish's rim, a cup's foot on a saucer) lays them on the
    /// photo's edges.
    pub photos: Vec<Option<Luma>>,
    /// Weight of the rim term relative to the silhouette MSE (0: off).
    pub rim_weight: f64,
    /// Whether small things in a mask that are not the object (a spoon, a tea bag's string
    /// and tag: thin spurs and small separate pieces, [`super::extras`]) are made don't care
    /// before the fit. On by default.
    pub ignore_extras: bool,
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
            prior_weight: 1e-4,
            restarts: DEFAULT_RESTARTS,
            resolutions: [128, 256, 512],
            // The paper runs stage 1 at LOW detail. Our dish's LOW mesh (12 sectors) is so
            // polygonal that, measured on random dishes, the true shape scored worse at 128² than
            // a wrong camera pitch; MEDIUM (24 sectors) does not have that problem.
            lods: [Lod::Low, Lod::Medium, Lod::High],
            start: None,
            windows: Vec::new(),
            window_weight: DEFAULT_WINDOW_WEIGHT,
            photos: Vec::new(),
            rim_weight: DEFAULT_RIM_WEIGHT,
            ignore_extras: true,
        }
    }
}

/// A checked fit: what every run of it starts from.
#[derive(Clone)]
pub(super) struct Plan {
    /// The window term, shared by every stage's objective.
    pub windows: Option<Arc<WindowTerm>>,
    /// The masks at each stage's resolution, shared by every run.
    pub stage_masks: Arc<[Vec<Mask>; 3]>,
    /// The rim term of each stage (for its masks), shared by every run.
    pub rim: [Option<Arc<RimTerm>>; 3],
    /// Per view: what its mask tells.
    pub stats: Vec<MaskStats>,
    /// Per view: its vertical field of view.
    pub fov: Vec<f64>,
    /// The generators stage 1 tries (one, or every differentiable one for `auto`).
    pub candidates: Vec<&'static dyn Generator>,
    /// The start parameters, sanitised.
    pub start: Option<Vec<f64>>,
    /// Stage-1 evaluations of a run.
    pub stage1: usize,
}

impl FitConfig {
    /// The runs a fit of `generator` (a name, or `auto`) at `quality` makes unless told
    /// otherwise, the one policy of the page, the CLI and the benches: one below
    /// [`QUICK_QUALITY`] (a quick preview), else the generator's own number
    /// ([`Capabilities::fit_runs`](crate::generators::Capabilities::fit_runs): six for a
    /// building, five for a dish), and [`DEFAULT_RESTARTS`] for `auto` or an unknown name.
    pub fn restarts_for(generator: &str, quality: f64) -> usize {
        if quality < QUICK_QUALITY {
            return 1;
        }
        crate::generators::by_name(generator)
            .map_or(DEFAULT_RESTARTS, |g| g.capabilities().fit_runs.max(1))
    }

    /// Stage-1 evaluations asked for: the budget, or [`DEFAULT_EVALUATIONS`] × quality.
    pub(super) fn stage1_evaluations(&self) -> usize {
        self.budget
            .unwrap_or(((DEFAULT_EVALUATIONS as f64) * self.quality).round() as usize)
    }

    /// Checks the settings against `masks` (one per view, all the same size). Errors on an
    /// unknown or non-differentiable generator, no masks or too many, masks of different
    /// sizes, empty or all-object masks, too small images, and bad settings.
    pub(super) fn plan(&self, masks: &[Mask]) -> Result<Plan, FitError> {
        let config = self;
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
        check_quality(config.quality).map_err(FitError)?;
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
        if !(config.prior_weight.is_finite() && config.prior_weight >= 0.0) {
            return Err(FitError("the shape prior's weight must be ≥ 0".into()));
        }
        if config.resolutions.iter().any(|&r| !(8..=4096).contains(&r)) {
            return Err(FitError("stage resolutions must be within 8..=4096".into()));
        }
        if !(config.rim_weight.is_finite() && config.rim_weight >= 0.0) {
            return Err(FitError("the rim weight must be ≥ 0".into()));
        }
        if config.photos.len() > masks.len() {
            return Err(FitError(format!(
                "{} photos for {} views",
                config.photos.len(),
                masks.len()
            )));
        }
        for (i, p) in config.photos.iter().enumerate() {
            if let Some(p) = p
                && (p.width(), p.height()) != (w0, h0)
            {
                return Err(FitError(format!(
                    "photo {} is {}×{}, its mask {w0}×{h0}",
                    i + 1,
                    p.width(),
                    p.height()
                )));
            }
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
        let stage1 = config.stage1_evaluations().max(1);
        let stage_masks: Arc<[Vec<Mask>; 3]> = Arc::new(
            config
                .resolutions
                .map(|side| masks.iter().map(|m| resample_mask(m, side)).collect()),
        );
        let rim = [0, 1, 2].map(|i| {
            RimTerm::new(&config.photos, &stage_masks[i], config.rim_weight).map(Arc::new)
        });
        Ok(Plan {
            windows,
            stage_masks,
            rim,
            stats,
            fov,
            candidates,
            start,
            stage1,
        })
    }
}
