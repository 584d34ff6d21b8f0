//! Masks: the currency between segmentation, the renderer's losses and the fit.
//!
//! A [`Mask`] holds soft object coverage in `[0, 1]` per pixel (1 = object), or
//! [`Mask::DONT_CARE`] where the pixel must not count (a band of uncertainty around a segmented
//! edge, or pixels the user marked unknown). A [`LabelImage`] holds one small label per pixel for
//! multi-label work (building windows, tree branch/leaf masks). Both are row-major, top row first.

use std::fmt;

/// Largest side accepted for a mask or label image; larger inputs are refused, not allocated.
pub const MAX_SIDE: u32 = 8192;

/// A mask or label image that cannot be built.
#[derive(Clone, Debug, PartialEq)]
pub struct MaskError(pub String);

impl fmt::Display for MaskError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for MaskError {}

fn check_size(width: u32, height: u32, len: usize) -> Result<(), MaskError> {
    if width == 0 || height == 0 {
        return Err(MaskError(format!("image size {width}×{height} is empty")));
    }
    if width > MAX_SIDE || height > MAX_SIDE {
        return Err(MaskError(format!(
            "image size {width}×{height} exceeds {MAX_SIDE} pixels a side"
        )));
    }
    if len != width as usize * height as usize {
        return Err(MaskError(format!(
            "{len} values for a {width}×{height} image"
        )));
    }
    Ok(())
}

/// Soft object coverage per pixel, with "don't care" pixels.
#[derive(Clone, Debug, PartialEq)]
pub struct Mask {
    width: u32,
    height: u32,
    values: Vec<f32>,
}

impl Mask {
    /// The value of a pixel that must not count in losses or IoU.
    pub const DONT_CARE: f32 = -1.0;

    /// A mask from row-major values: each in `[0, 1]` or [`Mask::DONT_CARE`]. Values outside
    /// are refused (NaN included), so downstream code can trust the range.
    pub fn new(width: u32, height: u32, values: Vec<f32>) -> Result<Mask, MaskError> {
        check_size(width, height, values.len())?;
        if let Some((i, v)) = values
            .iter()
            .enumerate()
            .find(|&(_, &v)| !((0.0..=1.0).contains(&v) || v == Self::DONT_CARE))
        {
            return Err(MaskError(format!(
                "mask value {v} at pixel {i} is neither in [0, 1] nor DONT_CARE"
            )));
        }
        Ok(Mask {
            width,
            height,
            values,
        })
    }

    /// An all-background mask.
    pub fn empty(width: u32, height: u32) -> Result<Mask, MaskError> {
        Mask::new(width, height, vec![0.0; width as usize * height as usize])
    }

    /// A mask from 8-bit grey values: ≥ 128 is object, below is background; no don't-care.
    pub fn from_luma8(width: u32, height: u32, luma: &[u8]) -> Result<Mask, MaskError> {
        check_size(width, height, luma.len())?;
        Mask::new(
            width,
            height,
            luma.iter()
                .map(|&v| if v >= 128 { 1.0 } else { 0.0 })
                .collect(),
        )
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The values, row-major.
    pub fn values(&self) -> &[f32] {
        &self.values
    }

    /// Whether pixel `i` counts.
    pub fn cares(&self, i: usize) -> bool {
        self.values[i] != Self::DONT_CARE
    }

    /// Sum of object coverage over the pixels that count.
    pub fn area(&self) -> f64 {
        self.values
            .iter()
            .filter(|&&v| v != Self::DONT_CARE)
            .map(|&v| f64::from(v))
            .sum()
    }

    /// 8-bit grey form for saving: object 255, background 0, don't care 128.
    pub fn to_luma8(&self) -> Vec<u8> {
        self.values
            .iter()
            .map(|&v| {
                if v == Self::DONT_CARE {
                    128
                } else {
                    (v * 255.0).round() as u8
                }
            })
            .collect()
    }
}

/// One label per pixel (0 = background; meaning of other labels is the caller's), with
/// [`LabelImage::DONT_CARE`] for pixels that must not count.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LabelImage {
    width: u32,
    height: u32,
    labels: Vec<u8>,
}

impl LabelImage {
    /// The label of a pixel that must not count.
    pub const DONT_CARE: u8 = 255;

    /// A label image from row-major labels.
    pub fn new(width: u32, height: u32, labels: Vec<u8>) -> Result<LabelImage, MaskError> {
        check_size(width, height, labels.len())?;
        Ok(LabelImage {
            width,
            height,
            labels,
        })
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The labels, row-major.
    pub fn labels(&self) -> &[u8] {
        &self.labels
    }

    /// The binary mask of one label (don't-care pixels stay don't care).
    pub fn mask_of(&self, label: u8) -> Mask {
        let values = self
            .labels
            .iter()
            .map(|&l| match l {
                Self::DONT_CARE => Mask::DONT_CARE,
                l if l == label => 1.0,
                _ => 0.0,
            })
            .collect();
        Mask {
            width: self.width,
            height: self.height,
            values,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refuses_bad_sizes_and_values() {
        assert!(Mask::new(0, 4, vec![]).is_err());
        assert!(Mask::new(2, 2, vec![0.0; 3]).is_err());
        assert!(Mask::new(1, 1, vec![f32::NAN]).is_err());
        assert!(Mask::new(1, 1, vec![1.5]).is_err());
        assert!(Mask::new(MAX_SIDE + 1, 1, vec![0.0; MAX_SIDE as usize + 1]).is_err());
        assert!(Mask::new(1, 2, vec![Mask::DONT_CARE, 0.5]).is_ok());
    }

    #[test]
    fn label_mask_keeps_dont_care() {
        let l = LabelImage::new(3, 1, vec![0, 2, LabelImage::DONT_CARE]).unwrap();
        assert_eq!(l.mask_of(2).values(), &[0.0, 1.0, Mask::DONT_CARE]);
        assert_eq!(l.mask_of(2).to_luma8(), vec![0, 255, 128]);
    }
}
