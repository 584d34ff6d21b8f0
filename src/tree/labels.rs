//! Semantic tree masks (paper §3.5.1): a [`LabelImage`] with background, branch and leaf labels,
//! made from a photo by colour (green → leaf, brown or grey → branch, the rest → background) or
//! taken from a user-supplied label image.

use super::{BACKGROUND, BRANCH, LEAF};
use crate::mask::{LabelImage, MaskError};
use serde::{Deserialize, Serialize};

/// Colour rules for [`labels_from_rgb`], in HSV with hue in degrees and saturation/value in
/// `[0, 1]`. The defaults suit daylight photos of trees against sky, grass-free ground or walls.
/// A hue range whose start is above its end wraps through red (`(330, 170)`: red, orange,
/// yellow and green — autumn leaves). In JSON (the page's "Adjust colours"), fields are
/// camelCase and any left out keep their defaults; [`ColorThresholds::check`] refuses
/// values out of range.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, rename_all = "camelCase", deny_unknown_fields)]
pub struct ColorThresholds {
    /// Hue range of foliage (yellow-green to blue-green).
    pub leaf_hue: (f32, f32),
    /// Least saturation of foliage: greyish greens are not leaves.
    pub leaf_min_saturation: f32,
    /// Least value (brightness) of foliage: shadowed greens still count down to here.
    pub leaf_min_value: f32,
    /// Hue range of bark (red to orange-brown).
    pub bark_hue: (f32, f32),
    /// Saturation range of brown bark.
    pub bark_saturation: (f32, f32),
    /// Value range of bark, brown or grey: very dark shadows and bright sky are excluded.
    pub bark_value: (f32, f32),
    /// Greys (saturation at most this) in the bark value range count as bark (birch, beech).
    pub grey_max_saturation: f32,
    /// Colours that are neither foliage nor bark count as branch instead of background: for
    /// labels limited to an object mask ([`apply_mask_codes`]), where everything inside is tree
    /// (dark trunks in shade, painted or lichen-covered bark).
    pub rest_as_branch: bool,
}

impl Default for ColorThresholds {
    fn default() -> Self {
        ColorThresholds {
            leaf_hue: (60.0, 170.0),
            leaf_min_saturation: 0.18,
            leaf_min_value: 0.08,
            bark_hue: (0.0, 50.0),
            bark_saturation: (0.12, 0.8),
            bark_value: (0.08, 0.6),
            grey_max_saturation: 0.12,
            rest_as_branch: false,
        }
    }
}

impl ColorThresholds {
    /// Colour rules from camelCase JSON (fields left out keep their defaults), checked
    /// ([`ColorThresholds::check`]).
    pub fn from_json(text: &str) -> Result<ColorThresholds, MaskError> {
        let t: ColorThresholds =
            serde_json::from_str(text).map_err(|e| MaskError(format!("colour rules: {e}")))?;
        t.check()?;
        Ok(t)
    }

    /// Errors, in words, on a hue outside `[0, 360]`, a saturation or value outside `[0, 1]`,
    /// a range whose start is above its end (hues excepted: they wrap) or a non-finite number.
    pub fn check(&self) -> Result<(), MaskError> {
        let bad = |m: String| Err(MaskError(m));
        for (name, (lo, hi)) in [("leaf hue", self.leaf_hue), ("bark hue", self.bark_hue)] {
            if !(lo.is_finite()
                && hi.is_finite()
                && (0.0..=360.0).contains(&lo)
                && (0.0..=360.0).contains(&hi))
            {
                return bad(format!("{name} {lo}–{hi}: hues are degrees in 0–360"));
            }
        }
        for (name, (lo, hi)) in [
            ("bark saturation", self.bark_saturation),
            ("bark brightness", self.bark_value),
        ] {
            if !(lo.is_finite() && hi.is_finite() && 0.0 <= lo && lo <= hi && hi <= 1.0) {
                return bad(format!(
                    "{name} {lo}–{hi}: a range within 0–1, low end first"
                ));
            }
        }
        for (name, v) in [
            ("leaf saturation", self.leaf_min_saturation),
            ("leaf brightness", self.leaf_min_value),
            ("grey saturation", self.grey_max_saturation),
        ] {
            if !(v.is_finite() && (0.0..=1.0).contains(&v)) {
                return bad(format!("{name} {v}: must be within 0–1"));
            }
        }
        Ok(())
    }
}

/// Whether hue `h` lies in `(lo, hi)`, wrapping through 360° when `lo > hi`.
fn in_hue(h: f32, (lo, hi): (f32, f32)) -> bool {
    if lo <= hi {
        (lo..=hi).contains(&h)
    } else {
        h >= lo || h <= hi
    }
}

/// Hue (degrees), saturation and value of an 8-bit RGB colour.
pub fn rgb_to_hsv(r: u8, g: u8, b: u8) -> (f32, f32, f32) {
    let (r, g, b) = (
        f32::from(r) / 255.0,
        f32::from(g) / 255.0,
        f32::from(b) / 255.0,
    );
    let max = r.max(g).max(b);
    let min = r.min(g).min(b);
    let delta = max - min;
    let hue = if delta <= 0.0 {
        0.0
    } else if max == r {
        60.0 * ((g - b) / delta).rem_euclid(6.0)
    } else if max == g {
        60.0 * ((b - r) / delta + 2.0)
    } else {
        60.0 * ((r - g) / delta + 4.0)
    };
    let sat = if max > 0.0 { delta / max } else { 0.0 };
    (hue, sat, max)
}

/// The label of one colour under `t`.
pub fn classify(r: u8, g: u8, b: u8, t: &ColorThresholds) -> u8 {
    let (h, s, v) = rgb_to_hsv(r, g, b);
    let in_range = |x: f32, (lo, hi): (f32, f32)| (lo..=hi).contains(&x);
    if in_hue(h, t.leaf_hue) && s >= t.leaf_min_saturation && v >= t.leaf_min_value {
        LEAF
    } else if t.rest_as_branch
        || (in_range(v, t.bark_value)
            && (s <= t.grey_max_saturation
                || (in_hue(h, t.bark_hue) && in_range(s, t.bark_saturation))))
    {
        BRANCH
    } else {
        BACKGROUND
    }
}

/// Labels a photo by colour. `pixels` is row-major, `channels` values a pixel (3 = RGB,
/// 4 = RGBA; alpha below 128 is background).
pub fn labels_from_rgb(
    width: u32,
    height: u32,
    pixels: &[u8],
    channels: usize,
    thresholds: &ColorThresholds,
) -> Result<LabelImage, MaskError> {
    if channels != 3 && channels != 4 {
        return Err(MaskError(format!(
            "{channels} channels a pixel; expected 3 (RGB) or 4 (RGBA)"
        )));
    }
    thresholds.check()?;
    let n = width as usize * height as usize;
    if pixels.len() != n * channels {
        return Err(MaskError(format!(
            "{} bytes for a {width}×{height} image with {channels} channels",
            pixels.len()
        )));
    }
    let labels = pixels
        .chunks_exact(channels)
        .map(|p| {
            if channels == 4 && p[3] < 128 {
                BACKGROUND
            } else {
                classify(p[0], p[1], p[2], thresholds)
            }
        })
        .collect();
    LabelImage::new(width, height, labels)
}

/// Share of a tree's pixels that must be leaves for its labels to look like a tree with a
/// crown ([`foliage_problem`]).
pub const MIN_LEAF_SHARE: f64 = 0.05;

/// Says what is implausible about tree labels, or `None` when they look like a tree with
/// foliage: no tree pixel at all, or leaves under [`MIN_LEAF_SHARE`] of the tree's pixels (a
/// fit would make a leafless stick).
pub fn foliage_problem(labels: &LabelImage) -> Option<String> {
    let (mut leaf, mut branch) = (0usize, 0usize);
    for &l in labels.labels() {
        leaf += usize::from(l == LEAF);
        branch += usize::from(l == BRANCH);
    }
    if leaf + branch == 0 {
        return Some("no tree found: no pixel is foliage or bark".into());
    }
    let share = leaf as f64 / (leaf + branch) as f64;
    (share < MIN_LEAF_SHARE).then(|| {
        format!(
            "hardly any foliage: {:.1} % of the tree's {} pixels are leaves; set the leaf colours \
             (--tree-colors, the page's \"Adjust the colours\") or give a label image",
            100.0 * share,
            leaf + branch
        )
    })
}

/// Width of the image frame whose colours [`labels_adaptive`] takes as the background.
const FRAME: usize = 4;

/// Labels a photo of a tree on a plain or sky background by the photo's own colours, for
/// foliage of any colour (yellow, orange, red, blue-green):
///
/// 1. the object is what differs from the background, which is taken row by row from the
///    image's left and right frame (so a sky gradient stays background);
/// 2. inside the object, a bark colour model comes from the object's lowest rows (the trunk's
///    foot) and a foliage model from its upper half (mean and spread per channel);
/// 3. every object pixel takes the nearer model; when the two models are alike (a bush with
///    foliage down to the ground), the whole object is foliage.
///
/// `pixels` as for [`labels_from_rgb`].
pub fn labels_adaptive(
    width: u32,
    height: u32,
    pixels: &[u8],
    channels: usize,
) -> Result<LabelImage, MaskError> {
    if channels != 3 && channels != 4 {
        return Err(MaskError(format!(
            "{channels} channels a pixel; expected 3 (RGB) or 4 (RGBA)"
        )));
    }
    let (w, h) = (width as usize, height as usize);
    if pixels.len() != w * h * channels {
        return Err(MaskError(format!(
            "{} bytes for a {width}×{height} image with {channels} channels",
            pixels.len()
        )));
    }
    let rgb = |i: usize| -> [f64; 3] {
        let p = &pixels[i * channels..i * channels + 3];
        [f64::from(p[0]), f64::from(p[1]), f64::from(p[2])]
    };
    let opaque = |i: usize| channels == 3 || pixels[i * channels + 3] >= 128;
    let frame = FRAME.min(w / 2).max(1);
    let mut object = vec![false; w * h];
    for y in 0..h {
        let mut bg = [0.0; 3];
        let mut n = 0.0;
        for x in (0..frame).chain(w.saturating_sub(frame)..w) {
            let c = rgb(y * w + x);
            for k in 0..3 {
                bg[k] += c[k];
            }
            n += 1.0;
        }
        let bg = bg.map(|v| v / n);
        for x in 0..w {
            let i = y * w + x;
            let c = rgb(i);
            let d = (0..3).map(|k| (c[k] - bg[k]).powi(2)).sum::<f64>().sqrt();
            object[i] = opaque(i) && d > 40.0;
        }
    }
    let rows: Vec<usize> = (0..h)
        .filter(|&y| object[y * w..(y + 1) * w].iter().any(|&o| o))
        .collect();
    let mut labels = vec![BACKGROUND; w * h];
    let (Some(&top), Some(&bottom)) = (rows.first(), rows.last()) else {
        return LabelImage::new(width, height, labels);
    };
    let span = bottom + 1 - top;
    let model = |y0: usize, y1: usize| -> Option<([f64; 3], [f64; 3])> {
        let (mut s, mut s2, mut n) = ([0.0; 3], [0.0; 3], 0.0);
        for y in y0..y1 {
            for x in 0..w {
                if object[y * w + x] {
                    let c = rgb(y * w + x);
                    for k in 0..3 {
                        s[k] += c[k];
                        s2[k] += c[k] * c[k];
                    }
                    n += 1.0;
                }
            }
        }
        (n > 0.0).then(|| {
            let m = s.map(|v| v / n);
            let sd = [0, 1, 2].map(|k| (s2[k] / n - m[k] * m[k]).max(0.0).sqrt().max(8.0));
            (m, sd)
        })
    };
    let foot = model(bottom + 1 - (span / 12).max(1), bottom + 1);
    let crown = model(top, top + (span / 2).max(1));
    let (Some(bark), Some(leaf)) = (foot, crown) else {
        return LabelImage::new(width, height, labels);
    };
    let dist = |c: [f64; 3], (m, sd): ([f64; 3], [f64; 3])| {
        (0..3).map(|k| ((c[k] - m[k]) / sd[k]).powi(2)).sum::<f64>()
    };
    // Alike: each model's mean lies within the other's spread.
    let alike = dist(bark.0, leaf) < 1.0 && dist(leaf.0, bark) < 1.0;
    let foot_top = bottom + 1 - (span / 12).max(1);
    let mut branches = 0;
    for i in 0..w * h {
        if object[i] {
            let c = rgb(i);
            labels[i] = if alike || dist(c, leaf) <= dist(c, bark) {
                LEAF
            } else {
                branches += 1;
                BRANCH
            };
        }
    }
    if branches == 0 {
        // All alike: the object's foot is where its stem is.
        for (i, l) in labels.iter_mut().enumerate().skip(foot_top * w) {
            if object[i] {
                *l = BRANCH;
            }
        }
    }
    LabelImage::new(width, height, labels)
}

/// The labels of a photo as the CLI and the benchmark make them: by the colour rules `t`
/// ([`labels_from_rgb`]); when those find hardly any foliage ([`foliage_problem`]), by the
/// photo's own colours ([`labels_adaptive`]) if that finds foliage. The string says which was
/// used when it was not the rules.
pub fn photo_labels(
    width: u32,
    height: u32,
    pixels: &[u8],
    channels: usize,
    t: &ColorThresholds,
) -> Result<(LabelImage, Option<String>), MaskError> {
    let rules = labels_from_rgb(width, height, pixels, channels, t)?;
    if foliage_problem(&rules).is_none() {
        return Ok((rules, None));
    }
    let adaptive = labels_adaptive(width, height, pixels, channels)?;
    if foliage_problem(&adaptive).is_none() {
        return Ok((
            adaptive,
            Some(
                "few pixels have the leaf colours: foliage and bark were told apart by this \
                 photo's own colours (tree against a plain background)"
                    .into(),
            ),
        ));
    }
    Ok((rules, None))
}

/// A tree's label image from decoded RGBA pixels, as the CLI reads an image file: a grey,
/// opaque image holding only the label values 0, 1, 2 and 255 is taken as labels
/// ([`labels_from_values`]), anything else as a photo labelled by colour ([`photo_labels`]).
/// The string says how a photo was labelled when it was not by the rules.
pub fn labels_from_image(
    width: u32,
    height: u32,
    rgba: &[u8],
    t: &ColorThresholds,
) -> Result<(LabelImage, Option<String>), MaskError> {
    let is_labels = rgba
        .chunks_exact(4)
        .all(|p| p[0] == p[1] && p[1] == p[2] && p[3] == 255 && matches!(p[0], 0 | 1 | 2 | 255));
    if is_labels {
        let values = rgba.chunks_exact(4).map(|p| p[0]).collect();
        Ok((labels_from_values(width, height, values)?, None))
    } else {
        photo_labels(width, height, rgba, 4, t)
    }
}

/// A user-supplied label image: every value must be [`BACKGROUND`], [`BRANCH`], [`LEAF`] or
/// [`LabelImage::DONT_CARE`].
pub fn labels_from_values(
    width: u32,
    height: u32,
    values: Vec<u8>,
) -> Result<LabelImage, MaskError> {
    if let Some((i, v)) = values
        .iter()
        .enumerate()
        .find(|&(_, &v)| !matches!(v, BACKGROUND | BRANCH | LEAF | LabelImage::DONT_CARE))
    {
        return Err(MaskError(format!(
            "label {v} at pixel {i}: tree labels are 0 background, 1 branch, 2 leaf, 255 don't care"
        )));
    }
    LabelImage::new(width, height, values)
}

/// Restricts colour labels to an object mask given as 8-bit codes, one a pixel, as the page's
/// mask step makes them: 0 background (label cleared), 128 don't care
/// ([`LabelImage::DONT_CARE`]), anything else object (label kept). Errors on a code count
/// other than the pixel count.
pub fn apply_mask_codes(labels: &LabelImage, codes: &[u8]) -> Result<LabelImage, MaskError> {
    if codes.len() != labels.labels().len() {
        return Err(MaskError(format!(
            "{} mask codes for a {}×{} image",
            codes.len(),
            labels.width(),
            labels.height()
        )));
    }
    let values = labels
        .labels()
        .iter()
        .zip(codes)
        .map(|(&l, &c)| match c {
            0 => BACKGROUND,
            128 => LabelImage::DONT_CARE,
            _ => l,
        })
        .collect();
    LabelImage::new(labels.width(), labels.height(), values)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(rgb: [u8; 3], expected: u8) {
        let got = classify(rgb[0], rgb[1], rgb[2], &ColorThresholds::default());
        assert_eq!(got, expected, "colour {rgb:?}");
    }

    #[test]
    fn colours_map_to_labels() {
        check([40, 120, 30], LEAF); // leaf green
        check([20, 60, 25], LEAF); // shadowed foliage
        check([150, 170, 60], LEAF); // yellow-green
        check([90, 60, 35], BRANCH); // brown bark
        check([110, 110, 105], BRANCH); // grey bark
        check([135, 190, 235], BACKGROUND); // sky
        check([250, 250, 250], BACKGROUND); // white wall
        check([5, 5, 5], BACKGROUND); // black
        check([200, 40, 40], BACKGROUND); // red car
    }

    #[test]
    fn thresholds_adjust_the_labels() {
        // Autumn: orange and red leaves are background by default, leaves with a hue range
        // that wraps through red; dark brown bark stays bark when leaves must be bright.
        let autumn = ColorThresholds {
            leaf_hue: (330.0, 170.0),
            leaf_min_value: 0.45,
            ..ColorThresholds::default()
        };
        let orange = [230, 120, 30];
        let red = [200, 30, 40];
        let bark = [90, 60, 35];
        check(orange, BACKGROUND);
        for (rgb, label) in [
            (orange, LEAF),
            (red, LEAF),
            (bark, BRANCH),
            ([40, 120, 30], LEAF),
        ] {
            assert_eq!(classify(rgb[0], rgb[1], rgb[2], &autumn), label, "{rgb:?}");
        }
        // Inside a mask, the rest can be branch: a blue-painted trunk.
        let rest = ColorThresholds {
            rest_as_branch: true,
            ..ColorThresholds::default()
        };
        assert_eq!(
            classify(40, 60, 200, &ColorThresholds::default()),
            BACKGROUND
        );
        assert_eq!(classify(40, 60, 200, &rest), BRANCH);
        assert_eq!(classify(40, 120, 30, &rest), LEAF);
    }

    #[test]
    fn thresholds_read_from_json_and_are_checked() {
        let t: ColorThresholds =
            serde_json::from_str(r#"{"leafHue":[20,170],"restAsBranch":true}"#).unwrap();
        assert_eq!(t.leaf_hue, (20.0, 170.0));
        assert!(t.rest_as_branch);
        assert_eq!(t.bark_value, ColorThresholds::default().bark_value);
        assert!(serde_json::from_str::<ColorThresholds>(r#"{"leafHew":[1,2]}"#).is_err());
        for bad in [
            ColorThresholds {
                leaf_hue: (0.0, 400.0),
                ..ColorThresholds::default()
            },
            ColorThresholds {
                bark_value: (0.6, 0.1),
                ..ColorThresholds::default()
            },
            ColorThresholds {
                leaf_min_saturation: f32::NAN,
                ..ColorThresholds::default()
            },
        ] {
            assert!(bad.check().is_err(), "{bad:?}");
            assert!(labels_from_rgb(1, 1, &[0, 0, 0], 3, &bad).is_err());
        }
    }

    #[test]
    fn bad_inputs_are_refused() {
        let t = ColorThresholds::default();
        assert!(labels_from_rgb(2, 2, &[0; 11], 3, &t).is_err());
        assert!(labels_from_rgb(2, 2, &[0; 8], 2, &t).is_err());
        assert!(labels_from_values(2, 1, vec![0, 3]).is_err());
        let l = labels_from_rgb(2, 1, &[40, 120, 30, 255, 40, 120, 30, 0], 4, &t).unwrap();
        assert_eq!(l.labels(), &[LEAF, BACKGROUND]);
        assert!(apply_mask_codes(&l, &[255]).is_err());
    }

    #[test]
    fn mask_codes_restrict_labels() {
        let l = labels_from_values(4, 1, vec![LEAF, BRANCH, LEAF, LEAF]).unwrap();
        let m = apply_mask_codes(&l, &[255, 0, 128, 200]).unwrap();
        assert_eq!(m.labels(), &[LEAF, BACKGROUND, LabelImage::DONT_CARE, LEAF]);
    }

    /// A synthetic photo: sky gradient, a crown of `leaf` (with a darker shade mixed in) on a
    /// brown trunk.
    fn tree_photo(leaf: [u8; 3]) -> (u32, u32, Vec<u8>) {
        let (w, h) = (64u32, 64u32);
        let mut px = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let (dx, dy) = (x as f64 - 32.0, y as f64 - 24.0);
                let c = if dx * dx + dy * dy < 18.0 * 18.0 {
                    if (x + y) % 3 == 0 {
                        leaf.map(|v| (f64::from(v) * 0.7) as u8)
                    } else {
                        leaf
                    }
                } else if (30..34).contains(&x) && (40..60).contains(&y) {
                    [90, 62, 40]
                } else {
                    [110 + (y as u8), 160 + (y as u8) / 2, 230]
                };
                px.extend(c);
            }
        }
        (w, h, px)
    }

    #[test]
    fn foliage_of_any_colour_is_labelled_by_the_photo() {
        for (name, leaf) in [
            ("yellow", [230u8, 200, 40]),
            ("orange", [230, 120, 30]),
            ("red", [190, 30, 35]),
            ("dark green", [25, 70, 30]),
            ("blue-green", [40, 110, 100]),
        ] {
            let (w, h, px) = tree_photo(leaf);
            let (l, _) = photo_labels(w, h, &px, 3, &ColorThresholds::default()).unwrap();
            let at = |x: u32, y: u32| l.labels()[(y * w + x) as usize];
            assert_eq!(at(32, 24), LEAF, "{name}: crown centre");
            assert_eq!(at(20, 20), LEAF, "{name}: crown");
            assert_eq!(at(31, 55), BRANCH, "{name}: trunk");
            assert_eq!(at(2, 2), BACKGROUND, "{name}: sky");
            assert_eq!(at(60, 60), BACKGROUND, "{name}: sky below");
            assert!(foliage_problem(&l).is_none(), "{name}");
        }
        // The rules alone miss yellow and red foliage: that is what the fallback is for.
        let (w, h, px) = tree_photo([190, 30, 35]);
        let rules = labels_from_rgb(w, h, &px, 3, &ColorThresholds::default()).unwrap();
        assert!(foliage_problem(&rules).is_some());
    }

    #[test]
    fn a_tree_without_foliage_is_called_implausible() {
        let l = labels_from_values(4, 1, vec![BRANCH, BRANCH, BRANCH, BACKGROUND]).unwrap();
        assert!(foliage_problem(&l).unwrap().contains("hardly any foliage"));
        let none = labels_from_values(2, 1, vec![BACKGROUND, BACKGROUND]).unwrap();
        assert!(foliage_problem(&none).unwrap().contains("no tree"));
        let ok = labels_from_values(3, 1, vec![BRANCH, LEAF, LEAF]).unwrap();
        assert!(foliage_problem(&ok).is_none());
    }
}
