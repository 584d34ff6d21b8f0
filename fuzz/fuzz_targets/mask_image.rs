//! cargo-fuzz target: arbitrary bytes as a mask image for a photo (`procfit reconstruct --mask`,
//! the page's "open a mask") and as a tree's label image (grey levels 0/1/2/255, or a photo
//! labelled by colour). A hostile file must give an error, never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use procfit::segment::{Photo, segment_mask_image};
use procfit::tree::labels::{ColorThresholds, labels_from_image};
use std::sync::OnceLock;

/// A 64×48 grey photo (the mask must match its aspect ratio to be read).
fn photo() -> &'static Photo {
    static PHOTO: OnceLock<Photo> = OnceLock::new();
    PHOTO.get_or_init(|| {
        let grey = vec![128; 64 * 48 * 4];
        Photo::from_rgba(64, 48, &grey, 64).unwrap_or_else(|e| panic!("the fixed photo: {e}"))
    })
}

fuzz_target!(|data: &[u8]| {
    if let Ok(seg) = segment_mask_image(photo(), data) {
        assert_eq!(seg.mask.width(), 64);
        assert_eq!(seg.mask.height(), 48);
    }
    if let Ok(p) = Photo::decode(data, 128) {
        let _ = labels_from_image(p.width(), p.height(), p.rgba(), &ColorThresholds::default());
    }
});
