//! Binary morphology on pixel masks: connected components, holes, and the uncertainty band.
//!
//! Masks here are `&[bool]` row-major with explicit width and height; the segmentation code
//! turns them into [`crate::mask::Mask`] at the end.

use std::collections::VecDeque;

/// Connected components of the `true` pixels (8-connected if `eight`, else 4-connected).
/// Returns a label per pixel (`u32::MAX` for `false` pixels) and each component's pixels.
pub fn components(mask: &[bool], w: usize, h: usize, eight: bool) -> (Vec<u32>, Vec<Vec<usize>>) {
    let mut label = vec![u32::MAX; mask.len()];
    let mut comps: Vec<Vec<usize>> = Vec::new();
    let mut queue = VecDeque::new();
    for start in 0..mask.len() {
        if !mask[start] || label[start] != u32::MAX {
            continue;
        }
        let id = comps.len() as u32;
        let mut pixels = Vec::new();
        label[start] = id;
        queue.push_back(start);
        while let Some(i) = queue.pop_front() {
            pixels.push(i);
            let (x, y) = ((i % w) as isize, (i / w) as isize);
            for dy in -1..=1isize {
                for dx in -1..=1isize {
                    if (dx == 0 && dy == 0) || (!eight && dx != 0 && dy != 0) {
                        continue;
                    }
                    let (nx, ny) = (x + dx, y + dy);
                    if nx < 0 || ny < 0 || nx >= w as isize || ny >= h as isize {
                        continue;
                    }
                    let j = ny as usize * w + nx as usize;
                    if mask[j] && label[j] == u32::MAX {
                        label[j] = id;
                        queue.push_back(j);
                    }
                }
            }
        }
        comps.push(pixels);
    }
    (label, comps)
}

/// Keeps the largest 8-connected component plus every component containing a pixel for which
/// `keep` is true (the user's object scribbles).
pub fn largest_component(
    mask: &[bool],
    w: usize,
    h: usize,
    keep: &dyn Fn(usize) -> bool,
) -> Vec<bool> {
    let (_, comps) = components(mask, w, h, true);
    let mut out = vec![false; mask.len()];
    let largest = comps
        .iter()
        .enumerate()
        .max_by_key(|(_, c)| c.len())
        .map(|(k, _)| k);
    for (k, c) in comps.iter().enumerate() {
        if Some(k) == largest || c.iter().any(|&i| keep(i)) {
            for &i in c {
                out[i] = true;
            }
        }
    }
    out
}

/// Holes: 4-connected background components that do not touch the image border.
pub fn holes(mask: &[bool], w: usize, h: usize) -> Vec<Vec<usize>> {
    let inv: Vec<bool> = mask.iter().map(|&m| !m).collect();
    let (_, comps) = components(&inv, w, h, false);
    comps
        .into_iter()
        .filter(|c| {
            !c.iter().any(|&i| {
                let (x, y) = (i % w, i / w);
                x == 0 || y == 0 || x + 1 == w || y + 1 == h
            })
        })
        .collect()
}

/// Pixels within Chebyshev distance `r` of the mask's boundary (on either side), `r ≥ 1`.
pub fn boundary_band(mask: &[bool], w: usize, h: usize, r: usize) -> Vec<bool> {
    let mut edge = vec![false; mask.len()];
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            let differs =
                (x + 1 < w && mask[i + 1] != mask[i]) || (y + 1 < h && mask[i + w] != mask[i]);
            if differs {
                edge[i] = true;
                if x + 1 < w && mask[i + 1] != mask[i] {
                    edge[i + 1] = true;
                }
                if y + 1 < h && mask[i + w] != mask[i] {
                    edge[i + w] = true;
                }
            }
        }
    }
    dilate(&edge, w, h, r.saturating_sub(1))
}

/// Square dilation of radius `r` (separable running maximum).
pub fn dilate(mask: &[bool], w: usize, h: usize, r: usize) -> Vec<bool> {
    if r == 0 {
        return mask.to_vec();
    }
    let mut tmp = vec![false; mask.len()];
    for y in 0..h {
        for x in 0..w {
            let lo = x.saturating_sub(r);
            let hi = (x + r).min(w - 1);
            tmp[y * w + x] = (lo..=hi).any(|k| mask[y * w + k]);
        }
    }
    let mut out = vec![false; mask.len()];
    for y in 0..h {
        let lo = y.saturating_sub(r);
        let hi = (y + r).min(h - 1);
        for x in 0..w {
            out[y * w + x] = (lo..=hi).any(|k| tmp[k * w + x]);
        }
    }
    out
}

/// Square erosion of radius `r`: the pixels whose whole `(2r+1)²` square (clipped to the
/// image) is set.
pub fn erode(mask: &[bool], w: usize, h: usize, r: usize) -> Vec<bool> {
    let inv: Vec<bool> = mask.iter().map(|&m| !m).collect();
    dilate(&inv, w, h, r).iter().map(|&m| !m).collect()
}

/// Square opening of radius `r` (erosion, then dilation): removes specks and strands
/// narrower than `2r + 1` pixels and keeps the rest as it was, up to its corners.
pub fn open(mask: &[bool], w: usize, h: usize, r: usize) -> Vec<bool> {
    dilate(&erode(mask, w, h, r), w, h, r)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(rows: &[&str]) -> (Vec<bool>, usize, usize) {
        let w = rows[0].len();
        let m = rows
            .iter()
            .flat_map(|r| r.bytes().map(|b| b == b'#'))
            .collect();
        (m, w, rows.len())
    }

    #[test]
    fn ring_has_one_hole_and_largest_component_drops_specks() {
        let (m, w, h) = parse(&["........", ".####...", ".#..#..#", ".####...", "........"]);
        let hs = holes(&m, w, h);
        assert_eq!(hs.len(), 1);
        assert_eq!(hs[0].len(), 2);
        let l = largest_component(&m, w, h, &|_| false);
        assert!(!l[2 * w + 7] && l[w + 1]);
        let l = largest_component(&m, w, h, &|i| i == 2 * w + 7);
        assert!(l[2 * w + 7]);
        let band = boundary_band(&m, w, h, 1);
        assert!(band[w + 1] && band[w] && !band[7]);
    }
}
