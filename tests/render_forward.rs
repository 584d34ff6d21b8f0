//! Forward-pass behaviour of the silhouette renderer: areas of known shapes, edge cancellation,
//! occlusion in the backward pass, determinism with and without rayon, and bad input.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "a test binary: a failed step should stop it loudly"
)]

use glam::{DVec3, Vec3};
use procfit::camera::{N_VIEW_PARAMS, View};
use procfit::render::testmesh::{cube, cup, merged, transformed, uv_sphere};
use procfit::render::{Renderer, Topology};

fn view(size: u32) -> View {
    View::turntable(size, size, 0.4, 3.0, 0.6, DVec3::ZERO).unwrap()
}

fn topo(mesh: &procfit::generators::Mesh) -> Topology {
    Topology::new(&mesh.triangles, mesh.positions.len()).unwrap()
}

#[test]
fn sphere_covers_its_projected_disc() {
    // A sphere of radius r at distance d projects to a disc of radius f·r/√(d² − r²).
    let (r, d) = (0.6f64, 3.0f64);
    let mesh = uv_sphere(r as f32, 48, 96);
    let v = view(128);
    let mut ren = Renderer::new(128, 128).unwrap();
    let cov = ren.forward(&topo(&mesh), &mesh.positions, &v).unwrap();
    let area: f64 = cov.iter().map(|&c| f64::from(c)).sum();
    let rad = v.focal() * r / (d * d - r * r).sqrt();
    // The tessellated sphere is slightly smaller than the true one (inscribed polygon).
    let expected = std::f64::consts::PI * rad * rad;
    assert!(
        (area / expected - 1.0).abs() < 0.01,
        "area {area:.1}, expected {expected:.1}"
    );
    assert!(cov.iter().all(|&c| (0.0..=1.0).contains(&c)));
}

#[test]
fn only_a_few_per_cent_of_edges_survive_cancellation() {
    let mesh = cup(30, 64);
    let t = topo(&mesh);
    let mut ren = Renderer::new(128, 128).unwrap();
    ren.forward(&t, &mesh.positions, &view(128)).unwrap();
    let frac = ren.n_silhouette_edges() as f64 / t.n_edges() as f64;
    assert!(frac > 0.0 && frac < 0.1, "{frac:.3} of the edges remain");
}

#[test]
fn edges_hidden_behind_another_object_get_no_gradient() {
    // A small cube entirely behind a big sphere (seen from the camera).
    let toward_camera = Vec3::new(0.4f32.sin(), 0.0, 0.4f32.cos());
    let sphere = transformed(&uv_sphere(0.6, 16, 32), 1.0, toward_camera * 0.5);
    let hidden = transformed(&cube(0.15), 1.0, -toward_camera * 0.5);
    let mesh = merged(&sphere, &hidden);
    let t = topo(&mesh);
    let v = view(64);
    let mut ren = Renderer::new(64, 64).unwrap();
    ren.forward(&t, &mesh.positions, &v).unwrap();
    let adj = vec![1.0f32; 64 * 64];
    let mut gp = vec![Vec3::ZERO; mesh.positions.len()];
    let mut gv = [0.0; N_VIEW_PARAMS];
    ren.backward(&t, &mesh.positions, &v, &adj, &mut gp, &mut gv)
        .unwrap();
    let n_sphere = sphere.positions.len();
    assert!(gp[..n_sphere].iter().any(|g| g.length() > 0.0));
    assert!(
        gp[n_sphere..].iter().all(|&g| g == Vec3::ZERO),
        "hidden cube got a gradient"
    );
    // And the image is just the sphere's.
    let mut alone = Renderer::new(64, 64).unwrap();
    let only = alone
        .forward(&topo(&sphere), &sphere.positions, &v)
        .unwrap();
    assert_eq!(only, ren.coverage());
}

#[test]
fn rayon_gives_bit_identical_results() {
    let mesh = cup(20, 48);
    let t = topo(&mesh);
    let mut v = view(96);
    v.params.pitch = 0.4;
    let run = |parallel: bool| {
        let mut ren = Renderer::new(96, 96).unwrap();
        ren.set_parallel(parallel);
        let cov = ren.forward(&t, &mesh.positions, &v).unwrap().to_vec();
        let adj: Vec<f32> = (0..cov.len())
            .map(|i| ((i % 7) as f32 - 3.0) * 0.1)
            .collect();
        let mut gp = vec![Vec3::ZERO; mesh.positions.len()];
        let mut gv = [0.0; N_VIEW_PARAMS];
        ren.backward(&t, &mesh.positions, &v, &adj, &mut gp, &mut gv)
            .unwrap();
        (cov, gp, gv)
    };
    let (a, b) = (run(false), run(true));
    assert!(
        a.0.iter()
            .zip(&b.0)
            .all(|(x, y)| x.to_bits() == y.to_bits())
    );
    assert!(
        a.1.iter()
            .zip(&b.1)
            .all(|(x, y)| x.to_array().map(f32::to_bits) == y.to_array().map(f32::to_bits))
    );
    assert!(
        a.2.iter()
            .zip(&b.2)
            .all(|(x, y)| x.to_bits() == y.to_bits())
    );
    assert!(a.1.iter().any(|g| *g != Vec3::ZERO));
}

#[test]
fn object_outside_the_image_renders_empty_with_zero_gradient() {
    let mesh = transformed(&cube(0.3), 1.0, Vec3::new(5.0, 0.0, 0.0));
    let t = topo(&mesh);
    let v = view(32);
    let mut ren = Renderer::new(32, 32).unwrap();
    assert!(
        ren.forward(&t, &mesh.positions, &v)
            .unwrap()
            .iter()
            .all(|&c| c == 0.0)
    );
    let mut gp = vec![Vec3::ZERO; 8];
    let mut gv = [0.0; N_VIEW_PARAMS];
    ren.backward(&t, &mesh.positions, &v, &[1.0; 32 * 32], &mut gp, &mut gv)
        .unwrap();
    assert!(gp.iter().all(|&g| g == Vec3::ZERO) && gv.iter().all(|&g| g == 0.0));
}

#[test]
fn empty_mesh_renders_empty() {
    let t = Topology::new(&[], 0).unwrap();
    let mut ren = Renderer::new(8, 8).unwrap();
    assert!(
        ren.forward(&t, &[], &view(8))
            .unwrap()
            .iter()
            .all(|&c| c == 0.0)
    );
}

#[test]
fn object_covering_the_whole_image_renders_full() {
    let mesh = cube(5.0);
    let mut v = view(16);
    v.pose = procfit::camera::CameraPose::turntable(0.0, 12.0, DVec3::ZERO).unwrap();
    let mut ren = Renderer::new(16, 16).unwrap();
    let cov = ren.forward(&topo(&mesh), &mesh.positions, &v).unwrap();
    assert!(cov.iter().all(|&c| c == 1.0));
}

/// Each bad input must give an error whose message names the problem.
#[test]
fn bad_input_gives_clear_errors() {
    fn check<T: std::fmt::Debug>(r: Result<T, procfit::render::RenderError>, needle: &str) {
        match r {
            Err(e) => assert!(e.0.contains(needle), "error `{}` lacks `{needle}`", e.0),
            Ok(v) => panic!("expected an error about `{needle}`, got {v:?}"),
        }
    }
    let mesh = cube(0.5);
    let t = topo(&mesh);
    let v = view(16);
    check(Renderer::new(0, 16), "image size");
    check(Renderer::new(16, 100_000), "image size");
    check(Topology::new(&[[0, 1, 9]], 3), "indexes past");
    let mut ren = Renderer::new(16, 16).unwrap();
    check(
        ren.forward(&t, &mesh.positions[..7], &v).map(|_| ()),
        "positions",
    );
    let mut nan = mesh.positions.clone();
    nan[3].y = f32::NAN;
    check(ren.forward(&t, &nan, &v).map(|_| ()), "not finite");
    let inside = cube(5.0);
    check(
        ren.forward(&topo(&inside), &inside.positions, &v)
            .map(|_| ()),
        "camera",
    );
    check(
        ren.forward(&t, &mesh.positions, &view(8)).map(|_| ()),
        "8×8",
    );
    // A vertex just in front of the camera plane projects absurdly far: an error, not a hang.
    let back = Vec3::new(0.4f32.sin(), 0.0, 0.4f32.cos());
    let right = Vec3::new(0.4f32.cos(), 0.0, -0.4f32.sin());
    let mut near = mesh.positions.clone();
    near[0] = back * 3.0 + right * 100.0 - back * 1e-6;
    check(ren.forward(&t, &near, &v).map(|_| ()), "camera plane");
    let mut bad_fov = v;
    bad_fov.params.fov_y = 4.0;
    check(
        ren.forward(&t, &mesh.positions, &bad_fov).map(|_| ()),
        "field of view",
    );
    let mut gp = vec![Vec3::ZERO; 8];
    let mut gv = [0.0; N_VIEW_PARAMS];
    // Backward before any successful forward with these inputs.
    check(
        ren.backward(&t, &mesh.positions, &v, &[0.0; 256], &mut gp, &mut gv),
        "forward",
    );
    ren.forward(&t, &mesh.positions, &v).unwrap();
    check(
        ren.backward(&t, &mesh.positions, &v, &[0.0; 255], &mut gp, &mut gv),
        "adjoint",
    );
    check(
        ren.backward(&t, &mesh.positions, &v, &[f32::NAN; 256], &mut gp, &mut gv),
        "adjoint",
    );
    check(
        ren.backward(&t, &mesh.positions, &v, &[0.0; 256], &mut gp[..3], &mut gv),
        "gradient",
    );
}

/// tiny-skia's anti-aliasing (4×4 sub-samples) against a 16× super-sampled, box-averaged
/// render: what the forward pass's coverage error is, stated as a bound.
#[test]
fn coverage_is_close_to_exact_area_coverage() {
    let mesh = cup(10, 48);
    let t = topo(&mesh);
    let mut v = view(64);
    v.params.pitch = 0.5;
    let mut ren = Renderer::new(64, 64).unwrap();
    let cov = ren.forward(&t, &mesh.positions, &v).unwrap().to_vec();
    let ss = 16usize;
    let mut big = Renderer::new(64 * ss as u32, 64 * ss as u32).unwrap();
    let bv = View {
        width: 64 * ss as u32,
        height: 64 * ss as u32,
        ..v
    };
    let b = big.forward(&t, &mesh.positions, &bv).unwrap();
    let (mut worst, mut sum, mut signed, mut n) = (0.0f32, 0.0f32, 0.0f32, 0);
    for (i, &c) in cov.iter().enumerate() {
        let (x, y) = (i % 64, i / 64);
        let mut r = 0.0;
        for dy in 0..ss {
            for dx in 0..ss {
                r += b[(ss * y + dy) * 64 * ss + ss * x + dx];
            }
        }
        r /= (ss * ss) as f32;
        if r > 0.0 && r < 1.0 || c > 0.0 && c < 1.0 {
            worst = worst.max((c - r).abs());
            sum += (c - r).abs();
            signed += c - r;
            n += 1;
        }
    }
    let mean = sum / n as f32;
    println!(
        "boundary pixels {n}: mean |error| {mean:.4}, worst {worst:.4}, signed sum {signed:.3}"
    );
    // Random-looking per pixel (16 sub-sample levels), unbiased overall: no dilation or erosion.
    assert!(
        mean < 0.03 && worst < 0.15 && signed.abs() < 0.01 * n as f32,
        "mean {mean}, worst {worst}, signed {signed}"
    );
}

#[test]
fn multi_view_loss_is_bit_identical_with_rayon() {
    let mesh = cup(8, 32);
    let t = topo(&mesh);
    let views: Vec<View> = (0..3)
        .map(|i| View::turntable(48, 48, 2.0 * i as f64, 3.0, 0.6, DVec3::ZERO).unwrap())
        .collect();
    let masks: Vec<procfit::mask::Mask> = views
        .iter()
        .map(|v| {
            let mut r = Renderer::new(48, 48).unwrap();
            let moved: Vec<Vec3> = mesh.positions.iter().map(|&p| p * 1.1).collect();
            procfit::mask::Mask::new(48, 48, r.forward(&t, &moved, v).unwrap().to_vec()).unwrap()
        })
        .collect();
    let run = |parallel: bool| {
        let mut l = procfit::render::MultiViewLoss::new(48, 48, 3).unwrap();
        l.set_parallel(parallel);
        let mut gp = vec![Vec3::ZERO; mesh.positions.len()];
        let mut gv = vec![[0.0; N_VIEW_PARAMS]; 3];
        let loss = l
            .evaluate(&t, &mesh.positions, &views, &masks, &mut gp, &mut gv)
            .unwrap();
        (loss, gp, gv)
    };
    let (a, b) = (run(false), run(true));
    assert!(a.0 > 0.0 && a.0.to_bits() == b.0.to_bits());
    assert!(
        a.1.iter()
            .zip(&b.1)
            .all(|(x, y)| x.to_array().map(f32::to_bits) == y.to_array().map(f32::to_bits))
    );
    assert_eq!(a.2, b.2);
}

/// Edge cancellation must give the union of the triangles for any triangle list, not only for
/// closed, consistently oriented meshes: a soup of overlapping triangles with random winding,
/// duplicates and shared edges, compared with a z-buffer fill of every triangle (the label
/// renderer with one label, 4×4 sub-samples).
#[test]
fn random_triangle_soup_renders_as_the_union_of_its_triangles() {
    let mut seed = 0x1234_5678_u32;
    let mut rnd = || {
        seed ^= seed << 13;
        seed ^= seed >> 17;
        seed ^= seed << 5;
        seed as f32 / u32::MAX as f32
    };
    let positions: Vec<Vec3> = (0..40)
        .map(|_| Vec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5) * 1.6)
        .collect();
    let mut triangles: Vec<[u32; 3]> = (0..60)
        .map(|_| [0, 0, 0].map(|_: u32| (rnd() * 39.99) as u32))
        .collect();
    triangles.push(triangles[0]); // a duplicate
    triangles.push([triangles[1][1], triangles[1][0], triangles[1][2]]); // its mirror twin
    let t = Topology::new(&triangles, positions.len()).unwrap();
    let v = view(64);
    let mut ren = Renderer::new(64, 64).unwrap();
    let cov = ren.forward(&t, &positions, &v).unwrap();
    let mut lab = procfit::render::LabelRenderer::new(64, 64, 4).unwrap();
    let zero = vec![0u8; triangles.len()];
    let reference = lab.render(&positions, &triangles, &zero, 1, &v).unwrap();
    let (mut worst, mut area_a, mut area_b) = (0.0f32, 0.0f32, 0.0f32);
    for (&a, &b) in cov.iter().zip(reference) {
        worst = worst.max((a - b).abs());
        area_a += a;
        area_b += b;
    }
    assert!(
        area_b > 200.0,
        "the soup should cover a good part of the image"
    );
    // Two 16-level anti-aliasings of the same union: close per pixel, equal in area.
    assert!(
        worst < 0.3 && (area_a / area_b - 1.0).abs() < 0.01,
        "worst {worst}, areas {area_a} vs {area_b}"
    );
}
