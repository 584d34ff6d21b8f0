//! The export-side description of a photo's camera: what the reconstruction hands the GLB writer
//! for each input photo, and what the importer gives back.

use super::GlbError;
use glam::{Mat4, Quat, Vec3};

/// A perspective camera with a pose, in glTF's camera convention: the camera looks down its
/// local −Z axis with +Y up and +X to the right of the image.
#[derive(Clone, Debug, PartialEq)]
pub struct ExportCamera {
    /// Node name; `None` gives `photo_<i>`.
    pub name: Option<String>,
    /// Vertical field of view in radians, in (0, π).
    pub yfov: f32,
    /// Image width / height, > 0.
    pub aspect: f32,
    /// Near clipping distance, > 0.
    pub znear: f32,
    /// Far clipping distance (> `znear`), or `None` for an infinite projection.
    pub zfar: Option<f32>,
    /// Camera-to-world transform, a 4×4 matrix in column-major order (glTF's `matrix` layout).
    /// It must be rigid (rotation + translation, no scale, no mirror): glTF camera nodes carry
    /// no scale.
    pub camera_to_world: [f32; 16],
}

/// Numbers per camera in a flat camera list ([`ExportCamera::to_floats`]): the vertical field of
/// view (radians), the aspect (width / height), then the 4×4 camera-to-world matrix in
/// column-major order. The page keeps a fit's cameras so, and hands them back for each GLB.
pub const CAMERA_FLOATS: usize = 18;

/// How far from 1 the scale of a "rigid" pose may be (float noise of a fitted rotation).
const RIGID_TOLERANCE: f32 = 1e-3;

impl ExportCamera {
    /// The camera as [`CAMERA_FLOATS`] numbers (its name, near and far planes are not kept).
    pub fn to_floats(&self) -> [f32; CAMERA_FLOATS] {
        let mut out = [0.0; CAMERA_FLOATS];
        out[0] = self.yfov;
        out[1] = self.aspect;
        out[2..].copy_from_slice(&self.camera_to_world);
        out
    }

    /// A camera called `name` from [`CAMERA_FLOATS`] numbers, with the near plane at 0.01 and
    /// an infinite far plane (what the fit's cameras are exported with).
    pub fn from_floats(c: &[f32; CAMERA_FLOATS], name: Option<String>) -> ExportCamera {
        let mut camera_to_world = [0.0; 16];
        camera_to_world.copy_from_slice(&c[2..]);
        ExportCamera {
            name,
            yfov: c[0],
            aspect: c[1],
            znear: 0.01,
            zfar: None,
            camera_to_world,
        }
    }

    /// A camera at `eye` looking at `target`, with world +Y as the up hint.
    pub fn look_at(eye: Vec3, target: Vec3, yfov: f32, aspect: f32) -> ExportCamera {
        // Columns of the pose: image right, image up, backward (the camera looks down −Z),
        // position. A view straight up or down falls back to +Z as the up hint.
        let forward = (target - eye).normalize_or(Vec3::NEG_Z);
        let hint = if forward.cross(Vec3::Y).length_squared() < 1e-12 {
            Vec3::Z
        } else {
            Vec3::Y
        };
        let right = forward.cross(hint).normalize();
        let up = right.cross(forward);
        let pose = Mat4::from_cols(
            right.extend(0.0),
            up.extend(0.0),
            (-forward).extend(0.0),
            eye.extend(1.0),
        );
        ExportCamera {
            name: None,
            yfov,
            aspect,
            znear: 0.01,
            zfar: None,
            camera_to_world: pose.to_cols_array(),
        }
    }

    /// The pose as (rotation, translation), checking every field; `which` names the camera in
    /// error messages.
    pub(crate) fn checked_pose(&self, which: &str) -> Result<(Quat, Vec3), GlbError> {
        let bad = |m: String| Err(GlbError::Export(format!("{which}: {m}")));
        if !(self.yfov.is_finite() && self.yfov > 0.0 && self.yfov < std::f32::consts::PI) {
            return bad(format!("yfov {} is not in (0, π) radians", self.yfov));
        }
        if !(self.aspect.is_finite() && self.aspect > 0.0) {
            return bad(format!("aspect ratio {} is not positive", self.aspect));
        }
        if !(self.znear.is_finite() && self.znear > 0.0) {
            return bad(format!("znear {} is not positive", self.znear));
        }
        if let Some(zfar) = self.zfar
            && !(zfar.is_finite() && zfar > self.znear)
        {
            return bad(format!("zfar {zfar} is not beyond znear {}", self.znear));
        }
        if !self.camera_to_world.iter().all(|v| v.is_finite()) {
            return bad("camera-to-world matrix has a non-finite entry".into());
        }
        let m = Mat4::from_cols_array(&self.camera_to_world);
        let bottom = m.row(3);
        if (bottom - glam::Vec4::W).abs().max_element() > RIGID_TOLERANCE {
            return bad(format!("bottom row {bottom} is not (0, 0, 0, 1)"));
        }
        if m.determinant() <= 0.0 {
            return bad("camera-to-world matrix is singular or mirrored".into());
        }
        let (_, rotation, translation) = m.to_scale_rotation_translation();
        let rotation = rotation.normalize();
        // Rebuilding the matrix from rotation + translation alone catches scale and shear.
        let rebuilt = Mat4::from_rotation_translation(rotation, translation);
        let error = (0..4)
            .map(|c| (rebuilt.col(c) - m.col(c)).abs().max_element())
            .fold(0.0f32, f32::max);
        if error > RIGID_TOLERANCE {
            return bad(format!(
                "camera-to-world matrix is not rigid (off by {error} from a rotation)"
            ));
        }
        Ok((rotation, translation))
    }
}
