//! The independent building benchmark in CI (issue 15): two of the buildings of
//! `procfit::building_bench` (written there, not by procfit's generator) fitted at a reduced
//! budget must keep their IoU-64 above a stated level — from the clean mask and from the photo
//! on textured ground; and the paper's own test building, when its (unlicensed, never copied)
//! file is present beside the checkout, from one mask at each of three cameras. Measured
//! levels are beside each test (`cargo bench --bench building_bench l-hip shed-studio paper`).
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "a test binary: a failed step should stop it loudly"
)]

use procfit::bench_cases::BenchFit;
use procfit::building_bench::{
    BenchBuilding, BenchScore, Input, PAPER_CAMERAS, case_named, case_view, cases, fit_and_score,
    fit_and_score_input, input_mask, paper_building,
};
use procfit::generators::building::Building;
use procfit::reconstruct::eval::{agreement_warning, photo_match_level, photo_match_warning};
use std::path::PathBuf;

/// Quality of the fits here: the default (at the bench's `--quick` 0.4 single-view fits land
/// in other basins too often to hold a level: l-hip 0.747 there, 0.964 at the default), with the
/// page's and the CLI's number of runs for a building (`FitConfig::restarts_for`, six). About
/// 3 s a fit on 2 threads in release.
const QUALITY: f64 = 1.0;

/// The fits here: [`QUALITY`], the default seed, every run scored or not.
fn settings(each: bool) -> BenchFit {
    BenchFit {
        quality: QUALITY,
        seed: 0,
        each,
        runs: None,
        windows: false,
    }
}

/// The photo of `case` on `input`'s ground as the segmentation reads it.
fn photo_of(case: &BenchBuilding, input: Input) -> procfit::segment::Photo {
    let px = procfit::building_bench::photo(&case.mesh, &case.view, input).unwrap();
    procfit::segment::Photo::from_rgba(
        case.view.width,
        case.view.height,
        &px,
        procfit::segment::WORKING_SIDE,
    )
    .unwrap()
}

fn check(name: &str, input: Input, min: f64) -> BenchScore {
    check_seeded(name, input, min, settings(true).seed)
}

/// [`check`] with the fit's seed `seed`.
fn check_seeded(name: &str, input: Input, min: f64, seed: u64) -> BenchScore {
    let case = case_named(name).unwrap();
    // Every run scored too (the bench's `--each`): one of them is the fit.
    let fit = BenchFit {
        seed,
        ..settings(true)
    };
    let s = fit_and_score_input(&case.mesh, &case.view, input, fit).unwrap();
    eprintln!("{name} ({}): {s:?}", input.name());
    let kept: Vec<_> = s.runs.iter().filter(|r| r.kept).collect();
    assert_eq!(kept.len(), 1, "{name}: one run is kept");
    assert_eq!(kept[0].iou64, s.iou64);
    assert!(
        s.runs
            .iter()
            .all(|r| r.loss >= kept[0].loss * 0.9 && !r.shape.is_empty())
    );
    assert!(
        s.iou64 >= min,
        "{name} ({}): IoU-64 {:.3} < {min}",
        input.name(),
        s.iou64
    );
    s
}

/// What the CLI and the page say of how the fit matches its photo (`None`: it matches), from
/// the fit's photo-view IoU against the mask it was given and the building's level.
fn match_warning(s: &BenchScore) -> Option<String> {
    photo_match_warning(&[s.mask_photo_iou], &[], photo_match_level(&Building))
}

/// Measured 0.958 (0.753 before the generator had L footprints). The runs that match the
/// mask about as well agree on the shape, and the fit outlines the mask (photo-view IoU 0.987
/// measured): no warning of either kind, and no runs added.
#[test]
fn l_shaped_house_from_its_mask() {
    let s = check("l-hip", Input::Mask, 0.90);
    assert!(
        agreement_warning(s.agreement, s.front_only).is_none(),
        "agreement {:?}",
        s.agreement
    );
    assert_eq!(match_warning(&s), None);
    assert_eq!(s.runs.len(), 6, "no rescue runs for a fit that matches");
}

/// A box read from an L does not outline it, and then the fit tries L-shaped footprints: the L
/// with flat roofs from its mask at seed 1 was kept as a box by all six runs (IoU-64 0.556,
/// photo-view IoU below the building's level 0.97); the two runs the fit adds from the
/// generator's rescue seeds find the L (0.882 measured, 0.993), and one of them is kept. (This
/// was the L on a gradient at seed 4, 0.595 → 0.988, until the building's photos were cut
/// closer to their outline: its first six runs find the L now.)
#[test]
fn a_box_that_does_not_outline_its_photo_is_refitted_from_l_seeds() {
    let s = check_seeded("l-flat", Input::Mask, 0.85, 1);
    assert_eq!(s.runs.len(), 8, "six runs and two rescue runs");
    let kept = s.runs.iter().position(|r| r.kept);
    assert!(kept.is_some_and(|k| k >= 6), "kept run {kept:?}");
    assert_eq!(match_warning(&s), None);
}

/// The shed-roofed studio from its mask at seed 3: the fit found the right box and roof
/// (IoU-64 0.987 at MEDIUM detail), but stage 1, at LOW detail where a balcony stripe is a
/// window stripe, had made stripes on both ends balconies, which stood out of the walls at the
/// HIGH detail a fitted building is shown and scored at: 0.798. Stage 3 now starts by taking
/// off the balconies its views do not ask for (`Generator::plain_range`): 0.992 measured.
#[test]
fn a_fit_adds_no_balconies_it_cannot_see() {
    check_seeded("shed-studio", Input::Mask, 0.95, 3);
}

/// The L with flat roofs from its mask at seed 3: the fit keeps a run scoring IoU-64 0.734 (at
/// HIGH detail, as it is saved), while another matching the mask about as well scores 0.903.
/// The runs' 3D agreement was measured at MEDIUM detail, where balcony slabs, doors and stairs
/// are not built, and said 0.990: no warning. At the detail the fit ends at and saves it is
/// 0.804, and the fit says the shape is a guess.
#[test]
fn runs_are_compared_at_the_detail_the_fit_saves() {
    let s = check_seeded("l-flat", Input::Mask, 0.70, 3);
    let w = agreement_warning(s.agreement, s.front_only);
    assert!(w.is_some(), "agreement {:?}", s.agreement);
}

/// The hip-roofed bungalow seen from its end at eye level (2° up), from its mask: one view shows
/// neither its length nor its ridge, and the fit's runs match the mask about as well with
/// different shapes (3D agreement 0.618 measured; the kept one scores IoU-64 0.675). The CLI and
/// the page must say so rather than present the fit as the building. (This was the house with
/// two dormers on textured ground at seed 1 until the building's photos were cut closer to
/// their outline: it is fitted right now, 0.920, and of the benchmark's fits over five seeds
/// only the paper's building from (140°, 28°) at seed 3 is warned. Before that the L with flat
/// roofs on textured ground at seed 2 until the fit added runs from L-shaped footprints, the L
/// with hip roofs on plain ground at the default seed until every other restart held the hip
/// ridge at the middle; the house with two dormers on a gradient until the hip roof's ridge
/// length; the five-storey block on a gradient until the generator had chimneys. The agreement
/// only sees what the runs disagree on: seen straight from the front at eye level the flat
/// block, the shed-roofed studio and the gable house are fitted at the wrong depth (IoU-64
/// 0.72–0.85) by runs that agree on it; `eval::depth_agreement` finds such a depth a guess,
/// from a few degrees up by the photo (the tower below), at eye level by where the camera
/// stands (the studio below).)
#[test]
fn a_house_whose_shape_the_photo_does_not_fix_is_flagged() {
    let case = case_named("hip-bungalow").unwrap();
    let view = case_view(&case.mesh, 90f64.to_radians(), 2f64.to_radians()).unwrap();
    let s = fit_and_score_input(&case.mesh, &view, Input::Mask, settings(true)).unwrap();
    eprintln!("hip-bungalow from its end: {s:?}");
    let w = agreement_warning(s.agreement, s.front_only);
    assert!(w.is_some(), "agreement {:?}", s.agreement);
    assert!(w.unwrap().contains("add a photo from another side"));
}

/// The eight-storey tower seen straight from the front, 3° up, from its mask: the photo shows
/// its front and nothing of how far it reaches back. The fit's runs agree on one depth (the
/// seeds' proportions), so they alone would not say so; the same front reaching 1.6 times as
/// far back matches the mask as well (`eval::depth_agreement`), and the fit says the shape is
/// a guess (agreement 0.775 measured; 0.987 from the runs alone; the kept one happens to score
/// IoU-64 0.922).
#[test]
fn a_tower_seen_straight_on_is_said_to_be_a_guess_in_depth() {
    let case = case_named("tower").unwrap();
    let view = case_view(&case.mesh, 0.0, 3f64.to_radians()).unwrap();
    let s = fit_and_score_input(&case.mesh, &view, Input::Mask, settings(true)).unwrap();
    eprintln!("tower straight on: {s:?}");
    let w = agreement_warning(s.agreement, s.front_only);
    assert!(w.is_some(), "agreement {:?}", s.agreement);
}

/// The shed-roofed studio photographed straight from the front at eye level (1° up), from its
/// mask: the photo shows its front and nothing of how far it reaches back, and the fit's runs
/// agree on a wrong depth and roof (IoU-64 0.735 measured, photo-view IoU 0.994, 3D agreement
/// of the runs none). The camera stands before the front, below the roof's top
/// (`eval::front_only`), so the fit says the depth is a guess, and why (agreement 0.832
/// measured).
#[test]
fn a_facade_seen_straight_on_at_eye_level_is_said_to_be_a_guess_in_depth() {
    let case = case_named("shed-studio").unwrap();
    let view = case_view(&case.mesh, 0.0, 1f64.to_radians()).unwrap();
    let s = fit_and_score_input(&case.mesh, &view, Input::Mask, settings(true)).unwrap();
    eprintln!("shed studio straight on: {s:?}");
    assert!(s.front_only, "the camera was fitted elsewhere");
    let w = agreement_warning(s.agreement, s.front_only);
    assert!(
        w.as_deref()
            .is_some_and(|w| w.contains("only the front") && w.contains("its depth")),
        "agreement {:?}: {w:?}",
        s.agreement
    );
}

/// Measured 0.977 (0.777 before the generator had shed roofs); the photo on textured ground
/// goes through the automatic segmentation, and the fit outlines its automatic mask (0.992):
/// not said to be a mismatch. The roof's colour measured in the photo (issue 17)
/// is the colour it was drawn with, ΔE 0.7 (CIE76); the walls come out ΔE 21 darker: the
/// photo's sun is high, so no wall is seen fully lit, and one photo cannot tell a dark wall
/// from a wall in the shade.
#[test]
fn shed_roof_on_textured_ground() {
    let s = check("shed-studio", Input::Textured, 0.90);
    assert_eq!(match_warning(&s), None);
    let roof = s.colour_de.and_then(|(_, roof)| roof);
    assert!(roof.is_some_and(|d| d <= 6.0), "roof colour ΔE {roof:?}");
}

/// "Find windows" on the shed-roofed studio's photo on textured ground: the runs fitted to the
/// windows found in it (three added to the six) match the outline less well than the others,
/// so the fit leaves the windows out, says so, and is the fit without them. Measured at seeds
/// 0 and 1 (with half of the six fitting the windows): 0.980 and 0.990, left out (0.991
/// without windows at seed 1); 0.743 at seed 1 when every run fitted the windows.
#[test]
fn windows_that_cost_the_outline_are_left_out() {
    let case = case_named("shed-studio").unwrap();
    let fit = BenchFit {
        windows: true,
        ..settings(false)
    };
    let s = fit_and_score_input(&case.mesh, &case.view, Input::Textured, fit).unwrap();
    eprintln!("{s:?}");
    assert!(s.windows_left_out, "the windows were kept");
    assert!(s.iou64 >= 0.95, "IoU-64 {:.3}", s.iou64);
    assert_eq!(match_warning(&s), None);
}

/// Measured 0.925 (0.636 before: the fit took the plain photo's house for an L whose wing hid
/// behind the main block; Occam's step now tries the rectangle). The segmented mask itself is
/// the true one within a pixel or two of the outline.
#[test]
fn gable_house_on_plain_ground() {
    check("gable-chimney", Input::Plain, 0.90);
}

/// Measured 0.907 (0.681 before: stage 1 rarely reached an L and the fit settled on a
/// rectangle; the L house is now an extra seed that joins when it screens better; 0.840 with
/// three runs).
#[test]
fn l_shaped_gable_house_on_plain_ground() {
    check("l-gable", Input::Plain, 0.80);
}

/// Measured 0.811 (0.594 with three runs, when all three ended in a wrong footprint's basin
/// at 2.5–3 times the loss of the right one; 0.879 when measured with an earlier version).
#[test]
fn l_shaped_flat_block_on_plain_ground() {
    check("l-flat", Input::Plain, 0.80);
}

/// Measured 0.927 / 0.935 / 0.946 at this seed (0.939 / 0.935 / 0.946 before stage 3 took off
/// the balconies its views do not ask for; 0.891 / 0.742 / 0.797 before the hip roof's ridge
/// length and the odd restarts' middle ridge). Over seeds 0–4 the means per camera are 0.944 /
/// 0.938 / 0.940 and single fits go down to 0.886 (from (−55°, 18°) at seed 3), so the
/// issue's 0.92 each is not reached at every seed; the level guards against a regression
/// below that.
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
        let s = fit_and_score(&mesh, &view, mask, settings(false)).unwrap();
        eprintln!("paper building at ({yaw}°, {pitch}°): {s:?}");
        assert!(
            s.iou64 >= 0.85,
            "paper building at ({yaw}°, {pitch}°): IoU-64 {:.3}",
            s.iou64
        );
    }
}

/// The IoU of two masks (coverage above one half).
fn mask_iou(a: &procfit::mask::Mask, b: &procfit::mask::Mask) -> f64 {
    let (a, b) = (a.values(), b.values());
    assert_eq!(a.len(), b.len());
    let both = a
        .iter()
        .zip(b)
        .filter(|(x, y)| **x > 0.5 && **y > 0.5)
        .count();
    let either = a
        .iter()
        .zip(b)
        .filter(|(x, y)| **x > 0.5 || **y > 0.5)
        .count();
    both as f64 / either as f64
}

/// A building's photo is cut for a building (`Capabilities::outline_smoothing`): the L with
/// flat roofs on textured ground, whose shaded wall's foot is close in colour to the ground, lost
/// a wedge of it to the cut's smoothness as the default cuts it (405 pixels, mask IoU 0.974
/// measured) and keeps it cut as a building's (46 pixels, 0.994).
#[test]
fn a_building_photo_is_cut_into_its_corners() {
    let case = case_named("l-flat").unwrap();
    let truth = input_mask(&case.mesh, &case.view, Input::Mask).unwrap();
    let p = photo_of(&case, Input::Textured);
    let iou = |opts: &procfit::segment::Options| {
        mask_iou(
            &procfit::segment::segment_auto_with(&p, opts)
                .unwrap()
                .object,
            &truth,
        )
    };
    let default = iou(&procfit::segment::Options::default());
    let building = iou(&procfit::segment::Options::for_generator(Some(&Building)));
    assert!(
        building >= 0.985 && building >= default + 0.01,
        "mask IoU as a building's {building:.4}, by default {default:.4}"
    );
}

/// Issue 15, the mask's confidence means something: every photo of the benchmark (ten
/// buildings on plain, gradient and textured ground) is segmented as the CLI does for a
/// building, and the automatic masks must be right (IoU ≥ 0.96 against the true silhouette,
/// mean ≥ 0.985) and mostly not flagged for the user to check. Measured: mean IoU 0.993,
/// lowest 0.985 (the hip-roofed bungalow on plain ground; as a dish's photo is cut 0.991 and
/// 0.974, the five-storey block on the gradient, 0.958 before the segmentation's last cut near
/// the outline kept the wall below its lowest windows), 25 of 30 not flagged (26 as a dish's
/// photo is cut: the finer cut follows the grass's grain a little, and one more outline on
/// textured ground falls under the edge check's level; 14 before the mask check measured the
/// outline's edges against the surroundings' alone and the frame check followed a horizon).
#[test]
fn photo_masks_are_right_and_not_doubted() {
    let (mut sum, mut n, mut trusted) = (0.0, 0usize, 0usize);
    let mut report = Vec::new();
    for case in cases().unwrap() {
        let truth = input_mask(&case.mesh, &case.view, Input::Mask).unwrap();
        for input in [Input::Plain, Input::Gradient, Input::Textured] {
            let p = photo_of(&case, input);
            let opts = procfit::segment::Options::for_generator(Some(&Building));
            let seg = procfit::segment::segment_auto_with(&p, &opts).unwrap();
            let iou = mask_iou(&seg.object, &truth);
            let doubted = seg.is_low_confidence();
            report.push(format!(
                "{} {}: IoU {iou:.3}, confidence {:.2} {:?}",
                case.name,
                input.name(),
                seg.confidence,
                seg.warnings
            ));
            assert!(iou >= 0.96, "{}", report.join("\n"));
            sum += iou;
            n += 1;
            trusted += usize::from(!doubted);
        }
    }
    eprintln!("{}", report.join("\n"));
    assert!(sum / n as f64 >= 0.985, "mean IoU {:.4}", sum / n as f64);
    assert!(
        trusted * 10 >= n * 8,
        "only {trusted} of {n} right masks not doubted"
    );
}
