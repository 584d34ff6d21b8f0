//! The textures procfit makes itself (issue 17: "trees that look like trees"): a leaf-cluster
//! texture with an alpha cut-out for leaf cards, and a tiling bark texture for trunks and
//! branches. Both are drawn procedurally from fixed formulas (no files, no licence question),
//! encoded once per process as small PNGs and embedded in every GLB that has such parts.
//!
//! Both are near-neutral in colour: the material's `baseColorFactor` (the part's colour, from the
//! photo when it was measured) multiplies them, so the texture adds the shape and the grain and
//! the part colour stays what the user sees.

use std::sync::OnceLock;

/// Side of the square leaf-cluster texture, pixels.
pub const LEAF_SIDE: u32 = 128;
/// Width (around the stem) and height (along it) of the bark texture, pixels.
pub const BARK_SIZE: (u32, u32) = (64, 128);

/// Leaves drawn on one card: (centre u, centre v, angle of the midrib in radians, length,
/// width), in card units. Chosen by hand to fill the card like a small twig of leaves, with gaps
/// between them so the card reads as leaves, not as a square.
const LEAVES: [(f32, f32, f32, f32, f32); 9] = [
    (0.50, 0.30, 1.57, 0.42, 0.15),
    (0.30, 0.42, 2.30, 0.38, 0.14),
    (0.70, 0.42, 0.84, 0.38, 0.14),
    (0.22, 0.66, 2.70, 0.34, 0.12),
    (0.78, 0.66, 0.44, 0.34, 0.12),
    (0.50, 0.62, 1.57, 0.36, 0.14),
    (0.38, 0.82, 2.00, 0.30, 0.11),
    (0.62, 0.82, 1.14, 0.30, 0.11),
    (0.50, 0.12, 1.57, 0.22, 0.09),
];

/// The leaf-cluster texture as PNG bytes (RGBA, alpha 255 on a leaf and 0 between leaves).
pub fn leaf_png() -> &'static [u8] {
    static PNG: OnceLock<Vec<u8>> = OnceLock::new();
    PNG.get_or_init(|| png(&leaf_rgba(), LEAF_SIDE, LEAF_SIDE))
}

/// The bark texture as PNG bytes (RGB, tiles in both directions).
pub fn bark_png() -> &'static [u8] {
    static PNG: OnceLock<Vec<u8>> = OnceLock::new();
    PNG.get_or_init(|| png(&bark_rgba(), BARK_SIZE.0, BARK_SIZE.1))
}

/// RGBA pixels of the leaf texture, row-major from the top (glTF's UV origin).
pub fn leaf_rgba() -> Vec<u8> {
    let n = LEAF_SIDE as usize;
    let mut out = vec![0u8; 4 * n * n];
    for y in 0..n {
        for x in 0..n {
            let (u, v) = ((x as f32 + 0.5) / n as f32, (y as f32 + 0.5) / n as f32);
            // The top-most leaf drawn last wins.
            let mut hit = None;
            for (k, &(cu, cv, angle, len, width)) in LEAVES.iter().enumerate() {
                let (du, dv) = (u - cu, v - cv);
                let (c, s) = (angle.cos(), angle.sin());
                // Along the midrib from the leaf's base (s = 0) to its tip (s = 1); across it.
                let along = (du * c - dv * s) / len + 0.5;
                let across = (du * s + dv * c) / width;
                if !(0.0..=1.0).contains(&along) {
                    continue;
                }
                let half = (std::f32::consts::PI * along).sin().powf(0.7);
                if across.abs() <= half {
                    hit = Some((k, along, across / half.max(1e-3)));
                }
            }
            let Some((k, along, across)) = hit else {
                continue;
            };
            // Lighter towards the tip and the edges, a pale midrib, faint side veins, each leaf
            // a little warmer or cooler than the next.
            let mut l = 0.78 + 0.12 * along - 0.1 * (1.0 - across.abs());
            if across.abs() < 0.07 {
                l += 0.12;
            }
            let vein = ((along * 9.0 - across.abs() * 2.5) * std::f32::consts::TAU).cos();
            if vein > 0.93 {
                l += 0.06;
            }
            let tint = (k as f32 * 2.39).sin() * 0.06;
            let rgb = [l * (1.0 + tint), l, l * (1.0 - tint)];
            let i = 4 * (y * n + x);
            for (o, c) in out[i..i + 3].iter_mut().zip(rgb) {
                *o = (c.clamp(0.0, 1.0) * 255.0).round() as u8;
            }
            out[i + 3] = 255;
        }
    }
    out
}

/// RGBA pixels of the bark texture (opaque): vertical fissures that wander a little, ridges
/// between them, fine grain. Periodic in both directions (integer frequencies), so it tiles.
pub fn bark_rgba() -> Vec<u8> {
    let (w, h) = (BARK_SIZE.0 as usize, BARK_SIZE.1 as usize);
    let tau = std::f32::consts::TAU;
    let mut out = vec![255u8; 4 * w * h];
    for y in 0..h {
        for x in 0..w {
            let (u, v) = (x as f32 / w as f32, y as f32 / h as f32);
            let wander = 0.05 * (tau * 2.0 * v).sin() + 0.03 * (tau * (5.0 * v + 3.0 * u)).sin();
            let ridge = (tau * 5.0 * (u + wander)).sin().abs();
            let grain = hash(x as u32, y as u32) * 0.12;
            let l = 0.55 + 0.4 * ridge.powf(0.6) + grain;
            let i = 4 * (y * w + x);
            out[i] = (l.clamp(0.0, 1.0) * 255.0).round() as u8;
            out[i + 1] = (l.clamp(0.0, 1.0) * 250.0).round() as u8;
            out[i + 2] = (l.clamp(0.0, 1.0) * 242.0).round() as u8;
        }
    }
    out
}

/// A value in 0–1 from two integers (fixed, so the texture is the same in every file).
fn hash(x: u32, y: u32) -> f32 {
    let mut h = x.wrapping_mul(0x9E37_79B9) ^ y.wrapping_mul(0x85EB_CA6B);
    h ^= h >> 15;
    h = h.wrapping_mul(0x2C1B_3C6D);
    h ^= h >> 12;
    (h & 0xFFFF) as f32 / 65535.0
}

/// `rgba` (`w × h`) as PNG; an RGBA PNG when any pixel is not opaque, else RGB. Encoding a
/// buffer of the right length into memory cannot fail; should it, the result is empty and the
/// caller writes no texture.
fn png(rgba: &[u8], w: u32, h: u32) -> Vec<u8> {
    use image::ImageEncoder;
    let opaque = rgba.chunks_exact(4).all(|p| p[3] == 255);
    let mut bytes = Vec::new();
    let encoder = image::codecs::png::PngEncoder::new_with_quality(
        &mut bytes,
        image::codecs::png::CompressionType::Best,
        image::codecs::png::FilterType::Adaptive,
    );
    let result = if opaque {
        let rgb: Vec<u8> = rgba
            .chunks_exact(4)
            .flat_map(|p| [p[0], p[1], p[2]])
            .collect();
        encoder.write_image(&rgb, w, h, image::ExtendedColorType::Rgb8)
    } else {
        encoder.write_image(rgba, w, h, image::ExtendedColorType::Rgba8)
    };
    if result.is_err() {
        bytes.clear();
    }
    bytes
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn leaves_cover_part_of_the_card_and_cut_out_the_rest() {
        let px = leaf_rgba();
        let on = px.chunks_exact(4).filter(|p| p[3] == 255).count();
        let share = on as f64 / (LEAF_SIDE * LEAF_SIDE) as f64;
        assert!((0.3..0.8).contains(&share), "leaf share {share}");
        assert!(px.chunks_exact(4).all(|p| p[3] == 0 || p[3] == 255));
        let png = leaf_png();
        assert!(
            png.starts_with(b"\x89PNG") && png.len() < 16_000,
            "{}",
            png.len()
        );
        let back = image::load_from_memory(png).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!((back.width(), back.height()), (LEAF_SIDE, LEAF_SIDE));
    }

    #[test]
    fn bark_tiles_and_is_small() {
        let px = bark_rgba();
        let (w, h) = (BARK_SIZE.0 as usize, BARK_SIZE.1 as usize);
        // The first and last columns (and rows) differ about as much as neighbours do.
        let step = |a: usize, b: usize| (i32::from(px[4 * a]) - i32::from(px[4 * b])).abs();
        let seam: i32 = (0..h).map(|y| step(y * w, y * w + w - 1)).sum::<i32>() / h as i32;
        let inner: i32 = (0..h).map(|y| step(y * w + 10, y * w + 11)).sum::<i32>() / h as i32;
        assert!(seam <= inner + 12, "seam {seam}, inner {inner}");
        let png = bark_png();
        assert!(
            png.starts_with(b"\x89PNG") && png.len() < 24_000,
            "{}",
            png.len()
        );
    }
}
