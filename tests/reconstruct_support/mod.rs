//! Shared helpers of the reconstruction tests and benchmark: random non-preset shapes, random
//! cameras, masks rendered from known meshes, and the aligned IoU-64 of a fit.

#![allow(dead_code, reason = "each test binary uses a different subset")]

use glam::{DVec2, DVec3, Vec3};
use procfit::camera::ViewParams;
use procfit::generators::{self, Generator, Lod, Mesh};
use procfit::mask::Mask;
use procfit::optim::Rng;
use procfit::reconstruct::{
    FitConfig, FitResult, Session, align_to_reference, iou64, render_coverage, views::ViewVars,
};

/// A random dish: a preset's body and handle blended towards another's, then jittered, so it
/// is none of the presets. `handle` forces the handle on or off.
pub fn random_dish(rng: &mut Rng, handle: bool) -> Vec<f64> {
    let g = generators::by_name("dish").unwrap();
    let seeds = g.seeds();
    let a = &seeds[rng.below(seeds.len())];
    let b = &seeds[rng.below(seeds.len())];
    let t = rng.range(0.2, 0.8);
    let mut x: Vec<f64> = a.iter().zip(b).map(|(a, b)| a + t * (b - a)).collect();
    for (i, s) in g.params().iter().enumerate() {
        if s.kind.is_continuous() {
            x[i] += rng.normal() * 0.04 * (s.max - s.min);
        }
    }
    // Profile radii in 0..9 stay monotone enough to look like a dish.
    x[10] = if handle { 1.0 } else { 0.0 };
    procfit::generators::sanitize_params(g.params(), &x).unwrap()
}

/// A random camera for a single photo: the handle side visible, looking slightly down, the
/// object filling about 60 % of the image height.
pub fn random_view(rng: &mut Rng, mesh: &Mesh, side: u32, fov_y: f64) -> ViewParams {
    let (lo, hi) = mesh.bounds().unwrap();
    let size = f64::from((hi - lo).max_element());
    let centre = (0.5 * (lo + hi)).as_dvec3();
    let yaw = rng.range(-0.7, 0.7);
    let pitch = rng.range(0.1, 0.6);
    let roll = rng.range(-0.05, 0.05);
    let half_h = 3.0 * (0.5 * fov_y).tan();
    let scale = rng.range(0.9, 1.3) * half_h / size;
    let mut p = ViewParams {
        yaw,
        pitch,
        roll,
        translation: DVec3::ZERO,
        scale,
        fov_y,
        principal: DVec2::ZERO,
    };
    let c = p.rotation_and_derivatives()[0] * centre * scale;
    p.translation = DVec3::new(
        -c.x + rng.range(-0.1, 0.1) * half_h,
        -c.y + rng.range(-0.1, 0.1) * half_h,
        0.0,
    );
    let _ = side;
    p
}

/// The mask of `mesh` seen through `params` at `side²`.
pub fn render_mask(mesh: &Mesh, params: &ViewParams, side: u32) -> Mask {
    let vars = ViewVars {
        yaw: params.yaw,
        pitch: params.pitch,
        roll: params.roll,
        tx: params.translation.x,
        ty: params.translation.y,
        log_scale: params.scale.ln(),
        fov_y: params.fov_y,
    };
    assert_eq!(params.translation.z, 0.0);
    let view = vars.view(side, side);
    let c = render_coverage(mesh, &view).unwrap();
    // Binarise like a segmented photo.
    Mask::new(
        side,
        side,
        c.iter()
            .map(|&v| if v >= 0.5 { 1.0 } else { 0.0 })
            .collect(),
    )
    .unwrap()
}

/// Runs a fit to the end.
pub fn fit(config: FitConfig, masks: Vec<Mask>) -> FitResult {
    let mut s = Session::new(config, masks).unwrap();
    s.run().unwrap()
}

/// IoU-64 of a fit against the reference mesh, aligned through view 0 (the reference's true
/// object transform is `truth`).
pub fn fit_iou64(result: &FitResult, reference: &Mesh, truth: &ViewParams) -> f64 {
    let g = result.model.generator;
    let mesh = g.generate(&result.model.params, Lod::High).unwrap();
    let aligned = align_to_reference(&mesh.positions, &result.views[0].params, truth);
    iou64(
        (&aligned, &mesh.triangles),
        (&reference.positions, &reference.triangles),
        128,
    )
    .unwrap()
}

/// A mesh of generator `name` at `lod`.
pub fn mesh_of(name: &str, params: &[f64], lod: Lod) -> Mesh {
    generators::by_name(name)
        .unwrap()
        .generate(params, lod)
        .unwrap()
}

/// `positions` as a Vec3 list (keeps glam out of the tests' imports).
pub fn positions(mesh: &Mesh) -> &[Vec3] {
    &mesh.positions
}

/// The generator by name.
pub fn generator(name: &str) -> &'static dyn Generator {
    generators::by_name(name).unwrap()
}
