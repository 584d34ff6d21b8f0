//! Gaussian mixture colour models, as in GrabCut (Rother et al. 2004, §3.1).
//!
//! Each model has up to [`COMPONENTS`] full-covariance Gaussians over RGB in `[0, 1]`. Fitting
//! follows GrabCut's hard-assignment EM: start from a deterministic k-means split, then
//! alternately assign each sample to its most likely component and re-estimate. Covariances get
//! a small ridge so a uniform region (a studio backdrop) gives a finite density instead of a
//! singular matrix.

/// Number of mixture components (GrabCut uses 5).
pub const COMPONENTS: usize = 5;

/// Fewest samples per component when choosing the number of components.
const MIN_PER_COMPONENT: usize = 60;

/// Ridge added to covariance diagonals: σ ≈ 1.5/255 of sensor noise that every photo has.
const RIDGE: f64 = 4e-5;

/// An RGB colour in `[0, 1]`.
pub type Rgb = [f32; 3];

#[derive(Clone, Debug)]
struct Component {
    mean: [f32; 3],
    /// Inverse covariance (row-major 3×3).
    inv: [f32; 9],
    /// log(weight) − ½ log det Σ − 3/2 log 2π: the constant part of the log density.
    log_norm: f32,
    /// The mean's log colour split into its mean `m` and centred log-chroma `u` (with `u·u`),
    /// when the hue is strong enough to shade ([`SHADE_MIN_CHROMA`]).
    log_chroma: Option<(f32, [f32; 3], f32)>,
}

/// A Gaussian mixture over RGB colours.
#[derive(Clone, Debug)]
pub struct Gmm {
    comps: Vec<Component>,
}

#[derive(Clone, Copy, Default)]
struct Acc {
    n: f64,
    s: [f64; 3],
    ss: [f64; 6],
}

impl Acc {
    fn add(&mut self, c: &Rgb) {
        let x = [f64::from(c[0]), f64::from(c[1]), f64::from(c[2])];
        self.n += 1.0;
        for (s, v) in self.s.iter_mut().zip(x) {
            *s += v;
        }
        self.ss[0] += x[0] * x[0];
        self.ss[1] += x[0] * x[1];
        self.ss[2] += x[0] * x[2];
        self.ss[3] += x[1] * x[1];
        self.ss[4] += x[1] * x[2];
        self.ss[5] += x[2] * x[2];
    }
}

impl Gmm {
    /// Fits a mixture to `samples` (must be non-empty): k-means start, then `iterations` rounds
    /// of hard-assignment EM.
    pub fn fit(samples: &[Rgb], iterations: usize) -> Option<Gmm> {
        // A component needs enough samples for its covariance not to collapse onto the ridge
        // (which would make the training samples look far more likely than new ones).
        let k = (samples.len() / MIN_PER_COMPONENT).clamp(1, COMPONENTS);
        Gmm::fit_k(samples, k, iterations)
    }

    /// [`Gmm::fit`] with `k` components (1..=[`COMPONENTS`]).
    pub fn fit_k(samples: &[Rgb], k: usize, iterations: usize) -> Option<Gmm> {
        if samples.is_empty() {
            return None;
        }
        let centres = kmeans(samples, k.clamp(1, COMPONENTS).min(samples.len()), 6);
        let mut assign: Vec<usize> = samples.iter().map(|s| nearest(&centres, s)).collect();
        let mut gmm = Gmm::from_assignment(samples, &assign, centres.len())?;
        for _ in 0..iterations {
            for (a, s) in assign.iter_mut().zip(samples) {
                *a = gmm.best_component(s);
            }
            gmm = Gmm::from_assignment(samples, &assign, gmm.comps.len())?;
        }
        Some(gmm)
    }

    /// One hard-EM round on new samples from the current model (GrabCut's per-iteration refit).
    pub fn refit(&self, samples: &[Rgb]) -> Option<Gmm> {
        if samples.is_empty() {
            return None;
        }
        let assign: Vec<usize> = samples.iter().map(|s| self.best_component(s)).collect();
        Gmm::from_assignment(samples, &assign, self.comps.len())
    }

    fn from_assignment(samples: &[Rgb], assign: &[usize], k: usize) -> Option<Gmm> {
        let mut acc = vec![Acc::default(); k];
        for (s, &a) in samples.iter().zip(assign) {
            acc[a].add(s);
        }
        let total = samples.len() as f64;
        let comps: Vec<Component> = acc
            .iter()
            .filter(|a| a.n > 0.0)
            .filter_map(|a| component(a, total))
            .collect();
        if comps.is_empty() {
            None
        } else {
            Some(Gmm { comps })
        }
    }

    fn best_component(&self, c: &Rgb) -> usize {
        let mut best = 0;
        let mut best_l = f32::NEG_INFINITY;
        for (k, comp) in self.comps.iter().enumerate() {
            let l = comp.log_density(c);
            if l > best_l {
                best_l = l;
                best = k;
            }
        }
        best
    }

    /// −log p(c): the data term D of GrabCut's energy (eq. 8–9), with the sum over components
    /// replaced by its largest term (as GrabCut's own implementation effectively does when it
    /// assigns each pixel one component, eq. 8): off by at most log K, and no exp/log per pixel.
    pub fn nll(&self, c: &Rgb) -> f32 {
        let mut best = f32::NEG_INFINITY;
        for comp in &self.comps {
            best = best.max(comp.log_density(c));
        }
        -best
    }

    /// −log p(c) when `c` may also be a shaded copy of a model colour (a table in a soft
    /// shadow, or farther from the light): the least of [`Gmm::nll`] and, over the components
    /// whose hue is strong enough to tell a shade of their colour from another colour
    /// (log-chroma length at least [`SHADE_MIN_CHROMA`]), the component's density at the
    /// pixel's un-shaded colour plus [`SHADE_PENALTY`]. A shade is the colour darkened or
    /// brightened by a factor in `[lo, hi]` and its log-chroma stretched by a factor in
    /// [`SHADE_SATURATION`]: light bounced off the table itself, which fills its shadows,
    /// has the table's hue, so shadows are deeper in the hue, not only darker. A grey or white
    /// component is never shaded: a darker grey is as likely a grey object as a shadow.
    pub fn nll_shaded(&self, c: &Rgb, lo: f32, hi: f32) -> f32 {
        let mut best = f32::NEG_INFINITY;
        let lc = c.map(|v| v.max(1.0 / 512.0).ln());
        let mc = (lc[0] + lc[1] + lc[2]) / 3.0;
        for comp in &self.comps {
            best = best.max(comp.log_density(c));
            let Some((m, u, uu)) = comp.log_chroma else {
                continue;
            };
            // In log RGB the brightness axis (1, 1, 1) and the centred chroma `u` are
            // orthogonal, so the two factors are found independently, each clamped.
            let beta = (mc - m).clamp(lo.ln(), hi.ln());
            let uc = [lc[0] - mc, lc[1] - mc, lc[2] - mc];
            let gamma = ((uc[0] * u[0] + uc[1] * u[1] + uc[2] * u[2]) / uu)
                .clamp(SHADE_SATURATION[0], SHADE_SATURATION[1]);
            let x = [0, 1, 2].map(|k| (lc[k] - beta - (gamma - 1.0) * u[k]).exp());
            best = best.max(comp.log_density(&x) - SHADE_PENALTY);
        }
        -best
    }
}

/// Smallest length of a component's centred log colour (its log-chroma) for
/// [`Gmm::nll_shaded`] to shade it: a wooden table has ≈ 0.4, a white or grey wall below 0.05.
pub const SHADE_MIN_CHROMA: f32 = 0.15;
/// The range of the log-chroma stretch of a shade (1 = the colour's own hue strength).
pub const SHADE_SATURATION: [f32; 2] = [0.8, 2.2];
/// Prior cost (nats) of explaining a colour as shaded rather than as it is.
pub const SHADE_PENALTY: f32 = 2.0;

impl Component {
    fn log_density(&self, c: &Rgb) -> f32 {
        let d = [
            c[0] - self.mean[0],
            c[1] - self.mean[1],
            c[2] - self.mean[2],
        ];
        let i = &self.inv;
        // Symmetric quadratic form: diagonal plus twice the upper triangle.
        let q = d[0] * d[0] * i[0]
            + d[1] * d[1] * i[4]
            + d[2] * d[2] * i[8]
            + 2.0 * (d[0] * d[1] * i[1] + d[0] * d[2] * i[2] + d[1] * d[2] * i[5]);
        self.log_norm - 0.5 * q
    }
}

fn component(a: &Acc, total: f64) -> Option<Component> {
    let n = a.n;
    let m = [a.s[0] / n, a.s[1] / n, a.s[2] / n];
    let c00 = a.ss[0] / n - m[0] * m[0] + RIDGE;
    let c01 = a.ss[1] / n - m[0] * m[1];
    let c02 = a.ss[2] / n - m[0] * m[2];
    let c11 = a.ss[3] / n - m[1] * m[1] + RIDGE;
    let c12 = a.ss[4] / n - m[1] * m[2];
    let c22 = a.ss[5] / n - m[2] * m[2] + RIDGE;
    // Inverse of the symmetric 3×3 by cofactors.
    let i00 = c11 * c22 - c12 * c12;
    let i01 = c02 * c12 - c01 * c22;
    let i02 = c01 * c12 - c02 * c11;
    let det = c00 * i00 + c01 * i01 + c02 * i02;
    if !(det.is_finite() && det > 0.0) {
        return None;
    }
    let i11 = c00 * c22 - c02 * c02;
    let i12 = c01 * c02 - c00 * c12;
    let i22 = c00 * c11 - c01 * c01;
    let inv = [i00, i01, i02, i01, i11, i12, i02, i12, i22].map(|v| (v / det) as f32);
    let weight = n / total;
    let log_norm = weight.ln() - 0.5 * det.ln() - 1.5 * (2.0 * std::f64::consts::PI).ln();
    let mean = m.map(|v| v as f32);
    let lm = mean.map(|v| v.max(1.0 / 512.0).ln());
    let avg = (lm[0] + lm[1] + lm[2]) / 3.0;
    let u = lm.map(|v| v - avg);
    let uu = u[0] * u[0] + u[1] * u[1] + u[2] * u[2];
    Some(Component {
        mean,
        inv,
        log_norm: log_norm as f32,
        log_chroma: (uu >= SHADE_MIN_CHROMA * SHADE_MIN_CHROMA).then_some((avg, u, uu)),
    })
}

fn dist2(a: &Rgb, b: &Rgb) -> f32 {
    (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)
}

fn nearest(centres: &[Rgb], s: &Rgb) -> usize {
    let mut best = 0;
    let mut bd = f32::INFINITY;
    for (k, c) in centres.iter().enumerate() {
        let d = dist2(c, s);
        if d < bd {
            bd = d;
            best = k;
        }
    }
    best
}

/// Deterministic k-means: farthest-point seeding from the mean, then Lloyd iterations.
fn kmeans(samples: &[Rgb], k: usize, iterations: usize) -> Vec<Rgb> {
    let n = samples.len() as f32;
    let mut mean = [0.0f32; 3];
    for s in samples {
        for c in 0..3 {
            mean[c] += s[c] / n;
        }
    }
    let mut centres: Vec<Rgb> = Vec::with_capacity(k);
    let mut d: Vec<f32> = samples.iter().map(|s| dist2(s, &mean)).collect();
    while centres.len() < k {
        let (i, &far) = d
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))
            .unwrap_or((0, &0.0));
        if far <= 0.0 && !centres.is_empty() {
            break;
        }
        let c = samples[i];
        centres.push(c);
        for (dv, s) in d.iter_mut().zip(samples) {
            *dv = dv.min(dist2(s, &c));
        }
        if centres.len() == 1 {
            // The first seed is the farthest from the mean; later seeds are farthest from all.
            d = samples.iter().map(|s| dist2(s, &c)).collect();
        }
    }
    for _ in 0..iterations {
        let mut sum = vec![[0.0f64; 4]; centres.len()];
        for s in samples {
            let k = nearest(&centres, s);
            for c in 0..3 {
                sum[k][c] += f64::from(s[c]);
            }
            sum[k][3] += 1.0;
        }
        for (c, s) in centres.iter_mut().zip(&sum) {
            if s[3] > 0.0 {
                *c = [
                    (s[0] / s[3]) as f32,
                    (s[1] / s[3]) as f32,
                    (s[2] / s[3]) as f32,
                ];
            }
        }
    }
    centres
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_colour_clusters_are_told_apart_and_uniform_data_is_finite() {
        let mut s = Vec::new();
        for i in 0..200 {
            let e = (i % 7) as f32 * 0.002;
            s.push([0.9 + e, 0.1, 0.1]);
            s.push([0.1, 0.1 + e, 0.9]);
        }
        let g = Gmm::fit(&s, 3).unwrap();
        let red = g.nll(&[0.9, 0.1, 0.1]);
        let green = g.nll(&[0.1, 0.9, 0.1]);
        assert!(red + 20.0 < green, "red {red}, green {green}");
        let u = Gmm::fit(&[[0.5, 0.5, 0.5]; 50], 2).unwrap();
        assert!(u.nll(&[0.5, 0.5, 0.5]).is_finite());
        assert!(u.nll(&[0.5, 0.5, 0.5]) < u.nll(&[0.6, 0.5, 0.5]));
        assert!(Gmm::fit(&[], 1).is_none());
    }
}
