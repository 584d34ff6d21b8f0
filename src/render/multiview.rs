//! The silhouette loss of eq. 1 over several views with its gradient, as one call a fit makes
//! per iteration: render every view, score it against its mask, and pull the adjoints back to
//! vertex positions and view parameters.
//!
//! Views run in parallel with rayon when asked; each view writes its own buffers and the sums
//! over views run sequentially in view order afterwards, so the result is bit-identical with or
//! without threads. All buffers live in the [`MultiViewLoss`] and are reused every call.

use super::{RenderError, Renderer, Topology};
use crate::camera::{N_VIEW_PARAMS, View};
use crate::loss::mse_with_adjoint;
use crate::mask::Mask;
use glam::Vec3;
use rayon::prelude::*;

/// Per-view state: a renderer, its adjoint image and its gradient buffers.
#[derive(Debug)]
struct Slot {
    renderer: Renderer,
    adjoint: Vec<f32>,
    grad_pos: Vec<Vec3>,
    grad_view: [f64; N_VIEW_PARAMS],
    loss: f64,
}

/// Evaluates `L = (1/N) Σᵢ MSE(render(positions, viewᵢ), maskᵢ)` (paper eq. 1) and its
/// gradient for N views of one image size.
#[derive(Debug)]
pub struct MultiViewLoss {
    width: u32,
    height: u32,
    slots: Vec<Slot>,
    parallel: bool,
}

impl MultiViewLoss {
    /// Buffers for `n_views` views of `width × height`. Errors on a bad size or no views.
    pub fn new(width: u32, height: u32, n_views: usize) -> Result<MultiViewLoss, RenderError> {
        if n_views == 0 {
            return Err(RenderError(
                "a multi-view loss needs at least one view".into(),
            ));
        }
        let slots = (0..n_views)
            .map(|_| {
                Ok(Slot {
                    renderer: Renderer::new(width, height)?,
                    adjoint: vec![0.0; width as usize * height as usize],
                    grad_pos: Vec::new(),
                    grad_view: [0.0; N_VIEW_PARAMS],
                    loss: 0.0,
                })
            })
            .collect::<Result<Vec<_>, RenderError>>()?;
        Ok(MultiViewLoss {
            width,
            height,
            slots,
            parallel: false,
        })
    }

    /// Runs the views on rayon's pool (each render itself stays on one thread: below ~20k
    /// vertices a render takes well under a millisecond and splitting it costs more than it
    /// gains, see `benches/render.rs`). Results are bit-identical either way.
    pub fn set_parallel(&mut self, parallel: bool) {
        self.parallel = parallel;
    }

    /// Number of views.
    pub fn n_views(&self) -> usize {
        self.slots.len()
    }

    /// The coverage image of view `i` from the last [`MultiViewLoss::evaluate`], if any.
    pub fn coverage(&self, i: usize) -> Option<&[f32]> {
        self.slots.get(i).map(|s| s.renderer.coverage())
    }

    /// The loss of each view from the last evaluation (already divided by N).
    pub fn view_losses(&self) -> impl Iterator<Item = f64> + '_ {
        self.slots.iter().map(|s| s.loss)
    }

    /// Computes the loss and **overwrites** `grad_pos` (dL/d object-space positions) and
    /// `grad_views[i]` (dL/d the parameters of view `i`; sum them for parameters the views
    /// share). `views` and `masks` need one entry per view, of this size.
    pub fn evaluate(
        &mut self,
        topo: &Topology,
        positions: &[Vec3],
        views: &[View],
        masks: &[Mask],
        grad_pos: &mut [Vec3],
        grad_views: &mut [[f64; N_VIEW_PARAMS]],
    ) -> Result<f64, RenderError> {
        let n = self.slots.len();
        if views.len() != n || masks.len() != n || grad_views.len() != n {
            return Err(RenderError(format!(
                "{} views, {} masks and {} view gradients for a {n}-view loss",
                views.len(),
                masks.len(),
                grad_views.len()
            )));
        }
        if let Some(m) = masks
            .iter()
            .find(|m| m.width() != self.width || m.height() != self.height)
        {
            return Err(RenderError(format!(
                "mask is {}×{}, the loss renders {}×{}",
                m.width(),
                m.height(),
                self.width,
                self.height
            )));
        }
        if grad_pos.len() != positions.len() {
            return Err(RenderError(format!(
                "gradient buffer has {} entries for {} vertices",
                grad_pos.len(),
                positions.len()
            )));
        }
        let weight = 1.0 / n as f64;
        let one = |s: &mut Slot, view: &View, mask: &Mask| -> Result<(), RenderError> {
            s.grad_pos.clear();
            s.grad_pos.resize(positions.len(), Vec3::ZERO);
            s.grad_view = [0.0; N_VIEW_PARAMS];
            let cov = s.renderer.forward(topo, positions, view)?;
            s.loss = mse_with_adjoint(cov, mask, weight, &mut s.adjoint)
                .map_err(|e| RenderError(e.0))?;
            s.renderer.backward(
                topo,
                positions,
                view,
                &s.adjoint,
                &mut s.grad_pos,
                &mut s.grad_view,
            )
        };
        if self.parallel {
            self.slots
                .par_iter_mut()
                .zip(views.par_iter().zip(masks.par_iter()))
                .map(|(s, (v, m))| one(s, v, m))
                .collect::<Result<Vec<()>, RenderError>>()?;
        } else {
            for (s, (v, m)) in self.slots.iter_mut().zip(views.iter().zip(masks)) {
                one(s, v, m)?;
            }
        }
        grad_pos.fill(Vec3::ZERO);
        let mut loss = 0.0;
        for (s, gv) in self.slots.iter().zip(grad_views.iter_mut()) {
            loss += s.loss;
            *gv = s.grad_view;
            for (g, d) in grad_pos.iter_mut().zip(&s.grad_pos) {
                *g += *d;
            }
        }
        Ok(loss)
    }
}
