//! Benchmark of the whole fit at the default budget (quality 1): wall time and IoU-64 for a
//! mug (the measured, lathed one — not the generator's), a bowl (a non-preset dish) and a
//! building (a non-preset one), each from one 512² mask, on 1 and 2 threads. Prints a markdown
//! table of medians over several random cameras. Run with `cargo bench --bench reconstruct`;
//! `-- WORD …` runs only the objects whose name contains one of the words (`-- building`);
//! `-- --threads N` runs one thread count only; `-- --cameras N` fits N cameras (4); `-- --runs
//! N` makes N runs a fit (the page's and the CLI's number by default);
//! `-- --each` prints a line per camera (its yaw and elevation, the IoU-64, the photo-view IoU
//! against the mask as the CLI prints it, and the fitted parameters) and per run (loss, tie
//! prior, fitted yaw and elevation, IoU-64, IoU-64 against the kept run, photo-view IoU, the IoU
//! of its holes with the mask's, the parameters: enough
//! to re-apply another choice among the runs to the same runs without fitting again);
//! `-- --fill-holes` fills the masks' holes (a mug handle's) before fitting, to measure what
//! the hole tells the fit.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "a benchmark binary: a failed workload should stop it loudly"
)]

#[path = "../tests/reconstruct_support/mod.rs"]
mod support;

use procfit::generators::{Lod, Mesh};
use procfit::optim::Rng;
use procfit::reconstruct::FitConfig;
use std::time::Instant;
use support::*;

/// Random cameras per object (each fitted once per thread count); `-- --cameras N` for more.
const CAMERAS: usize = 4;
// PROCFIT_QUALITY=q scales the budget (default 1).
const SIDE: u32 = 512;

fn main() {
    let mut rng = Rng::new(2024);
    let mug = measured_mug();
    // A bowl no preset describes: the bowl body, wider at the base, a little taller.
    let mut bowl_x = generator("dish").preset("bowl").unwrap().values;
    for (i, r) in bowl_x.iter_mut().enumerate().take(9) {
        *r += 0.4 - 0.05 * i as f64;
    }
    bowl_x[9] *= 1.15;
    let bowl = mesh_of("dish", &bowl_x, Lod::High);
    let building = mesh_of("building", &random_building(&mut Rng::new(1)), Lod::High);
    let cases: Vec<(&str, &str, Mesh)> = vec![
        ("mug (measured, OBJ)", "dish", mug),
        ("bowl", "dish", bowl),
        ("building", "building", building),
    ];
    let args: Vec<String> = std::env::args().skip(1).collect();
    let each = args.iter().any(|a| a == "--each");
    let fill_holes = args.iter().any(|a| a == "--fill-holes");
    // The number after `flag`, if given.
    let number = |flag: &str| -> Option<usize> {
        let i = args.iter().position(|a| a == flag)?;
        Some(
            args.get(i + 1)?
                .parse()
                .unwrap_or_else(|_| panic!("{flag} N")),
        )
    };
    let only_threads = number("--threads");
    let cameras = number("--cameras").unwrap_or(CAMERAS);
    let runs = number("--runs");
    let words: Vec<String> = args
        .iter()
        .enumerate()
        .filter(|&(i, a)| {
            !a.starts_with('-')
                && (i == 0 || !matches!(args[i - 1].as_str(), "--threads" | "--cameras" | "--runs"))
        })
        .map(|(_, a)| a.clone())
        .collect();
    let wanted = |name: &str| words.is_empty() || words.iter().any(|w| name.contains(w.as_str()));
    println!(
        "| object | threads | wall time median (min–max) over {cameras} cameras | evaluations | IoU-64 mean (min–max) |"
    );
    println!("|---|---|---|---|---|");
    for (name, g, mesh) in &cases {
        // The cameras are drawn for every object, so a filtered run sees the same ones.
        let truths: Vec<_> = (0..cameras)
            .map(|_| random_view_at(&mut rng, mesh, 0.5, 0.0))
            .collect();
        if !wanted(name) {
            continue;
        }
        let mut masks: Vec<_> = truths.iter().map(|t| render_mask(mesh, t, SIDE)).collect();
        if fill_holes {
            masks = masks.iter().map(without_holes).collect();
        }
        let quality: f64 = std::env::var("PROCFIT_QUALITY")
            .ok()
            .and_then(|q| q.parse().ok())
            .unwrap_or(1.0);
        let mut first_params = None;
        for threads in [1, 2] {
            if only_threads.is_some_and(|n| n != threads) {
                continue;
            }
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let (mut times, mut ious, mut evals, mut params) = (vec![], vec![], 0, vec![]);
            for (truth, mask) in truths.iter().zip(&masks) {
                let t0 = Instant::now();
                let r = pool.install(|| {
                    let mut session = procfit::reconstruct::Session::new(
                        FitConfig {
                            generator: g.to_string(),
                            fov_y: vec![Some(0.5)],
                            quality,
                            // The page's and the CLI's number of runs for this generator
                            // unless `--runs` says otherwise.
                            restarts: runs.unwrap_or(FitConfig::restarts_for(g, quality)),
                            ..FitConfig::default()
                        },
                        vec![mask.clone()],
                    )
                    .unwrap();
                    let r = session.run().unwrap();
                    if each {
                        eprintln!(
                            "    3D agreement of the runs: {:?}",
                            session.agreement().unwrap()
                        );
                        for (k, run) in session.run_results().into_iter().enumerate() {
                            let Some(run) = run else { continue };
                            let (photo, holes) = run_photo_and_holes(run, mask);
                            eprintln!(
                                "    run {k}: loss {:.6e}, tie prior {:.3}, fitted yaw {:.0}°, elevation {:.1}°, IoU-64 {:.3}, against the kept run {:.3}, photo-view IoU {photo:.4}, holes' IoU {holes:.3}, params {:?}",
                                run.loss,
                                run.model.generator.tie_prior(&run.model.params),
                                run.views[0].params.yaw.to_degrees(),
                                run.views[0].params.pitch.to_degrees(),
                                fit_iou64(run, mesh, truth),
                                procfit::reconstruct::eval::fit_agreement(&r, run, 128).unwrap(),
                                run.model.params
                            );
                        }
                    }
                    r
                });
                times.push(t0.elapsed().as_secs_f64());
                ious.push(fit_iou64(&r, mesh, truth));
                if each {
                    // What the CLI prints and checks against the generator's level.
                    let photo = procfit::reconstruct::eval::result_photo_ious(
                        &r,
                        std::slice::from_ref(mask),
                    )
                    .unwrap()[0];
                    eprintln!(
                        "  {name}: camera yaw {:.0}°, elevation {:.0}° (fitted {:.0}°, {:.0}°): \
                         IoU-64 {:.3}, photo-view IoU {photo:.3}, params {:.3?}",
                        truth.yaw.to_degrees(),
                        truth.pitch.to_degrees(),
                        r.views[0].params.yaw.to_degrees(),
                        r.views[0].params.pitch.to_degrees(),
                        ious[ious.len() - 1],
                        r.model.params
                    );
                }
                evals = r.evaluations;
                params.push(r.model.params.clone());
            }
            // Same seed, same result whatever the thread count.
            match &first_params {
                None => first_params = Some(params),
                Some(p) => assert_eq!(p, &params, "{name}: threads changed the fit"),
            }
            times.sort_by(f64::total_cmp);
            let mean = ious.iter().sum::<f64>() / ious.len() as f64;
            let (lo, hi) = ious
                .iter()
                .fold((1.0f64, 0.0f64), |(a, b), &v| (a.min(v), b.max(v)));
            println!(
                "| {name} | {threads} | {:.2} s ({:.2}–{:.2}) | {evals} | {mean:.3} ({lo:.3}–{hi:.3}) |",
                times[times.len() / 2],
                times[0],
                times[times.len() - 1],
            );
        }
    }
}

/// A run's photo-view IoU against `mask` and the IoU of its silhouette's holes (background
/// not connected to the border, a handle's) with the mask's: 1 when neither has a hole.
fn run_photo_and_holes(
    run: &procfit::reconstruct::FitResult,
    mask: &procfit::mask::Mask,
) -> (f64, f64) {
    let model = &run.model;
    let mesh = model.generator.generate(&model.params, model.lod).unwrap();
    let coverage = procfit::reconstruct::render_coverage(&mesh, &run.views[0]).unwrap();
    let (w, h) = (mask.width() as usize, mask.height() as usize);
    let holes_of = |object: Vec<bool>| {
        let mut out = vec![false; w * h];
        for hole in procfit::segment::morph::holes(&object, w, h) {
            for i in hole {
                out[i] = true;
            }
        }
        out
    };
    let fitted = holes_of(coverage.iter().map(|&c| c > 0.5).collect());
    let truth = holes_of(mask.values().iter().map(|&v| v > 0.5).collect());
    let both = fitted
        .iter()
        .zip(&truth)
        .filter(|(a, b)| **a && **b)
        .count();
    let either = fitted
        .iter()
        .zip(&truth)
        .filter(|(a, b)| **a || **b)
        .count();
    let photo =
        procfit::reconstruct::eval::result_photo_ious(run, std::slice::from_ref(mask)).unwrap()[0];
    let holes = if either == 0 {
        1.0
    } else {
        both as f64 / either as f64
    };
    (photo, holes)
}

/// `mask` with every hole (background not connected to the border) made object.
fn without_holes(mask: &procfit::mask::Mask) -> procfit::mask::Mask {
    let (w, h) = (mask.width() as usize, mask.height() as usize);
    let object: Vec<bool> = mask.values().iter().map(|&v| v > 0.5).collect();
    let mut values = mask.values().to_vec();
    for hole in procfit::segment::morph::holes(&object, w, h) {
        for i in hole {
            values[i] = 1.0;
        }
    }
    procfit::mask::Mask::new(mask.width(), mask.height(), values).unwrap()
}
