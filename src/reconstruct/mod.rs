//! The reconstruction pipeline (paper §3.2, §3.4): masks in, generator parameters and one
//! camera per view out.
//!
//! - [`views`]: how a view is parameterised, how the single-view scale/distance ambiguity is
//!   fixed, the field of view from EXIF, and the camera guesses made from each mask.
//! - [`objective`]: eq. 1 (mean silhouette MSE over the views) and its gradient by eq. 2, as an
//!   [`Objective`](crate::optim::Objective) for the optimisers.
//! - [`session`]: the coarse-to-fine schedule (memetic at 128², Adam at 256² and 512²) as a
//!   resumable [`Session`] for the page and the CLI: [`FitConfig::restarts`] runs stepped side
//!   by side, the best kept. Its pieces: [`config`] (the settings, checked once), `run` (one
//!   run's stage machine), `seeds` (stage 1's seed points), `handover` (stage 1 → 2).
//! - [`windows`]: the window term of a building fit (window labels per view), and
//!   `layout_search`, the building layout sweep it drives at the hand-over.
//! - [`rim`]: the rim term of a dish fit (the photo's edge where the rim's near half lies,
//!   which fixes the camera's height from above).
//! - [`eval`]: the paper's IoU over 64 turntable views.
//! - [`extras`]: small things in a mask that are not the object (a spoon, a tea bag's tag),
//!   made don't care before the fit ([`FitConfig::ignore_extras`]).

pub mod config;
pub mod eval;
pub mod extras;
mod handover;
mod layout_search;
pub mod objective;
pub mod rim;
mod run;
mod seeds;
pub mod session;
pub mod views;
pub mod windows;

pub use config::{
    DEFAULT_EVALUATIONS, DEFAULT_RESTARTS, FitConfig, MAX_QUALITY, MAX_RESTARTS, MAX_VIEWS,
    QUICK_QUALITY, check_quality,
};
pub use eval::{align_to_reference, iou64, normalized};
pub use objective::{FitObjective, Layout, render_coverage, resample_mask};
pub use rim::{DEFAULT_RIM_WEIGHT, Luma, RimTerm};
pub use session::{FitResult, PREVIEW_SIDE, Progress, Session, WINDOW_OUTLINE_SLACK};
pub use views::{CAMERA_DISTANCE, DEFAULT_FOV_Y, ViewSlot, ViewVars, fov_from_focal_35mm};
pub use windows::{DEFAULT_WINDOW_WEIGHT, WindowTerm};

use crate::glb::ExportCamera;
use std::fmt;

/// A fit that cannot start or go on; the message says why, in one line.
#[derive(Clone, Debug, PartialEq)]
pub struct FitError(pub String);

impl fmt::Display for FitError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for FitError {}

/// The glTF camera of a fitted view, in the model's frame: the renderer moves the object by
/// `p ↦ t + s·R·p` in front of a fixed camera, so in the model's frame the camera sits at
/// `Rᵀ(eye − t)/s` with orientation `Rᵀ·R_cam` (a pinhole camera's picture does not change when
/// its frame is scaled about its centre, so the pose stays rigid).
pub fn export_camera(view: &crate::camera::View, name: Option<String>) -> ExportCamera {
    let r = view.params.rotation_and_derivatives()[0];
    let rt = r.transpose();
    let pos = rt * (view.pose.position - view.params.translation) / view.params.scale;
    let rot = rt * view.pose.rotation;
    let m = glam::DMat4::from_cols(
        rot.x_axis.extend(0.0),
        rot.y_axis.extend(0.0),
        rot.z_axis.extend(0.0),
        pos.extend(1.0),
    );
    ExportCamera {
        name,
        yfov: view.params.fov_y as f32,
        aspect: view.width as f32 / view.height as f32,
        znear: 0.01,
        zfar: None,
        camera_to_world: m.as_mat4().to_cols_array(),
    }
}

/// The view of a glTF camera ([`export_camera`]'s output, or any GLB's) over a `width × height`
/// image: its pose in the model's frame and its vertical field of view, the object left where
/// it is (no object transform).
pub fn camera_view(cam: &ExportCamera, width: u32, height: u32) -> crate::camera::View {
    let mat = glam::Mat4::from_cols_array(&cam.camera_to_world).as_dmat4();
    crate::camera::View {
        width,
        height,
        pose: crate::camera::CameraPose {
            rotation: glam::DMat3::from_mat4(mat),
            position: mat.w_axis.truncate(),
        },
        params: crate::camera::ViewParams {
            fov_y: f64::from(cam.yfov),
            ..Default::default()
        },
    }
}
