//! The dish generator (cups, mugs, bowls, plates, tumblers, vases): paper §3.3, Algorithm 1,
//! with the reference implementation's 53 parameters and four of ours for a saucer, written once
//! over [`Scalar`] so the mesh and its vector–Jacobian product come from the same code.
//!
//! # Shape
//! - **Body**: a profile curve lathed around +Y. Nine radii (`profile_radius_i`, in units of
//!   [`RADIUS_UNIT`]) sit at equal heights from the bottom corner to the rim; a Catmull-Rom
//!   spline through them (the reference smooths with quadratic fits; Catmull-Rom is smooth,
//!   interpolating and cheap to differentiate) gives the outer wall. A quarter-circle corner of
//!   radius [`CORNER`] joins it to a flat bottom. The inner wall is the outer one offset inward
//!   along its normals by [`WALL`]; a half circle joins them into a rounded rim, and a concentric
//!   corner and an inner floor at height [`WALL`] close the solid. The result is one closed,
//!   welded surface (poles on the axis, the seam column shared).
//! - **Handle** (when `has_handle` is 1): a tube of circular cross-section swept over half a
//!   circle in 20 steps in the XY plane on the +X side, centred on the outer wall at
//!   `handle_center_y` × height. Step k sits at angle −90° + 180°·k/19 and distance
//!   `handle_radius_k` × height from the centre; its tube radius is `handle_thickness` ×
//!   `handle_thickness_mult_k`. The two end points are snapped onto the wall — their x is the
//!   wall radius at their height, evaluated through the same spline, minus half the tube radius
//!   so the tube sinks into the wall — which keeps the attachment differentiable. End caps close
//!   the tube.
//!
//! # Units and placement
//! A single photo has no absolute scale, so the dish keeps the reference's units: the body is
//! `0.9 × y_scale` tall (a mug is about 0.9 units), radii are `0.09 ×` the radius parameters,
//! and the wall is 0.025 thick. Unlike the reference (which moves the model down by 0.5) the
//! dish **stands on the ground plane y = 0**, centred on the Y axis; the handle points to +X.
//!
//! # Deviations from the reference, and why
//! - Profile radii range over [0.5, 8] instead of [0.1, 8], and the spline's radius is kept
//!   above [`MIN_RADIUS`] by a smooth maximum, so the inner wall never crosses the axis (a
//!   radius of 0.1 × 0.09 is thinner than the wall).
//! - Handle radii are relative to the body height, so a handle keeps its proportions when
//!   `y_scale` changes.
//!
//! # Levels of detail
//! q = 1, 2, 4, 8 for LOW … ULTRA: 12·q sectors around the axis, 2·q spline samples per profile
//! segment, 2·q segments on the rim, corner and handle cross-section (6·q points), and the 20
//! handle steps at every level (they are parameters).

use crate::ad::{Scalar, Var};
use crate::build::{Builder, Model, generate, generate_with_vjp};
use crate::{EdgeRing, GenError, Generator, Lod, Mesh, ParamKind, ParamSpec, Part, Preset, Vjp};
use glam::Vec2;
use std::f64::consts::{PI, TAU};
use std::sync::OnceLock;

/// Radius of one profile-radius unit.
pub const RADIUS_UNIT: f64 = 0.09;
/// Body height of `y_scale = 1`.
pub const HEIGHT_UNIT: f64 = 0.9;
/// Wall (and floor) thickness.
pub const WALL: f64 = 0.025;
/// Radius of the rounded bottom corner (outside).
pub const CORNER: f64 = 0.03;
/// Smallest radius of the outer wall (kept by a smooth maximum).
pub const MIN_RADIUS: f64 = 0.04;
/// Handle steps (sweep radii and thickness multipliers).
pub const HANDLE_STEPS: usize = 20;

/// Index of the first profile radius (9 of them).
pub const P_RADIUS: usize = 0;
/// Index of `y_scale`.
pub const P_Y_SCALE: usize = 9;
/// Index of `has_handle`.
pub const P_HAS_HANDLE: usize = 10;
/// Index of `handle_thickness`.
pub const P_HANDLE_THICKNESS: usize = 11;
/// Index of `handle_center_y`.
pub const P_HANDLE_CENTER: usize = 12;
/// Index of the first handle sweep radius (20 of them).
pub const P_SWEEP: usize = 13;
/// Index of the first handle thickness multiplier (20 of them).
pub const P_MULT: usize = 33;
/// Index of `has_saucer`.
pub const P_HAS_SAUCER: usize = 53;
/// Index of `saucer_radius` (a multiple of the body's bottom radius).
pub const P_SAUCER_RADIUS: usize = 54;
/// Index of `saucer_height` (the rim's height, in units of [`HEIGHT_UNIT`]).
pub const P_SAUCER_HEIGHT: usize = 55;
/// Index of `saucer_well` (the flat well's radius, a share of the saucer's radius).
pub const P_SAUCER_WELL: usize = 56;
/// Number of parameters.
pub const N_PARAMS: usize = 57;

const SWEEP_NAMES: [&str; 20] = [
    "handle_radius_00",
    "handle_radius_01",
    "handle_radius_02",
    "handle_radius_03",
    "handle_radius_04",
    "handle_radius_05",
    "handle_radius_06",
    "handle_radius_07",
    "handle_radius_08",
    "handle_radius_09",
    "handle_radius_10",
    "handle_radius_11",
    "handle_radius_12",
    "handle_radius_13",
    "handle_radius_14",
    "handle_radius_15",
    "handle_radius_16",
    "handle_radius_17",
    "handle_radius_18",
    "handle_radius_19",
];
const SWEEP_LABELS: [&str; 20] = [
    "Handle radius 1",
    "Handle radius 2",
    "Handle radius 3",
    "Handle radius 4",
    "Handle radius 5",
    "Handle radius 6",
    "Handle radius 7",
    "Handle radius 8",
    "Handle radius 9",
    "Handle radius 10",
    "Handle radius 11",
    "Handle radius 12",
    "Handle radius 13",
    "Handle radius 14",
    "Handle radius 15",
    "Handle radius 16",
    "Handle radius 17",
    "Handle radius 18",
    "Handle radius 19",
    "Handle radius 20",
];
const MULT_NAMES: [&str; 20] = [
    "handle_thickness_mult_00",
    "handle_thickness_mult_01",
    "handle_thickness_mult_02",
    "handle_thickness_mult_03",
    "handle_thickness_mult_04",
    "handle_thickness_mult_05",
    "handle_thickness_mult_06",
    "handle_thickness_mult_07",
    "handle_thickness_mult_08",
    "handle_thickness_mult_09",
    "handle_thickness_mult_10",
    "handle_thickness_mult_11",
    "handle_thickness_mult_12",
    "handle_thickness_mult_13",
    "handle_thickness_mult_14",
    "handle_thickness_mult_15",
    "handle_thickness_mult_16",
    "handle_thickness_mult_17",
    "handle_thickness_mult_18",
    "handle_thickness_mult_19",
];
const MULT_LABELS: [&str; 20] = [
    "Handle thickness × 1",
    "Handle thickness × 2",
    "Handle thickness × 3",
    "Handle thickness × 4",
    "Handle thickness × 5",
    "Handle thickness × 6",
    "Handle thickness × 7",
    "Handle thickness × 8",
    "Handle thickness × 9",
    "Handle thickness × 10",
    "Handle thickness × 11",
    "Handle thickness × 12",
    "Handle thickness × 13",
    "Handle thickness × 14",
    "Handle thickness × 15",
    "Handle thickness × 16",
    "Handle thickness × 17",
    "Handle thickness × 18",
    "Handle thickness × 19",
    "Handle thickness × 20",
];
const RADIUS_NAMES: [&str; 9] = [
    "profile_radius_0",
    "profile_radius_1",
    "profile_radius_2",
    "profile_radius_3",
    "profile_radius_4",
    "profile_radius_5",
    "profile_radius_6",
    "profile_radius_7",
    "profile_radius_8",
];
const RADIUS_LABELS: [&str; 9] = [
    "Radius at bottom",
    "Radius at 1/8 height",
    "Radius at 2/8 height",
    "Radius at 3/8 height",
    "Radius at 4/8 height",
    "Radius at 5/8 height",
    "Radius at 6/8 height",
    "Radius at 7/8 height",
    "Radius at rim",
];

fn spec() -> &'static [ParamSpec] {
    static SPEC: OnceLock<Vec<ParamSpec>> = OnceLock::new();
    SPEC.get_or_init(|| {
        let c = |name, label, group, unit, min, max, default| ParamSpec {
            name,
            label,
            group,
            unit,
            min,
            max,
            default,
            kind: ParamKind::Continuous,
        };
        let mut s = Vec::with_capacity(N_PARAMS);
        for i in 0..9 {
            s.push(c(
                RADIUS_NAMES[i],
                RADIUS_LABELS[i],
                "Body",
                "",
                0.5,
                8.0,
                4.0,
            ));
        }
        s.push(c("y_scale", "Height", "Body", "", 0.1, 1.25, 1.0));
        s.push(ParamSpec {
            kind: ParamKind::Boolean,
            ..c("has_handle", "Has handle", "Handle", "", 0.0, 1.0, 1.0)
        });
        s.push(c(
            "handle_thickness",
            "Handle thickness",
            "Handle",
            "",
            0.025,
            0.075,
            0.045,
        ));
        s.push(c(
            "handle_center_y",
            "Handle height",
            "Handle",
            "",
            0.3,
            0.7,
            0.5,
        ));
        for i in 0..HANDLE_STEPS {
            s.push(c(
                SWEEP_NAMES[i],
                SWEEP_LABELS[i],
                "Handle shape",
                "",
                0.1,
                0.5,
                0.3,
            ));
        }
        for i in 0..HANDLE_STEPS {
            s.push(c(
                MULT_NAMES[i],
                MULT_LABELS[i],
                "Handle shape",
                "",
                0.5,
                2.0,
                1.0,
            ));
        }
        s.push(ParamSpec {
            kind: ParamKind::Boolean,
            ..c("has_saucer", "Has saucer", "Saucer", "", 0.0, 1.0, 0.0)
        });
        s.push(c(
            "saucer_radius",
            "Saucer radius (× foot)",
            "Saucer",
            "",
            1.3,
            5.0,
            SAUCER.radius,
        ));
        s.push(c(
            "saucer_height",
            "Saucer height",
            "Saucer",
            "",
            0.02,
            0.2,
            SAUCER.height,
        ));
        s.push(c(
            "saucer_well",
            "Saucer well (share)",
            "Saucer",
            "",
            0.25,
            0.8,
            SAUCER.well,
        ));
        s
    })
}

const PARTS: [Part; 3] = [
    Part {
        name: "body",
        color: [0.85, 0.82, 0.76, 1.0],
    },
    Part {
        name: "handle",
        color: [0.80, 0.77, 0.70, 1.0],
    },
    Part {
        name: "saucer",
        color: [0.88, 0.86, 0.82, 1.0],
    },
];

/// A saucer under the body: radius (× the body's bottom radius), rim height and well share.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SaucerShape {
    /// `saucer_radius`.
    pub radius: f64,
    /// `saucer_height`.
    pub height: f64,
    /// `saucer_well`.
    pub well: f64,
}

/// The saucer the presets and seeds use: about 2.4 times the cup's foot, its rim 0.17 ×
/// [`HEIGHT_UNIT`] ≈ 0.15 units high (16 mm beside a mug of 0.9 units = 95 mm; measured
/// saucers' rims stand 15–17 mm above the table). From above or from the side, the cup's foot hides behind the saucer's front
/// rim, so one silhouette cannot tell a taller saucer under a taller cup from a lower one
/// under a squatter cup (the height of the cup's rim over the saucer's is all it pins): the fit
/// keeps about the seed's rim height, and a 5 mm seed rim made cups on saucers 15 % too
/// squat (the dish photo benchmark's three saucer cases, IoU-64 0.71–0.77). The fit's shape
/// prior now holds the rim at [`SAUCER_RISE`] of the saucer's radius, whatever the cup's size.
/// Tried and not kept: seeds whose rim already stands at that ratio (0.22 under the mug, 0.17
/// under the tea cup): the Mitsuba photos' three cups on saucers (lens known, seeds 0 / 1 / 2)
/// 0.907 / 0.908 / 0.893 → 0.885 / 0.892 / 0.899.
pub const SAUCER: SaucerShape = SaucerShape {
    radius: 2.4,
    height: 0.17,
    well: 0.45,
};

/// A body shape: nine profile radii and the height scale.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyShape {
    /// Machine name.
    pub name: &'static str,
    /// Human label.
    pub label: &'static str,
    /// Profile radii, bottom to rim.
    pub radii: [f64; 9],
    /// `y_scale`.
    pub y_scale: f64,
    /// The handle this body usually has, by name, or `None`.
    pub handle: Option<&'static str>,
}

/// The six body shapes the presets and seeds are made of.
pub const BODIES: [BodyShape; 6] = [
    BodyShape {
        name: "mug",
        label: "Mug",
        radii: [3.8, 3.9, 3.95, 4.0, 4.0, 4.0, 4.0, 4.0, 4.0],
        y_scale: 1.0,
        handle: Some("round"),
    },
    BodyShape {
        name: "tea_cup",
        label: "Tea cup",
        radii: [2.9, 3.3, 3.8, 4.2, 4.5, 4.8, 5.0, 5.1, 5.2],
        y_scale: 0.7,
        handle: Some("ear"),
    },
    BodyShape {
        name: "bowl",
        label: "Bowl",
        radii: [2.6, 3.8, 4.6, 5.1, 5.4, 5.6, 5.75, 5.85, 5.9],
        y_scale: 0.55,
        handle: None,
    },
    BodyShape {
        name: "plate",
        label: "Plate",
        radii: [4.0, 4.6, 5.1, 5.5, 5.8, 6.0, 6.2, 6.35, 6.5],
        y_scale: 0.12,
        handle: None,
    },
    BodyShape {
        name: "tumbler",
        label: "Tumbler",
        radii: [2.8, 2.87, 2.94, 3.0, 3.06, 3.12, 3.18, 3.24, 3.3],
        y_scale: 1.15,
        handle: None,
    },
    BodyShape {
        name: "vase",
        label: "Vase",
        radii: [2.5, 3.8, 4.6, 4.7, 4.2, 3.0, 2.0, 1.9, 2.4],
        y_scale: 1.25,
        handle: None,
    },
];

/// A handle shape: thickness, height, sweep radii and thickness multipliers.
#[derive(Clone, Debug, PartialEq)]
pub struct HandleShape {
    /// Machine name.
    pub name: &'static str,
    /// `handle_thickness`.
    pub thickness: f64,
    /// `handle_center_y`.
    pub center: f64,
    /// Sweep radii.
    pub radii: [f64; HANDLE_STEPS],
    /// Thickness multipliers.
    pub mults: [f64; HANDLE_STEPS],
}

/// The four handle shapes: a round loop, an ear (wider at the top, thin at the bottom), a
/// D-shaped square loop and a small finger loop.
pub fn handle_shapes() -> Vec<HandleShape> {
    let steps = |f: &dyn Fn(f64) -> f64| -> [f64; HANDLE_STEPS] {
        std::array::from_fn(|k| f(k as f64 / (HANDLE_STEPS - 1) as f64))
    };
    vec![
        HandleShape {
            name: "round",
            thickness: 0.045,
            center: 0.5,
            radii: steps(&|_| 0.3),
            mults: steps(&|_| 1.0),
        },
        HandleShape {
            name: "ear",
            thickness: 0.035,
            center: 0.55,
            radii: steps(&|s| 0.22 + 0.12 * (PI * s).sin() * (0.6 + 0.4 * s)),
            mults: steps(&|s| 0.7 + 0.6 * s),
        },
        HandleShape {
            name: "square",
            thickness: 0.04,
            center: 0.5,
            // A D shape: radius 1 / max(|cos θ|, |sin θ|) of a square, softened.
            radii: steps(&|s| {
                let th = PI * (s - 0.5);
                (0.26 / th.cos().abs().max(th.sin().abs()).max(0.75)).min(0.45)
            }),
            mults: steps(&|_| 1.0),
        },
        HandleShape {
            name: "small",
            thickness: 0.03,
            center: 0.6,
            radii: steps(&|_| 0.17),
            mults: steps(&|_| 1.0),
        },
    ]
}

/// The parameter vector of a body with a handle (or without one when `handle` is `None`; the
/// handle parameters then take the round handle's values so the vector stays in range).
pub fn compose(body: &BodyShape, handle: Option<&HandleShape>) -> Vec<f64> {
    let shapes = handle_shapes();
    let h = handle.unwrap_or(&shapes[0]);
    let mut v = Vec::with_capacity(N_PARAMS);
    v.extend_from_slice(&body.radii);
    v.push(body.y_scale);
    v.push(if handle.is_some() { 1.0 } else { 0.0 });
    v.push(h.thickness);
    v.push(h.center);
    v.extend_from_slice(&h.radii);
    v.extend_from_slice(&h.mults);
    v.extend([0.0, SAUCER.radius, SAUCER.height, SAUCER.well]);
    v
}

/// [`compose`] standing on a saucer.
pub fn on_saucer(body: &BodyShape, handle: Option<&HandleShape>, saucer: &SaucerShape) -> Vec<f64> {
    let mut v = compose(body, handle);
    v[P_HAS_SAUCER] = 1.0;
    v[P_SAUCER_RADIUS] = saucer.radius;
    v[P_SAUCER_HEIGHT] = saucer.height;
    v[P_SAUCER_WELL] = saucer.well;
    v
}

/// The dish generator.
#[derive(Clone, Copy, Debug, Default)]
pub struct Dish;

/// Level-of-detail factor q = 1, 2, 4, 8.
fn lod_q(lod: Lod) -> usize {
    1 << lod.index()
}

/// Uniform Catmull-Rom interpolation between `p[1]` and `p[2]` at `t ∈ [0, 1]`.
fn catmull_rom<S: Scalar>(p: [S; 4], t: S) -> S {
    let a = p[1] * 2.0;
    let b = p[2] - p[0];
    let c = p[0] * 2.0 - p[1] * 5.0 + p[2] * 4.0 - p[3];
    let d = p[1] * 3.0 - p[0] - p[2] * 3.0 + p[3];
    (a + t * (b + t * (c + t * d))) * 0.5
}

/// The outer wall: radius as a function of the spline coordinate u ∈ [0, 8].
struct Wall<S> {
    /// Control radii with one linearly extrapolated phantom at each end (11 values).
    ctrl: [S; 11],
}

impl<S: Scalar> Wall<S> {
    fn new(r: &[S]) -> Self {
        let mut ctrl = [S::cst(0.0); 11];
        for i in 0..9 {
            ctrl[i + 1] = r[i] * RADIUS_UNIT;
        }
        ctrl[0] = ctrl[1] * 2.0 - ctrl[2];
        ctrl[10] = ctrl[9] * 2.0 - ctrl[8];
        Wall { ctrl }
    }

    /// Radius at `u`, clamped to [0, 8] (outside, the end radius holds: zero derivative in u).
    fn radius(&self, u: S) -> S {
        let uv = u.val();
        let (seg, t) = if uv <= 0.0 {
            (0, S::cst(0.0))
        } else if uv >= 8.0 {
            (7, S::cst(1.0))
        } else {
            let seg = (uv.floor() as usize).min(7);
            (seg, u - seg as f64)
        };
        let c = &self.ctrl;
        catmull_rom([c[seg], c[seg + 1], c[seg + 2], c[seg + 3]], t)
            .smooth_max(S::cst(MIN_RADIUS), 0.005)
    }
}

/// Unit vector of (x, y), kept finite when the two are (almost) zero.
fn unit2<S: Scalar>(x: S, y: S) -> (S, S) {
    let l = (x * x + y * y + 1e-18).sqrt();
    (x / l, y / l)
}

impl Model for Dish {
    fn spec(&self) -> &[ParamSpec] {
        spec()
    }

    fn parts(&self) -> &[Part] {
        &PARTS
    }

    fn build<S: Scalar>(&self, p: &[S], lod: Lod) -> Result<Builder<S>, GenError> {
        let q = lod_q(lod);
        let mut b = Builder::new();
        let height = p[P_Y_SCALE] * HEIGHT_UNIT;
        let wall = Wall::new(&p[P_RADIUS..P_RADIUS + 9]);
        let wall_h = height - CORNER;

        // ---- Profile, outer pole → rim → inner pole, as (r, y). ----
        let zero = S::cst(0.0);
        let r0 = p[P_RADIUS] * RADIUS_UNIT;
        let flat = r0 - CORNER; // radius where the bottom corner starts (≥ 0.015)
        let (nb, nc, nr, per_seg) = (q, 2 * q, 2 * q, 2 * q);
        let mut prof: Vec<(S, S)> = Vec::with_capacity(64 * q);
        prof.push((zero, zero));
        for j in 1..nb {
            prof.push((flat * (j as f64 / nb as f64), zero));
        }
        let corner_start = prof.len();
        for k in 0..nc {
            let a = -PI / 2.0 + PI / 2.0 * k as f64 / nc as f64;
            prof.push((flat + CORNER * a.cos(), S::cst(CORNER + CORNER * a.sin())));
        }
        let wall_start = prof.len();
        let ns = 8 * per_seg;
        for j in 0..=ns {
            let u = j as f64 / per_seg as f64;
            prof.push((
                wall.radius(S::cst(u)),
                wall_h * (j as f64 / ns as f64) + CORNER,
            ));
        }
        // Outward normals of the outer wall samples (tangent rotated clockwise).
        let normals: Vec<(S, S)> = (wall_start..prof.len())
            .map(|i| {
                let prev = prof[i - 1];
                let next = prof[(i + 1).min(prof.len() - 1)];
                let (tx, ty) = unit2(next.0 - prev.0, next.1 - prev.1);
                (ty, -tx)
            })
            .collect();
        // Rounded rim: a half circle from the outer to the inner top (interior points only).
        let top = prof[prof.len() - 1];
        let (nx, ny) = normals[normals.len() - 1];
        let half = WALL / 2.0;
        let (mx, my) = (top.0 - nx * half, top.1 - ny * half);
        for k in 1..nr {
            let phi = PI * k as f64 / nr as f64;
            let (c, s) = (phi.cos() * half, phi.sin() * half);
            // Upward tangent τ = normal rotated counter-clockwise: (−ny, nx).
            prof.push((mx + nx * c - ny * s, my + ny * c + nx * s));
        }
        // Inner wall, rim to bottom.
        for (j, &(nx, ny)) in normals.iter().enumerate().rev() {
            let (r, y) = prof[wall_start + j];
            prof.push((r - nx * WALL, y - ny * WALL));
        }
        // Inner corner: concentric with the outer one, radius CORNER − WALL.
        for k in (0..nc).rev() {
            let a = -PI / 2.0 + PI / 2.0 * k as f64 / nc as f64;
            let rad = CORNER - WALL;
            prof.push((flat + rad * a.cos(), S::cst(CORNER + rad * a.sin())));
        }
        for j in (1..nb).rev() {
            prof.push((flat * (j as f64 / nb as f64), S::cst(WALL)));
        }
        prof.push((zero, S::cst(WALL)));
        debug_assert!(corner_start == nb);
        debug_assert_eq!(
            prof.len(),
            body_profile_len(q),
            "edge_rings reads this layout"
        );

        lathe(&mut b, &prof, lathe_sectors(q), 0, 1);

        if p[P_HAS_HANDLE].val() > 0.5 {
            handle(&mut b, p, &wall, height, handle_sectors(q));
        }
        if p[P_HAS_SAUCER].val() > 0.5 {
            // The cup stands in the saucer's well: lift it, then lathe the saucer below.
            let sp = saucer_profile(p, r0);
            let lift = sp[sp.len() - 1].1;
            for v in &mut b.pos {
                v[1] = v[1] + lift;
            }
            lathe(&mut b, &sp, lathe_sectors(q), 2, 3);
        }
        Ok(b)
    }
}

/// The saucer rim's radius and height in model units, for a body of bottom radius `r0`.
fn saucer_rim<S: Scalar>(p: &[S], r0: S) -> (S, S) {
    (p[P_SAUCER_RADIUS] * r0, p[P_SAUCER_HEIGHT] * HEIGHT_UNIT)
}

/// The saucer's profile, outer pole → rim → inner pole, as (r, y): a foot ring on the ground,
/// the underside rising to the rim, a rounded rim lip, the top falling to the flat well. Its
/// radius is `saucer_radius` × the body's bottom radius `r0`, so a cup keeps its saucer when it
/// is scaled; the well's top (the last point) is where the cup stands. Tried and not kept: the
/// well raised to 0.3 of the rim's height, as measured saucers' are (4–5 mm of 15–17): the
/// Mitsuba photos' three cups on saucers (lens known, seeds 0 / 1 / 2) 0.907 / 0.908 / 0.893 →
/// 0.904 / 0.887 / 0.876.
fn saucer_profile<S: Scalar>(p: &[S], r0: S) -> Vec<(S, S)> {
    let zero = S::cst(0.0);
    let (r, h) = saucer_rim(p, r0);
    let rw = p[P_SAUCER_WELL] * r;
    // Thickness of the plate: a third of the rim height, at most a wall and a tenth of the
    // radius (so the rim never folds over the well).
    let t = (h * (1.0 / 3.0)).min(S::cst(WALL)).min(r * 0.1);
    let rf = rw * 0.8;
    vec![
        (zero, zero),
        (rf, zero),
        (rw, t * 0.5),
        (r - t, h - t),
        (r, h - t * 0.5),
        (r - t * 0.5, h),
        (r - t * 1.5, h),
        (rw, t),
        (zero, t),
    ]
}

/// Profile points of the body's lathe (see `build`): the bottom pole and `q − 1` bottom
/// points, `2·q` in the corner, `16·q + 1` on the outer wall, `2·q − 1` inside the rim's half
/// circle, `16·q + 1` on the inner wall, `2·q` in the inner corner, `q − 1` inner bottom points
/// and the inner pole.
fn body_profile_len(q: usize) -> usize {
    40 * q + 1
}

/// Sectors around the body's and the saucer's lathes.
fn lathe_sectors(q: usize) -> usize {
    12 * q
}

/// Sectors around the handle's tube; the handle has `HANDLE_STEPS` rings of them and the two
/// end caps' centres.
fn handle_sectors(q: usize) -> usize {
    6 * q
}

/// The vertex of profile point `j` (not a pole) in sector `s` of a lathe of `n` sectors whose
/// first vertex (its first pole) is `first`.
fn lathe_vertex(first: usize, n: usize, j: usize, s: usize) -> u32 {
    (first + 1 + (j - 1) * n + s % n) as u32
}

/// [`Generator::edge_rings`] of the dish. The rim: where the rounded rim meets the inner wall,
/// profile point `21·q` of the body's lathe (the inner wall's top). From above, the rim's near
/// half shows in a photo where the lip meets the cup's inside, which the lip's near side hides
/// from view: on a thin lip the occluding contour lies at `90° + elevation` round the half
/// circle, so nearer the inner top than the apex from every camera above about 45°; on a thick
/// lip with a flat top (real mugs and espresso cups: 4–5 mm) it is the inner edge from every
/// camera above the rim. Measured on the Mitsuba photos (mean IoU-64 over the twelve, lens
/// known, seeds 0 / 1 / 2, without the shape prior): the inner top 0.916 / 0.910 / 0.923, the
/// apex (`20·q`, before) 0.912 / 0.910 / 0.902.
///
/// With a saucer, the cup's foot too, where the cup meets the saucer in a photo from above: the
/// outer wall's first point (`3·q`), or where the wall turns to face the camera between it and
/// the next point up (a belly hides the foot); seen inside the saucer rim's top (the saucer's profile point 5, its lathe after the body's and the handle's
/// vertices). Measured on the Mitsuba photos' three cups on saucers over seeds 0–7 (mean IoU-64;
/// 0.850 without the foot): this 0.863; the foot alone, skipped where the wall does not face
/// the camera, 0.866; the contour searched from the corner's bottom (`q`) to `9·q` 0.861, from
/// `3·q` to `9·q` 0.851 (a teacup's belly and its shadowed foot are two edges); the foot's
/// term at half the rim's weight 0.842, at twice 0.863.
///
/// Tried and not kept: the inside's floor (the inner corner's middle, `38·q`), every point
/// of it seen through the rim's opening, where a photo from above shows the floor meet the far
/// wall. On the six photos that show the floor (lens known, seeds 0 / 1 / 2), the mug from 60°
/// went 0.892 / 0.833 / 0.888 → 0.741 / 0.805 / 0.756 (fitted too deep: height over rim 1.30–1.42
/// for 1.19), the serving bowl from 55° 0.881 / 0.941 / 0.930 → 0.657 / 0.667 / 0.813 and the
/// teacup from 50° 0.944 / 0.949 / 0.942 → 0.887 / 0.811 / 0.895: the glaze's highlights
/// on the floor are stronger edges than the floor's soft corner. Nor the cup's sides over the
/// saucer (at the wall's seven inner control heights, the two points around each ring where
/// the wall turns from facing the camera, seen inside the saucer's rim, weighing one ring all
/// together): the three cups on saucers (before the saucer's proportion in [`shape_prior`])
/// 0.878 / 0.856 / 0.874 → 0.880 / 0.823 / 0.871, the espresso cup's runs' losses up by half
/// (white cup, white saucer: the nearest strong edge is the saucer's well or a shadow).
pub fn edge_rings(params: &[f64], lod: Lod) -> Vec<EdgeRing> {
    let q = lod_q(lod);
    let n = lathe_sectors(q);
    let ring = |first: usize, j: usize| (0..n).map(|s| lathe_vertex(first, n, j, s)).collect();
    let mut rings = vec![EdgeRing {
        vertices: ring(0, 21 * q),
        ..EdgeRing::default()
    }];
    let on = |i: usize| params.get(i).is_some_and(|&v| v > 0.5);
    if on(P_HAS_SAUCER) {
        let body = 2 + (body_profile_len(q) - 2) * n;
        let handle = if on(P_HAS_HANDLE) {
            HANDLE_STEPS * handle_sectors(q) + 2
        } else {
            0
        };
        rings.push(EdgeRing {
            vertices: ring(0, 3 * q),
            above: vec![ring(0, 3 * q + 1)],
            seen_within: ring(body + handle, 5),
        });
    }
    rings
}

/// Revolves a profile from pole to pole (first and last points on the axis) around +Y in `n`
/// sectors: welded rings, single pole vertices, u around the axis and v along the profile's
/// arc length.
fn lathe<S: Scalar>(b: &mut Builder<S>, prof: &[(S, S)], n: usize, part: u8, group: u16) {
    let np = prof.len();
    let (cs, sn): (Vec<f64>, Vec<f64>) = (0..n)
        .map(|s| {
            let a = TAU * s as f64 / n as f64;
            (a.cos(), a.sin())
        })
        .unzip();
    let mut arc = vec![0.0f64; np];
    for j in 1..np {
        let dr = prof[j].0.val() - prof[j - 1].0.val();
        let dy = prof[j].1.val() - prof[j - 1].1.val();
        arc[j] = arc[j - 1] + dr.hypot(dy);
    }
    let total = arc[np - 1].max(1e-12);
    // Vertex index of (profile point j, sector s): poles are one vertex.
    let mut first = vec![0u32; np];
    for (j, &(r, y)) in prof.iter().enumerate() {
        if j == 0 || j == np - 1 {
            first[j] = b.vertex([S::cst(0.0), y, S::cst(0.0)]);
        } else {
            first[j] = b.pos.len() as u32;
            for s in 0..n {
                b.vertex([r * cs[s], y, r * sn[s]]);
            }
        }
    }
    let idx = |j: usize, s: usize| -> u32 {
        if j == 0 || j == np - 1 {
            first[j]
        } else {
            first[j] + (s % n) as u32
        }
    };
    for j in 0..np - 1 {
        let (v0, v1) = ((arc[j] / total) as f32, (arc[j + 1] / total) as f32);
        for s in 0..n {
            let (u0, u1) = (s as f32 / n as f32, (s + 1) as f32 / n as f32);
            let (a, bb, c, d) = (idx(j, s), idx(j, s + 1), idx(j + 1, s), idx(j + 1, s + 1));
            let (ua, ub, uc, ud) = (
                Vec2::new(u0, v0),
                Vec2::new(u1, v0),
                Vec2::new(u0, v1),
                Vec2::new(u1, v1),
            );
            // Along the profile × around the axis points outward, so (a, c, b) is CCW.
            if j != 0 {
                b.tri([a, c, bb], [ua, uc, ub], part, group);
            }
            if j + 1 != np - 1 {
                b.tri([bb, c, d], [ub, uc, ud], part, group);
            }
        }
    }
}

/// The handle tube (see the module doc).
fn handle<S: Scalar>(b: &mut Builder<S>, p: &[S], wall: &Wall<S>, height: S, nm: usize) {
    let wall_h = height - CORNER;
    let wall_radius = |y: S| wall.radius((y - CORNER) / wall_h * 8.0);
    let cy = p[P_HANDLE_CENTER] * height;
    let cx = wall_radius(cy);
    let last = HANDLE_STEPS - 1;
    let thick: Vec<S> = (0..HANDLE_STEPS)
        .map(|k| p[P_HANDLE_THICKNESS] * p[P_MULT + k])
        .collect();
    let centres: Vec<(S, S)> = (0..HANDLE_STEPS)
        .map(|k| {
            let th = -PI / 2.0 + PI * k as f64 / last as f64;
            let r = p[P_SWEEP + k] * height;
            let y = cy + r * th.sin();
            let x = if k == 0 || k == last {
                // Snapped onto the wall at the end's own height, sunk by half the tube radius.
                wall_radius(y) - thick[k] * 0.5
            } else {
                cx + r * th.cos()
            };
            (x, y)
        })
        .collect();
    let (ca, sa): (Vec<f64>, Vec<f64>) = (0..nm)
        .map(|m| {
            let a = TAU * m as f64 / nm as f64;
            (a.cos(), a.sin())
        })
        .unzip();
    let first = b.pos.len() as u32;
    for k in 0..HANDLE_STEPS {
        let prev = centres[k.saturating_sub(1)];
        let next = centres[(k + 1).min(last)];
        let (tx, ty) = unit2(next.0 - prev.0, next.1 - prev.1);
        let (nx, ny) = (ty, -tx);
        let (x, y) = centres[k];
        for m in 0..nm {
            let c = thick[k] * ca[m];
            b.vertex([x + nx * c, y + ny * c, thick[k] * sa[m]]);
        }
    }
    let idx = |k: usize, m: usize| first + (k * nm + m % nm) as u32;
    for k in 0..last {
        let (v0, v1) = (k as f32 / last as f32, (k + 1) as f32 / last as f32);
        for m in 0..nm {
            let (u0, u1) = (m as f32 / nm as f32, (m + 1) as f32 / nm as f32);
            let (a, bb, c, d) = (idx(k, m), idx(k, m + 1), idx(k + 1, m), idx(k + 1, m + 1));
            b.quad(
                [a, c, d, bb],
                [
                    Vec2::new(u0, v0),
                    Vec2::new(u0, v1),
                    Vec2::new(u1, v1),
                    Vec2::new(u1, v0),
                ],
                1,
                2,
            );
        }
    }
    // End caps: fans around the sweep's end points, facing back along the sweep.
    for (k, outward_back) in [(0, true), (last, false)] {
        let (x, y) = centres[k];
        let ctr = b.vertex([x, y, S::cst(0.0)]);
        let uv = |m: usize| Vec2::new(0.5 + 0.5 * ca[m % nm] as f32, 0.5 + 0.5 * sa[m % nm] as f32);
        for m in 0..nm {
            let (i0, i1) = (idx(k, m), idx(k, m + 1));
            if outward_back {
                b.tri([ctr, i0, i1], [Vec2::splat(0.5), uv(m), uv(m + 1)], 1, 0);
            } else {
                b.tri([ctr, i1, i0], [Vec2::splat(0.5), uv(m + 1), uv(m)], 1, 0);
            }
        }
    }
}

/// The regulariser of the reference (notes): penalise the profile narrowing going up (weakly:
/// vases do narrow), a rim more than three times wider than the base, and jumpy handle radii
/// and thickness multipliers (only when there is a handle). Written over [`Scalar`] so its
/// gradient comes from the tape.
pub fn regularizer<S: Scalar>(p: &[S]) -> S {
    let mut v = S::cst(0.0);
    for i in 0..8 {
        // Radii are in [0.5, 8]; a unit step inward costs 0.1.
        v = v + (p[P_RADIUS + i] - p[P_RADIUS + i + 1]).relu_sq() * 0.1;
    }
    v = v + (p[P_RADIUS + 8] / p[P_RADIUS] - 3.0).relu_sq();
    if p[P_HAS_HANDLE].val() > 0.5 {
        for k in 0..HANDLE_STEPS - 1 {
            // Normalised by the ranges (0.4 and 1.5) so both terms weigh alike.
            let dr = (p[P_SWEEP + k + 1] - p[P_SWEEP + k]) / 0.4;
            let dm = (p[P_MULT + k + 1] - p[P_MULT + k]) / 1.5;
            v = v + (dr * dr + dm * dm) * 0.5;
        }
    }
    v
}

/// The dish's [`Generator::shape_prior`], two proportions of real dishes that a photo may not
/// show:
/// - real dishes' walls are smooth curves, so the profile's curvature changes slowly up the
///   wall; the nine radii's third differences are penalised (the sum of their squares). A
///   bowl's or a teacup's steady curve, a vase's belly and neck cost little; a step does (a
///   teacup's lower half a narrow cylinder and its upper half a bowl, or a mug on a narrow
///   foot). The outline alone leaves such steps free where it does not show the wall: behind a
///   saucer's rim, or under a cup seen from high above, where a narrow foot under a taller cup
///   seen from lower matches the photo as well as the truth.
/// - with a saucer, its rim stands [`SAUCER_RISE`] of its radius above the table
///   ([`SAUCER_RISE_WEIGHT`] × the squared difference of the ratio).
pub fn shape_prior<S: Scalar>(p: &[S]) -> S {
    let mut v = S::cst(0.0);
    for i in 0..6 {
        let r = |k: usize| p[P_RADIUS + i + k];
        let kink = r(3) - r(2) * 3.0 + r(1) * 3.0 - r(0);
        v = v + kink * kink;
    }
    if p[P_HAS_SAUCER].val() > 0.5 {
        let (r, h) = saucer_rim(p, p[P_RADIUS] * RADIUS_UNIT);
        let d = h / r - SAUCER_RISE;
        v = v + d * d * SAUCER_RISE_WEIGHT;
    }
    v
}

/// A saucer's rim height over its radius in [`shape_prior`]. Measured saucers: 15.5 mm over
/// 57.5 (an espresso saucer, Ø 115: 0.27), 17 over 70 (a teacup's, Ø 140: 0.24), 16 over 75
/// (a cappuccino saucer, Ø 150: 0.21). A photo pins only the cup's rim height over the
/// saucer's (the cup's foot hides behind the saucer's front rim), so without it the fit keeps
/// the seed's rim height in the model's units whatever the cup's size: a saucer half as high
/// as a real one under a cup 10–15 % too squat (the Mitsuba espresso cup from 45°: rim height
/// over radius 0.13, height over rim 0.87 against 1.00).
pub const SAUCER_RISE: f64 = 0.24;

/// The weight of [`SAUCER_RISE`] in [`shape_prior`]: strong, since the photo does not pin the
/// ratio (at the fit's prior weight, 1e-4, a ratio 0.1 off costs 1e-3, about the whole
/// silhouette loss of a good fit).
/// The Mitsuba dish photos' three cups on saucers (mean IoU-64, lens known, seeds 0 / 1 / 2;
/// 0.878 / 0.856 / 0.874 without): 10 → 0.857 / 0.869 / 0.868, 100 → 0.898 / 0.914 / 0.877,
/// 300 → 0.897 / 0.903 / 0.879, 1000 → 0.907 / 0.908 / 0.893, 3000 → 0.906 / 0.908 / 0.899,
/// 10000 → 0.902 / 0.920 / 0.906.
pub const SAUCER_RISE_WEIGHT: f64 = 1000.0;

/// A penalty over the dish's parameters and its gradient in the continuous ones, from the tape.
/// A vector the generator would refuse has no meaningful penalty (0, no gradient); the caller
/// gets the error from `generate`.
fn penalty(params: &[f64], f: fn(&[Var]) -> Var) -> (f64, Vec<f64>) {
    match crate::sanitize_params(spec(), params) {
        Ok(p) => {
            let active: Vec<bool> = spec().iter().map(|s| s.kind.is_continuous()).collect();
            crate::ad::gradient(&p, &active, f)
        }
        Err(_) => (0.0, vec![0.0; params.len()]),
    }
}

impl Generator for Dish {
    fn name(&self) -> &'static str {
        "dish"
    }
    /// How much the handle is pinched: its middle closer to the wall than its ends (mean sweep
    /// radius of the four end steps minus that of the four middle ones, if positive). Real
    /// handles bulge outwards or are round; a pinched one is what a round handle turned towards
    /// or away from the camera looks like when fitted side-on, the wrong half of the ambiguity
    /// (the fit's choice between tied restarts, measured in `src/reconstruct/session.rs`).
    /// A mug's handle: one outline cannot tell a handle turned towards the camera from a
    /// shorter one seen side-on (nor one leaning up from one leaning down): the two outline
    /// a photo alike and differ in 3D. Measured on the measured mug from 96 random cameras
    /// (`cargo bench --bench reconstruct -- mug --cameras 96 --each`): in 9 fits the kept
    /// run's IoU-64 is below 0.90 (down to 0.808), its handle turned 8–30° from the truth's,
    /// while its photo-view IoU (0.991–0.995) is that of the right runs; no choice among the
    /// runs by what the mask shows (loss, photo-view IoU, the handle's hole) tells them apart.
    fn one_view_caveat(&self, params: &[f64]) -> Option<&'static str> {
        params
            .get(P_HAS_HANDLE)
            .is_some_and(|&h| h > 0.5)
            .then_some(
                "one photo cannot tell a handle turned towards the camera from a shorter one seen \
             side-on: check the handle with the sliders, or add a photo from another side",
            )
    }

    fn tie_prior(&self, params: &[f64]) -> f64 {
        if params.len() < N_PARAMS || params[P_HAS_HANDLE] <= 0.5 {
            return 0.0;
        }
        let mean = |ks: [usize; 4]| ks.iter().map(|&k| params[P_SWEEP + k]).sum::<f64>() / 4.0;
        (mean([0, 1, HANDLE_STEPS - 2, HANDLE_STEPS - 1]) - mean([8, 9, 10, 11])).max(0.0)
    }
    fn label(&self) -> &'static str {
        "Dish (cup, mug, bowl, plate, glass, vase)"
    }
    /// 2: the saucer (params of version 1 read as a cup without one).
    fn version(&self) -> u32 {
        2
    }
    fn params(&self) -> &[ParamSpec] {
        spec()
    }

    fn presets(&self) -> Vec<Preset> {
        let handles = handle_shapes();
        let by_name = |n: &str| handles.iter().find(|h| h.name == n);
        let mut out: Vec<Preset> = BODIES
            .iter()
            .map(|b| Preset {
                name: b.name,
                label: b.label,
                values: compose(b, b.handle.and_then(by_name)),
            })
            .collect();
        for (name, label, h) in [
            ("mug_ear_handle", "Mug with ear handle", "ear"),
            ("mug_square_handle", "Mug with square handle", "square"),
            ("mug_small_handle", "Mug with small handle", "small"),
        ] {
            out.push(Preset {
                name,
                label,
                values: compose(&BODIES[0], by_name(h)),
            });
        }
        out.push(Preset {
            name: "tea_cup_on_saucer",
            label: "Tea cup on a saucer",
            values: on_saucer(&BODIES[1], by_name("ear"), &SAUCER),
        });
        out
    }

    /// The 6 bodies × 4 handles, then the 6 bodies without a handle (paper: presets are
    /// concatenated into the initial population).
    fn seeds(&self) -> Vec<Vec<f64>> {
        let handles = handle_shapes();
        let mut out = Vec::with_capacity(BODIES.len() * (handles.len() + 1));
        for b in &BODIES {
            for h in &handles {
                out.push(compose(b, Some(h)));
            }
        }
        for b in &BODIES {
            out.push(compose(b, None));
        }
        out
    }

    /// The mug and the tea cup on a saucer, with their usual handle and without one: tried
    /// only when a saucer explains the photo better than every bare dish.
    fn extra_seeds(&self) -> (Vec<Vec<f64>>, std::ops::Range<usize>) {
        let handles = handle_shapes();
        let mut out = Vec::new();
        for b in &BODIES[..2] {
            let h = b.handle.and_then(|n| handles.iter().find(|h| h.name == n));
            out.push(on_saucer(b, h, &SAUCER));
            out.push(on_saucer(b, None, &SAUCER));
        }
        (out, P_HAS_SAUCER..N_PARAMS)
    }

    /// Where the rounded rim meets the inner wall, and with a saucer the cup's foot (or just
    /// above it, where the wall turns to face the camera), seen inside the saucer's rim (see
    /// [`edge_rings`]).
    fn edge_rings(&self, params: &[f64], lod: Lod) -> Vec<EdgeRing> {
        edge_rings(params, lod)
    }

    fn differentiable(&self) -> bool {
        true
    }

    fn capabilities(&self) -> crate::Capabilities {
        crate::Capabilities {
            fit: Some(crate::FitMethod::Gradients),
            display_name: "Cup, mug or bowl",
            fitted_lod: Lod::Low,
            mask_extra: crate::MaskExtra::None,
            // A run takes 2–3 s natively (about 1.4 s of wall time each on 2 threads). The
            // measured mug from 12 random cameras (`cargo bench --bench reconstruct -- mug
            // --cameras 12`), mean (lowest) IoU-64 by runs: 3 → 0.961 (0.895), 4 → 0.963
            // (0.895), 5 → 0.969 (0.952), in 4.2, 5.9 and 7.2 s. One photo cannot tell a
            // handle turned towards the camera from a shorter one side-on; more runs give the
            // tie-break (`tie_prior`) more of both to choose from. From 96 cameras (`-- mug
            // --cameras 96 --runs N`): 5 → 0.947 (0.808, 9 below 0.90), 8 → 0.949 (0.808, 9
            // below 0.90) in 7.0 s instead of about 4.5: not kept.
            fit_runs: 5,
            // A fit to a clean mask scores 0.95–0.99 (procfit's reconstruct tests); 0.85 leaves
            // room for a rough hand-corrected mask and still catches a wrong kind of object or
            // a mask that holds more than the object. A handle turned towards the camera and
            // a shorter one side-on outline alike, so no level catches that: the measured mug
            // from 24 random cameras (`cargo bench --bench reconstruct -- mug --cameras 24
            // --each --threads 2`) outlines its mask at 0.991–0.995 whether its IoU-64 is
            // 0.871 or 0.988. That is the 3D agreement's to say.
            photo_match_level: 0.85,
            // A dish's outline is round, its photos have reflections and a table's grain at
            // the edge: less smoothing lets them in (the Mitsuba dish photos, `cargo bench
            // --bench dish_photo_bench -- --fov known --seed N`, masks 0.978 -> 0.976 and
            // IoU-64 0.931 / 0.933 / 0.932 -> 0.905 / 0.903 / 0.915 at 0.3, seeds 0 / 1 / 2).
            // A smoother cut is no better: at 0.7 the masks are as at 0.5 (0.978) and the fits
            // 0.898 / 0.925 / 0.908 (how much a fit moves when its mask moves by a few pixels).
            outline_smoothing: 0.5,
            // A lathed body is as deep as it is wide (the handle's turn is the agreement's).
            free_depth: false,
        }
    }

    fn generate(&self, params: &[f64], lod: Lod) -> Result<Mesh, GenError> {
        generate(self, params, lod)
    }

    fn generate_with_vjp(
        &self,
        params: &[f64],
        lod: Lod,
    ) -> Result<(Mesh, Box<dyn Vjp>), GenError> {
        generate_with_vjp(self, params, lod)
    }

    fn regularizer(&self, params: &[f64]) -> (f64, Vec<f64>) {
        penalty(params, regularizer)
    }

    fn shape_prior(&self, params: &[f64]) -> (f64, Vec<f64>) {
        penalty(params, shape_prior)
    }
}
