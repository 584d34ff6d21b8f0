//! The second label for buildings: windows inside the façade.
//!
//! Two ways, both returning a [`LabelImage`] with [`LABEL_BACKGROUND`], [`LABEL_FACADE`] and
//! [`LABEL_WINDOW`] (and [`LabelImage::DONT_CARE`] where the mask is don't care):
//!
//! - [`detect_windows`]: windows as *darker, rectangular* regions inside the object. Works for
//!   the common daylight façade: glass darker than a lighter wall, windows axis-aligned in the
//!   photo (a frontal or mildly oblique view), each window a separate blob. Does not work for
//!   lit windows at night, reflective glass brighter than the wall, dark walls, strong
//!   perspective (windows become trapezoids, the fill test may reject them) or windows joined
//!   by a dark band (a ribbon window counts as one wide window, or is rejected if wider than
//!   half the façade).
//! - [`windows_from_strokes`]: the user paints some windows ([`Label::Object`]) and optionally
//!   some wall ([`Label::Background`]); colour models from the strokes and a graph cut inside
//!   the object label the rest. Works whenever windows and wall differ in colour.
//!
//! The wall brush on windows found automatically erases them ([`erase_windows`]). When the mask
//! is corrected afterwards, windows found automatically are simply found again (and erased
//! again where the wall brush went); windows the user painted are kept as they are and [`clip_windows`] fits them to the new
//! object (none outside it, façade where the object grew).

use super::gmm::{Gmm, Rgb};
use super::grabcut::{HARD, cut_grid, for_stroke_pixels, nlinks_of};
use super::maxflow::Graph;
use super::morph;
use super::{Label, Photo, SegmentError, Segmentation, Stroke};
use crate::mask::{LabelImage, Mask};

/// Label of pixels outside the object.
pub const LABEL_BACKGROUND: u8 = 0;
/// Label of object pixels that are not windows.
pub const LABEL_FACADE: u8 = 1;
/// Label of window pixels.
pub const LABEL_WINDOW: u8 = 2;

fn check(photo: &Photo, seg: &Segmentation) -> Result<(usize, usize, Vec<bool>), SegmentError> {
    let (w, h) = (photo.width() as usize, photo.height() as usize);
    if seg.object.width() as usize != w || seg.object.height() as usize != h {
        return Err(SegmentError(format!(
            "the object mask is {}×{} but the photo is {w}×{h}",
            seg.object.width(),
            seg.object.height()
        )));
    }
    let obj: Vec<bool> = seg.object.values().iter().map(|&v| v >= 0.5).collect();
    if !obj.iter().any(|&o| o) {
        return Err(SegmentError::new("no object to look for windows in"));
    }
    Ok((w, h, obj))
}

fn labels(seg: &Segmentation, obj: &[bool], win: &[bool]) -> Result<LabelImage, SegmentError> {
    let l = seg
        .mask
        .values()
        .iter()
        .zip(obj.iter().zip(win))
        .map(|(&m, (&o, &wi))| {
            if m == Mask::DONT_CARE {
                LabelImage::DONT_CARE
            } else if o && wi {
                LABEL_WINDOW
            } else if o {
                LABEL_FACADE
            } else {
                LABEL_BACKGROUND
            }
        })
        .collect();
    Ok(LabelImage::new(seg.object.width(), seg.object.height(), l)?)
}

/// Windows as darker rectangles inside the segmented object (see the module doc for limits).
pub fn detect_windows(photo: &Photo, seg: &Segmentation) -> Result<LabelImage, SegmentError> {
    let (w, h, obj) = check(photo, seg)?;
    let luma: Vec<f32> = photo
        .rgba()
        .chunks_exact(4)
        .map(|p| {
            (0.299 * f32::from(p[0]) + 0.587 * f32::from(p[1]) + 0.114 * f32::from(p[2])) / 255.0
        })
        .collect();
    let mut inside: Vec<f32> = luma
        .iter()
        .zip(&obj)
        .filter(|(_, o)| **o)
        .map(|(l, _)| *l)
        .collect();
    inside.sort_unstable_by(f32::total_cmp);
    let median = inside[inside.len() / 2];
    let mut dev: Vec<f32> = inside.iter().map(|l| (l - median).abs()).collect();
    dev.sort_unstable_by(f32::total_cmp);
    let mad = dev[dev.len() / 2] * 1.4826;
    // Darker than the wall by more than its own texture and JPEG noise.
    let threshold = median - (2.5 * mad).max(0.08);
    let dark: Vec<bool> = (0..w * h).map(|i| obj[i] && luma[i] < threshold).collect();
    let Some(ob) = seg.bbox else {
        return Err(SegmentError::new("no object to look for windows in"));
    };
    let (ow, oh) = ((ob.x1 - ob.x0) as usize, (ob.y1 - ob.y0) as usize);
    let min_area = (inside.len() / 5000).max(6);
    let mut win = vec![false; w * h];
    let (_, comps) = morph::components(&dark, w, h, false);
    for c in comps {
        if c.len() < min_area {
            continue;
        }
        let (mut x0, mut y0, mut x1, mut y1) = (usize::MAX, usize::MAX, 0, 0);
        for &i in &c {
            let (x, y) = (i % w, i / w);
            x0 = x0.min(x);
            y0 = y0.min(y);
            x1 = x1.max(x + 1);
            y1 = y1.max(y + 1);
        }
        let (bw, bh) = (x1 - x0, y1 - y0);
        let fill = c.len() as f32 / (bw * bh) as f32;
        // Rectangular (fills most of its box), not a sliver, and not a whole side or roof.
        if fill >= 0.6 && bw >= 2 && bh >= 2 && 2 * bw <= ow && 2 * bh <= oh {
            for y in y0..y1 {
                for x in x0..x1 {
                    win[y * w + x] = true;
                }
            }
        }
    }
    labels(seg, &obj, &win)
}

/// `labels` with the windows under `strokes` turned into façade: the wall brush on windows found
/// automatically (the page keeps those strokes and erases with them again when the windows are
/// found again after a mask correction). Every other pixel keeps its label; a stroke's labels
/// (its [`Stroke::label`]) do not matter. Errors on a bad stroke (radius, points).
pub fn erase_windows(labels: &LabelImage, strokes: &[Stroke]) -> Result<LabelImage, SegmentError> {
    let (w, h) = (labels.width() as usize, labels.height() as usize);
    let mut out = labels.labels().to_vec();
    for s in strokes {
        for_stroke_pixels(s, w, h, |i| {
            if out[i] == LABEL_WINDOW {
                out[i] = LABEL_FACADE;
            }
        })?;
    }
    Ok(LabelImage::new(labels.width(), labels.height(), out)?)
}

/// Window labels made for an earlier mask, fitted to the segmentation's current one: window
/// pixels stay windows where they are still inside the object and are dropped outside it;
/// every other object pixel is façade, the mask's don't-care pixels don't care, the rest
/// background —
/// as [`detect_windows`] labels. Errors on labels of another size or an empty object.
pub fn clip_windows(seg: &Segmentation, previous: &LabelImage) -> Result<LabelImage, SegmentError> {
    let (w, h) = (seg.object.width(), seg.object.height());
    if (previous.width(), previous.height()) != (w, h) {
        return Err(SegmentError(format!(
            "the window labels are {}×{} but the mask is {w}×{h}",
            previous.width(),
            previous.height()
        )));
    }
    let obj: Vec<bool> = seg.object.values().iter().map(|&v| v >= 0.5).collect();
    if !obj.iter().any(|&o| o) {
        return Err(SegmentError::new("no object to keep windows in"));
    }
    let win: Vec<bool> = previous
        .labels()
        .iter()
        .map(|&l| l == LABEL_WINDOW)
        .collect();
    labels(seg, &obj, &win)
}

/// Windows from the user's strokes: [`Label::Object`] strokes paint windows,
/// [`Label::Background`] strokes paint wall. At least one window stroke is needed.
pub fn windows_from_strokes(
    photo: &Photo,
    seg: &Segmentation,
    strokes: &[Stroke],
) -> Result<LabelImage, SegmentError> {
    let (w, h, obj) = check(photo, seg)?;
    let colors = photo.colors();
    let mut mark = vec![0u8; w * h];
    for s in strokes {
        let v = if s.label == Label::Object { 1 } else { 2 };
        for_stroke_pixels(s, w, h, |i| {
            if obj[i] {
                mark[i] = v;
            }
        })?;
    }
    let win_s: Vec<Rgb> = (0..w * h)
        .filter(|&i| mark[i] == 1)
        .map(|i| colors[i])
        .collect();
    if win_s.is_empty() {
        return Err(SegmentError::new(
            "paint at least one window stroke inside the object",
        ));
    }
    let win_model =
        Gmm::fit(&win_s, 3).ok_or_else(|| SegmentError::new("cannot model the window colours"))?;
    let wall_s: Vec<Rgb> = if mark.contains(&2) {
        (0..w * h)
            .filter(|&i| mark[i] == 2)
            .map(|i| colors[i])
            .collect()
    } else {
        // No wall strokes: the wall is the object minus anything window-coloured.
        let mut nll: Vec<f32> = win_s.iter().map(|c| win_model.nll(c)).collect();
        nll.sort_unstable_by(f32::total_cmp);
        let tau = nll[(nll.len() * 9 / 10).min(nll.len() - 1)];
        (0..w * h)
            .filter(|&i| obj[i] && mark[i] == 0 && win_model.nll(&colors[i]) > tau)
            .map(|i| colors[i])
            .collect()
    };
    let wall_model = Gmm::fit(&wall_s, 3).ok_or_else(|| {
        SegmentError::new("cannot model the wall colours: paint a wall stroke too")
    })?;
    let nl = nlinks_of(&colors, w, h);
    let mut g = Graph::default();
    cut_grid(&mut g, w, h, &nl, false, |i| {
        if !obj[i] || mark[i] == 2 {
            -HARD
        } else if mark[i] == 1 {
            HARD
        } else {
            wall_model.nll(&colors[i]) - win_model.nll(&colors[i])
        }
    });
    let win: Vec<bool> = (0..w * h).map(|i| obj[i] && g.is_source(i)).collect();
    labels(seg, &obj, &win)
}
