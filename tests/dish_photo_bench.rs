//! The dish photo benchmark's machinery in CI (issue 16), without its renderer: the photos
//! come from Mitsuba (`scripts/make-dish-photo-bench.py`, run by hand), so these tests write a
//! small case of their own in the same layout and check what the bench relies on — that the
//! fit is moved into the truth's frame through the photo's camera correctly (a wrong frame
//! change scores far lower), that a case loads and its camera reproduces its silhouette, and
//! that the whole CLI pipeline (segment, fit, score) runs on it and scores it well.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "a test binary: a failed step should stop it loudly"
)]

use glam::{DVec3, Vec3};
use procfit::bench_cases::{BenchFit, case_dirs};
use procfit::camera::{CameraPose, View, ViewParams};
use procfit::dish_photo_bench::{
    BenchCamera, BenchCase, binary_iou, fit_case, photo_view, to_photo_frame, truth_check,
};
use procfit::generators::{Generator, Lod, Mesh, dish::Dish};
use procfit::reconstruct::{iou64, render_coverage};
use std::path::PathBuf;

/// The generator's first cup preset with a handle, standing on y = 0 (the scene's frame).
fn cup() -> Mesh {
    let preset = Dish.presets().into_iter().next().unwrap();
    let mut m = Dish.generate(&preset.values, Lod::Medium).unwrap();
    let lo = m.bounds().unwrap().0;
    for p in &mut m.positions {
        p.y -= lo.y;
    }
    m
}

/// A camera 45° above the table looking at the cup, 4:3, a 50 mm lens.
fn camera(m: &Mesh) -> BenchCamera {
    let (lo, hi) = m.bounds().unwrap();
    let c = (0.5 * (lo + hi)).as_dvec3();
    let r = 0.5 * f64::from((hi - lo).length());
    let el = 45f64.to_radians();
    let fov_y = procfit::reconstruct::fov_from_focal_35mm(50.0, 256, 192).unwrap();
    let d = r / (0.3 * fov_y).tan();
    let eye = c + d * DVec3::new(0.3 * el.cos(), el.sin(), el.cos());
    BenchCamera {
        name: "test-cup".into(),
        kind: "mug".into(),
        width: 256,
        height: 192,
        fov_y,
        focal_35mm: 50.0,
        position: eye.to_array(),
        target: c.to_array(),
        up: [0.0, 1.0, 0.0],
        elevation_deg: 45.0,
        object_parts: vec!["dish".into()],
        has_saucer: false,
        spoon: "none".into(),
    }
}

#[test]
fn a_fit_seen_by_another_camera_is_moved_onto_the_truth() {
    let truth = cup();
    let photo = photo_view(&camera(&truth)).unwrap();
    // The fit's camera is the reconstruction's fixed one, with an object transform of its own;
    // the model is the truth as that camera would need it to look the same, twice as far away.
    let fixed = CameraPose::look_at(DVec3::new(0.0, 0.0, 3.0), DVec3::ZERO, DVec3::Y).unwrap();
    let fitted = View {
        width: photo.width,
        height: photo.height,
        pose: fixed,
        params: ViewParams {
            yaw: 0.4,
            scale: 1.7,
            translation: DVec3::new(0.1, -0.2, 0.3),
            fov_y: photo.params.fov_y,
            ..ViewParams::default()
        },
    };
    let r = fitted.params.rotation_and_derivatives()[0];
    let model: Vec<Vec3> = truth
        .positions
        .iter()
        .map(|&p| {
            // Photo camera space, doubled (the same picture), then back through the fit's view.
            let c = 2.0 * (photo.pose.rotation.transpose() * (p.as_dvec3() - photo.pose.position));
            let w = fixed.position + fixed.rotation * c;
            let q = r.transpose() * (w - fitted.params.translation) / fitted.params.scale;
            q.as_vec3()
        })
        .collect();
    let model_mesh = Mesh {
        positions: model.clone(),
        ..truth.clone()
    };
    // The fit's view of the model is the photo's view of the truth.
    let a = render_coverage(&truth, &photo).unwrap();
    let b = render_coverage(&model_mesh, &fitted).unwrap();
    let diff = a
        .iter()
        .zip(&b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f32::max);
    assert!(diff < 0.02, "the two renders differ by {diff}");
    // Moved through the photo's camera, the model is the truth (up to scale): IoU-64 ≈ 1.
    let moved = to_photo_frame(&model, &fitted, &photo);
    let good = iou64(
        (&moved, &truth.triangles),
        (&truth.positions, &truth.triangles),
        128,
    )
    .unwrap();
    assert!(
        good > 0.995,
        "moved through the photo's camera: IoU-64 {good}"
    );
    // Taken as if both cameras were one (the test recoveries' `align_to_reference`, which
    // assumes it), the model comes out tilted: the bench would be wrong by this much.
    let wrong =
        procfit::reconstruct::align_to_reference(&model, &fitted.params, &ViewParams::default());
    let bad = iou64(
        (&wrong, &truth.triangles),
        (&truth.positions, &truth.triangles),
        128,
    )
    .unwrap();
    assert!(
        bad < good - 0.05,
        "a wrong frame change scores {bad} against {good}"
    );
}

/// Writes a case in the script's layout: a flat-shaded photo over a plain background, the
/// masks from procfit's renderer, the camera and the truth.
fn write_case(dir: &std::path::Path, truth: &Mesh, cam: &BenchCamera) {
    std::fs::create_dir_all(dir).unwrap();
    let view = photo_view(cam).unwrap();
    let cov = render_coverage(truth, &view).unwrap();
    let (w, h) = (cam.width, cam.height);
    let mut photo = image::RgbImage::new(w, h);
    for (i, &c) in cov.iter().enumerate() {
        let (x, y) = (i as u32 % w, i as u32 / w);
        let bg = [200.0, 205.0, 210.0 - 20.0 * y as f32 / h as f32];
        let fg = [150.0, 40.0, 35.0];
        let px = std::array::from_fn(|k| (bg[k] + c * (fg[k] - bg[k])).round() as u8);
        photo.put_pixel(x, y, image::Rgb(px));
    }
    photo.save(dir.join("photo.png")).unwrap();
    let mask: Vec<u8> = cov.iter().map(|&c| (c * 255.0).round() as u8).collect();
    for name in ["mask.png", "mask_full.png"] {
        image::GrayImage::from_raw(w, h, mask.clone())
            .unwrap()
            .save(dir.join(name))
            .unwrap();
    }
    let mut obj = String::from("o dish\n");
    for p in &truth.positions {
        obj += &format!("v {} {} {}\n", p.x, p.y, p.z);
    }
    for t in &truth.triangles {
        obj += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    std::fs::write(dir.join("truth.obj"), obj).unwrap();
    let json = serde_json::json!({
        "name": cam.name, "kind": cam.kind, "width": w, "height": h, "fov_y": cam.fov_y,
        "focal_35mm": cam.focal_35mm, "position": cam.position, "target": cam.target,
        "up": cam.up, "elevation_deg": cam.elevation_deg, "object_parts": cam.object_parts,
        "has_saucer": cam.has_saucer, "spoon": cam.spoon, "seed": 1
    });
    std::fs::write(dir.join("camera.json"), json.to_string()).unwrap();
}

#[test]
fn a_case_loads_and_the_cli_pipeline_scores_it() {
    let root: PathBuf =
        std::env::temp_dir().join(format!("procfit-dish-bench-{}", std::process::id()));
    assert!(case_dirs(&root.join("absent"), &[]).is_empty());
    let truth = cup();
    let cam = camera(&truth);
    write_case(&root.join("test-cup"), &truth, &cam);
    let dirs = case_dirs(&root, &[]);
    assert_eq!(dirs.len(), 1);
    let case = BenchCase::load(&dirs[0]).unwrap();
    assert_eq!(case.camera.name, "test-cup");
    // The camera read back reproduces the silhouette it was written from (soft coverage
    // against the binarised mask: the outline's pixels cost a little at this small size,
    // 0.982 measured; a wrong camera convention scores far lower).
    let check = truth_check(&case).unwrap();
    assert!(check > 0.97, "truth check {check}");
    assert!((binary_iou(&case.mask, &case.mask_full) - 1.0).abs() < 1e-12);
    // The CLI's pipeline at a quick quality: a plain background is segmented well, and a cup
    // the generator can make is recovered. Its runs are scored too (`--each`): one run at this
    // quality (a quick preview), the kept one, scored as the fit.
    let s = fit_case(
        &case,
        Some(cam.fov_y),
        BenchFit {
            quality: 0.3,
            seed: 0,
            each: true,
            runs: None,
            windows: false,
        },
    )
    .unwrap();
    std::fs::remove_dir_all(&root).ok();
    println!(
        "mask IoU {:.3}, IoU-64 {:.3}, photo-view IoU {:.3} / {:.3}, warnings {:?}",
        s.mask_iou, s.iou64, s.photo_iou, s.cli_photo_iou, s.warnings
    );
    assert!(s.mask_iou > 0.95, "mask IoU {}", s.mask_iou);
    assert!(s.photo_iou > 0.9, "photo-view IoU {}", s.photo_iou);
    assert!(s.iou64 > 0.85, "IoU-64 {}", s.iou64);
    assert_eq!(s.runs.len(), 1);
    let run = &s.runs[0];
    assert!(run.kept);
    assert_eq!(run.iou64, s.iou64);
    assert_eq!(run.photo_iou, s.photo_iou);
    assert!(run.cut_iou > 0.9, "against the hard cut {}", run.cut_iou);
}
