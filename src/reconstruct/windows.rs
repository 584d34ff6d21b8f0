//! The window term of a building fit (paper §3.2: buildings are compared on their window
//! masks as well as their silhouettes).
//!
//! A view may carry a window label image (as [`crate::segment::windows`] makes them:
//! [`LABEL_BACKGROUND`], [`LABEL_FACADE`], [`LABEL_WINDOW`], [`LabelImage::DONT_CARE`]). The
//! term compares, over the pixels the labels put *inside the object* (façade or window), the
//! rendered coverage of the model's window parts (parts named `window…`, front-most surface
//! wins: [`LabelRenderer`]) with the window mask, as a soft Dice loss `1 − 2Σab / (Σa + Σb)`,
//! scaled by the fraction of the image inside the object and by [`WindowTerm::weight`]: at
//! most `weight × object fraction`, so the silhouette's MSE (up to the object fraction and
//! more) still dominates.
//!
//! **Why Dice, not MSE.** Measured (tests/reconstruct_windows.rs): with a per-pixel MSE, a
//! camera that is still off early in stage 1 puts rendered windows between the photo's, and
//! every rendered window then costs its area twice — so the search learned *fewer* windows
//! (two storeys instead of six). The Dice loss of misaligned windows is 1 however many there
//! are, so only aligned windows lower it.
//!
//! **No gradient.** The window parts only exist at HIGH detail and their coverage is rendered by
//! the z-buffered label renderer, which has no backward pass. The term therefore counts in every
//! stage's *value* (stage 1's memetic search, which changes floors and stripe counts by
//! mutation; the hand-over probes; the choice of the best Adam iterate) but adds nothing to the
//! gradient: discrete parameters (floor count, stripes) get no gradient anyway, and the
//! continuous ones follow the silhouette.
//!
//! **Scratch.** Each thread keeps its label renderers (one per image size) in a thread-local
//! slot, as the objective does for its silhouette renderers.

use super::FitError;
use crate::camera::View;
use crate::generators::{Generator, Lod};
use crate::mask::LabelImage;
use crate::render::LabelRenderer;
use crate::segment::windows::{LABEL_BACKGROUND, LABEL_FACADE, LABEL_WINDOW};
use std::cell::RefCell;

/// Longer side of the images the window term is computed at (windows are small: at 128 px a
/// storey of a five-storey block is ~10 px, a window ~5 px).
pub const WINDOW_SIDE: u32 = 192;

/// Sub-samples per pixel side of the window render.
const SAMPLES: u32 = 2;

/// Default weight of the window term relative to the silhouette MSE.
///
/// Lighter weights tried and not kept. On the independent buildings on textured ground with
/// the windows found in the photos (`cargo bench --bench building_bench -- --seed N --inputs
/// textured --windows`; without windows 0.918 / 0.875 / 0.910 at seeds 0 / 1 / 2, with this
/// weight 0.792 at seed 1): 0.08 → 0.774 at seed 1; 0.03 → 0.856 / 0.895 / 0.868 (the flat
/// block 0.45–0.82, the tower 0.70–0.99 from seed to seed), and
/// `window_labels_settle_floors_and_window_columns` (`tests/reconstruct_windows.rs`) then
/// finds 9 front window columns, not 7. Nor was fitting the silhouette alone first and
/// sweeping the layout with the window term only at the end (after stage 3) enough: the
/// floors right (6), the columns not (5, at weight 0.03 or 0.25).
pub const DEFAULT_WINDOW_WEIGHT: f64 = 0.25;

/// One view's window mask at the term's size.
#[derive(Clone, Debug)]
pub struct WindowTarget {
    /// 1 window, 0 façade, as a fraction where a pixel covers both.
    target: Vec<f32>,
    /// Whether the pixel counts (inside the object, not don't-care).
    inside: Vec<bool>,
}

/// The window term of one stage: per-view targets at one size, and its weight.
#[derive(Clone, Debug)]
pub struct WindowTerm {
    width: u32,
    height: u32,
    /// One entry per view; `None` for a view without window labels.
    targets: Vec<Option<WindowTarget>>,
    /// Multiplies the term (see the module doc).
    pub weight: f64,
}

thread_local! {
    static LABEL_RENDERERS: RefCell<Vec<LabelRenderer>> = const { RefCell::new(Vec::new()) };
}

impl WindowTerm {
    /// The term for `labels` (one optional label image per view, each the size of that view's
    /// mask, `w × h`), reduced to [`WINDOW_SIDE`]. `None` when no view has labels. Errors on a
    /// size mismatch, a label other than the four known ones, or a bad weight.
    pub fn new(
        labels: &[Option<LabelImage>],
        n_views: usize,
        mask_size: (u32, u32),
        weight: f64,
    ) -> Result<Option<WindowTerm>, FitError> {
        if labels.len() > n_views {
            return Err(FitError(format!(
                "{} window label images for {n_views} views",
                labels.len()
            )));
        }
        if !(weight.is_finite() && weight >= 0.0) {
            return Err(FitError("the window weight must be ≥ 0".into()));
        }
        if weight == 0.0 || labels.iter().all(Option::is_none) {
            return Ok(None);
        }
        let (w, h) = mask_size;
        for (i, l) in labels.iter().enumerate() {
            let Some(l) = l else { continue };
            if (l.width(), l.height()) != (w, h) {
                return Err(FitError(format!(
                    "the window labels of view {i} are {}×{} but its mask is {w}×{h}",
                    l.width(),
                    l.height()
                )));
            }
            if let Some(&bad) = l.labels().iter().find(|&&v| {
                ![
                    LABEL_BACKGROUND,
                    LABEL_FACADE,
                    LABEL_WINDOW,
                    LabelImage::DONT_CARE,
                ]
                .contains(&v)
            }) {
                return Err(FitError(format!(
                    "the window labels of view {i} hold label {bad}; expected 0 (background), 1 (façade), 2 (window) or 255 (don't care)"
                )));
            }
        }
        let long = w.max(h);
        let f = if long > WINDOW_SIDE {
            f64::from(WINDOW_SIDE) / f64::from(long)
        } else {
            1.0
        };
        let tw = ((f64::from(w) * f).round() as u32).max(1);
        let th = ((f64::from(h) * f).round() as u32).max(1);
        let mut targets: Vec<Option<WindowTarget>> = labels
            .iter()
            .map(|l| l.as_ref().map(|l| resample(l, tw, th)))
            .collect();
        targets.resize(n_views, None);
        Ok(Some(WindowTerm {
            width: tw,
            height: th,
            targets,
            weight,
        }))
    }

    /// The term's image size.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// The term for the generator parameters `gen_x` with view `view_of(v, w, h)` for view `v`
    /// at the term's size. Errors when the model cannot be built or rendered.
    pub fn value(
        &self,
        generator: &dyn Generator,
        gen_x: &[f64],
        view_of: impl Fn(usize, u32, u32) -> View,
    ) -> Result<f64, String> {
        let mesh = generator
            .generate(gen_x, Lod::High)
            .map_err(|e| e.to_string())?;
        let is_window: Vec<u8> = mesh
            .parts
            .iter()
            .map(|p| u8::from(p.name.starts_with("window")))
            .collect();
        let tri_labels: Vec<u8> = mesh
            .tri_parts
            .iter()
            .map(|&p| is_window.get(usize::from(p)).copied().unwrap_or(0))
            .collect();
        let any_window = tri_labels.contains(&1);
        let (w, h) = (self.width, self.height);
        let n = w as usize * h as usize;
        // Mean over views; each view's Dice loss weighted by its object fraction.
        let scale = self.weight / (self.targets.len() as f64 * n as f64);
        let mut total = 0.0;
        LABEL_RENDERERS.with(|cell| -> Result<(), String> {
            let mut own = Vec::new();
            let mut borrowed = cell.try_borrow_mut().ok();
            let renderers: &mut Vec<LabelRenderer> = match borrowed.as_deref_mut() {
                Some(r) => r,
                None => &mut own,
            };
            for (v, t) in self.targets.iter().enumerate() {
                let Some(t) = t else { continue };
                let inside = t.inside.iter().filter(|&&b| b).count() as f64;
                let (mut ab, mut a, mut b) = (0.0f64, 0.0f64, 0.0f64);
                if any_window {
                    let i = match renderers.iter().position(|r| r.size() == (w, h)) {
                        Some(i) => i,
                        None => {
                            if renderers.len() >= 2 {
                                renderers.remove(0);
                            }
                            renderers.push(
                                LabelRenderer::new(w, h, SAMPLES).map_err(|e| e.to_string())?,
                            );
                            renderers.len() - 1
                        }
                    };
                    let view = view_of(v, w, h);
                    let planes = renderers[i]
                        .render(&mesh.positions, &mesh.triangles, &tri_labels, 2, &view)
                        .map_err(|e| e.to_string())?;
                    for (k, &c) in planes[n..2 * n].iter().enumerate() {
                        if t.inside[k] {
                            let (c, tk) = (f64::from(c), f64::from(t.target[k]));
                            ab += c * tk;
                            a += c;
                            b += tk;
                        }
                    }
                } else {
                    // No window parts: nothing is rendered as window.
                    b = (0..n)
                        .filter(|&k| t.inside[k])
                        .map(|k| f64::from(t.target[k]))
                        .sum();
                }
                // Soft Dice loss, 0 for a perfect match and 1 for no overlap at all.
                let dice_loss = if a + b > 0.0 {
                    1.0 - 2.0 * ab / (a + b)
                } else {
                    0.0
                };
                let sum = inside * dice_loss;
                total += scale * sum;
            }
            Ok(())
        })?;
        Ok(total)
    }
}

/// `labels` reduced to `tw × th` by a box filter over the source pixels whose centres fall in
/// each target pixel: a target pixel counts when most of its sources are inside the object, and
/// its target is the window fraction of those.
fn resample(labels: &LabelImage, tw: u32, th: u32) -> WindowTarget {
    let (w, h) = (labels.width() as usize, labels.height() as usize);
    let (tw, th) = (tw as usize, th as usize);
    let (sx, sy) = (w as f64 / tw as f64, h as f64 / th as f64);
    let mut window = vec![0u32; tw * th];
    let mut inside = vec![0u32; tw * th];
    let mut count = vec![0u32; tw * th];
    for (i, &l) in labels.labels().iter().enumerate() {
        let (x, y) = (i % w, i / w);
        let tx = (((x as f64 + 0.5) / sx) as usize).min(tw - 1);
        let ty = (((y as f64 + 0.5) / sy) as usize).min(th - 1);
        let t = ty * tw + tx;
        count[t] += 1;
        if l == LABEL_FACADE || l == LABEL_WINDOW {
            inside[t] += 1;
            if l == LABEL_WINDOW {
                window[t] += 1;
            }
        }
    }
    WindowTarget {
        target: (0..tw * th)
            .map(|t| {
                if inside[t] == 0 {
                    0.0
                } else {
                    window[t] as f32 / inside[t] as f32
                }
            })
            .collect(),
        inside: (0..tw * th)
            .map(|t| inside[t] > 0 && 2 * inside[t] > count[t])
            .collect(),
    }
}
