//! From photo to mask: decoding, orientation, downscaling and object segmentation.
//!
//! The paper leaves mask extraction to "any existing segmentation algorithm" (§3.1); this module
//! is that algorithm, in pure Rust so the page needs no model download.
//!
//! Flow: bytes → [`Photo::decode`] (or [`Photo::from_rgba`] from a browser canvas) → an upright
//! RGBA photo at working resolution → a [`Segmentation`] by one of four ways:
//! 1. [`segment_alpha`]: the photo's own alpha channel;
//! 2. [`segment_auto`]: border background model + GrabCut ([`grabcut::Session::automatic`]);
//! 3. interactive: [`grabcut::Session::with_rect`], [`grabcut::Session::add_stroke`] and
//!    [`grabcut::Session::recut`];
//! 4. [`segment_mask_image`]: a mask image supplied by the user.
//!
//! Buildings get a second label, windows: [`windows::detect_windows`] finds darker rectangles
//! inside the façade, [`windows::windows_from_strokes`] follows the user's strokes.
//!
//! Every way ends in the same [`Segmentation`]: a 0/1 object mask, the mask the fit takes
//! (the same, with [`Mask::DONT_CARE`] only where the source itself is unsure: a
//! semi-transparent alpha, a mask image's grey; no band along the outline: measured, it cost
//! the fit accuracy), the bounding box and a confidence with human-readable warnings.
//! Nothing here reads a clock: `std::time::Instant` panics on wasm32.
//!
//! What automatic mode can and cannot do (it models colour, not shape or meaning):
//! - works when the object's colours differ from the background's and the image border shows
//!   background (plain, gradient, noisy, patterned walls; a table along one side);
//! - keeps holes that show the background (a handle's loop), fills others;
//! - takes a shadow or a darker stretch of a coloured table (wood) for background: the border
//!   model also explains shaded copies of its saturated colours ([`gmm::Gmm::nll_shaded`]);
//!   on a white or grey table a shadow is as dark as a grey object, and may be taken in;
//! - fails where object and background share colours (a white cup on a white table), or where
//!   the object is a darker shade of a coloured table's hue, and cannot see glass;
//!   such masks usually come out with a low agreement between cut and colour models, or
//!   [`plausible`] finds them doubtful against the photo around them; either way
//!   [`Segmentation::warnings`] reports it — the user then corrects with strokes or a rectangle.
//! - A uniform image, or an object that fills the frame, leaves nothing to learn the
//!   background from: the result is flagged ([`Segmentation::is_low_confidence`]).

pub mod bench;
pub mod decode;
mod frame;
pub mod gmm;
pub mod grabcut;
pub mod maxflow;
pub mod morph;
pub mod plausible;
pub mod windows;

use std::fmt;

pub use decode::{Photo, WORKING_SIDE};
pub use grabcut::{Options, Session};

use crate::mask::{Mask, MaskError};

/// Why a photo or mask could not be processed; the message is meant for the user.
#[derive(Clone, Debug, PartialEq)]
pub struct SegmentError(pub String);

impl SegmentError {
    fn new(msg: &str) -> SegmentError {
        SegmentError(msg.to_owned())
    }
}

impl fmt::Display for SegmentError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for SegmentError {}

impl From<MaskError> for SegmentError {
    fn from(e: MaskError) -> SegmentError {
        SegmentError(e.0)
    }
}

/// A pixel rectangle in the working image; `x1` and `y1` are exclusive.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BBox {
    /// Left column.
    pub x0: u32,
    /// Top row.
    pub y0: u32,
    /// One past the right column.
    pub x1: u32,
    /// One past the bottom row.
    pub y1: u32,
}

/// What a stroke marks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Label {
    /// The object (or, for windows, a window).
    Object,
    /// The background (or, for windows, plain façade).
    Background,
}

/// A user's brush stroke in working-image pixels.
#[derive(Clone, Debug, PartialEq)]
pub struct Stroke {
    /// What the painted pixels are.
    pub label: Label,
    /// Polyline vertices `[x, y]` (pixel centres are at `+0.5`).
    pub points: Vec<[f32; 2]>,
    /// Brush radius in pixels.
    pub radius: f32,
}

/// A segmented object.
#[derive(Clone, Debug, PartialEq)]
pub struct Segmentation {
    /// 0/1 object mask, no don't-care pixels.
    pub object: Mask,
    /// What the fit should use: [`Segmentation::object`], with [`Mask::DONT_CARE`] where the
    /// source is unsure (a semi-transparent alpha, a mask image's grey 128). An automatic cut
    /// has no don't-care pixels: a band of them along the outline cost the fit accuracy.
    pub mask: Mask,
    /// Bounding box of the object, `None` if nothing was found.
    pub bbox: Option<BBox>,
    /// 0..1; for GrabCut the share of pixels where the cut agrees with the colour models alone,
    /// capped at 0.4 when there are warnings.
    pub confidence: f32,
    /// Reasons not to trust the mask (empty when all looks fine).
    pub warnings: Vec<String>,
}

impl Segmentation {
    /// Whether the mask should be checked by the user before fitting.
    pub fn is_low_confidence(&self) -> bool {
        !self.warnings.is_empty() || self.confidence < 0.5
    }
}

/// The default way: the photo's own alpha channel if it has transparency (its background was
/// already removed), else automatic segmentation.
pub fn segment(photo: &Photo) -> Result<Segmentation, SegmentError> {
    if photo.has_alpha() {
        segment_alpha(photo)
    } else {
        segment_auto(photo)
    }
}

/// Automatic segmentation with default options.
pub fn segment_auto(photo: &Photo) -> Result<Segmentation, SegmentError> {
    segment_auto_with(photo, &Options::default())
}

/// Automatic segmentation with `opts` (an object kind's: [`Options::for_generator`]).
pub fn segment_auto_with(photo: &Photo, opts: &Options) -> Result<Segmentation, SegmentError> {
    Ok(Session::automatic(photo, opts)?.segmentation().clone())
}

/// Alpha below this is background, above [`ALPHA_OBJECT`] object, between don't care.
const ALPHA_BACKGROUND: u8 = 16;
const ALPHA_OBJECT: u8 = 240;

/// The mask from the photo's alpha channel (a photo whose background was already removed):
/// coverage α, hard object α ≥ ½, semi-transparent pixels don't care.
pub fn segment_alpha(photo: &Photo) -> Result<Segmentation, SegmentError> {
    if !photo.has_alpha() {
        return Err(SegmentError::new(
            "the photo has no transparency: its alpha channel cannot give a mask",
        ));
    }
    let alpha: Vec<u8> = photo.rgba().chunks_exact(4).map(|p| p[3]).collect();
    from_levels(photo.width(), photo.height(), &alpha, 1.0)
}

/// A mask from 8-bit levels: below 16 background, above 240 object, between don't care (so a
/// saved [`Mask::to_luma8`] with its grey 128 band reads back as it was written).
fn from_levels(
    width: u32,
    height: u32,
    levels: &[u8],
    confidence: f32,
) -> Result<Segmentation, SegmentError> {
    let (w, h) = (width as usize, height as usize);
    let obj: Vec<bool> = levels.iter().map(|&a| a >= 128).collect();
    let warnings = mask_warnings(&obj, w, h);
    let mut seg = grabcut::build_segmentation(&obj, w, h, confidence, warnings)?;
    let values: Vec<f32> = seg
        .mask
        .values()
        .iter()
        .zip(levels)
        .map(|(&v, &a)| {
            if (ALPHA_BACKGROUND..=ALPHA_OBJECT).contains(&a) {
                Mask::DONT_CARE
            } else {
                v
            }
        })
        .collect();
    seg.mask = Mask::new(width, height, values)?;
    if !seg.warnings.is_empty() {
        seg.confidence = seg.confidence.min(0.4);
    }
    Ok(seg)
}

/// What to tell the user about a given mask (a mask image, a photo's alpha channel): empty,
/// the whole image, smaller than [`SMALL_MASK`] of the frame, or touching two or more of the
/// image's sides over more than a quarter of each (an object cut by the frame, or a mask that
/// took background in). `obj` is the object's pixels, `w`×`h`, row-major.
pub fn mask_warnings(obj: &[bool], w: usize, h: usize) -> Vec<String> {
    let mut warnings = Vec::new();
    let area = obj.iter().filter(|&&o| o).count();
    if area == 0 {
        warnings.push("the mask is empty".to_owned());
        return warnings;
    }
    if area == obj.len() {
        warnings.push("the mask covers the whole image".to_owned());
        return warnings;
    }
    let frac = area as f32 / obj.len() as f32;
    if frac < SMALL_MASK {
        warnings.push(format!(
            "the mask covers only {:.1} % of the image: check that it is the whole object",
            100.0 * frac
        ));
    }
    let sides = grabcut::touching_sides(obj, w, h);
    if sides >= 2 {
        warnings.push(format!(
            "the mask touches {sides} sides of the image: if the object is cut by the frame, \
             the model is only fitted to what the photo shows; check the mask"
        ));
    }
    warnings
}

/// A mask below this share of the frame gets a warning ([`mask_warnings`], automatic masks).
pub const SMALL_MASK: f32 = 0.03;

/// A user-supplied mask image (any decodable format) for `photo`: white (or opaque, if the
/// image has transparency) is object, black background, mid grey don't care. It must have the
/// photo's aspect ratio; it is resampled to the working size.
pub fn segment_mask_image(photo: &Photo, bytes: &[u8]) -> Result<Segmentation, SegmentError> {
    let (pw, ph) = (photo.width(), photo.height());
    let m = Photo::decode(bytes, pw.max(ph).max(decode::MIN_SIDE))?;
    let (mw, mh) = m.source_size();
    let (sw, sh) = photo.source_size();
    let aspect = |a: u32, b: u32| f64::from(a) / f64::from(b);
    if (aspect(mw, mh) / aspect(sw, sh) - 1.0).abs() > 0.02 {
        return Err(SegmentError(format!(
            "the mask is {mw}×{mh} but the photo is {sw}×{sh}: their shapes differ"
        )));
    }
    let (rgba, _) = decode::area_resample(m.rgba(), m.width(), m.height(), 4, pw, ph);
    let levels: Vec<u8> = rgba
        .chunks_exact(4)
        .map(|p| {
            if m.has_alpha() {
                p[3]
            } else {
                // Rec. 601 luma.
                ((u32::from(p[0]) * 299 + u32::from(p[1]) * 587 + u32::from(p[2]) * 114) / 1000)
                    as u8
            }
        })
        .collect();
    from_levels(pw, ph, &levels, 1.0)
}
