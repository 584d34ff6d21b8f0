//! Silhouette renderer benchmark: forward, and forward + MSE adjoint + backward, at 128², 256²,
//! 512² for a welded ~3.8k-vertex and a ~20k-vertex closed lathe (a cup); single thread, with
//! rayon inside one view, and the 4-view loss single thread and with rayon over views. Prints
//! a markdown table of medians (and minima, which are steadier on a shared machine).
//!
//! Run: `cargo bench --bench render`. Paper Table 4, their renderer: 6.7 / 23.2 / 87.1 ms at
//! 128² / 256² / 512² for ~3k vertices; targets here ≤ 1 / 3 / 10 ms single thread. The
//! workload is `procfit::render::bench::BenchScene`, which the page can time in wasm.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "a benchmark binary: a failed workload should stop it loudly"
)]

use procfit::render::bench::{BenchMesh, BenchScene};
use std::time::Instant;

/// Median and minimum milliseconds of `f` over enough repetitions to fill ~0.4 s.
fn time(mut f: impl FnMut()) -> (f64, f64) {
    f();
    let t0 = Instant::now();
    f();
    let once = t0.elapsed().as_secs_f64();
    let reps = ((0.4 / once.max(1e-6)) as usize).clamp(7, 300);
    let mut v: Vec<f64> = (0..reps)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    v.sort_by(f64::total_cmp);
    (v[v.len() / 2], v[0])
}

fn cell((median, min): (f64, f64)) -> String {
    format!("{median:.3} ({min:.3})")
}

fn main() {
    println!("Times in ms: median (min).\n");
    println!(
        "| mesh | size | silhouette edges | forward 1T | fwd+bwd 1T | fwd+bwd rayon | \
         4 views 1T | 4 views rayon |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for (label, mesh) in [("cup", BenchMesh::Small), ("cup", BenchMesh::Large)] {
        for size in [128u32, 256, 512] {
            let mut s = BenchScene::new(mesh, size, 4).expect("scene");
            s.set_parallel(false);
            let fwd = time(|| s.forward().expect("forward"));
            let edges = s.n_silhouette_edges();
            let st = time(|| {
                s.forward_backward().expect("forward + backward");
            });
            let m1 = time(|| {
                s.evaluate().expect("evaluate");
            });
            s.set_parallel(true);
            let mt = time(|| {
                s.forward_backward().expect("forward + backward");
            });
            let mp = time(|| {
                s.evaluate().expect("evaluate");
            });
            println!(
                "| {label} {} v | {size}² | {edges} | {} | {} | {} | {} | {} |",
                s.n_vertices(),
                cell(fwd),
                cell(st),
                cell(mt),
                cell(m1),
                cell(mp)
            );
        }
    }
    println!(
        "\nrayon threads: {}; targets (native, one view, fwd+bwd, 1T): ≤ 1 / 3 / 10 ms.",
        rayon::current_num_threads()
    );
}
