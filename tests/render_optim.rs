//! Recovering known quantities by gradient descent alone on the silhouette MSE (eq. 1): an
//! object pose seen from three turntable views, and a sphere's radius through the vertex
//! gradients (the chain rule of eq. 2 with d(position)/d(radius) = unit direction).
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "a test binary: a failed step should stop it loudly"
)]

use glam::{DVec3, Vec3};
use procfit::camera::{N_VIEW_PARAMS, View, ViewParams};
use procfit::mask::Mask;
use procfit::render::testmesh::{cube, uv_sphere};
use procfit::render::{MultiViewLoss, Renderer, Topology};

/// Plain Adam (Kingma & Ba) on a flat vector.
struct Adam {
    lr: f64,
    m: Vec<f64>,
    v: Vec<f64>,
    t: i32,
}

impl Adam {
    fn new(n: usize, lr: f64) -> Adam {
        Adam {
            lr,
            m: vec![0.0; n],
            v: vec![0.0; n],
            t: 0,
        }
    }

    fn step(&mut self, x: &mut [f64], g: &[f64]) {
        self.t += 1;
        let (b1, b2) = (0.9f64, 0.999f64);
        for i in 0..x.len() {
            self.m[i] = b1 * self.m[i] + (1.0 - b1) * g[i];
            self.v[i] = b2 * self.v[i] + (1.0 - b2) * g[i] * g[i];
            let mh = self.m[i] / (1.0 - b1.powi(self.t));
            let vh = self.v[i] / (1.0 - b2.powi(self.t));
            x[i] -= self.lr * mh / (vh.sqrt() + 1e-12);
        }
    }
}

const SIZE: u32 = 96;

fn views(params: ViewParams) -> Vec<View> {
    [0.0, 2.1, 4.2]
        .iter()
        .map(|&az| {
            let mut v = View::turntable(SIZE, SIZE, az, 3.0, 0.6, DVec3::ZERO).unwrap();
            v.params = params;
            v
        })
        .collect()
}

fn masks(topo: &Topology, positions: &[Vec3], views: &[View]) -> Vec<Mask> {
    let mut r = Renderer::new(SIZE, SIZE).unwrap();
    views
        .iter()
        .map(|v| {
            let cov = r.forward(topo, positions, v).unwrap().to_vec();
            Mask::new(SIZE, SIZE, cov).unwrap()
        })
        .collect()
}

#[test]
fn recovers_object_pose_from_three_views() {
    let mesh = cube(0.4);
    let topo = Topology::new(&mesh.triangles, mesh.positions.len()).unwrap();
    let truth = ViewParams {
        yaw: 0.5,
        pitch: 0.3,
        roll: -0.1,
        translation: DVec3::new(0.1, -0.05, 0.08),
        ..ViewParams::default()
    };
    let targets = masks(&topo, &mesh.positions, &views(truth));
    // Start a few pixels and degrees away; fit yaw, pitch, roll and translation (scale and
    // field of view stay fixed: with few views they trade off against distance).
    let free = [0usize, 1, 2, 3, 4, 5];
    let mut x = truth.to_vec();
    for (k, d) in free.iter().zip([0.15, -0.12, 0.1, -0.08, 0.06, -0.1]) {
        x[*k] += d;
    }
    let mut loss = MultiViewLoss::new(SIZE, SIZE, 3).unwrap();
    let mut gp = vec![Vec3::ZERO; mesh.positions.len()];
    let mut gv = vec![[0.0; N_VIEW_PARAMS]; 3];
    let mut adam = Adam::new(free.len(), 0.01);
    let mut first = None;
    let mut last = 0.0;
    for _ in 0..200 {
        let vs = views(ViewParams::from_slice(&x).unwrap());
        last = loss
            .evaluate(&topo, &mesh.positions, &vs, &targets, &mut gp, &mut gv)
            .unwrap();
        first.get_or_insert(last);
        // The object transform is shared by the views: its gradient is the sum.
        let g: Vec<f64> = free
            .iter()
            .map(|&k| gv.iter().map(|v| v[k]).sum())
            .collect();
        let mut y: Vec<f64> = free.iter().map(|&k| x[k]).collect();
        adam.step(&mut y, &g);
        for (&k, v) in free.iter().zip(y) {
            x[k] = v;
        }
    }
    let t = truth.to_vec();
    let err: Vec<f64> = free.iter().map(|&k| (x[k] - t[k]).abs()).collect();
    println!("errors {err:?}, loss {first:?} → {last}");
    // 0.002 rad and 0.001 units are about 1/30 of a pixel at this view (measured: ≤ 1.2e-4).
    assert!(
        err[..3].iter().all(|&e| e < 0.002) && err[3..].iter().all(|&e| e < 0.001),
        "errors {err:?}, loss {first:?} → {last}"
    );
}

#[test]
fn recovers_sphere_radius_from_vertex_gradients() {
    let unit = uv_sphere(1.0, 16, 32);
    let topo = Topology::new(&unit.triangles, unit.positions.len()).unwrap();
    let at = |r: f64| -> Vec<Vec3> { unit.positions.iter().map(|&p| p * r as f32).collect() };
    let vs = views(ViewParams::default());
    let targets = masks(&topo, &at(0.5), &vs);
    let mut radius = 0.3;
    let mut loss = MultiViewLoss::new(SIZE, SIZE, 3).unwrap();
    let mut gp = vec![Vec3::ZERO; unit.positions.len()];
    let mut gv = vec![[0.0; N_VIEW_PARAMS]; 3];
    let mut adam = Adam::new(1, 0.01);
    for _ in 0..150 {
        let pos = at(radius);
        loss.evaluate(&topo, &pos, &vs, &targets, &mut gp, &mut gv)
            .unwrap();
        // eq. 2: dL/dr = Σ dL/dpos · dpos/dr, and dpos/dr is the unit-sphere vertex.
        let g: f64 = gp
            .iter()
            .zip(&unit.positions)
            .map(|(g, u)| f64::from(g.dot(*u)))
            .sum();
        let mut x = [radius];
        adam.step(&mut x, &[g]);
        radius = x[0];
    }
    println!("radius {radius}");
    // 0.001 is 1/30 px at this view (measured: 2e-5).
    assert!((radius - 0.5).abs() < 0.001, "radius {radius}");
}
