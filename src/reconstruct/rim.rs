//! The rim's edge: a cue beyond the outline (issue 16, views from above).
//!
//! From above, a cup's outline is its rim's far half, its sides and its foot; the rim's near
//! half lies inside the outline, where the photo shows it as an edge (the inside of the cup
//! meets the outside there). One outline fits a camera too low with a shape to suit it as well
//! as the truth (a mug seen from 60° was fitted from 47° with a pinched rim, IoU-64 0.73), but
//! the near rim of such a fit lies 10–20 pixels off the photo's rim edge.
//!
//! A cup on a saucer has a second such ring, its foot: the mask takes cup and saucer as one, so
//! how deep the cup stands in it (how tall the cup is) is free, but the photo shows an edge
//! where the cup's wall meets the saucer (the Mitsuba espresso cup on a saucer from 45° was
//! fitted 12 % too squat, IoU-64 0.76).
//!
//! The term: the generator's edge rings ([`Generator::edge_rings`]) are projected through each
//! view; on each ring's near half (points nearer the camera than the ring's centre by more than
//! half the ring's depth, so the ends, which run into the outline, are left out; for a ring with
//! [`EdgeRing::above`], the point where the surface going up first faces the camera, none where
//! it never does; for one with
//! [`EdgeRing::seen_within`], only inside that ring's projection), each point looks along the
//! ring's normal on screen, up to [`RANGE_SHARE`] of the image either way, for the strongest
//! brightness edge across that normal inside the object (not within two pixels of the mask's
//! border). A point that finds one (at least half the object's 90th-percentile edge strength,
//! and at least [`MIN_EDGE`])
//! costs `(t/R)²` for the offset `t` and range `R`, and its gradient pulls it along the normal
//! towards the edge (the edge held fixed, as in ICP); one that finds none costs 1, with no
//! gradient. The term is the sum over the rings of the mean over their near points, averaged
//! over the views with a photo, times
//! [`FitConfig::rim_weight`](super::FitConfig::rim_weight), and its pixel gradients go back
//! through the projection ([`ScreenChain`]) to the ring's vertices and the view.
//!
//! Views given as mask images have no photo and no term, nor has a photo with no edge inside
//! the object ([`MIN_EDGE_PIXELS`]), nor a generator without a rim.

use super::FitError;
use super::objective::resample_mask;
use crate::camera::{N_VIEW_PARAMS, Projector, View};
use crate::generators::{EdgeRing, Generator, Lod};
use crate::mask::Mask;
use crate::render::ScreenChain;
use glam::{DVec2, DVec3, Vec3};

/// The default [`FitConfig::rim_weight`](super::FitConfig::rim_weight): a rim that finds no
/// edge anywhere costs about the whole silhouette loss of a good fit (5e-4 – 1e-3). The Mitsuba
/// dish photos' mean IoU-64 at seeds 0 / 1 / 2 (`cargo bench --bench dish_photo_bench -- --fov
/// known --seed N`; 0.891 / 0.893 / 0.873 without the term): 5e-4 → 0.885 / 0.884 / –, 1e-3 →
/// 0.920 / 0.910 / 0.928, 2e-3 → 0.933 / 0.912 / 0.912, 3e-3 → 0.903 / 0.905 / –.
/// A sharper term in stage 3 only, once stages 1 and 2 have found the basin (seed 0, lens
/// known; 0.930 with this one): twice the weight 0.930, half the [`RANGE_SHARE`] 0.927; both
/// together moved the five photos from 45° up by −0.042 (the espresso cup on a saucer with a
/// spoon, 0.869 → 0.827) to +0.002: not kept (with this term the bench's fitted elevation of
/// the mug from 60° is 54–56° in every run).
pub const DEFAULT_RIM_WEIGHT: f64 = 1e-3;

/// How far along its normal a rim point looks for the photo's edge, as a share of the image's
/// longer side (20 pixels at 512). Twice as far reaches more of the photo's other edges:
/// the Mitsuba dish photos' mean IoU-64 0.920 / 0.910 → 0.913 / 0.904 (seeds 0 / 1).
/// A cost that rises faster (`(t/σ)²` with σ half the range, capped at 1, so a point more than
/// σ off counts as one that found no edge) made it worse: 0.912 / 0.900 / 0.894 at seeds
/// 0 / 1 / 2 against 0.919 / 0.921 / 0.918 (the serving bowl from 55° fell to 0.50).
pub const RANGE_SHARE: f64 = 0.04;

/// The least brightness step a pixel (after a binomial blur) that counts as the rim's edge:
/// a white bowl's smooth inside is all weak edges, and its rim's faint line would otherwise
/// lose to them. Measured on the Mitsuba dish photos (`cargo bench --bench dish_photo_bench`,
/// seed 0): 0.001 → IoU-64 0.911, 0.02 → 0.920, 0.04 → 0.864.
pub const MIN_EDGE: f32 = 0.02;

/// Fewer object pixels than this on an edge at least [`MIN_EDGE`] strong, and a view has no
/// rim term: the photo shows nothing inside the outline.
pub const MIN_EDGE_PIXELS: usize = 16;

/// The search's step along a rim point's normal, pixels.
const STEP: f64 = 0.5;

/// A photo's brightness, one value in `[0, 1]` a pixel, row-major: what the rim term reads.
#[derive(Clone, Debug, PartialEq)]
pub struct Luma {
    width: u32,
    height: u32,
    values: Vec<f32>,
}

impl Luma {
    /// The brightness (Rec. 601 weights) of an RGBA image. Errors when `rgba` is not
    /// `4 · width · height` bytes or the image is empty.
    pub fn from_rgba(width: u32, height: u32, rgba: &[u8]) -> Result<Luma, FitError> {
        let n = width as usize * height as usize;
        if n == 0 || rgba.len() != 4 * n {
            return Err(FitError(format!(
                "{} bytes for a {width}×{height} RGBA photo",
                rgba.len()
            )));
        }
        let values = rgba
            .chunks_exact(4)
            .map(|p| {
                (0.299 * f32::from(p[0]) + 0.587 * f32::from(p[1]) + 0.114 * f32::from(p[2]))
                    / 255.0
            })
            .collect();
        Ok(Luma {
            width,
            height,
            values,
        })
    }

    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// At most `max_side` on its longer side, as [`resample_mask`] reduces a mask.
    fn resampled(&self, max_side: u32) -> Result<Vec<f32>, FitError> {
        let as_mask = Mask::new(self.width, self.height, self.values.clone())
            .map_err(|e| FitError(e.to_string()))?;
        Ok(resample_mask(&as_mask, max_side).values().to_vec())
    }
}

/// One view's brightness gradient at a stage's size, zero outside the object's interior.
struct EdgeField {
    w: usize,
    h: usize,
    gx: Vec<f32>,
    gy: Vec<f32>,
    /// An edge weaker than this across the ring is not the rim's.
    threshold: f32,
    /// How far a point looks, in pixels.
    range: f64,
}

impl EdgeField {
    /// The field of `luma` (at the size of `mask`) inside `mask`'s object.
    fn new(luma: &[f32], mask: &Mask) -> Option<EdgeField> {
        let (w, h) = (mask.width() as usize, mask.height() as usize);
        if luma.len() != w * h || w < 8 || h < 8 {
            return None;
        }
        let at = |v: &[f32], x: usize, y: usize| v[y * w + x];
        // A binomial blur, then Sobel (per pixel, in brightness per pixel).
        let mut blur = luma.to_vec();
        for y in 1..h - 1 {
            for x in 1..w - 1 {
                let mut s = 0.0;
                for (dy, ky) in [(0, 1.0), (1, 2.0), (2, 1.0)] {
                    for (dx, kx) in [(0, 1.0), (1, 2.0), (2, 1.0)] {
                        s += ky * kx * at(luma, x + dx - 1, y + dy - 1);
                    }
                }
                blur[y * w + x] = s / 16.0;
            }
        }
        let object = |x: usize, y: usize| {
            let i = y * w + x;
            mask.cares(i) && mask.values()[i] >= 0.5
        };
        // Inside: every pixel within two of it is object (the outline's edge is not the rim's).
        let inside = |x: usize, y: usize| {
            x >= 3
                && y >= 3
                && x + 3 < w
                && y + 3 < h
                && (y - 2..=y + 2).all(|yy| (x - 2..=x + 2).all(|xx| object(xx, yy)))
        };
        let (mut gx, mut gy) = (vec![0.0f32; w * h], vec![0.0f32; w * h]);
        let mut strengths = Vec::new();
        for y in 1..h - 1 {
            for x in 1..w - 1 {
                if !inside(x, y) {
                    continue;
                }
                let b = |dx: usize, dy: usize| at(&blur, x + dx - 1, y + dy - 1);
                let sx =
                    (b(2, 0) + 2.0 * b(2, 1) + b(2, 2) - b(0, 0) - 2.0 * b(0, 1) - b(0, 2)) / 8.0;
                let sy =
                    (b(0, 2) + 2.0 * b(1, 2) + b(2, 2) - b(0, 0) - 2.0 * b(1, 0) - b(2, 0)) / 8.0;
                gx[y * w + x] = sx;
                gy[y * w + x] = sy;
                strengths.push(sx.hypot(sy));
            }
        }
        if strengths.len() < MIN_EDGE_PIXELS {
            return None;
        }
        let k = strengths.len() * 9 / 10;
        let (_, p90, _) = strengths.select_nth_unstable_by(k, f32::total_cmp);
        let threshold = (0.5 * *p90).max(MIN_EDGE);
        // No edge inside the object (a mask image sent as the photo, a blank object): no term,
        // rather than a constant that would only widen the restarts' tie window.
        if strengths.iter().filter(|&&s| s >= threshold).count() < MIN_EDGE_PIXELS {
            return None;
        }
        Some(EdgeField {
            w,
            h,
            gx,
            gy,
            threshold,
            range: (RANGE_SHARE * w.max(h) as f64).max(2.0),
        })
    }

    /// The brightness gradient at `p` (pixel coordinates, centres at +0.5), bilinear.
    fn gradient(&self, p: DVec2) -> DVec2 {
        let (x, y) = (p.x - 0.5, p.y - 0.5);
        if !(x >= 0.0 && y >= 0.0 && x < (self.w - 1) as f64 && y < (self.h - 1) as f64) {
            return DVec2::ZERO;
        }
        let (x0, y0) = (x.floor() as usize, y.floor() as usize);
        let (fx, fy) = (x - x0 as f64, y - y0 as f64);
        let g = |v: &[f32]| {
            let a = |xx: usize, yy: usize| f64::from(v[yy * self.w + xx]);
            (1.0 - fy) * ((1.0 - fx) * a(x0, y0) + fx * a(x0 + 1, y0))
                + fy * ((1.0 - fx) * a(x0, y0 + 1) + fx * a(x0 + 1, y0 + 1))
        };
        DVec2::new(g(&self.gx), g(&self.gy))
    }

    /// The offset along `n` (unit) from `p` of the strongest edge across `n` within the
    /// range, nearer ones preferred; `None` when none is strong enough. Either way round:
    /// only edges darker towards the ring's inside (the lip against the cup's shaded inside)
    /// lost the Mitsuba dish photos' mean IoU-64 0.930 → 0.915 (seed 0, lens known; the
    /// serving bowl from 55° 0.881 → 0.805), only brighter ones 0.913 (the mug from 60°
    /// 0.892 → 0.908, fitted from 58° instead of 56°, but the serving bowl 0.701): glazes and
    /// lights differ.
    fn edge_offset(&self, p: DVec2, n: DVec2) -> Option<f64> {
        let r = self.range;
        let steps = (r / STEP).ceil() as i64;
        let across = |t: f64| self.gradient(p + t * n).dot(n).abs();
        let mut best: Option<(f64, f64)> = None;
        for k in -steps..=steps {
            let t = k as f64 * STEP;
            let s = across(t);
            if s < f64::from(self.threshold) {
                continue;
            }
            let score = s * (1.0 - 0.5 * (t / r) * (t / r));
            if best.is_none_or(|(b, _)| score > b) {
                best = Some((score, t));
            }
        }
        // The edge between the samples: the peak of the parabola through the best and its two
        // neighbours, so the offset moves smoothly with the point (and the gradient is the
        // value's).
        best.map(|(_, t)| {
            let (a, b, c) = (across(t - STEP), across(t), across(t + STEP));
            let curve = a - 2.0 * b + c;
            if curve < 0.0 {
                t + STEP * (0.5 * (a - c) / curve).clamp(-0.5, 0.5)
            } else {
                t
            }
        })
    }
}

/// Two vertices and their weights: a point on the edge between them.
type Between = [(u32, f64); 2];

/// A near ring point that found the photo's edge: the vertices it lies between with their
/// weights, its camera-space position and dL/d(its pixel position).
struct Pull {
    between: Between,
    cam: DVec3,
    grad: DVec2,
}

/// One ring's mean cost in one view over its near points that are seen, and their pulls
/// (gradients of that mean); `None` when the ring has no such point in the view.
fn ring_cost(
    field: &EdgeField,
    pr: &Projector,
    ring: &EdgeRing,
    positions: &[Vec3],
) -> Option<(f64, Vec<Pull>)> {
    let cam_of = |v: &[u32]| -> Vec<DVec3> {
        v.iter()
            .map(|&i| pr.to_camera(positions[i as usize]))
            .collect()
    };
    let base = cam_of(&ring.vertices);
    let depth = |c: &DVec3| -c.z;
    let centre = base.iter().map(depth).sum::<f64>() / base.len() as f64;
    let half = base
        .iter()
        .map(|c| (depth(c) - centre).abs())
        .fold(0.0, f64::max);
    if half.is_nan() || half <= 0.0 || base.iter().any(|c| depth(c) <= 0.0) {
        return None;
    }
    // The edge's points: each ring vertex, or where the surface above it first faces the camera.
    let m = base.len();
    let mut chain = vec![ring.vertices.clone()];
    chain.extend(ring.above.iter().cloned());
    let chain_cam: Vec<Vec<DVec3>> = chain.iter().map(|r| cam_of(r)).collect();
    // The lathe's axis: through the first ring's centre towards the last one's.
    let mean = |ring: &[DVec3]| ring.iter().copied().sum::<DVec3>() / m as f64;
    let origin = mean(&base);
    let axis = (mean(&chain_cam[chain_cam.len() - 1]) - origin).normalize_or_zero();
    let points: Vec<Option<(Between, DVec3)>> = (0..m)
        .map(|i| {
            if chain.len() == 1 {
                return Some(([(ring.vertices[i], 1.0), (ring.vertices[i], 0.0)], base[i]));
            }
            contour(&chain, &chain_cam, i, (origin, axis))
        })
        .collect();
    let within: Vec<DVec2> = cam_of(&ring.seen_within)
        .into_iter()
        .map(|c| pr.to_pixel(c))
        .collect();
    let px: Vec<Option<DVec2>> = points
        .iter()
        .map(|p| p.map(|(_, c)| pr.to_pixel(c)))
        .collect();
    let mut cost = 0.0;
    let mut near = Vec::new();
    let mut n_near = 0usize;
    for i in 0..m {
        if centre - depth(&base[i]) <= 0.5 * half {
            continue;
        }
        let (Some((between, c)), Some(p)) = (points[i], px[i]) else {
            continue;
        };
        if within.len() >= 3 && !inside_polygon(p, &within) {
            continue;
        }
        n_near += 1;
        let (Some(next), Some(prev)) = (px[(i + 1) % m], px[(i + m - 1) % m]) else {
            cost += 1.0;
            continue;
        };
        let t = next - prev;
        if t.length() < 1e-6 {
            cost += 1.0;
            continue;
        }
        let n = t.perp().normalize();
        let r = field.range;
        match field.edge_offset(p, n) {
            Some(off) => {
                cost += (off / r) * (off / r);
                // Moving the point by δ along n moves the edge's offset by −δ.
                near.push(Pull {
                    between,
                    cam: c,
                    grad: -2.0 * off / (r * r) * n,
                });
            }
            None => cost += 1.0,
        }
    }
    if n_near == 0 {
        return None;
    }
    for p in &mut near {
        p.grad /= n_near as f64;
    }
    Some((cost / n_near as f64, near))
}

/// Going up `chain` (rings, lowest first; camera space in `cam`) at position `i` around them,
/// where the surface first faces the camera: the vertices it lies between with their weights
/// and the point. A vertex faces the camera when its outward normal (the surface's tangent
/// turned outward in the plane of the vertex and the lathe's axis, through `origin` along
/// `axis`) points at the camera; between a vertex that does not and one that does, the point is where that
/// facing crosses zero, linearly. `None` when no vertex faces the camera.
fn contour(
    chain: &[Vec<u32>],
    cam: &[Vec<DVec3>],
    i: usize,
    (origin, axis): (DVec3, DVec3),
) -> Option<(Between, DVec3)> {
    let k_max = chain.len() - 1;
    let facing = |k: usize| {
        let p = cam[k][i];
        let along = (cam[(k + 1).min(k_max)][i] - cam[k.saturating_sub(1)][i]).normalize_or_zero();
        let out = p - origin;
        let out = (out - out.dot(axis) * axis).normalize_or_zero();
        // The tangent a·out + b·axis turned clockwise in the meridian plane: b·out − a·axis.
        let normal = along.dot(axis) * out - along.dot(out) * axis;
        normal.dot(-p.normalize_or_zero())
    };
    let mut before = facing(0);
    if before > 0.0 {
        return Some(([(chain[0][i], 1.0), (chain[0][i], 0.0)], cam[0][i]));
    }
    for k in 1..=k_max {
        let f = facing(k);
        if f > 0.0 {
            let a = (before / (before - f)).clamp(0.0, 1.0);
            let point = cam[k - 1][i] + a * (cam[k][i] - cam[k - 1][i]);
            return Some(([(chain[k - 1][i], 1.0 - a), (chain[k][i], a)], point));
        }
        before = f;
    }
    None
}

/// Whether `p` is inside the closed polygon `poly` (even–odd rule).
fn inside_polygon(p: DVec2, poly: &[DVec2]) -> bool {
    let mut inside = false;
    let mut j = poly.len() - 1;
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[j]);
        if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x) {
            inside = !inside;
        }
        j = i;
    }
    inside
}

/// The rim term of one stage: each view's edge field at the stage's size (`None` for a view
/// without a photo).
pub struct RimTerm {
    views: Vec<Option<EdgeField>>,
    weight: f64,
}

impl RimTerm {
    /// The term for `masks` (one stage's, one per view) from `photos` (per view, at the fit's
    /// full mask size; missing or `None`: no photo). `None` when no view has a usable photo or
    /// the weight is 0.
    pub fn new(photos: &[Option<Luma>], masks: &[Mask], weight: f64) -> Option<RimTerm> {
        if weight <= 0.0 {
            return None;
        }
        let views: Vec<Option<EdgeField>> = masks
            .iter()
            .enumerate()
            .map(|(v, m)| {
                let luma = photos.get(v)?.as_ref()?;
                let values = luma.resampled(m.width().max(m.height())).ok()?;
                EdgeField::new(&values, m)
            })
            .collect();
        views
            .iter()
            .any(Option::is_some)
            .then_some(RimTerm { views, weight })
    }

    /// The term's value for `generator`'s mesh `positions` of `params` at `lod` through
    /// `views`; with `grads`, **adds** its gradient to dL/d(positions) and dL/d(each view's
    /// parameters).
    pub fn evaluate(
        &self,
        generator: &dyn Generator,
        params: &[f64],
        lod: Lod,
        positions: &[Vec3],
        views: &[View],
        mut grads: Option<(&mut [Vec3], &mut [[f64; N_VIEW_PARAMS]])>,
    ) -> f64 {
        let rings: Vec<EdgeRing> = generator
            .edge_rings(params, lod)
            .into_iter()
            .filter(|r| {
                let fits = |v: &[u32]| v.iter().all(|&i| (i as usize) < positions.len());
                r.vertices.len() >= 6
                    && r.above
                        .iter()
                        .all(|a| a.len() == r.vertices.len() && fits(a))
                    && fits(&r.vertices)
                    && fits(&r.seen_within)
            })
            .collect();
        if rings.is_empty() {
            return 0.0;
        }
        let mut total = 0.0;
        // Per view: its near points, each with its pixel gradient of the view's cost.
        let mut pulls: Vec<(usize, Vec<Pull>)> = Vec::new();
        for (v, (field, view)) in self.views.iter().zip(views).enumerate() {
            let Some(field) = field else { continue };
            let pr = view.projector();
            let mut near = Vec::new();
            let mut counted = false;
            for ring in &rings {
                let Some((cost, pulled)) = ring_cost(field, &pr, ring, positions) else {
                    continue;
                };
                counted = true;
                total += cost;
                near.extend(pulled);
            }
            if counted {
                pulls.push((v, near));
            }
        }
        if pulls.is_empty() {
            return 0.0;
        }
        // The mean over the views that count (one entry of `pulls` each).
        let scale = self.weight / pulls.len() as f64;
        if let Some((grad_pos, grad_views)) = grads.as_mut() {
            for (v, near) in pulls {
                let chain = ScreenChain::new(&views[v]);
                for pull in near {
                    // The point's position in the world, and its gradient shared by the two
                    // vertices it lies between by their weights (the weights held fixed).
                    let [(va, wa), (vb, wb)] = pull.between;
                    let world = (wa * positions[va as usize].as_dvec3()
                        + wb * positions[vb as usize].as_dvec3())
                    .as_vec3();
                    let g = chain.add(world, pull.cam, scale * pull.grad, &mut grad_views[v]);
                    grad_pos[va as usize] += wa as f32 * g;
                    grad_pos[vb as usize] += wb as f32 * g;
                }
            }
        }
        scale * total
    }
}

#[cfg(test)]
mod tests {
    use super::{contour, inside_polygon};
    use glam::{DVec2, DVec3};

    /// Camera space (looking down −z) of a lathe around `axis` through `centre`: ring `k` of
    /// `profile` (radius, height), `n` points around.
    fn rings(profile: &[(f64, f64)], n: usize, centre: DVec3, axis: DVec3) -> Vec<Vec<DVec3>> {
        let side = axis.any_orthonormal_vector();
        let other = axis.cross(side);
        profile
            .iter()
            .map(|&(r, y)| {
                (0..n)
                    .map(|s| {
                        let a = std::f64::consts::TAU * s as f64 / n as f64;
                        centre + y * axis + r * (a.cos() * side + a.sin() * other)
                    })
                    .collect()
            })
            .collect()
    }

    /// Seen from 45° above: a wall that widens upwards faces the camera from its foot; a belly
    /// (narrow foot, wider above) hides its foot on the near side, and the contour lies up the
    /// surface, between the first back-facing and the first facing ring; a plate flaring out
    /// at 27° shows nothing of its near underside from 45° or 80° above.
    #[test]
    fn the_contour_is_where_the_surface_going_up_first_faces_the_camera() {
        let n = 16;
        let ids: Vec<Vec<u32>> = (0..4)
            .map(|k| (0..n).map(|s| (k * n + s) as u32).collect())
            .collect();
        let at = |elevation: f64, profile: &[(f64, f64)]| {
            // Up tilted towards the camera (at the origin, looking down −z): seen from above.
            let axis = DVec3::new(0.0, elevation.cos(), elevation.sin());
            let cam = rings(profile, n, DVec3::new(0.0, 0.0, -5.0), axis);
            // The point nearest the camera on the foot ring.
            let i = (0..n)
                .min_by(|&a, &b| (-cam[0][a].z).total_cmp(&(-cam[0][b].z)))
                .unwrap();
            contour(&ids, &cam, i, (DVec3::new(0.0, 0.0, -5.0), axis)).map(|(w, p)| (i, w, p))
        };
        let up = 45f64.to_radians();
        let widening = [(1.0, 0.0), (1.05, 0.5), (1.1, 1.0), (1.15, 1.5)];
        let (i, w, _) = at(up, &widening).unwrap();
        assert_eq!(w, [(ids[0][i], 1.0), (ids[0][i], 0.0)], "the foot itself");
        let belly = [(0.5, 0.0), (0.9, 0.2), (1.1, 0.6), (1.15, 1.2)];
        let (i, w, p) = at(up, &belly).unwrap();
        assert!(w[0].0 != w[1].0 && w[0].1 > 0.0 && w[1].1 > 0.0, "{w:?}");
        assert!(w[0].0 > ids[0][i], "above the foot: {w:?}");
        assert!(p.is_finite());
        let flaring = [(0.4, 0.0), (0.6, 0.1), (0.8, 0.2), (1.0, 0.3)];
        assert!(
            at(80f64.to_radians(), &flaring).is_none(),
            "all facing down"
        );
        assert!(at(up, &flaring).is_none(), "all facing down");
    }

    #[test]
    fn inside_a_polygon() {
        let square = [
            DVec2::new(0.0, 0.0),
            DVec2::new(2.0, 0.0),
            DVec2::new(2.0, 2.0),
            DVec2::new(0.0, 2.0),
        ];
        assert!(inside_polygon(DVec2::new(1.0, 1.0), &square));
        assert!(!inside_polygon(DVec2::new(3.0, 1.0), &square));
        assert!(!inside_polygon(DVec2::new(1.0, -0.5), &square));
    }
}
