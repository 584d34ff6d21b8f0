//! Does the object run off the frame? The automatic mask takes the photo's border for
//! background; when the object crosses the border (it is cut by the frame, or fills it), that
//! is false, and the cut finds a fragment or nothing. This module looks at each side of the
//! frame for a long stretch whose colours are none of the background seen at that side's two
//! ends (nor a blend of them, for gradients), and that continues deep into the image, as an
//! object's body does and a patterned background's cells do not.

use super::gmm::Rgb;

/// Share of each side's ends taken as that side's background sample.
const END: f32 = 0.1;
/// Least colour distance (RGB in 0..1) that counts as "other than the background".
const MIN_DISTANCE: f32 = 0.08;
/// A side is crossed when a stretch this long (share of the side) is other than its ends…
const MIN_RUN: f32 = 0.15;
/// …and the colour of the stretch's middle stays on the line inward for this share of the
/// frame's extent perpendicular to the side.
const DEPTH: f32 = 0.12;

fn dist(a: Rgb, b: Rgb) -> f32 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

fn lerp(a: Rgb, b: Rgb, t: f32) -> Rgb {
    [
        a[0] + (b[0] - a[0]) * t,
        a[1] + (b[1] - a[1]) * t,
        a[2] + (b[2] - a[2]) * t,
    ]
}

fn mean(v: &[Rgb]) -> Rgb {
    let n = v.len().max(1) as f32;
    let s = v
        .iter()
        .fold([0.0; 3], |s, c| [s[0] + c[0], s[1] + c[1], s[2] + c[2]]);
    s.map(|x| x / n)
}

/// The sides (top, bottom, left, right) the object appears to cross, from the photo's colours
/// (`w`×`h`, row-major).
pub(super) fn crossed_sides(colors: &[Rgb], w: usize, h: usize) -> [bool; 4] {
    let depth = (w.min(h) / 40).max(2);
    let mut out = [false; 4];
    for (s, crossed) in out.iter_mut().enumerate() {
        // The side as a profile along it: position t → pixel index at depth d.
        let (len, inward) = if s < 2 { (w, h) } else { (h, w) };
        let at = |t: usize, d: usize| -> usize {
            match s {
                0 => d * w + t,
                1 => (h - 1 - d) * w + t,
                2 => t * w + d,
                _ => t * w + (w - 1 - d),
            }
        };
        if len < 20 {
            continue;
        }
        let profile: Vec<Rgb> = (0..len)
            .map(|t| mean(&(0..depth).map(|d| colors[at(t, d)]).collect::<Vec<_>>()))
            .collect();
        let e = ((len as f32 * END) as usize).max(2);
        let (m0, m1) = (mean(&profile[..e]), mean(&profile[len - e..]));
        let noise = profile[..e]
            .iter()
            .map(|c| dist(*c, m0))
            .chain(profile[len - e..].iter().map(|c| dist(*c, m1)))
            .fold(0.0f32, f32::max);
        let thr = (2.0 * noise).max(MIN_DISTANCE);
        let (c0, c1) = (e as f32 / 2.0, len as f32 - e as f32 / 2.0);
        let other = |c: Rgb, t: usize| {
            let k = ((t as f32 - c0) / (c1 - c0)).clamp(0.0, 1.0);
            dist(c, m0) > thr && dist(c, m1) > thr && dist(c, lerp(m0, m1, k)) > thr
        };
        // Background that changes along the side (sky above the horizon, then the ground;
        // a gradient) is followed from each end for as long as it changes smoothly: what is
        // reached without a jump is background, whatever its colour. Without this, three of
        // the building benchmark's ten photos on a gradient (sky, then grass) said the
        // building ran off the left and right edges. Thin lines of up to 2 % are stepped over.
        let gap = (len / 50).max(1);
        let reached = smooth_from_ends(&profile, thr, gap);
        // The longest stretch of "other" positions, gaps of up to 2 % bridged.
        let (mut best, mut start, mut last) = ((0, 0), None::<usize>, 0);
        for (t, &c) in profile.iter().enumerate().take(len - e).skip(e) {
            if !reached[t] && other(c, t) {
                let s0 = match start {
                    Some(s0) if t - last <= gap => s0,
                    _ => t,
                };
                start = Some(s0);
                last = t;
                if last + 1 - s0 > best.1 - best.0 {
                    best = (s0, last + 1);
                }
            }
        }
        if ((best.1 - best.0) as f32) < MIN_RUN * len as f32 {
            continue;
        }
        // Inward from the stretch's middle: the pixels must stay unlike the side's background
        // for DEPTH of the frame.
        let mid = (best.0 + best.1) / 2;
        let reach = ((inward as f32 * DEPTH) as usize).min(inward);
        let unlike = (0..reach)
            .filter(|&d| other(colors[at(mid, d)], mid))
            .count();
        *crossed = unlike as f32 >= 0.8 * reach as f32;
    }
    out
}

/// Samples along each side's profile this many at a time make the running mean that the
/// next sample is compared with in [`smooth_from_ends`].
const RUNNING: usize = 5;

/// The positions of `profile` reached from either end by steps of less than `thr` from the
/// running mean of the last [`RUNNING`] samples reached: a background's slow change (a
/// gradient, the ground below a horizon) is followed, an object's edge stops the walk. A
/// thin line across the background (a seam between a table's planks) is stepped over: the
/// walk goes on when the background's colour is back within `gap` samples.
fn smooth_from_ends(profile: &[Rgb], thr: f32, gap: usize) -> Vec<bool> {
    let len = profile.len();
    let mut reached = vec![false; len];
    for forward in [true, false] {
        let at = |k: usize| if forward { k } else { len - 1 - k };
        let mut recent: Vec<Rgb> = Vec::with_capacity(RUNNING);
        let mut k = 0;
        while k < len {
            if !recent.is_empty() {
                let m = mean(&recent);
                // The next sample within the gap that is the background's colour again.
                let Some(back) =
                    (k..(k + gap + 1).min(len)).find(|&j| dist(profile[at(j)], m) < thr)
                else {
                    break;
                };
                for j in k..back {
                    reached[at(j)] = true;
                }
                k = back;
            }
            reached[at(k)] = true;
            if recent.len() == RUNNING {
                recent.remove(0);
            }
            recent.push(profile[at(k)]);
            k += 1;
        }
    }
    reached
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(w: usize, h: usize, f: impl Fn(usize, usize) -> Rgb) -> Vec<Rgb> {
        (0..w * h).map(|i| f(i % w, i / w)).collect()
    }

    #[test]
    fn a_framed_object_crosses_nothing() {
        let img = image(200, 150, |x, y| {
            if (60..140).contains(&x) && (40..110).contains(&y) {
                [0.8, 0.2, 0.1]
            } else {
                [0.85, 0.85, 0.8]
            }
        });
        assert_eq!(crossed_sides(&img, 200, 150), [false; 4]);
    }

    #[test]
    fn a_gradient_background_crosses_nothing() {
        let img = image(200, 150, |x, y| {
            let t = y as f32 / 150.0 * 0.6 + x as f32 / 200.0 * 0.2;
            [0.9 - 0.5 * t, 0.9 - 0.45 * t, 0.95 - 0.3 * t]
        });
        assert_eq!(crossed_sides(&img, 200, 150), [false; 4]);
    }

    #[test]
    fn a_horizon_crosses_nothing() {
        // Sky lightening towards the horizon, then grass darkening towards the camera, with a
        // little noise: the left and right sides go from one background to another.
        let img = image(200, 150, |x, y| {
            let n = ((x * 7919 + y * 104_729) % 13) as f32 / 13.0 * 0.03;
            if y < 60 {
                let t = y as f32 / 60.0;
                [0.55 + 0.2 * t + n, 0.65 + 0.15 * t + n, 0.9 + n]
            } else {
                let t = (y - 60) as f32 / 90.0;
                [0.45 - 0.1 * t + n, 0.55 - 0.1 * t + n, 0.38 - 0.08 * t + n]
            }
        });
        assert_eq!(crossed_sides(&img, 200, 150), [false; 4]);
    }

    #[test]
    fn plank_seams_cross_nothing() {
        // A table of planks with dark seams every 15 rows (none at the ends), lit by a lamp so
        // its middle rows are brighter than either end of a side: each side's walk must step
        // over the seams to follow the light's smooth change, or the lit middle is "an object".
        let img = image(200, 150, |x, y| {
            let d = (y as f32 - 75.0) / 35.0;
            let lit = 0.3 * (-d * d).exp() - 0.02 * x as f32 / 200.0;
            if (15..135).contains(&y) && y % 15 < 2 {
                [0.25, 0.15, 0.08]
            } else {
                [0.45 + lit, 0.3 + lit, 0.15 + 0.6 * lit]
            }
        });
        assert_eq!(crossed_sides(&img, 200, 150), [false; 4]);
    }

    #[test]
    fn an_object_cut_by_the_frame_crosses_those_sides() {
        let bg = [0.85, 0.85, 0.8];
        let cut = image(200, 150, |x, y| {
            if x > 150 && (30..120).contains(&y) {
                [0.2, 0.3, 0.7]
            } else {
                bg
            }
        });
        assert_eq!(crossed_sides(&cut, 200, 150), [false, false, false, true]);
        let tall = image(200, 150, |x, _| {
            if (40..160).contains(&x) {
                [0.2, 0.3, 0.7]
            } else {
                bg
            }
        });
        assert_eq!(crossed_sides(&tall, 200, 150), [true, true, false, false]);
    }
}
