//! The mask step's edge: one [`MaskSession`] per photo, an opaque handle around the core's
//! GrabCut session (`segment::Session`). Photos come in as upright RGBA pixels from a browser
//! canvas; masks go out as 8-bit codes (object 255, background 0, don't care 128 — the same
//! as [`Mask::to_luma8`](crate::mask::Mask::to_luma8)), in working-image pixels.

use super::js;
use crate::mask::LabelImage;
use crate::segment::windows::{clip_windows, detect_windows, erase_windows, windows_from_strokes};
use crate::segment::{BBox, Label, Options, Photo, Session, Stroke, WORKING_SIDE};
use wasm_bindgen::prelude::*;

/// A photo's segmentation, kept for corrections.
#[wasm_bindgen]
pub struct MaskSession {
    photo: Photo,
    session: Session,
    /// The object kind's segmentation options, for a new start from a rectangle too.
    opts: Options,
}

/// What the page shows next to a mask.
#[derive(serde::Serialize)]
struct MaskInfo {
    width: u32,
    height: u32,
    /// `[x0, y0, x1, y1]` in working pixels (end exclusive), or `None` when nothing was found.
    bbox: Option<[u32; 4]>,
    confidence: f32,
    low_confidence: bool,
    warnings: Vec<String>,
    /// The outline smoothing the session cuts with (its object kind's).
    outline_smoothing: f32,
}

impl MaskSession {
    /// A label image the size of the current mask, from the page's bytes.
    fn labels_of(&self, labels: &[u8]) -> Result<LabelImage, JsError> {
        let s = self.session.segmentation();
        let (w, h) = (s.object.width(), s.object.height());
        if labels.len() != (w as usize) * (h as usize) {
            return Err(JsError::new(&format!(
                "{} window labels for a {w}×{h} mask",
                labels.len()
            )));
        }
        LabelImage::new(w, h, labels.to_vec()).map_err(js)
    }
}

#[wasm_bindgen]
impl MaskSession {
    /// Segments a `width`×`height` RGBA photo automatically (downscaled to the working size
    /// first), cut for the object kind `generator` (a generator's name; `undefined` or an
    /// unknown name: the default cut). Errors are messages for the user (too small, bad
    /// length, nothing found…).
    #[wasm_bindgen(constructor)]
    pub fn new(
        width: u32,
        height: u32,
        rgba: &[u8],
        generator: Option<String>,
    ) -> Result<MaskSession, JsError> {
        let photo = Photo::from_rgba(width, height, rgba, WORKING_SIDE).map_err(js)?;
        let kind = generator.as_deref().and_then(crate::generators::by_name);
        let opts = Options::for_generator(kind);
        let session = Session::automatic(&photo, &opts).map_err(js)?;
        Ok(MaskSession {
            photo,
            session,
            opts,
        })
    }

    /// Starts over from a rectangle around the object (GrabCut proper: outside is background),
    /// in working pixels, end exclusive.
    #[wasm_bindgen(js_name = setRect)]
    pub fn set_rect(&mut self, x0: u32, y0: u32, x1: u32, y1: u32) -> Result<(), JsError> {
        let rect = BBox { x0, y0, x1, y1 };
        self.session = Session::with_rect(&self.photo, rect, &self.opts).map_err(js)?;
        Ok(())
    }

    /// Paints an object (`object = true`) or background stroke along the polyline `points`
    /// (`[x0, y0, x1, y1, …]` in working pixels) and cuts again.
    #[wasm_bindgen(js_name = addStroke)]
    pub fn add_stroke(&mut self, object: bool, points: &[f32], radius: f32) -> Result<(), JsError> {
        if points.is_empty()
            || !points.len().is_multiple_of(2)
            || !points.iter().all(|v| v.is_finite())
        {
            return Err(JsError::new("a stroke needs finite x, y pairs"));
        }
        if !(radius.is_finite() && radius > 0.0) {
            return Err(JsError::new("a stroke needs a positive radius"));
        }
        let stroke = stroke_of(object, points, radius);
        self.session.add_stroke(&stroke).map_err(js)?;
        self.session.recut().map_err(js)?;
        Ok(())
    }

    /// Window labels found automatically inside the current mask (darker rectangles; see
    /// `segment::windows`): 0 background, 1 façade, 2 window, 255 don't care, row-major in
    /// working pixels.
    #[wasm_bindgen(js_name = detectWindows)]
    pub fn detect_windows(&self) -> Result<Vec<u8>, JsError> {
        let labels = detect_windows(&self.photo, self.session.segmentation()).map_err(js)?;
        Ok(labels.labels().to_vec())
    }

    /// Window labels from the user's strokes inside the current mask, labelled like
    /// [`MaskSession::detect_windows`]. Stroke `i` paints windows when `window[i]` is 1 and
    /// wall when 0, has `counts[i]` points (`x, y` pairs in `points`, in order) and radius
    /// `radii[i]`, all in working pixels. At least one window stroke is needed.
    #[wasm_bindgen(js_name = windowsFromStrokes)]
    pub fn windows_from_strokes(
        &self,
        window: &[u8],
        counts: &[u32],
        points: &[f32],
        radii: &[f32],
    ) -> Result<Vec<u8>, JsError> {
        let strokes = strokes_of(window, counts, points, radii)?;
        let labels =
            windows_from_strokes(&self.photo, self.session.segmentation(), &strokes).map_err(js)?;
        Ok(labels.labels().to_vec())
    }

    /// `labels` (as the calls here give them) with the windows under the wall-brush strokes
    /// turned into façade (see `segment::windows::erase_windows`): stroke `i` has `counts[i]`
    /// points (`x, y` pairs in `points`) and radius `radii[i]`, in working pixels.
    #[wasm_bindgen(js_name = eraseWindows)]
    pub fn erase_windows(
        &self,
        labels: &[u8],
        counts: &[u32],
        points: &[f32],
        radii: &[f32],
    ) -> Result<Vec<u8>, JsError> {
        let labels = self.labels_of(labels)?;
        let strokes = strokes_of(&vec![0; counts.len()], counts, points, radii)?;
        Ok(erase_windows(&labels, &strokes)
            .map_err(js)?
            .labels()
            .to_vec())
    }

    /// Window labels made for an earlier mask (`labels`, as the two calls above give them)
    /// fitted to the current one: windows outside the object dropped, the rest as before (see
    /// `segment::windows::clip_windows`). For painted windows after a mask correction.
    #[wasm_bindgen(js_name = clipWindows)]
    pub fn clip_windows(&self, labels: &[u8]) -> Result<Vec<u8>, JsError> {
        let previous = self.labels_of(labels)?;
        let clipped = clip_windows(self.session.segmentation(), &previous).map_err(js)?;
        Ok(clipped.labels().to_vec())
    }

    /// The mask for the fit: object 255, background 0, don't care 128 (a band along the
    /// outline), row-major in working pixels.
    pub fn codes(&self) -> Vec<u8> {
        self.session.segmentation().mask.to_luma8()
    }

    /// `{ width, height, bbox, confidence, low_confidence, warnings, outline_smoothing }`.
    pub fn info(&self) -> Result<JsValue, JsError> {
        let s = self.session.segmentation();
        let info = MaskInfo {
            width: s.mask.width(),
            height: s.mask.height(),
            bbox: s.bbox.map(|b| [b.x0, b.y0, b.x1, b.y1]),
            confidence: s.confidence,
            low_confidence: s.is_low_confidence(),
            warnings: s.warnings.clone(),
            outline_smoothing: self.opts.outline_smoothing,
        };
        serde_wasm_bindgen::to_value(&info).map_err(js)
    }
}

/// A stroke from the page's numbers: object (or window) when `object`, else background (or
/// wall); `points` are `x, y` pairs in working pixels.
fn stroke_of(object: bool, points: &[f32], radius: f32) -> Stroke {
    Stroke {
        label: if object {
            Label::Object
        } else {
            Label::Background
        },
        points: points.chunks_exact(2).map(|p| [p[0], p[1]]).collect(),
        radius,
    }
}

/// Strokes from flat arrays: stroke `i` is a window (or object) stroke when `window[i]` is 1 and
/// a wall (background) one when 0, has `counts[i]` points (`x, y` pairs in `points`, in order)
/// and radius `radii[i]`, all in working pixels.
fn strokes_of(
    window: &[u8],
    counts: &[u32],
    points: &[f32],
    radii: &[f32],
) -> Result<Vec<Stroke>, JsError> {
    if window.len() != counts.len() || window.len() != radii.len() {
        return Err(JsError::new(
            "one kind, point count and radius per window stroke",
        ));
    }
    if !points.iter().all(|v| v.is_finite()) || !radii.iter().all(|r| r.is_finite() && *r > 0.0) {
        return Err(JsError::new(
            "window strokes need finite points and positive radii",
        ));
    }
    let mut strokes = Vec::with_capacity(window.len());
    let mut at = 0usize;
    for ((&kind, &n), &radius) in window.iter().zip(counts).zip(radii) {
        let n = n as usize;
        let Some(p) = points.get(2 * at..2 * (at + n)) else {
            return Err(JsError::new(
                "the window stroke points are fewer than the counts say",
            ));
        };
        if n == 0 {
            return Err(JsError::new("a window stroke needs at least one point"));
        }
        strokes.push(stroke_of(kind == 1, p, radius));
        at += n;
    }
    if 2 * at != points.len() {
        return Err(JsError::new(
            "the window stroke points are more than the counts say",
        ));
    }
    Ok(strokes)
}
