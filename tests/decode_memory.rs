//! Issue 19: a photo is brought to the working size at decode, with memory for the working size
//! where the format allows it. This binary runs under dhat's heap statistics (procfit forbids
//! unsafe code, so it does not write its own counting allocator) and decodes a 12 MP PNG: row by
//! row it must peak far below the photo's own pixels (12 MP × 3 bytes = 36 MB), which the full
//! decode, kept as the reference, needs at least.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "a test binary: a failed step should stop it loudly"
)]

use procfit::segment::Photo;

#[global_allocator]
static ALLOC: dhat::Alloc = dhat::Alloc;

const MB: usize = 1 << 20;
const W: u32 = 4000;
const H: u32 = 3000;

/// A 4000×3000 RGB PNG of smooth colour with a dark disc, written a row at a time so that
/// making it never holds the image (the heap's peak before the decode stays small).
fn png_card() -> Vec<u8> {
    let mut out = Vec::new();
    let mut enc = png::Encoder::new(&mut out, W, H);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut writer = enc.write_header().unwrap();
    let mut stream = writer.stream_writer().unwrap();
    let mut row = vec![0u8; W as usize * 3];
    for y in 0..H {
        for x in 0..W {
            let (u, v) = (x as f32 / W as f32, y as f32 / H as f32);
            let disc = (u - 0.5).powi(2) + (v - 0.5).powi(2) < 0.05;
            let k = if disc { 0.25 } else { 1.0 };
            let px = [200.0 * u * k, 180.0 * (1.0 - v) * k, 120.0 * k];
            row[x as usize * 3..x as usize * 3 + 3].copy_from_slice(&px.map(|c| c as u8));
        }
        std::io::Write::write_all(&mut stream, &row).unwrap();
    }
    stream.finish().unwrap();
    writer.finish().unwrap();
    out
}

/// An upper bound of the heap's peak above what was live before `f` (dhat keeps the global
/// peak only: were the peak before `f` higher, this overestimates, never underestimates).
fn peak_during<T>(f: impl FnOnce() -> T) -> (usize, T) {
    let before = dhat::HeapStats::get().curr_bytes;
    let out = f();
    (dhat::HeapStats::get().max_bytes.saturating_sub(before), out)
}

#[test]
fn a_12_mp_png_decodes_in_memory_for_the_working_size() {
    let _profiler = dhat::Profiler::builder().testing().build();
    let png = png_card();
    let (rows, photo) = peak_during(|| Photo::decode(&png, 512).unwrap());
    assert_eq!((photo.width(), photo.height()), (512, 384));
    assert_eq!(photo.source_size(), (W, H));
    let (full, reference) = peak_during(|| Photo::decode_full(&png, 512).unwrap());
    assert_eq!(photo.rgba(), reference.rgba(), "the same pixels either way");
    eprintln!(
        "12 MP PNG ({:.1} MB): heap peak {:.1} MB row by row, {:.1} MB decoded in full",
        png.len() as f64 / MB as f64,
        rows as f64 / MB as f64,
        full as f64 / MB as f64
    );
    // The output (0.8 MB), the area accumulators (3 MB), a row and the inflater's state.
    assert!(
        rows < 8 * MB,
        "row-by-row PNG decode peaked at {rows} bytes"
    );
    assert!(
        full > 36 * MB,
        "the reference decodes every pixel ({full} bytes)"
    );
}
