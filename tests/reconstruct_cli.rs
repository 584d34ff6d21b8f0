//! The `reconstruct`, `render` and `eval` subcommands as a user runs them: `--help`, a
//! render → reconstruct → eval round trip, and bad input ending in one line on stderr with a
//! non-zero exit code.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "a test binary: a failed step should stop it loudly"
)]

mod cli_support;

use cli_support::{fails_with, procfit, run_ok, s};
use std::path::{Path, PathBuf};

fn scratch(name: &str) -> PathBuf {
    cli_support::scratch("recon-cli", name)
}

fn write_png(path: &Path, w: u32, h: u32, f: impl Fn(u32, u32) -> u8) {
    image::GrayImage::from_fn(w, h, |x, y| image::Luma([f(x, y)]))
        .save(path)
        .unwrap();
}

#[test]
fn every_subcommand_has_help() {
    for sub in ["reconstruct", "render", "eval"] {
        let out = procfit(&[sub, "--help"]);
        assert!(out.status.success(), "{sub} --help failed");
        assert!(String::from_utf8_lossy(&out.stdout).contains("Usage"));
    }
}

#[test]
fn render_reconstruct_eval_round_trip() {
    let cam = scratch("cam.json");
    std::fs::write(
        &cam,
        r#"{"yaw": 0.3, "pitch": 0.4, "ty": -0.3, "fov_y": 0.5}"#,
    )
    .unwrap();
    let mask = scratch("mug.png");
    run_ok(&[
        "render",
        "--generator",
        "dish",
        "--preset",
        "mug",
        "--camera",
        s(&cam),
        "--size",
        "160",
        "-o",
        s(&mask),
    ]);
    let (glb, params) = (scratch("fit.glb"), scratch("fit.json"));
    let (said, err) = run_ok(&[
        "reconstruct",
        "--generator",
        "dish",
        "--fov",
        "0.5",
        "--budget",
        "600",
        "--quality",
        "0.5",
        "--lod",
        "0",
        s(&mask),
        "-o",
        s(&glb),
        "--params-out",
        s(&params),
    ]);
    assert!(
        err.contains("stage 3/3") && err.contains("ETA"),
        "progress: {err}"
    );
    assert!(
        !err.contains("does not match"),
        "a good fit is not warned about: {err}"
    );
    // What one photo of a mug cannot tell is said (`eval::one_view_caveat`).
    assert!(
        said.contains("note: one photo cannot tell a handle turned towards the camera"),
        "{said}"
    );
    let doc = procfit::model::Model::from_json(&std::fs::read_to_string(&params).unwrap()).unwrap();
    assert_eq!(doc.generator.name(), "dish");
    let reference = scratch("ref.glb");
    assert!(
        procfit(&[
            "generate",
            "--generator",
            "dish",
            "--preset",
            "mug",
            "-o",
            s(&reference)
        ])
        .status
        .success()
    );
    let (text, _) = run_ok(&[
        "eval",
        "--reference",
        s(&reference),
        s(&glb),
        "--mask",
        s(&mask),
    ]);
    let value = |key: &str| -> f64 {
        let line = text.lines().find(|l| l.starts_with(key)).unwrap();
        line[key.len()..]
            .split_whitespace()
            .next()
            .unwrap()
            .parse()
            .unwrap()
    };
    // The GLB's camera must re-project the model onto the input mask.
    assert!(value("input-view IoU:") > 0.95, "{text}");
    // The photo-view IoU `reconstruct` printed is the written model's, at the detail it was
    // written at (`--lod 0`: 0.984 measured, where the fit's own detail gives 0.996).
    let printed = last_photo_view_iou(&said);
    assert!(
        (printed - value("input-view IoU:")).abs() < 0.0011,
        "printed {printed}: {text}"
    );
    assert!(value("IoU-64:") > 0.9, "{text}");

    // Refit from the fitted GLB: the generator comes from it; a contradicting one is refused.
    let refit = scratch("refit.glb");
    let (said, _) = run_ok(&[
        "reconstruct",
        "--start",
        s(&glb),
        "--fov",
        "0.5",
        "--budget",
        "300",
        "--quality",
        "0.5",
        "--restarts",
        "1",
        s(&mask),
        "-o",
        s(&refit),
    ]);
    assert!(said.contains("dish fitted"), "{said}");
    assert!(said.contains("photo-view IoU"), "{said}");
    assert!(
        said.contains("lod 2,"),
        "the default level of detail is 2: {said}"
    );

    // Issue 17: `--lod` and OBJ out (with its MTL), from the same fit.
    let (obj, obj_params) = (scratch("refit.obj"), scratch("refit-obj.json"));
    let mtl = obj.with_extension("mtl");
    let _ = std::fs::remove_file(&mtl);
    let (said, _) = run_ok(&[
        "reconstruct",
        "--start",
        s(&glb),
        "--fov",
        "0.5",
        "--budget",
        "300",
        "--quality",
        "0.5",
        "--restarts",
        "1",
        "--lod",
        "1",
        s(&mask),
        "-o",
        s(&obj),
        "--params-out",
        s(&obj_params),
    ]);
    assert!(
        said.contains("lod 1,") && said.contains("watertight"),
        "{said}"
    );
    let fitted =
        procfit::model::Model::from_json(&std::fs::read_to_string(&obj_params).unwrap()).unwrap();
    assert_eq!(fitted.lod, procfit::generators::Lod::Medium);
    let mesh = fitted
        .generator
        .generate(&fitted.params, fitted.lod)
        .unwrap();
    let back = procfit::glb::import_obj(&std::fs::read(&obj).unwrap()).unwrap();
    assert_eq!(
        back.triangles.len(),
        mesh.triangles.len(),
        "the OBJ is the lod 1 mesh"
    );
    assert!(
        std::fs::read_to_string(&mtl)
            .unwrap()
            .contains("newmtl body")
    );
    for (args, needle) in [
        (
            vec!["--generator", "building", "--start", s(&params)],
            "is a dish model",
        ),
        (vec!["--start", s(&mask)], "neither a GLB nor params JSON"),
        (vec!["--start", "missing.json"], "cannot read"),
    ] {
        let mut all = vec!["reconstruct"];
        all.extend(args);
        all.extend([s(&mask), "-o", s(&refit)]);
        fails_with(&all, needle);
    }
}

#[test]
fn bad_input_gives_one_line_and_failure() {
    let check = fails_with;
    let empty = scratch("empty.png");
    write_png(&empty, 64, 64, |_, _| 0);
    let full = scratch("full.png");
    write_png(&full, 64, 64, |_, _| 255);
    let tiny = scratch("tiny.png");
    write_png(&tiny, 1, 1, |_, _| 255);
    let blob = |w: u32, h: u32| {
        move |x: u32, y: u32| {
            if x > w / 4 && x < w / 2 && y > h / 4 && y < 3 * h / 4 {
                255
            } else {
                0
            }
        }
    };
    let a = scratch("a.png");
    write_png(&a, 64, 64, blob(64, 64));
    let b = scratch("b.png");
    write_png(&b, 64, 48, blob(64, 48));
    let text = scratch("not-an-image.png");
    std::fs::write(&text, "hello").unwrap();
    let out = scratch("out.glb");
    let recon = |img: &[&str], needle: &str| {
        let mut args = vec!["reconstruct", "--generator", "dish"];
        args.extend_from_slice(img);
        args.extend_from_slice(&["-o", s(&out)]);
        check(&args, needle);
    };
    recon(&[s(&empty)], "empty.png: no object in this mask image");
    recon(&[s(&full)], "full.png: this mask image is all object");
    recon(&[s(&tiny)], "1×1");
    recon(&[s(&text)], "not a readable image");
    recon(&[s(&a), s(&b)], "same size");
    recon(&["/nonexistent/photo.jpg"], "cannot read");
    check(
        &["reconstruct", "--generator", "teapot", s(&a), "-o", s(&out)],
        "unknown generator",
    );
    check(
        &[
            "render",
            "--generator",
            "dish",
            "--preset",
            "mug",
            "--camera",
            s(&text),
            "--size",
            "0",
            "-o",
            s(&scratch("out.png")),
        ],
        "camera JSON",
    );
    check(&["eval", "--reference", s(&text), s(&out)], "");
}

/// Issue 19: `reconstruct copy.jpg -o copy.jpg` exited 0 and turned the photo into a GLB.
#[test]
fn an_output_that_is_an_input_is_refused_before_any_work() {
    let photo = scratch("copy.jpg");
    std::fs::copy("www/samples/mug.jpg", &photo).unwrap();
    let before = std::fs::read(&photo).unwrap();
    fails_with(
        &["reconstruct", s(&photo), "-o", s(&photo)],
        "is an input of this command",
    );
    // The same file by another spelling of its path.
    let dotted = photo.parent().unwrap().join(".").join("copy.jpg");
    fails_with(
        &[
            "reconstruct",
            s(&photo),
            "-o",
            "x.glb",
            "--params-out",
            s(&dotted),
        ],
        "is an input of this command",
    );
    assert_eq!(
        std::fs::read(&photo).unwrap(),
        before,
        "the photo is untouched"
    );
}

/// Issue 19: `-o x.glb --params-out x.glb` said it wrote the GLB and left JSON in its place.
#[test]
fn two_outputs_on_one_path_are_refused() {
    let glb = scratch("twice.glb");
    fails_with(
        &[
            "reconstruct",
            "www/samples/mug.jpg",
            "-o",
            s(&glb),
            "--params-out",
            s(&glb),
        ],
        "-o and --params-out are the same file",
    );
    assert!(!glb.exists());
    // The OBJ's material file is an output like the others.
    let obj = scratch("twice.obj");
    fails_with(
        &[
            "reconstruct",
            "www/samples/mug.jpg",
            "-o",
            s(&obj),
            "--params-out",
            s(&obj.with_extension("mtl")),
        ],
        "the OBJ's material file and --params-out are the same file",
    );
}

/// Issue 19: a missing output folder failed only after 12 s of fitting; now at once (the
/// budget here would take minutes if the fit ran).
#[test]
fn a_missing_output_folder_fails_before_the_fit() {
    let t = std::time::Instant::now();
    fails_with(
        &[
            "reconstruct",
            "www/samples/mug.jpg",
            "--budget",
            "1000000",
            "-o",
            "no-such-folder/x.glb",
        ],
        "does not exist",
    );
    fails_with(
        &[
            "generate",
            "--generator",
            "dish",
            "-o",
            "no-such-folder/x.glb",
        ],
        "does not exist",
    );
    assert!(t.elapsed().as_secs() < 30, "the fit did not start");
}

/// Issue 19: the first 3 kB of the mug sample (or 95 % of it) was fitted, exit 0, no warning.
#[test]
fn a_truncated_jpeg_is_one_line_of_error() {
    let bytes = std::fs::read("www/samples/mug.jpg").unwrap();
    for keep in [3000, bytes.len() * 95 / 100] {
        let cut = scratch(&format!("cut-{keep}.jpg"));
        std::fs::write(&cut, &bytes[..keep]).unwrap();
        fails_with(
            &["reconstruct", s(&cut), "-o", s(&scratch("cut.glb"))],
            "truncated",
        );
        fails_with(
            &[
                "reconstruct",
                "--generator",
                "tree",
                s(&cut),
                "-o",
                s(&scratch("cut.glb")),
            ],
            "truncated",
        );
    }
}

/// Issue 19: `--quality -1` got clap's "use '-- -1'" tip instead of the range.
#[test]
fn a_negative_number_is_a_bad_value_not_a_missing_flag() {
    fails_with(
        &[
            "reconstruct",
            "www/samples/mug.jpg",
            "-o",
            s(&scratch("q.glb")),
            "--quality",
            "-1",
        ],
        "quality -1 is not in (0, 16]",
    );
    fails_with(
        &[
            "reconstruct",
            "www/samples/mug.jpg",
            "-o",
            s(&scratch("q.glb")),
            "--fov",
            "-0.5",
        ],
        "field of view -0.5 rad",
    );
}

/// The last photo's photo-view IoU in what `reconstruct` printed.
fn last_photo_view_iou(said: &str) -> f64 {
    said.lines()
        .find_map(|l| l.strip_prefix("photo-view IoU: "))
        .and_then(|l| l.rsplit(' ').next())
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no photo-view IoU in {said}"))
}

/// Issue 16: a fit that cannot match its photo was reported as fitted, with nothing else. Now
/// every fit prints its photo-view IoU, and a poor one gets a warning with what to try: an
/// L-shaped mask has no lathed (dish) model.
#[test]
fn a_fit_reports_how_well_it_matches_the_photo_and_warns_when_poorly() {
    let l_shape = scratch("l-shape.png");
    write_png(&l_shape, 160, 160, |x, y| {
        if (20..140).contains(&y) && (30..130).contains(&x) && (x < 60 || y > 110) {
            255
        } else {
            0
        }
    });
    let out = scratch("l-shape.glb");
    let (said, err) = run_ok(&[
        "reconstruct",
        "--generator",
        "dish",
        "--budget",
        "600",
        "--quality",
        "0.3",
        "--restarts",
        "1",
        s(&l_shape),
        "-o",
        s(&out),
    ]);
    let iou = last_photo_view_iou(&said);
    assert!(iou < 0.85, "{said}");
    assert!(
        err.contains("warning: the model does not match") && err.contains("check the mask"),
        "{err}"
    );
}

/// A building is boxes and planes: a round outline (a disc, 100 × 120 pixels) is no building's.
/// The first six fits' best does not match it, so the fit adds two from L-shaped footprints
/// (`Session::rescue_runs`) and says so; none matches (photo-view IoU 0.934 measured, below the
/// building's level 0.97), and the CLI says that too, with what to try.
#[test]
fn a_building_fit_that_cannot_match_tries_other_shapes_and_says_so() {
    let disc = scratch("disc.png");
    write_png(&disc, 200, 200, |x, y| {
        let (dx, dy) = ((f64::from(x) - 100.0) / 50.0, (f64::from(y) - 100.0) / 60.0);
        if dx * dx + dy * dy <= 1.0 { 255 } else { 0 }
    });
    let (said, err) = run_ok(&[
        "reconstruct",
        "--generator",
        "building",
        s(&disc),
        "-o",
        s(&scratch("disc.glb")),
    ]);
    assert!(
        said.contains("the best of the first 6 fits did not match the photos (photo-view IoU 0.")
            && said.contains("below 0.97): 2 more fits from other shapes ran"),
        "{said}"
    );
    let iou = last_photo_view_iou(&said);
    assert!(iou < 0.97, "{said}");
    assert!(
        err.contains("warning: the model does not match") && err.contains("(below 0.97)"),
        "{err}"
    );
}

/// Never a confident wrong answer: the hip-roofed bungalow of the building benchmark (drawn
/// without procfit's generator) seen from its end at eye level, its mask: from one view the
/// fit's runs disagree in 3D (0.618 measured; the kept one scores IoU-64 0.675 against the
/// truth). The CLI prints the agreement and says what to do. (This was the house with two
/// dormers on textured ground at seed 1 until the building's photos were cut closer to their
/// outline, the L with flat roofs on textured ground at seed 2 until the fit added runs from
/// L-shaped footprints when the kept box does not outline the photo; before that the L with
/// hip roofs on plain ground, the house with two dormers on a gradient, the five-storey block on
/// a gradient and the block on textured ground, each until a change to the fit found their
/// shape or one like it; see tests/building_bench.rs.)
#[test]
fn a_fit_the_photo_does_not_fix_says_so() {
    let case = procfit::building_bench::case_named("hip-bungalow").unwrap();
    let view =
        procfit::building_bench::case_view(&case.mesh, 90f64.to_radians(), 2f64.to_radians())
            .unwrap();
    let mask = procfit::building_bench::input_mask(
        &case.mesh,
        &view,
        procfit::building_bench::Input::Mask,
    )
    .unwrap();
    let png = scratch("hip-bungalow-end.png");
    image::GrayImage::from_raw(
        mask.width(),
        mask.height(),
        mask.values()
            .iter()
            .map(|&v| if v > 0.5 { 255 } else { 0 })
            .collect(),
    )
    .unwrap()
    .save(&png)
    .unwrap();
    let out = scratch("hip-bungalow-end.glb");
    let fov = view.params.fov_y.to_string();
    let (said, err) = run_ok(&[
        "reconstruct",
        "--generator",
        "building",
        "--fov",
        &fov,
        s(&png),
        "-o",
        s(&out),
    ]);
    let agreement: f64 = said
        .lines()
        .find_map(|l| l.strip_prefix("3D agreement of the runs that match the photos as well: "))
        .and_then(|l| l.split(' ').next())
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("no 3D agreement in {said}"));
    assert!(agreement < 0.85, "{said}");
    assert!(
        err.contains("warning: the photo does not fix the shape")
            && err.contains("add a photo from another side"),
        "{err}"
    );
}

/// Issues 15 and 19: a mask that is a small part of the frame, or that touches several sides
/// of it, is said before the fit (the user may have given a fragment or a cut object).
#[test]
fn a_small_or_frame_touching_mask_is_said_before_the_fit() {
    for (name, f) in [
        (
            "tiny-mask.png",
            (|x, y| {
                if (70..86).contains(&x) && (60..80).contains(&y) {
                    255
                } else {
                    0
                }
            }) as fn(u32, u32) -> u8,
        ),
        (
            "cut-mask.png",
            |x, y| if x > 80 && y < 100 { 255 } else { 0 },
        ),
    ] {
        let mask = scratch(name);
        write_png(&mask, 160, 160, f);
        let out = scratch(&name.replace(".png", ".glb"));
        let (_, err) = run_ok(&[
            "reconstruct",
            "--generator",
            "dish",
            "--budget",
            "100",
            "--quality",
            "0.1",
            "--restarts",
            "1",
            s(&mask),
            "-o",
            s(&out),
        ]);
        let said = err
            .lines()
            .position(|l| l.contains("covers only") || l.contains("touches 2 sides"))
            .unwrap_or_else(|| panic!("{name}: nothing said about the mask in {err}"));
        assert!(err.lines().nth(said).unwrap().contains(name), "{err}");
    }
}
