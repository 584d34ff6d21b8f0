//! Benchmark: a 12 MP JPEG (made here) → mask at working resolution, automatic mode and an
//! interactive re-cut. Prints a markdown table of medians; run with
//! `cargo bench --bench segment`. Targets (issue 5, for wasm): automatic ≤ 300 ms, re-cut
//! ≤ 50 ms; these are native numbers. Then the same photo as a PNG (no reduced-scale decode:
//! every pixel is decoded and area-averaged) and the area downscale alone.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "a benchmark binary: a failed workload should stop it loudly"
)]

use std::time::Instant;

use procfit::segment::bench::synthetic_photo_jpeg;
use procfit::segment::decode::area_resample;
use procfit::segment::{Label, Options, Photo, Session, Stroke, WORKING_SIDE};

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
    let jpeg = synthetic_photo_jpeg();
    let runs = 7;
    // Wall and CPU times per step.
    let mut times: [(Vec<f64>, Vec<f64>); 5] = Default::default();
    let opts = Options::default();
    let mut size = (0, 0);
    for _ in 0..runs {
        let (photo, w, c) = timed(|| Photo::decode(&jpeg, WORKING_SIDE).expect("decode"));
        times[0].0.push(w);
        times[0].1.push(c);
        // The reference: every pixel decoded (what `decode` did before the scaled JPEG decode).
        let (_, w, c) = timed(|| Photo::decode_full(&jpeg, WORKING_SIDE).expect("decode"));
        times[4].0.push(w);
        times[4].1.push(c);
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
    let [d, a, r, r2, f] = times.map(|(w, c)| (median(w), median(c)));
    println!(
        "12 MP JPEG ({} KB) → {}×{} working image, median of {runs} runs, native, one thread\n",
        jpeg.len() / 1024,
        size.0,
        size.1
    );
    println!("| step | wall ms | CPU ms | wasm target ms |");
    println!("|---|---:|---:|---:|");
    println!(
        "| decode, every pixel (reference) + EXIF + downscale | {:.1} | {:.1} | |",
        f.0, f.1
    );
    println!(
        "| decode at reduced DCT scale + EXIF + downscale | {:.1} | {:.1} | |",
        d.0, d.1
    );
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
    // The same photo as a PNG, and the area downscale alone on its 12 MP of RGB.
    let rgb = image::load_from_memory(&jpeg).expect("decode").into_rgb8();
    let (sw, sh) = rgb.dimensions();
    let mut png = Vec::new();
    image::DynamicImage::ImageRgb8(rgb.clone())
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .expect("encode");
    let (mut png_t, mut down_t) = ((vec![], vec![]), (vec![], vec![]));
    for _ in 0..runs {
        let (_, w, c) = timed(|| Photo::decode(&png, WORKING_SIDE).expect("decode"));
        png_t.0.push(w);
        png_t.1.push(c);
        let (_, w, c) = timed(|| area_resample(rgb.as_raw(), sw, sh, 3, size.0, size.1));
        down_t.0.push(w);
        down_t.1.push(c);
    }
    println!(
        "| the same photo as a PNG ({} KB): decode + downscale | {:.1} | {:.1} | |",
        png.len() / 1024,
        median(png_t.0),
        median(png_t.1)
    );
    println!(
        "| area downscale alone, {sw}×{sh} RGB → {}×{} | {:.1} | {:.1} | |",
        size.0,
        size.1,
        median(down_t.0),
        median(down_t.1)
    );
}
