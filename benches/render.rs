//! Silhouette renderer benchmark: forward and forward + backward (MSE adjoint included) at
//! 128², 256², 512² for a welded ~3.8k-vertex and a ~20k-vertex closed lathe (a cup), single
//! thread and with rayon. Prints a markdown table of medians.
//!
//! Run: `cargo bench --bench render` (paper Table 4, their renderer: 6.7 / 23.2 / 87.1 ms at
//! 128² / 256² / 512² for ~3k vertices).

use glam::DVec3;
use procfit::camera::{N_VIEW_PARAMS, View};
use procfit::mask::Mask;
use procfit::render::testmesh::cup;
use procfit::render::{MultiViewLoss, Renderer, Topology};
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Median milliseconds of `f` over enough repetitions to fill about half a second.
fn time(mut f: impl FnMut()) -> f64 {
    f();
    let t0 = Instant::now();
    f();
    let once = t0.elapsed().as_secs_f64();
    let reps = ((0.5 / once.max(1e-6)) as usize).clamp(5, 200);
    median(
        (0..reps)
            .map(|_| {
                let t = Instant::now();
                f();
                t.elapsed().as_secs_f64() * 1e3
            })
            .collect(),
    )
}

fn main() {
    println!(
        "| mesh | size | silhouette edges | forward 1T (ms) | fwd+bwd 1T (ms) | fwd+bwd rayon (ms) |"
    );
    println!("|---|---|---|---|---|---|");
    for (label, rings, sectors) in [("cup 3.8k", 27, 64), ("cup 20k", 75, 128)] {
        let mesh = cup(rings, sectors);
        let topo = Topology::new(&mesh.triangles, mesh.positions.len()).expect("topology");
        for size in [128u32, 256, 512] {
            let mut view = View::turntable(size, size, 0.5, 3.0, 0.5, DVec3::new(0.0, 0.0, 0.0))
                .expect("view");
            view.params.pitch = 0.35;
            // Target: the same cup slightly moved, so the adjoint is non-zero along the boundary.
            let mut tv = view;
            tv.params.translation.x += 0.02;
            tv.params.scale = 1.03;
            let mut r = Renderer::new(size, size).expect("renderer");
            let target = r
                .forward(&topo, &mesh.positions, &tv)
                .expect("target")
                .to_vec();
            let mask = Mask::new(size, size, target).expect("mask");
            let fwd = time(|| {
                r.forward(&topo, &mesh.positions, &view).expect("forward");
            });
            let edges = r.n_silhouette_edges();
            let mut grad = vec![glam::Vec3::ZERO; mesh.positions.len()];
            let mut gv = [[0.0; N_VIEW_PARAMS]];
            let mut both = |parallel: bool| {
                let mut l = MultiViewLoss::new(size, size, 1).expect("loss");
                l.set_parallel(parallel);
                time(|| {
                    l.evaluate(
                        &topo,
                        &mesh.positions,
                        std::slice::from_ref(&view),
                        std::slice::from_ref(&mask),
                        &mut grad,
                        &mut gv,
                    )
                    .expect("evaluate");
                })
            };
            let (st, mt) = (both(false), both(true));
            println!(
                "| {label} ({} v) | {size}² | {edges} | {fwd:.3} | {st:.3} | {mt:.3} |",
                mesh.positions.len()
            );
        }
    }
    println!(
        "\nrayon threads: {}. Targets (native, single thread, fwd+bwd): ≤ 1 / 3 / 10 ms.",
        rayon::current_num_threads()
    );
}
