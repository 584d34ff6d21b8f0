//! cargo-fuzz target: arbitrary text as a params JSON (`--start`, `--params`, the page's "open"),
//! then the model it describes generated at the lowest detail. A hostile document must give a
//! `ModelError` (or a generator error), never a panic, a hang or a huge allocation.
#![no_main]

use libfuzzer_sys::fuzz_target;
use procfit::generators::Lod;
use procfit::model::Model;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(model) = Model::from_json(text) {
        let _ = model.to_json();
        let _ = model.generator.generate(&model.params, Lod::Low);
    }
});
