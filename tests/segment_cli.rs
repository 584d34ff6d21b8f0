//! `procfit segment` as a user runs it (issue 16): the automatic mask written, given back to
//! `reconstruct` unedited, fits exactly as the photo does; a building's windows and a tree's
//! labels come with it in the forms `reconstruct` takes; bad input ends in one line, and the
//! photo is never overwritten.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "a test binary: a failed step should stop it loudly"
)]

mod cli_support;

use cli_support::{fails_with, procfit, run_ok, s};
use std::path::{Path, PathBuf};

fn scratch(name: &str) -> PathBuf {
    cli_support::scratch("segment-cli", name)
}

/// A photo-like PNG of the mug preset: `procfit render`'s silhouette painted brown with a
/// little texture over a light, slightly graded background.
fn mug_photo(name: &str) -> PathBuf {
    // One camera file per photo: the tests run in parallel, and a shared file can be read
    // while another test is rewriting it (an empty read, seen on CI).
    let cam = scratch(&format!("{name}.cam.json"));
    std::fs::write(
        &cam,
        r#"{"yaw": 0.4, "pitch": 0.35, "ty": -0.2, "fov_y": 0.5}"#,
    )
    .unwrap();
    let silhouette = scratch(&format!("{name}.silhouette.png"));
    run_ok(&[
        "render",
        "--generator",
        "dish",
        "--preset",
        "mug",
        "--camera",
        s(&cam),
        "--size",
        "200x150",
        "-o",
        s(&silhouette),
    ]);
    let cover = image::open(&silhouette).unwrap().to_luma8();
    let photo = scratch(name);
    image::RgbImage::from_fn(200, 150, |x, y| {
        let c = f32::from(cover.get_pixel(x, y)[0]) / 255.0;
        let bg = [215.0 + y as f32 * 0.2, 212.0, 205.0 - x as f32 * 0.05];
        let grain = ((x * 7 + y * 13) % 5) as f32 * 3.0;
        let fg = [120.0 + grain, 70.0 + grain, 40.0];
        let mix = |i: usize| (fg[i] * c + bg[i] * (1.0 - c)).round() as u8;
        image::Rgb([mix(0), mix(1), mix(2)])
    })
    .save(&photo)
    .unwrap();
    photo
}

/// `reconstruct` one image with a small, fixed budget; the params JSON and stdout.
fn fit(image: &Path, tag: &str) -> (String, String) {
    let (glb, params) = (
        scratch(&format!("{tag}.glb")),
        scratch(&format!("{tag}.json")),
    );
    let (said, _) = run_ok(&[
        "reconstruct",
        "--generator",
        "dish",
        "--fov",
        "0.5",
        "--budget",
        "300",
        "--quality",
        "0.3",
        "--restarts",
        "1",
        s(image),
        "-o",
        s(&glb),
        "--params-out",
        s(&params),
    ]);
    (std::fs::read_to_string(&params).unwrap(), said)
}

/// The photo-view IoU `reconstruct` printed.
fn photo_view_iou(said: &str) -> String {
    said.lines()
        .find_map(|l| l.strip_prefix("photo-view IoU: "))
        .and_then(|l| l.rsplit(' ').next())
        .unwrap_or_else(|| panic!("no photo-view IoU in {said}"))
        .to_string()
}

#[test]
fn the_written_mask_given_back_fits_as_the_photo_does() {
    let photo = mug_photo("mug.png");
    let mask = scratch("mug-mask.png");
    let (said, _) = run_ok(&["segment", s(&photo), "-o", s(&mask)]);
    assert!(said.contains("confidence"), "{said}");
    // The mask is at the working size (the photo's own, under 512 px): the cut as the fit takes
    // it, object and background, with no don't-care band along the outline.
    let img = image::open(&mask).unwrap().to_luma8();
    assert_eq!(img.dimensions(), (200, 150));
    let count = |v: u8| img.pixels().filter(|p| p[0] == v).count();
    assert_eq!(
        count(0) + count(255),
        200 * 150,
        "only object and background"
    );
    assert!(
        count(255) > 2000 && count(0) > 10_000,
        "object and background"
    );
    assert_eq!(
        count(0) + count(128) + count(255),
        200 * 150,
        "three levels only"
    );

    let (from_photo, said_photo) = fit(&photo, "from-photo");
    let (from_mask, said_mask) = fit(&mask, "from-mask");
    // The same fit; only the photo has colours to measure (a mask image has none).
    let doc = |t: &str| serde_json::from_str::<serde_json::Value>(t).unwrap();
    let (from_photo, from_mask) = (doc(&from_photo), doc(&from_mask));
    assert_eq!(
        from_photo["params"], from_mask["params"],
        "the same parameters"
    );
    assert!(from_photo.get("colors").is_some() && from_mask.get("colors").is_none());
    assert_eq!(photo_view_iou(&said_photo), photo_view_iou(&said_mask));

    // An edit counts: the mask with its object erased on the right half fits differently.
    let mut edited = img.clone();
    for (x, _, p) in edited.enumerate_pixels_mut() {
        if x >= 100 {
            p[0] = 0;
        }
    }
    let cut = scratch("mug-mask-cut.png");
    edited.save(&cut).unwrap();
    let (from_cut, _) = fit(&cut, "from-cut");
    assert_ne!(
        doc(&from_cut)["params"],
        from_mask["params"],
        "the corrected mask is what the fit uses"
    );
}

#[test]
fn the_output_never_overwrites_the_photo() {
    let photo = mug_photo("own.png");
    let before = std::fs::read(&photo).unwrap();
    fails_with(&["segment", s(&photo), "-o", s(&photo)], "is an input");
    // Nor does a generator's extra output.
    let mask = scratch("own-mask.png");
    fails_with(
        &[
            "segment",
            "--generator",
            "building",
            s(&photo),
            "-o",
            s(&mask),
            "--windows-out",
            s(&photo),
        ],
        "is an input",
    );
    fails_with(
        &[
            "segment",
            "--generator",
            "tree",
            s(&photo),
            "-o",
            s(&mask),
            "--labels-out",
            s(&mask),
        ],
        "same file",
    );
    assert_eq!(
        std::fs::read(&photo).unwrap(),
        before,
        "the photo is untouched"
    );
}

#[test]
fn bad_input_is_one_line() {
    let photo = mug_photo("bad.png");
    let not_image = scratch("not-an-image.png");
    std::fs::write(&not_image, b"hello").unwrap();
    let out = scratch("bad-out.png");
    for (args, needle) in [
        (vec!["segment", "missing.jpg", "-o", s(&out)], "cannot read"),
        (
            vec!["segment", s(&not_image), "-o", s(&out)],
            "not a readable image",
        ),
        (vec!["segment", s(&photo), "-o", "out.jpg"], "name it .png"),
        (
            vec!["segment", "--generator", "vase", s(&photo), "-o", s(&out)],
            "unknown generator",
        ),
        (
            vec![
                "segment",
                "--generator",
                "dish",
                s(&photo),
                "-o",
                s(&out),
                "--windows-out",
                "w.png",
            ],
            "has no windows",
        ),
        (
            vec!["segment", s(&photo), "-o", "/no/such/folder/m.png"],
            "folder",
        ),
        (
            vec!["segment", s(&photo), "-o", s(&out), "--tree-colors", "{}"],
            "--tree-colors",
        ),
    ] {
        fails_with(&args, needle);
    }
    assert!(!out.exists(), "nothing written on an error");
    let out = procfit(&["segment", "--help"]);
    assert!(String::from_utf8_lossy(&out.stdout).contains("Usage"));
}

/// A plain façade with a grid of dark windows on a sky-blue background, 240×180.
fn facade_photo(name: &str) -> PathBuf {
    let photo = scratch(name);
    image::RgbImage::from_fn(240, 180, |x, y| {
        let wall = (60..180).contains(&x) && (40..170).contains(&y);
        let window = wall
            && (x - 60) % 30 >= 10
            && (x - 60) % 30 < 22
            && (y - 40) % 32 >= 10
            && (y - 40) % 32 < 24;
        image::Rgb(if window {
            [40, 45, 60]
        } else if wall {
            [200, 170, 140]
        } else {
            [150, 190, 235]
        })
    })
    .save(&photo)
    .unwrap();
    photo
}

#[test]
fn a_building_gets_its_window_mask_and_reconstruct_takes_it() {
    let photo = facade_photo("facade.png");
    let mask = scratch("facade-mask.png");
    let (said, _) = run_ok(&[
        "segment",
        "--generator",
        "building",
        s(&photo),
        "-o",
        s(&mask),
    ]);
    let windows = scratch("facade-mask.windows.png");
    assert!(said.contains("window mask"), "{said}");
    let w = image::open(&windows).unwrap().to_luma8();
    assert_eq!(w.dimensions(), (240, 180));
    // The windows are found where they are painted, and nowhere off the wall.
    let (mut hit, mut off) = (0, 0);
    for (x, y, p) in w.enumerate_pixels() {
        if p[0] == 255 {
            let wall = (60..180).contains(&x) && (40..170).contains(&y);
            let window = wall
                && (x - 60) % 30 >= 10
                && (x - 60) % 30 < 22
                && (y - 40) % 32 >= 10
                && (y - 40) % 32 < 24;
            if window {
                hit += 1;
            } else {
                off += 1;
            }
        }
    }
    assert!(hit > 800 && off < hit / 5, "windows: {hit} on, {off} off");

    // `reconstruct --windows` refuses them for a generator without windows, and too many.
    let out = scratch("facade.glb");
    fails_with(
        &[
            "reconstruct",
            "--generator",
            "dish",
            "--windows",
            s(&windows),
            s(&mask),
            "-o",
            s(&out),
        ],
        "--windows is for a generator with windows",
    );
    fails_with(
        &[
            "reconstruct",
            "--generator",
            "building",
            "--windows",
            s(&windows),
            "--windows",
            s(&windows),
            s(&mask),
            "-o",
            s(&out),
        ],
        "2 window masks for 1 images",
    );
    let small = scratch("small-windows.png");
    image::GrayImage::new(120, 90).save(&small).unwrap();
    fails_with(
        &[
            "reconstruct",
            "--generator",
            "building",
            "--windows",
            s(&small),
            s(&mask),
            "-o",
            s(&out),
        ],
        "is 120×90 at the working size",
    );
}

#[test]
fn a_tree_gets_its_label_image() {
    // Green crown over a brown trunk on a pale sky.
    let photo = scratch("tree.png");
    image::RgbImage::from_fn(160, 200, |x, y| {
        let (dx, dy) = (x as f32 - 80.0, y as f32 - 70.0);
        image::Rgb(if dx * dx + dy * dy < 50.0 * 50.0 {
            [40, 130, 40]
        } else if (74..86).contains(&x) && y > 100 && y < 190 {
            [100, 70, 40]
        } else {
            [225, 230, 240]
        })
    })
    .save(&photo)
    .unwrap();
    let (mask, labels) = (scratch("tree-mask.png"), scratch("tree-labels.png"));
    let (said, _) = run_ok(&[
        "segment",
        "--generator",
        "tree",
        s(&photo),
        "-o",
        s(&mask),
        "--labels-out",
        s(&labels),
    ]);
    assert!(said.contains("leaf"), "{said}");
    let l = image::open(&labels).unwrap().to_luma8();
    assert_eq!(l.dimensions(), (160, 200), "the photo's own size");
    assert!(
        l.pixels().all(|p| matches!(p[0], 0 | 1 | 2 | 255)),
        "label values only"
    );
    assert_eq!(l.get_pixel(80, 70)[0], 2, "leaf in the crown");
    assert_eq!(l.get_pixel(80, 160)[0], 1, "branch in the trunk");
    assert_eq!(l.get_pixel(5, 5)[0], 0, "background");
    let m = image::open(&mask).unwrap().to_luma8();
    assert_eq!(m.get_pixel(80, 160)[0], 255);
    assert_eq!(m.get_pixel(5, 5)[0], 0);
}

/// `segment --generator building` cuts the photo as `reconstruct --generator building` does, a
/// building's way (closer into corners) and not the default way: the L with flat roofs on
/// textured ground (the building benchmark's) keeps its shaded wall's foot (405 pixels of the
/// true silhouette the default cut leaves out, 46 as a building's, measured).
#[test]
fn a_building_photo_is_written_as_a_building_is_cut() {
    let case = procfit::building_bench::case_named("l-flat").unwrap();
    let input = procfit::building_bench::Input::Textured;
    let px = procfit::building_bench::photo(&case.mesh, &case.view, input).unwrap();
    let photo = scratch("l-flat-textured.png");
    image::RgbaImage::from_raw(case.view.width, case.view.height, px)
        .unwrap()
        .save(&photo)
        .unwrap();
    let truth = procfit::building_bench::input_mask(
        &case.mesh,
        &case.view,
        procfit::building_bench::Input::Mask,
    )
    .unwrap();
    let missing = |generator: &str| {
        let out = scratch(&format!("l-flat-{generator}.png"));
        run_ok(&[
            "segment",
            "--generator",
            generator,
            s(&photo),
            "-o",
            s(&out),
        ]);
        let mask = image::open(&out).unwrap().to_luma8();
        mask.pixels()
            .zip(truth.values())
            .filter(|(m, t)| **t > 0.5 && m[0] < 128)
            .count()
    };
    let (building, default) = (missing("building"), missing("auto"));
    assert!(
        building * 2 < default,
        "true object pixels left out: {building} as a building's, {default} by default"
    );
}
