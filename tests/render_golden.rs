//! Golden images of the forward silhouette pass (cube, sphere, a lathed cup, two overlapping
//! objects, an open surface, a mesh crossing the image border) and of the multi-label pass.
//!
//! Tolerance: at most 0.5 % of the pixels may differ from the golden by more than 2/255, and
//! none by more than 64/255 (room for a sub-sample flipping on another CPU, none for a shape
//! change). On failure `<name>.actual.png` and `<name>.diff.png` (|difference| × 4) are written
//! next to the golden. `PROCFIT_BLESS=1 cargo test --test render_golden` rewrites the goldens
//! (review them before committing).
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "a test binary: a failed step should stop it loudly"
)]

use glam::{DVec3, Vec3};
use procfit::camera::View;
use procfit::generators::Mesh;
use procfit::render::testmesh::{cube, cup, merged, open_tube, transformed, uv_sphere};
use procfit::render::{LabelRenderer, Renderer, Topology};
use std::path::PathBuf;

const SIZE: u32 = 64;

fn view(azimuth: f64, pitch: f64) -> View {
    let mut v = View::turntable(SIZE, SIZE, azimuth, 3.0, 0.6, DVec3::ZERO).unwrap();
    v.params.pitch = pitch;
    v
}

fn silhouette(mesh: &Mesh, v: &View) -> Vec<u8> {
    let topo = Topology::new(&mesh.triangles, mesh.positions.len()).unwrap();
    let mut r = Renderer::new(SIZE, SIZE).unwrap();
    let cov = r.forward(&topo, &mesh.positions, v).unwrap();
    cov.iter().map(|&c| (c * 255.0).round() as u8).collect()
}

/// Compares `actual` (8-bit grey, SIZE²) with `tests/golden/<name>.png`.
fn check(name: &str, actual: &[u8]) {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/golden");
    let path = dir.join(format!("{name}.png"));
    let save = |p: PathBuf, data: Vec<u8>| {
        image::GrayImage::from_raw(SIZE, SIZE, data)
            .unwrap()
            .save(&p)
            .unwrap();
    };
    if std::env::var("PROCFIT_BLESS").is_ok() {
        save(path, actual.to_vec());
        return;
    }
    let golden = image::open(&path)
        .unwrap_or_else(|e| panic!("{name}: no golden at {} ({e}); bless it", path.display()))
        .to_luma8()
        .into_raw();
    assert_eq!(
        golden.len(),
        actual.len(),
        "{name}: golden has another size"
    );
    let diffs: Vec<u8> = golden
        .iter()
        .zip(actual)
        .map(|(&g, &a)| g.abs_diff(a))
        .collect();
    let off = diffs.iter().filter(|&&d| d > 2).count();
    let worst = diffs.iter().copied().max().unwrap_or(0);
    let ok = off as f64 <= 0.005 * diffs.len() as f64 && worst <= 64;
    if !ok {
        save(dir.join(format!("{name}.actual.png")), actual.to_vec());
        save(
            dir.join(format!("{name}.diff.png")),
            diffs.iter().map(|&d| d.saturating_mul(4)).collect(),
        );
    }
    assert!(
        ok,
        "{name}: {off} pixels differ by more than 2/255 (allowed {}), worst {worst}/255; \
         see {name}.actual.png and {name}.diff.png",
        (0.005 * diffs.len() as f64) as usize
    );
}

#[test]
fn golden_silhouettes() {
    let toward = |az: f32| Vec3::new(az.sin(), 0.0, az.cos());
    let cases: Vec<(&str, Mesh, View)> = vec![
        ("cube", cube(0.45), view(0.6, 0.5)),
        ("sphere", uv_sphere(0.7, 16, 32), view(0.0, 0.0)),
        ("cup_lathe", cup(12, 48), view(0.3, 0.6)),
        (
            "two_overlapping",
            merged(
                &transformed(&cube(0.35), 1.0, Vec3::new(-0.25, 0.1, 0.0)),
                &transformed(
                    &uv_sphere(0.35, 12, 24),
                    1.0,
                    toward(0.4) * 0.8 + Vec3::new(0.2, -0.1, 0.0),
                ),
            ),
            view(0.4, 0.2),
        ),
        ("open_tube", open_tube(0.45, 0.9, 32), view(0.2, 0.7)),
        (
            "crossing_border",
            transformed(&cube(0.4), 1.6, Vec3::new(0.6, 0.45, 0.0)),
            view(0.5, 0.3),
        ),
    ];
    for (name, mesh, v) in &cases {
        check(name, &silhouette(mesh, v));
    }
}

#[test]
fn golden_labels() {
    // Label 0 (grey 100): a cube; label 1 (grey 200): a sphere partly in front of it.
    let m = merged(
        &transformed(&cube(0.35), 1.0, Vec3::new(-0.25, 0.1, 0.0)),
        &transformed(&uv_sphere(0.35, 12, 24), 1.0, Vec3::new(0.2, -0.1, 0.7)),
    );
    let mut r = LabelRenderer::new(SIZE, SIZE, 4).unwrap();
    let v = view(0.0, 0.2);
    r.render(&m.positions, &m.triangles, &m.tri_parts, 2, &v)
        .unwrap();
    let img = r.label_image(255).unwrap();
    let grey: Vec<u8> = img
        .labels()
        .iter()
        .map(|&l| match l {
            0 => 100,
            1 => 200,
            _ => 0,
        })
        .collect();
    check("labels_cube_behind_sphere", &grey);
}
