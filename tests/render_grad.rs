//! Gradients of the silhouette MSE (paper eq. 1) against central finite differences, for every
//! view parameter and for vertex positions, on small scenes with occlusion, border-crossing
//! silhouettes, thin parts and open surfaces.
//!
//! The edge integrals differentiate the exact (box-filtered) area coverage. tiny-skia's coverage
//! is a 4×4-sub-sampled approximation of it whose staircase makes finite differences at the
//! base resolution useless, so the finite differences use the loss of a super-sampled,
//! box-averaged render (the "reference") against the same target, with steps that move the
//! silhouette a fraction of a pixel. Each scene is checked twice:
//! - **exact**: the adjoint 2(I − M) is computed from the reference coverage, isolating the
//!   backward pass; thresholds are tight.
//! - **product**: the adjoint comes from the renderer's own tiny-skia coverage, as in a fit;
//!   thresholds allow for tiny-skia's coverage error (about 1/16 per boundary pixel), which
//!   matters most for parts about a pixel thin.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "a test binary: a failed step should stop it loudly"
)]

use glam::{DVec3, Vec3};
use procfit::camera::{N_VIEW_PARAMS, View, ViewParams};
use procfit::generators::Mesh;
use procfit::loss::{mse, mse_with_adjoint};
use procfit::mask::Mask;
use procfit::render::testmesh::{cube, cup, merged, open_tube, transformed, uv_sphere};
use procfit::render::{Renderer, Topology};

const SIZE: u32 = 64;
/// Finite-difference steps per view parameter at `Fd::step = 1`: each moves the silhouette
/// about a quarter pixel at this view.
const EPS: [f64; N_VIEW_PARAMS] = [
    0.015, 0.015, 0.015, 0.008, 0.008, 0.008, 0.015, 0.008, 0.004, 0.004,
];
/// Step for vertex positions at `Fd::step = 1` (world units ≈ a quarter pixel).
const EPS_POS: f64 = 0.008;

/// Finite-difference settings.
#[derive(Clone, Copy)]
struct Fd {
    /// Super-sampling factor of the reference render.
    ss: usize,
    /// Multiplier of the steps above.
    step: f64,
}

/// Enough for silhouettes many pixels wide.
const FD: Fd = Fd { ss: 8, step: 1.0 };
/// Parts about a pixel thin: the loss curves within a pixel, so smaller steps and a finer
/// reference (convergence was checked down to ss 32, step 0.1).
const FD_THIN: Fd = Fd { ss: 32, step: 0.1 };

/// Thresholds on the relative errors of one scene: (mean, max).
#[derive(Clone, Copy)]
struct Tol {
    exact: (f64, f64),
    product: (f64, f64),
}

const TOL: Tol = Tol {
    exact: (0.05, 0.15),
    product: (0.06, 0.3),
};

struct Scene {
    mesh: Mesh,
    topo: Topology,
    view: View,
    target: Mask,
}

fn base_view() -> View {
    View::turntable(SIZE, SIZE, 0.4, 3.0, 0.6, DVec3::ZERO).unwrap()
}

/// A scene whose target is the same mesh seen with a perturbed object transform, several
/// pixels away, so the current silhouette lies where the target is flat 0 or 1.
fn scene(mesh: Mesh, pitch: f64) -> Scene {
    let mut view = base_view();
    view.params.pitch = pitch;
    let topo = Topology::new(&mesh.triangles, mesh.positions.len()).unwrap();
    let mut tp = view.params;
    tp.translation += DVec3::new(0.12, -0.1, 0.05);
    tp.yaw += 0.15;
    tp.roll -= 0.1;
    tp.scale *= 1.1;
    let mut r = Renderer::new(SIZE, SIZE).unwrap();
    let cov = r
        .forward(&topo, &mesh.positions, &View { params: tp, ..view })
        .unwrap()
        .to_vec();
    let target = Mask::new(SIZE, SIZE, cov).unwrap();
    Scene {
        mesh,
        topo,
        view,
        target,
    }
}

/// An `ss`×-super-sampled, box-averaged render at the base size.
fn reference_coverage(s: &Scene, positions: &[Vec3], params: &ViewParams, ss: usize) -> Vec<f32> {
    let w = SIZE as usize;
    let big_side = (ss * w) as u32;
    let mut r = Renderer::new(big_side, big_side).unwrap();
    let v = View {
        params: *params,
        width: big_side,
        height: big_side,
        ..s.view
    };
    let big = r.forward(&s.topo, positions, &v).unwrap();
    let mut cov = vec![0.0f32; w * w];
    for (i, c) in cov.iter_mut().enumerate() {
        let (x, y) = (i % w, i / w);
        let mut sum = 0.0;
        for dy in 0..ss {
            for dx in 0..ss {
                sum += big[(ss * y + dy) * ss * w + ss * x + dx];
            }
        }
        *c = sum / (ss * ss) as f32;
    }
    cov
}

fn reference_loss(s: &Scene, positions: &[Vec3], params: &ViewParams, ss: usize) -> f64 {
    mse(&reference_coverage(s, positions, params, ss), &s.target).unwrap()
}

/// Analytic gradients; the adjoint from the reference coverage (`Some(ss)`) or from the
/// renderer's own (`None`).
fn grads(s: &Scene, adjoint_ss: Option<usize>) -> (Vec<Vec3>, [f64; N_VIEW_PARAMS]) {
    let mut r = Renderer::new(SIZE, SIZE).unwrap();
    r.forward(&s.topo, &s.mesh.positions, &s.view).unwrap();
    let cov = match adjoint_ss {
        Some(ss) => reference_coverage(s, &s.mesh.positions, &s.view.params, ss),
        None => r.coverage().to_vec(),
    };
    let mut adj = vec![0.0; cov.len()];
    mse_with_adjoint(&cov, &s.target, 1.0, &mut adj).unwrap();
    let mut gp = vec![Vec3::ZERO; s.mesh.positions.len()];
    let mut gv = [0.0; N_VIEW_PARAMS];
    r.backward(&s.topo, &s.mesh.positions, &s.view, &adj, &mut gp, &mut gv)
        .unwrap();
    (gp, gv)
}

/// Errors of (analytic, fd, step) triples relative to `|fd| + floor`, the floor being 3 % of
/// the largest loss change per step in the set, so derivatives that are truly ~0 (a sphere's
/// rotation) are judged against the scene's scale rather than against zero. A zero analytic
/// value where the finite difference is not zero gives error ≥ 0.97.
fn rel_errors(pairs: &[(f64, f64, f64)]) -> Vec<f64> {
    let scale = pairs
        .iter()
        .map(|&(_, fd, e)| (fd * e).abs())
        .fold(0.0, f64::max);
    pairs
        .iter()
        .map(|&(g, fd, e)| (g - fd).abs() / (fd.abs() + 0.03 * scale / e))
        .collect()
}

/// Deterministic smooth deformation fields δp = A·p + b, which move many silhouette vertices
/// at once (per-vertex finite differences would each move a sliver of a pixel).
fn fields(positions: &[Vec3], n: usize) -> Vec<Vec<Vec3>> {
    let mut seed = 0x9e37_79b9_u32;
    let mut rnd = || {
        seed ^= seed << 13;
        seed ^= seed >> 17;
        seed ^= seed << 5;
        (seed as f32 / u32::MAX as f32) * 2.0 - 1.0
    };
    (0..n)
        .map(|_| {
            let a = glam::Mat3::from_cols_array(&[(); 9].map(|_| rnd()));
            let b = Vec3::new(rnd(), rnd(), rnd());
            let dir: Vec<Vec3> = positions.iter().map(|&p| a * p + b).collect();
            let norm = dir.iter().map(|d| d.length()).fold(0.0, f32::max);
            dir.into_iter().map(|d| d / norm).collect()
        })
        .collect()
}

/// Labels of [`check`]'s derivatives: the view parameters, then the deformation fields.
fn view_and_field_labels() -> Vec<String> {
    ViewParams::NAMES
        .iter()
        .map(|n| n.to_string())
        .chain((0..4).map(|i| format!("field{i}")))
        .collect()
}

fn judge(
    name: &str,
    what: &str,
    labels: &[String],
    pairs: &[(f64, f64, f64)],
    (mean_max, max_max): (f64, f64),
) {
    let errs = rel_errors(pairs);
    let mean = errs.iter().sum::<f64>() / errs.len() as f64;
    let max = errs.iter().copied().fold(0.0, f64::max);
    let table: Vec<String> = labels
        .iter()
        .zip(pairs.iter().zip(&errs))
        .map(|(n, ((g, fd, _), e))| format!("  {n}: {g:.4e} vs fd {fd:.4e} (err {e:.3})"))
        .collect();
    let report = format!(
        "{name} [{what}]: mean rel. error {mean:.3} (≤ {mean_max}), max {max:.3} (≤ {max_max})\n{}",
        table.join("\n")
    );
    println!("{report}");
    assert!(mean <= mean_max && max <= max_max, "{report}");
}

/// Finite differences of the reference loss: every view parameter, then four deformation
/// fields, as (derivative, step).
fn finite_differences(s: &Scene, fd: Fd, dirs: &[Vec<Vec3>]) -> Vec<(f64, f64)> {
    let p0 = s.view.params.to_vec();
    let mut fds = Vec::new();
    for k in 0..N_VIEW_PARAMS {
        let (mut a, mut b) = (p0, p0);
        let e = EPS[k] * fd.step;
        a[k] += e;
        b[k] -= e;
        let pa = ViewParams::from_slice(&a).unwrap();
        let pb = ViewParams::from_slice(&b).unwrap();
        let d = reference_loss(s, &s.mesh.positions, &pa, fd.ss)
            - reference_loss(s, &s.mesh.positions, &pb, fd.ss);
        fds.push((d / (2.0 * e), e));
    }
    for dir in dirs {
        let e = EPS_POS * fd.step;
        let moved = |sign: f64| -> Vec<Vec3> {
            let k = (sign * e) as f32;
            s.mesh
                .positions
                .iter()
                .zip(dir)
                .map(|(&p, &d)| p + d * k)
                .collect()
        };
        let d = reference_loss(s, &moved(1.0), &s.view.params, fd.ss)
            - reference_loss(s, &moved(-1.0), &s.view.params, fd.ss);
        fds.push((d / (2.0 * e), e));
    }
    fds
}

/// The analytic counterparts of [`finite_differences`].
fn analytic(s: &Scene, adjoint_ss: Option<usize>, dirs: &[Vec<Vec3>]) -> Vec<f64> {
    let (gp, gv) = grads(s, adjoint_ss);
    gv.iter()
        .copied()
        .chain(
            dirs.iter()
                .map(|dir| gp.iter().zip(dir).map(|(g, d)| f64::from(g.dot(*d))).sum()),
        )
        .collect()
}

fn pairs(analytic: &[f64], fds: &[(f64, f64)]) -> Vec<(f64, f64, f64)> {
    analytic
        .iter()
        .zip(fds)
        .map(|(&g, &(fd, e))| (g, fd, e))
        .collect()
}

/// Checks every view-parameter derivative and four vertex-position directional derivatives of
/// one scene against finite differences, for the exact and the product adjoint.
fn check(name: &str, s: Scene, fd: Fd, tol: Tol) {
    let dirs = fields(&s.mesh.positions, 4);
    let fds = finite_differences(&s, fd, &dirs);
    assert!(
        fds.iter().all(|f| f.0 != 0.0),
        "{name}: a finite difference is zero, the scene does not exercise it"
    );
    let exact = analytic(&s, Some(fd.ss), &dirs);
    judge(
        name,
        "exact",
        &view_and_field_labels(),
        &pairs(&exact, &fds),
        tol.exact,
    );
    let product = analytic(&s, None, &dirs);
    judge(
        name,
        "product",
        &view_and_field_labels(),
        &pairs(&product, &fds),
        tol.product,
    );
}

/// The harness itself: a gradient that is silently zero (or has lost a factor of two) must
/// fail the thresholds.
#[test]
fn zero_or_halved_gradients_fail_the_check() {
    let s = scene(transformed(&cube(0.4), 1.0, Vec3::new(0.15, 0.1, 0.0)), 0.3);
    let dirs = fields(&s.mesh.positions, 4);
    let fds = finite_differences(&s, FD, &dirs);
    let good = analytic(&s, None, &dirs);
    for bad in [
        vec![0.0; good.len()],
        good.iter().map(|g| 0.5 * g).collect(),
    ] {
        let r = std::panic::catch_unwind(|| {
            judge(
                "corrupted",
                "test",
                &view_and_field_labels(),
                &pairs(&bad, &fds),
                TOL.product,
            )
        });
        assert!(r.is_err(), "a corrupted gradient passed the check");
    }
    judge(
        "cube",
        "product",
        &view_and_field_labels(),
        &pairs(&good, &fds),
        TOL.product,
    );
}

#[test]
fn gradients_of_closed_meshes_match_finite_differences() {
    let c = Vec3::new(0.15, 0.1, 0.0);
    check("cube", scene(transformed(&cube(0.4), 1.0, c), 0.3), FD, TOL);
    let sphere = transformed(&uv_sphere(0.6, 16, 32), 1.0, c);
    check("sphere", scene(sphere, 0.0), FD, TOL);
    check(
        "cup (lathe, self-occluding)",
        scene(cup(6, 32), 0.5),
        FD,
        TOL,
    );
}

#[test]
fn gradients_with_open_surfaces_and_border_match_finite_differences() {
    check("open tube", scene(open_tube(0.4, 0.8, 32), 0.6), FD, TOL);
    let big = transformed(&cube(0.4), 1.6, Vec3::new(0.5, 0.3, 0.0));
    check("cube crossing the border", scene(big, 0.3), FD, TOL);
}

#[test]
fn gradients_with_occlusion_match_finite_differences() {
    // A sphere in front of a cube: the cube's silhouette behind the sphere must not count.
    let toward_camera = Vec3::new(0.4f32.sin(), 0.0, 0.4f32.cos());
    let two = merged(
        &transformed(&cube(0.35), 1.0, Vec3::new(-0.2, 0.1, 0.0)),
        &transformed(
            &uv_sphere(0.35, 12, 24),
            1.0,
            toward_camera * 0.8 + Vec3::new(0.1, -0.1, 0.0),
        ),
    );
    check("sphere occluding a cube", scene(two, 0.2), FD, TOL);
}

#[test]
fn gradients_of_thin_parts_match_finite_differences() {
    // A rod about 1.4 px wide. tiny-skia's coverage error is a large fraction of such a rod's
    // coverage, hence the looser product tolerance.
    let tol = Tol {
        exact: (0.05, 0.15),
        product: (0.2, 0.5),
    };
    check(
        "thin rod",
        scene(open_tube(0.02, 1.2, 8), 0.2),
        FD_THIN,
        tol,
    );
}

/// Every coordinate of every cube vertex on its own (the hidden back corner must get zero).
#[test]
fn per_vertex_gradients_of_a_cube_match_finite_differences() {
    let s = scene(transformed(&cube(0.4), 1.0, Vec3::new(0.15, 0.1, 0.0)), 0.3);
    let mut out = Vec::new();
    for (what, adjoint_ss) in [("exact", Some(FD.ss)), ("product", None)] {
        let (gp, _) = grads(&s, adjoint_ss);
        let mut pairs = Vec::new();
        for v in 0..s.mesh.positions.len() {
            for axis in 0..3 {
                let moved = |d: f32| {
                    let mut p = s.mesh.positions.clone();
                    p[v][axis] += d;
                    p
                };
                let e = EPS_POS;
                let fd = (reference_loss(&s, &moved(e as f32), &s.view.params, FD.ss)
                    - reference_loss(&s, &moved(-e as f32), &s.view.params, FD.ss))
                    / (2.0 * e);
                pairs.push((f64::from(gp[v][axis]), fd, e));
            }
        }
        out.push((what, pairs));
    }
    let labels: Vec<String> = (0..s.mesh.positions.len())
        .flat_map(|v| ["x", "y", "z"].map(|a| format!("v{v}.{a}")))
        .collect();
    assert!(out[0].1.iter().filter(|p| p.1 != 0.0).count() >= 12);
    judge("cube vertices", out[0].0, &labels, &out[0].1, TOL.exact);
    judge("cube vertices", out[1].0, &labels, &out[1].1, TOL.product);
}
