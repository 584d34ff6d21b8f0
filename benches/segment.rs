//! Benchmark: a 12 MP JPEG (made here) → mask at working resolution, automatic mode and an
//! interactive re-cut. Prints a markdown table of medians; run with
//! `cargo bench --bench segment`. Targets (issue 5, for wasm): automatic ≤ 300 ms, re-cut
//! ≤ 50 ms; these are native numbers.

use std::time::Instant;

use image::codecs::jpeg::JpegEncoder;
use image::{ExtendedColorType, ImageEncoder};
use procfit::segment::{Label, Options, Photo, Session, Stroke, WORKING_SIDE};

/// A 4000×3000 photo: a shaded red cup with a handle on a gradient wall, with sensor noise.
fn photo_jpeg() -> Vec<u8> {
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
    JpegEncoder::new_with_quality(&mut out, 88)
        .write_image(&rgb, w, h, ExtendedColorType::Rgb8)
        .expect("encode");
    out
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let jpeg = photo_jpeg();
    let runs = 7;
    let (mut decode, mut auto, mut recut) = (Vec::new(), Vec::new(), Vec::new());
    let opts = Options::default();
    let mut size = (0, 0);
    for _ in 0..runs {
        let t = Instant::now();
        let photo = Photo::decode(&jpeg, WORKING_SIDE).expect("decode");
        decode.push(t.elapsed().as_secs_f64() * 1e3);
        size = (photo.width(), photo.height());
        let t = Instant::now();
        let mut session = Session::automatic(&photo, &opts).expect("segment");
        auto.push(t.elapsed().as_secs_f64() * 1e3);
        session
            .add_stroke(&Stroke {
                label: Label::Background,
                points: vec![[20.0, 300.0], [120.0, 320.0]],
                radius: 4.0,
            })
            .expect("stroke");
        let t = Instant::now();
        session.recut().expect("recut");
        recut.push(t.elapsed().as_secs_f64() * 1e3);
    }
    let (d, a, r) = (median(decode), median(auto), median(recut));
    println!(
        "12 MP JPEG ({} KB) → {}×{} working image, median of {runs} runs, native\n",
        jpeg.len() / 1024,
        size.0,
        size.1
    );
    println!("| step | median ms | wasm target ms |");
    println!("|---|---:|---:|");
    println!("| decode + EXIF + downscale | {d:.1} | |");
    println!(
        "| automatic mask ({} GrabCut iterations) | {a:.1} | |",
        opts.iterations
    );
    println!("| photo → automatic mask total | {:.1} | 300 |", d + a);
    println!(
        "| interactive re-cut ({} iterations) | {r:.1} | 50 |",
        opts.recut_iterations
    );
}
