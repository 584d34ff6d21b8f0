//! cargo-fuzz target: arbitrary bytes through procfit's GLB and OBJ importers. Any panic, abort,
//! out-of-memory or timeout is a bug: hostile files must give a `GlbError`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(glb) = procfit::glb::import_glb(data) {
        // What a caller does next must not panic either.
        let _ = glb.model();
        let _ = glb.reference.bounds();
    }
    // Sniffs GLB vs OBJ, so OBJ text is fuzzed too.
    let _ = procfit::glb::import_reference(data);
});
