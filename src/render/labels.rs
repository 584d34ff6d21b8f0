//! Multi-label silhouettes: one coverage image per part label, the front-most surface winning,
//! for building window masks and tree branch/leaf impostors (paper §3.2 uses window masks for
//! buildings; trees compare branch and leaf masks).
//!
//! Unlike the single-label silhouette, which only needs the union of triangles, which label a
//! point shows depends on depth, so this is a small z-buffer rasterizer over `s × s`
//! sub-samples per pixel (1/z interpolated linearly on screen, which is perspective-correct).
//! Coverage of label `l` at a pixel is the fraction of its sub-samples whose nearest surface has
//! label `l`. No culling: open surfaces (leaf cards) show both sides. Forward only.
//! Buffers are owned by the [`LabelRenderer`] and reused.

use super::RenderError;
use crate::camera::View;
use crate::mask::LabelImage;
use glam::{DVec2, Vec3};

/// Largest sub-sampling factor per side.
pub const MAX_SAMPLES_PER_SIDE: u32 = 8;

/// Renders per-label coverage images of one size.
#[derive(Debug)]
pub struct LabelRenderer {
    width: u32,
    height: u32,
    ss: u32,
    n_labels: usize,
    /// Per sub-sample: 1/depth of the nearest surface so far (0 = nothing).
    inv_depth: Vec<f32>,
    /// Per sub-sample: label of the nearest surface (meaningful where `inv_depth > 0`).
    label: Vec<u8>,
    screen: Vec<DVec2>,
    inv_z: Vec<f64>,
    coverage: Vec<f32>,
}

impl LabelRenderer {
    /// A renderer for `width × height` images with `samples_per_side²` sub-samples per pixel
    /// (1..=8). Errors on a bad size.
    pub fn new(
        width: u32,
        height: u32,
        samples_per_side: u32,
    ) -> Result<LabelRenderer, RenderError> {
        if width == 0 || height == 0 || width > super::MAX_SIDE || height > super::MAX_SIDE {
            return Err(RenderError(format!(
                "image size {width}×{height} is not within 1..={} a side",
                super::MAX_SIDE
            )));
        }
        if !(1..=MAX_SAMPLES_PER_SIDE).contains(&samples_per_side) {
            return Err(RenderError(format!(
                "{samples_per_side} samples per side is not within 1..={MAX_SAMPLES_PER_SIDE}"
            )));
        }
        let n = (width * samples_per_side) as usize * (height * samples_per_side) as usize;
        Ok(LabelRenderer {
            width,
            height,
            ss: samples_per_side,
            n_labels: 0,
            inv_depth: vec![0.0; n],
            label: vec![0; n],
            screen: Vec::new(),
            inv_z: Vec::new(),
            coverage: Vec::new(),
        })
    }

    /// Width and height of the images this renderer makes.
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Renders `triangles` of `positions` seen through `view`, triangle `t` carrying label
    /// `tri_labels[t] < n_labels`. Returns the coverage planes: `n_labels` row-major images,
    /// plane `l` at `[l·W·H .. (l+1)·W·H]`. Errors on mismatched lengths, bad indices or
    /// labels, non-finite positions or a vertex on or behind the camera plane.
    pub fn render(
        &mut self,
        positions: &[Vec3],
        triangles: &[[u32; 3]],
        tri_labels: &[u8],
        n_labels: usize,
        view: &View,
    ) -> Result<&[f32], RenderError> {
        if view.width != self.width || view.height != self.height {
            return Err(RenderError(format!(
                "view is {}×{} but the renderer is {}×{}",
                view.width, view.height, self.width, self.height
            )));
        }
        if tri_labels.len() != triangles.len() {
            return Err(RenderError(format!(
                "{} labels for {} triangles",
                tri_labels.len(),
                triangles.len()
            )));
        }
        if n_labels == 0 || n_labels > 256 {
            return Err(RenderError(format!(
                "{n_labels} labels is not within 1..=256"
            )));
        }
        if let Some(&l) = tri_labels.iter().find(|&&l| usize::from(l) >= n_labels) {
            return Err(RenderError(format!("label {l} but only {n_labels} labels")));
        }
        let nv = positions.len();
        if let Some(t) = triangles
            .iter()
            .find(|t| t.iter().any(|&i| i as usize >= nv))
        {
            return Err(RenderError(format!(
                "triangle {t:?} indexes past {nv} vertices"
            )));
        }
        if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
            return Err(RenderError(format!("vertex {i} is not finite")));
        }
        view.params.validate()?;
        let proj = view.projector();
        self.screen.clear();
        self.inv_z.clear();
        let near = 1e-9 * (1.0 + view.pose.position.length());
        for (i, &p) in positions.iter().enumerate() {
            let c = proj.to_camera(p);
            if -c.z <= near {
                return Err(RenderError(format!(
                    "vertex {i} is on or behind the camera plane (camera inside or touching the object)"
                )));
            }
            let s = proj.to_pixel(c);
            if !s.is_finite() {
                return Err(RenderError(format!("vertex {i} projects to infinity")));
            }
            // Scale to sub-sample units once, so sample (i, j) sits at (i + ½, j + ½).
            self.screen.push(s * f64::from(self.ss));
            self.inv_z.push(-1.0 / c.z);
        }
        self.inv_depth.fill(0.0);
        self.label.fill(0);
        for (t, &l) in triangles.iter().zip(tri_labels) {
            self.raster(*t, l);
        }
        self.resolve(n_labels);
        Ok(&self.coverage)
    }

    fn raster(&mut self, t: [u32; 3], label: u8) {
        let [a, b, c] = t.map(|i| self.screen[i as usize]);
        let [za, zb, zc] = t.map(|i| self.inv_z[i as usize]);
        let area = (b - a).perp_dot(c - a);
        if area == 0.0 || !area.is_finite() {
            return;
        }
        let (sw, sh) = (
            (self.width * self.ss) as i64,
            (self.height * self.ss) as i64,
        );
        let lo = a.min(b).min(c);
        let hi = a.max(b).max(c);
        // Samples at k + ½ inside [lo, hi]: k from ceil(lo − ½) to floor(hi − ½).
        let x0 = ((lo.x - 0.5).ceil().max(0.0) as i64).min(sw);
        let x1 = ((hi.x - 0.5).floor().min((sw - 1) as f64) as i64).max(-1);
        let y0 = ((lo.y - 0.5).ceil().max(0.0) as i64).min(sh);
        let y1 = ((hi.y - 0.5).floor().min((sh - 1) as f64) as i64).max(-1);
        let inv_area = 1.0 / area;
        // Each barycentric weight is linear in the sample's x along a row: its slope, so that
        // a row's samples outside the triangle are skipped without being tested. The span is
        // widened by a sample each side against rounding; the test inside it is the exact one,
        // so which samples are drawn does not depend on the span.
        let slopes = [
            (b.y - c.y) * inv_area,
            (c.y - a.y) * inv_area,
            (a.y - b.y) * inv_area,
        ];
        for y in y0..=y1 {
            let py = y as f64 + 0.5;
            let (mut k0, mut k1) = (x0, x1);
            let px = x0 as f64 + 0.5;
            let p = DVec2::new(px, py);
            let wa = (b - p).perp_dot(c - p) * inv_area;
            let wb = (c - p).perp_dot(a - p) * inv_area;
            for (w, s) in [wa, wb, 1.0 - wa - wb].into_iter().zip(slopes) {
                // w(X) = w + s (X − px) ≥ 0.
                if s > 0.0 {
                    let lo = (px - w / s - 0.5).ceil() - 1.0;
                    if lo.is_finite() && lo > k0 as f64 {
                        k0 = lo.min(x1 as f64 + 1.0) as i64;
                    }
                } else if s < 0.0 {
                    let hi = (px - w / s - 0.5).floor() + 1.0;
                    if hi.is_finite() && hi < k1 as f64 {
                        k1 = hi.max(x0 as f64 - 1.0) as i64;
                    }
                }
            }
            for x in k0..=k1 {
                let p = DVec2::new(x as f64 + 0.5, py);
                // Barycentric weights with the triangle's own orientation; both orientations
                // are drawn (no culling).
                let wa = (b - p).perp_dot(c - p) * inv_area;
                let wb = (c - p).perp_dot(a - p) * inv_area;
                let wc = 1.0 - wa - wb;
                if wa < 0.0 || wb < 0.0 || wc < 0.0 {
                    continue;
                }
                let iz = (wa * za + wb * zb + wc * zc) as f32;
                let k = y as usize * sw as usize + x as usize;
                if iz > self.inv_depth[k] {
                    self.inv_depth[k] = iz;
                    self.label[k] = label;
                }
            }
        }
    }

    fn resolve(&mut self, n_labels: usize) {
        let (w, h, ss) = (self.width as usize, self.height as usize, self.ss as usize);
        self.n_labels = n_labels;
        self.coverage.clear();
        self.coverage.resize(n_labels * w * h, 0.0);
        let inc = 1.0 / (ss * ss) as f32;
        for y in 0..h * ss {
            for x in 0..w * ss {
                let k = y * w * ss + x;
                if self.inv_depth[k] > 0.0 {
                    let pix = (y / ss) * w + x / ss;
                    self.coverage[usize::from(self.label[k]) * w * h + pix] += inc;
                }
            }
        }
    }

    /// The last render as a [`LabelImage`]: per pixel the label covering most of it, or
    /// `background` where less than half the pixel is covered.
    pub fn label_image(&self, background: u8) -> Result<LabelImage, RenderError> {
        let n = self.width as usize * self.height as usize;
        let labels = (0..n)
            .map(|i| {
                let (mut best, mut best_c, mut total) = (background, 0.0f32, 0.0f32);
                for l in 0..self.n_labels {
                    let c = self.coverage[l * n + i];
                    total += c;
                    if c > best_c {
                        (best, best_c) = (l as u8, c);
                    }
                }
                if total < 0.5 { background } else { best }
            })
            .collect();
        LabelImage::new(self.width, self.height, labels).map_err(|e| RenderError(e.0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::testmesh::{cube, merged, transformed};
    use glam::DVec3;

    fn view(size: u32) -> View {
        View::turntable(size, size, 0.0, 3.0, 0.6, DVec3::ZERO).unwrap()
    }

    #[test]
    fn front_label_wins_and_planes_sum_to_the_silhouette() {
        // Label 0: big cube behind; label 1: small cube in front (nearer the camera on +Z).
        let back = cube(0.4);
        let front = transformed(&cube(0.15), 1.0, Vec3::new(0.0, 0.0, 0.8));
        let m = merged(&back, &front);
        let mut r = LabelRenderer::new(32, 32, 4).unwrap();
        let cov = r
            .render(&m.positions, &m.triangles, &m.tri_parts, 2, &view(32))
            .unwrap()
            .to_vec();
        let n = 32 * 32;
        let centre = 16 * 32 + 16;
        assert_eq!((cov[centre], cov[n + centre]), (0.0, 1.0));
        // A pixel near the big cube's edge is label 0 only.
        assert_eq!((cov[16 * 32 + 8], cov[n + 16 * 32 + 8]), (1.0, 0.0));
        // Summed over labels, the planes are the silhouette (up to the two anti-aliasings).
        let mut sil = crate::render::Renderer::new(32, 32).unwrap();
        let topo = crate::render::Topology::new(&m.triangles, m.positions.len()).unwrap();
        let s = sil.forward(&topo, &m.positions, &view(32)).unwrap();
        let (mut diff, mut area_l, mut area_s) = (0.0f32, 0.0f32, 0.0f32);
        for i in 0..n {
            let sum = cov[i] + cov[n + i];
            diff = diff.max((sum - s[i]).abs());
            area_l += sum;
            area_s += s[i];
        }
        assert!(
            diff < 0.2 && (area_l / area_s - 1.0).abs() < 0.01,
            "{diff} {area_l} {area_s}"
        );
        let img = r.label_image(255).unwrap();
        assert_eq!(img.labels()[centre], 1);
        assert_eq!(img.labels()[0], 255);
        // Swap depths: the small cube behind the big one disappears.
        let hidden = transformed(&cube(0.15), 1.0, Vec3::new(0.0, 0.0, -0.8));
        let m2 = merged(&back, &hidden);
        let cov2 = r
            .render(&m2.positions, &m2.triangles, &m2.tri_parts, 2, &view(32))
            .unwrap();
        assert!(cov2[n..].iter().all(|&c| c == 0.0));
    }

    /// Every sample tested against every triangle, nearest wins: what [`LabelRenderer::render`]
    /// draws, without its per-row spans.
    fn brute_force(r: &LabelRenderer, tris: &[([DVec2; 3], [f64; 3], u8)]) -> Vec<u8> {
        let (sw, sh) = ((r.width * r.ss) as usize, (r.height * r.ss) as usize);
        let mut depth = vec![0.0f32; sw * sh];
        let mut label = vec![255u8; sw * sh];
        for &([a, b, c], [za, zb, zc], l) in tris {
            let area = (b - a).perp_dot(c - a);
            if area == 0.0 {
                continue;
            }
            for y in 0..sh {
                for x in 0..sw {
                    let p = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
                    let wa = (b - p).perp_dot(c - p) * (1.0 / area);
                    let wb = (c - p).perp_dot(a - p) * (1.0 / area);
                    let wc = 1.0 - wa - wb;
                    if wa < 0.0 || wb < 0.0 || wc < 0.0 {
                        continue;
                    }
                    let iz = (wa * za + wb * zb + wc * zc) as f32;
                    if iz > depth[y * sw + x] {
                        depth[y * sw + x] = iz;
                        label[y * sw + x] = l;
                    }
                }
            }
        }
        label
    }

    #[test]
    fn row_spans_draw_the_samples_every_test_would() {
        // Random triangles (thin slivers, huge ones past the frame, both orientations, shared
        // edges) straight in sub-sample units: the spans must skip no sample inside a triangle.
        let mut r = LabelRenderer::new(24, 20, 3).unwrap();
        let mut state = 12_345u64;
        let mut rnd = move || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for round in 0..40 {
            let mut tris = Vec::new();
            for t in 0..12u8 {
                let spread = if round % 3 == 0 { 160.0 } else { 80.0 };
                let mut pt = || DVec2::new(rnd() * spread - 10.0, rnd() * spread - 10.0);
                let a = pt();
                let (b, c) = if t % 4 == 0 {
                    // A sliver: the third corner nearly on the first edge.
                    let b = pt();
                    (b, a.lerp(b, 0.7) + DVec2::new(0.05, -0.03))
                } else if t % 4 == 1 {
                    // Integer and half-integer corners: samples exactly on edges.
                    let q = |v: DVec2| (v * 2.0).round() / 2.0;
                    (q(pt()), q(pt()))
                } else {
                    (pt(), pt())
                };
                let a = if t % 4 == 1 {
                    (a * 2.0).round() / 2.0
                } else {
                    a
                };
                tris.push(([a, b, c], [rnd() + 0.1, rnd() + 0.1, rnd() + 0.1], t % 3));
            }
            r.screen = tris.iter().flat_map(|t| t.0).collect();
            r.inv_z = tris.iter().flat_map(|t| t.1).collect();
            r.inv_depth.fill(0.0);
            r.label.fill(0);
            for (i, t) in tris.iter().enumerate() {
                let i = 3 * i as u32;
                r.raster([i, i + 1, i + 2], t.2);
            }
            let drawn: Vec<u8> = r
                .inv_depth
                .iter()
                .zip(&r.label)
                .map(|(&d, &l)| if d > 0.0 { l } else { 255 })
                .collect();
            assert_eq!(drawn, brute_force(&r, &tris), "round {round}");
        }
    }

    #[test]
    fn refuses_bad_input() {
        let m = cube(0.4);
        let mut r = LabelRenderer::new(8, 8, 2).unwrap();
        let v = view(8);
        assert!(LabelRenderer::new(8, 8, 0).is_err());
        assert!(LabelRenderer::new(0, 8, 2).is_err());
        assert!(
            r.render(&m.positions, &m.triangles, &m.tri_parts[1..], 1, &v)
                .is_err()
        );
        assert!(
            r.render(&m.positions, &m.triangles, &m.tri_parts, 0, &v)
                .is_err()
        );
        let mut nan = m.positions.clone();
        nan[0].x = f32::NAN;
        assert!(r.render(&nan, &m.triangles, &m.tri_parts, 1, &v).is_err());
        let big = cube(10.0);
        assert!(
            r.render(&big.positions, &big.triangles, &big.tri_parts, 1, &v)
                .is_err()
        );
    }
}
