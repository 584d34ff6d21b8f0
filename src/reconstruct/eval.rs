//! Evaluation as in the paper (§4, notes "Evaluation as they did it"): the silhouette IoU
//! averaged over 64 turntable views — cameras on a horizontal circle at azimuth 2πi/64,
//! distance 3, vertical field of view 0.5 rad, looking at the origin — after normalising both
//! models to their bounding box (centre at the origin, longest side 1).
//!
//! The two meshes must first be in the same frame. For a fit, [`align_to_reference`] maps the
//! reconstruction into the reference's frame through view 0: both are seen by the same camera,
//! the fitted object transform places the reconstruction, the reference's known transform (a
//! synthetic test knows it) places the reference.

use super::FitError;
use super::objective::render_coverage;
use super::session::FitResult;
use crate::camera::{View, ViewParams};
use crate::generators::{Generator, Lod, Mesh};
use crate::loss;
use crate::mask::Mask;
use crate::render::{Renderer, Topology};
use glam::{DVec3, Vec3};

/// Turntable views of the evaluation.
pub const EVAL_VIEWS: usize = 64;
/// Turntable distance.
pub const EVAL_DISTANCE: f64 = 3.0;
/// Turntable vertical field of view, radians.
pub const EVAL_FOV_Y: f64 = 0.5;
/// Default side of the evaluation images.
pub const EVAL_SIDE: u32 = 256;

/// `positions` moved so their bounding box is centred on the origin with its longest side 1.
/// Errors when there are no positions or they are all one point.
pub fn normalized(positions: &[Vec3]) -> Result<Vec<Vec3>, FitError> {
    let first = *positions
        .first()
        .ok_or_else(|| FitError("a mesh to evaluate has no vertices".into()))?;
    let (lo, hi) = positions
        .iter()
        .fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    let size = (hi - lo).max_element();
    if !(size.is_finite() && size > 0.0) {
        return Err(FitError("a mesh to evaluate has no extent".into()));
    }
    let c = 0.5 * (lo + hi);
    Ok(positions.iter().map(|&p| (p - c) / size).collect())
}

/// The IoU-64 between two meshes given in the same frame (each as positions and triangles),
/// rendered at `side × side`. Returns the mean IoU over the 64 views.
pub fn iou64(
    a: (&[Vec3], &[[u32; 3]]),
    b: (&[Vec3], &[[u32; 3]]),
    side: u32,
) -> Result<f64, FitError> {
    turntable_iou(a, b, side, EVAL_VIEWS)
}

/// The mean silhouette IoU over `views` turntable views (azimuth 2πi/views, distance 3, fov
/// 0.5 rad) after normalising both meshes; [`iou64`] is `views = 64`.
pub fn turntable_iou(
    a: (&[Vec3], &[[u32; 3]]),
    b: (&[Vec3], &[[u32; 3]]),
    side: u32,
    views: usize,
) -> Result<f64, FitError> {
    let err = |e: crate::render::RenderError| FitError(e.0);
    let (pa, pb) = (normalized(a.0)?, normalized(b.0)?);
    // Edge structures and the renderer are built once and reused for every view.
    let ta = Topology::new(a.1, pa.len()).map_err(err)?;
    let tb = Topology::new(b.1, pb.len()).map_err(err)?;
    let mut r = Renderer::new(side, side).map_err(err)?;
    let mut ca = Vec::new();
    let mut total = 0.0;
    for i in 0..views.max(1) {
        let azimuth = std::f64::consts::TAU * i as f64 / views.max(1) as f64;
        let view = View::turntable(side, side, azimuth, EVAL_DISTANCE, EVAL_FOV_Y, DVec3::ZERO)
            .map_err(|e| FitError(e.to_string()))?;
        ca.clear();
        ca.extend_from_slice(r.forward(&ta, &pa, &view).map_err(err)?);
        let cb = r.forward(&tb, &pb, &view).map_err(err)?;
        let (mut inter, mut union) = (0.0f64, 0.0f64);
        for (&x, &y) in ca.iter().zip(cb) {
            inter += f64::from(x.min(y));
            union += f64::from(x.max(y));
        }
        total += if union > 0.0 { inter / union } else { 1.0 };
    }
    Ok(total / views.max(1) as f64)
}

/// Maps `positions` of a model placed by the object transform `fitted` into the frame of a
/// reference placed by `reference` in front of the same camera: `p ↦ T_ref⁻¹(T_fit(p))`.
pub fn align_to_reference(
    positions: &[Vec3],
    fitted: &ViewParams,
    reference: &ViewParams,
) -> Vec<Vec3> {
    let rf = fitted.rotation_and_derivatives()[0];
    let rr = reference.rotation_and_derivatives()[0].transpose();
    positions
        .iter()
        .map(|p| {
            let w = fitted.translation + fitted.scale * (rf * p.as_dvec3());
            (rr * (w - reference.translation) / reference.scale).as_vec3()
        })
        .collect()
}

/// The IoU of a silhouette rendered from `mesh` through `view` against `mask` (same size).
pub fn view_iou(mesh: &Mesh, view: &View, mask: &Mask) -> Result<f64, FitError> {
    let c = render_coverage(mesh, view).map_err(FitError)?;
    loss::iou(&c, mask).map_err(|e| FitError(e.to_string()))
}

/// How well a fitted model matches each of its photos: the model rendered through each view's
/// fitted camera against that view's mask (don't-care excluded), the paper's eq. 1 masks.
pub fn photo_view_ious(mesh: &Mesh, views: &[View], masks: &[Mask]) -> Result<Vec<f64>, FitError> {
    if views.len() != masks.len() {
        return Err(FitError(format!(
            "{} views but {} masks",
            views.len(),
            masks.len()
        )));
    }
    views
        .iter()
        .zip(masks)
        .map(|(v, m)| view_iou(mesh, v, m))
        .collect()
}

/// The level below which a fit of `generator` is said not to match a photo
/// ([`Capabilities::photo_match_level`](crate::generators::Capabilities::photo_match_level)).
pub fn photo_match_level(generator: &dyn Generator) -> f64 {
    generator.capabilities().photo_match_level
}

/// The one-line verdict on [`photo_view_ious`]: `None` when every photo is matched at `level`
/// ([`photo_match_level`]) or better, else what is wrong and what to try. `names` label the
/// photos (file names); missing ones are numbered from 1.
pub fn photo_match_warning(ious: &[f64], names: &[String], level: f64) -> Option<String> {
    let poor: Vec<String> = ious
        .iter()
        .enumerate()
        .filter(|&(_, &iou)| iou < level)
        .map(|(i, iou)| {
            let name = names
                .get(i)
                .cloned()
                .unwrap_or_else(|| format!("photo {}", i + 1));
            format!("{name} (IoU {iou:.2})")
        })
        .collect();
    (!poor.is_empty()).then(|| {
        format!(
            "the model does not match {} (below {level:.2}): check the mask (it should hold the object and nothing else), choose another kind of object, or add a photo from another side",
            poor.join(", ")
        )
    })
}

/// [`photo_view_ious`] of a fit's result: its model, at the fit's level of detail (its finest
/// stage's: what the CLI writes by default and the page opens), through each fitted view
/// against that view's mask (the masks the fit was given, in order). What the CLI prints and
/// the page shows after a fit, and what the fit's rescue runs read.
pub fn result_photo_ious(result: &FitResult, masks: &[Mask]) -> Result<Vec<f64>, FitError> {
    result_photo_ious_at(result, masks, result.model.lod)
}

/// [`result_photo_ious`] with the model generated at `lod`: what the CLI prints for a model it
/// writes at another detail (`--lod`), so that the number is the written model's.
pub fn result_photo_ious_at(
    result: &FitResult,
    masks: &[Mask],
    lod: Lod,
) -> Result<Vec<f64>, FitError> {
    let model = &result.model;
    let mesh = model
        .generator
        .generate(&model.params, lod)
        .map_err(|e| FitError(e.to_string()))?;
    photo_view_ious(&mesh, &result.views, masks)
}

/// How alike two fits of the same photos are in 3D: the IoU-64 ([`iou64`], `side²`) of `b`
/// moved into `a`'s frame through their first views (both explain the same photo, so its
/// camera links them), each generated at its own level of detail. 1 when the photos fix the
/// shape; far below when another shape explains them as well (a box's depth from one view).
pub fn fit_agreement(a: &FitResult, b: &FitResult, side: u32) -> Result<f64, FitError> {
    let mesh = |r: &FitResult| {
        r.model
            .generator
            .generate(&r.model.params, r.model.lod)
            .map_err(|e| FitError(e.to_string()))
    };
    let view = |r: &FitResult| {
        r.views
            .first()
            .map(|v| v.params)
            .ok_or_else(|| FitError("a fit without a view".into()))
    };
    let (ma, mb) = (mesh(a)?, mesh(b)?);
    let moved = align_to_reference(&mb.positions, &view(b)?, &view(a)?);
    iou64(
        (&ma.positions, &ma.triangles),
        (&moved, &mb.triangles),
        side,
    )
}

/// Runs whose final loss is within this ratio of the kept run's explain the photos about as
/// well as it does: [`agreement`] compares their shapes with the kept one's.
pub const AGREEMENT_WINDOW: f64 = 0.25;

/// Below this [`agreement`] the photos are said not to fix the shape. On the independent
/// building benchmark (43 one-view fits a seed, `cargo bench --bench building_bench -- --seed
/// N`, seeds 0-4) 6 of 215 fits are below it, mean IoU-64 0.803 against 0.919 for the others,
/// which hold 17 of the 19 fits below 0.80: a warning says the shape is a guess, its absence
/// does not vouch for it (the runs often agree on a wrong shape; [`photo_match_warning`]
/// catches some of those). Since the building's photos are cut closer to their outline and a
/// fit adds runs from L footprints, 1 of 215 (the paper's building from (140°, 28°) at seed
/// 3, 0.845), and the 8 fits below 0.80 are not warned; since stage 3 takes off the balconies
/// its views do not ask for and the roof's kind is a structure choice, 2 (0.795 and 0.960),
/// and 3 of the 4 fits below 0.80 are not. Since the runs are compared at the detail the fit
/// ends at (HIGH, where balcony slabs, doors and stairs are built; MEDIUM before), 4 (0.734,
/// 0.795, 0.927 and 0.960: the paper's building from (30°, 8°) at seeds 0 and 1), and 1 of
/// the 3 fits below 0.80 is not (the L with hip roofs read as a box on a gradient at seed 0,
/// 0.722).
pub const AGREEMENT_LEVEL: f64 = 0.85;

/// How well the photos fix the shape: the lowest [`fit_agreement`] between the kept fit and
/// every other run whose final loss is within [`AGREEMENT_WINDOW`] of its loss and which the
/// tie-break finds at least as plausible (its [`Generator::tie_prior`] no higher: a mug whose
/// handle a run pinched to explain the photo is no alternative the fit believes in). `None`
/// when no other run is: nothing else explains the photos as well. At 128², 64 views.
///
/// Measured with the runs the prior rejects counted too, the measured mug from 12 random
/// cameras was warned about 4 times at IoU-64 0.959–0.985 (`cargo bench --bench reconstruct --
/// mug --cameras 12 --each`); without them, never.
pub fn agreement<'a>(
    kept: &FitResult,
    runs: impl IntoIterator<Item = &'a FitResult>,
) -> Result<Option<f64>, FitError> {
    let prior = |r: &FitResult| r.model.generator.tie_prior(&r.model.params);
    let kept_prior = prior(kept);
    let mut lowest: Option<f64> = None;
    for run in runs {
        if std::ptr::eq(run, kept)
            || run.loss > kept.loss * (1.0 + AGREEMENT_WINDOW)
            || prior(run) > kept_prior
        {
            continue;
        }
        let a = fit_agreement(kept, run, 128)?;
        lowest = Some(lowest.map_or(a, |l| l.min(a)));
    }
    Ok(lowest)
}

/// The stretches along the photo's line of sight that [`depth_agreement`] tries: the kept
/// model reaching 0.6 and 1.6 times as far back.
pub const DEPTH_STRETCHES: [f32; 2] = [0.6, 1.6];

/// A stretched copy whose photo-view IoU is at most this much below the kept model's, on every
/// photo, explains the photos as well ([`depth_agreement`]). On the independent building
/// benchmark's fits (`cargo bench --bench building_bench -- --seed N`, seeds 0-3, 344 stretched
/// copies) the least drop is 0.034: its views show a roof or a side wall. Seen straight on,
/// exactly at eye level, perspective still moves a stretched copy's outline by 0.008-0.043
/// (the tower, the five-storey block, the shed-roofed studio, the gable and hip houses), from
/// 3° up by -0.0005 (the tower stretched matches a hair better) to 0.040. Measured and not
/// kept: 0.015 also warns the tower at eye level (agreement 0.778, IoU-64 0.878) and the gable
/// house from its end (0.802, 0.746), while the block and the studio at eye level stay just
/// above the warning (0.863, 0.861): two more of fifteen such views, for a margin to the
/// benchmark's least drop of 0.019 instead of 0.029. Photos that show a model only from the
/// front need no slack: [`front_only`] says so from where their cameras stand.
pub const DEPTH_SLACK: f64 = 0.005;

/// How far off a side's normal a camera outside that side's extent may look and still count as
/// seeing it straight on ([`front_only`]), degrees: a wall reaching back `d` then shows at most
/// `d · sin 5°`, under a tenth of its depth.
pub const STRAIGHT_ON_DEGREES: f64 = 5.0;

/// Whether every photo shows the model (its mesh's bounds `lo`–`hi`, in its own frame) from
/// straight before or behind it along the same axis of its footprint (X or Z) and nothing
/// else of it: each camera, moved into
/// the model's frame, stands before that side (beyond the bounds along the side's normal, X or
/// Z), no higher than the model's top (so no roof top or roof slope beyond the top faces it)
/// and within the side's width (so neither neighbouring wall faces it) or looking within
/// [`STRAIGHT_ON_DEGREES`] of the side's normal. Such photos show nothing of how far the model
/// reaches back, whatever its outline: a façade photographed straight on from the street. The
/// perspective of set-back parts (a ridge, a stair house on a flat roof) still moves with the
/// depth, but as much with the roof's pitch or the part's height, which the photo does not fix
/// either.
pub fn front_only(views: &[View], lo: Vec3, hi: Vec3) -> bool {
    let (lo, hi) = (lo.as_dvec3(), hi.as_dvec3());
    let centre = 0.5 * (lo + hi);
    let axis = |view: &View| -> Option<usize> {
        let rotation = view.params.rotation_and_derivatives()[0];
        if !(view.params.scale.is_finite() && view.params.scale > 0.0) {
            return None;
        }
        let eye = rotation.transpose() * (view.pose.position - view.params.translation)
            / view.params.scale;
        if !eye.is_finite() || eye.y > hi.y {
            return None;
        }
        [0usize, 2].into_iter().find(|&a| {
            let b = 2 - a;
            let before = eye[a] < lo[a] || eye[a] > hi[a];
            let within = (lo[b]..=hi[b]).contains(&eye[b]);
            let off = (eye[b] - centre[b]).abs().atan2((eye[a] - centre[a]).abs());
            before && (within || off <= STRAIGHT_ON_DEGREES.to_radians())
        })
    };
    let mut axes = views.iter().map(axis);
    let Some(Some(first)) = axes.next() else {
        return false;
    };
    axes.all(|a| a == Some(first))
}

/// How well the photos fix the kept model's depth, for a generator whose shapes can be any
/// depth at the same front outline
/// ([`Capabilities::free_depth`](crate::generators::Capabilities::free_depth)): the kept
/// model is stretched along the first photo's line of sight (made level, towards the model's
/// centre), its front kept in place, by each of [`DEPTH_STRETCHES`], and each stretched copy
/// that matches every photo about as well ([`DEPTH_SLACK`]), or every copy when the photos
/// show the model only from the front ([`front_only`]), is an alternative the photos cannot
/// rule out; the lowest IoU-64 (128², as [`agreement`]) between the kept model and such a
/// copy, or `None` when the photos rule them all out (a roof or a side wall in view), the
/// generator's depth is not free, or the camera looks straight down. The runs of a fit often
/// agree on one depth (the seeds' proportions) when a photo does not show it, so
/// [`agreement`] alone misses it.
///
/// With [`front_only`], measured on the ten buildings of the independent benchmark seen from
/// about their own height (`cargo bench --bench building_bench -- --inputs mask,textured --view
/// Y,E --seed N`: straight from the front 1° up, from an end 1° up and from the front 3° below
/// the centre, from masks and from photos on textured ground, seeds 0 and 1; 120 fits): such
/// views are hard (65 fits below IoU-64 0.80, means per view and input 0.71–0.85, against
/// 0.90–0.96 from the benchmark's own cameras 6–28° up), and the fit now says the shape is a
/// guess for 98 of them instead of 48; the fits below 0.80 it does not warn about went from 37
/// to 20 (their fitted camera is wrong: a corner seen at eye level, or the camera fitted high
/// above, which one outline at eye level allows). No fit from the benchmark's own cameras sees
/// a model only from the front (seeds 1–3, 129 fits): their warnings are unchanged.
///
/// Tried and not kept: asking the fit instead, by refining the kept run (Adam at stage 2's
/// detail, 40–100 steps) with the depth parameter held at 0.6 and 1.6 times its value, against
/// the same refinement with it free. Seen straight on 1° up the held runs mostly ended at
/// 1.4–37 times the free run's loss (the studio 2.9–4.1 at 100 steps, its kept hip roof a guess
/// itself): within 10 % only the tower of the ten at 40 steps, the tower and the flat block of
/// five at 100, where the photos show no depth for any of them.
///
/// Nor for a dish seen from high above, stretched along its own axis from its rim down (the
/// same stretches): on the Mitsuba dish photos (`cargo bench --bench dish_photo_bench -- --fov
/// known`, seed 0) a stretched copy outlines its photo 0.15–0.53 worse, the serving bowl from
/// 55° 0.031–0.047 worse: up to 60° the outline shows how deep a dish is, and the fits from
/// high above that go wrong trade the camera's height for the shape, which a stretch does not
/// try (`tests/from_above.rs`).
pub fn depth_agreement(kept: &FitResult, masks: &[Mask]) -> Result<Option<f64>, FitError> {
    let Some(view) = kept.views.first() else {
        return Ok(None);
    };
    let Some(mesh) = free_depth_mesh(kept)? else {
        return Ok(None);
    };
    let Some((lo, hi)) = mesh.bounds() else {
        return Ok(None);
    };
    let centre = 0.5 * (lo + hi);
    // The line of sight to the model's centre, in the model's frame, made level.
    let rotation = view.params.rotation_and_derivatives()[0];
    let world = view.params.translation + view.params.scale * (rotation * centre.as_dvec3());
    let sight = rotation.transpose() * (world - view.pose.position);
    let level = DVec3::new(sight.x, 0.0, sight.z);
    if level.length() < 1e-6 * sight.length().max(1e-12) {
        return Ok(None);
    }
    let axis = level.normalize().as_vec3();
    // The front (nearest the camera along the axis) stays where it is: the same front, reaching
    // less far or further back.
    let front = mesh
        .positions
        .iter()
        .map(|&p| p.dot(axis))
        .fold(f32::INFINITY, f32::min);
    let straight_on = front_only(&kept.views, lo, hi);
    // Without the photos' say, the kept model's own photo-view IoUs are not needed.
    let base = match straight_on {
        true => Vec::new(),
        false => photo_view_ious(&mesh, &kept.views, masks)?,
    };
    let mut lowest: Option<f64> = None;
    for k in DEPTH_STRETCHES {
        let positions: Vec<Vec3> = mesh
            .positions
            .iter()
            .map(|&p| p + (k - 1.0) * (p.dot(axis) - front) * axis)
            .collect();
        let stretched = Mesh {
            positions,
            ..mesh.clone()
        };
        let matches = || -> Result<bool, FitError> {
            let ious = photo_view_ious(&stretched, &kept.views, masks)?;
            Ok(ious.iter().zip(&base).all(|(s, b)| *s >= b - DEPTH_SLACK))
        };
        if straight_on || matches()? {
            let a = iou64(
                (&mesh.positions, &mesh.triangles),
                (&stretched.positions, &stretched.triangles),
                128,
            )?;
            lowest = Some(lowest.map_or(a, |l| l.min(a)));
        }
    }
    Ok(lowest)
}

/// Whether the kept model of a fit whose generator's depth is free
/// ([`Capabilities::free_depth`](crate::generators::Capabilities::free_depth)) is seen only
/// from the front in every photo ([`front_only`]); false for any other generator.
pub fn fit_front_only(kept: &FitResult) -> Result<bool, FitError> {
    Ok(free_depth_mesh(kept)?
        .and_then(|mesh| mesh.bounds())
        .is_some_and(|(lo, hi)| front_only(&kept.views, lo, hi)))
}

/// The kept model's mesh when its generator's depth is free
/// ([`Capabilities::free_depth`](crate::generators::Capabilities::free_depth)), else `None`.
fn free_depth_mesh(kept: &FitResult) -> Result<Option<Mesh>, FitError> {
    let model = &kept.model;
    if !model.generator.capabilities().free_depth {
        return Ok(None);
    }
    model
        .generator
        .generate(&model.params, model.lod)
        .map(Some)
        .map_err(|e| FitError(e.to_string()))
}

/// The one-line verdict on an [`agreement`]: `None` at [`AGREEMENT_LEVEL`] or better (or
/// without one), else what it means and what to try; `front_only` when the photos show the
/// model only from the front ([`fit_front_only`]): then its depth is what they do not show.
pub fn agreement_warning(agreement: Option<f64>, front_only: bool) -> Option<String> {
    let a = agreement?;
    (a < AGREEMENT_LEVEL).then(|| {
        if front_only {
            format!(
                "the photo shows only the front, from about the model's own height: how far \
                 it reaches back (its depth) and what lies behind are a guess (agreement {a:.2} \
                 < {AGREEMENT_LEVEL:.2}): add a photo from a corner, or set the depth with the \
                 sliders"
            )
        } else {
            format!(
                "the photo does not fix the shape: other fits match it about as well but differ \
                 in 3D (agreement {a:.2} < {AGREEMENT_LEVEL:.2}), so what it does not show \
                 (depth, the far side, the roof) is a guess: add a photo from another side, or \
                 check the sliders"
            )
        }
    })
}

/// What one photo cannot tell about the fitted shape, after a fit from one photo
/// ([`Generator::one_view_caveat`]); `None` with several photos or nothing to say.
pub fn one_view_caveat(result: &FitResult) -> Option<&'static str> {
    let model = &result.model;
    (result.views.len() == 1)
        .then(|| model.generator.one_view_caveat(&model.params))
        .flatten()
}

/// The one-line note on [`Session::windows_left_out`](super::Session::windows_left_out):
/// `None` when the window labels were used (or there were none), else that they were not and
/// what to try.
pub fn windows_left_out_note(left_out: Option<(f64, f64)>) -> Option<String> {
    let (with, without) = left_out?;
    Some(format!(
        "the windows found were left out: the model fitted to them matched the outline less \
         well (IoU {with:.3} against {without:.3} without them), so the floors and window \
         columns are the outline's guess: check the windows (each should cover a window of the \
         building and nothing else), or add a photo"
    ))
}

/// The one-line verdict on a fitted tree's photo-view IoU (the tree pixels' silhouette IoU
/// through the photo's camera): `None` at `level` (the tree generator's
/// [`photo_match_level`]) or better, else what to try; `labels_hint` says how the labels are
/// corrected where this is shown (a CLI flag, a page control).
pub fn tree_match_warning(iou: f64, level: f64, labels_hint: &str) -> Option<String> {
    (iou < level).then(|| {
        format!(
            "the fitted tree does not match the photo (photo-view IoU {iou:.2} < \
             {level:.2}): check the labels ({labels_hint}), choose another kind of \
             object, or use a photo of one tree against a plain background"
        )
    })
}

#[cfg(test)]
mod tests {
    use super::front_only;
    use crate::camera::View;
    use glam::{DVec3, Vec3};

    /// A camera `distance` away at `azimuth` (radians, from +Z towards +X) and `height` above
    /// the origin, looking at the origin; the object untransformed.
    fn view(azimuth: f64, height: f64) -> View {
        let mut v = View::turntable(64, 64, azimuth, 30.0, 0.5, DVec3::ZERO).unwrap_or_else(|e| {
            panic!("{e}");
        });
        v.pose.position.y += height;
        v
    }

    /// A box 20 wide (X), 6 tall and 10 deep (Z), its floor at the origin's height.
    const LO: Vec3 = Vec3::new(-10.0, 0.0, -5.0);
    const HI: Vec3 = Vec3::new(10.0, 6.0, 5.0);

    #[test]
    fn a_camera_before_a_side_and_below_the_top_sees_only_that_side() {
        // Straight before the long side, at eye level, and before it within its width.
        assert!(front_only(&[view(0.0, 1.6)], LO, HI));
        assert!(
            front_only(&[view(0.3, 1.6)], LO, HI),
            "9 of 30 off the axis, 20 wide"
        );
        // Before the short side, straight on, and 4° off its normal (2 off it, 10 deep).
        assert!(front_only(&[view(90f64.to_radians(), 3.0)], LO, HI));
        assert!(front_only(&[view(86f64.to_radians(), 3.0)], LO, HI));
        // From in front and from behind: still nothing of the depth.
        assert!(front_only(&[view(0.0, 1.6), view(3.1, 1.6)], LO, HI));
    }

    #[test]
    fn a_camera_that_sees_a_second_wall_or_the_roof_does_not() {
        // A corner: both walls face the camera.
        assert!(!front_only(&[view(45f64.to_radians(), 1.6)], LO, HI));
        // Before the short side but 10° off its normal and outside its width (10 deep).
        assert!(!front_only(&[view(80f64.to_radians(), 1.6)], LO, HI));
        // Above the top: the roof shows the footprint.
        assert!(!front_only(&[view(0.0, 7.0)], LO, HI));
        // One photo from the front, one from the end: the end shows the depth.
        assert!(!front_only(
            &[view(0.0, 1.6), view(90f64.to_radians(), 1.6)],
            LO,
            HI
        ));
        assert!(!front_only(&[], LO, HI));
    }
}
