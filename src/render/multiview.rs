//! The silhouette loss of eq. 1 over several views with its gradient, as one call a fit makes
//! per evaluation: render every view, score it against its mask, and pull the adjoints back to
//! vertex positions and view parameters. This is the one implementation: the fit
//! ([`FitObjective`](crate::reconstruct::FitObjective), through a per-thread
//! [`MultiViewLoss`]), the renderer benchmark ([`super::bench`], native and wasm) and the tests
//! all run it.
//!
//! **Determinism.** The sums over views run in view order whatever runs in parallel: by
//! default the views run one after the other on one renderer, each backward adding its
//! gradient into the caller's buffer (what the fit does: its evaluations already run on
//! rayon's threads, one per individual, and stages 2 and 3 use rayon inside each render,
//! [`MultiViewLoss::set_parallel_render`]). With [`MultiViewLoss::set_parallel`] the views run
//! on rayon, each on its own renderer and gradient buffer, summed in view order afterwards.
//! Both give the same bits: a backward adds to each vertex at most once, so a view's own
//! buffer holds exactly the term the running sum would add.
//!
//! All buffers live in the [`MultiViewLoss`] and are reused every call.

use super::{RenderError, Renderer, Topology};
use crate::camera::{N_VIEW_PARAMS, View};
use crate::loss::mse_with_adjoint;
use crate::mask::Mask;
use glam::Vec3;
use rayon::prelude::*;

/// A renderer with its adjoint image, and the gradient buffers of one view when the views run
/// in parallel.
#[derive(Debug)]
struct Slot {
    renderer: Renderer,
    adjoint: Vec<f32>,
    grad_pos: Vec<Vec3>,
    grad_view: [f64; N_VIEW_PARAMS],
    loss: f64,
}

impl Slot {
    fn new(width: u32, height: u32, parallel_render: bool) -> Result<Slot, RenderError> {
        let mut renderer = Renderer::new(width, height)?;
        renderer.set_parallel(parallel_render);
        Ok(Slot {
            renderer,
            adjoint: vec![0.0; width as usize * height as usize],
            grad_pos: Vec::new(),
            grad_view: [0.0; N_VIEW_PARAMS],
            loss: 0.0,
        })
    }

    /// One view's term of eq. 1 (`weight` = 1/N), and with `grad` its gradient **added** into
    /// the position buffer and written into the view's.
    fn view(
        &mut self,
        topo: &Topology,
        positions: &[Vec3],
        view: &View,
        mask: &Mask,
        weight: f64,
        grad: Option<(&mut [Vec3], &mut [f64; N_VIEW_PARAMS])>,
    ) -> Result<f64, RenderError> {
        let cov = self.renderer.forward(topo, positions, view)?;
        let loss =
            mse_with_adjoint(cov, mask, weight, &mut self.adjoint).map_err(|e| RenderError(e.0))?;
        if let Some((grad_pos, grad_view)) = grad {
            *grad_view = [0.0; N_VIEW_PARAMS];
            self.renderer
                .backward(topo, positions, view, &self.adjoint, grad_pos, grad_view)?;
        }
        Ok(loss)
    }

    /// [`Slot::view`] into the slot's own gradient buffers (for views run in parallel).
    fn view_own(
        &mut self,
        topo: &Topology,
        positions: &[Vec3],
        view: &View,
        mask: &Mask,
        weight: f64,
        with_grad: bool,
    ) -> Result<(), RenderError> {
        let mut grad_pos = std::mem::take(&mut self.grad_pos);
        let mut grad_view = self.grad_view;
        grad_pos.clear();
        grad_pos.resize(positions.len(), Vec3::ZERO);
        let grad = with_grad.then_some((grad_pos.as_mut_slice(), &mut grad_view));
        let result = self.view(topo, positions, view, mask, weight, grad);
        self.grad_pos = grad_pos;
        self.grad_view = grad_view;
        self.loss = result?;
        Ok(())
    }
}

/// Evaluates `L = (1/N) Σᵢ MSE(render(positions, viewᵢ), maskᵢ)` (paper eq. 1) and its
/// gradient for N views of one image size.
#[derive(Debug)]
pub struct MultiViewLoss {
    width: u32,
    height: u32,
    n_views: usize,
    /// Slot 0 serves every view when they run one after the other; with parallel views there
    /// is one per view (made on first use).
    slots: Vec<Slot>,
    /// Each view's term of the last evaluation.
    losses: Vec<f64>,
    parallel: bool,
    parallel_render: bool,
}

impl MultiViewLoss {
    /// Buffers for `n_views` views of `width × height`. Errors on a bad size or no views.
    pub fn new(width: u32, height: u32, n_views: usize) -> Result<MultiViewLoss, RenderError> {
        if n_views == 0 {
            return Err(RenderError(
                "a multi-view loss needs at least one view".into(),
            ));
        }
        Ok(MultiViewLoss {
            width,
            height,
            n_views,
            slots: vec![Slot::new(width, height, false)?],
            losses: vec![0.0; n_views],
            parallel: false,
            parallel_render: false,
        })
    }

    /// Runs the views on rayon's pool, each on its own renderer (more memory: one renderer per
    /// view). Results are bit-identical either way.
    pub fn set_parallel(&mut self, parallel: bool) {
        self.parallel = parallel;
    }

    /// Uses rayon inside each render ([`Renderer::set_parallel`]): what a fit does when it
    /// evaluates one point at a time. Results are bit-identical either way.
    pub fn set_parallel_render(&mut self, parallel: bool) {
        self.parallel_render = parallel;
        for s in &mut self.slots {
            s.renderer.set_parallel(parallel);
        }
    }

    /// Number of views.
    pub fn n_views(&self) -> usize {
        self.n_views
    }

    /// Image width.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Image height.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// The loss of each view from the last evaluation (already divided by N).
    pub fn view_losses(&self) -> impl Iterator<Item = f64> + '_ {
        self.losses.iter().copied()
    }

    /// Computes the loss and **overwrites** `grad_pos` (dL/d object-space positions) and
    /// `grad_views[i]` (dL/d the parameters of view `i`, in
    /// [`ViewParams::NAMES`](crate::camera::ViewParams::NAMES) order; sum them for parameters
    /// the views share). `views` and `masks` need one entry per view, of this size.
    pub fn evaluate(
        &mut self,
        topo: &Topology,
        positions: &[Vec3],
        views: &[View],
        masks: &[Mask],
        grad_pos: &mut [Vec3],
        grad_views: &mut [[f64; N_VIEW_PARAMS]],
    ) -> Result<f64, RenderError> {
        if grad_views.len() != self.n_views {
            return Err(RenderError(format!(
                "{} view gradients for a {}-view loss",
                grad_views.len(),
                self.n_views
            )));
        }
        if grad_pos.len() != positions.len() {
            return Err(RenderError(format!(
                "gradient buffer has {} entries for {} vertices",
                grad_pos.len(),
                positions.len()
            )));
        }
        self.run(topo, positions, views, masks, Some((grad_pos, grad_views)))
    }

    /// The loss alone (no backward pass).
    pub fn value(
        &mut self,
        topo: &Topology,
        positions: &[Vec3],
        views: &[View],
        masks: &[Mask],
    ) -> Result<f64, RenderError> {
        self.run(topo, positions, views, masks, None)
    }

    fn run(
        &mut self,
        topo: &Topology,
        positions: &[Vec3],
        views: &[View],
        masks: &[Mask],
        grad: Option<(&mut [Vec3], &mut [[f64; N_VIEW_PARAMS]])>,
    ) -> Result<f64, RenderError> {
        let n = self.n_views;
        if views.len() != n || masks.len() != n {
            return Err(RenderError(format!(
                "{} views and {} masks for a {n}-view loss",
                views.len(),
                masks.len(),
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
        let weight = 1.0 / n as f64;
        let mut loss = 0.0;
        if self.parallel && n > 1 {
            while self.slots.len() < n {
                let s = Slot::new(self.width, self.height, self.parallel_render)?;
                self.slots.push(s);
            }
            let with_grad = grad.is_some();
            self.slots[..n]
                .par_iter_mut()
                .zip(views.par_iter().zip(masks.par_iter()))
                .map(|(s, (v, m))| s.view_own(topo, positions, v, m, weight, with_grad))
                .collect::<Result<Vec<()>, RenderError>>()?;
            // The sums, in view order.
            let mut grad = grad;
            if let Some((grad_pos, _)) = grad.as_mut() {
                grad_pos.fill(Vec3::ZERO);
            }
            for (k, s) in self.slots[..n].iter().enumerate() {
                loss += s.loss;
                self.losses[k] = s.loss;
                if let Some((grad_pos, grad_views)) = grad.as_mut() {
                    grad_views[k] = s.grad_view;
                    for (g, d) in grad_pos.iter_mut().zip(&s.grad_pos) {
                        *g += *d;
                    }
                }
            }
        } else {
            let slot = &mut self.slots[0];
            let mut grad = grad;
            if let Some((grad_pos, _)) = grad.as_mut() {
                grad_pos.fill(Vec3::ZERO);
            }
            for (k, (view, mask)) in views.iter().zip(masks).enumerate() {
                let g = grad.as_mut().map(|(gp, gv)| (&mut **gp, &mut gv[k]));
                let l = slot.view(topo, positions, view, mask, weight, g)?;
                loss += l;
                self.losses[k] = l;
            }
        }
        Ok(loss)
    }
}
