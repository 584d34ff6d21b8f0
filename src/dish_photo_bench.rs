//! The independent dish photo benchmark (issue 16): photo-realistic renders of dishes procfit
//! did not make, by a renderer procfit did not write, and their scoring.
//!
//! `scripts/make-dish-photo-bench.py` renders them with Mitsuba 3 into one folder per case
//! (`photo.png`, `mask.png`, `mask_full.png`, `camera.json`, `truth.obj`, and `spoon.obj` when
//! a spoon is in the scene): a mug, a teacup, an espresso cup, a cappuccino cup, two bowls, a
//! tumbler and a vase lathed from measured dimensions, some on a saucer, some with a spoon, on
//! a wooden table under an area light and a room environment, seen from 10°–60° above through
//! 35–70 mm lenses. The object is the dish with its saucer when it stands on one; the spoon
//! never is. `mask.png` is the object's visible pixels (the spoon hides what it covers),
//! `mask_full.png` its whole silhouette.
//!
//! Each case is fitted as `procfit reconstruct photo.png --generator dish [--fov F]` does:
//! the photo decoded at the working size, [`segment::segment_auto_with`], the dish fit at its
//! default settings ([`FitConfig`]; small extras such as a spoon made don't care; the photo's
//! brightness for the rim term, [`crate::reconstruct::rim`]). Scores:
//! - the automatic mask's IoU against the true visible mask (the hard cut, every pixel);
//! - the paper's IoU-64 against the truth: the fit is moved into the truth's frame through the
//!   photo's camera ([`to_photo_frame`]: the fitted camera's view of the model is placed in
//!   front of the photo's camera), both normalised to their box, 64 turntable views at 128²;
//! - the photo-view IoU: the fit through its fitted camera against the true whole silhouette;
//!   and the CLI's own photo-view IoU (against the automatic mask) with its warnings.
//!
//! `cargo bench --bench dish_photo_bench` prints the table; `tests/dish_photo_bench.rs` checks
//! the loading and the frame change on a case it writes itself (no renderer needed).

use crate::bench_cases::BenchFit;
use crate::camera::{CameraPose, View, ViewParams};
use crate::generators::{Generator, Lod, Mesh};
use crate::mask::Mask;
use crate::reconstruct::{FitConfig, FitError, FitResult, Luma, Session, eval, iou64};
use crate::segment::{self, Photo};
use glam::{DVec3, Vec3};
use serde::Deserialize;
use std::path::Path;

/// The photo's camera and what the case is, as the script wrote it (`camera.json`; the
/// scene's frame: metres, Y up, the table at y = 0).
#[derive(Clone, Debug, Deserialize)]
pub struct BenchCamera {
    /// Case name.
    pub name: String,
    /// The dish (mug, teacup, espresso, cappuccino, bowl, serving-bowl, tumbler, vase).
    pub kind: String,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Vertical field of view, radians.
    pub fov_y: f64,
    /// The lens as a 35 mm-equivalent focal length (what EXIF would say).
    pub focal_35mm: f64,
    /// Camera position.
    pub position: [f64; 3],
    /// The point it looks at.
    pub target: [f64; 3],
    /// The camera's up direction.
    pub up: [f64; 3],
    /// The camera's elevation above the table, degrees.
    pub elevation_deg: f64,
    /// The parts of `truth.obj` that are the object (the dish, and its saucer).
    pub object_parts: Vec<String>,
    /// Whether the dish stands on a saucer.
    pub has_saucer: bool,
    /// Where the spoon is: `none`, `in` (the cup) or `beside`.
    pub spoon: String,
}

/// One benchmark case, loaded.
pub struct BenchCase {
    /// The camera and names.
    pub camera: BenchCamera,
    /// The photo file's bytes (PNG), decoded as the CLI decodes a photo.
    pub photo: Vec<u8>,
    /// The object's visible pixels (coverage 0..1).
    pub mask: Mask,
    /// The object's whole silhouette (coverage 0..1).
    pub mask_full: Mask,
    /// The object's true mesh, in the scene's frame.
    pub truth: Mesh,
}

/// Reads a grey PNG as coverage (0..1).
pub fn read_mask(path: &Path) -> Result<Mask, FitError> {
    let img = image::open(path)
        .map_err(|e| FitError(format!("{}: {e}", path.display())))?
        .to_luma8();
    let values = img.as_raw().iter().map(|&v| f32::from(v) / 255.0).collect();
    Mask::new(img.width(), img.height(), values).map_err(|e| FitError(e.to_string()))
}

impl BenchCase {
    /// Loads the case in `dir`.
    pub fn load(dir: &Path) -> Result<BenchCase, FitError> {
        let at = |p: &Path, e: &dyn std::fmt::Display| FitError(format!("{}: {e}", p.display()));
        let cam_path = dir.join("camera.json");
        let text = std::fs::read_to_string(&cam_path).map_err(|e| at(&cam_path, &e))?;
        let camera: BenchCamera = serde_json::from_str(&text).map_err(|e| at(&cam_path, &e))?;
        let photo_path = dir.join("photo.png");
        let photo = std::fs::read(&photo_path).map_err(|e| at(&photo_path, &e))?;
        let obj_path = dir.join("truth.obj");
        let obj = std::fs::read(&obj_path).map_err(|e| at(&obj_path, &e))?;
        let reference = crate::glb::import_obj(&obj).map_err(|e| at(&obj_path, &e))?;
        let truth = Mesh {
            positions: reference.positions,
            triangles: reference.triangles,
            ..Mesh::default()
        };
        let mask = read_mask(&dir.join("mask.png"))?;
        let mask_full = read_mask(&dir.join("mask_full.png"))?;
        for m in [&mask, &mask_full] {
            if (m.width(), m.height()) != (camera.width, camera.height) {
                return Err(FitError(format!(
                    "{}: a mask is {}×{}, the camera {}×{}",
                    dir.display(),
                    m.width(),
                    m.height(),
                    camera.width,
                    camera.height
                )));
            }
        }
        Ok(BenchCase {
            camera,
            photo,
            mask,
            mask_full,
            truth,
        })
    }

    /// The photo's camera as a [`View`] of the scene's frame (the object transform is the
    /// identity).
    pub fn view(&self) -> Result<View, FitError> {
        photo_view(&self.camera)
    }
}

/// The photo's camera of `camera` as a [`View`] (identity object transform).
pub fn photo_view(camera: &BenchCamera) -> Result<View, FitError> {
    let e = |x: crate::camera::CameraError| FitError(x.0);
    let view = View {
        width: camera.width,
        height: camera.height,
        pose: CameraPose::look_at(
            DVec3::from_array(camera.position),
            DVec3::from_array(camera.target),
            DVec3::from_array(camera.up),
        )
        .map_err(e)?,
        params: ViewParams {
            fov_y: camera.fov_y,
            ..ViewParams::default()
        },
    };
    view.params.validate().map_err(e)?;
    Ok(view)
}

/// Moves a model seen through `fitted` (its object transform and camera) into the frame of
/// `photo`, another camera of the same image with the identity object transform: each point's
/// position in `fitted`'s camera space is put at the same place in `photo`'s. The fit cannot
/// know its depth, so the result is the truth's frame up to a scale about the photo's camera,
/// which the IoU-64's normalisation removes.
pub fn to_photo_frame(positions: &[Vec3], fitted: &View, photo: &View) -> Vec<Vec3> {
    let proj = fitted.projector();
    positions
        .iter()
        .map(|&p| {
            let c = proj.to_camera(p);
            (photo.pose.position + photo.pose.rotation * c).as_vec3()
        })
        .collect()
}

/// The IoU of two masks cut at ½ (don't-care pixels of either left out).
pub fn binary_iou(a: &Mask, b: &Mask) -> f64 {
    let (mut inter, mut union) = (0usize, 0usize);
    for (&x, &y) in a.values().iter().zip(b.values()) {
        if x == Mask::DONT_CARE || y == Mask::DONT_CARE {
            continue;
        }
        let (x, y) = (x >= 0.5, y >= 0.5);
        inter += usize::from(x && y);
        union += usize::from(x || y);
    }
    if union == 0 {
        1.0
    } else {
        inter as f64 / union as f64
    }
}

/// How well procfit's renderer, given the case's camera, reproduces the renderer's silhouette
/// of the truth (`mask_full`): a check of the data and of the camera conventions (≈ 0.99).
pub fn truth_check(case: &BenchCase) -> Result<f64, FitError> {
    eval::view_iou(&case.truth, &case.view()?, &binarised(&case.mask_full))
}

fn binarised(m: &Mask) -> Mask {
    let v = m
        .values()
        .iter()
        .map(|&x| if x >= 0.5 { 1.0 } else { 0.0 })
        .collect();
    Mask::new(m.width(), m.height(), v).unwrap_or_else(|_| m.clone())
}

/// The scores of one fit of a case.
#[derive(Clone, Debug)]
pub struct BenchScore {
    /// The automatic mask (the hard cut) against the true visible mask.
    pub mask_iou: f64,
    /// The paper's IoU-64 against the truth (128², the fit at HIGH in the truth's frame).
    pub iou64: f64,
    /// The fit through its fitted camera against the true whole silhouette.
    pub photo_iou: f64,
    /// The fit through its fitted camera against the automatic mask (what the CLI prints).
    pub cli_photo_iou: f64,
    /// What the CLI would tell: the mask's warnings, then the "does not match" one, then the
    /// "does not fix the shape" one.
    pub warnings: Vec<String>,
    /// The fitted dish's saucer switch (`has_saucer` > ½).
    pub saucer: bool,
    /// The fitted camera's elevation above the dish's ground plane, degrees (a diagnosis: the
    /// photo's is [`BenchCamera::elevation_deg`]).
    pub fitted_elevation_deg: f64,
    /// The fitted model's height over its rim's diameter ([`rim_aspect`]).
    pub fitted_aspect: f64,
    /// The same of the truth.
    pub true_aspect: f64,
    /// How well the photo fixes the shape, as the CLI prints it (`Session::agreement`).
    pub agreement: Option<f64>,
    /// Every run of the fit when asked for ([`BenchFit::each`]), in run order; empty otherwise.
    pub runs: Vec<RunScore>,
}

/// One run of a fit's restarts ([`BenchScore::runs`]).
#[derive(Clone, Debug)]
pub struct RunScore {
    /// Its final loss.
    pub loss: f64,
    /// Its [`Generator::tie_prior`].
    pub tie_prior: f64,
    /// Its IoU-64, as [`BenchScore::iou64`].
    pub iou64: f64,
    /// Its camera's elevation, as [`BenchScore::fitted_elevation_deg`].
    pub elevation_deg: f64,
    /// Its [`rim_aspect`].
    pub aspect: f64,
    /// Its photo-view IoU against the true silhouette, as [`BenchScore::photo_iou`].
    pub photo_iou: f64,
    /// Its photo-view IoU against the automatic mask (the CLI's own photo-view IoU).
    pub cut_iou: f64,
    /// Its IoU-64 against the kept run's model, both in the kept run's frame
    /// ([`eval::fit_agreement`]): how different a shape it is.
    pub agreement: f64,
    /// Whether the fit kept it.
    pub kept: bool,
    /// Its generator parameters: with the loss, the tie prior and the IoU-64, enough to try
    /// another choice among the runs without fitting again.
    pub params: Vec<f64>,
}

/// A mesh's height over the diameter of its rim (the widest circle among its top 3 % in
/// height, about the centre of those points), Y up: how tall a dish is for its opening, the
/// proportion a view from above gets wrong when it misjudges the elevation.
pub fn rim_aspect(positions: &[Vec3]) -> f64 {
    let (lo, hi) = positions
        .iter()
        .fold((f32::MAX, f32::MIN), |(l, h), p| (l.min(p.y), h.max(p.y)));
    let top: Vec<&Vec3> = positions
        .iter()
        .filter(|p| p.y >= hi - 0.03 * (hi - lo))
        .collect();
    if top.is_empty() {
        return 0.0;
    }
    let (xl, xh) = top
        .iter()
        .fold((f32::MAX, f32::MIN), |(a, b), p| (a.min(p.x), b.max(p.x)));
    let (zl, zh) = top
        .iter()
        .fold((f32::MAX, f32::MIN), |(a, b), p| (a.min(p.z), b.max(p.z)));
    let c = glam::Vec2::new(0.5 * (xl + xh), 0.5 * (zl + zh));
    let r = top
        .iter()
        .map(|p| (glam::Vec2::new(p.x, p.z) - c).length())
        .fold(0.0f32, f32::max);
    if r > 0.0 {
        f64::from((hi - lo) / (2.0 * r))
    } else {
        0.0
    }
}

/// The automatic segmentation of the case's photo, as the CLI makes it for `--generator dish`
/// (decoded at the working size, [`segment::segment_auto_with`] with the dish's options).
pub fn auto_segmentation(case: &BenchCase) -> Result<segment::Segmentation, FitError> {
    segment_decoded(&decoded(case)?)
}

/// [`auto_segmentation`] of the decoded photo.
fn segment_decoded(photo: &Photo) -> Result<segment::Segmentation, FitError> {
    let opts = segment::Options::for_generator(Some(&crate::generators::dish::Dish));
    segment::segment_auto_with(photo, &opts).map_err(|x| FitError(x.0))
}

/// The case's photo decoded at the working size, as the CLI decodes it.
fn decoded(case: &BenchCase) -> Result<Photo, FitError> {
    Photo::decode(&case.photo, segment::WORKING_SIDE).map_err(|x| FitError(x.0))
}

/// Fits the case's photo as the CLI does (segmented automatically, the dish generator at the
/// default settings, `fov_y` as `--fov` would give it, `None` as a PNG without EXIF) with the
/// budget and seed of `fit`, and scores it; with `fit.each`, every run of the fit too
/// ([`BenchScore::runs`]). The caller times it.
pub fn fit_case(
    case: &BenchCase,
    fov_y: Option<f64>,
    fit: BenchFit,
) -> Result<BenchScore, FitError> {
    // Decoded once: segmented, and its brightness for the rim term.
    let photo = decoded(case)?;
    let seg = segment_decoded(&photo)?;
    let luma = Luma::from_rgba(photo.width(), photo.height(), photo.rgba())?;
    if (seg.mask.width(), seg.mask.height()) != (case.mask.width(), case.mask.height()) {
        return Err(FitError(format!(
            "{}: the photo is not at the working size",
            case.camera.name
        )));
    }
    let mask_iou = binary_iou(&seg.object, &case.mask);
    let generator = crate::generators::dish::Dish.name();
    let config = FitConfig {
        generator: generator.into(),
        fov_y: vec![fov_y],
        quality: fit.quality,
        restarts: fit.runs_for(generator),
        seed: fit.seed,
        photos: vec![Some(luma)],
        ..FitConfig::default()
    };
    let masks = vec![seg.mask.clone()];
    let mut session = Session::new(config, masks.clone())?;
    let result = session.run()?;
    let mut warnings = seg.warnings.clone();
    let cli_ious = eval::result_photo_ious(&result, &masks)?;
    let level = eval::photo_match_level(result.model.generator);
    if let Some(w) = eval::photo_match_warning(&cli_ious, &["photo".into()], level) {
        warnings.push(w);
    }
    let g = result.model.generator;
    if let Ok(dir) = std::env::var("PROCFIT_DISH_DUMP") {
        let names: Vec<String> = g
            .params()
            .iter()
            .zip(&result.model.params)
            .map(|(s, v)| format!("{} {v:.4}", s.name))
            .collect();
        let path = Path::new(&dir).join(format!("{}.params", case.camera.name));
        if let Err(e) = std::fs::write(&path, format!("{}\nloss {}", names.join("\n"), result.loss))
        {
            eprintln!("PROCFIT_DISH_DUMP: {}: {e}", path.display());
        }
    }
    let agreement = session.agreement()?;
    if let Some(w) = eval::agreement_warning(agreement, session.front_only()?) {
        warnings.push(w);
    }
    let kept = score_fit(case, &result)?;
    let mut runs = Vec::new();
    if fit.each {
        for run in session.run_results().into_iter().flatten() {
            let s = score_fit(case, run)?;
            let cut_iou = eval::result_photo_ious(run, std::slice::from_ref(&seg.object))?
                .first()
                .copied()
                .unwrap_or(0.0);
            runs.push(RunScore {
                photo_iou: s.photo_iou,
                cut_iou,
                agreement: eval::fit_agreement(&result, run, 128)?,
                loss: run.loss,
                tie_prior: g.tie_prior(&run.model.params),
                iou64: s.iou64,
                elevation_deg: s.elevation_deg,
                aspect: s.aspect,
                kept: run.loss == result.loss && run.model.params == result.model.params,
                params: run.model.params.clone(),
            });
        }
    }
    let photo_iou = kept.photo_iou;
    let iou = kept.iou64;
    let fitted_elevation_deg = kept.elevation_deg;
    let saucer = g
        .params()
        .iter()
        .position(|s| s.name == "has_saucer")
        .and_then(|i| result.model.params.get(i))
        .is_some_and(|&v| v > 0.5);
    Ok(BenchScore {
        fitted_elevation_deg,
        agreement,
        fitted_aspect: kept.aspect,
        true_aspect: rim_aspect(&case.truth.positions),
        mask_iou,
        iou64: iou,
        photo_iou,
        cli_photo_iou: cli_ious.first().copied().unwrap_or(0.0),
        warnings,
        saucer,
        runs,
    })
}

/// What [`score_fit`] measures of one fit.
struct FitScore {
    iou64: f64,
    photo_iou: f64,
    elevation_deg: f64,
    aspect: f64,
}

/// The IoU-64 of `fit` against the case's truth, its photo-view IoU against the true
/// silhouette, its camera's elevation and its [`rim_aspect`].
fn score_fit(case: &BenchCase, fit: &FitResult) -> Result<FitScore, FitError> {
    let mesh = fit
        .model
        .generator
        .generate(&fit.model.params, Lod::High)
        .map_err(|x| FitError(x.to_string()))?;
    let fitted = fit
        .views
        .first()
        .ok_or_else(|| FitError("a fit without a view".into()))?;
    let moved = to_photo_frame(&mesh.positions, fitted, &case.view()?);
    let iou64 = iou64(
        (&moved, &mesh.triangles),
        (&case.truth.positions, &case.truth.triangles),
        128,
    )?;
    let photo_iou = eval::view_iou(&mesh, fitted, &binarised(&case.mask_full))?;
    // The object's up axis in the fitted camera's frame (camera on +Z looking down −Z):
    // tilted towards the camera by the elevation.
    let up = fitted.params.rotation_and_derivatives()[0] * DVec3::Y;
    Ok(FitScore {
        iou64,
        photo_iou,
        elevation_deg: up.z.clamp(-1.0, 1.0).asin().to_degrees(),
        aspect: rim_aspect(&mesh.positions),
    })
}
