//! Shared helpers of the reconstruction tests and benchmark: random non-preset shapes, random
//! cameras, masks rendered from known meshes, and the aligned IoU-64 of a fit.

#![allow(dead_code, reason = "each test binary uses a different subset")]

use glam::Vec3;
use procfit::camera::ViewParams;
use procfit::generators::{self, Generator, Lod, Mesh};
use procfit::mask::Mask;
use procfit::optim::Rng;
use procfit::reconstruct::{
    CAMERA_DISTANCE, FitConfig, FitResult, Session, align_to_reference, iou64, render_coverage,
    views::ViewVars,
};

/// A random dish: a seed's body and handle blended towards another's, then perturbed smoothly
/// (a random tilt and bend of the profile, small noise elsewhere), so it is none of the presets
/// yet looks like a real dish. `handle` forces the handle on or off.
pub fn random_dish(rng: &mut Rng, handle: bool) -> Vec<f64> {
    let g = generators::by_name("dish").unwrap();
    // The cups without a saucer (the saucer seeds came later; the cases stay what they were).
    let has_saucer = g
        .params()
        .iter()
        .position(|s| s.name == "has_saucer")
        .unwrap();
    let seeds: Vec<Vec<f64>> = g
        .seeds()
        .into_iter()
        .filter(|s| s[has_saucer] < 0.5)
        .collect();
    let a = &seeds[rng.below(seeds.len())];
    let b = &seeds[rng.below(seeds.len())];
    let t = rng.range(0.2, 0.8);
    let mut x: Vec<f64> = a.iter().zip(b).map(|(a, b)| a + t * (b - a)).collect();
    let (tilt, bend, grow) = (
        rng.range(-0.6, 0.6),
        rng.range(-0.4, 0.4),
        rng.range(0.85, 1.15),
    );
    for (i, xi) in x.iter_mut().enumerate().take(9) {
        let s = i as f64 / 8.0;
        *xi = *xi * grow + tilt * (s - 0.5) + bend * (4.0 * s * (1.0 - s) - 0.5);
    }
    // The saucer's sizes are left alone: they came later, and drawing for them would change
    // every case after them (a saucer-less dish does not show them anyway).
    for (i, s) in g.params().iter().enumerate().skip(9) {
        if s.kind.is_continuous() && !s.name.starts_with("saucer_") {
            x[i] += rng.normal() * 0.02 * (s.max - s.min);
        }
    }
    x[10] = if handle { 1.0 } else { 0.0 };
    procfit::generators::sanitize_params(g.params(), &x).unwrap()
}

/// A random camera for a photo as people take them, the object spun by `spin` plus a random
/// angle: the handle side visible, the
/// camera 14°–34° above the object (much lower and a bowl's rim ellipse degenerates, so its
/// depth cannot be told from one view), the object filling about 60 % of the image height.
pub fn random_view_at(rng: &mut Rng, mesh: &Mesh, fov_y: f64, spin: f64) -> ViewParams {
    let yaw = spin + rng.range(-0.7, 0.7);
    let pitch = rng.range(0.25, 0.6);
    view_with(rng, mesh, fov_y, yaw, pitch)
}

/// Like [`random_view_at`] with a given camera elevation.
pub fn view_at(rng: &mut Rng, mesh: &Mesh, fov_y: f64, spin: f64, pitch: f64) -> ViewParams {
    let yaw = spin + rng.range(-0.7, 0.7);
    view_with(rng, mesh, fov_y, yaw, pitch)
}

fn view_with(rng: &mut Rng, mesh: &Mesh, fov_y: f64, yaw: f64, pitch: f64) -> ViewParams {
    let (lo, hi) = mesh.bounds().unwrap();
    let roll = rng.range(-0.05, 0.05);
    let fill = rng.range(0.9, 1.3);
    let mut vars = ViewVars {
        yaw,
        pitch,
        roll,
        tx: 0.0,
        ty: 0.0,
        log_scale: 0.0,
        fov_y,
    }
    .framing(lo, hi, fill);
    let half_h = CAMERA_DISTANCE * (0.5 * fov_y).tan();
    vars.tx += rng.range(-0.1, 0.1) * half_h;
    vars.ty += rng.range(-0.1, 0.1) * half_h;
    vars.params()
}

/// The fit's camera with the object placed by `params`, for a `side²` image.
pub fn square_view(params: ViewParams, side: u32) -> procfit::camera::View {
    procfit::camera::View {
        width: side,
        height: side,
        pose: procfit::reconstruct::views::camera_pose(),
        params,
    }
}

/// A camera at `yaw` and `pitch` (radians; the fov 0.5 rad) that sees `mesh` centred,
/// its largest extent 60 % of the image's height.
pub fn framing_view(mesh: &Mesh, yaw: f64, pitch: f64) -> ViewVars {
    let (lo, hi) = mesh.bounds().unwrap();
    let vars = ViewVars {
        yaw,
        pitch,
        roll: 0.0,
        tx: 0.0,
        ty: 0.0,
        log_scale: 0.0,
        fov_y: 0.5,
    };
    vars.framing(lo, hi, 0.6)
}

/// The mask of `mesh` seen through `params` at `side²`.
pub fn render_mask(mesh: &Mesh, params: &ViewParams, side: u32) -> Mask {
    let view = square_view(*params, side);
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

/// How many of the building generator's presets and parameters [`random_building`] draws from:
/// the first seven presets (rectangular, mirror-symmetric) and the first 51 parameters, the
/// generator as it was when these cases were measured, so the cases stay the same buildings
/// (the L-shaped and shed-roof presets and the footprint parameters came later; the building
/// benchmark, `tests/building_bench.rs`, covers them).
const RANDOM_BUILDING_PRESETS: usize = 7;
const RANDOM_BUILDING_PARAMS: usize = 51;

/// A random building: a preset with its floor count changed by up to one and every continuous
/// parameter moved by up to 6 % of its range, so it is none of the presets.
pub fn random_building(rng: &mut Rng) -> Vec<f64> {
    let g = generators::by_name("building").unwrap();
    let presets = g.presets();
    let n = presets.len().min(RANDOM_BUILDING_PRESETS);
    let mut x = presets[rng.below(n)].values.clone();
    for (i, s) in g.params().iter().enumerate().take(RANDOM_BUILDING_PARAMS) {
        if s.kind.is_continuous() {
            x[i] += rng.range(-0.06, 0.06) * (s.max - s.min);
        } else if s.name == "floors" {
            x[i] += rng.below(3) as f64 - 1.0;
        }
    }
    procfit::generators::sanitize_params(g.params(), &x).unwrap()
}

/// IoU-64 aligned through view `v`.
pub fn fit_iou64_view(result: &FitResult, reference: &Mesh, truth: &ViewParams, v: usize) -> f64 {
    let g = result.model.generator;
    let mesh = g.generate(&result.model.params, Lod::High).unwrap();
    let aligned = align_to_reference(&mesh.positions, &result.views[v].params, truth);
    iou64(
        (&aligned, &mesh.triangles),
        (&reference.positions, &reference.triangles),
        128,
    )
    .unwrap()
}

/// A mug lathed from measured dimensions (a common 300 ml mug: 80 mm across, 95 mm tall,
/// 4 mm wall, 6 mm base, a round handle of 10 mm tube on a 28 mm bend), 48 sectors and a
/// 12-sided handle tube — not the generator's construction or tessellation — as OBJ text.
pub fn measured_mug_obj() -> String {
    use std::f64::consts::{PI, TAU};
    use std::fmt::Write;
    let mm = 0.001;
    // Closed profile (radius, height) from the bottom centre over the outside, the rim and
    // the inside back to the axis.
    let profile = [
        (0.0, 0.0),
        (36.0, 0.0),
        (39.0, 1.5),
        (40.0, 5.0),
        (40.0, 60.0),
        (40.0, 95.0),
        (38.0, 95.0),
        (36.0, 93.0),
        (36.0, 10.0),
        (33.0, 6.0),
        (0.0, 6.0),
    ];
    let sectors = 48;
    let mut obj = String::from("# measured mug\n");
    let mut n = 0usize;
    for &(r, y) in &profile {
        for s in 0..sectors {
            let a = TAU * s as f64 / sectors as f64;
            writeln!(
                obj,
                "v {} {} {}",
                r * a.cos() * mm,
                y * mm,
                -r * a.sin() * mm
            )
            .unwrap();
        }
    }
    for k in 0..profile.len() - 1 {
        for s in 0..sectors {
            let (a, b) = (k * sectors + s, k * sectors + (s + 1) % sectors);
            let (c, d) = (a + sectors, b + sectors);
            writeln!(obj, "f {} {} {}", a + 1, b + 1, d + 1).unwrap();
            writeln!(obj, "f {} {} {}", a + 1, d + 1, c + 1).unwrap();
        }
    }
    n += profile.len() * sectors;
    // Handle: a tube swept over half a circle on the +X side, its ends inside the wall.
    let (steps, ring, tube, bend, cy) = (24, 12, 5.0, 28.0, 50.0);
    for i in 0..=steps {
        let t = -PI / 2.0 + PI * i as f64 / steps as f64;
        let (cx, cyy) = (38.0 + bend * t.cos(), cy + bend * t.sin());
        let (nx, ny) = (t.cos(), t.sin());
        for j in 0..ring {
            let u = TAU * j as f64 / ring as f64;
            let (x, y, z) = (
                cx + tube * u.cos() * nx,
                cyy + tube * u.cos() * ny,
                tube * u.sin(),
            );
            writeln!(obj, "v {} {} {}", x * mm, y * mm, z * mm).unwrap();
        }
    }
    for i in 0..steps {
        for j in 0..ring {
            let a = n + i * ring + j;
            let b = n + i * ring + (j + 1) % ring;
            let (c, d) = (a + ring, b + ring);
            writeln!(obj, "f {} {} {}", a + 1, d + 1, b + 1).unwrap();
            writeln!(obj, "f {} {} {}", a + 1, c + 1, d + 1).unwrap();
        }
    }
    obj
}

/// The measured mug as a mesh (through the OBJ importer).
pub fn measured_mug() -> Mesh {
    let reference = procfit::glb::import_obj(measured_mug_obj().as_bytes()).unwrap();
    Mesh {
        positions: reference.positions,
        triangles: reference.triangles,
        ..Mesh::default()
    }
}

/// The measured mug standing on a measured saucer (150 mm across, a 16 mm high rim, 4 mm
/// plate, a 70 mm flat well the mug stands in), lathed in 48 sectors — not the generator's
/// construction.
pub fn measured_mug_on_saucer() -> Mesh {
    use std::f64::consts::TAU;
    let mm = 0.001f32;
    let well = 4.0f32;
    let mut mesh = measured_mug();
    for p in &mut mesh.positions {
        p.y += well * mm;
    }
    // Closed profile (radius, height): foot ring, underside, rim lip, top, well.
    let profile = [
        (0.0, 0.0),
        (30.0, 0.0),
        (35.0, 2.0),
        (72.0, 13.0),
        (75.0, 15.0),
        (74.0, 16.0),
        (70.0, 16.0),
        (38.0, well),
        (0.0, well),
    ];
    let sectors = 48usize;
    let base = mesh.positions.len() as u32;
    for &(r, y) in &profile {
        for s in 0..sectors {
            let a = TAU * s as f64 / sectors as f64;
            mesh.positions.push(Vec3::new(
                r * a.cos() as f32 * mm,
                y * mm,
                -r * a.sin() as f32 * mm,
            ));
        }
    }
    let n = sectors as u32;
    for k in 0..profile.len() as u32 - 1 {
        for s in 0..n {
            let (a, b) = (base + k * n + s, base + k * n + (s + 1) % n);
            let (c, d) = (a + n, b + n);
            mesh.triangles.push([a, b, d]);
            mesh.triangles.push([a, d, c]);
        }
    }
    mesh
}

/// A synthetic photo of a dish from above for the rim term: background grey, the object
/// (`mask`) bright, and inside `ring` (the rim projected, in order around it) dark, so the rim
/// is an edge all round.
pub fn photo_with_dark_rim(mask: &Mask, ring: &[glam::DVec2]) -> procfit::reconstruct::Luma {
    photo_of_cup(mask, mask, ring)
}

/// [`photo_with_dark_rim`] of a cup on a saucer: the object's pixels outside the cup (`cup`,
/// the mask of the cup alone) are the saucer, darker than the cup and lighter than the inside
/// of the rim, so the cup's foot is an edge too.
pub fn photo_of_cup(mask: &Mask, cup: &Mask, ring: &[glam::DVec2]) -> procfit::reconstruct::Luma {
    let inside_rim = |q: glam::DVec2| {
        let mut odd = false;
        for k in 0..ring.len() {
            let (a, b) = (ring[k], ring[(k + 1) % ring.len()]);
            if (a.y > q.y) != (b.y > q.y) && q.x < a.x + (q.y - a.y) * (b.x - a.x) / (b.y - a.y) {
                odd = !odd;
            }
        }
        odd
    };
    let w = mask.width() as usize;
    let mut rgba = Vec::with_capacity(4 * mask.values().len());
    for (i, &m) in mask.values().iter().enumerate() {
        let q = glam::DVec2::new((i % w) as f64 + 0.5, (i / w) as f64 + 0.5);
        let v: u8 = if m < 0.5 {
            128
        } else if inside_rim(q) {
            77
        } else if cup.values()[i] < 0.5 {
            150
        } else {
            204
        };
        rgba.extend([v, v, v, 255]);
    }
    procfit::reconstruct::Luma::from_rgba(mask.width(), mask.height(), &rgba).unwrap()
}

/// Checks `grad` (the objective's at `p`) against central finite differences of `value` at
/// each `(index, step)`: within `rel` of the larger of the two, plus 2e-3.
pub fn check_finite_differences(
    value: impl Fn(&[f64]) -> f64,
    p: &[f64],
    grad: &[f64],
    checks: &[(usize, f64)],
    rel: f64,
) {
    for &(i, h) in checks {
        let (mut a, mut b) = (p.to_vec(), p.to_vec());
        a[i] += h;
        b[i] -= h;
        let fd = (value(&a) - value(&b)) / (2.0 * h);
        let err = (grad[i] - fd).abs();
        assert!(
            err <= rel * fd.abs().max(grad[i].abs()) + 2e-3,
            "d/dx[{i}]: analytic {} vs finite difference {fd}",
            grad[i]
        );
    }
}
