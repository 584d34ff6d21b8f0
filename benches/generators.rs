//! Benchmark of the procedural generators: per generator, preset and level of detail, the mesh
//! size, the median time of `generate` and of the gradient (`generate_with_vjp` + one `vjp`),
//! printed as a markdown table. Run with `cargo bench --bench generators` (one thread).
//! Targets (issue 3): LOW mug `generate` ≤ 0.2 ms, gradient ≤ 2 ms.

use procfit::generators::{self, Lod};
use std::hint::black_box;
use std::time::{Duration, Instant};

/// Median wall time of `f` over repeated runs (at least 5, about 0.2 s in total).
fn median(mut f: impl FnMut()) -> Duration {
    f(); // warm-up
    let mut times = Vec::new();
    let start = Instant::now();
    while times.len() < 5 || (start.elapsed() < Duration::from_millis(200) && times.len() < 2000) {
        let t = Instant::now();
        f();
        times.push(t.elapsed());
    }
    times.sort_unstable();
    times[times.len() / 2]
}

fn ms(d: Duration) -> String {
    format!("{:.3}", d.as_secs_f64() * 1e3)
}

fn main() {
    // `cargo bench` passes `--bench`; a name filter may follow.
    let filter: Option<String> = std::env::args().skip(1).find(|a| !a.starts_with("--"));
    println!("| generator | preset | lod | vertices | triangles | generate ms | gradient ms |");
    println!("|---|---|---|---:|---:|---:|---:|");
    for g in generators::all() {
        for preset in g.presets() {
            let key = format!("{}/{}", g.name(), preset.name);
            if filter.as_deref().is_some_and(|f| !key.contains(f)) {
                continue;
            }
            for lod in Lod::ALL {
                let Ok(mesh) = g.generate(&preset.values, lod) else {
                    println!("| {} | {} | {lod:?} | error | | | |", g.name(), preset.name);
                    continue;
                };
                let t_gen = median(|| {
                    black_box(g.generate(black_box(&preset.values), lod).ok());
                });
                let t_grad = if g.differentiable() {
                    let adj = vec![glam::Vec3::ONE; mesh.positions.len()];
                    let mut d = vec![0.0; preset.values.len()];
                    ms(median(|| {
                        if let Ok((_, vjp)) = g.generate_with_vjp(black_box(&preset.values), lod) {
                            black_box(vjp.vjp(&adj, &mut d).ok());
                        }
                    }))
                } else {
                    "–".into()
                };
                println!(
                    "| {} | {} | {lod:?} | {} | {} | {} | {} |",
                    g.name(),
                    preset.name,
                    mesh.positions.len(),
                    mesh.triangles.len(),
                    ms(t_gen),
                    t_grad
                );
            }
        }
    }
}
