//! The independent building benchmark in CI (issue 15): two of the buildings of
//! `procfit::building_bench` (written there, not by procfit's generator) fitted at a reduced
//! budget must keep their IoU-64 above a stated level — from the clean mask and from the photo
//! on textured ground; and the paper's own test building, when its (unlicensed, never copied)
//! file is present beside the checkout, from one mask at each of three cameras. Measured
//! levels: see the constants and `cargo bench --bench building_bench -- --quick`.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "a test binary: a failed step should stop it loudly"
)]

use procfit::building_bench::{
    Input, PAPER_CAMERAS, case_view, cases, fit_and_score, input_mask, paper_building,
};
use std::path::PathBuf;

/// Quality of the fits here (the bench's `--quick`).
const QUALITY: f64 = 0.4;

fn check(name: &str, input: Input, min: f64) {
    let case = cases()
        .unwrap()
        .into_iter()
        .find(|c| c.name == name)
        .unwrap();
    let mask = input_mask(&case.mesh, &case.view, input).unwrap();
    let s = fit_and_score(&case.mesh, &case.view, mask, QUALITY).unwrap();
    eprintln!("{name} ({}): {s:?}", input.name());
    assert!(
        s.iou64 >= min,
        "{name} ({}): IoU-64 {:.3} < {min}",
        input.name(),
        s.iou64
    );
}

#[test]
fn gable_house_from_its_mask() {
    check("gable-chimney", Input::Mask, 0.90);
}

#[test]
fn l_shaped_house_on_textured_ground() {
    check("l-gable", Input::Textured, 0.85);
}

#[test]
fn paper_building_from_three_cameras() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/data/paper/building_test_2_original.obj");
    let Some(mesh) = paper_building(&path).unwrap() else {
        eprintln!(
            "skipped: the paper's building is not at {} (it has no licence and is never in the repository)",
            path.display()
        );
        return;
    };
    for (yaw, pitch) in PAPER_CAMERAS {
        let view = case_view(&mesh, yaw.to_radians(), pitch.to_radians()).unwrap();
        let mask = input_mask(&mesh, &view, Input::Mask).unwrap();
        let s = fit_and_score(&mesh, &view, mask, QUALITY).unwrap();
        eprintln!("paper building at ({yaw}°, {pitch}°): {s:?}");
        assert!(
            s.iou64 >= 0.80,
            "paper building at ({yaw}°, {pitch}°): IoU-64 {:.3}",
            s.iou64
        );
    }
}
