//! Fuzz-style robustness test of the importer: thousands of seeded mutations of valid GLBs (bit
//! flips, truncations, rewritten length fields, absurd numbers in the JSON, spliced bytes) must
//! each give `Ok` or a clear `Err`, never a panic. The same mutations drive the `cargo fuzz`
//! target in `fuzz/` without the seed limit.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "a test binary: a failed step should stop it loudly"
)]

mod glb_support;

use glb_support::{Prism, Rng, doc_of, frame, take_apart};
use procfit::generators::{Generator, Lod};
use procfit::glb::{ExportCamera, import_glb, import_reference, write_glb};
use std::panic::{AssertUnwindSafe, catch_unwind};

/// Valid GLBs to start from: the test prism with and without cameras, state and leaves.
fn seeds() -> Vec<Vec<u8>> {
    let cam = ExportCamera::look_at(glam::Vec3::new(0.0, 0.5, 2.0), glam::Vec3::ZERO, 0.8, 1.5);
    let mut out = Vec::new();
    for preset in Prism.presets() {
        let mesh = Prism.generate(&preset.values, Lod::Low).unwrap();
        let doc = doc_of(&Prism, &preset.values, Lod::Low, Some(5));
        out.push(write_glb(&mesh, Some(&doc), std::slice::from_ref(&cam)).unwrap());
        out.push(write_glb(&mesh, None, &[]).unwrap());
    }
    out
}

/// Numbers that break naive length arithmetic.
const NASTY: [u64; 12] = [
    0,
    1,
    3,
    11,
    12,
    19,
    20,
    0x7fff_ffff,
    0xffff_fffe,
    0xffff_ffff,
    1 << 32,
    u64::MAX,
];

/// One mutation of `base`, chosen and parametrised by `rng`.
fn mutate(base: &[u8], rng: &mut Rng) -> Vec<u8> {
    let mut b = base.to_vec();
    match rng.below(6) {
        // Random bit flips anywhere.
        0 => {
            for _ in 0..1 + rng.below(8) {
                let i = rng.below(b.len());
                b[i] ^= 1 << rng.below(8);
            }
        }
        // Truncation.
        1 => b.truncate(rng.below(b.len())),
        // A framing length field (total, JSON chunk, BIN chunk) set to a nasty or random value.
        2 => {
            let json_len = u32::from_le_bytes(b[12..16].try_into().unwrap()) as usize;
            let at = [8, 12, 20 + json_len][rng.below(3)];
            let v = if rng.below(2) == 0 {
                NASTY[rng.below(NASTY.len())] as u32
            } else {
                rng.next_u64() as u32
            };
            if at + 4 <= b.len() {
                b[at..at + 4].copy_from_slice(&v.to_le_bytes());
            }
        }
        // A number in the JSON replaced by a nasty one, framed correctly so it reaches the
        // accessor and node logic.
        3 => {
            let (json, bin) = take_apart(&b);
            let mut text = serde_json::to_string(&json).unwrap();
            let digits: Vec<usize> = text
                .char_indices()
                .filter(|(_, c)| c.is_ascii_digit())
                .map(|(i, _)| i)
                .collect();
            let at = digits[rng.below(digits.len())];
            let end = text[at..]
                .find(|c: char| !c.is_ascii_digit())
                .map_or(text.len(), |e| at + e);
            let v = NASTY[rng.below(NASTY.len())];
            let v = if rng.below(3) == 0 {
                format!("{v}e30")
            } else {
                v.to_string()
            };
            text.replace_range(at..end, &v);
            b = frame(text.as_bytes(), &bin);
        }
        // A random JSON byte replaced, framed correctly.
        4 => {
            let (json, bin) = take_apart(&b);
            let mut text = serde_json::to_vec(&json).unwrap();
            let i = rng.below(text.len());
            text[i] = b"{}[]\",:-0123456789eE.\xff\x00 "[rng.below(24)];
            b = frame(&text, &bin);
        }
        // A span of the file copied over another span.
        _ => {
            let len = 1 + rng.below(64);
            let from = rng.below(b.len().saturating_sub(len).max(1));
            let to = rng.below(b.len().saturating_sub(len).max(1));
            let span: Vec<u8> = b[from..(from + len).min(b.len())].to_vec();
            let end = (to + span.len()).min(b.len());
            b[to..end].copy_from_slice(&span[..end - to]);
        }
    }
    b
}

#[test]
fn thousands_of_mutated_glbs_never_panic_the_importer() {
    let seeds = seeds();
    // PROCFIT_FUZZ_CASES / PROCFIT_FUZZ_SEED run longer or different campaigns by hand.
    let cases: usize = std::env::var("PROCFIT_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(20_000);
    let seed: u64 = std::env::var("PROCFIT_FUZZ_SEED")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0x0ddb_1a5e);
    let mut rng = Rng(seed | 1);
    let (mut ok, mut err) = (0usize, 0usize);
    for case in 0..cases {
        let base = &seeds[case % seeds.len()];
        let mut state = Rng(rng.next_u64() | 1);
        let start = state.0;
        let bytes = mutate(base, &mut state);
        let outcome = catch_unwind(AssertUnwindSafe(|| {
            let r = import_glb(&bytes);
            if let Ok(g) = &r {
                // Everything a caller does next must not panic either.
                let _ = g.model();
                let _ = g.reference.bounds();
            }
            let _ = import_reference(&bytes);
            r.is_ok()
        }));
        match outcome {
            Ok(true) => ok += 1,
            Ok(false) => err += 1,
            Err(_) => panic!("case {case} (mutation seed {start:#x}) panicked the importer"),
        }
    }
    eprintln!("{ok} imported, {err} rejected");
    // Both outcomes must be common, or the mutations are not exercising the importer.
    assert!(ok > cases / 20 && err > cases / 4, "ok {ok}, err {err}");
}
