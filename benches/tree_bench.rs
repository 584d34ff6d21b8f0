//! The independent tree benchmark (issue 14), not a test: the tree fit, at its default settings,
//! on the trees `node scripts/make-tree-bench.mjs` renders with ez-tree into
//! `target/tree-bench/` (run that first; without it this prints how). Per tree: the paper's
//! similarity, IoU-64 (128², the fit at MEDIUM moved into the truth's frame through the photo's
//! two cameras, [`procfit::tree::bench::to_truth_frame`]), the photo-view IoU (the fit through
//! its own photo camera against the photo's object mask; both of the tree as the CLI writes it,
//! its leaves carved by the photo, [`procfit::tree::carve`]) and the wall time of the fit and
//! the carving on 2 threads (not of the scoring); and the
//! baselines: a sphere, an ellipsoid on the truth's crown box, the same species another seed.
//!
//! `cargo bench --bench tree_bench` fits the colour photo (labelled as the CLI does);
//! `-- --labels` fits the true label image too; `-- --quick` cuts the GA budget (`PHOTO_GA_BUDGET`) by 4,
//! `-- --budget N` sets it, `-- --seed N` the fit's seed (1 by default), `-- --frame
//! off|area|top|both` the candidates' framing ([`CandidateFraming`]; `--no-area` is `off`);
//! `-- --carve N` cuts leaf cards into N×N tiles to carve (`CARVE_GRID` by default),
//! `-- --no-carve` measures the tree as generated; `-- NAME …` runs only those cases; `-- --dir DIR` reads another folder; `-- --analyse`
//! adds a table of where the photo-view IoU is lost ([`analyse_silhouette`]: as is, leaf gaps
//! closed, convex hulls, fills, area ratio) for each fit, the truth and the other seed.

use procfit::bench_cases::case_dirs;
use procfit::tree::bench::{
    BenchCase, SilhouetteAnalysis, analyse_silhouette, crown_ellipsoid, fit_case_tree, score_case,
    sphere,
};
use procfit::tree::impostor::{CandidateFraming, PhotoFitOptions, silhouette_iou64};
use procfit::tree::labels::{ColorThresholds, foliage_problem, photo_labels};
use std::path::PathBuf;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let quick = args.iter().any(|a| a == "--quick");
    let with_labels = args.iter().any(|a| a == "--labels");
    // `--paper`: the paper's fitness alone (no silhouette term), `--no-fov`: the photo's field
    // of view unknown to the fit; both for before/after comparisons.
    let paper = args.iter().any(|a| a == "--paper");
    let no_fov = args.iter().any(|a| a == "--no-fov");
    let analyse = args.iter().any(|a| a == "--analyse");
    // `--no-envelope`: without the crown-envelope seeds; `--no-area`: without the area framing;
    // `--weight W`: another silhouette weight.
    let no_envelope = args.iter().any(|a| a == "--no-envelope");
    let no_area = args.iter().any(|a| a == "--no-area");
    let mut weight = None;
    let mut framing = None;
    let mut budget_arg: Option<usize> = None;
    let mut seed = 1;
    // `--carve N`: N×N tiles a leaf card; `--no-carve`: the tree as generated.
    let mut carve = Some(procfit::tree::carve::CARVE_GRID);
    let mut analyses: Vec<(String, &str, SilhouetteAnalysis)> = Vec::new();
    let mut dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target/tree-bench");
    let mut names = Vec::new();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--dir" => dir = PathBuf::from(it.next().ok_or("--dir needs a folder")?),
            "--weight" => {
                weight = Some(it.next().ok_or("--weight needs a number")?.parse::<f64>()?)
            }
            "--frame" => {
                framing = Some(match it.next().map(String::as_str) {
                    Some("off") => CandidateFraming::Off,
                    Some("area") => CandidateFraming::Area,
                    Some("top") => CandidateFraming::Top,
                    Some("both") => CandidateFraming::AreaAndTop,
                    _ => return Err("--frame takes off, area, top or both".into()),
                })
            }
            "--seed" => seed = it.next().ok_or("--seed needs a number")?.parse::<u64>()?,
            "--carve" => {
                carve = Some(
                    it.next()
                        .ok_or("--carve needs a number")?
                        .parse::<usize>()?,
                )
            }
            "--no-carve" => carve = None,
            "--budget" => {
                budget_arg = Some(
                    it.next()
                        .ok_or("--budget needs a number")?
                        .parse::<usize>()?,
                )
            }
            "--bench" | "--quick" | "--labels" | "--paper" | "--no-fov" | "--analyse"
            | "--no-envelope" | "--no-area" => {}
            n if !n.starts_with('-') => names.push(n.to_string()),
            _ => {}
        }
    }
    let dirs = case_dirs(&dir, &names);
    if dirs.is_empty() {
        println!(
            "no tree benchmark cases in {}: run `node scripts/make-tree-bench.mjs` first",
            dir.display()
        );
        return Ok(());
    }
    let budget = budget_arg.or(quick.then_some(procfit::tree::impostor::PHOTO_GA_BUDGET / 4));
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build()?;
    println!(
        "## Independent tree benchmark (ez-tree), {} cases, 2 threads, seed {seed}, {}{}\n",
        dirs.len(),
        match carve {
            Some(g) => format!("leaves carved {g}×{g}"),
            None => "leaves not carved".into(),
        },
        match budget {
            Some(b) => format!(", GA budget {b}"),
            None => String::new(),
        }
    );
    println!(
        "| tree | kind | input | similarity | IoU-64 | photo-view IoU | seconds | sphere | crown ellipsoid | other seed |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    let mut sums: Vec<(String, Vec<[f64; 7]>)> = Vec::new();
    for d in &dirs {
        let case = BenchCase::load(d)?;
        let sph = silhouette_iou64(&case.truth, &sphere(), 128)?;
        let ell = silhouette_iou64(&case.truth, &crown_ellipsoid(&case.truth), 128)?;
        let other = silhouette_iou64(&case.truth, &case.other, 128)?;
        let (w, h, px) = &case.photo;
        let (from_photo, _) = photo_labels(*w, *h, px, 4, &ColorThresholds::default())?;
        let mut inputs = vec![("photo", from_photo)];
        if with_labels {
            inputs.push(("true labels", case.labels.clone()));
        }
        for (input, labels) in &inputs {
            let row = match foliage_problem(labels) {
                Some(p) => Err(format!("refused: {p}")),
                None => {
                    let mut options = PhotoFitOptions {
                        fov_y: (!no_fov).then_some(case.camera.fov_y),
                        ..PhotoFitOptions::default()
                    };
                    if let Some(f) = framing {
                        options.framing = f;
                    }
                    if let Some(w) = weight {
                        options.silhouette_weight = w;
                    }
                    if paper {
                        options.silhouette_weight = 0.0;
                    }
                    if no_envelope {
                        options.envelope_seeds = false;
                    }
                    if no_area {
                        options.framing = CandidateFraming::Off;
                    }
                    // Timed: the fit and the carving (what a user waits for), not the scoring.
                    let t = std::time::Instant::now();
                    pool.install(|| {
                        let fit = fit_case_tree(labels, seed, budget, &options, carve)?;
                        let seconds = t.elapsed().as_secs_f64();
                        Ok::<_, String>((
                            score_case(&case, &fit)?,
                            fit.mesh,
                            fit.photo_view,
                            seconds,
                        ))
                    })
                    .map(|(r, mesh, view, seconds)| {
                        if analyse {
                            let c = &case.camera.name;
                            let truth_view = case.view();
                            let rows = [
                                ("fit", analyse_silhouette(&mesh, &view, &case.labels)),
                                (
                                    "truth",
                                    truth_view.clone().and_then(|v| {
                                        analyse_silhouette(&case.truth, &v, &case.labels)
                                    }),
                                ),
                                (
                                    "other seed",
                                    truth_view.and_then(|v| {
                                        analyse_silhouette(&case.other, &v, &case.labels)
                                    }),
                                ),
                            ];
                            for (what, a) in rows {
                                if let Ok(a) = a {
                                    analyses.push((c.clone(), what, a));
                                }
                            }
                        }
                        (r, seconds)
                    })
                }
            };
            let c = &case.camera;
            match row {
                Ok((r, seconds)) => {
                    println!(
                        "| {} | {} | {input} | {:.3} | {:.3} | {:.3} | {:.1} | {sph:.3} | {ell:.3} | {other:.3} |",
                        c.name, c.kind, r.similarity, r.iou64, r.photo_iou, seconds
                    );
                    let v = [r.similarity, r.iou64, r.photo_iou, seconds, sph, ell, other];
                    match sums.iter_mut().find(|s| s.0 == *input) {
                        Some(s) => s.1.push(v),
                        None => sums.push((input.to_string(), vec![v])),
                    }
                }
                Err(e) => println!(
                    "| {} | {} | {input} | failed: {e} | 0 | 0 | | {sph:.3} | {ell:.3} | {other:.3} |",
                    c.name, c.kind
                ),
            }
        }
    }
    for (input, rows) in &sums {
        let n = rows.len() as f64;
        let mean = |k: usize| rows.iter().map(|r| r[k]).sum::<f64>() / n;
        let above = rows.iter().filter(|r| r[1] > r[4]).count();
        println!(
            "| **mean** ({} fitted) | | {input} | {:.3} | {:.3} | {:.3} | {:.1} | {:.3} | {:.3} | {:.3} |",
            rows.len(),
            mean(0),
            mean(1),
            mean(2),
            mean(3),
            mean(4),
            mean(5),
            mean(6)
        );
        println!(
            "\n{input}: {above} of {} fitted trees above the sphere\n",
            rows.len()
        );
    }
    if !analyses.is_empty() {
        println!("## Where the photo-view IoU is lost\n");
        println!(
            "| tree | mesh | IoU | gaps closed | hulls | photo fill | mesh fill | area / photo's |"
        );
        println!("|---|---|---|---|---|---|---|---|");
        for what in ["fit", "truth", "other seed"] {
            let rows: Vec<_> = analyses.iter().filter(|r| r.1 == what).collect();
            for (name, _, a) in &rows {
                println!(
                    "| {name} | {what} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.2} |",
                    a.iou, a.closed_iou, a.hull_iou, a.photo_fill, a.fit_fill, a.area_ratio
                );
            }
            let n = rows.len().max(1) as f64;
            let mean =
                |f: fn(&SilhouetteAnalysis) -> f64| rows.iter().map(|r| f(&r.2)).sum::<f64>() / n;
            println!(
                "| **mean** | {what} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.2} |",
                mean(|a| a.iou),
                mean(|a| a.closed_iou),
                mean(|a| a.hull_iou),
                mean(|a| a.photo_fill),
                mean(|a| a.fit_fill),
                mean(|a| a.area_ratio)
            );
        }
    }
    Ok(())
}
