//! The fit's objective (paper eq. 1 and 2): generator parameters and per-view camera values in,
//! the mean silhouette MSE over the views (plus the generator's regulariser) out, with the
//! gradient from the renderer's edge integrals pulled back through the generator's
//! vector–Jacobian product.
//!
//! The optimisation vector is laid out by [`Layout`]: the generator's parameters in spec order,
//! then each view's [`VIEW_VARS`](super::views::VIEW_VARS) (and its field of view when fitted).
//!
//! Eq. 1 itself is [`MultiViewLoss`], the one implementation the benches and tests run too;
//! this module adds the generator (eq. 2), the camera values and the regulariser.
//!
//! **Scratch buffers.** An evaluation needs a [`MultiViewLoss`] per image size (a renderer and
//! an adjoint image), a vertex-gradient buffer and the view gradients. Evaluations run on
//! rayon's threads, so each thread keeps its own in a thread-local slot and reuses them on every
//! call (the caller-allocates rule, with the thread as the caller). A nested evaluation on the
//! same thread (rayon work stealing inside a parallel render) finds the slot busy and allocates
//! its own. Edge structures ([`Topology`]) depend only on the discrete parameters and the level
//! of detail, so they are cached per combination, shared between threads.

use super::rim::RimTerm;
use super::views::{ViewSlot, ViewVars};
use super::windows::WindowTerm;
use crate::camera::{N_VIEW_PARAMS, View};
use crate::generators::{Generator, Lod, Mesh};
use crate::mask::Mask;
use crate::optim::Objective;
use crate::render::{MultiViewLoss, Renderer, Topology};
use glam::Vec3;
use std::cell::RefCell;
use std::collections::HashMap;
use std::sync::{Arc, Mutex};

/// Where each value sits in the optimisation vector.
#[derive(Clone, Debug, PartialEq)]
pub struct Layout {
    /// Number of generator parameters (they come first).
    pub n_gen: usize,
    /// Number of views.
    pub n_views: usize,
    /// Whether each view's field of view is a variable.
    pub fit_fov: bool,
    /// The field of view of each view when it is not fitted (and its start when it is).
    pub fov_y: Vec<f64>,
}

impl Layout {
    /// Values per view.
    pub fn per_view(&self) -> usize {
        ViewSlot::count(self.fit_fov)
    }

    /// Length of the optimisation vector.
    pub fn len(&self) -> usize {
        self.n_gen + self.n_views * self.per_view()
    }

    /// Whether the vector is empty (never, for a real generator).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Index of view `v`'s first value.
    pub fn view_offset(&self, v: usize) -> usize {
        self.n_gen + v * self.per_view()
    }

    /// Index of view `v`'s value `slot` (the field of view only when it is fitted).
    pub fn slot(&self, v: usize, slot: ViewSlot) -> usize {
        self.view_offset(v) + slot.index()
    }

    /// View `v`'s values in `x`.
    pub fn view_vars(&self, x: &[f64], v: usize) -> ViewVars {
        let o = self.view_offset(v);
        ViewVars::read(&x[o..o + self.per_view()], self.fov_y[v])
    }

    /// Writes view `v`'s values into `x`.
    pub fn set_view_vars(&self, x: &mut [f64], v: usize, vars: &ViewVars) {
        let o = self.view_offset(v);
        vars.write(&mut x[o..o + self.per_view()]);
    }
}

/// Per-thread scratch: eq. 1's buffers by image size and view count, the views of the point,
/// a vertex gradient and the view gradients.
#[derive(Default)]
struct Scratch {
    losses: Vec<MultiViewLoss>,
    views: Vec<View>,
    grad_pos: Vec<Vec3>,
    grad_views: Vec<[f64; N_VIEW_PARAMS]>,
}

thread_local! {
    static SCRATCH: RefCell<Scratch> = RefCell::new(Scratch::default());
}

/// The loss for `n` views of `w × h` in `losses`, made on first use (at most a few are kept).
fn loss_for(
    losses: &mut Vec<MultiViewLoss>,
    w: u32,
    h: u32,
    n: usize,
    parallel_render: bool,
) -> Result<&mut MultiViewLoss, String> {
    let found = losses
        .iter()
        .position(|l| l.width() == w && l.height() == h && l.n_views() == n);
    let i = match found {
        Some(i) => i,
        None => {
            if losses.len() >= 4 {
                losses.remove(0);
            }
            losses.push(MultiViewLoss::new(w, h, n).map_err(|e| e.to_string())?);
            losses.len() - 1
        }
    };
    let l = &mut losses[i];
    l.set_parallel_render(parallel_render);
    Ok(l)
}

/// Most edge structures kept; a building has one per combination of its discrete values.
const TOPOLOGY_CACHE: usize = 256;

/// An edge structure with the triangle count of the mesh it was built from.
type Cached = Arc<(usize, Topology)>;

/// Edge structures per (discrete parameter values, level of detail), checked against the mesh
/// they are used for.
#[derive(Default)]
struct TopologyCache {
    map: Mutex<HashMap<Vec<i64>, Cached>>,
}

impl TopologyCache {
    fn get(&self, key: Vec<i64>, mesh: &Mesh) -> Result<Cached, String> {
        let matches =
            |t: &Cached| t.0 == mesh.triangles.len() && t.1.n_vertices() == mesh.positions.len();
        if let Ok(map) = self.map.lock()
            && let Some(t) = map.get(&key)
            && matches(t)
        {
            return Ok(t.clone());
        }
        let topo = Arc::new((
            mesh.triangles.len(),
            Topology::new(&mesh.triangles, mesh.positions.len()).map_err(|e| e.to_string())?,
        ));
        if let Ok(mut map) = self.map.lock() {
            if map.len() >= TOPOLOGY_CACHE {
                map.clear();
            }
            map.insert(key, topo.clone());
        }
        Ok(topo)
    }
}

/// Eq. 1 for one stage: a generator at one level of detail against masks of one size.
pub struct FitObjective {
    generator: &'static dyn Generator,
    lod: Lod,
    layout: Layout,
    masks: Vec<Mask>,
    reg_weight: f64,
    prior_weight: f64,
    parallel_render: bool,
    topologies: TopologyCache,
    windows: Option<Arc<WindowTerm>>,
    rim: Option<Arc<RimTerm>>,
}

impl FitObjective {
    /// An objective over `masks` (all the same size, one per view of `layout`). `reg_weight`
    /// multiplies the generator's regulariser; `parallel_render` lets each render use rayon
    /// (for stages that evaluate one point at a time).
    pub fn new(
        generator: &'static dyn Generator,
        lod: Lod,
        layout: Layout,
        masks: Vec<Mask>,
        reg_weight: f64,
        parallel_render: bool,
    ) -> FitObjective {
        FitObjective {
            generator,
            lod,
            layout,
            masks,
            reg_weight,
            prior_weight: 0.0,
            parallel_render,
            topologies: TopologyCache::default(),
            windows: None,
            rim: None,
        }
    }

    /// Adds the generator's shape prior ([`Generator::shape_prior`]) at `weight` (relative to
    /// the MSE); without it, none.
    pub fn with_shape_prior(mut self, weight: f64) -> FitObjective {
        self.prior_weight = weight;
        self
    }

    /// Adds the window term ([`super::windows`]): its value counts, its gradient is zero.
    pub fn with_windows(mut self, windows: Option<Arc<WindowTerm>>) -> FitObjective {
        self.windows = windows;
        self
    }

    /// Adds the rim term ([`super::rim`]), built for this objective's masks.
    pub fn with_rim(mut self, rim: Option<Arc<RimTerm>>) -> FitObjective {
        self.rim = rim;
        self
    }

    /// Whether the window term is part of this objective.
    pub fn has_windows(&self) -> bool {
        self.windows.is_some()
    }

    /// The layout of the optimisation vector.
    pub fn layout(&self) -> &Layout {
        &self.layout
    }

    /// Width and height of the stage's images.
    pub fn size(&self) -> (u32, u32) {
        self.masks
            .first()
            .map_or((1, 1), |m| (m.width(), m.height()))
    }

    /// View `v` of point `x` at the stage's size.
    pub fn view(&self, x: &[f64], v: usize) -> View {
        let (w, h) = self.size();
        self.layout.view_vars(x, v).view(w, h)
    }

    fn key(&self, gen_x: &[f64]) -> Vec<i64> {
        let mut key: Vec<i64> = self
            .generator
            .params()
            .iter()
            .zip(gen_x)
            .filter(|(s, _)| !s.kind.is_continuous())
            .map(|(_, &v)| v.round() as i64)
            .collect();
        key.push(self.lod.index() as i64);
        key
    }

    /// Loss and, when `grad` is given, its gradient. Errors become `+∞` in the callers.
    fn evaluate(&self, x: &[f64], grad: Option<&mut [f64]>) -> Result<f64, String> {
        let layout = &self.layout;
        if x.len() != layout.len() {
            return Err(format!(
                "point has {} values, expected {}",
                x.len(),
                layout.len()
            ));
        }
        let gen_x = &x[..layout.n_gen];
        let (mesh, vjp) = match grad {
            Some(_) => {
                let (m, v) = self
                    .generator
                    .generate_with_vjp(gen_x, self.lod)
                    .map_err(|e| e.to_string())?;
                (m, Some(v))
            }
            None => (
                self.generator
                    .generate(gen_x, self.lod)
                    .map_err(|e| e.to_string())?,
                None,
            ),
        };
        let topo = self.topologies.get(self.key(gen_x), &mesh)?;
        let topo = &topo.1;
        let (w, h) = self.size();
        let mut loss = 0.0;
        let mut grad = grad;
        SCRATCH.with(|cell| -> Result<(), String> {
            // A render that uses rayon may, while it waits, run another evaluation on this very
            // thread (work stealing); that one finds the slot taken and uses its own buffers.
            let mut own = None;
            let mut borrowed = cell.try_borrow_mut().ok();
            let scratch: &mut Scratch = match borrowed.as_deref_mut() {
                Some(s) => s,
                None => own.insert(Scratch::default()),
            };
            let n = layout.n_views;
            scratch.views.clear();
            scratch.views.extend((0..n).map(|v| self.view(x, v)));
            let eq1 = loss_for(&mut scratch.losses, w, h, n, self.parallel_render)?;
            // The rim term (value, and with the buffers its gradient).
            let rim = |views: &[View], grads| {
                self.rim.as_ref().map_or(0.0, |term| {
                    term.evaluate(
                        self.generator,
                        gen_x,
                        self.lod,
                        &mesh.positions,
                        views,
                        grads,
                    )
                })
            };
            let Some(g) = grad.as_deref_mut() else {
                loss += eq1
                    .value(topo, &mesh.positions, &scratch.views, &self.masks)
                    .map_err(|e| e.to_string())?;
                loss += rim(&scratch.views, None);
                return Ok(());
            };
            scratch.grad_pos.clear();
            scratch.grad_pos.resize(mesh.positions.len(), Vec3::ZERO);
            scratch.grad_views.clear();
            scratch.grad_views.resize(n, [0.0; N_VIEW_PARAMS]);
            // Eq. 1: the mean over views of the per-view MSE.
            loss += eq1
                .evaluate(
                    topo,
                    &mesh.positions,
                    &scratch.views,
                    &self.masks,
                    &mut scratch.grad_pos,
                    &mut scratch.grad_views,
                )
                .map_err(|e| e.to_string())?;
            loss += rim(
                &scratch.views,
                Some((&mut scratch.grad_pos, &mut scratch.grad_views)),
            );
            g.fill(0.0);
            for (v, (gv, view)) in scratch.grad_views.iter().zip(&scratch.views).enumerate() {
                pull_back_view(layout, x, v, gv, view.params.scale, g);
            }
            if let Some(vjp) = vjp.as_ref() {
                // Eq. 2: dLoss/dP = dLoss/dpos · dpos/dP.
                vjp.vjp(&scratch.grad_pos, &mut g[..layout.n_gen])
                    .map_err(|e| e.to_string())?;
            }
            Ok(())
        })?;
        if let Some(term) = &self.windows {
            // Value only (see the windows module): the views at the term's size.
            loss += term.value(self.generator, gen_x, |v, w, h| {
                layout.view_vars(x, v).view(w, h)
            })?;
        }
        for (weight, penalty) in [
            (self.reg_weight, Generator::regularizer as fn(_, _) -> _),
            (self.prior_weight, Generator::shape_prior),
        ] {
            if weight > 0.0 {
                let (r, rg) = penalty(self.generator, gen_x);
                loss += weight * r;
                if let Some(g) = grad.as_deref_mut() {
                    for (gi, ri) in g.iter_mut().zip(rg) {
                        *gi += weight * ri;
                    }
                }
            }
        }
        Ok(loss)
    }
}

impl Objective for FitObjective {
    fn value(&self, x: &[f64]) -> f64 {
        self.evaluate(x, None).unwrap_or(f64::INFINITY)
    }

    fn has_gradient(&self) -> bool {
        self.generator.differentiable()
    }

    fn value_grad(&self, x: &[f64], grad: &mut [f64]) -> f64 {
        match self.evaluate(x, Some(grad)) {
            Ok(v) => v,
            Err(_) => {
                grad.fill(0.0);
                f64::INFINITY
            }
        }
    }
}

/// Writes dL/d(view `v`'s values) into `grad` from the renderer's dL/d(view parameters) `gv`
/// ([`ViewParams::NAMES`](crate::camera::ViewParams::NAMES) order) at point `x`, whose object
/// scale is `scale`.
fn pull_back_view(
    layout: &Layout,
    x: &[f64],
    v: usize,
    gv: &[f64; N_VIEW_PARAMS],
    scale: f64,
    grad: &mut [f64],
) {
    use crate::camera::ViewParams as P;
    let vars = layout.view_vars(x, v);
    let j = super::views::renderer_angles_jacobian(vars.yaw, vars.pitch, vars.roll);
    // The renderer's angles are functions of all three of ours.
    let renderer = [P::YAW, P::PITCH, P::ROLL];
    for (m, slot) in [ViewSlot::Yaw, ViewSlot::Pitch, ViewSlot::Roll]
        .into_iter()
        .enumerate()
    {
        grad[layout.slot(v, slot)] = (0..3).map(|k| j[k][m] * gv[renderer[k]]).sum();
    }
    grad[layout.slot(v, ViewSlot::Tx)] = gv[P::TX];
    grad[layout.slot(v, ViewSlot::Ty)] = gv[P::TY];
    // d/d ln s = s · d/ds.
    grad[layout.slot(v, ViewSlot::LogScale)] = gv[P::SCALE] * scale;
    if layout.fit_fov {
        grad[layout.slot(v, ViewSlot::FovY)] = gv[P::FOV_Y];
    }
}

/// Renders the silhouette coverage of `mesh` through `view` (row-major, `view.width ×
/// view.height`).
pub fn render_coverage(mesh: &Mesh, view: &View) -> Result<Vec<f32>, String> {
    let topo = Topology::new(&mesh.triangles, mesh.positions.len()).map_err(|e| e.to_string())?;
    let mut r = Renderer::new(view.width, view.height).map_err(|e| e.to_string())?;
    Ok(r.forward(&topo, &mesh.positions, view)
        .map_err(|e| e.to_string())?
        .to_vec())
}

/// `mask` reduced so that its longer side is at most `max_side` (box filter over the source
/// pixels whose centres fall in each target pixel; a target pixel is don't-care when most of
/// its sources are). Smaller masks are returned as they are.
pub fn resample_mask(mask: &Mask, max_side: u32) -> Mask {
    let (w, h) = (mask.width(), mask.height());
    let long = w.max(h);
    if long <= max_side || max_side == 0 {
        return mask.clone();
    }
    let f = f64::from(max_side) / f64::from(long);
    let tw = ((f64::from(w) * f).round() as u32).max(1);
    let th = ((f64::from(h) * f).round() as u32).max(1);
    let (sx, sy) = (f64::from(w) / f64::from(tw), f64::from(h) / f64::from(th));
    let mut sum = vec![0.0f64; tw as usize * th as usize];
    let mut count = vec![0u32; tw as usize * th as usize];
    let mut dont = vec![0u32; tw as usize * th as usize];
    for (i, &v) in mask.values().iter().enumerate() {
        let (x, y) = (i % w as usize, i / w as usize);
        let tx = (((x as f64 + 0.5) / sx) as usize).min(tw as usize - 1);
        let ty = (((y as f64 + 0.5) / sy) as usize).min(th as usize - 1);
        let t = ty * tw as usize + tx;
        if v == Mask::DONT_CARE {
            dont[t] += 1;
        } else {
            sum[t] += f64::from(v);
            count[t] += 1;
        }
    }
    let values = (0..sum.len())
        .map(|t| {
            if count[t] == 0 || dont[t] > count[t] {
                Mask::DONT_CARE
            } else {
                (sum[t] / f64::from(count[t])) as f32
            }
        })
        .collect();
    // Every value is a mean of values in [0, 1] or DONT_CARE, and the size is valid.
    Mask::new(tw, th, values).unwrap_or_else(|_| mask.clone())
}
