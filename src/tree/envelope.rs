//! The crown envelope of a tree label image, and GA seeds that match it (issue 14: "the fit
//! must reproduce the crown's outline — width, height, where it starts, asymmetry, density —
//! before the branch structure").
//!
//! [`Envelope::measure`] reads a few numbers off a label image, all relative to the tree's
//! height in pixels so that they compare across scales: where the foliage starts above the
//! foot, how wide it is, how far its centre sits to the side of the trunk's foot, how high its
//! mass is, and how densely it fills its own outline. [`envelope_seeds`] takes each preset of
//! the tree generator and corrects, by a few rounds of render → measure → adjust, the genes
//! that set those numbers (height, bare trunk, first-level branch length and envelope width,
//! envelope peak, trunk bend, leaves per twig), so the GA's first population holds trees of
//! the photo's crown outline with every preset's branching. The GA then only has to refine.

use super::impostor::TreeImpostor;
use super::{BRANCH, LEAF, TreeError, genome_to_params, params_to_genome};
use crate::generators::tree::{TreeGenerator, idx};
use crate::generators::{Generator, Lod};
use crate::mask::LabelImage;

/// The crown envelope of a label image (see the module doc); lengths are fractions of the
/// tree's height in pixels (foot row to top row).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Envelope {
    /// The tree's height, pixels (rows from the top tree pixel to the foot).
    pub height_px: f64,
    /// Where the foliage starts above the foot (its 2 % lowest leaf pixels left out).
    pub crown_base: f64,
    /// Width of the foliage (its 2 % leftmost and 2 % rightmost leaf pixels left out).
    pub width: f64,
    /// The foliage's mean column minus the foot's column (positive: right of the trunk).
    pub offset: f64,
    /// The foliage's mean height above the foot.
    pub centroid: f64,
    /// Leaf pixels over the area between each row's outermost leaf pixels.
    pub fill: f64,
}

/// Share of leaf pixels left out at each end when measuring extents (stray leaves).
const TAIL: f64 = 0.02;

impl Envelope {
    /// Measures a label image's envelope; `None` without tree or leaf pixels.
    pub fn measure(labels: &LabelImage) -> Option<Envelope> {
        let w = labels.width() as usize;
        let px = labels.labels();
        let rows = px.len() / w.max(1);
        let is_tree = |l: u8| l == BRANCH || l == LEAF;
        let top = (0..rows).find(|&y| px[y * w..(y + 1) * w].iter().any(|&l| is_tree(l)))?;
        let bottom = (0..rows)
            .rev()
            .find(|&y| px[y * w..(y + 1) * w].iter().any(|&l| is_tree(l)))?;
        let foot_row = &px[bottom * w..(bottom + 1) * w];
        let first = foot_row.iter().position(|&l| is_tree(l))?;
        let last = foot_row.iter().rposition(|&l| is_tree(l))?;
        let foot_x = (first + last + 1) as f64 / 2.0;
        let foot_y = (bottom + 1) as f64;
        let height_px = (bottom + 1 - top) as f64;
        let (mut xs, mut ys) = (Vec::new(), Vec::new());
        let mut span = 0usize;
        for y in 0..rows {
            let row = &px[y * w..(y + 1) * w];
            if let (Some(a), Some(b)) = (
                row.iter().position(|&l| l == LEAF),
                row.iter().rposition(|&l| l == LEAF),
            ) {
                span += b + 1 - a;
            }
            for (x, _) in row.iter().enumerate().filter(|(_, l)| **l == LEAF) {
                xs.push(x as f64 + 0.5);
                ys.push(y as f64 + 0.5);
            }
        }
        if xs.is_empty() {
            return None;
        }
        let n = xs.len() as f64;
        let (mean_x, mean_y) = (xs.iter().sum::<f64>() / n, ys.iter().sum::<f64>() / n);
        let quantile = |v: &mut Vec<f64>, q: f64| {
            v.sort_by(f64::total_cmp);
            v[((q * (v.len() - 1) as f64).round() as usize).min(v.len() - 1)]
        };
        let (x0, x1) = (quantile(&mut xs, TAIL), quantile(&mut xs, 1.0 - TAIL));
        let low = quantile(&mut ys, 1.0 - TAIL);
        Some(Envelope {
            height_px,
            crown_base: (foot_y - low).max(0.0) / height_px,
            width: (x1 - x0) / height_px,
            offset: (mean_x - foot_x) / height_px,
            centroid: (foot_y - mean_y) / height_px,
            fill: n / span.max(1) as f64,
        })
    }
}

/// Rounds of render → measure → adjust per preset in [`envelope_seeds`].
pub const ENVELOPE_ROUNDS: usize = 4;

/// The generator's presets as genomes, each adjusted over [`ENVELOPE_ROUNDS`] rounds so that
/// its impostor (through `impostor`'s view, seed gene `seed`) has `target`'s envelope: the
/// tree's height in pixels, where the crown starts, its width, side offset, mass height and
/// fill. Genomes whose tree cannot be built or shows no leaves are left as they last were.
pub fn envelope_seeds(
    target: &Envelope,
    impostor: &mut TreeImpostor,
    seed: Option<u32>,
) -> Result<Vec<Vec<f64>>, TreeError> {
    let g = TreeGenerator;
    let spec = g.params();
    let mut out = Vec::new();
    for preset in g.presets() {
        let mut params = preset.values.clone();
        if let Some(s) = seed {
            params[idx::SEED] = f64::from(s);
        }
        for _ in 0..ENVELOPE_ROUNDS {
            let Ok(mesh) = g.generate(&params, Lod::Low) else {
                break;
            };
            let Some(e) = Envelope::measure(&impostor.render(&mesh)?) else {
                break;
            };
            adjust(&mut params, &e, target);
            params = genome_to_params(spec, &params_to_genome(spec, &params)?)?;
        }
        out.push(params_to_genome(spec, &params)?);
    }
    Ok(out)
}

/// One correction of `params` from the envelope `e` its tree has towards `target`. Each gene
/// moves by the measured error through a rough, monotone model of its effect; the rounds of
/// [`envelope_seeds`] make up for the model's error.
fn adjust(params: &mut [f64], e: &Envelope, target: &Envelope) {
    // Size: the tree's height in pixels scales with the height gene (all lengths are
    // relative to it).
    params[idx::HEIGHT] *= target.height_px / e.height_px;
    // Where the crown starts: the bare trunk's share, moved by the error.
    params[idx::BASE_SIZE] += 0.8 * (target.crown_base - e.crown_base);
    // Width: first-level branches (and the pruning envelope, when it prunes) scale it.
    let ratio = (target.width / e.width.max(1e-3)).clamp(0.5, 2.0);
    params[idx::LEVEL0 + 1] *= ratio;
    params[idx::PRUNE_WIDTH] *= ratio;
    // Mass height: the envelope's peak (within the crown) follows the centroid's error.
    let crown = (1.0 - target.crown_base).max(0.1);
    params[idx::PRUNE_PEAK] += (target.centroid - e.centroid) / crown;
    // Side offset: a trunk bent by `c` radians in all leans its top by about `c / 2` of its
    // height, to −x for positive `c` (the bend is about +Z, the camera looks along −Z).
    params[idx::TRUNK_CURVE] -= (2.0 * (target.offset - e.offset)).to_degrees();
    // Fill: leaves per twig, in proportion.
    let fill = (target.fill / e.fill.max(1e-3)).clamp(0.5, 2.0);
    params[idx::LEAVES] = (params[idx::LEAVES] * fill).max(1.0);
}
