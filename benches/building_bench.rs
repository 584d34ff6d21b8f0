//! The independent building benchmark (issue 15), not a test: the building fit at its default
//! settings on buildings written by [`procfit::building_bench`] (not by procfit's generator),
//! one camera each, from the clean mask and from photo-like images on plain, gradient and
//! textured ground segmented as the CLI segments a photo. Per case × input: the paper's IoU-64
//! (the fit moved into the truth's frame through view 0, 64 turntable views at 128²), the
//! photo-view IoU (the fit through its own camera against the true mask, and against the mask
//! the fit was given: a photo's automatic cut, what the CLI prints) and wall time on 2
//! threads; then the means per input. When the paper's test building is present (by default
//! `../shared/data/paper/building_test_2_original.obj` beside the checkout; it has no licence
//! and is read from there, never copied), its masks from three cameras are fitted too.
//!
//! `cargo bench --bench building_bench` runs everything; `-- --quick` at quality 0.4,
//! `-- --quality Q` at Q; `-- --seed N` fits with seed N (0 by default: judge a change over
//! several seeds); `-- --runs N` makes N runs a fit (the page's number by default);
//! `-- NAME …` only those cases (`paper` for the paper's building); `-- --inputs mask,plain`
//! only those inputs; `-- --view YAW,ELEVATION` sees every case from there instead of its own
//! camera (degrees; `0,1`: straight from the front, 1° up; the paper's building keeps its
//! three); `-- --paper-obj PATH` reads the paper's building from elsewhere;
//! The *3D agreement* column is what the CLI prints after a fit: how alike the runs that match
//! the mask about as well are in 3D (`procfit::reconstruct::eval::agreement`); below
//! `AGREEMENT_LEVEL` the CLI and the page warn that the mask does not fix the shape, and the
//! last lines say how the warned fits score against the others, for that warning, for the
//! photo-view IoU against its mask below the building's `photo_match_level` (the CLI's "does
//! not match" warning) and for either.
//! `-- --save DIR` also writes each case's photos and masks there as PNG; `-- --each` prints
//! every run of each fit (loss, tie prior, IoU-64, photo-view IoU against its mask, main shape
//! parameters) after its row;
//! `-- --windows` fits each photo with the window labels found in it, as the page's "Find
//! windows" gives them (the fit's window term and layout search in half the runs: about 20×
//! the time); a row says when the fit left them out (`Session::windows_left_out`).

use procfit::bench_cases::BenchFit;
use procfit::building_bench::{
    BenchScore, Input, PAPER_CAMERAS, case_view, cases, fit_and_score, fit_and_score_input,
    input_mask, paper_building,
};
use procfit::generators::Generator;
use procfit::reconstruct::eval::{
    AGREEMENT_LEVEL, agreement_warning, photo_match_level, photo_match_warning,
};
use std::path::PathBuf;

/// One fitted row: IoU-64, photo-view IoU, seconds.
type Row = (f64, f64, f64);

/// One fit's IoU-64 and whether the CLI warns about it: that the mask does not fix the shape,
/// that the model does not match the photo.
type Warned = (f64, bool, bool);

/// [`Warned`] of a fit `s`, with the building's photo-match `level`, as the CLI judges it.
fn warned_of(s: &BenchScore, level: f64) -> Warned {
    (
        s.iou64,
        agreement_warning(s.agreement, s.front_only).is_some(),
        photo_match_warning(&[s.mask_photo_iou], &[], level).is_some(),
    )
}

/// The agreement column: the number, or "–" without one.
fn agreement_cell(a: Option<f64>) -> String {
    a.map_or("–".to_string(), |a| format!("{a:.3}"))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let fit = BenchFit::from_args(&args)?;
    let mut paper_obj = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/data/paper/building_test_2_original.obj");
    if !paper_obj.exists() {
        paper_obj = PathBuf::from("/work/shared/data/paper/building_test_2_original.obj");
    }
    let mut save: Option<PathBuf> = None;
    let mut names = Vec::new();
    let mut inputs: Vec<Input> = Input::ALL.to_vec();
    let mut camera: Option<(f64, f64)> = None;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            // Read by `BenchFit::from_args`.
            "--seed" | "--runs" | "--quality" => {
                it.next();
            }
            "--save" => save = Some(PathBuf::from(it.next().ok_or("--save needs a folder")?)),
            "--paper-obj" => {
                paper_obj = PathBuf::from(it.next().ok_or("--paper-obj needs a file")?)
            }
            "--view" => {
                let v = it.next().ok_or("--view needs YAW,ELEVATION in degrees")?;
                let (y, p) = v.split_once(',').ok_or("--view YAW,ELEVATION")?;
                camera = Some((y.trim().parse()?, p.trim().parse()?));
            }
            "--inputs" => {
                let list = it.next().ok_or("--inputs needs a list")?;
                inputs = Input::ALL
                    .into_iter()
                    .filter(|i| list.split(',').any(|n| n == i.name()))
                    .collect();
            }
            n if !n.starts_with('-') => names.push(n.to_string()),
            _ => {}
        }
    }
    let wanted = |n: &str| names.is_empty() || names.iter().any(|x| x == n);
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build()?;
    println!(
        "## Independent building benchmark, 2 threads, quality {}, seed {}, {} runs a fit{}\n",
        fit.quality,
        fit.seed,
        fit.runs_for(procfit::generators::building::Building.name()),
        if fit.windows {
            ", photos with the windows found in them"
        } else {
            ""
        }
    );
    println!(
        "| building | kind | input | IoU-64 | photo-view IoU | … against its mask | seconds | ΔE wall / roof | 3D agreement |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    let mut sums: Vec<(Input, Vec<Row>)> = Vec::new();
    // Every fit's IoU-64, whether the CLI warns that the mask does not fix the shape, and
    // whether it warns that the model does not match the photo.
    let level = photo_match_level(&procfit::generators::building::Building);
    let mut warned: Vec<Warned> = Vec::new();
    let mut run =
        |name: &str,
         kind: &str,
         input: Input,
         f: &(dyn Fn() -> Result<BenchScore, procfit::reconstruct::FitError> + Sync)| {
            let t = std::time::Instant::now();
            match pool.install(f) {
                Ok(s) => {
                    let secs = t.elapsed().as_secs_f64();
                    // The photo's part colours against the colours it was drawn with.
                    let de = |d: Option<f64>| d.map_or("–".to_string(), |d| format!("{d:.1}"));
                    let colours = s
                        .colour_de
                        .map_or(String::new(), |(w, r)| format!("{} / {}", de(w), de(r)));
                    // With window labels: whether the fit kept a run of the outline alone.
                    let left_out = match s.windows_left_out {
                        true => " (windows left out)",
                        false => "",
                    };
                    println!(
                        "| {name} | {kind} | {}{left_out} | {:.3} | {:.3} | {:.3} | {secs:.1} | {colours} | {} |",
                        input.name(),
                        s.iou64,
                        s.photo_iou,
                        s.mask_photo_iou,
                        agreement_cell(s.agreement)
                    );
                    print_runs(&s);
                    warned.push(warned_of(&s, level));
                    let row = (s.iou64, s.photo_iou, secs);
                    match sums.iter_mut().find(|x| x.0 == input) {
                        Some(x) => x.1.push(row),
                        None => sums.push((input, vec![row])),
                    }
                }
                Err(e) => println!("| {name} | {kind} | {} | failed: {e} | 0 | |", input.name()),
            }
        };
    for case in cases()? {
        if !wanted(case.name) {
            continue;
        }
        let view = match camera {
            Some((yaw, pitch)) => case_view(&case.mesh, yaw.to_radians(), pitch.to_radians())?,
            None => case.view,
        };
        if let Some(dir) = &save {
            save_images(dir, case.name, &case.mesh, &view)?;
        }
        for &input in &inputs {
            run(case.name, case.kind, input, &|| {
                fit_and_score_input(&case.mesh, &view, input, fit)
            });
        }
    }
    for (input, rows) in &sums {
        let n = rows.len() as f64;
        println!(
            "| **mean** ({} cases) | | {} | {:.3} | {:.3} | {:.1} |",
            rows.len(),
            input.name(),
            rows.iter().map(|r| r.0).sum::<f64>() / n,
            rows.iter().map(|r| r.1).sum::<f64>() / n,
            rows.iter().map(|r| r.2).sum::<f64>() / n,
        );
    }
    if wanted("paper") {
        match paper_building(&paper_obj)? {
            None => println!(
                "\nthe paper's building is not at {} (give --paper-obj PATH): skipped",
                paper_obj.display()
            ),
            Some(mesh) => {
                println!("\n## The paper's test building (the paper reports IoU-64 0.886)\n");
                println!(
                    "| camera (yaw°, elevation°) | input | IoU-64 | photo-view IoU | seconds | 3D agreement |"
                );
                println!("|---|---|---|---|---|---|");
                for (yaw, pitch) in PAPER_CAMERAS {
                    let view = case_view(&mesh, yaw.to_radians(), pitch.to_radians())?;
                    let t = std::time::Instant::now();
                    let r = pool.install(|| {
                        let mask = input_mask(&mesh, &view, Input::Mask)?;
                        fit_and_score(&mesh, &view, mask, fit)
                    });
                    match r {
                        Ok(s) => {
                            println!(
                                "| {yaw:.0}, {pitch:.0} | mask | {:.3} | {:.3} | {:.1} | {} |",
                                s.iou64,
                                s.photo_iou,
                                t.elapsed().as_secs_f64(),
                                agreement_cell(s.agreement)
                            );
                            print_runs(&s);
                            warned.push(warned_of(&s, level));
                        }
                        Err(e) => println!("| {yaw:.0}, {pitch:.0} | mask | failed: {e} | 0 | |"),
                    }
                }
            }
        }
    }
    // Do the warnings go with the bad fits? The warned fits and the others: how many, their
    // mean IoU-64 and how many are below 0.80.
    let mean = |which: fn(&Warned) -> bool, w: bool| {
        let v: Vec<f64> = warned
            .iter()
            .filter(|x| which(x) == w)
            .map(|x| x.0)
            .collect();
        if v.is_empty() {
            return "no fits".to_string();
        }
        let m = v.iter().sum::<f64>() / v.len() as f64;
        let bad = v.iter().filter(|&&x| x < 0.8).count();
        format!("{} fits, mean IoU-64 {m:.3}, {bad} below 0.80", v.len())
    };
    let verdicts = [
        (
            format!(
                "3D agreement below {AGREEMENT_LEVEL} (the CLI warns that the mask does not fix \
                 the shape)"
            ),
            (|x| x.1) as fn(&Warned) -> bool,
        ),
        (
            format!(
                "photo-view IoU against its mask below {level} (the CLI warns that the model \
                 does not match the photo)"
            ),
            |x| x.2,
        ),
        ("either warning".to_string(), |x| x.1 || x.2),
    ];
    println!();
    for (what, which) in verdicts {
        println!(
            "{what}: {}; the others: {}",
            mean(which, true),
            mean(which, false)
        );
    }
    Ok(())
}

/// With `--each`, the runs of a fit on stderr, the kept one marked, after the two candidates of
/// a fit with window labels.
fn print_runs(s: &BenchScore) {
    if let Some([(a, x), (b, y)]) = s.window_candidates {
        eprintln!(
            "    windows: the best run fitting them outline {a:.4}, IoU-64 {x:.3}; of the outline alone {b:.4}, {y:.3}"
        );
    }
    for (k, r) in s.runs.iter().enumerate() {
        eprintln!(
            "    run {k}{}: loss {:.5}, tie prior {:.3}, IoU-64 {:.3}, against the kept run {:.3}, photo-view IoU {:.4}, {}",
            if r.kept { " (kept)" } else { "" },
            r.loss,
            r.tie_prior,
            r.iou64,
            r.agreement,
            r.photo_iou,
            r.shape
        );
    }
}

/// Writes the photos of a case and the masks the fit gets (object white, background black,
/// don't care grey) as PNG files into `dir`.
fn save_images(
    dir: &std::path::Path,
    name: &str,
    mesh: &procfit::generators::Mesh,
    view: &procfit::camera::View,
) -> Result<(), Box<dyn std::error::Error>> {
    std::fs::create_dir_all(dir)?;
    let (w, h) = (view.width, view.height);
    for input in Input::ALL {
        if input != Input::Mask {
            let px = procfit::building_bench::photo(mesh, view, input)?;
            image::RgbaImage::from_raw(w, h, px)
                .ok_or("bad photo size")?
                .save(dir.join(format!("{name}-{}.png", input.name())))?;
        }
        let m = input_mask(mesh, view, input)?;
        let luma: Vec<u8> = m
            .values()
            .iter()
            .map(|&v| {
                if v == procfit::mask::Mask::DONT_CARE {
                    128
                } else {
                    (v * 255.0) as u8
                }
            })
            .collect();
        image::GrayImage::from_raw(w, h, luma)
            .ok_or("bad mask size")?
            .save(dir.join(format!("{name}-{}-mask.png", input.name())))?;
    }
    Ok(())
}
