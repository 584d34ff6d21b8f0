//! Photo → mask end to end: synthetic photos with known truth (a shaded cup with a handle loop
//! over plain, gradient, noisy and textured backgrounds, sensor noise, JPEG), EXIF orientation,
//! interactive strokes, the other mask sources, windows and bad input.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "a test binary: a failed step should stop it loudly"
)]

use image::codecs::jpeg::JpegEncoder;
use image::codecs::png::PngEncoder;
use image::metadata::Orientation;
use image::{DynamicImage, ExtendedColorType, ImageEncoder, RgbImage, RgbaImage};
use procfit::mask::Mask;
use procfit::segment::plausible;
use procfit::segment::windows::{
    LABEL_BACKGROUND, LABEL_WINDOW, clip_windows, detect_windows, windows_from_strokes,
};
use procfit::segment::{
    BBox, Label, Options, Photo, Segmentation, Session, Stroke, WORKING_SIDE, segment,
    segment_alpha, segment_auto, segment_mask_image,
};

// ---------------------------------------------------------------- synthetic photos

/// Deterministic noise (tests must not flake).
struct Rng(u64);
impl Rng {
    fn uniform(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((self.0 >> 40) as f32 + 0.5) / (1u64 << 24) as f32
    }
    fn gauss(&mut self) -> f32 {
        let (a, b) = (self.uniform(), self.uniform());
        (-2.0 * a.ln()).sqrt() * (std::f32::consts::TAU * b).cos()
    }
}

#[derive(Clone, Copy, Debug)]
enum Bg {
    Plain,
    Gradient,
    Noisy,
    Textured,
    /// Wall above, a wooden table below 70 % of the height.
    Table,
    /// Sharp-edged cells of many colours (a patterned cloth): strong edges everywhere.
    Cells,
    /// A wall above 25 % of the height, below it a wooden table of planks (each its own shade,
    /// grain streaks, dark seams) with the cup's soft contact shadow, darker and deeper in the
    /// wood's hue, to the left of and below [`CUP`]'s base: the dish photo benchmark's
    /// failure (issue 16) in a few lines.
    Planks,
    /// A wall lit warm from the left and cool from the right, darker towards the top: each
    /// side of the border has colours the others lack.
    LitWall,
}

fn background(bg: Bg, u: f32, v: f32, rng: &mut Rng) -> [f32; 3] {
    match bg {
        Bg::Plain => [0.86, 0.86, 0.83],
        Bg::Gradient => {
            let t = 0.55 * v + 0.15 * u;
            [0.92 - 0.45 * t, 0.92 - 0.40 * t, 0.95 - 0.30 * t]
        }
        Bg::Noisy => {
            let n = 0.06 * rng.gauss();
            [0.8 + n, 0.82 + n, 0.78 + n]
        }
        Bg::Textured => {
            // Two-tone blue-grey checker with wavy stripes on top: colours far from the cup's.
            let check = ((u * 14.0).floor() + (v * 10.0).floor()) as i32 % 2 == 0;
            let stripe = 0.06 * (u * 90.0 + 6.0 * (v * 20.0).sin()).sin();
            if check {
                [0.55 + stripe, 0.62 + stripe, 0.70 + stripe]
            } else {
                [0.80 + stripe, 0.82 + stripe, 0.84 + stripe]
            }
        }
        Bg::Cells => {
            const PALETTE: [[f32; 3]; 6] = [
                [0.35, 0.55, 0.3],
                [0.2, 0.3, 0.55],
                [0.85, 0.75, 0.35],
                [0.6, 0.6, 0.62],
                [0.5, 0.35, 0.6],
                [0.15, 0.2, 0.3],
            ];
            let hash = |a: i32, b: i32, k: u32| {
                let mut x =
                    (a as u32).wrapping_mul(73_856_093) ^ (b as u32).wrapping_mul(19_349_663) ^ k;
                x ^= x >> 13;
                x = x.wrapping_mul(0x5bd1_e995);
                x ^= x >> 15;
                x
            };
            let (gx, gy) = (u * 12.0, v * 9.0);
            let mut best = (f32::INFINITY, 0u32);
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let (cx, cy) = (gx.floor() as i32 + dx, gy.floor() as i32 + dy);
                    let px = cx as f32 + (hash(cx, cy, 1) % 1000) as f32 / 1000.0;
                    let py = cy as f32 + (hash(cx, cy, 2) % 1000) as f32 / 1000.0;
                    let d = (px - gx).powi(2) + (py - gy).powi(2);
                    if d < best.0 {
                        best = (d, hash(cx, cy, 3));
                    }
                }
            }
            PALETTE[(best.1 % 6) as usize]
        }
        Bg::Planks => planks(u * 360.0 / 270.0, v, rng),
        Bg::LitWall => {
            let light = 0.5 + 0.5 * v;
            let warm = [0.80, 0.66, 0.50];
            let cool = [0.50, 0.62, 0.80];
            let grain = 0.02 * (u * 90.0 + 4.0 * (v * 11.0).sin()).sin() + 0.01 * rng.gauss();
            [0, 1, 2].map(|c| (warm[c] + (cool[c] - warm[c]) * u) * light + grain)
        }
        Bg::Table => {
            if v > 0.7 {
                let grain = 0.04 * (u * 60.0 + 3.0 * (v * 40.0).sin()).sin();
                [0.62 + grain, 0.48 + grain, 0.32 + grain]
            } else {
                [0.88, 0.88, 0.86]
            }
        }
    }
}

/// [`Bg::Planks`] at `(x, y)` in units of the image height (the cup scenes are 360×270).
fn planks(x: f32, y: f32, rng: &mut Rng) -> [f32; 3] {
    if y < 0.25 {
        return [0.80, 0.79, 0.76];
    }
    // Planks run slightly askew; each has its own brightness and grain phase.
    let t = (y - 0.25) * 6.0 + 0.08 * x;
    let k = t.floor();
    let f = t - k;
    // The planks under the cup are darker than those along the photo's border.
    let shade = 1.0 - 0.16 * (-((t - 2.6) / 1.2).powi(2)).exp() + 0.05 * (k * 2.7).sin();
    // Wide soft grain and thin dark streaks.
    let streak = (x * 23.0 + 6.0 * f + k * 1.3).sin() * (x * 5.0 + k * 2.1).sin();
    let grain = 0.04 * (x * 40.0 + k * 1.9 + 2.0 * (x * 7.0 + k).sin()).sin()
        - 0.22 * (streak - 0.75).max(0.0) * 4.0
        + 0.01 * rng.gauss();
    let seam = if f < 0.03 { 0.45 } else { 1.0 };
    let wood = [0.66, 0.50, 0.34].map(|c| (c * shade + grain * c) * seam);
    // The contact shadow: a soft blob left of and under the base, down to 45 % of the light,
    // the wood's hue deepened (light bounced off the wood fills it).
    let (dx, dy) = ((x - (CUP.cx - 0.14)) / 0.34, (y - CUP.bottom - 0.02) / 0.1);
    let d = (dx * dx + dy * dy).sqrt();
    let s = if d < 1.0 {
        0.7 * (1.0 - d * d).powf(1.5)
    } else {
        0.0
    };
    let deepen = [1.0, 0.8, 0.55];
    [0, 1, 2].map(|c| wood[c] * (1.0 - s) * (1.0 - s * (1.0 - deepen[c])))
}

/// A cup seen from the side: a tapered lathe body, a saucer-free base and a ring handle on the
/// right whose loop shows the background. Coordinates in units of the image height.
#[derive(Clone, Copy)]
struct Cup {
    cx: f32,
    top: f32,
    bottom: f32,
    r_top: f32,
    r_bottom: f32,
    albedo: [f32; 3],
}

const CUP: Cup = Cup {
    cx: 0.62,
    top: 0.22,
    bottom: 0.78,
    r_top: 0.20,
    r_bottom: 0.15,
    albedo: [0.78, 0.18, 0.12],
};

impl Cup {
    fn radius(&self, y: f32) -> Option<f32> {
        if y < self.top || y > self.bottom {
            return None;
        }
        let t = (y - self.top) / (self.bottom - self.top);
        Some(self.r_top + (self.r_bottom - self.r_top) * t)
    }
    fn handle(&self) -> ([f32; 2], f32, f32) {
        let ym = self.top + 0.42 * (self.bottom - self.top);
        let r = self.radius(ym).unwrap_or(0.0);
        ([self.cx + r + 0.02, ym], 0.13, 0.075)
    }
    /// Colour of the cup at (x, y) if the point is on it.
    fn shade(&self, x: f32, y: f32) -> Option<[f32; 3]> {
        let light = [-0.55f32, -0.35, 0.76];
        if let Some(r) = self.radius(y) {
            let dx = (x - self.cx) / r;
            if dx.abs() <= 1.0 {
                let n = [dx, 0.0, (1.0 - dx * dx).sqrt()];
                let l = (n[0] * light[0] + n[2] * light[2]).max(0.0);
                let spec = l.powi(40) * 0.35;
                return Some(self.albedo.map(|a| a * (0.22 + 0.78 * l) + spec));
            }
        }
        let (c, ro, ri) = self.handle();
        let d = ((x - c[0]).powi(2) + (y - c[1]).powi(2)).sqrt();
        if d <= ro && d >= ri && x > self.cx {
            let t = (d - ri) / (ro - ri) * 2.0 - 1.0;
            let l = (0.55 + 0.4 * (1.0 - t * t).sqrt() * (-(y - c[1]) / d)).clamp(0.0, 1.0);
            return Some(self.albedo.map(|a| a * (0.22 + 0.7 * l)));
        }
        None
    }
}

/// Shapes to draw over the background, first hit wins.
#[derive(Clone, Copy)]
enum Shape {
    Cup(Cup),
    /// A flat ellipse (a saucer): centre, radii, colour.
    Ellipse([f32; 2], [f32; 2], [f32; 3]),
    /// An axis-aligned rectangle `[x0, y0, x1, y1]` with a colour and a little shading.
    Rect([f32; 4], [f32; 3]),
}

impl Shape {
    fn shade(&self, x: f32, y: f32) -> Option<[f32; 3]> {
        match self {
            Shape::Cup(c) => c.shade(x, y),
            Shape::Ellipse(c, r, col) => {
                let d = ((x - c[0]) / r[0]).powi(2) + ((y - c[1]) / r[1]).powi(2);
                (d <= 1.0).then_some(*col)
            }
            Shape::Rect(r, col) => (x >= r[0] && x < r[2] && y >= r[1] && y < r[3])
                .then(|| col.map(|c| c * (1.0 - 0.1 * (y - r[1]) / (r[3] - r[1])))),
        }
    }
}

struct Scene {
    w: u32,
    h: u32,
    bg: Bg,
    shapes: Vec<Shape>,
    /// Shapes whose pixels count as the object in the truth.
    truth_shapes: usize,
}

/// Renders RGB8 with 3×3 supersampling and sensor noise; the truth is the pixel centre's cover.
fn render(scene: &Scene, seed: u64) -> (RgbImage, Vec<bool>) {
    let mut rng = Rng(seed);
    let (w, h) = (scene.w, scene.h);
    let s = h as f32;
    let mut img = RgbImage::new(w, h);
    let mut truth = vec![false; (w * h) as usize];
    let hit = |x: f32, y: f32, k: usize| scene.shapes[..k].iter().find_map(|sh| sh.shade(x, y));
    for py in 0..h {
        for px in 0..w {
            let mut acc = [0.0f32; 3];
            for sy in 0..3 {
                for sx in 0..3 {
                    let x = (px as f32 + (sx as f32 + 0.5) / 3.0) / s;
                    let y = (py as f32 + (sy as f32 + 0.5) / 3.0) / s;
                    let c = hit(x, y, scene.shapes.len())
                        .unwrap_or_else(|| background(scene.bg, x * s / w as f32, y, &mut rng));
                    for k in 0..3 {
                        acc[k] += c[k] / 9.0;
                    }
                }
            }
            let n = 0.012 * rng.gauss();
            let p = acc.map(|v| {
                ((v + n + 0.004 * rng.gauss()) * 255.0)
                    .round()
                    .clamp(0.0, 255.0) as u8
            });
            img.put_pixel(px, py, image::Rgb(p));
            let (cx, cy) = ((px as f32 + 0.5) / s, (py as f32 + 0.5) / s);
            truth[(py * w + px) as usize] = hit(cx, cy, scene.truth_shapes).is_some();
        }
    }
    (img, truth)
}

fn jpeg(img: &RgbImage, quality: u8) -> Vec<u8> {
    let mut out = Vec::new();
    JpegEncoder::new_with_quality(&mut out, quality)
        .write_image(
            img.as_raw(),
            img.width(),
            img.height(),
            ExtendedColorType::Rgb8,
        )
        .unwrap();
    out
}

fn png(bytes: &[u8], w: u32, h: u32, t: ExtendedColorType) -> Vec<u8> {
    let mut out = Vec::new();
    PngEncoder::new(&mut out)
        .write_image(bytes, w, h, t)
        .unwrap();
    out
}

fn cup_scene(bg: Bg) -> Scene {
    Scene {
        w: 360,
        h: 270,
        bg,
        shapes: vec![Shape::Cup(CUP)],
        truth_shapes: 1,
    }
}

fn object_of(seg: &Segmentation) -> Vec<bool> {
    seg.object.values().iter().map(|&v| v >= 0.5).collect()
}

fn iou(a: &[bool], b: &[bool]) -> f64 {
    assert_eq!(a.len(), b.len());
    let inter = a.iter().zip(b).filter(|(x, y)| **x && **y).count();
    let union = a.iter().zip(b).filter(|(x, y)| **x || **y).count();
    inter as f64 / union.max(1) as f64
}

// ---------------------------------------------------------------- automatic mode

fn check_auto(bg: Bg, min_iou: f64) {
    let scene = cup_scene(bg);
    let (img, truth) = render(&scene, 11);
    let photo = Photo::decode(&jpeg(&img, 85), WORKING_SIDE).unwrap();
    let seg = segment_auto(&photo).unwrap();
    if let Ok(dir) = std::env::var("PROCFIT_SEGMENT_DEBUG_DIR") {
        // Look at what was segmented: the input and the mask (grey = don't care).
        img.save(format!("{dir}/auto_{bg:?}.png")).unwrap();
        let m = png(
            &seg.mask.to_luma8(),
            scene.w,
            scene.h,
            ExtendedColorType::L8,
        );
        std::fs::write(format!("{dir}/auto_{bg:?}_mask.png"), m).unwrap();
    }
    // The fit takes the cut as it is: no don't-care band along the outline (it cost accuracy
    // on the independent building and dish photo benchmarks).
    assert_eq!(seg.mask, seg.object, "{bg:?}: the fit's mask is the cut");
    let got = object_of(&seg);
    let score = iou(&got, &truth);
    eprintln!(
        "{bg:?}: IoU {score:.4}, confidence {:.3}, warnings {:?}",
        seg.confidence, seg.warnings
    );
    assert!(
        score >= min_iou,
        "{bg:?}: IoU {score:.4} < {min_iou}; warnings {:?}",
        seg.warnings
    );
    assert!(
        !seg.is_low_confidence(),
        "{bg:?}: {:?} {}",
        seg.warnings,
        seg.confidence
    );
    // The handle's loop is a real hole: it shows the background and must stay open.
    let (c, _, _) = CUP.handle();
    let s = scene.h as f32;
    let hole = (c[1] * s) as usize * scene.w as usize + ((c[0] + 0.02) * s) as usize;
    assert!(
        !truth[hole] && !got[hole],
        "{bg:?}: the handle's loop was filled"
    );
    let b = seg.bbox.unwrap();
    let tb = bbox(&truth, scene.w as usize);
    for (g, t) in [(b.x0, tb.x0), (b.y0, tb.y0), (b.x1, tb.x1), (b.y1, tb.y1)] {
        assert!(g.abs_diff(t) <= 2, "{bg:?}: bbox {b:?} vs truth {tb:?}");
    }
}

fn bbox(m: &[bool], w: usize) -> BBox {
    let mut b = BBox {
        x0: u32::MAX,
        y0: u32::MAX,
        x1: 0,
        y1: 0,
    };
    for (i, _) in m.iter().enumerate().filter(|(_, v)| **v) {
        let (x, y) = ((i % w) as u32, (i / w) as u32);
        b.x0 = b.x0.min(x);
        b.y0 = b.y0.min(y);
        b.x1 = b.x1.max(x + 1);
        b.y1 = b.y1.max(y + 1);
    }
    b
}

#[test]
fn auto_plain() {
    check_auto(Bg::Plain, 0.97);
}
#[test]
fn auto_gradient() {
    check_auto(Bg::Gradient, 0.97);
}
#[test]
fn auto_noisy() {
    check_auto(Bg::Noisy, 0.95);
}
#[test]
fn auto_textured() {
    check_auto(Bg::Textured, 0.92);
}
#[test]
fn auto_cells() {
    check_auto(Bg::Cells, 0.92);
}
#[test]
fn auto_table() {
    check_auto(Bg::Table, 0.95);
}
/// A wall lit warm from the left and cool from the right, darker towards the top, differs on
/// every side of the border, so no side's colours are explained by the others'. The automatic
/// segmentation took all four sides for an object running off the frame and had no background
/// left: "cannot build colour models" (an error, no mask). Now the frame check, which finds
/// nothing running off any side, keeps them background: the cup is found (IoU 0.943) and not
/// flagged. Its handle's loop is filled: the loop shows a colour of the wall that the border
/// does not have, and the hole test asks the border (asking the wall around the hole instead
/// opened the coffee in `coffee_photo_smoke_test`'s cup).
#[test]
fn a_wall_lit_unevenly_on_every_side_still_gives_a_mask() {
    let scene = cup_scene(Bg::LitWall);
    let (img, truth) = render(&scene, 11);
    let photo = Photo::decode(&jpeg(&img, 85), WORKING_SIDE).unwrap();
    let seg = segment_auto(&photo).expect("a cup on an unevenly lit wall gives a mask");
    let score = iou(&object_of(&seg), &truth);
    eprintln!(
        "lit wall: IoU {score:.4}, confidence {:.3}, warnings {:?}",
        seg.confidence, seg.warnings
    );
    assert!(score >= 0.93, "IoU {score:.4}");
    assert!(!seg.is_low_confidence(), "{:?}", seg.warnings);
}

/// An outline smoothing outside (0, 1] is refused with a message, not a panic or a mask cut
/// without smoothness.
#[test]
fn an_outline_smoothing_out_of_range_is_refused() {
    let (img, _) = render(&cup_scene(Bg::Plain), 3);
    let photo = Photo::decode(&jpeg(&img, 90), WORKING_SIDE).unwrap();
    for v in [0.0, -0.5, 1.5, f32::NAN, f32::INFINITY] {
        let opts = Options {
            outline_smoothing: v,
            ..Options::default()
        };
        let err = Session::automatic(&photo, &opts)
            .err()
            .unwrap_or_else(|| panic!("{v} accepted"));
        assert!(err.0.contains("outline smoothing"), "{v}: {}", err.0);
    }
    let opts = Options {
        outline_smoothing: 1.0,
        ..Options::default()
    };
    assert!(Session::automatic(&photo, &opts).is_ok());
}

/// A grey cup (the espresso cup's colour) over [`Bg::Planks`].
fn planks_scene() -> Scene {
    Scene {
        w: 360,
        h: 270,
        bg: Bg::Planks,
        shapes: vec![Shape::Cup(Cup {
            albedo: [0.42, 0.40, 0.39],
            ..CUP
        })],
        truth_shapes: 1,
    }
}

/// The mask check (`plausible`) judges a mask by the photo around it, not by the colour models
/// that made it: on [`Bg::Planks`] the true mask passes, and the mask the automatic
/// segmentation made before issue 16 — the cup, its shadow and a block of the plank under
/// it — is doubted, with a warning that says to correct it by hand.
#[test]
fn a_mask_that_took_in_table_and_shadow_is_doubted() {
    let scene = planks_scene();
    let (img, truth) = render(&scene, 16);
    let photo = Photo::decode(&jpeg(&img, 85), WORKING_SIDE).unwrap();
    let (w, h) = (scene.w as usize, scene.h as usize);
    let colors = photo.colors();
    let right = plausible::assess(&colors, &truth, w, h).unwrap();
    eprintln!("true mask: {right:?}");
    assert_eq!(plausible::doubt(&right), None, "{right:?}");
    // The old mistake: the cup plus the table from the left of its base down to the next
    // seam (y 0.7..0.92 of the height, x 0.3..0.75).
    let wrong: Vec<bool> = (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f32 / h as f32, (i / w) as f32 / h as f32);
            truth[i] || ((0.3..0.75).contains(&x) && (0.7..0.92).contains(&y))
        })
        .collect();
    let bad = plausible::assess(&colors, &wrong, w, h).unwrap();
    eprintln!("cup + table: {bad:?}");
    let warning = plausible::doubt(&bad).expect("a mask with table in it must be doubted");
    assert!(warning.contains("by hand"), "{warning}");
}

/// Issue 16: on a wooden table the automatic mask took in the contact shadow and a block of
/// plank (the first seed held the grain's dark streaks and the shadow, so the object's colour
/// model learnt the wood): IoU 0.79 with no warning before the fix, 0.99 after.
#[test]
fn auto_planks_with_a_shadow() {
    let scene = planks_scene();
    let (img, truth) = render(&scene, 16);
    let photo = Photo::decode(&jpeg(&img, 85), WORKING_SIDE).unwrap();
    let seg = segment_auto(&photo).unwrap();
    if let Ok(dir) = std::env::var("PROCFIT_SEGMENT_DEBUG_DIR") {
        img.save(format!("{dir}/auto_planks.png")).unwrap();
        let m = png(
            &seg.mask.to_luma8(),
            scene.w,
            scene.h,
            ExtendedColorType::L8,
        );
        std::fs::write(format!("{dir}/auto_planks_mask.png"), m).unwrap();
    }
    let got = object_of(&seg);
    let score = iou(&got, &truth);
    let extra = got.iter().zip(&truth).filter(|(g, t)| **g && !**t).count() as f64
        / truth.iter().filter(|&&t| t).count() as f64;
    eprintln!(
        "planks: IoU {score:.4}, extra {:.1} %, warnings {:?}",
        100.0 * extra,
        seg.warnings
    );
    assert!(score >= 0.95, "planks: IoU {score:.4}, extra {extra:.3}");
    assert!(!seg.is_low_confidence(), "{:?}", seg.warnings);
}

// ---------------------------------------------------------------- EXIF orientation

/// Inserts a minimal big-endian EXIF APP1 segment with one Orientation (0x0112) entry.
fn with_exif_orientation(jpeg: &[u8], orientation: u16) -> Vec<u8> {
    let mut app1 = b"Exif\0\0MM\0\x2a\0\0\0\x08".to_vec();
    app1.extend(1u16.to_be_bytes());
    app1.extend(0x0112u16.to_be_bytes());
    app1.extend(3u16.to_be_bytes());
    app1.extend(1u32.to_be_bytes());
    app1.extend(orientation.to_be_bytes());
    app1.extend([0, 0]);
    app1.extend(0u32.to_be_bytes());
    let mut out = jpeg[..2].to_vec();
    out.extend([0xFF, 0xE1]);
    out.extend(((app1.len() + 2) as u16).to_be_bytes());
    out.extend(app1);
    out.extend(&jpeg[2..]);
    out
}

#[test]
fn exif_orientations_give_the_same_mask() {
    let scene = cup_scene(Bg::Gradient);
    let (upright, truth) = render(&scene, 5);
    let mut reference: Option<Vec<bool>> = None;
    for o in 1..=8u8 {
        // Store the pixels so that applying orientation `o` brings them upright again.
        let inverse = match o {
            6 => 8,
            8 => 6,
            other => other,
        };
        let mut stored = DynamicImage::ImageRgb8(upright.clone());
        stored.apply_orientation(Orientation::from_exif(inverse).unwrap());
        let bytes = with_exif_orientation(&jpeg(&stored.to_rgb8(), 90), u16::from(o));
        let photo = Photo::decode(&bytes, WORKING_SIDE).unwrap();
        assert_eq!(
            (photo.width(), photo.height()),
            (scene.w, scene.h),
            "orientation {o}"
        );
        assert_eq!(photo.source_size(), (scene.w, scene.h), "orientation {o}");
        let got = object_of(&segment_auto(&photo).unwrap());
        assert!(
            iou(&got, &truth) >= 0.97,
            "orientation {o}: {}",
            iou(&got, &truth)
        );
        match &reference {
            None => reference = Some(got),
            Some(r) => assert!(iou(&got, r) >= 0.98, "orientation {o}: {}", iou(&got, r)),
        }
    }
}

// ---------------------------------------------------------------- interactive

#[test]
fn background_stroke_removes_a_wrongly_included_saucer() {
    let saucer = [0.15, 0.3, 0.75];
    let scene = Scene {
        w: 360,
        h: 270,
        bg: Bg::Plain,
        shapes: vec![
            Shape::Cup(CUP),
            Shape::Ellipse([CUP.cx, CUP.bottom], [0.3, 0.05], saucer),
        ],
        truth_shapes: 1,
    };
    let (img, truth) = render(&scene, 3);
    let photo = Photo::decode(&jpeg(&img, 85), WORKING_SIDE).unwrap();
    let mut session = Session::automatic(&photo, &Options::default()).unwrap();
    let before = iou(&object_of(session.segmentation()), &truth);
    assert!(
        before < 0.9,
        "the saucer should be included at first: IoU {before}"
    );
    let s = scene.h as f32;
    let y = CUP.bottom * s;
    session
        .add_stroke(&Stroke {
            label: Label::Background,
            points: vec![[(CUP.cx - 0.27) * s, y], [(CUP.cx - 0.2) * s, y + 3.0]],
            radius: 3.0,
        })
        .unwrap();
    let after = iou(&object_of(session.recut().unwrap()), &truth);
    eprintln!("saucer: IoU {before:.4} before the stroke, {after:.4} after");
    assert!(
        after >= 0.95,
        "after the stroke: IoU {after} (before {before})"
    );
}

#[test]
fn object_stroke_keeps_a_part_cut_off_by_a_background_coloured_band() {
    // A wall-coloured band around the cup's foot splits it in two: automatic mode keeps the
    // larger upper part only; an object stroke on the foot brings it back.
    let y0 = 0.62;
    let band = Shape::Rect([0.3, y0, 0.95, y0 + 0.04], [0.86, 0.86, 0.83]);
    let scene = Scene {
        w: 360,
        h: 270,
        bg: Bg::Plain,
        shapes: vec![band, Shape::Cup(CUP)],
        truth_shapes: 2,
    };
    let (img, truth) = render(&scene, 21);
    let s = scene.h as f32;
    let foot: Vec<usize> = (0..truth.len())
        .filter(|&i| truth[i] && (i / scene.w as usize) as f32 > (y0 + 0.05) * s)
        .collect();
    let kept = |seg: &Segmentation| {
        let o = object_of(seg);
        foot.iter().filter(|&&i| o[i]).count() as f64 / foot.len() as f64
    };
    let photo = Photo::decode(&jpeg(&img, 85), WORKING_SIDE).unwrap();
    let mut session = Session::automatic(&photo, &Options::default()).unwrap();
    let before = kept(session.segmentation());
    assert!(before < 0.05, "the foot should be lost at first: {before}");
    session
        .add_stroke(&Stroke {
            label: Label::Object,
            points: vec![[CUP.cx * s, (CUP.bottom - 0.05) * s]],
            radius: 3.0,
        })
        .unwrap();
    let after = kept(session.recut().unwrap());
    eprintln!("foot: {before:.3} kept before the stroke, {after:.3} after");
    assert!(after >= 0.97, "after the stroke the foot is {after} kept");
}

/// Touch-up strokes straddling the outline (half on the cup, half on the wall) fix their own
/// pixels and must not take their colours out of either model: a background stroke that
/// half covers the cup would otherwise remove the cup's red from the object model.
#[test]
fn sloppy_strokes_across_the_outline_keep_the_mask() {
    check_sloppy(Label::Object);
    check_sloppy(Label::Background);
}

fn check_sloppy(label: Label) {
    let scene = cup_scene(Bg::Gradient);
    let (img, truth) = render(&scene, 17);
    let photo = Photo::decode(&jpeg(&img, 85), WORKING_SIDE).unwrap();
    let mut session = Session::automatic(&photo, &Options::default()).unwrap();
    let s = scene.h as f32;
    let edge = CUP.cx - CUP.radius(0.3).unwrap();
    session
        .add_stroke(&Stroke {
            label,
            points: vec![[(edge - 0.04) * s, 0.3 * s], [(edge + 0.04) * s, 0.3 * s]],
            radius: 6.0,
        })
        .unwrap();
    let score = iou(&object_of(session.recut().unwrap()), &truth);
    eprintln!("sloppy {label:?} stroke: IoU {score:.4}");
    assert!(score >= 0.97, "IoU {score} after a sloppy {label:?} stroke");
}

#[test]
fn rectangle_selects_the_smaller_of_two_objects() {
    let small = Cup {
        cx: 1.0,
        top: 0.35,
        bottom: 0.75,
        r_top: 0.12,
        r_bottom: 0.09,
        albedo: [0.2, 0.6, 0.25],
    };
    let big = Cup {
        cx: 0.33,
        r_top: 0.15,
        r_bottom: 0.12,
        ..CUP
    };
    let scene = Scene {
        w: 360,
        h: 270,
        bg: Bg::Gradient,
        shapes: vec![Shape::Cup(small), Shape::Cup(big)],
        truth_shapes: 1,
    };
    let (img, truth) = render(&scene, 8);
    let photo = Photo::decode(&jpeg(&img, 85), WORKING_SIDE).unwrap();
    let auto = object_of(&segment_auto(&photo).unwrap());
    assert!(
        iou(&auto, &truth) < 0.5,
        "automatic mode keeps the larger cup"
    );
    let rect = BBox {
        x0: 230,
        y0: 75,
        x1: 355,
        y1: 215,
    };
    let session = Session::with_rect(&photo, rect, &Options::default()).unwrap();
    let score = iou(&object_of(session.segmentation()), &truth);
    assert!(score >= 0.95, "rectangle: IoU {score}");
}

// ---------------------------------------------------------------- other mask sources

#[test]
fn alpha_channel_gives_the_mask() {
    let (img, truth) = render(&cup_scene(Bg::Plain), 1);
    let mut rgba = RgbaImage::new(img.width(), img.height());
    for (i, (p, q)) in img.pixels().zip(rgba.pixels_mut()).enumerate() {
        *q = image::Rgba([p[0], p[1], p[2], if truth[i] { 255 } else { 0 }]);
    }
    let bytes = png(
        rgba.as_raw(),
        img.width(),
        img.height(),
        ExtendedColorType::Rgba8,
    );
    let photo = Photo::decode(&bytes, WORKING_SIDE).unwrap();
    let seg = segment_alpha(&photo).unwrap();
    assert_eq!(object_of(&seg), truth);
    assert_eq!(seg.mask, seg.object, "a hard alpha leaves nothing unsure");
    assert_eq!(
        segment(&photo).unwrap(),
        seg,
        "segment() prefers the alpha channel"
    );
    assert!(!seg.is_low_confidence());
    let opaque = Photo::decode(&jpeg(&img, 80), WORKING_SIDE).unwrap();
    assert!(
        segment_alpha(&opaque)
            .unwrap_err()
            .0
            .contains("no transparency")
    );
}

#[test]
fn user_mask_image_is_read_resampled_and_checked() {
    let (img, truth) = render(&cup_scene(Bg::Plain), 1);
    let (w, h) = (img.width(), img.height());
    let photo = Photo::decode(&jpeg(&img, 80), WORKING_SIDE).unwrap();
    // Same size, with a grey don't-care pixel: read back exactly.
    let mut luma: Vec<u8> = truth.iter().map(|&t| if t { 255 } else { 0 }).collect();
    luma[0] = 128;
    let seg = segment_mask_image(&photo, &png(&luma, w, h, ExtendedColorType::L8)).unwrap();
    let mut expected = truth.clone();
    expected[0] = true;
    assert_eq!(object_of(&seg), expected);
    assert_eq!(seg.mask.values()[0], Mask::DONT_CARE);
    // Twice the size (nearest-neighbour upscale): area-resampled back.
    let big: Vec<u8> = (0..4 * w * h)
        .map(|i| {
            let (x, y) = (i % (2 * w) / 2, i / (2 * w) / 2);
            if truth[(y * w + x) as usize] { 255 } else { 0 }
        })
        .collect();
    let seg = segment_mask_image(&photo, &png(&big, 2 * w, 2 * h, ExtendedColorType::L8)).unwrap();
    assert!(iou(&object_of(&seg), &truth) >= 0.99);
    let square = vec![0u8; (h * h) as usize];
    let err = segment_mask_image(&photo, &png(&square, h, h, ExtendedColorType::L8)).unwrap_err();
    assert!(err.0.contains("shapes differ"), "{err}");
}

#[test]
fn large_photo_is_downscaled_before_segmentation() {
    let mut scene = cup_scene(Bg::Gradient);
    (scene.w, scene.h) = (1600, 1200);
    let (img, _) = render(&scene, 2);
    let photo = Photo::decode(&jpeg(&img, 85), WORKING_SIDE).unwrap();
    assert_eq!((photo.width(), photo.height()), (512, 384));
    assert_eq!(photo.source_size(), (1600, 1200));
    // The browser path: raw RGBA of the same photo, downscaled the same way.
    let rgba = DynamicImage::ImageRgb8(img).to_rgba8();
    let raw = Photo::from_rgba(1600, 1200, rgba.as_raw(), WORKING_SIDE).unwrap();
    assert_eq!((raw.width(), raw.height()), (512, 384));
    (scene.w, scene.h) = (512, 384);
    let (_, truth) = render(&scene, 2);
    for p in [&photo, &raw] {
        let score = iou(&object_of(&segment(p).unwrap()), &truth);
        assert!(score >= 0.97, "IoU {score}");
    }
}

/// A large EXIF-rotated JPEG decoded at reduced DCT scale gives the same working image and mask
/// as decoding every pixel (issue 5's scaled decode).
fn check_scaled_decode(w: u32, h: u32, side: u32, orientation: u8) {
    let mut scene = cup_scene(Bg::Gradient);
    (scene.w, scene.h) = (w, h);
    let (upright, _) = render(&scene, 3);
    let inverse = match orientation {
        6 => 8,
        8 => 6,
        other => other,
    };
    let mut stored = DynamicImage::ImageRgb8(upright);
    stored.apply_orientation(Orientation::from_exif(inverse).unwrap());
    let bytes = with_exif_orientation(&jpeg(&stored.to_rgb8(), 85), u16::from(orientation));
    let fast = Photo::decode(&bytes, side).unwrap();
    let full = Photo::decode_full(&bytes, side).unwrap();
    let case = format!("{w}×{h} → {side}, orientation {orientation}");
    assert_eq!(
        (fast.width(), fast.height()),
        (full.width(), full.height()),
        "{case}"
    );
    assert_eq!(fast.source_size(), (w, h), "{case}");
    assert_eq!(full.source_size(), (w, h), "{case}");
    // Same pixels up to the DCT's rounding: mean absolute difference under 1.5 levels.
    let diff: u64 = fast
        .rgba()
        .iter()
        .zip(full.rgba())
        .map(|(a, b)| u64::from(a.abs_diff(*b)))
        .sum();
    let mean = diff as f64 / fast.rgba().len() as f64;
    assert!(mean < 1.5, "{case}: mean pixel difference {mean}");
    let a = object_of(&segment_auto(&fast).unwrap());
    let b = object_of(&segment_auto(&full).unwrap());
    let score = iou(&a, &b);
    assert!(score >= 0.99, "{case}: IoU {score}");
}

#[test]
fn scaled_jpeg_decode_gives_the_full_decode_mask() {
    check_scaled_decode(2048, 1536, 256, 6); // 1/8 scale, rotated
    check_scaled_decode(1280, 960, 256, 3); // 1/4 scale, upside down
    check_scaled_decode(1600, 1200, 512, 8); // 1/2 scale, rotated the other way
}

// ---------------------------------------------------------------- windows

fn facade() -> (Scene, Vec<[f32; 4]>) {
    let mut shapes = Vec::new();
    let mut windows = Vec::new();
    for row in 0..4 {
        for col in 0..3 {
            let x0 = 0.42 + col as f32 * 0.2;
            let y0 = 0.25 + row as f32 * 0.17;
            let r = [x0, y0, x0 + 0.1, y0 + 0.1];
            windows.push(r);
            shapes.push(Shape::Rect(r, [0.2, 0.24, 0.3]));
        }
    }
    shapes.push(Shape::Rect([0.32, 0.12, 1.05, 0.95], [0.86, 0.78, 0.64]));
    let n = shapes.len();
    (
        Scene {
            w: 360,
            h: 270,
            bg: Bg::Gradient,
            shapes,
            truth_shapes: n,
        },
        windows,
    )
}

#[test]
fn windows_detected_and_painted() {
    let (scene, windows) = facade();
    let (img, truth) = render(&scene, 4);
    let s = scene.h as f32;
    let win_truth: Vec<bool> = (0..scene.w * scene.h)
        .map(|i| {
            let (x, y) = (
                ((i % scene.w) as f32 + 0.5) / s,
                ((i / scene.w) as f32 + 0.5) / s,
            );
            windows
                .iter()
                .any(|r| x >= r[0] && x < r[2] && y >= r[1] && y < r[3])
        })
        .collect();
    let photo = Photo::decode(&jpeg(&img, 85), WORKING_SIDE).unwrap();
    let seg = segment_auto(&photo).unwrap();
    assert!(iou(&object_of(&seg), &truth) >= 0.97);
    let labels = detect_windows(&photo, &seg).unwrap();
    let got: Vec<bool> = labels.labels().iter().map(|&l| l == LABEL_WINDOW).collect();
    let score = iou(&got, &win_truth);
    eprintln!("windows: detected IoU {score:.4}");
    assert!(score >= 0.9, "detected windows: IoU {score}");
    // Strokes: two windows painted, one wall stroke.
    let centre = |r: [f32; 4]| [(r[0] + r[2]) / 2.0 * s, (r[1] + r[3]) / 2.0 * s];
    let strokes = [
        Stroke {
            label: Label::Object,
            points: vec![centre(windows[0])],
            radius: 4.0,
        },
        Stroke {
            label: Label::Object,
            points: vec![centre(windows[7])],
            radius: 4.0,
        },
        Stroke {
            label: Label::Background,
            points: vec![[0.37 * s, 0.3 * s], [0.37 * s, 0.8 * s]],
            radius: 2.0,
        },
    ];
    let labels = windows_from_strokes(&photo, &seg, &strokes).unwrap();
    let got: Vec<bool> = labels.labels().iter().map(|&l| l == LABEL_WINDOW).collect();
    let score = iou(&got, &win_truth);
    eprintln!("windows: painted IoU {score:.4}");
    assert!(score >= 0.95, "painted windows: IoU {score}");
}

#[test]
fn painted_windows_are_clipped_to_a_corrected_mask() {
    let (scene, _) = facade();
    let (img, _) = render(&scene, 4);
    let photo = Photo::decode(&jpeg(&img, 85), WORKING_SIDE).unwrap();
    let whole = segment_auto(&photo).unwrap();
    let before = detect_windows(&photo, &whole).unwrap();
    let windows =
        |l: &procfit::mask::LabelImage| l.labels().iter().filter(|&&v| v == LABEL_WINDOW).count();
    // The mask corrected to a box around the left two window columns only.
    let s = photo.height() as f32 / scene.h as f32;
    let rect = BBox {
        x0: (80.0 * s) as u32,
        y0: (25.0 * s) as u32,
        x1: (205.0 * s) as u32,
        y1: (262.0 * s) as u32,
    };
    let session = Session::with_rect(&photo, rect, &Options::default()).unwrap();
    let seg = session.segmentation();
    let after = clip_windows(seg, &before).unwrap();
    let obj: Vec<bool> = seg.object.values().iter().map(|&v| v >= 0.5).collect();
    let (mut outside, mut kept, mut lost) = (0, 0, 0);
    for (i, (&b, &a)) in before.labels().iter().zip(after.labels()).enumerate() {
        let band = seg.mask.values()[i] == Mask::DONT_CARE;
        if a == LABEL_WINDOW && !obj[i] {
            outside += 1;
        }
        if b == LABEL_WINDOW && obj[i] && !band {
            if a == LABEL_WINDOW {
                kept += 1
            } else {
                lost += 1
            }
        }
        // Outside the new object nothing but background (or the outline band) is left.
        assert!(
            obj[i] || band || a == LABEL_BACKGROUND,
            "pixel {i}: label {a} outside the object"
        );
    }
    eprintln!(
        "windows: {} before, {} after the box, {kept} kept",
        windows(&before),
        windows(&after)
    );
    assert_eq!(outside, 0, "window pixels outside the corrected mask");
    assert_eq!(lost, 0, "windows inside the corrected mask were dropped");
    // The right window column is gone, the two left ones stay.
    assert!(
        kept > 0 && windows(&after) < windows(&before) * 3 / 4,
        "{} of {}",
        windows(&after),
        windows(&before)
    );
    // Labels for another mask size are refused.
    let small = procfit::mask::LabelImage::new(4, 4, vec![LABEL_WINDOW; 16]).unwrap();
    assert!(clip_windows(seg, &small).is_err());
}

// ---------------------------------------------------------------- bad input

fn crc32(bytes: &[u8]) -> u32 {
    let mut c = !0u32;
    for &b in bytes {
        c ^= u32::from(b);
        for _ in 0..8 {
            c = if c & 1 != 0 {
                0xEDB8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
        }
    }
    !c
}

/// A valid PNG whose header is rewritten to claim `w`×`h` (with a correct CRC).
fn png_claiming(w: u32, h: u32) -> Vec<u8> {
    let mut p = png(&[0u8; 64 * 3], 8, 8, ExtendedColorType::Rgb8);
    p[16..20].copy_from_slice(&w.to_be_bytes());
    p[20..24].copy_from_slice(&h.to_be_bytes());
    let crc = crc32(&p[12..29]);
    p[29..33].copy_from_slice(&crc.to_be_bytes());
    p
}

fn check_refused(bytes: &[u8], expected: &str) {
    let err = Photo::decode(bytes, WORKING_SIDE).unwrap_err();
    assert!(
        err.0.contains(expected),
        "expected an error containing {expected:?}, got {err}"
    );
}

#[test]
fn bad_files_are_refused_with_a_message() {
    check_refused(b"", "empty");
    check_refused(
        b"hello, this is not an image at all",
        "not a recognised image",
    );
    check_refused(b"GIF89a\x01\x00\x01\x00\x00\x00\x00;", "cannot decode");
    check_refused(&png(&[0, 0, 0], 1, 1, ExtendedColorType::Rgb8), "too small");
    check_refused(&png_claiming(0, 64), "cannot decode");
    check_refused(&png_claiming(20_000, 20_000), "decompression bomb");
    // Refused from its header, before any pixel is decoded, saying which limit.
    check_refused(
        &png_claiming(40_000, 100),
        "a side exceeds the 30000 pixel limit",
    );
    assert!(
        Photo::from_rgba(10, 10, &[0; 399], WORKING_SIDE)
            .unwrap_err()
            .0
            .contains("expected 400")
    );
    assert!(Photo::from_rgba(0, 10, &[], WORKING_SIDE).is_err());
    assert!(Photo::from_rgba(10, 10, &[0; 400], 0).is_err());
}

/// Issue 19: a truncated JPEG was decoded (missing rows grey) and fitted without a word; it is
/// now always a one-line error, whatever the point of truncation.
#[test]
fn truncated_jpeg_is_always_a_one_line_error() {
    let (img, _) = render(&cup_scene(Bg::Plain), 9);
    let bytes = jpeg(&img, 85);
    assert!(Photo::decode(&bytes, WORKING_SIDE).is_ok());
    for keep in [20, 200, bytes.len() / 3, bytes.len() / 2, bytes.len() - 10] {
        for decode in [Photo::decode, Photo::decode_full] {
            let e = decode(&bytes[..keep], WORKING_SIDE)
                .err()
                .unwrap_or_else(|| panic!("{keep} bytes: a truncated JPEG was accepted"));
            assert!(
                e.0.contains("truncated") || e.0.contains("cannot"),
                "{keep} bytes: {e}"
            );
            assert_eq!(e.0.lines().count(), 1, "{keep} bytes: {e}");
        }
    }
}

#[test]
fn sixteen_bit_png_segments_like_eight_bit() {
    let (img, truth) = render(&cup_scene(Bg::Gradient), 6);
    let wide: Vec<u8> = img
        .as_raw()
        .iter()
        .flat_map(|&v| (u16::from(v) * 257).to_be_bytes())
        .collect();
    let bytes = png(&wide, img.width(), img.height(), ExtendedColorType::Rgb16);
    let photo = Photo::decode(&bytes, WORKING_SIDE).unwrap();
    let score = iou(&object_of(&segment_auto(&photo).unwrap()), &truth);
    assert!(score >= 0.97, "IoU {score}");
}

#[test]
fn uniform_image_gives_a_flagged_empty_mask() {
    let img = RgbImage::from_pixel(200, 150, image::Rgb([120, 130, 140]));
    let photo = Photo::decode(&jpeg(&img, 90), WORKING_SIDE).unwrap();
    let seg = segment_auto(&photo).unwrap();
    assert!(seg.is_low_confidence());
    assert!(
        seg.object.area() < 0.002 * 200.0 * 150.0,
        "{}",
        seg.object.area()
    );
    assert!(
        seg.warnings
            .iter()
            .any(|w| w.contains("no distinct object")),
        "{:?}",
        seg.warnings
    );
}

/// A cup larger than the frame: it fills the photo and runs off every edge.
const HUGE: Cup = Cup {
    cx: 0.62,
    top: -0.4,
    bottom: 1.4,
    r_top: 0.85,
    r_bottom: 0.8,
    ..CUP
};

#[test]
fn object_filling_the_frame_is_flagged() {
    let scene = Scene {
        shapes: vec![Shape::Cup(HUGE)],
        ..cup_scene(Bg::Plain)
    };
    let (img, _) = render(&scene, 12);
    let photo = Photo::decode(&jpeg(&img, 85), WORKING_SIDE).unwrap();
    let seg = segment_auto(&photo).unwrap();
    eprintln!(
        "frame-filling cup: {:?}, confidence {}",
        seg.warnings, seg.confidence
    );
    assert!(
        seg.is_low_confidence(),
        "{:?} {}",
        seg.warnings,
        seg.confidence
    );
}

#[test]
fn bad_strokes_and_rectangles_are_refused() {
    let (img, _) = render(&cup_scene(Bg::Plain), 1);
    let photo = Photo::decode(&jpeg(&img, 80), WORKING_SIDE).unwrap();
    let mut s = Session::automatic(&photo, &Options::default()).unwrap();
    let stroke = |points: Vec<[f32; 2]>, radius: f32| Stroke {
        label: Label::Background,
        points,
        radius,
    };
    assert!(s.add_stroke(&stroke(vec![[f32::NAN, 1.0]], 2.0)).is_err());
    assert!(s.add_stroke(&stroke(vec![], 2.0)).is_err());
    assert!(s.add_stroke(&stroke(vec![[1.0, 1.0]], 0.0)).is_err());
    // Off-image strokes are clipped, not refused; clearing them restores the automatic mask.
    let initial = object_of(s.segmentation());
    let diagonal = stroke(vec![[-50.0, -50.0], [1e6, 1e6]], 3.0);
    assert!(s.add_stroke(&diagonal).is_ok());
    let stroked = object_of(s.recut().unwrap());
    assert!(
        iou(&stroked, &initial) < 0.99,
        "the diagonal stroke cuts the cup"
    );
    s.clear_strokes();
    let cleared = object_of(s.recut().unwrap());
    assert!(iou(&cleared, &initial) > 0.995);
    let bad = BBox {
        x0: 10,
        y0: 10,
        x1: 10,
        y1: 20,
    };
    assert!(s.set_rect(bad).is_err());
    let outside = BBox {
        x0: 0,
        y0: 0,
        x1: 1000,
        y1: 20,
    };
    assert!(Session::with_rect(&photo, outside, &Options::default()).is_err());
}

// ---------------------------------------------------------------- a real photograph

/// scikit-image's `coffee.png` (CC0, see tests/data/LICENSES.md): an espresso cup with a
/// spoon on a red-brown saucer, on a wooden table of similar colour, seen from above; the
/// saucer touches the bottom border. Expectations (hand-measured on the working image, 512×341):
/// the cup, saucer and spoon are object, the table's corners are not, the box is the saucer's
/// within a tolerance, and the area is that of the saucer plus the cup's rim (about 0.46 of the
/// frame) within ±0.1 — some wood next to the saucer is included, since its colour is close.
#[test]
fn coffee_photo_smoke_test() {
    let bytes = std::fs::read(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/coffee.png"
    ))
    .unwrap();
    let photo = Photo::decode(&bytes, WORKING_SIDE).unwrap();
    assert_eq!((photo.width(), photo.height()), (512, 341));
    let seg = segment_auto(&photo).unwrap();
    let obj = object_of(&seg);
    let at = |x: f32, y: f32| obj[(y * 341.0) as usize * 512 + (x * 512.0) as usize];
    let area = obj.iter().filter(|&&o| o).count() as f32 / obj.len() as f32;
    eprintln!(
        "coffee: area {area:.3}, bbox {:?}, confidence {:.3}, warnings {:?}",
        seg.bbox, seg.confidence, seg.warnings
    );
    for (name, x, y) in [
        ("coffee", 0.48, 0.37),
        ("saucer", 0.2, 0.62),
        ("spoon", 0.61, 0.71),
    ] {
        assert!(at(x, y), "{name} should be object");
    }
    for (x, y) in [
        (0.02, 0.02),
        (0.98, 0.02),
        (0.98, 0.5),
        (0.02, 0.95),
        (0.9, 0.95),
    ] {
        assert!(!at(x, y), "table at ({x}, {y}) should be background");
    }
    assert!((0.36..=0.56).contains(&area), "area {area}");
    let b = seg.bbox.unwrap();
    for (got, want, tol) in [
        (b.x0, 66, 15),
        (b.x1, 410, 15),
        (b.y0, 15, 10),
        (b.y1, 341, 10),
    ] {
        assert!(got.abs_diff(want) <= tol, "bbox {b:?}");
    }
}

// ---------------------------------------------------------------- tidy

/// `std::time::Instant` panics on wasm32: segmentation code must never read a clock.
#[test]
fn segmentation_code_reads_no_clock() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/src/segment");
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let text = std::fs::read_to_string(&path).unwrap();
        for (n, line) in text.lines().enumerate() {
            let code = line.split("//").next().unwrap_or("");
            assert!(
                !code.contains("Instant") && !code.contains("SystemTime"),
                "{}:{}: {line}",
                path.display(),
                n + 1
            );
        }
    }
}

/// A hand-made 16×16 baseline JPEG with four components (Adobe CMYK, no transform), each
/// uniform: only DC coefficients, standard luminance DC table, a one-code AC table (EOB).
fn cmyk_jpeg(cmyk: [u8; 4]) -> Vec<u8> {
    let mut j = vec![0xFF, 0xD8];
    // APP14 "Adobe", version 100, flags 0, transform 0 (CMYK as is).
    j.extend([0xFF, 0xEE, 0, 14]);
    j.extend(b"Adobe");
    j.extend([0, 100, 0, 0, 0, 0, 0]);
    // One quantisation table of ones.
    j.extend([0xFF, 0xDB, 0, 67, 0]);
    j.extend([1u8; 64]);
    // SOF0: 8-bit, 16×16, four components, no subsampling, table 0.
    j.extend([0xFF, 0xC0, 0, 20, 8, 0, 16, 0, 16, 4]);
    for id in 1..=4 {
        j.extend([id, 0x11, 0]);
    }
    // DC table 0 (standard luminance) and AC table 0 holding only EOB as the code "0".
    let dc_bits = [0u8, 1, 5, 1, 1, 1, 1, 1, 1, 0, 0, 0, 0, 0, 0, 0];
    j.extend([0xFF, 0xC4, 0, 2 + 17 + 12, 0x00]);
    j.extend(dc_bits);
    j.extend(0u8..12);
    j.extend([0xFF, 0xC4, 0, 2 + 17 + 1, 0x10, 1]);
    j.extend([0u8; 15]);
    j.push(0);
    // SOS over the four components.
    j.extend([0xFF, 0xDA, 0, 14, 4]);
    for id in 1..=4 {
        j.extend([id, 0x00]);
    }
    j.extend([0, 63, 0]);
    // Standard DC luminance codes per category (code, length).
    let dc_code = |cat: u32| -> (u32, u32) {
        match cat {
            0 => (0b00, 2),
            1 => (0b010, 3),
            2 => (0b011, 3),
            3 => (0b100, 3),
            4 => (0b101, 3),
            5 => (0b110, 3),
            c => ((1 << (c - 2)) - 2, c - 2),
        }
    };
    let mut bits: Vec<bool> = Vec::new();
    let put = |v: u32, n: u32, bits: &mut Vec<bool>| {
        for k in (0..n).rev() {
            bits.push(v >> k & 1 == 1);
        }
    };
    for mcu in 0..4 {
        for &c in &cmyk {
            let diff = if mcu == 0 {
                8 * (i32::from(c) - 128)
            } else {
                0
            };
            let cat = 32 - diff.unsigned_abs().leading_zeros();
            let (code, len) = dc_code(cat);
            put(code, len, &mut bits);
            let extra = if diff < 0 { diff - 1 } else { diff } as u32 & ((1 << cat) - 1);
            put(extra, cat, &mut bits);
            put(0, 1, &mut bits); // EOB
        }
    }
    while !bits.len().is_multiple_of(8) {
        bits.push(true);
    }
    for byte in bits.chunks(8) {
        let b = byte.iter().fold(0u8, |a, &x| a << 1 | u8::from(x));
        j.push(b);
        if b == 0xFF {
            j.push(0);
        }
    }
    j.extend([0xFF, 0xD9]);
    j
}

/// CMYK JPEGs (Adobe's inverted convention, as Photoshop writes them) decode to RGB
/// `(c·k, m·k, y·k) / 255` of the stored values.
#[test]
fn cmyk_jpeg_decodes_to_rgb() {
    let cmyk = [20u8, 200, 180, 250];
    let photo = Photo::decode(&cmyk_jpeg(cmyk), WORKING_SIDE).unwrap();
    assert_eq!((photo.width(), photo.height()), (16, 16));
    let k = f32::from(cmyk[3]) / 255.0;
    let want = [0, 1, 2].map(|c| f32::from(cmyk[c]) * k);
    for p in photo.rgba().chunks_exact(4) {
        for c in 0..3 {
            assert!(
                (f32::from(p[c]) - want[c]).abs() <= 2.0,
                "{p:?} vs {want:?}"
            );
        }
    }
    // A uniform photo has no object: flagged, not a panic.
    assert!(segment_auto(&photo).unwrap().is_low_confidence());
}

// ---------------------------------------------------------------- confidence on a labelled set

/// One labelled case: a scene, what it stands for, and whether the mask is a fragment of a frame
/// the object fills (no outline to find: the user must box or paint it).
struct Labelled {
    name: String,
    scene: Scene,
}

/// Cups in the situations users photograph them in, over every background: whole and in the
/// middle, small in the frame, cut by the frame's edge, cropped to its own box (it fills the
/// frame), filling the frame, and next to a second object.
fn labelled_set() -> Vec<Labelled> {
    let bgs = [
        Bg::Plain,
        Bg::Gradient,
        Bg::Noisy,
        Bg::Textured,
        Bg::Table,
        Bg::Cells,
    ];
    let small = Cup {
        cx: 0.5,
        top: 0.45,
        bottom: 0.57,
        r_top: 0.045,
        r_bottom: 0.035,
        ..CUP
    };
    let cut = Cup { cx: 1.28, ..CUP };
    // The cup's box is x 0.42..0.95 (with the handle), y 0.22..0.78; cropped to it and scaled
    // to the frame's height, the body spans x 0..0.71 and the (unscaled) handle ends at 0.83.
    let cropped = Cup {
        cx: 0.20 / 0.56,
        top: 0.0,
        bottom: 1.0,
        r_top: 0.20 / 0.56,
        r_bottom: 0.15 / 0.56,
        ..CUP
    };
    let mut out = Vec::new();
    for bg in bgs {
        let scene = |shapes: Vec<Shape>, w: u32| Scene {
            w,
            h: 270,
            bg,
            shapes,
            truth_shapes: 1,
        };
        let box_ = Shape::Rect([0.08, 0.35, 0.3, 0.78], [0.2, 0.45, 0.25]);
        for (what, s) in [
            ("whole", scene(vec![Shape::Cup(CUP)], 360)),
            ("small", scene(vec![Shape::Cup(small)], 360)),
            ("cut by the frame", scene(vec![Shape::Cup(cut)], 360)),
            ("cropped to its box", scene(vec![Shape::Cup(cropped)], 223)),
            ("filling the frame", scene(vec![Shape::Cup(HUGE)], 360)),
            ("beside a box", scene(vec![Shape::Cup(CUP), box_], 360)),
        ] {
            out.push(Labelled {
                name: format!("{bg:?}, {what}"),
                scene: s,
            });
        }
    }
    out
}

/// The confidence means something: on the labelled set, every automatic mask that misses the
/// truth (IoU < 0.8) is flagged for the user to check (a warning, confidence < 0.5), and at
/// least 90 % of the good masks (IoU ≥ 0.9) are not — small objects (under 3 % of the frame)
/// aside, which are flagged by design, whatever the mask. The table is printed with
/// `--nocapture`.
#[test]
fn low_confidence_goes_with_a_poor_mask() {
    let mut good = (0, 0);
    let mut missed = Vec::new();
    for (k, case) in labelled_set().into_iter().enumerate() {
        let (img, truth) = render(&case.scene, 100 + k as u64);
        let photo = Photo::decode(&jpeg(&img, 85), WORKING_SIDE).unwrap();
        let seg = segment_auto(&photo).unwrap();
        let score = iou(&object_of(&seg), &truth);
        let flagged = seg.is_low_confidence();
        if case.name.ends_with("small") {
            assert!(flagged, "{}: a small mask must be flagged", case.name);
        }
        eprintln!(
            "{:40} IoU {score:.3}  confidence {:.2}  {}{}",
            case.name,
            seg.confidence,
            if flagged { "CHECK " } else { "" },
            seg.warnings.join(" | ")
        );
        if score < 0.8 && !flagged {
            missed.push(format!(
                "{} (IoU {score:.3}, {:.2})",
                case.name, seg.confidence
            ));
        }
        if score >= 0.9 && !case.name.ends_with("small") {
            good.0 += 1;
            good.1 += usize::from(!flagged);
        }
    }
    assert!(
        missed.is_empty(),
        "poor masks reported with confidence: {missed:?}"
    );
    assert!(
        good.1 * 10 >= good.0 * 9,
        "only {} of {} good masks are not flagged",
        good.1,
        good.0
    );
}

/// Issue 19: the bundled mug photo cropped to (just inside) its own box filled the frame and the
/// automatic mask was a sliver of the handle reported at 97 %. Now such a crop is flagged, while
/// the same photo with a margin of background is not.
#[test]
fn a_photo_cropped_to_its_object_is_flagged() {
    let bytes = std::fs::read(concat!(env!("CARGO_MANIFEST_DIR"), "/www/samples/mug.jpg")).unwrap();
    let photo = Photo::decode(&bytes, WORKING_SIDE).unwrap();
    let whole = segment_auto(&photo).unwrap();
    assert!(!whole.is_low_confidence(), "{:?}", whole.warnings);
    let b = whole.bbox.unwrap();
    let img = image::load_from_memory(&bytes).unwrap().to_rgb8();
    let k = img.width() as f32 / photo.width() as f32;
    for (margin, flagged) in [(-0.05f32, true), (0.0, true), (0.1, false), (0.3, false)] {
        let (bw, bh) = ((b.x1 - b.x0) as f32, (b.y1 - b.y0) as f32);
        let x0 = ((b.x0 as f32 - margin * bw) * k).max(0.0) as u32;
        let y0 = ((b.y0 as f32 - margin * bh) * k).max(0.0) as u32;
        let x1 = (((b.x1 as f32 + margin * bw) * k) as u32).min(img.width());
        let y1 = (((b.y1 as f32 + margin * bh) * k) as u32).min(img.height());
        let crop = image::imageops::crop_imm(&img, x0, y0, x1 - x0, y1 - y0).to_image();
        let cropped = Photo::decode(&jpeg(&crop, 90), WORKING_SIDE).unwrap();
        let seg = segment_auto(&cropped).unwrap();
        let area = seg.object.area() / f64::from(cropped.width() * cropped.height());
        eprintln!(
            "margin {margin}: area {area:.3}, confidence {:.2}, {:?}",
            seg.confidence, seg.warnings
        );
        assert_eq!(
            seg.is_low_confidence(),
            flagged,
            "margin {margin}: area {area:.3}, confidence {}, {:?}",
            seg.confidence,
            seg.warnings
        );
    }
}

#[test]
fn the_wall_brush_erases_windows_and_nothing_else() {
    use procfit::mask::LabelImage;
    use procfit::segment::windows::{LABEL_FACADE, erase_windows};
    // A 20×10 façade with two windows; a stroke over the left one only.
    let (w, h) = (20u32, 10u32);
    let mut l = vec![LABEL_FACADE; (w * h) as usize];
    for y in 3..7 {
        for x in (2..6).chain(12..16) {
            l[(y * w + x) as usize] = LABEL_WINDOW;
        }
    }
    l[0] = LABEL_BACKGROUND;
    l[1] = LabelImage::DONT_CARE;
    let labels = LabelImage::new(w, h, l.clone()).unwrap();
    let stroke = Stroke {
        label: Label::Background,
        points: vec![[1.0, 5.0], [7.0, 5.0]],
        radius: 3.0,
    };
    let out = erase_windows(&labels, &[stroke]).unwrap();
    let o = out.labels();
    for (i, (&before, &after)) in l.iter().zip(o).enumerate() {
        let x = i as u32 % w;
        if before == LABEL_WINDOW && x < 10 {
            assert_eq!(after, LABEL_FACADE, "pixel {i}: the left window stays");
        } else {
            assert_eq!(after, before, "pixel {i} changed");
        }
    }
    // Nothing to erase with no strokes; a bad stroke is an error.
    assert_eq!(erase_windows(&labels, &[]).unwrap(), labels);
    let bad = Stroke {
        label: Label::Background,
        points: vec![],
        radius: 3.0,
    };
    assert!(erase_windows(&labels, &[bad]).is_err());
}
