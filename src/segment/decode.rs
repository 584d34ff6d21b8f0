//! Photo decoding: JPEG/PNG/WebP bytes or browser RGBA → an upright RGBA photo at working size.
//!
//! Order matters for memory and time: the decoder is bounded by [`image::Limits`] and a pixel
//! budget checked from the header *before* any pixel is decoded (a decompression bomb is refused,
//! not allocated); the full-size image is then box-filtered (exact area weights) straight to the
//! working resolution; EXIF orientation is applied last, on the small image, since rotation and
//! area averaging commute.
//!
//! A JPEG at least twice the working side is decoded at a reduced DCT scale (1/2, 1/4 or 1/8,
//! the largest reduction still ≥ the working size) by `jpeg-decoder`: the inverse DCT then makes
//! 4×4, 2×2 or 1×1 pixels per 8×8 block, which is the block's area average up to rounding, and the
//! area downscale does the rest. On a 12 MP photo this is several times cheaper than decoding
//! every pixel only to average them away (issue 5). Any JPEG that decoder refuses (arithmetic
//! coding, CMYK, 12-bit, truncated) goes through the full decode, as smaller photos do.
//!
//! A PNG (8-bit, not interlaced: nearly all) is decoded a row at a time straight into the area
//! downscale ([`AreaResampler`]), to the same pixels as the full decode: a 12 MP PNG peaks at
//! 4 MB of heap instead of 38 MB (`tests/decode_memory.rs`) and decodes ~30 % faster. A WebP
//! decoder has no row interface, so WebP takes the full decode.

use image::{DynamicImage, ImageDecoder, ImageReader, Limits, RgbaImage, metadata::Orientation};

use super::SegmentError;

/// Default longest side of the working image (the paper's masks are of this order).
pub const WORKING_SIDE: u32 = 512;

/// Largest photo accepted, in pixels (a 50 MP phone photo fits, a decompression bomb does not).
pub const MAX_PIXELS: u64 = 100_000_000;

/// Largest side accepted by the decoder.
pub const MAX_DECODE_SIDE: u32 = 30_000;

/// Smallest side of a photo that can be segmented meaningfully.
pub const MIN_SIDE: u32 = 8;

/// An upright photo at working resolution, RGBA8, row-major, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct Photo {
    width: u32,
    height: u32,
    rgba: Vec<u8>,
    has_alpha: bool,
    source_size: (u32, u32),
}

impl Photo {
    /// Decodes JPEG, PNG or WebP bytes, applies EXIF orientation and downscales so the longest
    /// side is at most `working_side`.
    pub fn decode(bytes: &[u8], working_side: u32) -> Result<Photo, SegmentError> {
        check_working_side(working_side)?;
        if bytes.is_empty() {
            return Err(SegmentError::new("the file is empty"));
        }
        check_complete(bytes)?;
        let fast = if is_jpeg(bytes) {
            decode_jpeg_scaled(bytes, working_side)
        } else if bytes.starts_with(PNG_SIGNATURE) {
            decode_png_rows(bytes, working_side)
        } else {
            Scaled::NotApplicable
        };
        match fast {
            Scaled::Done(photo) => Ok(photo),
            Scaled::Refused(e) => Err(e),
            Scaled::NotApplicable => Photo::decode_full(bytes, working_side),
        }
    }

    /// [`Photo::decode`] without the scaled JPEG decode: every source pixel is decoded, then
    /// area-averaged. The reference the scaled decode is tested and benchmarked against.
    pub fn decode_full(bytes: &[u8], working_side: u32) -> Result<Photo, SegmentError> {
        check_working_side(working_side)?;
        if bytes.is_empty() {
            return Err(SegmentError::new("the file is empty"));
        }
        check_complete(bytes)?;
        let reader = ImageReader::new(std::io::Cursor::new(bytes))
            .with_guessed_format()
            .map_err(|e| SegmentError(format!("cannot read the image: {e}")))?;
        if reader.format().is_none() {
            return Err(SegmentError::new(
                "not a recognised image: expected JPEG, PNG or WebP",
            ));
        }
        let mut reader = reader;
        let mut limits = Limits::default();
        limits.max_image_width = Some(MAX_DECODE_SIDE);
        limits.max_image_height = Some(MAX_DECODE_SIDE);
        limits.max_alloc = Some(4 * MAX_PIXELS + (64 << 20));
        reader.limits(limits);
        let mut decoder = reader
            .into_decoder()
            .map_err(|e| SegmentError(format!("cannot decode the image: {e}")))?;
        let (w, h) = decoder.dimensions();
        check_source_size(w, h)?;
        if is_jpeg(bytes) {
            // The component count is not known here: the bound that holds for any JPEG.
            check_jpeg_data_size(bytes.len(), w, h, false)?;
        }
        // A broken EXIF block is not worth refusing the photo for: treat it as upright.
        let orientation = decoder.orientation().unwrap_or(Orientation::NoTransforms);
        let img = DynamicImage::from_decoder(decoder)
            .map_err(|e| SegmentError(format!("cannot decode the image: {e}")))?;
        let (tw, th) = target_size(w, h, working_side);
        let (rgba, has_alpha) = match &img {
            DynamicImage::ImageLuma8(b) => area_resample(b.as_raw(), w, h, 1, tw, th),
            DynamicImage::ImageLumaA8(b) => area_resample(b.as_raw(), w, h, 2, tw, th),
            DynamicImage::ImageRgb8(b) => area_resample(b.as_raw(), w, h, 3, tw, th),
            DynamicImage::ImageRgba8(b) => area_resample(b.as_raw(), w, h, 4, tw, th),
            // 16-bit and float images: convert to 8 bits first (rare, and PNG-sized).
            other => area_resample(other.to_rgba8().as_raw(), w, h, 4, tw, th),
        };
        drop(img);
        oriented_photo(rgba, has_alpha, (w, h), (tw, th), orientation)
            .ok_or_else(|| SegmentError::new("internal: resampled buffer has the wrong size"))
    }

    /// A photo from raw RGBA8 pixels (e.g. a canvas `ImageData` from the browser, already
    /// upright), downscaled so the longest side is at most `working_side`.
    pub fn from_rgba(
        width: u32,
        height: u32,
        rgba: &[u8],
        working_side: u32,
    ) -> Result<Photo, SegmentError> {
        check_working_side(working_side)?;
        check_source_size(width, height)?;
        let expected = width as usize * height as usize * 4;
        if rgba.len() != expected {
            return Err(SegmentError(format!(
                "{} bytes for a {width}×{height} RGBA image (expected {expected})",
                rgba.len()
            )));
        }
        let (tw, th) = target_size(width, height, working_side);
        let (rgba, has_alpha) = area_resample(rgba, width, height, 4, tw, th);
        Ok(Photo {
            width: tw,
            height: th,
            rgba,
            has_alpha,
            source_size: (width, height),
        })
    }

    /// A photo from working-size RGBA pixels already made by this module (`rgba` must hold
    /// `width × height × 4` bytes).
    pub(super) fn from_parts(
        width: u32,
        height: u32,
        rgba: Vec<u8>,
        source_size: (u32, u32),
    ) -> Photo {
        let has_alpha = rgba.chunks_exact(4).any(|p| p[3] < 255);
        Photo {
            width,
            height,
            rgba,
            has_alpha,
            source_size,
        }
    }

    /// Width of the working image.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height of the working image.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// RGBA8 pixels of the working image.
    pub fn rgba(&self) -> &[u8] {
        &self.rgba
    }

    /// Whether the source had any pixel that is not fully opaque.
    pub fn has_alpha(&self) -> bool {
        self.has_alpha
    }

    /// Upright size of the source photo before downscaling.
    pub fn source_size(&self) -> (u32, u32) {
        self.source_size
    }

    /// Colours in `[0, 1]`, one per pixel.
    pub fn colors(&self) -> Vec<[f32; 3]> {
        self.rgba
            .chunks_exact(4)
            .map(|p| {
                [
                    f32::from(p[0]) / 255.0,
                    f32::from(p[1]) / 255.0,
                    f32::from(p[2]) / 255.0,
                ]
            })
            .collect()
    }
}

/// Outcome of the scaled JPEG decode.
enum Scaled {
    /// Decoded at reduced scale.
    Done(Photo),
    /// The header says the photo must be refused (too large, too small): the full path would
    /// refuse it too, so refuse it here without decoding anything.
    Refused(SegmentError),
    /// Not worth it (no reduction possible) or not supported by `jpeg-decoder`: use the full path.
    NotApplicable,
}

/// Decodes a JPEG at the largest DCT reduction (1/2, 1/4, 1/8) that is still at least the working
/// size, then area-downscales and orients it like [`Photo::decode_full`].
fn decode_jpeg_scaled(bytes: &[u8], working_side: u32) -> Scaled {
    let mut dec = jpeg_decoder::Decoder::new(std::io::Cursor::new(bytes));
    // Only the header is read here: the pixel budget is checked before any pixel is decoded.
    if dec.read_info().is_err() {
        return Scaled::NotApplicable;
    }
    let Some(info) = dec.info() else {
        return Scaled::NotApplicable;
    };
    let (w, h) = (u32::from(info.width), u32::from(info.height));
    if let Err(e) = check_header_size(w, h) {
        return Scaled::Refused(e);
    }
    let grey = info.pixel_format == jpeg_decoder::PixelFormat::L8;
    if let Err(e) = check_jpeg_data_size(bytes.len(), w, h, grey) {
        return Scaled::Refused(e);
    }
    let (tw, th) = target_size(w, h, working_side);
    // No reduction possible: the full decoder is the faster one at full scale.
    if w < 2 * tw || h < 2 * th {
        return Scaled::NotApplicable;
    }
    // `tw`, `th` ≤ 4096 (checked working side), so they fit in u16.
    let (Ok(rw), Ok(rh)) = (u16::try_from(tw), u16::try_from(th)) else {
        return Scaled::NotApplicable;
    };
    let Ok((sw, sh)) = dec.scale(rw, rh) else {
        return Scaled::NotApplicable;
    };
    let (sw, sh) = (u32::from(sw), u32::from(sh));
    if sw < tw || sh < th {
        return Scaled::NotApplicable;
    }
    dec.set_max_decoding_buffer_size(4 * MAX_PIXELS as usize + (64 << 20));
    let pixels = match dec.decode() {
        Ok(pixels) => pixels,
        // Corrupt or cut-off data: the full decoder would fill what it cannot read with grey
        // and call it a photo, after decoding every pixel at full scale (an 860-byte file
        // claiming 11552×4120 took 12 s and 170 MB that way, found by the `mask_image`
        // fuzzer): refuse it here, as the error it is.
        Err(e @ (jpeg_decoder::Error::Format(_) | jpeg_decoder::Error::Io(_))) => {
            return Scaled::Refused(SegmentError(format!("cannot decode the image: {e}")));
        }
        // A feature `jpeg-decoder` lacks (arithmetic coding, 12-bit…): the full decoder.
        Err(_) => return Scaled::NotApplicable,
    };
    let ch = match info.pixel_format {
        jpeg_decoder::PixelFormat::L8 => 1,
        jpeg_decoder::PixelFormat::RGB24 => 3,
        // 16-bit and CMYK: rare; the full path converts them.
        _ => return Scaled::NotApplicable,
    };
    if pixels.len() != sw as usize * sh as usize * ch {
        return Scaled::NotApplicable;
    }
    let (rgba, has_alpha) = area_resample(&pixels, sw, sh, ch, tw, th);
    drop(pixels);
    // A broken EXIF block is not worth refusing the photo for: treat it as upright.
    let orientation = dec
        .exif_data()
        .and_then(Orientation::from_exif_chunk)
        .unwrap_or(Orientation::NoTransforms);
    match oriented_photo(rgba, has_alpha, (w, h), (tw, th), orientation) {
        Some(photo) => Scaled::Done(photo),
        None => Scaled::NotApplicable,
    }
}

/// The first eight bytes of every PNG file.
const PNG_SIGNATURE: &[u8] = b"\x89PNG\r\n\x1a\n";

/// Decodes a PNG a row at a time straight into the area downscale ([`AreaResampler`]): the same
/// pixels as [`Photo::decode_full`], in memory for the working size instead of the photo's
/// 3–4 bytes a pixel (a 100 MP PNG would need 400 MB). Interlaced and 16-bit PNGs, rare for
/// photos, take the full path.
fn decode_png_rows(bytes: &[u8], working_side: u32) -> Scaled {
    let mut dec = png::Decoder::new(std::io::Cursor::new(bytes));
    // Only the header is read here: the pixel budget is checked before any pixel is decoded.
    let (w, h) = match dec.read_header_info() {
        Ok(info) => (info.width, info.height),
        Err(_) => return Scaled::NotApplicable,
    };
    if let Err(e) = check_header_size(w, h) {
        return Scaled::Refused(e);
    }
    // As the `image` crate reads a PNG: palettes and low bit depths expanded to 8 bits.
    dec.set_transformations(png::Transformations::EXPAND);
    let Ok(mut reader) = dec.read_info() else {
        return Scaled::NotApplicable;
    };
    if reader.info().interlaced {
        return Scaled::NotApplicable;
    }
    let ch = match reader.output_color_type() {
        (png::ColorType::Grayscale, png::BitDepth::Eight) => 1,
        (png::ColorType::GrayscaleAlpha, png::BitDepth::Eight) => 2,
        (png::ColorType::Rgb, png::BitDepth::Eight) => 3,
        (png::ColorType::Rgba, png::BitDepth::Eight) => 4,
        _ => return Scaled::NotApplicable,
    };
    // A broken EXIF block is not worth refusing the photo for: treat it as upright.
    let orientation = reader
        .info()
        .exif_metadata
        .as_deref()
        .and_then(Orientation::from_exif_chunk)
        .unwrap_or(Orientation::NoTransforms);
    let (tw, th) = target_size(w, h, working_side);
    let mut resampler = AreaResampler::new(w, h, ch, tw, th);
    let row_len = w as usize * ch;
    for _ in 0..h {
        match reader.next_row() {
            Ok(Some(row)) if row.data().len() == row_len => resampler.push_row(row.data()),
            Ok(_) => return Scaled::NotApplicable,
            Err(e) => {
                return Scaled::Refused(SegmentError(format!("cannot decode the image: {e}")));
            }
        }
    }
    // Read on to the end (IEND) as the full decoder does: a file cut after its last row is as
    // truncated as one cut before it.
    if let Err(e) = reader.finish() {
        return Scaled::Refused(SegmentError(format!("cannot decode the image: {e}")));
    }
    let (rgba, has_alpha) = resampler.finish();
    match oriented_photo(rgba, has_alpha, (w, h), (tw, th), orientation) {
        Some(photo) => Scaled::Done(photo),
        None => Scaled::NotApplicable,
    }
}

/// The photo from its downscaled pixels (`tw × th` RGBA) of a `w × h` source, turned upright by
/// its EXIF `orientation`; `None` when the buffer has the wrong size.
fn oriented_photo(
    rgba: Vec<u8>,
    has_alpha: bool,
    (w, h): (u32, u32),
    (tw, th): (u32, u32),
    orientation: Orientation,
) -> Option<Photo> {
    let small = RgbaImage::from_raw(tw, th, rgba)?;
    let mut small = DynamicImage::ImageRgba8(small);
    small.apply_orientation(orientation);
    let (ow, oh) = (small.width(), small.height());
    let swapped = ow != tw;
    Some(Photo {
        width: ow,
        height: oh,
        rgba: small.into_rgba8().into_raw(),
        has_alpha,
        source_size: if swapped { (h, w) } else { (w, h) },
    })
}

/// Whether `bytes` start like a JPEG file (start-of-image marker, then a marker).
fn is_jpeg(bytes: &[u8]) -> bool {
    bytes.starts_with(&[0xFF, 0xD8, 0xFF])
}

/// Refuses a JPEG that is cut off before its end. JPEG decoders fill the missing rows with grey
/// and call it a success, so a truncated download would be segmented and fitted as if it were the
/// photo. A complete JPEG has an end-of-image marker (FF D9) after its last start-of-scan marker
/// (FF DA); inside entropy-coded data an FF byte is always followed by 00 or a restart marker, so
/// neither can appear there by accident. (An EXIF thumbnail's markers come before the main
/// image's scans.) PNG and WebP decoders already fail on truncated data.
pub fn check_complete(bytes: &[u8]) -> Result<(), SegmentError> {
    if !is_jpeg(bytes) {
        return Ok(());
    }
    let last_scan = bytes.windows(2).rposition(|w| w == [0xFF, 0xDA]);
    let complete = last_scan.is_some_and(|sos| bytes[sos..].windows(2).any(|w| w == [0xFF, 0xD9]));
    if complete {
        Ok(())
    } else {
        Err(SegmentError::new(
            "the JPEG is truncated (the file ends before the image does): copy or download it again",
        ))
    }
}

/// Refuses a JPEG too short to hold the image its header claims. The decoders `image` and
/// `jpeg-decoder` use (Huffman coding only: they refuse arithmetic coding) spend at least one bit
/// on each 8×8 block of each component (its DC code, in the first scan that covers it), so a
/// complete file has at least that many bits. A grey image has `⌈w/8⌉·⌈h/8⌉` blocks; in a colour
/// one the component of the largest horizontal sampling is `w` wide and at least `h/4` high
/// (sampling factors are 1–4), so it alone has at least a quarter of that. Fuzzing found
/// sub-kilobyte files claiming 8222×4456 that decoded "successfully" into 36 MP of grey, and were
/// segmented as a photo; a cut-off download whose end marker survived is caught the same way.
fn check_jpeg_data_size(len: usize, w: u32, h: u32, grey: bool) -> Result<(), SegmentError> {
    let blocks = u64::from(w.div_ceil(8)) * u64::from(h.div_ceil(8));
    let min_blocks = if grey { blocks } else { blocks / 4 };
    let min_bytes = min_blocks / 8;
    if (len as u64) < min_bytes {
        return Err(SegmentError(format!(
            "the JPEG is truncated or corrupt: a {w}×{h} image needs at least {min_bytes} bytes \
             of data but the file has {len}: copy or download it again"
        )));
    }
    Ok(())
}

fn check_working_side(side: u32) -> Result<(), SegmentError> {
    if !(MIN_SIDE..=4096).contains(&side) {
        return Err(SegmentError(format!(
            "working side {side} is outside {MIN_SIDE}..=4096"
        )));
    }
    Ok(())
}

/// The size a file's header claims, checked before any pixel is decoded: each side within
/// [`MAX_DECODE_SIDE`] (the full decode's `image::Limits`), then [`check_source_size`].
fn check_header_size(w: u32, h: u32) -> Result<(), SegmentError> {
    if w > MAX_DECODE_SIDE || h > MAX_DECODE_SIDE {
        return Err(SegmentError(format!(
            "the image is {w}×{h}: a side exceeds the {MAX_DECODE_SIDE} pixel limit"
        )));
    }
    check_source_size(w, h)
}

fn check_source_size(w: u32, h: u32) -> Result<(), SegmentError> {
    if w == 0 || h == 0 {
        return Err(SegmentError(format!("the image is empty ({w}×{h})")));
    }
    if w < MIN_SIDE || h < MIN_SIDE {
        return Err(SegmentError(format!(
            "the image is {w}×{h}: too small to segment (at least {MIN_SIDE}×{MIN_SIDE})"
        )));
    }
    if u64::from(w) * u64::from(h) > MAX_PIXELS {
        return Err(SegmentError(format!(
            "the image claims {w}×{h} pixels, more than the {} MP limit \
             (refused before decoding: a decompression bomb or an absurdly large photo)",
            MAX_PIXELS / 1_000_000
        )));
    }
    Ok(())
}

/// Working size: the longest side shrunk to `side` (never enlarged), aspect kept.
fn target_size(w: u32, h: u32, side: u32) -> (u32, u32) {
    let longest = w.max(h);
    if longest <= side {
        return (w, h);
    }
    let s = f64::from(side) / f64::from(longest);
    let tw = ((f64::from(w) * s).round() as u32).max(1);
    let th = ((f64::from(h) * s).round() as u32).max(1);
    (tw, th)
}

/// Per output index, the source indices it covers and their area weights (sum 1).
fn area_weights(src: u32, dst: u32) -> Vec<(usize, Vec<f32>)> {
    let scale = f64::from(src) / f64::from(dst);
    (0..dst)
        .map(|o| {
            let a = f64::from(o) * scale;
            let b = (f64::from(o) + 1.0) * scale;
            let first = a.floor() as usize;
            let last = (b.ceil() as usize).min(src as usize);
            let w: Vec<f32> = (first..last)
                .map(|i| {
                    let lo = a.max(i as f64);
                    let hi = b.min(i as f64 + 1.0);
                    ((hi - lo).max(0.0) / scale) as f32
                })
                .collect();
            (first, w)
        })
        .collect()
}

/// Box filter with exact area weights from `ch`-channel 8-bit pixels to RGBA8, averaging colour
/// premultiplied by alpha so transparent pixels' colour does not bleed into the object's edge.
/// Returns the pixels and whether any source pixel had alpha below 255. [`AreaResampler`] does
/// the same a source row at a time.
pub fn area_resample(src: &[u8], w: u32, h: u32, ch: usize, tw: u32, th: u32) -> (Vec<u8>, bool) {
    let mut r = AreaResampler::new(w, h, ch, tw, th);
    // `max(1)`: an empty image (no caller passes one) gives an empty result, not a panic.
    for line in src.chunks_exact((w as usize * ch).max(1)).take(h as usize) {
        r.push_row(line);
    }
    r.finish()
}

/// [`area_resample`] fed one source row at a time, top to bottom: it holds the output and one
/// row, never the source image, so a decoder that yields rows (PNG) needs memory for the
/// working size only.
pub struct AreaResampler {
    w: usize,
    ch: usize,
    has_alpha: bool,
    mode: Resampling,
}

/// What [`AreaResampler`] does with each row.
enum Resampling {
    /// The size does not change: the RGBA8 output, converted a row at a time.
    Same(Vec<u8>),
    /// Area averaging.
    Area {
        tw: usize,
        /// Per output column: the first source column and the area weights from there.
        xw: Vec<(usize, Vec<f32>)>,
        /// Per output row: the first source row and the area weights from there.
        yw: Vec<(usize, Vec<f32>)>,
        /// The first output row the next source row can feed (rows arrive in order).
        oy0: usize,
        /// The next source row.
        y: usize,
        /// Premultiplied r, g, b and alpha per output pixel.
        acc: Vec<f32>,
        /// The current source row averaged across, per output column.
        row: Vec<f32>,
    },
}

impl AreaResampler {
    /// A resampler from `w × h` source pixels of `ch` channels (1 grey, 2 grey + alpha, 3 RGB,
    /// 4 RGBA) to `tw × th` RGBA.
    pub fn new(w: u32, h: u32, ch: usize, tw: u32, th: u32) -> AreaResampler {
        let (tw_, th_) = (tw as usize, th as usize);
        let mode = if (tw, th) == (w, h) {
            Resampling::Same(Vec::with_capacity(tw_ * th_ * 4))
        } else {
            Resampling::Area {
                tw: tw_,
                xw: area_weights(w, tw),
                yw: area_weights(h, th),
                oy0: 0,
                y: 0,
                acc: vec![0.0; tw_ * th_ * 4],
                row: vec![0.0; tw_ * 4],
            }
        };
        AreaResampler {
            w: w as usize,
            ch,
            has_alpha: false,
            mode,
        }
    }

    fn to_rgba(ch: usize, p: &[u8]) -> [f32; 4] {
        match ch {
            1 => [p[0].into(), p[0].into(), p[0].into(), 255.0],
            2 => [p[0].into(), p[0].into(), p[0].into(), p[1].into()],
            3 => [p[0].into(), p[1].into(), p[2].into(), 255.0],
            _ => [p[0].into(), p[1].into(), p[2].into(), p[3].into()],
        }
    }

    /// Adds the next source row (`w × ch` bytes; a shorter one is ignored).
    pub fn push_row(&mut self, line: &[u8]) {
        // One copy of the loops per channel count: with `ch` a constant the per-pixel
        // conversion folds away (5× faster than a run-time `ch`).
        match self.ch {
            1 => self.push::<1>(line),
            2 => self.push::<2>(line),
            3 => self.push::<3>(line),
            _ => self.push::<4>(line),
        }
    }

    fn push<const CH: usize>(&mut self, line: &[u8]) {
        let Some(line) = line.get(..self.w * CH) else {
            return;
        };
        if matches!(CH, 2 | 4) && !self.has_alpha {
            self.has_alpha = line.chunks_exact(CH).any(|p| p[CH - 1] < 255);
        }
        let (tw, xw, yw, oy0, y, acc, row) = match &mut self.mode {
            Resampling::Same(out) => {
                for p in line.chunks_exact(CH) {
                    out.extend(Self::to_rgba(CH, p).map(|v| v as u8));
                }
                return;
            }
            Resampling::Area {
                tw,
                xw,
                yw,
                oy0,
                y,
                acc,
                row,
            } => (*tw, xw, yw, oy0, y, acc, row),
        };
        let sy = *y;
        *y += 1;
        // The output rows this source row feeds: consecutive, from the first whose span
        // reaches it.
        while yw
            .get(*oy0)
            .is_some_and(|(first, ws)| first + ws.len() <= sy)
        {
            *oy0 += 1;
        }
        let fed = yw[*oy0..]
            .iter()
            .take_while(|(first, _)| *first <= sy)
            .count();
        if fed == 0 {
            return;
        }
        for (ox, (first, ws)) in xw.iter().enumerate() {
            let mut s = [0.0f32; 4];
            for (k, &wx) in ws.iter().enumerate() {
                let x = first + k;
                let p = Self::to_rgba(CH, &line[x * CH..x * CH + CH]);
                let a = p[3] * wx;
                s[0] += p[0] * a;
                s[1] += p[1] * a;
                s[2] += p[2] * a;
                s[3] += a;
            }
            row[ox * 4..ox * 4 + 4].copy_from_slice(&s);
        }
        for (oy, (first, ws)) in yw.iter().enumerate().skip(*oy0).take(fed) {
            let wt = ws[sy - first];
            let dst = &mut acc[oy * tw * 4..(oy + 1) * tw * 4];
            for (d, r) in dst.iter_mut().zip(row.iter()) {
                *d += r * wt;
            }
        }
    }

    /// The RGBA8 output and whether any source pixel had alpha below 255.
    pub fn finish(self) -> (Vec<u8>, bool) {
        let acc = match self.mode {
            Resampling::Same(out) => return (out, self.has_alpha),
            Resampling::Area { acc, .. } => acc,
        };
        let out = acc
            .chunks_exact(4)
            .flat_map(|p| {
                let a = p[3];
                let c = |v: f32| {
                    if a > 0.0 {
                        (v / a).round().clamp(0.0, 255.0) as u8
                    } else {
                        0
                    }
                };
                [c(p[0]), c(p[1]), c(p[2]), a.round().clamp(0.0, 255.0) as u8]
            })
            .collect();
        (out, self.has_alpha)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Corrupt JPEGs whose headers claim tens of megapixels, found by the fuzzers: an error,
    /// not a grey photo decoded at full scale.
    #[test]
    fn corrupt_large_jpegs_are_refused_not_filled_with_grey() {
        for bytes in [
            &include_bytes!(
                "../../fuzz/regressions/mask_image/corrupt-jpeg-claiming-11552x4120-decoded-in-full"
            )[..],
            &include_bytes!(
                "../../fuzz/regressions/decode_photo/corrupt-jpeg-claiming-2653x8510-decoded-in-full"
            )[..],
            // Decoded without an error, as 36 MP of grey, before the data-size bound.
            &include_bytes!(
                "../../fuzz/regressions/decode_photo/corrupt-jpeg-553-bytes-claiming-8222x4456-accepted-as-grey"
            )[..],
        ] {
            for side in [64, 128, 512] {
                let r = Photo::decode(bytes, side);
                assert!(
                    r.as_ref()
                        .is_err_and(|e| e.0.starts_with("the JPEG is truncated or corrupt")),
                    "{:?}",
                    r.map(|p| p.source_size())
                );
            }
        }
    }

    #[test]
    fn area_resample_averages_exactly() {
        // 4×2 RGB: left half black, right half white → 2×1 gives black and white; 3×1 gives grey
        // in the middle with exact third weights.
        let mut src = Vec::new();
        for _ in 0..2 {
            for x in 0..4 {
                let v = if x < 2 { 0 } else { 255 };
                src.extend([v, v, v]);
            }
        }
        let (out, alpha) = area_resample(&src, 4, 2, 3, 2, 1);
        assert_eq!(out, vec![0, 0, 0, 255, 255, 255, 255, 255]);
        assert!(!alpha);
        let (out, _) = area_resample(&src, 4, 2, 3, 3, 1);
        assert_eq!(&out[4..8], &[128, 128, 128, 255]);
        // Transparent red next to opaque green: colour stays green, alpha halves.
        let src = [255, 0, 0, 0, 0, 255, 0, 255];
        let (out, alpha) = area_resample(&src, 2, 1, 4, 1, 1);
        assert_eq!(out, vec![0, 255, 0, 128]);
        assert!(alpha);
        // Degenerate sizes are empty or transparent, never a panic.
        assert_eq!(area_resample(&[], 0, 0, 3, 0, 0).0.len(), 0);
        assert_eq!(area_resample(&[], 0, 4, 3, 2, 2).0, vec![0; 16]);
        assert_eq!(area_resample(&[], 4, 0, 3, 2, 2).0, vec![0; 16]);
    }

    #[test]
    fn a_truncated_jpeg_is_refused_and_a_complete_one_accepted() {
        let jpeg = small_photo_jpeg();
        assert!(Photo::decode(&jpeg, 512).is_ok());
        for keep in [jpeg.len() - 2, jpeg.len() * 95 / 100, jpeg.len() / 2, 700] {
            for decode in [Photo::decode, Photo::decode_full] {
                let Err(err) = decode(&jpeg[..keep], 512) else {
                    panic!("{keep} bytes: a truncated JPEG was accepted");
                };
                assert!(err.to_string().contains("truncated"), "{keep}: {err}");
                assert_eq!(err.to_string().lines().count(), 1);
            }
        }
        // Bytes after the end-of-image marker (some cameras append data) are fine.
        let mut padded = jpeg.clone();
        padded.extend_from_slice(b"trailing");
        assert!(Photo::decode(&padded, 512).is_ok());
    }

    /// A 64×48 colour gradient as a JPEG.
    fn small_photo_jpeg() -> Vec<u8> {
        let img =
            image::RgbImage::from_fn(64, 48, |x, y| image::Rgb([x as u8 * 4, y as u8 * 5, 90]));
        jpeg_of(image::DynamicImage::ImageRgb8(img))
    }

    /// `img` encoded as a JPEG by the `image` crate.
    fn jpeg_of(img: image::DynamicImage) -> Vec<u8> {
        let mut jpeg = Vec::new();
        img.write_to(
            &mut std::io::Cursor::new(&mut jpeg),
            image::ImageFormat::Jpeg,
        )
        .expect("encode");
        jpeg
    }

    #[test]
    fn a_jpeg_too_short_for_its_claimed_size_is_refused() {
        // A 64×48 photo whose frame header is edited to claim 8000×4000: the decoder would fill
        // 32 MP with grey from under a kilobyte of data and call it a photo.
        let mut jpeg = small_photo_jpeg();
        let sof = jpeg
            .windows(2)
            .position(|w| w == [0xFF, 0xC0])
            .expect("a baseline frame header");
        jpeg[sof + 5..sof + 9].copy_from_slice(&[0x0F, 0xA0, 0x1F, 0x40]); // height 4000, width 8000
        for decode in [Photo::decode, Photo::decode_full] {
            let Err(err) = decode(&jpeg, 512) else {
                panic!("{} bytes claiming 8000×4000 were accepted", jpeg.len());
            };
            let msg = err.to_string();
            assert!(
                msg.contains("truncated or corrupt") && msg.contains("8000×4000"),
                "{msg}"
            );
            assert_eq!(msg.lines().count(), 1);
        }
    }

    #[test]
    fn a_uniform_jpeg_is_not_too_short() {
        // The most compressible real images (one flat colour, grey and colour) are far above
        // the bound: it refuses only what no encoder can make.
        let grey = image::GrayImage::from_pixel(1024, 768, image::Luma([200]));
        let colour = image::RgbImage::from_pixel(1024, 768, image::Rgb([20, 90, 200]));
        for img in [
            image::DynamicImage::ImageLuma8(grey),
            image::DynamicImage::ImageRgb8(colour),
        ] {
            let jpeg = jpeg_of(img);
            let photo = Photo::decode(&jpeg, 512).expect("a flat JPEG decodes");
            assert_eq!((photo.width(), photo.height()), (512, 384));
        }
    }

    #[test]
    fn a_lossless_webp_with_an_overflowing_huffman_table_is_a_one_line_error() {
        // Found by the `decode_photo` fuzzer: image-webp 0.2.4 overflows a u16 on this table
        // and panics where overflow checks are on. The root Cargo.toml turns them off for
        // image-webp in every profile, so each build refuses it as the release build does.
        let webp = include_bytes!(
            "../../fuzz/regressions/decode_photo/webp-lossless-huffman-table-overflows-u16-in-image-webp-0.2.4"
        );
        for decode in [Photo::decode, Photo::decode_full] {
            let msg = decode(webp, 512).expect_err("a corrupt WebP").to_string();
            assert!(msg.starts_with("cannot decode the image"), "{msg}");
            assert_eq!(msg.lines().count(), 1, "{msg}");
        }
    }

    /// `img` encoded as a PNG by the `image` crate.
    fn png_of(img: &image::DynamicImage) -> Vec<u8> {
        let mut png = Vec::new();
        img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
            .expect("encode");
        png
    }

    #[test]
    fn a_png_decoded_row_by_row_is_the_full_decode() {
        // Every 8-bit layout, with transparency, at sizes that downscale by fractions and not
        // at all: the row path gives exactly the pixels of the full decode.
        let rgba = image::RgbaImage::from_fn(997, 613, |x, y| {
            image::Rgba([
                (x * 7) as u8,
                (y * 3) as u8,
                (x ^ y) as u8,
                if x % 97 < 9 { 0 } else { 255 },
            ])
        });
        let rgba = image::DynamicImage::ImageRgba8(rgba);
        let small = rgba.crop_imm(0, 0, 300, 200);
        let palette = {
            // Few colours: the encoder is free to write a palette; either way it must match.
            let grey = image::GrayImage::from_fn(640, 480, |x, y| {
                image::Luma([((x / 80 + y / 60) * 30) as u8])
            });
            image::DynamicImage::ImageLuma8(grey)
        };
        for img in [
            rgba.clone(),
            image::DynamicImage::ImageRgb8(rgba.to_rgb8()),
            image::DynamicImage::ImageLumaA8(rgba.to_luma_alpha8()),
            image::DynamicImage::ImageLuma8(rgba.to_luma8()),
            small,
            palette,
        ] {
            let png = png_of(&img);
            for side in [512, 256, 4096] {
                let rows = Photo::decode(&png, side).expect("row decode");
                let full = Photo::decode_full(&png, side).expect("full decode");
                assert_eq!((rows.width(), rows.height()), (full.width(), full.height()));
                assert_eq!(rows.source_size, full.source_size);
                assert_eq!(rows.has_alpha, full.has_alpha);
                assert!(rows.rgba == full.rgba, "{:?} at {side}", img.color());
            }
        }
    }

    #[test]
    fn a_truncated_or_corrupt_png_is_a_one_line_error() {
        let img = image::RgbImage::from_fn(800, 600, |x, y| {
            image::Rgb([(x * 5) as u8, (y * 7) as u8, (x * y) as u8])
        });
        let png = png_of(&image::DynamicImage::ImageRgb8(img));
        let mut flipped = png.clone();
        let mid = flipped.len() / 2;
        flipped[mid] ^= 0x55;
        for bad in [
            png[..png.len() / 2].to_vec(),
            png[..png.len() - 13].to_vec(),
            flipped,
        ] {
            assert!(Photo::decode_full(&bad, 512).is_err());
            let msg = Photo::decode(&bad, 512)
                .expect_err("a broken PNG")
                .to_string();
            assert_eq!(msg.lines().count(), 1, "{msg}");
        }
    }

    #[test]
    fn target_size_keeps_aspect_and_never_enlarges() {
        assert_eq!(target_size(4000, 3000, 512), (512, 384));
        assert_eq!(target_size(3000, 4000, 512), (384, 512));
        assert_eq!(target_size(100, 50, 512), (100, 50));
    }
}
