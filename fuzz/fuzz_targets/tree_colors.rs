//! cargo-fuzz target: arbitrary text as the tree-colour rules (`--tree-colors`, the page's
//! "Adjust the colours"), then applied to a small photo. Bad rules must give a `MaskError`.
#![no_main]

use libfuzzer_sys::fuzz_target;
use procfit::tree::labels::{ColorThresholds, labels_from_rgb, photo_labels};

/// A 16×16 photo with every hue, saturation and brightness step.
fn pixels() -> Vec<u8> {
    (0..256u32)
        .flat_map(|i| {
            let (r, g, b) = ((i * 37) % 256, (i * 91) % 256, (i * 53) % 256);
            [r as u8, g as u8, b as u8]
        })
        .collect()
}

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(t) = ColorThresholds::from_json(text) {
        let px = pixels();
        let _ = labels_from_rgb(16, 16, &px, 3, &t);
        let _ = photo_labels(16, 16, &px, 3, &t);
    }
});
