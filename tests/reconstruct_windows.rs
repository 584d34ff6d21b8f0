//! The window term of a building fit ([`procfit::reconstruct::windows`]): a silhouette cannot
//! tell six storeys of 2.7 m from four of 4.05 m, nor three window stripes of 1.8 m from two of
//! 2.7 m; the window labels can. A building is rendered to a silhouette and window labels, and
//! fitted from a start with the wrong floor count and window columns (and the same outline),
//! with and without the window term.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "a test binary: a failed step should stop it loudly"
)]

mod reconstruct_support;

use procfit::camera::View;
use procfit::generators::{Lod, Mesh, building::idx};
use procfit::mask::{LabelImage, Mask};
use procfit::optim::Rng;
use procfit::reconstruct::{FitConfig, FitResult, Session};
use procfit::render::LabelRenderer;
use reconstruct_support::*;

const SIDE: u32 = 256;

/// The true building: one entrance, end sections of three window stripes, six storeys, plain
/// sides, flat roof.
fn truth() -> Vec<f64> {
    let g = generator("building");
    let mut x: Vec<f64> = g.params().iter().map(|s| s.default).collect();
    x[idx::ENTRANCES] = 1.0;
    x[idx::FLOORS] = 6.0;
    x[idx::FLOOR_HEIGHT] = 2.7;
    x[idx::END_STRIPES] = 3.0;
    for k in 0..5 {
        x[idx::END_CODE + k] = 1.0;
    }
    x[idx::WINDOW_STRIPE_WIDTH] = 1.8;
    x[idx::SIDE_STRIPES] = 1.0;
    x[idx::SIDE_CODE] = 0.0;
    x[idx::ROOF_TYPE] = 0.0;
    procfit::generators::sanitize_params(g.params(), &x).unwrap()
}

/// Same outline, wrong layout: four storeys of 4.05 m, two window stripes of 2.7 m per end.
fn wrong_start(truth: &[f64]) -> Vec<f64> {
    let mut x = truth.to_vec();
    x[idx::FLOORS] = 4.0;
    x[idx::FLOOR_HEIGHT] = 4.05;
    x[idx::END_STRIPES] = 2.0;
    x[idx::WINDOW_STRIPE_WIDTH] = 2.7;
    x
}

/// Window labels of `mesh` seen through `view` (0 background, 1 façade, 2 window).
fn window_labels(mesh: &Mesh, view: &View) -> LabelImage {
    let tri: Vec<u8> = mesh
        .tri_parts
        .iter()
        .map(|&p| {
            if mesh.parts[usize::from(p)].name.starts_with("window") {
                2
            } else {
                1
            }
        })
        .collect();
    let mut r = LabelRenderer::new(view.width, view.height, 3).unwrap();
    r.render(&mesh.positions, &mesh.triangles, &tri, 3, view)
        .unwrap();
    r.label_image(0).unwrap()
}

/// Window columns on the front façade: distinct x-intervals of glass faces facing +z.
fn front_window_columns(params: &[f64]) -> usize {
    let mesh = mesh_of("building", params, Lod::High);
    let mut cols: Vec<(i64, i64)> = Vec::new();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        if mesh.parts[usize::from(mesh.tri_parts[t])].name != "window_glass" {
            continue;
        }
        let p = tri.map(|i| mesh.positions[i as usize]);
        let flat = (p[0].z - p[1].z).abs() < 1e-4 && (p[0].z - p[2].z).abs() < 1e-4;
        if !flat || p[0].z <= 0.0 {
            continue;
        }
        let lo = p.iter().map(|q| q.x).fold(f32::INFINITY, f32::min);
        let hi = p.iter().map(|q| q.x).fold(f32::NEG_INFINITY, f32::max);
        if hi - lo < 0.1 {
            // An edge of a side façade's pane, not a front pane.
            continue;
        }
        let key = ((lo * 100.0).round() as i64, (hi * 100.0).round() as i64);
        if !cols.contains(&key) {
            cols.push(key);
        }
    }
    cols.len()
}

struct Case {
    truth: Vec<f64>,
    view: procfit::camera::ViewParams,
    mask: Mask,
    labels: LabelImage,
}

fn case() -> Case {
    case_seeded(3)
}

fn case_seeded(seed: u64) -> Case {
    let truth = truth();
    let mesh = mesh_of("building", &truth, Lod::High);
    let mut rng = Rng::new(seed);
    let params = view_at(&mut rng, &mesh, 0.5, 0.0, 0.2);
    let mask = render_mask(&mesh, &params, SIDE);
    let view = square_view(params, SIDE);
    let labels = window_labels(&mesh, &view);
    Case {
        truth,
        view: params,
        mask,
        labels,
    }
}

/// A fit of `c`'s mask from its wrong start: with `windows`, the best of its runs that fit
/// `c`'s window labels (kept, or left out with the outline's cost said:
/// [`Session::windows_left_out`]); without, the fit's result.
fn run(c: &Case, windows: bool) -> FitResult {
    let labels = windows.then(|| c.labels.clone());
    let (result, session) = run_with(c, labels);
    if !windows {
        return result;
    }
    let [(framed, with), (_, without)] = session.window_candidates().unwrap();
    match session.windows_left_out() {
        None => assert_eq!(session.kept_run(), Some(framed)),
        Some(said) => {
            assert_eq!(said, (with, without));
            assert!(with < without - procfit::reconstruct::WINDOW_OUTLINE_SLACK);
        }
    }
    session.run_results()[framed].unwrap().clone()
}

/// A fit of `c`'s mask from its wrong start, with `labels` as its window labels when given;
/// the result and the session.
fn run_with(c: &Case, labels: Option<LabelImage>) -> (FitResult, Session) {
    let config = FitConfig {
        generator: "building".into(),
        fov_y: vec![Some(0.5)],
        budget: Some(3000),
        start: Some(wrong_start(&c.truth)),
        windows: labels.into_iter().map(Some).collect(),
        ..FitConfig::default()
    };
    let mut session = Session::new(config, vec![c.mask.clone()]).unwrap();
    let result = session.run().unwrap();
    (result, session)
}

#[test]
fn the_start_is_wrong_in_the_ways_a_silhouette_cannot_see() {
    let c = case();
    let start = wrong_start(&c.truth);
    assert_eq!(front_window_columns(&c.truth), 7);
    assert_eq!(front_window_columns(&start), 5);
    // The outline is the same: height and length agree to the millimetre.
    let (a, b) = (
        mesh_of("building", &c.truth, Lod::Low),
        mesh_of("building", &start, Lod::Low),
    );
    let (alo, ahi) = a.bounds().unwrap();
    let (blo, bhi) = b.bounds().unwrap();
    assert!((ahi - alo - (bhi - blo)).abs().max_element() < 1e-3);
    // The labels show windows.
    let windows = c.labels.labels().iter().filter(|&&l| l == 2).count();
    let facade = c.labels.labels().iter().filter(|&&l| l == 1).count();
    assert!(
        windows > 200 && facade > windows,
        "{windows} window and {facade} façade pixels"
    );
}

/// The runs fitted to the true labels find the floors and columns. Whether the fit keeps one
/// depends on the outline ([`procfit::reconstruct::WINDOW_OUTLINE_SLACK`]): measured, the best
/// of them outlines the mask at 0.984, the runs of the outline alone at 0.989, so the fit says
/// it left them out (on the building benchmark's photos the rule loses less than it saves).
#[test]
fn window_labels_settle_floors_and_window_columns() {
    let c = case();
    let with = run(&c, true);
    let without = run(&c, false);
    let (pw, po) = (&with.model.params, &without.model.params);
    eprintln!(
        "with windows: {} floors, {} front window columns, loss {:.5}; without: {} floors, {} columns, loss {:.5}; truth 6 floors, 7 columns",
        pw[idx::FLOORS],
        front_window_columns(pw),
        with.loss,
        po[idx::FLOORS],
        front_window_columns(po),
        without.loss
    );
    assert_eq!(pw[idx::FLOORS], 6.0, "floors with the window term");
    assert_eq!(
        front_window_columns(pw),
        7,
        "front window columns with the window term"
    );
    // The outline is still fitted (the single-view bar for buildings).
    let iou = fit_iou64(&with, &mesh_of("building", &c.truth, Lod::High), &c.view);
    assert!(iou >= 0.9, "IoU-64 with the window term {iou:.4}");
}

/// Window labels that disagree with the outline (a taller building's façade and windows, as
/// labels made elsewhere can say through `FitConfig::windows`): the runs that fit them give up
/// some of the outline, and the fit keeps a run of the outline alone, the fit without the
/// labels, and says so.
#[test]
fn window_labels_the_outline_contradicts_are_left_out() {
    let c = case();
    let view = square_view(c.view, SIDE);
    let mut taller = c.truth.clone();
    taller[idx::FLOORS] = 9.0;
    let labels = window_labels(&mesh_of("building", &taller, Lod::High), &view);
    let (result, session) = run_with(&c, Some(labels));
    let left_out = session.windows_left_out();
    let (with, without) = left_out.expect("the windows were kept");
    eprintln!("outline with the windows {with:.4}, without {without:.4}");
    assert!(with < without - procfit::reconstruct::WINDOW_OUTLINE_SLACK);
    let ious =
        procfit::reconstruct::eval::result_photo_ious(&result, std::slice::from_ref(&c.mask))
            .unwrap();
    assert!(
        (ious[0] - without).abs() < 1e-9 && ious[0] >= 0.97,
        "the kept model's outline {:.4}",
        ious[0]
    );
    let note = procfit::reconstruct::eval::windows_left_out_note(left_out).unwrap();
    assert!(note.contains("left out"), "{note}");
    assert!(
        note.contains(&format!("IoU {with:.3} against {without:.3}")),
        "{note}"
    );
    assert!(!note.contains("  "), "one line, single-spaced: {note}");
    // The runs of the outline are the fit's without labels: left out, the windows change nothing.
    let (without_labels, none) = run_with(&c, None);
    assert_eq!(none.windows_left_out(), None);
    assert_eq!(result.model.params, without_labels.model.params);
}

#[test]
fn window_labels_of_another_size_are_refused() {
    let c = case();
    let small = LabelImage::new(8, 8, vec![1; 64]).unwrap();
    let config = FitConfig {
        generator: "building".into(),
        windows: vec![Some(small)],
        ..FitConfig::default()
    };
    let err = Session::new(config, vec![c.mask.clone()]).err().unwrap();
    assert!(
        err.0.contains("window labels of view 0 are 8×8"),
        "{}",
        err.0
    );
    let bad = LabelImage::new(SIDE, SIDE, vec![7; (SIDE * SIDE) as usize]).unwrap();
    let config = FitConfig {
        generator: "building".into(),
        windows: vec![Some(bad)],
        ..FitConfig::default()
    };
    let err = Session::new(config, vec![c.mask.clone()]).err().unwrap();
    assert!(err.0.contains("label 7"), "{}", err.0);
    let config = FitConfig {
        generator: "building".into(),
        windows: vec![None, None],
        ..FitConfig::default()
    };
    let err = Session::new(config, vec![c.mask.clone()]).err().unwrap();
    assert!(
        err.0.contains("2 window label images for 1 views"),
        "{}",
        err.0
    );
}

/// Other cameras of the same building, printed (`cargo test --test reconstruct_windows --
/// --ignored --nocapture`; `SEEDS=5,7` picks them). Measured: floors right for cameras 3, 5,
/// 7, 11; front window columns right for 3 and 11, wrong for 5 (8) and 7 (10, two entrances):
/// the greedy sweep changes one discrete value at a time, and a different entrance count
/// needs several at once.
#[test]
#[ignore = "slow exploration (about 30 s a camera); prints, asserts nothing"]
fn other_cameras() {
    let seeds: Vec<u64> = std::env::var("SEEDS").map_or(vec![5, 7, 11], |s| {
        s.split(',').map(|v| v.parse().unwrap()).collect()
    });
    for seed in seeds {
        let c = case_seeded(seed);
        let r = run(&c, true);
        eprintln!(
            "seed {seed}: {} floors, {} columns; structure {:?} codes {:?} loss {:.5} evaluations {}",
            r.model.params[idx::FLOORS],
            front_window_columns(&r.model.params),
            &r.model.params[..5],
            &r.model.params[5..20],
            r.loss,
            r.evaluations
        );
    }
}

/// The page's building sample (www/samples/flats.jpg, rendered by procfit; 4 floors, 7 front
/// window columns), segmented and its windows found as the page does, fitted at a few qualities
/// with and without the window term; prints floors and window columns (`QUALITIES=0.25,1`).
/// Measured: with windows 4 floors at both qualities (7 and 8 columns: the true layout at
/// quality 0.25); without, 3 and 9 floors (7 and 11 columns). The window sweep costs
/// 3500–5000 evaluations at 128².
#[test]
#[ignore = "slow exploration; prints, asserts nothing"]
fn flats_sample() {
    use procfit::segment::{Photo, WORKING_SIDE, segment, windows::detect_windows};
    let root = env!("CARGO_MANIFEST_DIR");
    let bytes = std::fs::read(format!("{root}/www/samples/flats.jpg")).unwrap();
    let photo = Photo::decode(&bytes, WORKING_SIDE).unwrap();
    let seg = segment(&photo).unwrap();
    let labels = detect_windows(&photo, &seg).unwrap();
    let qualities: Vec<f64> = std::env::var("QUALITIES").map_or(vec![0.25, 1.0], |s| {
        s.split(',').map(|v| v.parse().unwrap()).collect()
    });
    for q in qualities {
        for windows in [true, false] {
            let config = FitConfig {
                generator: "building".into(),
                seed: 1,
                quality: q,
                windows: if windows {
                    vec![Some(labels.clone())]
                } else {
                    Vec::new()
                },
                ..FitConfig::default()
            };
            let r = fit(config, vec![seg.mask.clone()]);
            let p = &r.model.params;
            eprintln!(
                "quality {q} windows {windows}: {} floors, {} front window columns, loss {:.5}, {} evaluations; structure {:?}",
                p[idx::FLOORS],
                front_window_columns(p),
                r.loss,
                r.evaluations,
                &p[..5]
            );
        }
    }
}
