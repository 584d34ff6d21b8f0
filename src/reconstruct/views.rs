//! Cameras of the fit: how a view is parameterised, the field of view from a photo's focal
//! length, mask statistics and the initial camera guesses made from them.
//!
//! # Parameterisation
//! Every view has a fixed camera pose: at [`CAMERA_DISTANCE`] on the +Z axis, looking at the
//! origin, Y up (the reference implementation's look-at camera, notes "Renderer, loss,
//! camera"). What is fitted per view is the object transform of the renderer's
//! [`ViewParams`], through values that mean what a photo means: `yaw` turns the object about
//! its own vertical axis, `pitch` is the camera's elevation (positive shows the top), `roll`
//! the camera's tilt, i.e. `R = R_z(roll)·R_x(pitch)·R_y(yaw)`, converted to the renderer's
//! Euler angles (`R_y·R_x·R_z`, an order in which pitch with a non-zero yaw leans the object's
//! axis sideways); then the translation `tx`, `ty` across the image and the logarithm of the
//! object scale `ls` (scale = `exp(ls)`), plus the vertical field of view when
//! [`FitConfig::fit_fov`](super::FitConfig::fit_fov) asks for it. The principal point stays at
//! the image centre (glTF cameras have none).
//!
//! # The scale/distance ambiguity
//! One photo cannot tell a big object far away from a small one nearby. procfit fixes the
//! **distance**: the object's depth offset `tz` is always 0, so the camera is always
//! [`CAMERA_DISTANCE`] from the object's origin, and the apparent size is fitted through the
//! object scale. The generator's own size parameters and the scale can still trade against
//! each other (a taller mug scaled down looks the same); that direction is flat for the loss,
//! the optimiser is free to sit anywhere on it, and the result is reported in the generator's
//! units (a mug about 0.9 tall) with the cameras placed to match — the only consistent answer
//! without a metric cue. Each view has its own scale, since photos are taken from different
//! distances.
//!
//! # Initial guesses
//! From each mask: the bounding box and centroid of the object pixels. For each seed shape and
//! each (yaw, pitch) candidate, the scale and translation are solved so that the seed's
//! projected bounding box matches the mask's (a few fixed-point iterations, exact up to
//! perspective). Yaw candidates put the generator's +X side (a mug's handle) on the side where
//! the mask's centroid says the extra thin mass is: a handle stretches the bounding box more
//! than it moves the centroid.

use super::FitError;
use crate::camera::{CameraPose, View, ViewParams};
use crate::mask::Mask;
use crate::optim::Var;
use glam::{DMat3, DVec2, DVec3, Vec3};

/// Distance from the camera to the object's origin, in generator units (the paper's evaluation
/// distance).
pub const CAMERA_DISTANCE: f64 = 3.0;

/// Vertical field of view used when a photo says nothing: that of a 50 mm "normal" lens on
/// 35 mm film in landscape (36 × 24 mm frame), 2·atan(12/50).
pub const DEFAULT_FOV_Y: f64 = 0.471_089_961_441_726_7;

/// Fitted values per view, in this order (plus `fov_y` when fitted).
pub const VIEW_VARS: [&str; 6] = ["yaw", "pitch", "roll", "tx", "ty", "log_scale"];

/// Where each of a view's fitted values sits among the view's values in the optimisation
/// vector ([`VIEW_VARS`] order, the field of view last when it is fitted); see
/// [`Layout::slot`](super::Layout::slot).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ViewSlot {
    /// [`ViewVars::yaw`].
    Yaw = 0,
    /// [`ViewVars::pitch`].
    Pitch = 1,
    /// [`ViewVars::roll`].
    Roll = 2,
    /// [`ViewVars::tx`].
    Tx = 3,
    /// [`ViewVars::ty`].
    Ty = 4,
    /// [`ViewVars::log_scale`].
    LogScale = 5,
    /// [`ViewVars::fov_y`] (only when the field of view is fitted).
    FovY = 6,
}

impl ViewSlot {
    /// The slots in vector order.
    pub const ALL: [ViewSlot; 7] = [
        ViewSlot::Yaw,
        ViewSlot::Pitch,
        ViewSlot::Roll,
        ViewSlot::Tx,
        ViewSlot::Ty,
        ViewSlot::LogScale,
        ViewSlot::FovY,
    ];

    /// Index among the view's values.
    pub fn index(self) -> usize {
        self as usize
    }

    /// Values per view: 6, or 7 with the field of view.
    pub fn count(fit_fov: bool) -> usize {
        if fit_fov { 7 } else { 6 }
    }
}

/// The vertical field of view of a photo `width × height` taken at a 35 mm-equivalent focal
/// length `focal_35mm` (EXIF `FocalLengthIn35mmFilm`): the equivalent focal length refers to the
/// 43.27 mm diagonal of a 36 × 24 mm frame, so the diagonal field of view is
/// `2·atan(21.63/f)` and the vertical one follows from the image's aspect ratio. `None` when an
/// argument is not positive and finite.
pub fn fov_from_focal_35mm(focal_35mm: f64, width: u32, height: u32) -> Option<f64> {
    if !(focal_35mm.is_finite() && focal_35mm > 0.0) || width == 0 || height == 0 {
        return None;
    }
    let half_diag = 0.5 * (36.0f64.hypot(24.0));
    let tan_half_diag = half_diag / focal_35mm;
    let (w, h) = (f64::from(width), f64::from(height));
    Some(2.0 * (tan_half_diag * h / w.hypot(h)).atan())
}

/// `FocalLengthIn35mmFilm` (EXIF tag 0xA405) from a raw EXIF block (a TIFF header and IFDs, as
/// image decoders return it; a leading `Exif\0\0` is skipped). `None` when the block is
/// malformed, has no such tag, or the value is 0 (unknown). Every offset is bounds-checked.
pub fn focal_35mm_from_exif(exif: &[u8]) -> Option<f64> {
    let t = exif.strip_prefix(b"Exif\0\0").unwrap_or(exif);
    let le = match t.get(..2)? {
        b"II" => true,
        b"MM" => false,
        _ => return None,
    };
    let u16_at = |o: usize| -> Option<u16> {
        let b: [u8; 2] = t.get(o..o + 2)?.try_into().ok()?;
        Some(if le {
            u16::from_le_bytes(b)
        } else {
            u16::from_be_bytes(b)
        })
    };
    let u32_at = |o: usize| -> Option<u32> {
        let b: [u8; 4] = t.get(o..o + 4)?.try_into().ok()?;
        Some(if le {
            u32::from_le_bytes(b)
        } else {
            u32::from_be_bytes(b)
        })
    };
    // Finds `tag` in the IFD at `ifd` and returns the offset of its 12-byte entry.
    let find = |ifd: usize, tag: u16| -> Option<usize> {
        let n = usize::from(u16_at(ifd)?);
        (0..n.min(512))
            .map(|i| ifd + 2 + 12 * i)
            .find(|&e| u16_at(e) == Some(tag))
    };
    let ifd0 = u32_at(4)? as usize;
    let exif_ifd = u32_at(find(ifd0, 0x8769)? + 8)? as usize;
    let entry = find(exif_ifd, 0xA405)?;
    // Type SHORT (3), count 1: the value sits in the first two bytes of the value field.
    let value = match u16_at(entry + 2)? {
        3 => f64::from(u16_at(entry + 8)?),
        4 => f64::from(u32_at(entry + 8)?),
        _ => return None,
    };
    (value > 0.0).then_some(value)
}

/// `FocalLengthIn35mmFilm` from an image file's bytes (a JPEG's APP1 block, or whatever EXIF
/// the `image` crate finds in a PNG or WebP). `None` when the file is not a readable image or
/// carries no such tag. Only the headers are read, not the pixels. The page calls this on the
/// original file, because its downscaled bitmap has lost the EXIF.
pub fn focal_35mm_from_file(bytes: &[u8]) -> Option<f64> {
    use image::ImageDecoder;
    let mut decoder = image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .ok()?
        .into_decoder()
        .ok()?;
    let exif = decoder.exif_metadata().ok()??;
    focal_35mm_from_exif(&exif)
}

/// The fixed camera pose of every view.
pub fn camera_pose() -> CameraPose {
    // Cannot fail: eye and target differ and Y is not along the viewing direction.
    CameraPose::look_at(DVec3::new(0.0, 0.0, CAMERA_DISTANCE), DVec3::ZERO, DVec3::Y).unwrap_or(
        CameraPose {
            rotation: glam::DMat3::IDENTITY,
            position: DVec3::new(0.0, 0.0, CAMERA_DISTANCE),
        },
    )
}

/// One view's fitted values; also the camera JSON of `procfit render` (missing fields take
/// their defaults: no rotation, centred, scale 1, [`DEFAULT_FOV_Y`]).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct ViewVars {
    /// Object spin about its own vertical axis (radians).
    pub yaw: f64,
    /// Camera elevation (radians); positive shows the top of the object.
    pub pitch: f64,
    /// Camera tilt about the viewing axis (radians).
    pub roll: f64,
    /// Object translation along X.
    pub tx: f64,
    /// Object translation along Y.
    pub ty: f64,
    /// Natural logarithm of the object scale.
    pub log_scale: f64,
    /// Vertical field of view (radians).
    pub fov_y: f64,
}

impl Default for ViewVars {
    fn default() -> Self {
        ViewVars {
            yaw: 0.0,
            pitch: 0.0,
            roll: 0.0,
            tx: 0.0,
            ty: 0.0,
            log_scale: 0.0,
            fov_y: DEFAULT_FOV_Y,
        }
    }
}

/// The renderer's Euler angles `(yaw, pitch, roll)` with `R_y·R_x·R_z = R` for
/// `R = R_z(roll)·R_x(pitch)·R_y(yaw)` (camera tilt, elevation, object spin).
pub fn renderer_angles(yaw: f64, pitch: f64, roll: f64) -> [f64; 3] {
    let r =
        DMat3::from_rotation_z(roll) * DMat3::from_rotation_x(pitch) * DMat3::from_rotation_y(yaw);
    // For R = R_y(a)·R_x(b)·R_z(c): row 1 is (cos b·sin c, cos b·cos c, −sin b) and column 2
    // is (sin a·cos b, −sin b, cos a·cos b). glam matrices are column-major: r.col(j)[i] = R_ij.
    let at = |i: usize, j: usize| r.col(j)[i];
    let b = (-at(1, 2)).clamp(-1.0, 1.0).asin();
    let c = at(1, 0).atan2(at(1, 1));
    let a = at(0, 2).atan2(at(2, 2));
    [a, b, c]
}

/// `d renderer_angles / d (yaw, pitch, roll)` by central differences: `j[k][m]` is the
/// derivative of renderer angle `k` by value `m`. The conversion is smooth away from an
/// elevation of ±90°, which the pitch range keeps clear of.
pub fn renderer_angles_jacobian(yaw: f64, pitch: f64, roll: f64) -> [[f64; 3]; 3] {
    const H: f64 = 1e-6;
    let mut j = [[0.0; 3]; 3];
    for m in 0..3 {
        let mut lo = [yaw, pitch, roll];
        let mut hi = lo;
        lo[m] -= H;
        hi[m] += H;
        let (a, b) = (
            renderer_angles(lo[0], lo[1], lo[2]),
            renderer_angles(hi[0], hi[1], hi[2]),
        );
        for k in 0..3 {
            // Angles can wrap by 2π between the two samples.
            let mut d = b[k] - a[k];
            if d > std::f64::consts::PI {
                d -= std::f64::consts::TAU;
            } else if d < -std::f64::consts::PI {
                d += std::f64::consts::TAU;
            }
            j[k][m] = d / (2.0 * H);
        }
    }
    j
}

impl ViewVars {
    /// These angles and field of view, with the scale and shift that show the box `lo..hi` (in
    /// the object's frame, with an extent) centred in the image, its largest side `fill` times
    /// the image's half height.
    pub fn framing(self, lo: Vec3, hi: Vec3, fill: f64) -> ViewVars {
        let size = f64::from((hi - lo).max_element());
        let half_h = CAMERA_DISTANCE * (0.5 * self.fov_y).tan();
        let scale = fill * half_h / size;
        let c = self.params().rotation_and_derivatives()[0] * (0.5 * (lo + hi)).as_dvec3() * scale;
        ViewVars {
            tx: -c.x,
            ty: -c.y,
            log_scale: scale.ln(),
            ..self
        }
    }

    /// The renderer's parameters for these values.
    pub fn params(&self) -> ViewParams {
        let [yaw, pitch, roll] = renderer_angles(self.yaw, self.pitch, self.roll);
        ViewParams {
            yaw,
            pitch,
            roll,
            translation: DVec3::new(self.tx, self.ty, 0.0),
            scale: self.log_scale.exp(),
            fov_y: self.fov_y,
            principal: DVec2::ZERO,
        }
    }

    /// The renderer's view at `width × height`.
    pub fn view(&self, width: u32, height: u32) -> View {
        View {
            width,
            height,
            pose: camera_pose(),
            params: self.params(),
        }
    }

    /// The value in `slot`.
    pub fn get(&self, slot: ViewSlot) -> f64 {
        match slot {
            ViewSlot::Yaw => self.yaw,
            ViewSlot::Pitch => self.pitch,
            ViewSlot::Roll => self.roll,
            ViewSlot::Tx => self.tx,
            ViewSlot::Ty => self.ty,
            ViewSlot::LogScale => self.log_scale,
            ViewSlot::FovY => self.fov_y,
        }
    }

    /// Writes the fitted values into `out` (6 or 7 entries, see [`ViewSlot`]).
    pub fn write(&self, out: &mut [f64]) {
        for (o, slot) in out.iter_mut().zip(ViewSlot::ALL) {
            *o = self.get(slot);
        }
    }

    /// Reads fitted values from `v` (6 entries, or 7 with the field of view); `fov_y` is used
    /// when `v` has only 6.
    pub fn read(v: &[f64], fov_y: f64) -> ViewVars {
        let at = |s: ViewSlot, d: f64| v.get(s.index()).copied().unwrap_or(d);
        ViewVars {
            yaw: at(ViewSlot::Yaw, 0.0),
            pitch: at(ViewSlot::Pitch, 0.0),
            roll: at(ViewSlot::Roll, 0.0),
            tx: at(ViewSlot::Tx, 0.0),
            ty: at(ViewSlot::Ty, 0.0),
            log_scale: at(ViewSlot::LogScale, 0.0),
            fov_y: at(ViewSlot::FovY, fov_y),
        }
    }
}

/// What the fit needs to know about one mask.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MaskStats {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Bounding box of the object pixels (coverage ≥ 0.5): `min` and `max` pixel edges.
    pub bbox_min: DVec2,
    /// See `bbox_min`.
    pub bbox_max: DVec2,
    /// Coverage-weighted centroid of the object, pixels.
    pub centroid: DVec2,
    /// Object fraction of the pixels that count.
    pub fill: f64,
}

/// Smallest image side the fit accepts.
pub const MIN_SIDE: u32 = 8;

/// Why a mask has no silhouette to fit ([`check_mask`]); its `Display` follows "mask N" or
/// "this mask image".
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum MaskProblem {
    /// Smaller than [`MIN_SIDE`] on a side: width, height.
    TooSmall(u32, u32),
    /// No object pixel.
    Empty,
    /// (Nearly) all object: the object's share of the pixels that count.
    AllObject(f64),
}

impl std::fmt::Display for MaskProblem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            MaskProblem::TooSmall(w, h) => write!(
                f,
                "is {w}×{h}; at least {MIN_SIDE}×{MIN_SIDE} pixels are needed"
            ),
            MaskProblem::Empty => write!(f, "is empty: no object pixels to fit"),
            MaskProblem::AllObject(fill) => write!(
                f,
                "is all object ({:.0} % of the image): no silhouette to fit",
                100.0 * fill
            ),
        }
    }
}

/// Statistics of mask `index`. Errors when the image is smaller than [`MIN_SIDE`], has no object
/// pixel, or is (nearly) all object — there is no silhouette to fit then.
pub fn mask_stats(mask: &Mask, index: usize) -> Result<MaskStats, FitError> {
    check_mask(mask).map_err(|p| FitError(format!("mask {index} {p}")))
}

/// [`mask_stats`] with the reason a mask cannot be fitted as a [`MaskProblem`], for callers
/// that name the mask otherwise (the CLI, by its file).
pub fn check_mask(mask: &Mask) -> Result<MaskStats, MaskProblem> {
    let (w, h) = (mask.width(), mask.height());
    if w < MIN_SIDE || h < MIN_SIDE {
        return Err(MaskProblem::TooSmall(w, h));
    }
    let (mut lo, mut hi) = (DVec2::splat(f64::MAX), DVec2::splat(f64::MIN));
    let (mut sum, mut cx, mut cy, mut cared) = (0.0, 0.0, 0.0, 0usize);
    for (i, &v) in mask.values().iter().enumerate() {
        if v == Mask::DONT_CARE {
            continue;
        }
        cared += 1;
        let (x, y) = ((i % w as usize) as f64, (i / w as usize) as f64);
        let v = f64::from(v);
        sum += v;
        cx += v * (x + 0.5);
        cy += v * (y + 0.5);
        if v >= 0.5 {
            lo = lo.min(DVec2::new(x, y));
            hi = hi.max(DVec2::new(x + 1.0, y + 1.0));
        }
    }
    if sum < 1.0 || lo.x > hi.x {
        return Err(MaskProblem::Empty);
    }
    let fill = sum / cared.max(1) as f64;
    if fill > 0.98 {
        return Err(MaskProblem::AllObject(fill));
    }
    Ok(MaskStats {
        width: w,
        height: h,
        bbox_min: lo,
        bbox_max: hi,
        centroid: DVec2::new(cx / sum, cy / sum),
        fill,
    })
}

impl MaskStats {
    /// Bounding box centre, pixels.
    pub fn bbox_center(&self) -> DVec2 {
        0.5 * (self.bbox_min + self.bbox_max)
    }

    /// Bounding box size, pixels.
    pub fn bbox_size(&self) -> DVec2 {
        self.bbox_max - self.bbox_min
    }

    /// The yaw that puts the generator's +X side where the mask's thin extra mass is: 0 (+X to
    /// the right) when the centroid sits left of the bounding box centre, π otherwise.
    pub fn handle_yaw(&self) -> f64 {
        if self.centroid.x <= self.bbox_center().x {
            0.0
        } else {
            std::f64::consts::PI
        }
    }
}

/// Solves the scale and translation that make `positions` (object space), seen with the given
/// rotation and field of view, cover the mask's bounding box. Returns `None` when the shape
/// does not project (empty, or degenerate).
pub fn fit_box(
    positions: &[Vec3],
    stats: &MaskStats,
    yaw: f64,
    pitch: f64,
    fov_y: f64,
) -> Option<ViewVars> {
    let mut vars = ViewVars {
        yaw,
        pitch,
        roll: 0.0,
        tx: 0.0,
        ty: 0.0,
        log_scale: 0.0,
        fov_y,
    };
    if positions.is_empty() {
        return None;
    }
    // Start centred and small enough to be in front of the camera, then alternate: scale to
    // the box size, shift to the box centre.
    let extent = positions
        .iter()
        .fold(0.0f64, |m, p| m.max(f64::from(p.length())));
    if !(extent.is_finite() && extent > 0.0) {
        return None;
    }
    let centre =
        positions.iter().fold(DVec3::ZERO, |a, p| a + p.as_dvec3()) / positions.len() as f64;
    vars.log_scale = (0.5 / extent).ln();
    let r = vars.params().rotation_and_derivatives()[0];
    let c = r * centre * vars.log_scale.exp();
    vars.tx = -c.x;
    vars.ty = -c.y;
    for _ in 0..6 {
        let view = vars.view(stats.width, stats.height);
        let (mut lo, mut hi) = (DVec2::splat(f64::MAX), DVec2::splat(f64::MIN));
        for &p in positions {
            let (q, z) = view.project(p);
            if z <= 1e-3 {
                return None;
            }
            lo = lo.min(q);
            hi = hi.max(q);
        }
        let size = hi - lo;
        if !(size.x > 1e-9 && size.y > 1e-9) {
            return None;
        }
        let target = stats.bbox_size();
        // Geometric mean of the two ratios: a seed of another aspect ratio is scaled to the
        // same area, and the fit corrects the shape.
        let k = ((target.x / size.x) * (target.y / size.y)).sqrt();
        vars.log_scale += k.ln().clamp(-2.0, 2.0);
        // Shift in world units at the object's depth: pixels × depth / focal length.
        let shift = (stats.bbox_center() - 0.5 * (lo + hi)) * (CAMERA_DISTANCE / view.focal());
        vars.tx += shift.x;
        vars.ty -= shift.y;
    }
    vars.params().validate().ok()?;
    Some(vars)
}

/// The optimisation variables of one view, given the range of initial log-scales seen across
/// the guesses (`log_scale_lo..=hi`) and the field of view.
pub fn view_domain(
    log_scale_lo: f64,
    log_scale_hi: f64,
    fov_y: f64,
    fit_fov: bool,
    aspect: f64,
) -> Vec<Var> {
    use std::f64::consts::PI;
    // Half the visible height and width at the object's depth: the translation range.
    let half_h = CAMERA_DISTANCE * (0.5 * fov_y).tan();
    let half_w = half_h * aspect;
    let mut vars = vec![
        Var::continuous(-PI, PI).with_unit(1.0),
        Var::continuous(-0.6, 1.4).with_unit(1.0),
        Var::continuous(-0.5, 0.5).with_unit(1.0),
        // One unit of translation is half the visible height: lr 0.01 moves ~1 pixel at 256².
        Var::continuous(-1.5 * half_w, 1.5 * half_w).with_unit(0.5 * half_h),
        Var::continuous(-1.5 * half_h, 1.5 * half_h).with_unit(0.5 * half_h),
        // A log-scale unit of 0.5: lr 0.01 is a 0.5 % size step.
        Var::continuous(log_scale_lo - 1.0, log_scale_hi + 1.0).with_unit(0.5),
    ];
    if fit_fov {
        vars.push(Var::continuous(0.15, 1.6).with_unit(0.5));
    }
    vars
}

#[cfg(test)]
mod fov_tests {
    use super::DEFAULT_FOV_Y;

    #[test]
    fn default_fov_is_a_50mm_lens() {
        // Regression: the constant once disagreed with its documented formula.
        assert!((DEFAULT_FOV_Y - 2.0 * (12.0f64 / 50.0).atan()).abs() < 1e-15);
    }
}
