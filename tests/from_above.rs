//! Issue 16, views from above: where a single-view dish fit loses as the camera rises from 11°
//! to 70° above the table, from the mask alone and from a synthetic photo whose rim is an edge
//! (the object bright, the inside of its rim dark; the fit's rim term, `reconstruct::rim`). A
//! measurement, not a check (`#[ignore]`, it prints a table):
//! `cargo test --release --test from_above -- --ignored --nocapture`.
//!
//! Measured (stop 51; stop 33's in brackets), IoU-64 from 11° / 20° / 30° / 40° / 50° / 60° /
//! 70°, mask → photo:
//! - the measured mug 0.701 / 0.985 / 0.966 / 0.966 / 0.954 / 0.834 / 0.768 → 0.983 / 0.936 /
//!   0.969 / 0.950 / 0.920 / 0.911 / 0.805 (fitted elevation for 60°: 37.0° → 53.4°; [37.5° →
//!   43.2°]);
//! - a random bowl 0.991 / 0.995 / 0.996 / 0.996 / 0.993 / 0.831 / 0.782 → 0.995 / 0.997 /
//!   0.989 / 0.998 / 0.982 / 0.848 / 0.758;
//! - a random cup 0.977 / 0.856 / 0.915 / 0.950 / 0.917 / 0.947 / 0.842 → 0.994 / 0.879 /
//!   0.953 / 0.929 / 0.961 / 0.954 / 0.970.
//!
//! Means from 40–70°: mug 0.880 → 0.896 [0.882 → 0.887], bowl 0.900 → 0.896 [0.903 → 0.911],
//! cup 0.914 → 0.953 [0.881 → 0.918]; from 11–30°: mug 0.884 → 0.963, bowl 0.994 → 0.994, cup
//! 0.916 → 0.942. The photo-view IoU stays ≥ 0.987 throughout: from 60° up, the silhouette is
//! matched by a camera too low and a shape to suit it (the elevation–shape trade of one view),
//! which no number the user sees reveals; the rim's edge inside the outline brings the camera
//! partly back up (`the_rim_in_a_photo_fixes_the_camera_from_above`, a check), least for the
//! bowl, whose rim from 60–70° is most of its outline.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "a test binary: a failed step should stop it loudly"
)]

mod reconstruct_support;

use procfit::generators::Lod;
use procfit::optim::Rng;
use procfit::reconstruct::{FitConfig, Luma, eval};
use reconstruct_support::*;

/// Camera elevations measured, radians (about 11°, 20°, 30°, 40°, 50°, 60°, 70°).
const PITCHES: [f64; 7] = [0.2, 0.35, 0.52, 0.7, 0.87, 1.05, 1.22];

#[test]
#[ignore = "prints a table; takes minutes"]
fn single_view_dishes_from_above_table() {
    let mut cases = vec![("measured mug", measured_mug())];
    for (case, handle) in [(2u64, false), (7, true)] {
        let mut rng = Rng::new(case);
        let x = random_dish(&mut rng, handle);
        cases.push((
            if handle {
                "random cup 7"
            } else {
                "random bowl 2"
            },
            mesh_of("dish", &x, Lod::High),
        ));
    }
    eprintln!(
        "case            pitch°  IoU-64  photo-view  fitted pitch°  photo: IoU-64  fitted pitch°"
    );
    for (name, mesh) in &cases {
        let mut sum = [0.0f64; PITCHES.len()];
        let mut sum_photo = [0.0f64; PITCHES.len()];
        for (k, &pitch) in PITCHES.iter().enumerate() {
            let mut rng = Rng::new(31);
            let truth = view_at(&mut rng, mesh, 0.5, 0.0, pitch);
            let mask = render_mask(mesh, &truth, 256);
            let r = fit_dish(&mask, Vec::new());
            let iou = fit_iou64(&r, mesh, &truth);
            let pv = eval::result_photo_ious(&r, std::slice::from_ref(&mask)).unwrap()[0];
            let luma = photo_with_dark_rim(&mask, &projected_rim(mesh, &square_view(truth, 256)));
            let rp = fit_dish(&mask, vec![Some(luma)]);
            let iou_photo = fit_iou64(&rp, mesh, &truth);
            sum[k] = iou;
            sum_photo[k] = iou_photo;
            eprintln!(
                "{name:<15} {:>6.0}  {iou:.4}  {pv:.4}      {:>6.1}         {iou_photo:.4}  {:>6.1}",
                pitch.to_degrees(),
                r.views[0].params.pitch.to_degrees(),
                rp.views[0].params.pitch.to_degrees()
            );
        }
        let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
        eprintln!(
            "{name:<15} mean IoU-64 11–30°: {:.4}, 40–70°: {:.4}; with the photo's rim {:.4}, {:.4}",
            mean(&sum[..3]),
            mean(&sum[3..]),
            mean(&sum_photo[..3]),
            mean(&sum_photo[3..])
        );
    }
}

/// The rim of a lathed dish seen through `view`: its highest vertices, in order around their
/// centre, projected.
fn projected_rim(
    mesh: &procfit::generators::Mesh,
    view: &procfit::camera::View,
) -> Vec<glam::DVec2> {
    let top = mesh.positions.iter().map(|p| p.y).fold(f32::MIN, f32::max);
    let mut rim: Vec<glam::Vec3> = mesh
        .positions
        .iter()
        .copied()
        .filter(|p| p.y > top - 1e-4)
        .collect();
    let c = rim.iter().copied().sum::<glam::Vec3>() / rim.len() as f32;
    rim.sort_by(|a, b| {
        (a.z - c.z)
            .atan2(a.x - c.x)
            .total_cmp(&(b.z - c.z).atan2(b.x - c.x))
    });
    rim.iter().map(|&p| view.project(p).0).collect()
}

/// A dish fit of `mask` (field of view 0.5, 2000 stage-1 evaluations), with `photos`.
fn fit_dish(
    mask: &procfit::mask::Mask,
    photos: Vec<Option<Luma>>,
) -> procfit::reconstruct::FitResult {
    let config = FitConfig {
        generator: "dish".into(),
        fov_y: vec![Some(0.5)],
        budget: Some(2000),
        photos,
        ..FitConfig::default()
    };
    fit(config, vec![mask.clone()])
}

/// The rim term (`reconstruct::rim`) on a photo from 60° above: the measured mug (not the
/// generator's), its photo bright with the inside of its rim dark. From the mask alone the
/// camera comes out too low with a shape to suit it; with the photo, the fitted rim's near half
/// lies on the photo's edge and the camera's height and the shape follow.
#[test]
fn the_rim_in_a_photo_fixes_the_camera_from_above() {
    let mesh = measured_mug();
    let side = 256u32;
    let mut rng = Rng::new(31);
    let truth = view_at(&mut rng, &mesh, 0.5, 0.0, 1.05);
    let mask = render_mask(&mesh, &truth, side);
    let luma = photo_with_dark_rim(&mask, &projected_rim(&mesh, &square_view(truth, side)));
    let run = |photos| {
        let r = fit_dish(&mask, photos);
        (
            fit_iou64(&r, &mesh, &truth),
            r.views[0].params.pitch.to_degrees(),
        )
    };
    let (plain, plain_pitch) = run(Vec::new());
    let (with_rim, rim_pitch) = run(vec![Some(luma)]);
    let true_pitch = truth.pitch.to_degrees();
    eprintln!(
        "mask only: IoU-64 {plain:.3}, pitch {plain_pitch:.1}°; with the photo's rim: {with_rim:.3}, {rim_pitch:.1}° (true {true_pitch:.1}°)"
    );
    // Measured: mask only 0.835 from 37.5°, with the rim 0.851 from 43.2° (true 56.1°).
    assert!(
        (rim_pitch - true_pitch).abs() + 4.0 < (plain_pitch - true_pitch).abs(),
        "the rim did not bring the camera's height closer: {rim_pitch:.1}° against {plain_pitch:.1}° (true {true_pitch:.1}°)"
    );
    assert!(
        with_rim > plain - 0.01,
        "IoU-64 with the rim {with_rim:.3}, from the mask alone {plain:.3}"
    );
}
