//! Part colours from the photos (issue 17): each part's base colour estimated from the photo
//! pixels it covers when the fitted model is seen through each photo's fitted camera.
//!
//! Per view, the model is rendered with one label per part ([`LabelRenderer`], front-most part
//! wins, 2 × 2 sub-samples). A pixel speaks for a part when every sub-sample shows that part,
//! the mask calls it object (not background, not don't-care), and — where the part shows enough
//! of them — it lies at least [`EDGE_MARGIN`] pixels inside the part's region, away from the
//! silhouette and from other parts, where a fit that is a pixel off would mix in the background
//! or a neighbour. A thin part (a handle) falls back to a smaller margin.
//!
//! The estimate is robust to shading and highlights: pixels with a clipped channel (a specular
//! highlight or an over-exposed patch) are left out unless they are most of the part (a white
//! mug), the rest are sorted by luminance in linear RGB, and the mean of the band between the
//! [`BAND`] quantiles gives the hue and saturation: the upper half, the surface facing the light,
//! without the brightest few per cent (highlights that did not clip) or the shadowed side (which
//! shows the light, not the surface). Its brightness is the luminance at the [`LIT`] quantile:
//! the side facing the light shows the base colour itself, the rest of the band is darker.
//!
//! A part no photo shows (fewer than [`MIN_PIXELS`] pixels over all views) takes the colour of
//! the nearest seen part when both are plain opaque surfaces (a handle hidden behind its cup
//! takes the cup's colour), else keeps its default; [`Source`] says which, so the CLI and the
//! page can tell the user.

use crate::camera::View;
use crate::generators::{Mesh, Part};
use crate::mask::Mask;
use crate::model::PartColors;
use crate::render::labels::LabelRenderer;
use std::fmt;

/// Pixels a part needs over all views for its colour to be measured.
pub const MIN_PIXELS: usize = 12;
/// Distance (pixels, Chebyshev) from a part's region's border a pixel must have to count, when
/// the part shows [`MIN_PIXELS`] such pixels; else 1, else 0.
pub const EDGE_MARGIN: usize = 2;
/// The luminance quantiles whose band is averaged.
pub const BAND: (f64, f64) = (0.5, 0.95);
/// The luminance quantile taken as the brightness of the lit side.
pub const LIT: f64 = 0.9;
/// An 8-bit sRGB channel at or above this is taken as clipped.
const CLIPPED: u8 = 250;

/// Where a part's colour comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum Source {
    /// Measured in the photos over this many pixels.
    Photo {
        /// Pixels that spoke for the part, over all views.
        pixels: usize,
    },
    /// Not seen; the colour of this nearby part that was.
    Neighbour(&'static str),
    /// Not seen and no plain neighbour to borrow from: the generator's default.
    Default,
}

/// One part's estimated colour.
#[derive(Clone, Debug, PartialEq)]
pub struct PartColor {
    /// The part's name.
    pub part: &'static str,
    /// Linear RGB in 0–1 (the default colour when `source` is [`Source::Default`]).
    pub color: [f32; 3],
    /// Where it comes from.
    pub source: Source,
}

/// The colours cannot be estimated (mismatched inputs).
#[derive(Clone, Debug, PartialEq)]
pub struct ColorError(pub String);

impl fmt::Display for ColorError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for ColorError {}

/// A photo's pixels: 8-bit sRGB RGBA, row-major, `width × height` (the size of its mask and
/// fitted view).
#[derive(Clone, Copy, Debug)]
pub struct Rgba<'a> {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `4 · width · height` bytes.
    pub pixels: &'a [u8],
}

/// The colour of each part of `mesh` that has triangles, from `photos` seen through `views`
/// with their `masks` (one of each per view, all of one size per view). Parts in mesh order.
pub fn estimate(
    mesh: &Mesh,
    views: &[View],
    photos: &[Rgba<'_>],
    masks: &[Mask],
) -> Result<Vec<PartColor>, ColorError> {
    if views.len() != photos.len() || views.len() != masks.len() {
        return Err(ColorError(format!(
            "{} views, {} photos and {} masks: one of each per view",
            views.len(),
            photos.len(),
            masks.len()
        )));
    }
    let n_parts = mesh.parts.len();
    if n_parts == 0 || n_parts > 256 {
        return Err(ColorError(format!("{n_parts} parts is not within 1..=256")));
    }
    // samples[margin][part]: linear RGB of the part's pixels at least `margin` inside.
    let mut samples: Vec<Vec<Vec<[f32; 3]>>> = vec![vec![Vec::new(); n_parts]; EDGE_MARGIN + 1];
    for ((view, photo), mask) in views.iter().zip(photos).zip(masks) {
        view_samples(mesh, view, photo, mask, &mut samples)?;
    }
    let has_triangles: Vec<bool> = (0..n_parts)
        .map(|p| mesh.tri_parts.iter().any(|&t| usize::from(t) == p))
        .collect();
    let mut measured: Vec<Option<([f32; 3], usize)>> = vec![None; n_parts];
    for (p, slot) in measured.iter_mut().enumerate() {
        // The widest margin that still leaves enough pixels.
        if let Some(s) = samples
            .iter()
            .rev()
            .map(|by_part| &by_part[p])
            .find(|s| s.len() >= MIN_PIXELS)
        {
            *slot = Some((robust_color(s), s.len()));
        }
    }
    let mut out = Vec::new();
    for (p, part) in mesh.parts.iter().enumerate() {
        if !has_triangles[p] {
            continue;
        }
        let default = [part.color[0], part.color[1], part.color[2]];
        let (color, source) = match measured[p] {
            Some((c, pixels)) => (c, Source::Photo { pixels }),
            None => match nearest_seen(mesh, p, &measured) {
                Some(q) if plain(part) && plain(&mesh.parts[q]) => (
                    measured[q].map_or(default, |(c, _)| c),
                    Source::Neighbour(mesh.parts[q].name),
                ),
                _ => (default, Source::Default),
            },
        };
        out.push(PartColor {
            part: part.name,
            color,
            source,
        });
    }
    Ok(out)
}

/// The colour of each part of a tree (`mesh`'s parts with triangles) from a photo labelled
/// branch/leaf ([`crate::tree::labels`]; `labels` and `photo` of one size): leaf parts from the
/// leaf pixels, bark parts (trunk, branches) from the branch pixels, by the same robust estimate
/// as [`estimate`]. A tree fit matches the photo's crown and stems only roughly, so its parts
/// are coloured by the photo's classes rather than by the pixels they cover. A class with fewer
/// than [`MIN_PIXELS`] pixels leaves its parts at their defaults.
pub fn from_tree_labels(
    mesh: &Mesh,
    labels: &crate::mask::LabelImage,
    photo: &Rgba<'_>,
) -> Result<Vec<PartColor>, ColorError> {
    use crate::tree::{BRANCH, LEAF};
    let (w, h) = (labels.width(), labels.height());
    if (photo.width, photo.height) != (w, h) || photo.pixels.len() != 4 * w as usize * h as usize {
        return Err(ColorError(format!(
            "the labels are {w}×{h} but the photo is {}×{}",
            photo.width, photo.height
        )));
    }
    let srgb = srgb_to_linear_table();
    let class = |want: u8| -> Option<([f32; 3], usize)> {
        let px: Vec<[f32; 3]> = labels
            .labels()
            .iter()
            .zip(photo.pixels.chunks_exact(4))
            .filter(|&(&l, _)| l == want)
            .map(|(_, p)| [0, 1, 2].map(|k| srgb[usize::from(p[k])]))
            .collect();
        (px.len() >= MIN_PIXELS).then(|| (robust_color(&px), px.len()))
    };
    let (leaf, bark) = (class(LEAF), class(BRANCH));
    let mut out = Vec::new();
    for (p, part) in mesh.parts.iter().enumerate() {
        if !mesh.tri_parts.iter().any(|&t| usize::from(t) == p) {
            continue;
        }
        let measured = if crate::glb::is_foliage(part) {
            leaf
        } else if crate::glb::is_bark(part) {
            bark
        } else {
            None
        };
        let (color, source) = match measured {
            Some((c, pixels)) => (c, Source::Photo { pixels }),
            None => (
                [part.color[0], part.color[1], part.color[2]],
                Source::Default,
            ),
        };
        out.push(PartColor {
            part: part.name,
            color,
            source,
        });
    }
    Ok(out)
}

/// The colours of `estimate` that replace a default (measured or borrowed), for
/// [`crate::model::Model::colors`].
pub fn to_part_colors(colors: &[PartColor]) -> PartColors {
    colors
        .iter()
        .filter(|c| c.source != Source::Default)
        .map(|c| {
            (
                c.part.to_string(),
                c.color.map(|v| (v * 1000.0).round() / 1000.0),
            )
        })
        .collect()
}

/// A one-line account of the parts the photos did not show, or `None` when they showed all.
pub fn unseen_note(colors: &[PartColor]) -> Option<String> {
    let said: Vec<String> = colors
        .iter()
        .filter_map(|c| match c.source {
            Source::Photo { .. } => None,
            Source::Neighbour(from) => Some(format!("{} took the colour of {from}", c.part)),
            Source::Default => Some(format!("{} keeps its default colour", c.part)),
        })
        .collect();
    (!said.is_empty()).then(|| format!("the photos do not show every part: {}", said.join("; ")))
}

/// Adds one view's pixels to `samples`.
fn view_samples(
    mesh: &Mesh,
    view: &View,
    photo: &Rgba<'_>,
    mask: &Mask,
    samples: &mut [Vec<Vec<[f32; 3]>>],
) -> Result<(), ColorError> {
    let (w, h) = (view.width as usize, view.height as usize);
    if (photo.width, photo.height) != (view.width, view.height)
        || (mask.width(), mask.height()) != (view.width, view.height)
        || photo.pixels.len() != 4 * w * h
    {
        return Err(ColorError(format!(
            "a view is {}×{} but its photo is {}×{} ({} bytes) and its mask {}×{}",
            view.width,
            view.height,
            photo.width,
            photo.height,
            photo.pixels.len(),
            mask.width(),
            mask.height()
        )));
    }
    let n_parts = mesh.parts.len();
    let mut r = LabelRenderer::new(view.width, view.height, 2).map_err(|e| ColorError(e.0))?;
    let planes = r
        .render(
            &mesh.positions,
            &mesh.triangles,
            &mesh.tri_parts,
            n_parts,
            view,
        )
        .map_err(|e| ColorError(e.0))?;
    let n = w * h;
    // The part a pixel wholly shows inside the object, else NONE.
    const NONE: u16 = u16::MAX;
    let mut label: Vec<u16> = vec![NONE; n];
    for (i, (l, &m)) in label.iter_mut().zip(mask.values()).enumerate() {
        if m == Mask::DONT_CARE || m < 0.5 {
            continue;
        }
        if let Some(p) = (0..n_parts).find(|&p| planes[p * n + i] >= 0.999) {
            *l = p as u16;
        }
    }
    let srgb = srgb_to_linear_table();
    let mut eroded = label.clone();
    for (margin, by_part) in samples.iter_mut().enumerate() {
        if margin > 0 {
            eroded = erode(&eroded, w, h, NONE);
        }
        for (i, &l) in eroded.iter().enumerate() {
            if l == NONE {
                continue;
            }
            let px = &photo.pixels[4 * i..4 * i + 3];
            by_part[usize::from(l)].push([
                srgb[usize::from(px[0])],
                srgb[usize::from(px[1])],
                srgb[usize::from(px[2])],
            ]);
        }
    }
    Ok(())
}

/// `label` with every pixel whose 8 neighbours do not all carry its label (or that touches the
/// image's border) set to `none`: a one-pixel erosion of each label's region.
fn erode(label: &[u16], w: usize, h: usize, none: u16) -> Vec<u16> {
    let mut out = vec![none; label.len()];
    for y in 1..h.saturating_sub(1) {
        for x in 1..w.saturating_sub(1) {
            let l = label[y * w + x];
            if l == none {
                continue;
            }
            let inside =
                (y - 1..=y + 1).all(|yy| (x - 1..=x + 1).all(|xx| label[yy * w + xx] == l));
            if inside {
                out[y * w + x] = l;
            }
        }
    }
    out
}

/// The module doc's robust base colour of one part's pixels (linear RGB).
fn robust_color(pixels: &[[f32; 3]]) -> [f32; 3] {
    let clip = srgb_to_linear_table()[usize::from(CLIPPED)];
    let unclipped: Vec<[f32; 3]> = pixels
        .iter()
        .copied()
        .filter(|c| c.iter().all(|&v| v < clip))
        .collect();
    // A part that is mostly clipped is white (or over-exposed): its clipped pixels are its colour.
    let mut kept = if unclipped.len() * 2 >= pixels.len() && !unclipped.is_empty() {
        unclipped
    } else {
        pixels.to_vec()
    };
    kept.sort_by(|a, b| luminance(a).total_cmp(&luminance(b)));
    let n = kept.len();
    let lo = ((BAND.0 * n as f64).floor() as usize).min(n - 1);
    let hi = ((BAND.1 * n as f64).ceil() as usize).clamp(lo + 1, n);
    let band = &kept[lo..hi];
    let mut sum = [0.0f64; 3];
    for c in band {
        for k in 0..3 {
            sum[k] += f64::from(c[k]);
        }
    }
    let mean = sum.map(|s| s / band.len() as f64);
    // The band's hue and saturation at the brightness of the lit side.
    let lit = f64::from(luminance(&kept[((LIT * n as f64) as usize).min(n - 1)]));
    let l = f64::from(luminance(&mean.map(|v| v as f32)));
    let gain = if l > 1e-6 { lit / l } else { 1.0 };
    mean.map(|v| (v * gain).clamp(0.0, 1.0) as f32)
}

/// Relative luminance of linear RGB (Rec. 709 primaries).
fn luminance(c: &[f32; 3]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

/// Whether a part is a plain opaque surface (not glass or leaves), one that may lend or borrow
/// a colour.
fn plain(part: &Part) -> bool {
    crate::glb::is_plain(part)
}

/// The measured part nearest to part `p`: the smallest distance from `p`'s vertex centroid to
/// a vertex of a measured part.
fn nearest_seen(mesh: &Mesh, p: usize, measured: &[Option<([f32; 3], usize)>]) -> Option<usize> {
    let mut sum = glam::Vec3::ZERO;
    let mut count = 0usize;
    for (t, &part) in mesh.triangles.iter().zip(&mesh.tri_parts) {
        if usize::from(part) == p {
            for &i in t {
                sum += mesh.positions[i as usize];
                count += 1;
            }
        }
    }
    if count == 0 {
        return None;
    }
    let centre = sum / count as f32;
    let mut best: Option<(f32, usize)> = None;
    for (t, &part) in mesh.triangles.iter().zip(&mesh.tri_parts) {
        let q = usize::from(part);
        if q == p || measured.get(q).is_none_or(Option::is_none) {
            continue;
        }
        for &i in t {
            let d = mesh.positions[i as usize].distance_squared(centre);
            if best.is_none_or(|(bd, _)| d < bd) {
                best = Some((d, q));
            }
        }
    }
    best.map(|(_, q)| q)
}

/// 8-bit sRGB → linear, one entry per code.
fn srgb_to_linear_table() -> [f32; 256] {
    std::array::from_fn(|i| srgb_to_linear(i as f32 / 255.0))
}

/// One sRGB channel in 0–1 → linear (IEC 61966-2-1).
pub fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

/// One linear channel in 0–1 → sRGB (IEC 61966-2-1).
pub fn linear_to_srgb(v: f32) -> f32 {
    let v = v.clamp(0.0, 1.0);
    if v <= 0.003_130_8 {
        v * 12.92
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

/// CIE L*a*b* (D65 white) of a linear RGB colour (sRGB primaries).
pub fn lab(c: [f32; 3]) -> [f64; 3] {
    let [r, g, b] = c.map(f64::from);
    let x = 0.412_456_4 * r + 0.357_576_1 * g + 0.180_437_5 * b;
    let y = 0.212_672_9 * r + 0.715_152_2 * g + 0.072_175 * b;
    let z = 0.019_333_9 * r + 0.119_192 * g + 0.950_304_1 * b;
    let f = |t: f64| {
        if t > 216.0 / 24389.0 {
            t.cbrt()
        } else {
            (24389.0 / 27.0 * t + 16.0) / 116.0
        }
    };
    let (fx, fy, fz) = (f(x / 0.950_47), f(y), f(z / 1.088_83));
    [116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)]
}

/// CIE76 colour difference ΔE*ab between two linear RGB colours (2.3 is about the smallest
/// difference people notice side by side).
pub fn delta_e76(a: [f32; 3], b: [f32; 3]) -> f64 {
    let (a, b) = (lab(a), lab(b));
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lab_of_white_and_black() {
        let w = lab([1.0; 3]);
        assert!(
            (w[0] - 100.0).abs() < 0.01 && w[1].abs() < 0.01 && w[2].abs() < 0.01,
            "{w:?}"
        );
        assert!(lab([0.0; 3])[0].abs() < 1e-9);
        assert!(delta_e76([0.0, 0.0, 1.0], [0.0, 0.0, 1.0]) == 0.0);
    }

    #[test]
    fn srgb_round_trips() {
        for i in 0..=255 {
            let v = i as f32 / 255.0;
            assert!((linear_to_srgb(srgb_to_linear(v)) - v).abs() < 1e-5);
        }
    }

    #[test]
    fn robust_colour_ignores_shadows_and_clipped_highlights() {
        let blue = [0.05f32, 0.2, 0.6];
        let mut px = Vec::new();
        for i in 0..100 {
            // Lit 60–100 %, a few clipped white highlights, a dark shadowed third.
            let s = 0.6 + 0.4 * (i as f32 / 99.0);
            px.push(blue.map(|c| c * s));
        }
        px.extend(std::iter::repeat_n([1.0f32; 3], 8));
        px.extend(std::iter::repeat_n(blue.map(|c| c * 0.1), 40));
        let got = robust_color(&px);
        assert!(delta_e76(got, blue) < 6.0, "{got:?}");
        // A white part is mostly clipped: white it stays.
        let white = vec![[1.0f32; 3]; 30];
        assert_eq!(robust_color(&white), [1.0; 3]);
    }
}
