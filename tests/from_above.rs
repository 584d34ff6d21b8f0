//! Issue 16, views from above: where a single-view dish fit loses as the camera rises from 11°
//! to 70° above the table. A measurement, not a check (`#[ignore]`, it prints a table):
//! `cargo test --release --test from_above -- --ignored --nocapture`.
//!
//! Measured (stage-1 pitch candidates 0.15, 0.45, 0.8 rad), IoU-64 from 11° / 20° / 30° / 40° /
//! 50° / 60° / 70°: the measured mug 0.981 / 0.979 / 0.968 / 0.965 / 0.953 / 0.836 / 0.772
//! (fitted elevation 37.5° for 60°, 54.4° for 70°); a random bowl 0.990 / 0.994 / 0.997 /
//! 0.998 / 0.985 / 0.844 / 0.784; a random cup 0.982 / 0.856 / 0.830 / 0.937 / 0.909 / 0.810 /
//! 0.868. The photo-view IoU stays ≥ 0.987 throughout: from 60° up, the silhouette is matched
//! by a camera too low and a shape to suit it (the elevation–shape trade of one view), which
//! no number the user sees reveals.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "a test binary: a failed step should stop it loudly"
)]

mod reconstruct_support;

use procfit::generators::Lod;
use procfit::optim::Rng;
use procfit::reconstruct::{FitConfig, eval};
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
    eprintln!("case            pitch°  IoU-64  photo-view  fitted pitch°");
    for (name, mesh) in &cases {
        let mut sum = [0.0f64; PITCHES.len()];
        for (k, &pitch) in PITCHES.iter().enumerate() {
            let mut rng = Rng::new(31);
            let truth = view_at(&mut rng, mesh, 0.5, 0.0, pitch);
            let mask = render_mask(mesh, &truth, 256);
            let config = FitConfig {
                generator: "dish".into(),
                fov_y: vec![Some(0.5)],
                budget: Some(2000),
                ..FitConfig::default()
            };
            let r = fit(config, vec![mask.clone()]);
            let iou = fit_iou64(&r, mesh, &truth);
            let pv = eval::result_photo_ious(&r, &[mask]).unwrap()[0];
            sum[k] = iou;
            eprintln!(
                "{name:<15} {:>6.0}  {iou:.4}  {pv:.4}      {:>6.1}",
                pitch.to_degrees(),
                r.views[0].params.pitch.to_degrees()
            );
        }
        let side = sum[..3].iter().sum::<f64>() / 3.0;
        let above = sum[3..].iter().sum::<f64>() / 4.0;
        eprintln!("{name:<15} mean IoU-64 11–30°: {side:.4}, 40–70°: {above:.4}");
    }
}
