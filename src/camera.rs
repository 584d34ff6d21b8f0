//! Perspective pinhole camera and object transform, shared by the renderer, the fit and the exporter.
//!
//! Conventions (glTF's, used everywhere in procfit): world Y is up; a camera looks down its own
//! −Z axis with +X to the right and +Y up; pixel coordinates have x to the right and y **down**,
//! `(0, 0)` being the top-left corner of the top-left pixel, so pixel `(i, j)` covers
//! `[i, i + 1] × [j, j + 1]` and its centre is `(i + 0.5, j + 0.5)`.
//!
//! A [`View`] is everything one silhouette render needs: the image size, a fixed
//! [`CameraPose`] (camera-to-world rotation and position) and the differentiable [`ViewParams`]
//! — the object transform (yaw/pitch/roll, translation, uniform scale) and the intrinsics
//! (vertical field of view, principal-point offset). The fit steps [`ViewParams`] as a flat
//! vector ([`ViewParams::to_vec`], [`ViewParams::from_slice`], [`ViewParams::NAMES`]).
//! The camera pose itself is not a parameter on purpose: moving the camera is the inverse of
//! moving the object, so one of the two is enough, and keeping the pose fixed lets several
//! views (a turntable) share one object transform (the paper fits object rotation and
//! translation plus the field of view, §3.2; notes "Renderer, loss, camera").
//!
//! Projection of an object-space point `p`:
//! `w = t + s·R(yaw, pitch, roll)·p` (world), `c = Rcᵀ·(w − eye)` (camera),
//! `x = W/2 + H·pp_x + f·c.x/(−c.z)`, `y = H/2 + H·pp_y − f·c.y/(−c.z)` with the focal length
//! in pixels `f = (H/2)/tan(fov_y/2)`, `R = R_y(yaw)·R_x(pitch)·R_z(roll)`. The principal-point
//! offset is a fraction of the image height so one value means the same at every resolution.

use glam::{DMat3, DVec2, DVec3, Vec3};
use std::fmt;

/// A camera or view that cannot be built or used.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraError(pub String);

impl fmt::Display for CameraError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for CameraError {}

/// Where a camera is and where it looks: camera-to-world rotation (columns are the camera's
/// +X, +Y, +Z axes in world space; the camera looks down its −Z) and position.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraPose {
    /// Camera-to-world rotation (orthonormal, determinant +1).
    pub rotation: DMat3,
    /// Camera position in world space.
    pub position: DVec3,
}

impl CameraPose {
    /// A camera at `eye` looking at `target`, with `up` (world) kept as upright as possible.
    /// Errors when `eye == target`, when `up` is parallel to the viewing direction, or on
    /// non-finite input.
    pub fn look_at(eye: DVec3, target: DVec3, up: DVec3) -> Result<CameraPose, CameraError> {
        if !(eye.is_finite() && target.is_finite() && up.is_finite()) {
            return Err(CameraError("look-at with a non-finite point".into()));
        }
        let back = eye - target; // camera +Z points away from what it looks at
        if back.length() < 1e-12 {
            return Err(CameraError("look-at: eye and target coincide".into()));
        }
        let z = back.normalize();
        let x = up.cross(z);
        if x.length() < 1e-9 * up.length().max(1e-300) || up.length() < 1e-12 {
            return Err(CameraError(
                "look-at: up vector is parallel to the viewing direction".into(),
            ));
        }
        let x = x.normalize();
        let y = z.cross(x);
        Ok(CameraPose {
            rotation: DMat3::from_cols(x, y, z),
            position: eye,
        })
    }

    /// The paper's turntable camera: on a horizontal circle of radius `distance` around
    /// `target`, at azimuth `azimuth` radians (0 = on the +Z side, increasing towards +X),
    /// looking at `target` with Y up. Their evaluation uses 64 azimuths `2πi/64`, distance 3,
    /// fov 0.5 rad around the origin (notes "Evaluation as they did it").
    pub fn turntable(
        azimuth: f64,
        distance: f64,
        target: DVec3,
    ) -> Result<CameraPose, CameraError> {
        if !(distance.is_finite() && distance > 0.0 && azimuth.is_finite()) {
            return Err(CameraError(format!(
                "turntable distance {distance} / azimuth {azimuth} is not a positive finite number"
            )));
        }
        let eye = target + distance * DVec3::new(azimuth.sin(), 0.0, azimuth.cos());
        CameraPose::look_at(eye, target, DVec3::Y)
    }
}

/// Number of entries in [`ViewParams`]' flat vector.
pub const N_VIEW_PARAMS: usize = 10;

/// The differentiable part of a view: object transform and camera intrinsics.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewParams {
    /// Object rotation about world Y, radians (applied last).
    pub yaw: f64,
    /// Object rotation about X, radians.
    pub pitch: f64,
    /// Object rotation about Z, radians (applied first).
    pub roll: f64,
    /// Object translation in world space.
    pub translation: DVec3,
    /// Uniform object scale (> 0).
    pub scale: f64,
    /// Vertical field of view, radians, in `(0, π)`.
    pub fov_y: f64,
    /// Principal-point offset from the image centre, as a fraction of the image height
    /// (x to the right, y down).
    pub principal: DVec2,
}

impl Default for ViewParams {
    fn default() -> Self {
        ViewParams {
            yaw: 0.0,
            pitch: 0.0,
            roll: 0.0,
            translation: DVec3::ZERO,
            scale: 1.0,
            fov_y: 0.5,
            principal: DVec2::ZERO,
        }
    }
}

impl ViewParams {
    /// Names of the flat-vector entries, in order.
    pub const NAMES: [&'static str; N_VIEW_PARAMS] = [
        "yaw", "pitch", "roll", "tx", "ty", "tz", "scale", "fov_y", "pp_x", "pp_y",
    ];
    /// Index of `yaw` in the flat vector (and in the renderer's view gradient).
    pub const YAW: usize = 0;
    /// Index of `pitch`.
    pub const PITCH: usize = 1;
    /// Index of `roll`.
    pub const ROLL: usize = 2;
    /// Index of the translation's x.
    pub const TX: usize = 3;
    /// Index of the translation's y.
    pub const TY: usize = 4;
    /// Index of the translation's z.
    pub const TZ: usize = 5;
    /// Index of `scale`.
    pub const SCALE: usize = 6;
    /// Index of `fov_y`.
    pub const FOV_Y: usize = 7;

    /// The flat vector, in [`ViewParams::NAMES`] order.
    pub fn to_vec(&self) -> [f64; N_VIEW_PARAMS] {
        [
            self.yaw,
            self.pitch,
            self.roll,
            self.translation.x,
            self.translation.y,
            self.translation.z,
            self.scale,
            self.fov_y,
            self.principal.x,
            self.principal.y,
        ]
    }

    /// Parameters from a flat vector in [`ViewParams::NAMES`] order, validated.
    pub fn from_slice(v: &[f64]) -> Result<ViewParams, CameraError> {
        let v: &[f64; N_VIEW_PARAMS] = v.try_into().map_err(|_| {
            CameraError(format!(
                "view parameters need {N_VIEW_PARAMS} values, got {}",
                v.len()
            ))
        })?;
        let p = ViewParams {
            yaw: v[0],
            pitch: v[1],
            roll: v[2],
            translation: DVec3::new(v[3], v[4], v[5]),
            scale: v[6],
            fov_y: v[7],
            principal: DVec2::new(v[8], v[9]),
        };
        p.validate()?;
        Ok(p)
    }

    /// Checks that every value is finite, the scale positive and the field of view in `(0, π)`.
    pub fn validate(&self) -> Result<(), CameraError> {
        if let Some(i) = self.to_vec().iter().position(|x| !x.is_finite()) {
            return Err(CameraError(format!(
                "view parameter `{}` is not finite",
                Self::NAMES[i]
            )));
        }
        if self.scale <= 0.0 {
            return Err(CameraError(format!(
                "object scale {} is not positive",
                self.scale
            )));
        }
        if !(self.fov_y > 1e-6 && self.fov_y < std::f64::consts::PI - 1e-6) {
            return Err(CameraError(format!(
                "field of view {} rad is outside (0, π)",
                self.fov_y
            )));
        }
        Ok(())
    }

    /// The object rotation `R = R_y(yaw)·R_x(pitch)·R_z(roll)` and its three partial
    /// derivatives, in that order.
    pub fn rotation_and_derivatives(&self) -> [DMat3; 4] {
        let (ry, rx, rz) = (
            DMat3::from_rotation_y(self.yaw),
            DMat3::from_rotation_x(self.pitch),
            DMat3::from_rotation_z(self.roll),
        );
        // d/dθ of a rotation about axis k is (k×)·R_k.
        let (dy, dx, dz) = (
            skew(DVec3::Y) * ry,
            skew(DVec3::X) * rx,
            skew(DVec3::Z) * rz,
        );
        [ry * rx * rz, dy * rx * rz, ry * dx * rz, ry * rx * dz]
    }
}

/// The cross-product matrix `[k]×`.
fn skew(k: DVec3) -> DMat3 {
    DMat3::from_cols(
        DVec3::new(0.0, k.z, -k.y),
        DVec3::new(-k.z, 0.0, k.x),
        DVec3::new(k.y, -k.x, 0.0),
    )
}

/// Everything one render needs: image size, camera pose and the differentiable parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Fixed camera pose.
    pub pose: CameraPose,
    /// Differentiable object transform and intrinsics.
    pub params: ViewParams,
}

impl View {
    /// The paper's turntable view (see [`CameraPose::turntable`]) with identity object
    /// transform and the given field of view.
    pub fn turntable(
        width: u32,
        height: u32,
        azimuth: f64,
        distance: f64,
        fov_y: f64,
        target: DVec3,
    ) -> Result<View, CameraError> {
        let view = View {
            width,
            height,
            pose: CameraPose::turntable(azimuth, distance, target)?,
            params: ViewParams {
                fov_y,
                ..ViewParams::default()
            },
        };
        view.params.validate()?;
        Ok(view)
    }

    /// Focal length in pixels.
    pub fn focal(&self) -> f64 {
        0.5 * f64::from(self.height) / (0.5 * self.params.fov_y).tan()
    }

    /// Projects one object-space point: pixel position and depth (distance in front of the
    /// camera along its −Z; ≤ 0 means behind). For many points use [`View::projector`].
    pub fn project(&self, p: Vec3) -> (DVec2, f64) {
        self.projector().project(p)
    }

    /// The projection with its matrices precomputed, for projecting many points.
    pub fn projector(&self) -> Projector {
        let r = self.params.rotation_and_derivatives()[0];
        let rc_t = self.pose.rotation.transpose();
        let h = f64::from(self.height);
        Projector {
            // c = Rcᵀ·(t + s·R·p − eye) = M·p + k
            m: rc_t * (self.params.scale * r),
            k: rc_t * (self.params.translation - self.pose.position),
            f: self.focal(),
            centre: DVec2::new(
                0.5 * f64::from(self.width) + h * self.params.principal.x,
                0.5 * h + h * self.params.principal.y,
            ),
        }
    }
}

/// A [`View`]'s projection with its matrices precomputed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Projector {
    m: DMat3,
    k: DVec3,
    f: f64,
    centre: DVec2,
}

impl Projector {
    /// Camera-space position of an object-space point.
    pub fn to_camera(&self, p: Vec3) -> DVec3 {
        self.m * p.as_dvec3() + self.k
    }

    /// Pixel position of a camera-space point (in front of the camera).
    pub fn to_pixel(&self, c: DVec3) -> DVec2 {
        let z = -c.z;
        self.centre + DVec2::new(self.f * c.x / z, -self.f * c.y / z)
    }

    /// Pixel position and depth (see [`View::project`]).
    pub fn project(&self, p: Vec3) -> (DVec2, f64) {
        let c = self.to_camera(p);
        (self.to_pixel(c), -c.z)
    }

    /// The object-space point at `pixel` and `depth` (in front of the camera): the inverse of
    /// [`Projector::project`]. `None` when the object transform is singular.
    pub fn unproject(&self, pixel: DVec2, depth: f64) -> Option<DVec3> {
        let d = (pixel - self.centre) * (depth / self.f);
        let c = DVec3::new(d.x, -d.y, -depth);
        (self.m.determinant().abs() > 1e-12).then(|| self.m.inverse() * (c - self.k))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn look_at_centres_the_target_and_keeps_y_up() {
        let pose = CameraPose::look_at(DVec3::new(1.0, 2.0, 5.0), DVec3::ZERO, DVec3::Y).unwrap();
        let view = View {
            width: 64,
            height: 48,
            pose,
            params: ViewParams::default(),
        };
        let (c, z) = view.project(Vec3::ZERO);
        assert!((c - DVec2::new(32.0, 24.0)).length() < 1e-9 && z > 0.0);
        // A point above the target projects above the centre (smaller y).
        assert!(view.project(Vec3::new(0.0, 0.1, 0.0)).0.y < 24.0);
        assert!(CameraPose::look_at(DVec3::Y, DVec3::ZERO, DVec3::Y).is_err());
        assert!(CameraPose::look_at(DVec3::ZERO, DVec3::ZERO, DVec3::Y).is_err());
    }

    #[test]
    fn unproject_inverts_project() {
        let v = View::turntable(64, 48, 0.7, 4.0, 0.6, DVec3::new(0.0, 1.0, 0.0)).unwrap();
        let p = Vec3::new(0.3, 1.2, -0.4);
        let proj = v.projector();
        let (px, depth) = proj.project(p);
        let back = proj.unproject(px, depth).unwrap();
        assert!((back - p.as_dvec3()).length() < 1e-5, "{back} vs {p}");
    }

    #[test]
    fn turntable_at_azimuth_zero_looks_down_minus_z() {
        let v = View::turntable(32, 32, 0.0, 3.0, 0.5, DVec3::ZERO).unwrap();
        assert!((v.pose.position - DVec3::new(0.0, 0.0, 3.0)).length() < 1e-12);
        // +X in the world is to the right in the image.
        assert!(v.project(Vec3::X * 0.1).0.x > 16.0);
    }

    #[test]
    fn rotation_derivatives_match_finite_differences() {
        let p = ViewParams {
            yaw: 0.3,
            pitch: -0.2,
            roll: 0.7,
            ..ViewParams::default()
        };
        let [_, dy, dx, dz] = p.rotation_and_derivatives();
        let h = 1e-6;
        for (k, d) in [dy, dx, dz].into_iter().enumerate() {
            let mut a = p.to_vec();
            let mut b = p.to_vec();
            a[k] += h;
            b[k] -= h;
            let ra = ViewParams::from_slice(&a)
                .unwrap()
                .rotation_and_derivatives()[0];
            let rb = ViewParams::from_slice(&b)
                .unwrap()
                .rotation_and_derivatives()[0];
            let fd = (ra - rb) * (0.5 / h);
            assert!((fd - d).abs().to_cols_array().iter().all(|&e| e < 1e-8));
        }
    }

    #[test]
    fn refuses_bad_params() {
        let mut v = ViewParams::default().to_vec();
        assert!(ViewParams::from_slice(&v[..3]).is_err());
        v[6] = 0.0;
        assert!(ViewParams::from_slice(&v).is_err());
        v[6] = 1.0;
        v[7] = f64::NAN;
        assert!(ViewParams::from_slice(&v).is_err());
    }
}
