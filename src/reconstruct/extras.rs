//! Small things in a mask that are not the object (issue 16): a spoon leaning out of a cup, a
//! tea bag's string and tag hanging over the rim. No generator can explain them, and left in
//! the mask they pull the fit (a handle stretched towards the spoon, a body widened to the
//! tag). [`thin_extras`] finds them from the mask's shape alone, before the fit, and the fit
//! treats them as don't care: ignored, neither object nor background.
//!
//! What counts as an extra: the mask is opened (eroded, then dilated) by a radius `r` of
//! [`OPEN_RADIUS`] × the object's size, which keeps the body and removes everything thinner
//! than `2r`. Of what was removed, a connected piece is an extra when it is
//! - a *spur*: it touches the body in one place only (a handle's loop touches it in two and is
//!   kept, whatever its thickness);
//! - *long*: it reaches further than [`MIN_REACH`] × the object's size from the body (a rim's
//!   lip or a handle's thin stretch stays within a few pixels of the body and is kept);
//! - *small*: under [`MAX_EXTRA`] of the mask's area (a large thing on a thin neck is more
//!   likely part of the object, or a second object that the user should remove).
//!
//! A piece of the mask that does not touch the body at all and is small is an extra too.

use crate::mask::Mask;
use crate::segment::morph;

/// Opening radius, as a share of the longer side of the object's bounding box.
pub const OPEN_RADIUS: f32 = 0.03;
/// How far from the body a spur must reach to be an extra, as a share of the object's size.
pub const MIN_REACH: f32 = 0.08;
/// Largest extra, as a share of the mask's object area.
pub const MAX_EXTRA: f32 = 0.15;

/// Chamfer (3-4) distance, in pixels, from every pixel to the nearest pixel of `set` (`f32::MAX`
/// when `set` is empty). Two passes over the image.
fn distance_to(set: &[bool], w: usize, h: usize) -> Vec<f32> {
    const FAR: u32 = u32::MAX / 2;
    let mut d: Vec<u32> = set.iter().map(|&s| if s { 0 } else { FAR }).collect();
    let at = |x: usize, y: usize| y * w + x;
    for y in 0..h {
        for x in 0..w {
            let mut v = d[at(x, y)];
            if x > 0 {
                v = v.min(d[at(x - 1, y)] + 3);
            }
            if y > 0 {
                v = v.min(d[at(x, y - 1)] + 3);
                if x > 0 {
                    v = v.min(d[at(x - 1, y - 1)] + 4);
                }
                if x + 1 < w {
                    v = v.min(d[at(x + 1, y - 1)] + 4);
                }
            }
            d[at(x, y)] = v;
        }
    }
    for y in (0..h).rev() {
        for x in (0..w).rev() {
            let mut v = d[at(x, y)];
            if x + 1 < w {
                v = v.min(d[at(x + 1, y)] + 3);
            }
            if y + 1 < h {
                v = v.min(d[at(x, y + 1)] + 3);
                if x + 1 < w {
                    v = v.min(d[at(x + 1, y + 1)] + 4);
                }
                if x > 0 {
                    v = v.min(d[at(x - 1, y + 1)] + 4);
                }
            }
            d[at(x, y)] = v;
        }
    }
    d.into_iter()
        .map(|v| if v >= FAR { f32::MAX } else { v as f32 / 3.0 })
        .collect()
}

/// The pixels of the object `obj` (`w × h`, row-major) that are small extras, not the object
/// (see the module doc); all `false` when there are none.
pub fn thin_extras(obj: &[bool], w: usize, h: usize) -> Vec<bool> {
    let mut extra = vec![false; obj.len()];
    let area = obj.iter().filter(|&&o| o).count();
    if area == 0 || obj.len() != w * h {
        return extra;
    }
    let (mut x0, mut y0, mut x1, mut y1) = (w, h, 0, 0);
    for (i, _) in obj.iter().enumerate().filter(|&(_, &o)| o) {
        let (x, y) = (i % w, i / w);
        (x0, y0, x1, y1) = (x0.min(x), y0.min(y), x1.max(x), y1.max(y));
    }
    let size = (x1 - x0 + 1).max(y1 - y0 + 1) as f32;
    let r = (OPEN_RADIUS * size).max(1.5);
    // Opening: the pixels deeper than r inside the object, grown back by r.
    let background: Vec<bool> = obj.iter().map(|&o| !o).collect();
    let depth = distance_to(&background, w, h);
    let core: Vec<bool> = depth.iter().map(|&d| d > r).collect();
    let from_core = distance_to(&core, w, h);
    let opened: Vec<bool> = from_core
        .iter()
        .zip(obj)
        .map(|(&d, &o)| o && d <= r)
        .collect();
    // The body: the opened mask's largest piece.
    let (_, pieces) = morph::components(&opened, w, h, true);
    let Some(body_pixels) = pieces.iter().max_by_key(|p| p.len()) else {
        return extra;
    };
    let mut body = vec![false; obj.len()];
    for &i in body_pixels {
        body[i] = true;
    }
    let from_body = distance_to(&body, w, h);
    let rest: Vec<bool> = obj.iter().zip(&body).map(|(&o, &b)| o && !b).collect();
    let (_, parts) = morph::components(&rest, w, h, true);
    let touches_body = |i: usize| {
        let (x, y) = ((i % w) as isize, (i / w) as isize);
        [(-1, 0), (1, 0), (0, -1), (0, 1)].iter().any(|&(dx, dy)| {
            let (nx, ny) = (x + dx, y + dy);
            nx >= 0
                && ny >= 0
                && (nx as usize) < w
                && (ny as usize) < h
                && body[ny as usize * w + nx as usize]
        })
    };
    for part in &parts {
        if part.len() as f32 > MAX_EXTRA * area as f32 {
            continue;
        }
        let mut contact = vec![false; obj.len()];
        let mut touching = 0usize;
        for &i in part {
            if touches_body(i) {
                contact[i] = true;
                touching += 1;
            }
        }
        let is_extra = if touching == 0 {
            true
        } else {
            let (_, places) = morph::components(&contact, w, h, true);
            let reach = part.iter().map(|&i| from_body[i]).fold(0.0f32, f32::max);
            places.len() == 1 && reach > MIN_REACH * size
        };
        if is_extra {
            for &i in part {
                extra[i] = true;
            }
        }
    }
    extra
}

/// `mask` with its small extras ([`thin_extras`]) made don't care; the mask itself when it has
/// none.
pub fn without_extras(mask: &Mask) -> Mask {
    let (w, h) = (mask.width() as usize, mask.height() as usize);
    let obj: Vec<bool> = mask.values().iter().map(|&v| v >= 0.5).collect();
    let extra = thin_extras(&obj, w, h);
    if !extra.iter().any(|&e| e) {
        return mask.clone();
    }
    let values = mask
        .values()
        .iter()
        .zip(&extra)
        .map(|(&v, &e)| if e { Mask::DONT_CARE } else { v })
        .collect();
    Mask::new(mask.width(), mask.height(), values).unwrap_or_else(|_| mask.clone())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `w × h` mask from a predicate.
    fn shape(w: usize, h: usize, f: impl Fn(f32, f32) -> bool) -> Vec<bool> {
        (0..w * h)
            .map(|i| f((i % w) as f32 + 0.5, (i / w) as f32 + 0.5))
            .collect()
    }

    fn cup_body(x: f32, y: f32) -> bool {
        (40.0..110.0).contains(&x) && (40.0..120.0).contains(&y)
    }

    #[test]
    fn a_spoon_is_an_extra_and_the_body_is_not() {
        let (w, h) = (160, 160);
        // A 3 px bar from inside the rim up and out, 40 px long.
        let spoon =
            |x: f32, y: f32| (x - 90.0 - (50.0 - y) * 0.5).abs() < 1.5 && y > 10.0 && y < 50.0;
        let obj = shape(w, h, |x, y| cup_body(x, y) || spoon(x, y));
        let extra = thin_extras(&obj, w, h);
        assert!(extra[20 * w + 105], "the spoon's far end");
        assert!(!extra[80 * w + 75], "the body");
        let n = extra.iter().filter(|&&e| e).count();
        assert!((60..200).contains(&n), "{n} extra pixels");
    }

    #[test]
    fn a_handle_loop_is_kept() {
        let (w, h) = (160, 160);
        // A ring 4 px thick on the right side, touching the body at two places.
        let handle = |x: f32, y: f32| {
            let d = ((x - 110.0).powi(2) + (y - 80.0).powi(2)).sqrt();
            x > 108.0 && (18.0..22.0).contains(&d)
        };
        let obj = shape(w, h, |x, y| cup_body(x, y) || handle(x, y));
        let extra = thin_extras(&obj, w, h);
        assert!(
            !extra.iter().any(|&e| e),
            "nothing of the handle is an extra"
        );
    }

    #[test]
    fn a_short_lip_and_a_plain_shape_are_kept() {
        let (w, h) = (160, 160);
        // A 2 px lip sticking 3 px out of the rim.
        let lip = |x: f32, y: f32| (108.0..114.0).contains(&x) && (40.0..42.0).contains(&y);
        let obj = shape(w, h, |x, y| cup_body(x, y) || lip(x, y));
        assert!(!thin_extras(&obj, w, h).iter().any(|&e| e));
        let disc = shape(w, h, |x, y| (x - 80.0).powi(2) + (y - 80.0).powi(2) < 900.0);
        assert!(!thin_extras(&disc, w, h).iter().any(|&e| e));
    }

    #[test]
    fn a_small_separate_piece_is_an_extra() {
        let (w, h) = (160, 160);
        let tag = |x: f32, y: f32| (10.0..20.0).contains(&x) && (60.0..70.0).contains(&y);
        let obj = shape(w, h, |x, y| cup_body(x, y) || tag(x, y));
        let extra = thin_extras(&obj, w, h);
        assert!(extra[65 * w + 15] && !extra[80 * w + 75]);
    }
}
