//! The fuzz targets' regression test: every seed input, every file of the committed corpora
//! (`fuzz/corpus/<target>/`) and every crash the fuzzer ever found (`fuzz/regressions/<target>/`)
//! run through the same bodies the cargo-fuzz targets run (`fuzz/fuzz_targets/bodies.rs`), in
//! each `cargo test`. `PROCFIT_WRITE_FUZZ_SEEDS=1 cargo test --test fuzz_corpus` writes the seeds
//! into `fuzz/corpus/` to start a fuzzing run from.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "a test binary: a failed step should stop it loudly"
)]

#[path = "../fuzz/fuzz_targets/bodies.rs"]
#[allow(dead_code, reason = "shared with the fuzz targets")]
mod bodies;

use image::codecs::jpeg::JpegEncoder;
use image::codecs::png::PngEncoder;
use image::codecs::webp::WebPEncoder;
use image::{ExtendedColorType, ImageEncoder};
use procfit::generators;
use procfit::model::Model;
use std::path::{Path, PathBuf};

type Body = fn(&[u8]);

const TARGETS: [(&str, Body); 5] = [
    ("decode_photo", bodies::decode_photo),
    ("mask_image", bodies::mask_image),
    ("params_json", bodies::params_json),
    ("tree_colors", bodies::tree_colors),
    ("import_glb", bodies::import_glb),
];

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// A small test card: hue across, brightness down, a dark disc in the middle.
fn card(w: u32, h: u32) -> Vec<u8> {
    let mut px = Vec::with_capacity((w * h * 3) as usize);
    for y in 0..h {
        for x in 0..w {
            let (u, v) = (x as f32 / w as f32, y as f32 / h as f32);
            let disc = (u - 0.5).powi(2) + (v - 0.5).powi(2) < 0.06;
            let k = if disc { 0.2 } else { 1.0 - 0.5 * v };
            px.extend([u, 1.0 - u, 0.5].map(|c| (255.0 * c * k) as u8));
        }
    }
    px
}

fn encode(kind: &str, px: &[u8], w: u32, h: u32, t: ExtendedColorType) -> Vec<u8> {
    let mut out = Vec::new();
    match kind {
        "jpeg" => JpegEncoder::new_with_quality(&mut out, 80)
            .write_image(px, w, h, t)
            .unwrap(),
        "png" => PngEncoder::new(&mut out).write_image(px, w, h, t).unwrap(),
        _ => WebPEncoder::new_lossless(&mut out)
            .write_image(px, w, h, t)
            .unwrap(),
    }
    out
}

/// A big-endian EXIF APP1 segment with one Orientation entry, inserted after the JPEG's SOI.
fn with_exif(jpeg: &[u8], orientation: u16) -> Vec<u8> {
    let mut app1 = b"Exif\0\0MM\0\x2a\0\0\0\x08".to_vec();
    app1.extend(1u16.to_be_bytes());
    app1.extend(0x0112u16.to_be_bytes());
    app1.extend(3u16.to_be_bytes());
    app1.extend(1u32.to_be_bytes());
    app1.extend(orientation.to_be_bytes());
    app1.extend([0, 0, 0, 0, 0, 0]);
    let mut out = jpeg[..2].to_vec();
    out.extend([0xFF, 0xE1]);
    out.extend(((app1.len() + 2) as u16).to_be_bytes());
    out.extend(app1);
    out.extend(&jpeg[2..]);
    out
}

/// Valid inputs of each kind, small enough for the fuzzer to mutate quickly.
fn seeds(target: &str) -> Vec<(String, Vec<u8>)> {
    let rgb = ExtendedColorType::Rgb8;
    let mut out = Vec::new();
    match target {
        "decode_photo" => {
            let px = card(40, 30);
            for kind in ["jpeg", "png", "webp"] {
                out.push((format!("card.{kind}"), encode(kind, &px, 40, 30, rgb)));
            }
            let jpeg = encode("jpeg", &px, 40, 30, rgb);
            for o in [3, 6, 8] {
                out.push((format!("exif-{o}.jpg"), with_exif(&jpeg, o)));
            }
            let rgba: Vec<u8> = px
                .chunks_exact(3)
                .enumerate()
                .flat_map(|(i, p)| [p[0], p[1], p[2], (i % 256) as u8])
                .collect();
            out.push((
                "alpha.png".into(),
                encode("png", &rgba, 40, 30, ExtendedColorType::Rgba8),
            ));
        }
        "mask_image" => {
            let (w, h) = (32, 24);
            let mask: Vec<u8> = (0..w * h)
                .map(|i| match (i % w, i / w) {
                    (x, y) if (8..24).contains(&x) && (6..18).contains(&y) => 255,
                    (x, _) if x == 7 || x == 24 => 128,
                    _ => 0,
                })
                .collect();
            out.push((
                "mask.png".into(),
                encode("png", &mask, w, h, ExtendedColorType::L8),
            ));
            let labels: Vec<u8> = mask.iter().map(|&m| [0, 1, 2][m as usize % 3]).collect();
            out.push((
                "labels.png".into(),
                encode("png", &labels, w, h, ExtendedColorType::L8),
            ));
            out.push(("photo.jpg".into(), encode("jpeg", &card(w, h), w, h, rgb)));
        }
        "params_json" => {
            for g in generators::all() {
                for p in g.presets() {
                    let m = Model::new(g.name(), &p.values, generators::Lod::Low).unwrap();
                    out.push((format!("{}-{}.json", g.name(), p.name), m.to_json().into()));
                }
            }
        }
        "tree_colors" => {
            out.push(("empty.json".into(), b"{}".to_vec()));
            out.push((
                "autumn.json".into(),
                br#"{"leafHue":[330,170],"leafMinValue":0.45,"restAsBranch":true}"#.to_vec(),
            ));
            out.push((
                "all.json".into(),
                serde_json::to_vec(&procfit::tree::labels::ColorThresholds::default()).unwrap(),
            ));
        }
        _ => {
            let g = generators::all()[0];
            let m = Model::new(g.name(), &g.presets()[0].values, generators::Lod::Low).unwrap();
            let mesh = m
                .generator
                .generate(&m.params, generators::Lod::Low)
                .unwrap();
            let glb = procfit::glb::write_glb(&mesh, Some(&m.to_doc()), &[]).unwrap();
            out.push(("dish.glb".into(), glb));
            out.push((
                "tri.obj".into(),
                b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1\n".to_vec(),
            ));
        }
    }
    out
}

fn files(dir: &Path) -> Vec<PathBuf> {
    let Ok(read) = std::fs::read_dir(dir) else {
        return Vec::new();
    };
    let mut v: Vec<PathBuf> = read
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file())
        .collect();
    v.sort();
    v
}

#[test]
fn seeds_corpora_and_found_crashes_run_clean() {
    let write = std::env::var_os("PROCFIT_WRITE_FUZZ_SEEDS").is_some();
    for (target, body) in TARGETS {
        let seeds = seeds(target);
        assert!(!seeds.is_empty(), "{target}: no seeds");
        for (name, bytes) in &seeds {
            body(bytes);
            if write {
                let dir = root().join("fuzz/corpus").join(target);
                std::fs::create_dir_all(&dir).unwrap();
                std::fs::write(dir.join(format!("seed-{name}")), bytes).unwrap();
            }
        }
        let mut n = 0;
        for sub in ["fuzz/corpus", "fuzz/regressions"] {
            for path in files(&root().join(sub).join(target)) {
                body(&std::fs::read(&path).unwrap());
                n += 1;
            }
        }
        eprintln!(
            "{target}: {} seeds, {n} corpus and regression files",
            seeds.len()
        );
    }
}

/// The seeds are what they claim: each decodes (or parses) as the product reads it, so the
/// fuzzer starts from inputs that reach deep code.
#[test]
fn seeds_are_valid_inputs() {
    for (name, bytes) in seeds("decode_photo") {
        procfit::segment::Photo::decode(&bytes, 512).unwrap_or_else(|e| panic!("{name}: {e}"));
    }
    for (name, text) in seeds("params_json") {
        Model::from_json(std::str::from_utf8(&text).unwrap())
            .unwrap_or_else(|e| panic!("{name}: {e}"));
    }
    for (name, text) in seeds("tree_colors") {
        procfit::tree::labels::ColorThresholds::from_json(std::str::from_utf8(&text).unwrap())
            .unwrap_or_else(|e| panic!("{name}: {e}"));
    }
    for (name, bytes) in seeds("import_glb") {
        procfit::glb::import_reference(&bytes).unwrap_or_else(|e| panic!("{name}: {e}"));
    }
}
