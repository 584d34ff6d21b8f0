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

/// CPU time of this thread in ms (Linux), so a loaded machine does not inflate the figures.
fn cpu_ms() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<f64>().ok())
        .map_or(f64::NAN, |ns| ns / 1e6)
}

/// Wall and CPU milliseconds of `f`.
fn timed<T>(f: impl FnOnce() -> T) -> (T, f64, f64) {
    let (t, c) = (Instant::now(), cpu_ms());
    let r = f();
    (r, t.elapsed().as_secs_f64() * 1e3, cpu_ms() - c)
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let jpeg = photo_jpeg();
    let runs = 7;
    // Wall and CPU times per step.
    let mut times: [(Vec<f64>, Vec<f64>); 4] = Default::default();
    let opts = Options::default();
    let mut size = (0, 0);
    for _ in 0..runs {
        let (photo, w, c) = timed(|| Photo::decode(&jpeg, WORKING_SIDE).expect("decode"));
        times[0].0.push(w);
        times[0].1.push(c);
        size = (photo.width(), photo.height());
        let (mut session, w, c) = timed(|| Session::automatic(&photo, &opts).expect("segment"));
        times[1].0.push(w);
        times[1].1.push(c);
        session
            .add_stroke(&Stroke {
                label: Label::Background,
                points: vec![[20.0, 300.0], [120.0, 320.0]],
                radius: 4.0,
            })
            .expect("stroke");
        let ((), w, c) = timed(|| {
            session.recut().expect("recut");
        });
        times[2].0.push(w);
        times[2].1.push(c);
        // A second edit: the session's graph is built by now and only gets new capacities.
        session
            .add_stroke(&Stroke {
                label: Label::Object,
                points: vec![[330.0, 200.0], [340.0, 230.0]],
                radius: 3.0,
            })
            .expect("stroke");
        let ((), w, c) = timed(|| {
            session.recut().expect("recut");
        });
        times[3].0.push(w);
        times[3].1.push(c);
    }
    let [d, a, r, r2] = times.map(|(w, c)| (median(w), median(c)));
    println!(
        "12 MP JPEG ({} KB) → {}×{} working image, median of {runs} runs, native, one thread\n",
        jpeg.len() / 1024,
        size.0,
        size.1
    );
    println!("| step | wall ms | CPU ms | wasm target ms |");
    println!("|---|---:|---:|---:|");
    println!("| decode + EXIF + downscale | {:.1} | {:.1} | |", d.0, d.1);
    println!("| automatic mask | {:.1} | {:.1} | |", a.0, a.1);
    println!(
        "| photo → automatic mask total | {:.1} | {:.1} | 300 |",
        d.0 + a.0,
        d.1 + a.1
    );
    println!(
        "| first interactive re-cut (≤ {} iterations) | {:.1} | {:.1} | 50 |",
        opts.recut_iterations, r.0, r.1
    );
    println!(
        "| next interactive re-cut (graph reused) | {:.1} | {:.1} | 50 |",
        r2.0, r2.1
    );
}
