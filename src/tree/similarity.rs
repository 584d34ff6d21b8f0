//! Tree similarity (paper §3.5.1, eq. 3): compares two semantic tree masks stripe by stripe and
//! multiplies by the regularisation factors `min(c, c_ref) / max(c, c_ref)`.
//!
//! Each mask's tree (the rows holding branch or leaf pixels) is cut into `n` horizontal stripes
//! (the paper: 20–30). Per stripe ([`Stripe`]):
//! - `[a, d)`: crown borders, the first and one past the last occupied column;
//! - `[b, c)`: dense crown borders, the longest run of columns whose leaf pixels fill more than
//!   75 % of the stripe's height;
//! - `B`, `L`: the shares of branch and leaf pixels in the stripe's `[a, d)` box; the stripe is
//!   trunk when `B / L` exceeds [`SimilarityConfig::trunk_ratio`], crown otherwise.
//!
//! Stripes are compared stripe by stripe (numbers the paper leaves out follow the authors' code,
//! see the notes): the overlap (intersection over union) of the crown borders and of the dense
//! borders, the latter weighted 3×, scaled by `max(0.01, 1 − 3 |Δ branch share|)`; trunk
//! stripes are scored on their borders alone. Each pair of stripes at the same height counts
//! by the rows they share, so `TSim` is the row-weighted mean score over the rows either tree
//! spans (identical masks pair each stripe with itself and score 1). The result is
//! `TSim · Π_c min(c, c_ref) / max(c, c_ref)` over height, width, branch density, leaf density
//! and, when both sides give them, leaf size and branch-graph vertex count ([`TreeTraits`]).
//!
//! Every term is symmetric in its two masks, so `similarity(a, b) == similarity(b, a)`, and it
//! is exactly 1 for identical masks.

use super::{BRANCH, LEAF, TreeError};
use crate::mask::LabelImage;

/// Knobs of the similarity; the defaults are the paper's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SimilarityConfig {
    /// Number of horizontal stripes (paper: 20–30).
    pub stripes: usize,
    /// Share of leaf pixels in a column of a stripe above which the column is dense crown
    /// (paper: 75 %).
    pub dense_share: f64,
    /// A stripe is trunk when its branch pixels outnumber its leaf pixels by more than this.
    pub trunk_ratio: f64,
    /// Weight of the dense crown overlap against the crown border overlap.
    pub dense_weight: f64,
}

impl Default for SimilarityConfig {
    fn default() -> Self {
        SimilarityConfig {
            stripes: 24,
            dense_share: 0.75,
            trunk_ratio: 1.0,
            dense_weight: 3.0,
        }
    }
}

/// Characteristics of a tree that a mask does not show; `None` leaves the factor out.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TreeTraits {
    /// Average leaf size (any unit, the same on both sides).
    pub leaf_size: Option<f64>,
    /// Number of vertices of the branch graph (the paper recommends giving it, §3.5.1).
    pub graph_vertices: Option<f64>,
}

/// What one horizontal stripe of a tree mask holds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stripe {
    /// Top and bottom row of the stripe (fractional, in pixels).
    pub rows: (f64, f64),
    /// Crown borders `[a, d)` in columns; `None` when the stripe holds no tree pixel.
    pub crown: Option<(f64, f64)>,
    /// Dense crown borders `[b, c)` in columns; `None` when no column is dense.
    pub dense: Option<(f64, f64)>,
    /// Share of branch pixels in the stripe's crown box.
    pub branch: f64,
    /// Share of leaf pixels in the stripe's crown box.
    pub leaf: f64,
}

impl Stripe {
    /// Whether the stripe is trunk rather than crown (by the ratio B / L).
    pub fn is_trunk(&self, trunk_ratio: f64) -> bool {
        self.branch > trunk_ratio * self.leaf
    }

    /// Share of branch pixels among the tree pixels of the stripe.
    fn branch_share(&self) -> f64 {
        let t = self.branch + self.leaf;
        if t > 0.0 { self.branch / t } else { 0.0 }
    }
}

/// Stripes and whole-tree measures of one mask.
#[derive(Clone, Debug, PartialEq)]
pub struct TreeProfile {
    /// The stripes, top first.
    pub stripes: Vec<Stripe>,
    /// Height of the tree's bounding box in pixels.
    pub height: f64,
    /// Width of the tree's bounding box in pixels.
    pub width: f64,
    /// Branch pixels over the bounding box area.
    pub branch_density: f64,
    /// Leaf pixels over the bounding box area.
    pub leaf_density: f64,
    /// Number of branch pixels.
    pub branch_pixels: usize,
    /// Number of leaf pixels.
    pub leaf_pixels: usize,
}

/// The stripes and measures of a tree mask, or `None` when it holds no branch or leaf pixel.
pub fn profile(labels: &LabelImage, cfg: &SimilarityConfig) -> Option<TreeProfile> {
    let w = labels.width() as usize;
    let h = labels.height() as usize;
    let px = labels.labels();
    let is_tree = |l: u8| l == BRANCH || l == LEAF;
    // Bounding box of the tree.
    let mut top = usize::MAX;
    let mut bottom = 0;
    let mut left = usize::MAX;
    let mut right = 0;
    let (mut nb, mut nl) = (0usize, 0usize);
    for y in 0..h {
        for (x, &l) in px[y * w..(y + 1) * w].iter().enumerate() {
            if is_tree(l) {
                top = top.min(y);
                bottom = bottom.max(y);
                left = left.min(x);
                right = right.max(x);
                if l == BRANCH {
                    nb += 1;
                } else {
                    nl += 1;
                }
            }
        }
    }
    if top == usize::MAX {
        return None;
    }
    let tree_h = (bottom + 1 - top) as f64;
    let tree_w = (right + 1 - left) as f64;
    let n = cfg.stripes.max(1);
    let mut branch_cols = vec![0u32; w];
    let mut leaf_cols = vec![0u32; w];
    let mut stripes = Vec::with_capacity(n);
    for i in 0..n {
        let r0 = top as f64 + tree_h * i as f64 / n as f64;
        let r1 = top as f64 + tree_h * (i + 1) as f64 / n as f64;
        // A pixel row belongs to the stripe holding its centre.
        let y0 = (r0 - 0.5).ceil().max(0.0) as usize;
        let y1 = ((r1 - 0.5).ceil().max(0.0) as usize).min(h);
        branch_cols.fill(0);
        leaf_cols.fill(0);
        for y in y0..y1 {
            for (x, &l) in px[y * w..(y + 1) * w].iter().enumerate() {
                match l {
                    BRANCH => branch_cols[x] += 1,
                    LEAF => leaf_cols[x] += 1,
                    _ => {}
                }
            }
        }
        let rows = (y1.saturating_sub(y0)) as f64;
        let occupied = |x: usize| branch_cols[x] + leaf_cols[x] > 0;
        let a = (0..w).find(|&x| occupied(x));
        let d = (0..w).rev().find(|&x| occupied(x)).map(|x| x + 1);
        let (crown, branch, leaf) = match (a, d) {
            (Some(a), Some(d)) => {
                let area = rows * (d - a) as f64;
                let b: u32 = branch_cols[a..d].iter().sum();
                let l: u32 = leaf_cols[a..d].iter().sum();
                (
                    Some((a as f64, d as f64)),
                    f64::from(b) / area,
                    f64::from(l) / area,
                )
            }
            _ => (None, 0.0, 0.0),
        };
        // Longest run of dense columns (> dense_share leaf pixels).
        let dense_col = |x: usize| rows > 0.0 && f64::from(leaf_cols[x]) > cfg.dense_share * rows;
        let mut dense = None;
        let mut best = 0;
        let mut x = 0;
        while x < w {
            if dense_col(x) {
                let start = x;
                while x < w && dense_col(x) {
                    x += 1;
                }
                if x - start > best {
                    best = x - start;
                    dense = Some((start as f64, x as f64));
                }
            } else {
                x += 1;
            }
        }
        stripes.push(Stripe {
            rows: (r0, r1),
            crown,
            dense,
            branch,
            leaf,
        });
    }
    let area = tree_h * tree_w;
    Some(TreeProfile {
        stripes,
        height: tree_h,
        width: tree_w,
        branch_density: nb as f64 / area,
        leaf_density: nl as f64 / area,
        branch_pixels: nb,
        leaf_pixels: nl,
    })
}

/// Intersection over union of two intervals (1 for two empty ones at the same place).
fn interval_iou(a: (f64, f64), b: (f64, f64)) -> f64 {
    let inter = (a.1.min(b.1) - a.0.max(b.0)).max(0.0);
    let union = a.1.max(b.1) - a.0.min(b.0);
    if union > 0.0 { inter / union } else { 1.0 }
}

/// The regularisation factor of eq. 3: `min(c, c_ref) / max(c, c_ref)`; 1 when both are 0.
pub fn ratio_factor(c: f64, c_ref: f64) -> f64 {
    let (lo, hi) = (c.min(c_ref), c.max(c_ref));
    if hi <= 0.0 { 1.0 } else { (lo / hi).max(0.0) }
}

/// The score of two stripes, in `[0, 1]`, before weighting by their vertical overlap.
fn stripe_score(s: &Stripe, r: &Stripe, cfg: &SimilarityConfig) -> f64 {
    let (sc, rc) = match (s.crown, r.crown) {
        (None, None) => return 1.0,
        (Some(sc), Some(rc)) => (sc, rc),
        _ => return 0.0,
    };
    let borders = interval_iou(sc, rc);
    let share = (1.0 - 3.0 * (s.branch_share() - r.branch_share()).abs()).max(0.01);
    match (s.is_trunk(cfg.trunk_ratio), r.is_trunk(cfg.trunk_ratio)) {
        // Trunk stripes: where the trunk is and how wide.
        (true, true) => borders,
        (false, false) => {
            let dense = match (s.dense, r.dense) {
                (None, None) => 1.0,
                (Some(a), Some(b)) => interval_iou(a, b),
                _ => 0.0,
            };
            share * (borders + cfg.dense_weight * dense) / (1.0 + cfg.dense_weight)
        }
        // Trunk against crown: half credit for the borders, so the GA can still move towards
        // the right outline.
        _ => 0.5 * share * borders,
    }
}

/// TSim: stripe scores weighted by how many rows the two stripes share, over the rows either
/// tree spans. Stripe `i` of one tree meets the stripes of the other at the same height, so a
/// tree shifted or stretched vertically by less than a stripe loses a little, not everything;
/// rows only one tree covers score 0.
fn tsim(a: &TreeProfile, b: &TreeProfile, cfg: &SimilarityConfig) -> f64 {
    let span = |p: &TreeProfile| {
        let first = p.stripes.first().map_or(0.0, |s| s.rows.0);
        let last = p.stripes.last().map_or(0.0, |s| s.rows.1);
        (first, last)
    };
    let (sa, sb) = (span(a), span(b));
    let total = sa.1.max(sb.1) - sa.0.min(sb.0);
    if total <= 0.0 {
        return 0.0;
    }
    let mut sum = 0.0;
    let mut j0 = 0;
    for s in &a.stripes {
        // Stripes are sorted top to bottom: skip those of `b` entirely above `s`.
        while j0 < b.stripes.len() && b.stripes[j0].rows.1 <= s.rows.0 {
            j0 += 1;
        }
        for r in b.stripes[j0..].iter().take_while(|r| r.rows.0 < s.rows.1) {
            let overlap = s.rows.1.min(r.rows.1) - s.rows.0.max(r.rows.0);
            if overlap > 0.0 {
                sum += overlap * stripe_score(s, r, cfg);
            }
        }
    }
    sum / total
}

/// The parts of one similarity value, for reports and tests.
#[derive(Clone, Debug, PartialEq)]
pub struct SimilarityBreakdown {
    /// Mean stripe score (the paper's TSim).
    pub tsim: f64,
    /// Regularisation factors by name, each in `[0, 1]`.
    pub factors: Vec<(&'static str, f64)>,
    /// `tsim` times all factors.
    pub value: f64,
}

/// Compares two profiles (symmetric).
pub fn compare(
    a: &TreeProfile,
    a_traits: &TreeTraits,
    b: &TreeProfile,
    b_traits: &TreeTraits,
    cfg: &SimilarityConfig,
) -> SimilarityBreakdown {
    let tsim = tsim(a, b, cfg);
    let mut factors = vec![
        ("height", ratio_factor(a.height, b.height)),
        ("width", ratio_factor(a.width, b.width)),
        (
            "branch_density",
            ratio_factor(a.branch_density, b.branch_density),
        ),
        ("leaf_density", ratio_factor(a.leaf_density, b.leaf_density)),
    ];
    if let (Some(x), Some(y)) = (a_traits.leaf_size, b_traits.leaf_size) {
        factors.push(("leaf_size", ratio_factor(x, y)));
    }
    if let (Some(x), Some(y)) = (a_traits.graph_vertices, b_traits.graph_vertices) {
        factors.push(("graph_vertices", ratio_factor(x, y)));
    }
    let value = factors.iter().fold(tsim, |acc, &(_, f)| acc * f);
    SimilarityBreakdown {
        tsim,
        factors,
        value,
    }
}

/// A reference tree mask, checked and profiled once, to score many generated trees against.
#[derive(Clone, Debug)]
pub struct TreeReference {
    profile: TreeProfile,
    traits: TreeTraits,
    cfg: SimilarityConfig,
    size: (u32, u32),
}

impl TreeReference {
    /// Profiles a reference mask. Errors when it cannot guide a fit: no tree pixel at all, no
    /// leaf pixel, no branch pixel, a stripe count outside 1..=1000, or a non-finite or
    /// negative trait.
    pub fn new(
        labels: &LabelImage,
        traits: TreeTraits,
        cfg: SimilarityConfig,
    ) -> Result<TreeReference, TreeError> {
        if cfg.stripes == 0 || cfg.stripes > 1000 {
            return Err(TreeError(format!(
                "{} stripes; use 1..=1000 (the paper uses 20–30)",
                cfg.stripes
            )));
        }
        if !(cfg.dense_share.is_finite()
            && cfg.trunk_ratio.is_finite()
            && cfg.dense_weight.is_finite()
            && cfg.dense_weight >= 0.0)
        {
            return Err(TreeError("similarity settings must be finite".into()));
        }
        for (name, v) in [
            ("leaf size", traits.leaf_size),
            ("branch graph vertex count", traits.graph_vertices),
        ] {
            if let Some(v) = v
                && !(v.is_finite() && v >= 0.0)
            {
                return Err(TreeError(format!(
                    "reference {name} {v} is not a finite, non-negative number"
                )));
            }
        }
        let profile = profile(labels, &cfg).ok_or_else(|| {
            TreeError("the reference mask has no tree in it: no branch or leaf pixel".into())
        })?;
        if profile.leaf_pixels == 0 {
            return Err(TreeError(
                "the reference mask has no leaf pixels (label 2): check the colour thresholds"
                    .into(),
            ));
        }
        if profile.branch_pixels == 0 {
            return Err(TreeError(
                "the reference mask has no branch pixels (label 1): check the colour thresholds"
                    .into(),
            ));
        }
        Ok(TreeReference {
            profile,
            traits,
            cfg,
            size: (labels.width(), labels.height()),
        })
    }

    /// The reference's profile.
    pub fn profile(&self) -> &TreeProfile {
        &self.profile
    }

    /// Similarity of a generated tree's mask to the reference, in `[0, 1]`, with its parts. An
    /// empty candidate scores 0; a candidate of another size is an error.
    pub fn breakdown(
        &self,
        candidate: &LabelImage,
        traits: &TreeTraits,
    ) -> Result<SimilarityBreakdown, TreeError> {
        if (candidate.width(), candidate.height()) != self.size {
            return Err(TreeError(format!(
                "candidate mask is {}×{}, the reference {}×{}",
                candidate.width(),
                candidate.height(),
                self.size.0,
                self.size.1
            )));
        }
        Ok(match profile(candidate, &self.cfg) {
            None => SimilarityBreakdown {
                tsim: 0.0,
                factors: Vec::new(),
                value: 0.0,
            },
            Some(p) => compare(&p, traits, &self.profile, &self.traits, &self.cfg),
        })
    }

    /// [`TreeReference::breakdown`]'s value alone: the fitness of the GA.
    pub fn similarity(
        &self,
        candidate: &LabelImage,
        traits: &TreeTraits,
    ) -> Result<f64, TreeError> {
        Ok(self.breakdown(candidate, traits)?.value)
    }
}
