//! End-to-end tests of the fit: round trips from random non-preset shapes rendered from random
//! cameras, a mug that is not the generator's, determinism, and bad input.

mod reconstruct_support;

use procfit::generators::Lod;
use procfit::optim::Rng;
use procfit::reconstruct::FitConfig;
use reconstruct_support::*;

#[test]
fn experiment_one_dish() {
    let mut rng = Rng::new(1);
    let x = random_dish(&mut rng, true);
    let truth_mesh = mesh_of("dish", &x, Lod::High);
    let truth = random_view(&mut rng, &truth_mesh, 256, 0.5);
    let mask = render_mask(&truth_mesh, &truth, 256);
    let t0 = std::time::Instant::now();
    let config = FitConfig {
        generator: "dish".into(),
        fov_y: vec![Some(0.5)],
        ..FitConfig::default()
    };
    let mut s = procfit::reconstruct::Session::new(config, vec![mask]).unwrap();
    let mut last_stage = 0;
    loop {
        let p = s.step();
        if p.stage != last_stage {
            eprintln!(
                "stage {} at {:?} evals {} loss {}",
                p.stage,
                t0.elapsed(),
                p.evaluations,
                p.best_loss
            );
            last_stage = p.stage;
        }
        if p.done {
            eprintln!(
                "done at {:?} evals {} loss {}",
                t0.elapsed(),
                p.evaluations,
                p.best_loss
            );
            break;
        }
    }
    let r = s.result().unwrap();
    let iou = fit_iou64(&r, &truth_mesh, &truth);
    eprintln!("iou64 {iou} time {:?}", t0.elapsed());
    eprintln!("truth {:?}\nfit {:?}", &x[..11], &r.model.params[..11]);
    eprintln!("truth cam {:?}\nfit cam {:?}", truth, r.views[0].params);
    assert!(iou > 0.9, "IoU-64 {iou}");
}
