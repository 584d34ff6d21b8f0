//! The tree fit's edge: a [`TreeFitSession`] is an opaque handle around the core's resumable
//! tree fit ([`crate::tree::impostor::TreeSession`], paper §3.5), stepped by the worker in
//! slices like [`super::FitSession`]; cancelling is not stepping any more.
//!
//! The JavaScript API (all numbers plain, arrays typed):
//!
//! ```js
//! // A photo: RGBA bytes (width × height × 4), labelled by colour (green → leaf, brown/grey →
//! // branch); `codes` is the mask step's output (0 background, 128 don't care, else object;
//! // one byte a pixel) or an empty array to label the whole photo. `quality`: the effort, in
//! // (0, 16]; 1 is the default 1 152 GA evaluations (`ga_budget_for_quality`). `start`: a
//! // tree's parameters (Float64Array) to refit from ("Refit from here": its seed is kept, the
//! // result is never less similar than it), or an empty array to fit from scratch. `fovY`:
//! // the photo's vertical field of view in radians (`fovFromFocal35mm` of its EXIF focal
//! // length), or 0 when unknown (the fit's default). The photo is labelled with the default colours.
//! const fit = new TreeFitSession(width, height, rgba, codes, seed, quality, start, fovY);
//! // Or a label image: 0 background, 1 branch, 2 leaf, 255 don't care — such as the labels of
//! // a photo under other colour rules: `colors` is an object of `ColorThresholds`' camelCase
//! // fields (any left out keep their defaults: `{ leafHue: [330, 170], restAsBranch: true }`)
//! // or undefined for the defaults.
//! const defaults = treeColorDefaults(); // ColorThresholds::default() as such an object
//! const labels = treeLabels(width, height, rgba, codes, colors); // also what the page shows
//! const fit = TreeFitSession.fromLabels(width, height, labels, seed, quality, start, fovY);
//! // Both throw an Error with a sentence for a mask with no tree, no leaves or no branches,
//! // or a start that is not a tree's parameters.
//! const p = fit.step(); // one GA generation (or the seed trials, or a local-search round)
//! // p = { stage: 1 | 2 | 3, generation, evaluations, total_evaluations,
//! //       best_similarity, params: number[], done }
//! if (fit.previewWidth() > 0) {            // the best tree's labels changed in this step
//!   const labels = fit.previewLabels();    // Uint8Array, previewWidth × previewHeight (128²)
//! }
//! const r = fit.result(); // { generator: the tree generator's name, params, lod, seed, similarity,
//! //                          start_similarity (undefined without a start), evaluations,
//! //                          cameras: Float32Array-able number[18] (yfov, aspect, 16 floats
//! //                          camera-to-world, column-major): the photo's camera for generateGlb,
//! //                          photo_ious: [the photo-view IoU], match_level, match_warning
//! //                          (a sentence when below the level, else undefined),
//! //                          carved_photo_iou: the photo-view IoU at the photo's size of the
//! //                          tree as shown, HIGH, carved }
//! // The photo that carves the tree where it sees through it: kept by the
//! // worker and passed to generateCarvedGlb / exportCarvedFiles (generateGlb's and
//! // exportFiles' arguments, then it) while the page shows this fit's tree, edited or not.
//! const carve = fit.carve(); // a TreeCarve; carve.free() when done with it
//! ```
//!
//! Deterministic for a seed. The preview is in the fit's square frame (the photo's tree
//! scaled to 80 % of its height, foot at the bottom centre), not the photo's.

use super::js;
use crate::generators::Generator;
use crate::mask::LabelImage;
use crate::tree::carve::{CARVE_GRID, LeafCarve};
use crate::tree::impostor::{
    Framing, PhotoFitOptions, PhotoTreeFit, TreeSession, ga_budget_for_quality,
    start_photo_fit_with,
};
use crate::tree::labels::{ColorThresholds, apply_mask_codes, labels_from_rgb, labels_from_values};
use wasm_bindgen::prelude::*;

/// A tree fit in progress.
#[wasm_bindgen]
pub struct TreeFitSession {
    session: TreeSession,
    framing: Framing,
    seed: u32,
    preview: Option<LabelImage>,
    /// The photo's labels the fit uses, at the photo's size: what carves the result.
    labels: LabelImage,
}

/// A fitted tree's photo that carves it ([`crate::tree::carve::LeafCarve`]): made by
/// [`TreeFitSession::carve`], passed to `generateCarvedGlb` and `exportCarvedFiles` while the
/// page shows that fit's tree (the parameters may have been edited since).
#[wasm_bindgen]
pub struct TreeCarve(pub(crate) std::sync::Arc<LeafCarve>);

#[derive(serde::Serialize)]
struct StepOut {
    stage: u8,
    generation: usize,
    evaluations: usize,
    total_evaluations: usize,
    best_similarity: f64,
    params: Vec<f64>,
    done: bool,
}

#[derive(serde::Serialize)]
struct ResultOut {
    generator: &'static str,
    params: Vec<f64>,
    lod: u8,
    seed: u32,
    similarity: f64,
    /// The start tree's similarity (`None` without a start, or before the first step).
    start_similarity: Option<f64>,
    evaluations: usize,
    cameras: Vec<f32>,
    /// The photo's photo-view IoU (one entry): the tree pixels' silhouette IoU through the
    /// photo's camera, what the CLI prints.
    photo_ious: Vec<f64>,
    /// The level below which the tree is said not to match (the tree generator's
    /// `Capabilities::photo_match_level`).
    match_level: f64,
    /// The photo-view IoU at the photo's size of the tree as the page shows it (HIGH, its
    /// carved by the photo, `carve`).
    carved_photo_iou: f64,
    /// What is wrong and what to try when below the level (`None` otherwise).
    match_warning: Option<String>,
}

impl TreeFitSession {
    fn leaf_carve(&self) -> Result<LeafCarve, JsError> {
        let view = self.framing.photo_view().map_err(js)?;
        LeafCarve::new(self.labels.clone(), view, CARVE_GRID).map_err(js)
    }

    fn start(
        labels: &LabelImage,
        seed: u32,
        quality: f64,
        start: &[f64],
        fov_y: f64,
    ) -> Result<TreeFitSession, JsError> {
        let start = (!start.is_empty()).then_some(start);
        // The core's policy turns the effort into GA evaluations, as for the CLI.
        let budget = ga_budget_for_quality(quality).map_err(js)?;
        // 0 (or anything not positive): the photo's field of view is unknown.
        let options = PhotoFitOptions {
            fov_y: (fov_y > 0.0).then_some(fov_y),
            ..PhotoFitOptions::default()
        };
        let PhotoTreeFit { session, framing } =
            start_photo_fit_with(labels, u64::from(seed), budget, start, &options).map_err(js)?;
        Ok(TreeFitSession {
            session,
            framing,
            seed,
            preview: None,
            labels: labels.clone(),
        })
    }
}

/// The labels a tree fit of this photo would use (see [`TreeFitSession::new`]): 0 background,
/// 1 branch, 2 leaf, 255 don't care, row-major; for the page's preview over the photo.
#[wasm_bindgen(js_name = treeLabels)]
pub fn tree_labels(
    width: u32,
    height: u32,
    rgba: &[u8],
    codes: &[u8],
    colors: JsValue,
) -> Result<Vec<u8>, JsError> {
    Ok(photo_labels(width, height, rgba, codes, colors)?
        .labels()
        .to_vec())
}

/// The default colour rules ([`ColorThresholds::default`]) as a JS object of camelCase fields:
/// what the page's "Adjust the colours" shows before any change.
#[wasm_bindgen(js_name = treeColorDefaults)]
pub fn tree_color_defaults() -> Result<JsValue, JsError> {
    serde_wasm_bindgen::to_value(&ColorThresholds::default()).map_err(js)
}

/// The colour rules from JS: undefined or null for the defaults, else an object of
/// [`ColorThresholds`]' camelCase fields (checked; unknown fields refused).
fn colors_of(colors: JsValue) -> Result<ColorThresholds, JsError> {
    if colors.is_undefined() || colors.is_null() {
        return Ok(ColorThresholds::default());
    }
    let t: ColorThresholds = serde_wasm_bindgen::from_value(colors)
        .map_err(|e| JsError::new(&format!("tree colours: {e}")))?;
    t.check().map_err(js)?;
    Ok(t)
}

/// A photo's tree labels by colour, limited to its mask (`codes`; empty: the whole photo).
fn photo_labels(
    width: u32,
    height: u32,
    rgba: &[u8],
    codes: &[u8],
    colors: JsValue,
) -> Result<LabelImage, JsError> {
    let labels = labels_from_rgb(width, height, rgba, 4, &colors_of(colors)?).map_err(js)?;
    if codes.is_empty() {
        Ok(labels)
    } else {
        apply_mask_codes(&labels, codes).map_err(js)
    }
}

#[wasm_bindgen]
impl TreeFitSession {
    /// Starts a fit to a photo, from the tree `start` unless it is empty, through the
    /// photo's field of view `fov_y` (radians; 0 when unknown) (see the module doc); nothing
    /// is evaluated yet.
    #[wasm_bindgen(constructor)]
    #[allow(
        clippy::too_many_arguments,
        reason = "the JS constructor takes flat values, as the module doc lists them"
    )]
    pub fn new(
        width: u32,
        height: u32,
        rgba: &[u8],
        codes: &[u8],
        seed: u32,
        quality: f64,
        start: &[f64],
        fov_y: f64,
    ) -> Result<TreeFitSession, JsError> {
        TreeFitSession::start(
            &photo_labels(width, height, rgba, codes, JsValue::UNDEFINED)?,
            seed,
            quality,
            start,
            fov_y,
        )
    }

    /// Starts a fit to a label image (0 background, 1 branch, 2 leaf, 255 don't care), seen
    /// through the field of view `fov_y` (radians; 0 when unknown).
    #[wasm_bindgen(js_name = fromLabels)]
    pub fn from_labels(
        width: u32,
        height: u32,
        labels: &[u8],
        seed: u32,
        quality: f64,
        start: &[f64],
        fov_y: f64,
    ) -> Result<TreeFitSession, JsError> {
        let labels = labels_from_values(width, height, labels.to_vec()).map_err(js)?;
        TreeFitSession::start(&labels, seed, quality, start, fov_y)
    }

    /// One bounded slice of work; returns where the fit stands.
    pub fn step(&mut self) -> Result<JsValue, JsError> {
        let p = self.session.step();
        self.preview = p.preview;
        let out = StepOut {
            stage: p.stage,
            generation: p.generation,
            evaluations: p.evaluations,
            total_evaluations: p.total_evaluations,
            best_similarity: p.best_similarity,
            params: p.best_params,
            done: p.done,
        };
        serde_wasm_bindgen::to_value(&out).map_err(js)
    }

    /// Width of the preview of the last step (0 when it brought none).
    #[wasm_bindgen(js_name = previewWidth)]
    pub fn preview_width(&self) -> u32 {
        self.preview.as_ref().map_or(0, LabelImage::width)
    }

    /// Height of the preview of the last step (0 when it brought none).
    #[wasm_bindgen(js_name = previewHeight)]
    pub fn preview_height(&self) -> u32 {
        self.preview.as_ref().map_or(0, LabelImage::height)
    }

    /// The best tree's label image (0 background, 1 branch, 2 leaf), row-major; empty when the
    /// last step brought none.
    #[wasm_bindgen(js_name = previewLabels)]
    pub fn preview_labels(&self) -> Vec<u8> {
        self.preview
            .as_ref()
            .map_or_else(Vec::new, |p| p.labels().to_vec())
    }

    /// The part colours of the best tree so far from its photo: `labels` the photo's branch and
    /// leaf labels the fit used (`treeLabels`), `rgba` the photo at their size. Returns what
    /// `FitSession.partColors` does.
    #[wasm_bindgen(js_name = partColors)]
    pub fn part_colors(
        &self,
        width: u32,
        height: u32,
        labels: &[u8],
        rgba: &[u8],
    ) -> Result<JsValue, JsError> {
        let fit = self.session.result().map_err(js)?;
        let labels = labels_from_values(width, height, labels.to_vec()).map_err(js)?;
        let mesh = crate::generators::tree::TreeGenerator
            .generate(&fit.params, crate::generators::Lod::Low)
            .map_err(js)?;
        let photo = crate::colors::Rgba {
            width,
            height,
            pixels: rgba,
        };
        let found = crate::colors::from_tree_labels(&mesh, &labels, &photo).map_err(js)?;
        super::colors_out(&found)
    }

    /// The photo that carves this fit's tree: its labels and camera
    /// ([`crate::tree::carve::CARVE_GRID`] tiles a card side).
    pub fn carve(&self) -> Result<TreeCarve, JsError> {
        Ok(TreeCarve(std::sync::Arc::new(self.leaf_carve()?)))
    }

    /// The best tree so far (the result once done) and the photo's camera.
    pub fn result(&self) -> Result<JsValue, JsError> {
        let fit = self.session.result().map_err(js)?;
        let view = self.framing.photo_view().map_err(js)?;
        let cameras = crate::reconstruct::export_camera(&view, None)
            .to_floats()
            .to_vec();
        let iou = self.session.silhouette_iou().map_err(js)?;
        let mesh = crate::generators::tree::TreeGenerator
            .generate(&fit.params, crate::generators::Lod::High)
            .map_err(js)?;
        let (carved, _) = self.leaf_carve()?.apply(&mesh).map_err(js)?;
        let match_level =
            crate::reconstruct::eval::photo_match_level(&crate::generators::tree::TreeGenerator);
        let carved_photo_iou =
            crate::tree::bench::photo_view_iou(&carved, &view, &self.labels).map_err(js)?;
        let out = ResultOut {
            carved_photo_iou,
            photo_ious: vec![iou],
            match_level,
            match_warning: crate::reconstruct::eval::tree_match_warning(
                iou,
                match_level,
                "“Adjust the colours” in the mask step",
            ),
            // The tree GA fits the tree generator and no other.
            generator: crate::generators::tree::TreeGenerator.name(),
            params: fit.params,
            lod: crate::generators::Lod::High as u8,
            seed: self.seed,
            similarity: fit.similarity,
            start_similarity: self.session.start_similarity(),
            evaluations: fit.ga.evaluations,
            cameras,
        };
        serde_wasm_bindgen::to_value(&out).map_err(js)
    }
}
