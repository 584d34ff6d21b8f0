//! cargo-fuzz target `tree_colors`: see `bodies.rs` for what it feeds where, and README.md for how
//! to run it.
#![no_main]

#[allow(dead_code, reason = "bodies.rs holds every target's body; this one runs one")]
mod bodies;

libfuzzer_sys::fuzz_target!(|data: &[u8]| bodies::tree_colors(data));
