//! Benchmark workload shared by the native bench (`benches/segment.rs`) and the wasm bench page
//! (`bench.html`): a synthetic 12 MP photo, so both time exactly the same input.

use image::codecs::jpeg::JpegEncoder;
use image::{ExtendedColorType, ImageEncoder};

/// A 4000×3000 JPEG (quality 88): a shaded red cup with a handle on a gradient wall, with sensor noise.
pub fn synthetic_photo_jpeg() -> Vec<u8> {
    let (w, h) = (4000u32, 3000u32);
    let mut rgb = Vec::with_capacity((w * h * 3) as usize);
    let mut seed = 1u32;
    for y in 0..h {
        for x in 0..w {
            let (u, v) = (x as f32 / h as f32, y as f32 / h as f32);
            seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            let noise = ((seed >> 8) as f32 / (1u32 << 24) as f32 - 0.5) * 0.03;
            let r = 0.2 - 0.05 * (v - 0.22) / 0.56;
            let dx = (u - 0.66) / r;
            let (hx, hy) = (u - 0.66 - r - 0.02, v - 0.45);
            let d = (hx * hx + hy * hy).sqrt();
            let c = if (0.22..=0.78).contains(&v) && dx.abs() <= 1.0 {
                let l = (-0.55 * dx + 0.76 * (1.0 - dx * dx).sqrt()).max(0.0);
                [0.78, 0.18, 0.12].map(|a| a * (0.22 + 0.78 * l))
            } else if (0.075..=0.13).contains(&d) && hx > -0.02 {
                [0.5, 0.12, 0.08]
            } else {
                let t = 0.55 * v + 0.15 * u;
                [0.92 - 0.45 * t, 0.92 - 0.40 * t, 0.95 - 0.30 * t]
            };
            rgb.extend(c.map(|c| ((c + noise) * 255.0).clamp(0.0, 255.0) as u8));
        }
    }
    let mut out = Vec::new();
    // Encoding RGB8 of the right length into a Vec cannot fail; an empty result would fail the
    // benchmark loudly at decode.
    JpegEncoder::new_with_quality(&mut out, 88)
        .write_image(&rgb, w, h, ExtendedColorType::Rgb8)
        .map(|()| out)
        .unwrap_or_default()
}
