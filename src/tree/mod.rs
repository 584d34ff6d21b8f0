//! Trees (paper §3.5): semantic masks, the tree similarity loss (eq. 3) and the tree-structured
//! genetic algorithm with quality-estimation mutation (Fig. 8, Algorithm 3).
//!
//! The tree generator is not differentiable, so trees are fitted by a GA over a genome in
//! `[0, 1]^N` ([`genome_to_params`] maps it onto the generator's ranges). The GA is generic over
//! a fitness closure, so it is tested without rendering; the fitness used for trees is
//! [`similarity::TreeReference::similarity`] between the reference label image and the label
//! image of a generated tree.
//!
//! Label images use [`BACKGROUND`], [`BRANCH`] and [`LEAF`] (and
//! [`crate::mask::LabelImage::DONT_CARE`] for pixels that must not count).

pub mod bench;
pub mod carve;
pub mod envelope;
pub mod ga;
pub mod impostor;
pub mod labels;
pub mod mutation;
pub mod similarity;

use crate::generators::{GenError, ParamSpec, sanitize_params};
use std::fmt;

/// Label of background pixels.
pub const BACKGROUND: u8 = 0;
/// Label of branch and trunk pixels.
pub const BRANCH: u8 = 1;
/// Label of leaf pixels.
pub const LEAF: u8 = 2;

/// Something a tree fit cannot work with; the message says what and why.
#[derive(Clone, Debug, PartialEq)]
pub struct TreeError(pub String);

impl fmt::Display for TreeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for TreeError {}

impl From<GenError> for TreeError {
    fn from(e: GenError) -> Self {
        TreeError(e.to_string())
    }
}

/// An error unless `labels` is `view`'s size, worded "{what} W×H, the view W×H" (`what` names
/// the labels with its verb: "reference is").
pub(crate) fn check_view_size(
    labels: &crate::mask::LabelImage,
    view: &crate::camera::View,
    what: &str,
) -> Result<(), TreeError> {
    if (labels.width(), labels.height()) != (view.width, view.height) {
        return Err(TreeError(format!(
            "{what} {}×{}, the view {}×{}",
            labels.width(),
            labels.height(),
            view.width,
            view.height
        )));
    }
    Ok(())
}

/// Maps a genome in `[0, 1]^N` onto a generator's parameter ranges (clamped, whole-number kinds
/// rounded). Errors on a wrong length or a non-finite gene.
pub fn genome_to_params(spec: &[ParamSpec], genome: &[f64]) -> Result<Vec<f64>, TreeError> {
    if genome.len() != spec.len() {
        return Err(TreeError(format!(
            "genome has {} genes, the generator has {} parameters",
            genome.len(),
            spec.len()
        )));
    }
    let raw: Vec<f64> = spec
        .iter()
        .zip(genome)
        .map(|(s, &g)| s.min + g.clamp(0.0, 1.0) * (s.max - s.min))
        .collect();
    Ok(sanitize_params(spec, &raw)?)
}

/// The genome of a parameter vector: each value's position in its range (inverse of
/// [`genome_to_params`] up to rounding of whole-number kinds).
pub fn params_to_genome(spec: &[ParamSpec], params: &[f64]) -> Result<Vec<f64>, TreeError> {
    let params = sanitize_params(spec, params)?;
    Ok(spec
        .iter()
        .zip(&params)
        .map(|(s, &v)| {
            if s.max > s.min {
                (v - s.min) / (s.max - s.min)
            } else {
                0.0
            }
        })
        .collect())
}
