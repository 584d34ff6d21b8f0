//! GLB benchmark: time to write and to read back each generator's first preset at every level
//! of detail (median of repeated runs), with file sizes. Prints a markdown table.
//!
//! Run: `cargo bench --bench glb`

use procfit::generators::{self, Lod};
use procfit::glb::{import_glb, write_glb};
use procfit::model::Model;
use std::time::Instant;

/// Median wall time of `runs` calls of `f`, in milliseconds.
fn median_ms(runs: usize, mut f: impl FnMut()) -> f64 {
    let mut times: Vec<f64> = (0..runs)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[runs / 2]
}

fn main() {
    println!("| model | lod | triangles | GLB bytes | write ms | import ms |");
    println!("|---|---:|---:|---:|---:|---:|");
    for g in generators::all() {
        let Some(preset) = g.presets().into_iter().next() else {
            continue;
        };
        for lod in Lod::ALL {
            let model = match Model::new(g.name(), &preset.values, lod) {
                Ok(m) => m,
                Err(e) => {
                    eprintln!("{}: {e}", g.name());
                    continue;
                }
            };
            let Ok(mesh) = g.generate(&model.params, lod) else {
                continue;
            };
            let doc = model.to_doc();
            let runs = if mesh.triangles.len() > 20_000 {
                11
            } else {
                51
            };
            let mut bytes = Vec::new();
            let write = median_ms(runs, || {
                bytes = write_glb(&mesh, Some(&doc), &[]).unwrap_or_default();
            });
            let read = median_ms(runs, || {
                std::hint::black_box(import_glb(&bytes).ok());
            });
            println!(
                "| {} {} | {} | {} | {} | {write:.2} | {read:.2} |",
                g.name(),
                preset.name,
                lod.index(),
                mesh.triangles.len(),
                bytes.len()
            );
        }
    }
}
