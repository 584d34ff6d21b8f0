//! The fuzz targets' bodies, one function a target, shared by the cargo-fuzz targets in this
//! folder (each as its module `bodies`) and by the regression test that runs every corpus file and every crash
//! found through them in each `cargo test` (tests/fuzz_corpus.rs). Any panic, abort,
//! out-of-memory or timeout is a bug: hostile input must come back as an error.

use procfit::generators::Lod;
use procfit::model::Model;
use procfit::segment::{Photo, WORKING_SIDE, decode, segment_mask_image};
use procfit::tree::labels::{ColorThresholds, labels_from_image, labels_from_rgb, photo_labels};
use std::sync::OnceLock;

/// Arbitrary bytes as a photo file (JPEG, PNG, WebP, with or without EXIF), decoded the way the
/// CLI and the page's fallback decode it.
pub fn decode_photo(data: &[u8]) {
    let _ = decode::check_complete(data);
    if let Ok(photo) = Photo::decode(data, WORKING_SIDE) {
        assert!(photo.width() <= WORKING_SIDE && photo.height() <= WORKING_SIDE);
        let (w, h) = (photo.width() as usize, photo.height() as usize);
        assert_eq!(photo.rgba().len(), 4 * w * h);
    }
}

/// A 64×48 grey photo (a mask must have its aspect ratio to be read).
fn grey_photo() -> &'static Photo {
    static PHOTO: OnceLock<Photo> = OnceLock::new();
    PHOTO.get_or_init(|| {
        let grey = vec![128; 64 * 48 * 4];
        Photo::from_rgba(64, 48, &grey, 64).unwrap_or_else(|e| panic!("the fixed photo: {e}"))
    })
}

/// Arbitrary bytes as a mask image for a photo (`reconstruct` with a mask, the page's "open a
/// mask") and as a tree's label image (grey levels 0/1/2/255, or a photo labelled by colour).
pub fn mask_image(data: &[u8]) {
    if let Ok(seg) = segment_mask_image(grey_photo(), data) {
        assert_eq!((seg.mask.width(), seg.mask.height()), (64, 48));
    }
    if let Ok(p) = Photo::decode(data, 128) {
        let _ = labels_from_image(p.width(), p.height(), p.rgba(), &ColorThresholds::default());
    }
}

/// Arbitrary text as a params JSON (`--start`, `--params`, the page's "open"), then the model
/// it describes generated at the lowest detail.
pub fn params_json(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(model) = Model::from_json(text) {
        let _ = model.to_json();
        let _ = model.generator.generate(&model.params, Lod::Low);
    }
}

/// Arbitrary text as the tree-colour rules (`--tree-colors`, the page's "Adjust the colours"),
/// then applied to a 16×16 photo of many colours.
pub fn tree_colors(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(t) = ColorThresholds::from_json(text) {
        let px: Vec<u8> = (0..256u32)
            .flat_map(|i| [(i * 37) % 256, (i * 91) % 256, (i * 53) % 256].map(|v| v as u8))
            .collect();
        let _ = labels_from_rgb(16, 16, &px, 3, &t);
        let _ = photo_labels(16, 16, &px, 3, &t);
    }
}

/// Arbitrary bytes through the GLB and OBJ importers, then what a caller does next.
pub fn import_glb(data: &[u8]) {
    if let Ok(glb) = procfit::glb::import_glb(data) {
        let _ = glb.model();
        let _ = glb.reference.bounds();
    }
    // Sniffs GLB vs OBJ, so OBJ text is fuzzed too.
    let _ = procfit::glb::import_reference(data);
}
