//! cargo-fuzz target `mask_image`: see `bodies.rs` for what it feeds where, and README.md for how
//! to run it.
#![no_main]
#![allow(dead_code, reason = "bodies.rs holds every target's body; this one runs one")]

include!("bodies.rs");

libfuzzer_sys::fuzz_target!(|data: &[u8]| mask_image(data));
