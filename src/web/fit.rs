//! The fit step's edge: a [`FitSession`] is an opaque handle around the core's resumable
//! reconstruction `Session`. The worker calls [`FitSession::step`] in slices and yields to its
//! message loop between them, so the page stays responsive and a cancel arrives promptly;
//! cancelling is simply not stepping any more.

use super::js;
use crate::mask::{LabelImage, Mask};
use crate::reconstruct::{FitConfig, Luma, Session, eval, export_camera};
use wasm_bindgen::prelude::*;

/// A fit in progress.
#[wasm_bindgen]
pub struct FitSession {
    session: Session,
    /// The masks the fit was given: for the part colours' object pixels and to say how well its
    /// result matches each photo.
    masks: Vec<Mask>,
    /// The last progress's silhouette preview (view 0), as 0..255 coverage.
    preview: Option<(u32, u32, Vec<u8>)>,
}

/// One step's news for the page (the preview is fetched separately, as bytes).
#[derive(serde::Serialize)]
struct StepOut {
    stage: u8,
    generator: &'static str,
    iteration: usize,
    evaluations: usize,
    work_done: f64,
    work_total: f64,
    /// `null` before anything was evaluated.
    best_loss: Option<f64>,
    params: Vec<f64>,
    /// The run (1-based) whose stage and loss these are, of `runs` (fits from other seeds,
    /// stepped side by side; the best one is the result).
    run: usize,
    runs: usize,
    /// Of `runs`, those added from other shapes because the first runs' best model did not
    /// match a photo (`Session::rescue_runs`).
    rescue_runs: usize,
    done: bool,
}

/// The fitted model and its cameras.
#[derive(serde::Serialize)]
struct ResultOut {
    generator: &'static str,
    params: Vec<f64>,
    lod: u8,
    seed: Option<u64>,
    loss: f64,
    evaluations: usize,
    /// One camera per photo, [`super::CAMERA_FLOATS`] numbers each, for `generateGlb`.
    cameras: Vec<f32>,
    /// Each photo's photo-view IoU: the model at `lod` (the fit's finest stage's, the least
    /// detail the page opens it at) through its fitted camera against the photo's mask,
    /// don't-care excluded (`eval::result_photo_ious`, what the CLI prints).
    photo_ious: Vec<f64>,
    /// The level below which a photo is said not to be matched (the generator's
    /// `Capabilities::photo_match_level`).
    match_level: f64,
    /// What is wrong and what to try when a photo is below the level (`None` otherwise).
    match_warning: Option<String>,
    /// How well the photos fix the shape (`eval::agreement`, what the CLI prints): `None`
    /// before the end, with one run, or when no other run matched about as well.
    agreement: Option<f64>,
    /// What it means and what to try when it is below `eval::AGREEMENT_LEVEL`.
    agreement_warning: Option<String>,
    /// That the window labels given were left out, and why (`eval::windows_left_out_note`).
    windows_note: Option<String>,
    /// What one photo cannot tell about the fitted shape (`eval::one_view_caveat`).
    caveat: Option<String>,
}

/// Masks from 8-bit codes (object 255, background 0, don't care 128, anything else a soft
/// coverage), `widths[i] × heights[i]` each, concatenated.
fn masks_of(widths: &[u32], heights: &[u32], codes: &[u8]) -> Result<Vec<Mask>, JsError> {
    if widths.len() != heights.len() {
        return Err(JsError::new("one width and one height per mask"));
    }
    let mut masks = Vec::with_capacity(widths.len());
    let mut at = 0usize;
    for (&w, &h) in widths.iter().zip(heights) {
        let n = w as usize * h as usize;
        let Some(slice) = codes.get(at..at + n) else {
            return Err(JsError::new(
                "the mask bytes are shorter than the sizes say",
            ));
        };
        let values = slice
            .iter()
            .map(|&c| {
                if c == 128 {
                    Mask::DONT_CARE
                } else {
                    f32::from(c) / 255.0
                }
            })
            .collect();
        masks.push(Mask::new(w, h, values).map_err(js)?);
        at += n;
    }
    if at != codes.len() {
        return Err(JsError::new("the mask bytes are longer than the sizes say"));
    }
    Ok(masks)
}

/// Window labels per view: `flags[i]` is 1 when view `i` has labels, and `codes` holds the
/// labels of the flagged views only (0 background, 1 façade, 2 window, 255 don't care),
/// `widths[i] × heights[i]` each, concatenated. Empty `flags`: no view has labels.
fn windows_of(
    widths: &[u32],
    heights: &[u32],
    flags: &[u8],
    codes: &[u8],
) -> Result<Vec<Option<LabelImage>>, JsError> {
    if flags.is_empty() {
        return if codes.is_empty() {
            Ok(Vec::new())
        } else {
            Err(JsError::new(
                "window labels without the views they belong to",
            ))
        };
    }
    if flags.len() != widths.len() {
        return Err(JsError::new(&format!(
            "{} window flags for {} masks",
            flags.len(),
            widths.len()
        )));
    }
    let mut out = Vec::with_capacity(flags.len());
    let mut at = 0usize;
    for ((&w, &h), &f) in widths.iter().zip(heights).zip(flags) {
        if f == 0 {
            out.push(None);
            continue;
        }
        let n = w as usize * h as usize;
        let Some(slice) = codes.get(at..at + n) else {
            return Err(JsError::new(
                "the window label bytes are shorter than the sizes say",
            ));
        };
        out.push(Some(LabelImage::new(w, h, slice.to_vec()).map_err(js)?));
        at += n;
    }
    if at != codes.len() {
        return Err(JsError::new(
            "the window label bytes are longer than the sizes say",
        ));
    }
    Ok(out)
}

/// The photos' brightness per view from their RGBA pixels (`widths[i] × heights[i]` each,
/// concatenated); empty `rgba`: no photos.
fn photos_of(widths: &[u32], heights: &[u32], rgba: &[u8]) -> Result<Vec<Option<Luma>>, JsError> {
    if rgba.is_empty() {
        return Ok(Vec::new());
    }
    let total: usize = widths
        .iter()
        .zip(heights)
        .map(|(&w, &h)| 4 * w as usize * h as usize)
        .sum();
    if rgba.len() != total {
        return Err(JsError::new(&format!(
            "{} photo bytes for masks of {total} RGBA bytes",
            rgba.len()
        )));
    }
    let mut at = 0usize;
    widths
        .iter()
        .zip(heights)
        .map(|(&w, &h)| {
            let n = 4 * w as usize * h as usize;
            let luma = Luma::from_rgba(w, h, &rgba[at..at + n]).map_err(js)?;
            at += n;
            Ok(Some(luma))
        })
        .collect()
}

#[wasm_bindgen]
impl FitSession {
    /// Starts a fit of `generator` (or `auto`) to the masks (see `masks_of`); nothing is
    /// evaluated yet. `quality` scales every stage's budget (1 = default). `fov_y`: one
    /// vertical field of view (radians) per mask, 0 where unknown (the default is used), or
    /// empty. `start`: the generator's parameters to start from ("refit from here"; a named
    /// generator only), or empty. `window_flags`/`window_codes`: window labels for the views
    /// that have them (buildings; see `windows_of`), or both empty. `photos`: the photos'
    /// sRGB RGBA pixels, one per view at its mask's size, concatenated (the rim term of
    /// `reconstruct::rim` reads their edges), or empty.
    #[wasm_bindgen(constructor)]
    #[allow(
        clippy::too_many_arguments,
        reason = "flat numbers and typed arrays are what crosses the wasm boundary cheaply"
    )]
    pub fn new(
        generator: &str,
        seed: u32,
        quality: f64,
        widths: &[u32],
        heights: &[u32],
        codes: &[u8],
        fov_y: &[f64],
        start: &[f64],
        window_flags: &[u8],
        window_codes: &[u8],
        photos: &[u8],
    ) -> Result<FitSession, JsError> {
        if !fov_y.is_empty() && fov_y.len() != widths.len() {
            return Err(JsError::new(&format!(
                "{} fields of view for {} masks",
                fov_y.len(),
                widths.len()
            )));
        }
        let config = FitConfig {
            generator: generator.to_string(),
            seed: u64::from(seed),
            quality,
            // 0 stands for "unknown"; anything else is checked by the session.
            fov_y: fov_y.iter().map(|&f| (f != 0.0).then_some(f)).collect(),
            start: (!start.is_empty()).then(|| start.to_vec()),
            windows: windows_of(widths, heights, window_flags, window_codes)?,
            // The core's policy: a quick preview is one run (quality is checked there too).
            restarts: FitConfig::restarts_for(generator, quality),
            photos: photos_of(widths, heights, photos)?,
            ..FitConfig::default()
        };
        let masks = masks_of(widths, heights, codes)?;
        let session = Session::new(config, masks.clone()).map_err(js)?;
        Ok(FitSession {
            session,
            masks,
            preview: None,
        })
    }

    /// One bounded slice of work; returns where the fit stands.
    pub fn step(&mut self) -> Result<JsValue, JsError> {
        let p = self.session.step();
        self.preview = self
            .session
            .preview()
            .map(|m| (m.width(), m.height(), m.to_luma8()));
        let out = StepOut {
            stage: p.stage,
            generator: p.generator,
            iteration: p.iteration,
            evaluations: p.evaluations,
            work_done: p.work_done,
            work_total: p.work_total,
            best_loss: p.best_loss.is_finite().then_some(p.best_loss),
            params: p.params,
            run: p.run,
            runs: p.runs,
            rescue_runs: p.rescue_runs,
            done: p.done,
        };
        serde_wasm_bindgen::to_value(&out).map_err(js)
    }

    /// Width of the last preview (0 when there is none).
    #[wasm_bindgen(js_name = previewWidth)]
    pub fn preview_width(&self) -> u32 {
        self.preview.as_ref().map_or(0, |p| p.0)
    }

    /// Height of the last preview (0 when there is none).
    #[wasm_bindgen(js_name = previewHeight)]
    pub fn preview_height(&self) -> u32 {
        self.preview.as_ref().map_or(0, |p| p.1)
    }

    /// The last preview silhouette of view 0 as 0..255 coverage, row-major (empty when none).
    #[wasm_bindgen(js_name = previewCoverage)]
    pub fn preview_coverage(&self) -> Vec<u8> {
        self.preview.as_ref().map_or_else(Vec::new, |p| p.2.clone())
    }

    /// The part colours of the best model so far, measured in the photos: `rgba` holds one
    /// sRGB RGBA photo per view at its mask's size, concatenated (the masks' sizes). Returns
    /// `{ colors: { part: [r, g, b] }, parts: [{ part, color, source, from }], note }`:
    /// `colors` what the model takes (measured or borrowed), `parts` where each part's colour
    /// comes from (`photo`, `neighbour` of `from`, or `default`), `note` a sentence on the
    /// parts the photos do not show, or `null`.
    #[wasm_bindgen(js_name = partColors)]
    pub fn part_colors(&self, rgba: &[u8]) -> Result<JsValue, JsError> {
        use crate::colors::{self, Rgba};
        let r = self.session.result().map_err(js)?;
        let masks = &self.masks;
        let mut photos = Vec::with_capacity(masks.len());
        let mut at = 0usize;
        for m in masks {
            let n = 4 * m.width() as usize * m.height() as usize;
            let Some(pixels) = rgba.get(at..at + n) else {
                return Err(JsError::new(
                    "the photo bytes are shorter than the masks say",
                ));
            };
            photos.push(Rgba {
                width: m.width(),
                height: m.height(),
                pixels,
            });
            at += n;
        }
        if at != rgba.len() {
            return Err(JsError::new(
                "the photo bytes are longer than the masks say",
            ));
        }
        let mesh = r
            .model
            .generator
            .generate(&r.model.params, r.model.lod)
            .map_err(js)?;
        let found = colors::estimate(&mesh, &r.views, &photos, masks).map_err(js)?;
        super::colors_out(&found)
    }

    /// The best model so far (the result once done).
    pub fn result(&self) -> Result<JsValue, JsError> {
        let r = self.session.result().map_err(js)?;
        let cameras: Vec<f32> = r
            .views
            .iter()
            .flat_map(|v| export_camera(v, None).to_floats())
            .collect();
        let photo_ious = eval::result_photo_ious(&r, &self.masks).map_err(js)?;
        let match_level = eval::photo_match_level(r.model.generator);
        let agreement = self.session.agreement().map_err(js)?;
        let out = ResultOut {
            agreement,
            agreement_warning: eval::agreement_warning(
                agreement,
                self.session.front_only().map_err(js)?,
            ),
            windows_note: eval::windows_left_out_note(self.session.windows_left_out()),
            caveat: eval::one_view_caveat(&r).map(String::from),
            match_warning: eval::photo_match_warning(&photo_ious, &[], match_level),
            match_level,
            photo_ious,
            generator: r.model.generator.name(),
            params: r.model.params.clone(),
            lod: r.model.lod as u8,
            seed: r.model.seed,
            loss: r.loss,
            evaluations: r.evaluations,
            cameras,
        };
        serde_wasm_bindgen::to_value(&out).map_err(js)
    }
}
