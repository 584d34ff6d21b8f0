//! Shared checks for the generator tests: mesh validity (watertight parts, outward orientation,
//! no degenerate or duplicate triangles, unit normals, finite UVs), the gradient check against
//! central finite differences, and a small seeded random number generator.

#![allow(
    dead_code,
    reason = "each test binary uses a different subset of the helpers"
)]

use glam::{DVec3, Vec3};
use procfit_generators::build::Model;
use procfit_generators::rng::SplitMix64;
use procfit_generators::{Generator, Lod, Mesh};
use std::collections::HashMap;

/// The library's SplitMix64 with the one draw the tests add: uniform in `[lo, hi]`.
pub struct Rng(SplitMix64);

impl Rng {
    /// A stream from this raw state.
    pub fn new(state: u64) -> Rng {
        Rng(SplitMix64::from_state(state))
    }

    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        self.0.unit_f64()
    }

    /// Uniform in [lo, hi].
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
}

/// A random in-range parameter vector (whole-number kinds get whole numbers).
pub fn random_params(g: &dyn Generator, rng: &mut Rng) -> Vec<f64> {
    g.params()
        .iter()
        .map(|s| {
            let v = rng.range(s.min, s.max);
            if s.kind.is_continuous() { v } else { v.round() }
        })
        .collect()
}

/// Every promise a generated mesh makes; `Err` names the first broken one.
pub fn validate(m: &Mesh) -> Result<(), String> {
    m.check().map_err(|e| e.to_string())?;
    if m.triangles.is_empty() {
        return Err("no triangles".into());
    }
    let p: Vec<DVec3> = m.positions.iter().map(|p| p.as_dvec3()).collect();
    let extent = m
        .bounds()
        .map(|(lo, hi)| (hi - lo).max_element() as f64)
        .unwrap_or(1.0);
    // Degenerate: an area below (1e-7 × extent)² or an angle so thin the triangle is a sliver.
    for (t, tri) in m.triangles.iter().enumerate() {
        let [a, b, c] = tri.map(|i| p[i as usize]);
        if tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] {
            return Err(format!("triangle {t} repeats a vertex: {tri:?}"));
        }
        let area2 = (b - a).cross(c - a).length();
        if area2 < (1e-7 * extent).powi(2) {
            return Err(format!(
                "triangle {t} {tri:?} is degenerate (2·area {area2:e})"
            ));
        }
    }
    // Duplicates: the same three vertices twice, in any order.
    let mut seen = HashMap::new();
    for (t, tri) in m.triangles.iter().enumerate() {
        let mut k = *tri;
        k.sort_unstable();
        if let Some(o) = seen.insert(k, t) {
            return Err(format!("triangles {o} and {t} use the same vertices {k:?}"));
        }
    }
    // Watertight per part: every directed edge once, and its reverse once in the same part.
    for (part_id, part) in m.parts.iter().enumerate() {
        let tris: Vec<&[u32; 3]> = m
            .triangles
            .iter()
            .zip(&m.tri_parts)
            .filter(|(_, pt)| usize::from(**pt) == part_id)
            .map(|(t, _)| t)
            .collect();
        if tris.is_empty() {
            continue;
        }
        let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
        for t in &tris {
            for k in 0..3 {
                *edges.entry((t[k], t[(k + 1) % 3])).or_default() += 1;
            }
        }
        for (&(a, b), &n) in &edges {
            if n != 1 {
                return Err(format!("{}: edge {a}→{b} used {n} times", part.name));
            }
            if edges.get(&(b, a)) != Some(&1) {
                return Err(format!("{}: edge {a}→{b} has no opposite edge", part.name));
            }
        }
        // Outward orientation: the divergence theorem gives a positive volume.
        let vol: f64 = tris
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| p[i as usize]);
                a.dot(b.cross(c)) / 6.0
            })
            .sum();
        if vol <= 0.0 {
            return Err(format!(
                "{}: signed volume {vol:e} is not positive",
                part.name
            ));
        }
    }
    for (i, n) in m.corner_normals.iter().enumerate() {
        if (n.length() - 1.0).abs() > 1e-3 {
            return Err(format!("corner {i}: normal {n} is not unit"));
        }
    }
    // Corner normals face the same way as their triangle (no inverted shading).
    for (t, tri) in m.triangles.iter().enumerate() {
        let [a, b, c] = tri.map(|i| p[i as usize]);
        let face = (b - a).cross(c - a).normalize();
        for k in 0..3 {
            let n = m.corner_normals[3 * t + k].as_dvec3();
            if n.dot(face) <= 0.0 {
                return Err(format!("triangle {t} corner {k}: normal faces inward"));
            }
        }
    }
    if !m.corner_uvs.iter().all(|uv| uv.is_finite()) {
        return Err("non-finite uv".into());
    }
    Ok(())
}

/// Fixed random weights, one vector per vertex: the scalar of the gradient check is
/// `Σ_v w_v · position_v`.
pub fn weights(n: usize, seed: u64) -> Vec<Vec3> {
    let mut rng = Rng::new(seed);
    (0..n)
        .map(|_| {
            Vec3::new(
                rng.range(-1.0, 1.0) as f32,
                rng.range(-1.0, 1.0) as f32,
                rng.range(-1.0, 1.0) as f32,
            )
        })
        .collect()
}

/// The scalar of the gradient check in double precision, through the same build the generator
/// uses (unsanitised, so a step past a range end is not clamped away).
fn weighted<M: Model>(m: &M, p: &[f64], lod: Lod, w: &[Vec3]) -> Option<f64> {
    let b = m.build::<f64>(p, lod).ok()?;
    if b.pos.len() != w.len() {
        return None; // a step changed the topology
    }
    Some(
        b.pos
            .iter()
            .zip(w)
            .map(|(p, w)| p[0] * f64::from(w.x) + p[1] * f64::from(w.y) + p[2] * f64::from(w.z))
            .sum(),
    )
}

/// Checks the VJP of every continuous parameter against central finite differences.
///
/// Thresholds: `|vjp − fd| ≤ 1e-4·|fd| + 1e-6·max|fd|` per parameter (step 1e-6 of the range;
/// f64 throughout, so the finite difference is good to ~1e-8). A gradient that is silently
/// zero fails wherever the finite difference is not. Returns the number of parameters whose
/// finite difference is non-zero.
pub fn check_gradient<M: Model + Generator>(m: &M, params: &[f64], lod: Lod, what: &str) -> usize {
    let (mesh, vjp) = m.generate_with_vjp(params, lod).expect("generate_with_vjp");
    let w = weights(mesh.positions.len(), 7);
    let mut grad = vec![0.0; params.len()];
    vjp.vjp(&w, &mut grad).expect("vjp");
    let p = procfit_generators::sanitize_params(Model::spec(m), params).expect("sanitize");
    let mut fds = vec![0.0; params.len()];
    for (i, s) in Model::spec(m).iter().enumerate() {
        if !s.kind.is_continuous() {
            assert_eq!(grad[i], 0.0, "{what}: discrete `{}` has a gradient", s.name);
            continue;
        }
        let h = 1e-6 * (s.max - s.min);
        let mut hi = p.clone();
        let mut lo = p.clone();
        hi[i] += h;
        lo[i] -= h;
        let (Some(fh), Some(fl)) = (weighted(m, &hi, lod, &w), weighted(m, &lo, lod, &w)) else {
            panic!("{what}: a step of `{}` changed the topology", s.name);
        };
        fds[i] = (fh - fl) / (2.0 * h);
    }
    let scale = fds.iter().fold(0.0f64, |a, b| a.max(b.abs()));
    assert!(scale > 0.0, "{what}: no parameter moves the mesh");
    let mut moving = 0;
    for (i, s) in Model::spec(m).iter().enumerate() {
        let (g, fd) = (grad[i], fds[i]);
        if fd.abs() > 1e-6 * scale {
            moving += 1;
        }
        assert!(
            (g - fd).abs() <= 1e-4 * fd.abs() + 1e-6 * scale,
            "{what}: d/d `{}`: vjp {g:e} vs finite difference {fd:e}",
            s.name
        );
    }
    moving
}

/// Golden summary of a preset at a level: vertex count, triangle count and bounding box (min,
/// max) within `tol`. A surprise here is a regression; regenerate only for an intended change.
#[allow(
    clippy::too_many_arguments,
    reason = "one flat, data-driven golden case per call"
)]
pub fn check_summary(
    g: &dyn Generator,
    preset: &str,
    lod: Lod,
    tol: f32,
    verts: usize,
    tris: usize,
    lo: [f32; 3],
    hi: [f32; 3],
) {
    let p = g.preset(preset).expect("preset").values;
    let m = g.generate(&p, lod).expect("generate");
    let (blo, bhi) = m.bounds().expect("bounds");
    let got = (
        m.positions.len(),
        m.triangles.len(),
        blo.to_array(),
        bhi.to_array(),
    );
    let close = |a: [f32; 3], b: [f32; 3]| a.iter().zip(&b).all(|(x, y)| (x - y).abs() < tol);
    assert!(
        got.0 == verts && got.1 == tris && close(got.2, lo) && close(got.3, hi),
        "{preset} {lod:?}: got {got:?}"
    );
}

/// Every parameter at its minimum, at its maximum, and alternating both ways, at every level:
/// each must give a valid mesh.
pub fn check_range_corners(g: &dyn Generator) {
    let spec = g.params();
    let corners = [
        spec.iter().map(|s| s.min).collect::<Vec<_>>(),
        spec.iter().map(|s| s.max).collect(),
        spec.iter()
            .enumerate()
            .map(|(i, s)| if i % 2 == 0 { s.min } else { s.max })
            .collect(),
        spec.iter()
            .enumerate()
            .map(|(i, s)| if i % 2 == 1 { s.min } else { s.max })
            .collect(),
    ];
    for (c, p) in corners.iter().enumerate() {
        for lod in Lod::ALL {
            let m = g.generate(p, lod).expect("generate");
            if let Err(e) = validate(&m) {
                panic!("{} corner {c} {lod:?}: {e}", g.name());
            }
        }
    }
}
