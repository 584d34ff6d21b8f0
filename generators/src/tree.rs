//! Rule-based tree generator after Weber & Penn (1995), the paper's non-differentiable case
//! (§3.5): a trunk that may split, up to three levels of child branches placed along their
//! parents with length, down angle, rotation, curvature, taper, tropism and a pruning envelope,
//! and leaf cards on the last level. A seed parameter drives every random choice, so a parameter
//! vector always gives the same tree.
//!
//! The generator is deliberately not differentiable: a small parameter change moves whole
//! branches (the paper's reason for using a genetic algorithm). It is built to be fast because
//! the GA evaluates thousands of trees: no allocation per vertex beyond the output mesh, a
//! hand-rolled RNG, and coarse tubes and merged leaf cards at [`Lod::Low`].
//!
//! Output: branches as closed tubes (a ring per polyline point, capped at both ends), leaves as
//! double-sided cards (four welded corners, two triangles a side, back side wound the other
//! way). Parts: `trunk`, `branch`, `leaf`.

use crate::rng::SplitMix64 as Rng;
use crate::{GenError, Generator, Lod, Mesh, ParamKind, ParamSpec, Part, Preset, sanitize_params};
use glam::{Quat, Vec2, Vec3};
use std::f32::consts::{PI, TAU};

/// The tree generator (registered as `tree`).
pub struct TreeGenerator;

/// Crown shapes of Weber & Penn: how a first-level branch's length depends on where it sits on
/// the trunk.
pub const SHAPES: &[&str] = &[
    "conical",
    "spherical",
    "hemispherical",
    "cylindrical",
    "tapered_cylindrical",
    "flame",
    "inverse_conical",
    "tend_flame",
];

/// Index of each parameter in the vector (the order of [`TreeGenerator::params`]).
pub mod idx {
    /// Random seed for every random choice.
    pub const SEED: usize = 0;
    /// Tree height (m).
    pub const HEIGHT: usize = 1;
    /// Trunk base radius as a fraction of the height.
    pub const TRUNK_RADIUS: usize = 2;
    /// How much a stem narrows from base to tip (0 = cylinder, 1 = cone).
    pub const TAPER: usize = 3;
    /// Bare part of the trunk below the first branch, as a fraction of the height.
    pub const BASE_SIZE: usize = 4;
    /// Crown shape, an index into [`super::SHAPES`].
    pub const SHAPE: usize = 5;
    /// Branch levels below the trunk (1–3).
    pub const LEVELS: usize = 6;
    /// Total bend of the trunk (degrees).
    pub const TRUNK_CURVE: usize = 7;
    /// Number of extra trunks the trunk splits into.
    pub const SPLITS: usize = 8;
    /// Where the trunk splits, as a fraction of its length.
    pub const SPLIT_HEIGHT: usize = 9;
    /// Angle between split trunks and the main axis (degrees).
    pub const SPLIT_ANGLE: usize = 10;
    /// Tropism: branches bend up (> 0) or droop (< 0).
    pub const TROPISM: usize = 11;
    /// Pruning envelope strength (0 = none, 1 = branches end inside the envelope).
    pub const PRUNE_RATIO: usize = 12;
    /// Pruning envelope half width as a fraction of the height.
    pub const PRUNE_WIDTH: usize = 13;
    /// Height of the envelope's widest point, as a fraction of the crown height.
    pub const PRUNE_PEAK: usize = 14;
    /// Exponent relating a child's radius to its length ratio.
    pub const RATIO_POWER: usize = 15;
    /// Random variation of lengths and angles (0–1).
    pub const JITTER: usize = 16;
    /// First of the per-level blocks; level `l` (1-based) starts at `LEVEL0 + (l - 1) * PER_LEVEL`.
    pub const LEVEL0: usize = 17;
    /// Parameters per branch level: branches, length, down angle, rotate, curve.
    pub const PER_LEVEL: usize = 5;
    /// Leaves per last-level stem.
    pub const LEAVES: usize = LEVEL0 + 3 * PER_LEVEL;
    /// Length of a leaf card as a fraction of the tree height. A card stands for a cluster of
    /// leaves (v2: five times the v1 single-leaf size), so that crowns read as crowns: with
    /// single leaves the same parameters under another seed overlapped by IoU-64 0.2–0.4, so no
    /// fit could score better than that.
    pub const LEAF_SIZE: usize = LEAVES + 1;
    /// Leaf width over length.
    pub const LEAF_ASPECT: usize = LEAVES + 2;
    /// Number of parameters.
    pub const COUNT: usize = LEAVES + 3;
}

#[allow(
    clippy::too_many_arguments,
    reason = "one positional row per parameter keeps the table below readable"
)]
const fn spec(
    name: &'static str,
    label: &'static str,
    group: &'static str,
    unit: &'static str,
    min: f64,
    max: f64,
    default: f64,
    kind: ParamKind,
) -> ParamSpec {
    ParamSpec {
        name,
        label,
        group,
        unit,
        min,
        max,
        default,
        kind,
    }
}

const C: ParamKind = ParamKind::Continuous;
const I: ParamKind = ParamKind::Integer;

static PARAMS: [ParamSpec; idx::COUNT] = [
    spec("seed", "Seed", "Tree", "", 0.0, 999.0, 1.0, I),
    spec("height", "Height", "Tree", "m", 2.0, 30.0, 10.0, C),
    spec(
        "trunk_radius",
        "Trunk radius / height",
        "Trunk",
        "",
        0.005,
        0.06,
        0.025,
        C,
    ),
    spec("taper", "Taper", "Trunk", "", 0.0, 1.0, 0.8, C),
    spec("base_size", "Bare trunk", "Trunk", "", 0.0, 0.8, 0.3, C),
    spec(
        "shape",
        "Crown shape",
        "Tree",
        "",
        0.0,
        7.0,
        7.0,
        ParamKind::Categorical(SHAPES),
    ),
    spec("levels", "Branch levels", "Tree", "", 1.0, 3.0, 2.0, I),
    spec(
        "trunk_curve",
        "Trunk bend",
        "Trunk",
        "°",
        -60.0,
        60.0,
        0.0,
        C,
    ),
    spec("splits", "Trunk splits", "Trunk", "", 0.0, 3.0, 0.0, I),
    spec(
        "split_height",
        "Split height",
        "Trunk",
        "",
        0.1,
        0.9,
        0.5,
        C,
    ),
    spec(
        "split_angle",
        "Split angle",
        "Trunk",
        "°",
        0.0,
        60.0,
        25.0,
        C,
    ),
    spec("tropism", "Tropism", "Branches", "", -1.0, 1.0, 0.0, C),
    spec("prune_ratio", "Pruning", "Crown", "", 0.0, 1.0, 0.0, C),
    spec(
        "prune_width",
        "Envelope width",
        "Crown",
        "",
        0.1,
        1.0,
        0.5,
        C,
    ),
    spec("prune_peak", "Envelope peak", "Crown", "", 0.1, 0.9, 0.5, C),
    spec(
        "ratio_power",
        "Radius power",
        "Branches",
        "",
        1.0,
        3.0,
        1.5,
        C,
    ),
    spec("jitter", "Randomness", "Tree", "", 0.0, 1.0, 0.5, C),
    // Level 1.
    spec("branches_1", "Branches", "Level 1", "", 0.0, 40.0, 20.0, I),
    spec("length_1", "Length", "Level 1", "", 0.05, 1.0, 0.4, C),
    spec(
        "down_angle_1",
        "Down angle",
        "Level 1",
        "°",
        0.0,
        140.0,
        60.0,
        C,
    ),
    spec("rotate_1", "Rotation", "Level 1", "°", 0.0, 360.0, 137.5, C),
    spec("curve_1", "Curvature", "Level 1", "°", -90.0, 90.0, 0.0, C),
    // Level 2.
    spec("branches_2", "Branches", "Level 2", "", 0.0, 20.0, 8.0, I),
    spec("length_2", "Length", "Level 2", "", 0.05, 1.0, 0.4, C),
    spec(
        "down_angle_2",
        "Down angle",
        "Level 2",
        "°",
        0.0,
        140.0,
        45.0,
        C,
    ),
    spec("rotate_2", "Rotation", "Level 2", "°", 0.0, 360.0, 140.0, C),
    spec("curve_2", "Curvature", "Level 2", "°", -90.0, 90.0, 0.0, C),
    // Level 3.
    spec("branches_3", "Branches", "Level 3", "", 0.0, 10.0, 4.0, I),
    spec("length_3", "Length", "Level 3", "", 0.05, 1.0, 0.4, C),
    spec(
        "down_angle_3",
        "Down angle",
        "Level 3",
        "°",
        0.0,
        140.0,
        45.0,
        C,
    ),
    spec("rotate_3", "Rotation", "Level 3", "°", 0.0, 360.0, 140.0, C),
    spec("curve_3", "Curvature", "Level 3", "°", -90.0, 90.0, 0.0, C),
    // Leaves.
    spec("leaves", "Leaves per twig", "Leaves", "", 0.0, 30.0, 8.0, I),
    spec(
        "leaf_size",
        "Leaf cluster size / height",
        "Leaves",
        "",
        0.01,
        0.3,
        0.1,
        C,
    ),
    spec(
        "leaf_aspect",
        "Leaf width / length",
        "Leaves",
        "",
        0.1,
        1.5,
        0.6,
        C,
    ),
];

/// Parts of every tree mesh, indexed by [`PART_TRUNK`], [`PART_BRANCH`], [`PART_LEAF`].
pub const PARTS: [Part; 3] = [
    Part {
        name: "trunk",
        color: [0.18, 0.11, 0.06, 1.0],
    },
    Part {
        name: "branch",
        color: [0.24, 0.16, 0.09, 1.0],
    },
    Part {
        name: "leaf",
        color: [0.12, 0.35, 0.08, 1.0],
    },
];
/// Part id of the trunk.
pub const PART_TRUNK: u8 = 0;
/// Part id of the branches.
pub const PART_BRANCH: u8 = 1;
/// Part id of the leaves.
pub const PART_LEAF: u8 = 2;
/// Triangles per leaf card: the front pair, then the back pair. A silhouette needs only the
/// front pair (`i % LEAF_CARD_TRIANGLES < 2` over the leaf triangles, which come last).
pub const LEAF_CARD_TRIANGLES: usize = 4;

/// Polyline segments of the skeleton's trunk pieces and branches, whatever the LOD.
const SKELETON_TRUNK_SEGMENTS: usize = 20;
const SKELETON_BRANCH_SEGMENTS: usize = 8;

/// Tessellation per level of detail.
#[derive(Clone, Copy)]
struct Detail {
    /// Tube sides of the trunk and of branches.
    trunk_sides: usize,
    branch_sides: usize,
    /// Polyline segments of the trunk and of branch tubes (subsampling the skeleton's).
    trunk_segments: usize,
    branch_segments: usize,
    /// Leaves are merged `leaf_merge` to one card (area kept) to keep coarse levels cheap.
    leaf_merge: usize,
    /// Hard caps so that no parameter vector makes an absurd mesh (the GA samples the corners
    /// of the space and evaluates at LOW): beyond them further stems or leaf cards are
    /// skipped. Every preset stays below the LOW caps, so presets look alike at every level.
    max_stems: usize,
    max_leaves: usize,
}

fn detail(lod: Lod) -> Detail {
    match lod {
        Lod::Low => Detail {
            trunk_sides: 5,
            branch_sides: 3,
            trunk_segments: 4,
            branch_segments: 2,
            leaf_merge: 4,
            max_stems: 1500,
            max_leaves: 6000,
        },
        Lod::Medium => Detail {
            trunk_sides: 8,
            branch_sides: 4,
            trunk_segments: 8,
            branch_segments: 3,
            leaf_merge: 2,
            max_stems: 3000,
            max_leaves: 15000,
        },
        Lod::High => Detail {
            trunk_sides: 12,
            branch_sides: 6,
            trunk_segments: 12,
            branch_segments: 5,
            leaf_merge: 1,
            max_stems: 6000,
            max_leaves: 40000,
        },
        Lod::Ultra => Detail {
            trunk_sides: 20,
            branch_sides: 8,
            trunk_segments: 20,
            branch_segments: 8,
            leaf_merge: 1,
            max_stems: 6000,
            max_leaves: 40000,
        },
    }
}

/// One stem (trunk piece or branch) of the skeleton: a polyline with a radius per point.
#[derive(Clone, Debug)]
pub struct Stem {
    /// Branch level: 0 for trunk pieces, 1–3 for branches.
    pub level: u8,
    /// Polyline points, base first.
    pub points: Vec<Vec3>,
    /// Radius at each point.
    pub radii: Vec<f32>,
    /// Arc length.
    pub length: f32,
}

/// The branch graph of a tree and its leaves, before meshing.
#[derive(Clone, Debug, Default)]
pub struct Skeleton {
    /// All stems, trunk pieces first.
    pub stems: Vec<Stem>,
    /// Leaf cards: attachment point, direction along the leaf, normal of the card.
    pub leaves: Vec<(Vec3, Vec3, Vec3)>,
    /// Leaf card length and width (after LOD merging).
    pub leaf_dims: Vec2,
}

impl Skeleton {
    /// Number of vertices of the branch graph (polyline points over all stems), the
    /// regularisation characteristic the paper recommends (§3.5.1).
    pub fn graph_vertices(&self) -> usize {
        self.stems.iter().map(|s| s.points.len()).sum()
    }
}

struct Params {
    height: f32,
    trunk_radius: f32,
    taper: f32,
    base_size: f32,
    shape: usize,
    levels: usize,
    trunk_curve: f32,
    splits: usize,
    split_height: f32,
    split_angle: f32,
    tropism: f32,
    prune_ratio: f32,
    prune_width: f32,
    prune_peak: f32,
    ratio_power: f32,
    jitter: f32,
    branches: [f32; 3],
    length: [f32; 3],
    down_angle: [f32; 3],
    rotate: [f32; 3],
    curve: [f32; 3],
    leaves: usize,
    leaf_size: f32,
    leaf_aspect: f32,
}

impl Params {
    fn new(p: &[f64]) -> Params {
        let f = |i: usize| p[i] as f32;
        let lvl = |k: usize| -> [f32; 3] {
            std::array::from_fn(|l| f(idx::LEVEL0 + l * idx::PER_LEVEL + k))
        };
        Params {
            height: f(idx::HEIGHT),
            trunk_radius: f(idx::TRUNK_RADIUS) * f(idx::HEIGHT),
            taper: f(idx::TAPER),
            base_size: f(idx::BASE_SIZE),
            shape: p[idx::SHAPE] as usize,
            levels: p[idx::LEVELS] as usize,
            trunk_curve: f(idx::TRUNK_CURVE).to_radians(),
            splits: p[idx::SPLITS] as usize,
            split_height: f(idx::SPLIT_HEIGHT),
            split_angle: f(idx::SPLIT_ANGLE).to_radians(),
            tropism: f(idx::TROPISM),
            prune_ratio: f(idx::PRUNE_RATIO),
            prune_width: f(idx::PRUNE_WIDTH),
            prune_peak: f(idx::PRUNE_PEAK),
            ratio_power: f(idx::RATIO_POWER),
            jitter: f(idx::JITTER),
            branches: lvl(0),
            length: lvl(1),
            down_angle: lvl(2).map(f32::to_radians),
            rotate: lvl(3).map(f32::to_radians),
            curve: lvl(4).map(f32::to_radians),
            leaves: p[idx::LEAVES] as usize,
            leaf_size: f(idx::LEAF_SIZE) * f(idx::HEIGHT),
            leaf_aspect: f(idx::LEAF_ASPECT),
        }
    }
}

/// Weber & Penn's shape ratio: relative length of a first-level branch whose distance from the
/// trunk tip is `r` (1 at the crown base, 0 at the tip).
fn shape_ratio(shape: usize, r: f32) -> f32 {
    let r = r.clamp(0.0, 1.0);
    match shape {
        0 => 0.2 + 0.8 * r,
        1 => 0.2 + 0.8 * (PI * r).sin(),
        2 => 0.2 + 0.8 * (0.5 * PI * r).sin(),
        3 => 1.0,
        4 => 0.5 + 0.5 * r,
        5 => {
            if r <= 0.7 {
                r / 0.7
            } else {
                (1.0 - r) / 0.3
            }
        }
        6 => 1.0 - 0.8 * r,
        _ => {
            if r <= 0.7 {
                0.5 + 0.5 * r / 0.7
            } else {
                0.5 + 0.5 * (1.0 - r) / 0.3
            }
        }
    }
}

/// A unit vector perpendicular to `d`.
fn any_perp(d: Vec3) -> Vec3 {
    let a = if d.y.abs() < 0.9 { Vec3::Y } else { Vec3::X };
    d.cross(a).normalize()
}

/// Where on a stem a point at arc fraction `t` sits, its direction and radius.
fn sample_stem(stem: &Stem, t: f32) -> (Vec3, Vec3, f32) {
    let n = stem.points.len() - 1;
    let x = (t.clamp(0.0, 1.0) * n as f32).min(n as f32 - 1e-4);
    let i = x as usize;
    let f = x - i as f32;
    let (a, b) = (stem.points[i], stem.points[i + 1]);
    let dir = (b - a).normalize_or(Vec3::Y);
    let r = stem.radii[i] * (1.0 - f) + stem.radii[i + 1] * f;
    (a.lerp(b, f), dir, r)
}

struct Builder<'a> {
    p: &'a Params,
    d: Detail,
    rng: Rng,
    sk: Skeleton,
    /// Height of the crown base and of the top, for the pruning envelope.
    crown: (f32, f32),
}

impl Builder<'_> {
    /// The polyline of a stem from `base` along `dir`, bending by `curve` in total about `axis`
    /// and pulled up or down by tropism (levels ≥ 1).
    #[allow(
        clippy::too_many_arguments,
        reason = "private helper with the stem's full description"
    )]
    fn polyline(
        &self,
        level: u8,
        base: Vec3,
        dir: Vec3,
        axis: Vec3,
        length: f32,
        curve: f32,
        segments: usize,
        out: &mut Vec<Vec3>,
    ) {
        out.clear();
        out.push(base);
        let step = length / segments as f32;
        let bend = Quat::from_axis_angle(axis, curve / segments as f32);
        let mut d = dir;
        let mut p = base;
        // Tropism (Weber & Penn's tropism vector): a pull towards ±Y that grows along the stem.
        let trop = if level > 0 {
            self.p.tropism * 1.2 / segments as f32
        } else {
            0.0
        };
        for _ in 0..segments {
            d = (bend * d + Vec3::Y * trop).normalize_or(d);
            p += d * step;
            out.push(p);
        }
    }

    /// Whether a point is inside the pruning envelope (Weber & Penn's envelope, exponents ½).
    fn inside_envelope(&self, q: Vec3) -> bool {
        let (lo, hi) = self.crown;
        let r = (q.y - lo) / (hi - lo).max(1e-6);
        if !(0.0..=1.0).contains(&r) {
            return false;
        }
        let peak = self.p.prune_peak;
        let e = if r < peak {
            (r / peak).sqrt()
        } else {
            ((1.0 - r) / (1.0 - peak)).sqrt()
        };
        Vec2::new(q.x, q.z).length() <= self.p.prune_width * self.p.height * e
    }

    #[allow(
        clippy::too_many_arguments,
        reason = "private helper with the stem's full description"
    )]
    fn add_stem(
        &mut self,
        level: u8,
        base: Vec3,
        dir: Vec3,
        axis: Vec3,
        mut length: f32,
        radius: f32,
        curve: f32,
    ) -> Option<usize> {
        if self.sk.stems.len() >= self.d.max_stems || length <= 1e-4 || radius <= 0.0 {
            return None;
        }
        // The skeleton is built at one resolution for every LOD, so the branch layout (which
        // depends on tips, pruning and lengths) is the same at every level; meshes subsample.
        let segments = if level == 0 {
            SKELETON_TRUNK_SEGMENTS
        } else {
            SKELETON_BRANCH_SEGMENTS
        };
        let mut pts = Vec::with_capacity(segments + 1);
        self.polyline(level, base, dir, axis, length, curve, segments, &mut pts);
        // Pruning: shorten a branch whose tip leaves the envelope (bisection on its length),
        // then blend by the pruning ratio (Weber & Penn's PruneRatio).
        if level > 0 && self.p.prune_ratio > 0.0 && !self.inside_envelope(pts[segments]) {
            let (mut lo, mut hi) = (0.0f32, 1.0f32);
            for _ in 0..6 {
                let mid = 0.5 * (lo + hi);
                let tip = {
                    self.polyline(
                        level,
                        base,
                        dir,
                        axis,
                        length * mid,
                        curve,
                        segments,
                        &mut pts,
                    );
                    pts[segments]
                };
                if self.inside_envelope(tip) {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            length *= 1.0 - self.p.prune_ratio * (1.0 - lo);
            if length <= 1e-4 {
                return None;
            }
            self.polyline(level, base, dir, axis, length, curve, segments, &mut pts);
        }
        let tip_radius = radius * (1.0 - self.p.taper).max(0.05);
        let radii = (0..=segments)
            .map(|i| {
                let t = i as f32 / segments as f32;
                radius + (tip_radius - radius) * t
            })
            .collect();
        self.sk.stems.push(Stem {
            level,
            points: pts,
            radii,
            length,
        });
        Some(self.sk.stems.len() - 1)
    }

    /// The trunk: one piece, or a lower piece and `splits + 1` upper pieces.
    fn trunk(&mut self) -> Vec<usize> {
        let p = self.p;
        let h = p.height;
        let lean = self.rng.sym_f32() * 0.05 * p.jitter;
        let dir = Quat::from_rotation_z(lean) * Vec3::Y;
        let axis = Vec3::Z;
        let mut pieces = Vec::new();
        if p.splits == 0 {
            pieces.extend(self.add_stem(
                0,
                Vec3::ZERO,
                dir,
                axis,
                h,
                p.trunk_radius,
                p.trunk_curve,
            ));
            return pieces;
        }
        let l0 = h * p.split_height;
        let Some(first) = self.add_stem(
            0,
            Vec3::ZERO,
            dir,
            axis,
            l0,
            p.trunk_radius,
            p.trunk_curve * p.split_height,
        ) else {
            return pieces;
        };
        pieces.push(first);
        let (top, tdir, r) = {
            let s = &self.sk.stems[first];
            let n = s.points.len();
            (
                s.points[n - 1],
                (s.points[n - 1] - s.points[n - 2]).normalize_or(Vec3::Y),
                s.radii[n - 1],
            )
        };
        let n = p.splits + 1;
        let phase = self.rng.unit_f32() * TAU;
        let side = any_perp(tdir);
        // Split pieces share the cross-section (area kept), so each is thinner.
        let r_piece = r / (n as f32).sqrt() * 1.2;
        for k in 0..n {
            let around = Quat::from_axis_angle(tdir, phase + TAU * k as f32 / n as f32);
            let tilt_axis = around * side;
            let angle = p.split_angle * (1.0 + 0.2 * p.jitter * self.rng.sym_f32());
            let d = Quat::from_axis_angle(tilt_axis, angle) * tdir;
            // Split trunks bend back towards the vertical, like real forks.
            if let Some(i) = self.add_stem(0, top, d, tilt_axis, h - l0, r_piece, -0.6 * angle) {
                pieces.push(i);
            }
        }
        pieces
    }

    /// Children of stem `parent` at `level` (1-based), recursively.
    fn children(&mut self, parent: usize, level: usize, along: (f32, f32), count: f32) {
        if level > self.p.levels {
            return;
        }
        let l = level - 1;
        let p = self.p;
        let n = (count + self.rng.unit_f32() * 0.999).floor() as usize;
        let parent_len = self.sk.stems[parent].length;
        let parent_radius = self.sk.stems[parent].radii[0];
        let mut rot = self.rng.unit_f32() * TAU;
        for k in 0..n {
            let t = along.0 + (along.1 - along.0) * ((k as f32 + 0.5) / n as f32);
            let (pos, pdir, prad) = sample_stem(&self.sk.stems[parent], t);
            let offset = t * parent_len;
            // Weber & Penn: first-level lengths follow the crown shape; deeper levels shrink
            // with the distance from the parent's base.
            let max_len = if level == 1 {
                let trunk_len = p.height;
                let r = (1.0 - t) / (1.0 - p.base_size).max(1e-3);
                trunk_len * p.length[l] * shape_ratio(p.shape, r)
            } else {
                p.length[l] * (parent_len - 0.6 * offset).max(0.0)
            };
            let len = max_len * (1.0 + 0.3 * p.jitter * self.rng.sym_f32());
            rot += p.rotate[l] + 0.35 * p.jitter * self.rng.sym_f32();
            let down = p.down_angle[l] + 0.35 * p.jitter * self.rng.sym_f32();
            let side = any_perp(pdir);
            let around = Quat::from_axis_angle(pdir, rot) * side;
            let dir = Quat::from_axis_angle(around, down) * pdir;
            let axis = dir.cross(Vec3::Y).normalize_or(around);
            let ratio = (len / parent_len.max(1e-6)).clamp(0.0, 1.0);
            let radius = (parent_radius * ratio.powf(p.ratio_power)).min(prad * 0.9);
            let curve = p.curve[l] * (1.0 + 0.3 * p.jitter * self.rng.sym_f32());
            let Some(child) =
                self.add_stem(level as u8, pos, dir, axis, len, radius.max(1e-4), curve)
            else {
                continue;
            };
            if level < p.levels {
                let next = p.branches[level];
                let child_len = self.sk.stems[child].length;
                // Weber & Penn: a child's own branch count scales with its relative length.
                let c = next * (0.2 + 0.8 * child_len / (max_len.max(1e-6)));
                self.children(child, level + 1, (0.1, 1.0), c);
            } else {
                self.leaves(child);
            }
        }
    }

    /// Leaf cards along a last-level stem.
    fn leaves(&mut self, stem: usize) {
        let p = self.p;
        let merge = self.d.leaf_merge;
        let n = p.leaves.div_ceil(merge);
        let card_len = p.leaf_size * (merge as f32).sqrt();
        // Leaves draw from their own stream, seeded by one draw of the tree's: the number of
        // cards depends on the LOD, and it must not shift the random choices of the branches.
        let mut rng = Rng::from_state(self.rng.next_u64());
        for k in 0..n {
            if self.sk.leaves.len() >= self.d.max_leaves {
                return;
            }
            let t = 0.15 + 0.85 * (k as f32 + rng.unit_f32()) / n as f32;
            let (pos, dir, _) = sample_stem(&self.sk.stems[stem], t);
            let side = any_perp(dir);
            let around = Quat::from_axis_angle(dir, rng.unit_f32() * TAU) * side;
            let mut ldir = (Quat::from_axis_angle(around, 0.6 + 0.4 * rng.sym_f32()) * dir)
                .normalize_or(Vec3::Y);
            // Leaf clusters near the ground turn up rather than sink into it.
            if (pos + ldir * card_len).y < 0.0 {
                ldir.y = ldir.y.abs();
            }
            let normal = ldir.cross(around).normalize_or(Vec3::Z);
            self.sk.leaves.push((pos, ldir, normal));
        }
    }
}

/// Builds the skeleton (branch graph and leaf frames) for validated parameters.
///
/// The fit evaluates trees at [`Lod::Low`], where leaves are merged into fewer, larger cards
/// that grow from their bases, so the coarse crown is 5–12 % wider and taller than the same
/// leaves drawn one by one. The finer levels (what is exported and shown) move their leaf cards
/// so that their crown's box is the coarse one, the crown that was matched to the photo: the
/// crown keeps its size at every level of detail, and [`Lod::Low`]'s geometry (the GA's) is
/// unchanged.
fn build_skeleton(params: &[f64], lod: Lod) -> Skeleton {
    let mut sk = grow_skeleton(params, lod);
    if lod != Lod::Low && !sk.leaves.is_empty() {
        let fitted = grow_skeleton(params, Lod::Low);
        if let Some(target) = leaves_box(&fitted) {
            fit_leaves_to(&mut sk, target);
        }
    }
    sk
}

/// Corner bounding box of a leaf card attached at `pos`, along `dir`, facing `normal`.
fn card_box(pos: Vec3, dir: Vec3, normal: Vec3, dims: Vec2) -> (Vec3, Vec3) {
    let side = dir.cross(normal) * (0.5 * dims.y);
    let tip = dir * dims.x;
    [pos - side, pos + side, pos + side + tip, pos - side + tip]
        .into_iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), c| {
            (lo.min(c), hi.max(c))
        })
}

/// The bounding box of a skeleton's leaf cards, if it has any.
pub fn leaves_box(sk: &Skeleton) -> Option<(Vec3, Vec3)> {
    let b = sk
        .leaves
        .iter()
        .map(|&(p, d, n)| card_box(p, d, n, sk.leaf_dims))
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), (a, b)| {
            (lo.min(a), hi.max(b))
        });
    (b.0.is_finite() && b.1.is_finite()).then_some(b)
}

/// Moves the leaf cards (their centres scaled and shifted per axis about the leaves' centre) so
/// that their bounding box is `target`.
fn fit_leaves_to(sk: &mut Skeleton, target: (Vec3, Vec3)) {
    let boxes: Vec<(Vec3, Vec3)> = sk
        .leaves
        .iter()
        .map(|&(p, d, n)| card_box(p, d, n, sk.leaf_dims))
        .collect();
    if boxes.is_empty() {
        return;
    }
    let centres: Vec<Vec3> = boxes.iter().map(|&(lo, hi)| (lo + hi) * 0.5).collect();
    let halves: Vec<Vec3> = boxes.iter().map(|&(lo, hi)| (hi - lo) * 0.5).collect();
    let mean = centres.iter().sum::<Vec3>() / centres.len() as f32;
    let mut scale = [1.0f32; 3];
    let mut shift = [0.0f32; 3];
    for axis in 0..3 {
        let d: Vec<f32> = centres.iter().map(|c| c[axis] - mean[axis]).collect();
        let h: Vec<f32> = halves.iter().map(|v| v[axis]).collect();
        // The extent at scale k: max(k·d + h) − min(k·d − h), piecewise linear and
        // non-decreasing in k ≥ 0; Newton steps from k = 1 land on the right piece.
        let extent = |k: f32| {
            let (mut hi, mut lo) = (f32::NEG_INFINITY, f32::INFINITY);
            let (mut dhi, mut dlo) = (0.0, 0.0);
            for (&di, &hi_i) in d.iter().zip(&h) {
                if k * di + hi_i > hi {
                    hi = k * di + hi_i;
                    dhi = di;
                }
                if k * di - hi_i < lo {
                    lo = k * di - hi_i;
                    dlo = di;
                }
            }
            (hi, lo, dhi - dlo)
        };
        let want = target.1[axis] - target.0[axis];
        let mut k = 1.0f32;
        for _ in 0..8 {
            let (hi, lo, slope) = extent(k);
            if slope <= 1e-9 {
                break;
            }
            let next = (k - (hi - lo - want) / slope).clamp(0.0, 2.0);
            if (next - k).abs() < 1e-6 {
                k = next;
                break;
            }
            k = next;
        }
        let (hi, lo, _) = extent(k);
        scale[axis] = k;
        // Centre the fitted extent on the target's.
        shift[axis] = 0.5 * (target.0[axis] + target.1[axis]) - (mean[axis] + 0.5 * (hi + lo));
    }
    let (scale, shift) = (Vec3::from_array(scale), Vec3::from_array(shift));
    for (leaf, &c) in sk.leaves.iter_mut().zip(&centres) {
        let moved = mean + (c - mean) * scale + shift;
        leaf.0 += moved - c;
    }
}

/// Grows the skeleton at one level of detail, leaves as that level draws them.
fn grow_skeleton(params: &[f64], lod: Lod) -> Skeleton {
    let p = Params::new(params);
    let d = detail(lod);
    let seed = (params[idx::SEED] as u64).wrapping_mul(0x2545_F491_4F6C_DD1D) ^ 0x7472_6565;
    let crown_lo = p.height * p.base_size;
    let mut b = Builder {
        p: &p,
        d,
        rng: Rng::from_state(seed),
        sk: Skeleton::default(),
        crown: (crown_lo, p.height),
    };
    let pieces = b.trunk();
    if p.levels >= 1 && !pieces.is_empty() {
        // First-level branches are spread over the trunk from its bare base up: over the lower
        // piece before the split and over each upper piece after it, by length.
        let total = p.branches[0];
        if pieces.len() == 1 {
            b.children(pieces[0], 1, (p.base_size, 1.0), total);
        } else {
            let sh = p.split_height;
            if p.base_size < sh {
                let lo = p.base_size / sh;
                b.children(pieces[0], 1, (lo, 1.0), total * (sh - p.base_size));
            }
            let upper = (pieces.len() - 1) as f32;
            let start = ((p.base_size - sh) / (1.0 - sh)).max(0.0);
            for &piece in &pieces[1..] {
                let share = (1.0 - p.base_size.max(sh)) / upper;
                b.children(piece, 1, (start, 1.0), total * share);
            }
        }
    }
    let merge = d.leaf_merge as f32;
    b.sk.leaf_dims = Vec2::new(p.leaf_size, p.leaf_size * p.leaf_aspect) * merge.sqrt();
    b.sk
}

/// The branch graph and leaf frames of a tree: what the mesh is built from. Used for the
/// paper's optional regularisation by branch-graph vertex count (§3.5.1).
pub fn skeleton(params: &[f64], lod: Lod) -> Result<Skeleton, GenError> {
    let params = sanitize_params(&PARAMS, params)?;
    Ok(build_skeleton(&params, lod))
}

/// Appends a closed tube along a stem: rings around each polyline point, fan caps at both ends.
fn tube(mesh: &mut Mesh, stem: &Stem, sides: usize, segments: usize, part: u8) {
    // Subsample the skeleton's polyline to `segments` segments, ends kept.
    let total = stem.points.len() - 1;
    let m = segments.clamp(1, total);
    let pick = |i: usize| (i * total + m / 2) / m;
    let points: Vec<Vec3> = (0..=m).map(|i| stem.points[pick(i)]).collect();
    let radii: Vec<f32> = (0..=m).map(|i| stem.radii[pick(i)]).collect();
    let n = points.len();
    let base = mesh.positions.len() as u32;
    let mut normal = any_perp((points[1] - points[0]).normalize_or(Vec3::Y));
    let mut prev_dir = Vec3::ZERO;
    let mut ring_normals: Vec<Vec3> = Vec::with_capacity(n * sides);
    for i in 0..n {
        // Ring direction: the mean of the adjacent segments, so rings bisect the bends.
        let d_in = if i > 0 {
            points[i] - points[i - 1]
        } else {
            Vec3::ZERO
        };
        let d_out = if i + 1 < n {
            points[i + 1] - points[i]
        } else {
            Vec3::ZERO
        };
        let dir = (d_in.normalize_or_zero() + d_out.normalize_or_zero()).normalize_or(Vec3::Y);
        if i > 0 {
            // Parallel transport keeps the rings from twisting.
            normal = (Quat::from_rotation_arc(prev_dir, dir) * normal).normalize();
        }
        prev_dir = dir;
        let binormal = dir.cross(normal);
        for k in 0..sides {
            let a = TAU * k as f32 / sides as f32;
            let radial = normal * a.cos() + binormal * a.sin();
            mesh.positions.push(points[i] + radial * radii[i]);
            ring_normals.push(radial);
        }
    }
    let v = |i: usize, k: usize| base + (i * sides + k % sides) as u32;
    let rn = |i: usize, k: usize| ring_normals[i * sides + k % sides];
    let len = stem.length.max(1e-6);
    for i in 0..n - 1 {
        let v0 = i as f32 / (n - 1) as f32 * len;
        let v1 = (i + 1) as f32 / (n - 1) as f32 * len;
        for k in 0..sides {
            let (u0, u1) = (k as f32 / sides as f32, (k + 1) as f32 / sides as f32);
            let (a, b, c, d) = (v(i, k), v(i, k + 1), v(i + 1, k + 1), v(i + 1, k));
            mesh.triangles.push([a, b, c]);
            mesh.triangles.push([a, c, d]);
            mesh.corner_normals
                .extend([rn(i, k), rn(i, k + 1), rn(i + 1, k + 1)]);
            mesh.corner_normals
                .extend([rn(i, k), rn(i + 1, k + 1), rn(i + 1, k)]);
            let (ta, tb, tc, td) = (
                Vec2::new(u0, v0),
                Vec2::new(u1, v0),
                Vec2::new(u1, v1),
                Vec2::new(u0, v1),
            );
            mesh.corner_uvs.extend([ta, tb, tc, ta, tc, td]);
            mesh.tri_parts.extend([part, part]);
        }
    }
    // Caps: a centre vertex at each end, fans wound to face out of the tube.
    let start = mesh.positions.len() as u32;
    mesh.positions.push(points[0]);
    mesh.positions.push(points[n - 1]);
    let d0 = -(points[1] - points[0]).normalize_or(Vec3::Y);
    let d1 = (points[n - 1] - points[n - 2]).normalize_or(Vec3::Y);
    for k in 0..sides {
        mesh.triangles.push([start, v(0, k + 1), v(0, k)]);
        mesh.triangles
            .push([start + 1, v(n - 1, k), v(n - 1, k + 1)]);
        mesh.corner_normals.extend([d0, d0, d0, d1, d1, d1]);
        let a0 = TAU * k as f32 / sides as f32;
        let a1 = TAU * (k + 1) as f32 / sides as f32;
        let c = |a: f32| Vec2::new(0.5 + 0.5 * a.cos(), 0.5 + 0.5 * a.sin());
        let m = Vec2::splat(0.5);
        mesh.corner_uvs.extend([m, c(a1), c(a0), m, c(a0), c(a1)]);
        mesh.tri_parts.extend([part, part]);
    }
}

/// Appends a double-sided leaf card: four welded corners, two triangles facing `normal` and
/// two facing away, so the card reads from both sides.
fn leaf_card(mesh: &mut Mesh, pos: Vec3, dir: Vec3, normal: Vec3, dims: Vec2) {
    let side = dir.cross(normal) * (0.5 * dims.y);
    let tip = dir * dims.x;
    let b = mesh.positions.len() as u32;
    mesh.positions
        .extend([pos - side, pos + side, pos + side + tip, pos - side + tip]);
    // Front: (0, 1, 2), (0, 2, 3) wind counter-clockwise seen from `normal`'s side because
    // side × tip = (dir × normal) × dir = normal (dir ⟂ normal).
    mesh.triangles
        .extend([[b, b + 1, b + 2], [b, b + 2, b + 3]]);
    mesh.triangles
        .extend([[b, b + 2, b + 1], [b, b + 3, b + 2]]);
    mesh.corner_normals.extend([normal; 6]);
    mesh.corner_normals.extend([-normal; 6]);
    let uv = [
        Vec2::new(0.0, 0.0),
        Vec2::new(1.0, 0.0),
        Vec2::new(1.0, 1.0),
        Vec2::new(0.0, 1.0),
    ];
    mesh.corner_uvs
        .extend([uv[0], uv[1], uv[2], uv[0], uv[2], uv[3]]);
    mesh.corner_uvs
        .extend([uv[0], uv[2], uv[1], uv[0], uv[3], uv[2]]);
    mesh.tri_parts.extend([PART_LEAF; 4]);
}

/// Meshes a skeleton: tubes for the stems, cards for the leaves.
fn mesh_skeleton(sk: &Skeleton, lod: Lod) -> Mesh {
    let d = detail(lod);
    let mut mesh = Mesh {
        parts: PARTS.to_vec(),
        ..Mesh::default()
    };
    let tube_verts: usize = sk
        .stems
        .iter()
        .map(|_| (d.trunk_segments + 1) * d.trunk_sides.max(d.branch_sides) + 2)
        .sum();
    mesh.positions.reserve(tube_verts + 4 * sk.leaves.len());
    for s in &sk.stems {
        let (sides, segments, part) = if s.level == 0 {
            (d.trunk_sides, d.trunk_segments, PART_TRUNK)
        } else {
            (d.branch_sides, d.branch_segments, PART_BRANCH)
        };
        tube(&mut mesh, s, sides, segments, part);
    }
    for &(p, dir, n) in &sk.leaves {
        leaf_card(&mut mesh, p, dir, n, sk.leaf_dims);
    }
    mesh
}

/// Level-block parameter index: `lv(level, k)` with `k` 0 branches, 1 length, 2 down angle,
/// 3 rotate, 4 curve.
const fn lv(level: usize, k: usize) -> usize {
    idx::LEVEL0 + (level - 1) * idx::PER_LEVEL + k
}

impl Generator for TreeGenerator {
    fn name(&self) -> &'static str {
        "tree"
    }
    fn label(&self) -> &'static str {
        "Tree"
    }
    fn version(&self) -> u32 {
        2
    }
    fn params(&self) -> &[ParamSpec] {
        &PARAMS
    }
    fn presets(&self) -> Vec<Preset> {
        use idx::*;
        vec![
            self.preset_from_defaults(
                "oak",
                "Oak",
                &[
                    (HEIGHT, 12.0),
                    (TRUNK_RADIUS, 0.04),
                    (BASE_SIZE, 0.25),
                    (SHAPE, 2.0),
                    (LEVELS, 3.0),
                    (TRUNK_CURVE, 10.0),
                    (SPLITS, 2.0),
                    (SPLIT_HEIGHT, 0.35),
                    (SPLIT_ANGLE, 30.0),
                    (TROPISM, 0.1),
                    (PRUNE_RATIO, 0.6),
                    (PRUNE_WIDTH, 0.55),
                    (PRUNE_PEAK, 0.45),
                    (JITTER, 0.8),
                    (lv(1, 0), 14.0),
                    (lv(1, 1), 0.55),
                    (lv(1, 2), 65.0),
                    (lv(1, 4), -20.0),
                    (lv(2, 0), 8.0),
                    (lv(2, 1), 0.5),
                    (lv(2, 2), 50.0),
                    (lv(2, 4), 20.0),
                    (lv(3, 0), 5.0),
                    (lv(3, 1), 0.45),
                    (LEAVES, 8.0),
                    (LEAF_SIZE, 0.1),
                    (LEAF_ASPECT, 0.7),
                ],
            ),
            self.preset_from_defaults(
                "pine",
                "Pine",
                &[
                    (HEIGHT, 18.0),
                    (TRUNK_RADIUS, 0.02),
                    (TAPER, 0.95),
                    (BASE_SIZE, 0.3),
                    (SHAPE, 0.0),
                    (LEVELS, 2.0),
                    (TROPISM, -0.15),
                    (JITTER, 0.3),
                    (lv(1, 0), 40.0),
                    (lv(1, 1), 0.3),
                    (lv(1, 2), 85.0),
                    (lv(1, 3), 137.5),
                    (lv(1, 4), 10.0),
                    (lv(2, 0), 10.0),
                    (lv(2, 1), 0.35),
                    (lv(2, 2), 40.0),
                    (LEAVES, 10.0),
                    (LEAF_SIZE, 0.06),
                    (LEAF_ASPECT, 0.15),
                ],
            ),
            self.preset_from_defaults(
                "birch",
                "Birch",
                &[
                    (HEIGHT, 14.0),
                    (TRUNK_RADIUS, 0.015),
                    (BASE_SIZE, 0.35),
                    (SHAPE, 7.0),
                    (LEVELS, 2.0),
                    (TRUNK_CURVE, 8.0),
                    (TROPISM, -0.2),
                    (JITTER, 0.6),
                    (lv(1, 0), 24.0),
                    (lv(1, 1), 0.3),
                    (lv(1, 2), 40.0),
                    (lv(1, 4), 30.0),
                    (lv(2, 0), 9.0),
                    (lv(2, 1), 0.45),
                    (lv(2, 2), 35.0),
                    (LEAVES, 7.0),
                    (LEAF_SIZE, 0.06),
                    (LEAF_ASPECT, 0.7),
                ],
            ),
            self.preset_from_defaults(
                "willow",
                "Willow",
                &[
                    (HEIGHT, 10.0),
                    (TRUNK_RADIUS, 0.05),
                    (BASE_SIZE, 0.25),
                    (SHAPE, 1.0),
                    (LEVELS, 2.0),
                    (SPLITS, 1.0),
                    (SPLIT_HEIGHT, 0.3),
                    (SPLIT_ANGLE, 20.0),
                    (TROPISM, -0.9),
                    (JITTER, 0.5),
                    (lv(1, 0), 22.0),
                    (lv(1, 1), 0.6),
                    (lv(1, 2), 50.0),
                    (lv(1, 4), -30.0),
                    (lv(2, 0), 10.0),
                    (lv(2, 1), 0.8),
                    (lv(2, 2), 30.0),
                    (lv(2, 4), 10.0),
                    (LEAVES, 20.0),
                    (LEAF_SIZE, 0.1),
                    (LEAF_ASPECT, 0.25),
                ],
            ),
            self.preset_from_defaults(
                "poplar",
                "Poplar",
                &[
                    (HEIGHT, 20.0),
                    (TRUNK_RADIUS, 0.02),
                    (BASE_SIZE, 0.15),
                    (SHAPE, 5.0),
                    (LEVELS, 2.0),
                    (TROPISM, 0.6),
                    (PRUNE_RATIO, 1.0),
                    (PRUNE_WIDTH, 0.15),
                    (PRUNE_PEAK, 0.4),
                    (JITTER, 0.4),
                    (lv(1, 0), 35.0),
                    (lv(1, 1), 0.3),
                    (lv(1, 2), 25.0),
                    (lv(2, 0), 6.0),
                    (lv(2, 1), 0.4),
                    (lv(2, 2), 25.0),
                    (LEAVES, 10.0),
                    (LEAF_SIZE, 0.05),
                    (LEAF_ASPECT, 0.9),
                ],
            ),
            self.preset_from_defaults(
                "bush",
                "Bush",
                &[
                    (HEIGHT, 2.5),
                    (TRUNK_RADIUS, 0.02),
                    (BASE_SIZE, 0.02),
                    (SHAPE, 2.0),
                    (LEVELS, 2.0),
                    (SPLITS, 3.0),
                    (SPLIT_HEIGHT, 0.1),
                    (SPLIT_ANGLE, 45.0),
                    (TROPISM, 0.2),
                    (PRUNE_RATIO, 0.8),
                    (PRUNE_WIDTH, 0.9),
                    (PRUNE_PEAK, 0.35),
                    (JITTER, 0.9),
                    (lv(1, 0), 16.0),
                    (lv(1, 1), 0.65),
                    (lv(1, 2), 50.0),
                    (lv(2, 0), 8.0),
                    (lv(2, 1), 0.5),
                    (lv(2, 2), 45.0),
                    (LEAVES, 10.0),
                    (LEAF_SIZE, 0.15),
                    (LEAF_ASPECT, 0.7),
                ],
            ),
        ]
    }
    fn differentiable(&self) -> bool {
        false
    }
    fn capabilities(&self) -> crate::Capabilities {
        crate::Capabilities {
            fit: Some(crate::FitMethod::TreeGa),
            display_name: "Tree",
            fitted_lod: Lod::Low,
            mask_extra: crate::MaskExtra::TreeLabels,
            // The tree GA is one search; its budget is its effort.
            fit_runs: 1,
            // A tree's outline is ragged (leaf cards against a photo's foliage), so its level
            // is lower than a solid object's.
            photo_match_level: 0.8,
            // The segmentation's default: a tree is fitted to its colour labels; the cut only
            // bounds them.
            outline_smoothing: 0.5,
            // A tree's depth is a guess from one photo whatever it shows; its fit says what it
            // matched (the labels' IoU), not how deep the crown is.
            free_depth: false,
        }
    }
    fn generate(&self, params: &[f64], lod: Lod) -> Result<Mesh, GenError> {
        let params = sanitize_params(&PARAMS, params)?;
        let sk = build_skeleton(&params, lod);
        let mesh = mesh_skeleton(&sk, lod);
        mesh.check()?;
        Ok(mesh)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shape_ratios_stay_in_unit_range() {
        for s in 0..SHAPES.len() {
            for i in 0..=20 {
                let v = shape_ratio(s, i as f32 / 20.0);
                assert!((0.0..=1.0 + 1e-6).contains(&v), "shape {s} r {i}: {v}");
            }
        }
    }
}

#[cfg(test)]
mod homogeneity {
    use super::*;

    /// The height gene scales the whole tree: every length follows it, so the tree at height
    /// `s·h` is the tree at `h` scaled by `s` about its base (the photo fit's area framing
    /// relies on it, `src/tree/impostor.rs`).
    #[test]
    fn height_scales_the_whole_tree() {
        for preset in TreeGenerator.presets() {
            for s in [0.7, 1.3] {
                let spec = &TreeGenerator.params()[idx::HEIGHT];
                if !(spec.min..=spec.max).contains(&(preset.values[idx::HEIGHT] * s)) {
                    continue; // out of range heights are clamped, not scaled
                }
                let a = TreeGenerator
                    .generate(&preset.values, Lod::Low)
                    .expect("tree");
                let mut p = preset.values.clone();
                p[idx::HEIGHT] *= s;
                let b = TreeGenerator.generate(&p, Lod::Low).expect("tree");
                assert_eq!(a.positions.len(), b.positions.len(), "{}", preset.name);
                let worst = a
                    .positions
                    .iter()
                    .zip(&b.positions)
                    .map(|(pa, pb)| (*pa * s as f32 - *pb).length())
                    .fold(0.0f32, f32::max);
                eprintln!("{} ×{s}: worst {worst}", preset.name);
                assert!(
                    worst < 1e-3 * p[idx::HEIGHT] as f32,
                    "{}: {worst}",
                    preset.name
                );
            }
        }
    }
}
