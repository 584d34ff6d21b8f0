//! cargo-fuzz target: arbitrary bytes as a photo file (JPEG, PNG, WebP, with or without EXIF), the
//! way the CLI and the page's fallback decode it. Any panic, abort, out-of-memory or timeout is a
//! bug: a hostile file must give a `SegmentError`.
#![no_main]

use libfuzzer_sys::fuzz_target;
use procfit::segment::{Photo, decode};

fuzz_target!(|data: &[u8]| {
    let _ = decode::check_complete(data);
    // The working size the product uses, and a small one (other scale paths).
    if let Ok(photo) = Photo::decode(data, procfit::segment::WORKING_SIDE) {
        assert!(photo.width() <= procfit::segment::WORKING_SIDE);
        assert!(photo.height() <= procfit::segment::WORKING_SIDE);
        assert_eq!(
            photo.rgba().len(),
            4 * photo.width() as usize * photo.height() as usize
        );
    }
    let _ = Photo::decode_full(data, 64);
});
