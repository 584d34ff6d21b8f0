//! Silhouette rasterizer: anti-aliased coverage from tiny-skia and exact edge-sampling gradients.
//!
//! The paper renders only silhouette masks (§3.2, eq. 1) and gets vertex gradients by edge
//! sampling (§4.4, Li et al. 2018). Here both halves are a forward/gradient pair over flat
//! buffers:
//!
//! - **Forward** ([`Renderer::forward`]): project the welded mesh through a [`View`], orient every
//!   projected triangle positively on screen and add up its three directed edges per mesh edge.
//!   An edge shared by two triangles lying on opposite sides of it cancels; what remains (contour
//!   and boundary edges, a few per cent of all edges, with multiplicity) is a closed 1-cycle whose
//!   winding number at a point is the number of triangles covering it. Filled by tiny-skia with
//!   the non-zero rule it is exactly the union of the triangles, anti-aliased — at a fraction of
//!   the cost of filling every triangle.
//! - **Backward** ([`Renderer::backward`]): for an adjoint dL/dI per pixel, the derivative of the
//!   box-filtered coverage is a line integral over the visible silhouette boundary of
//!   adjoint × outward normal velocity. A point of a remaining edge is visible boundary when the
//!   winding number just outside it is 0 (its inside has ≥ 1 by construction), which also
//!   removes silhouette edges hidden behind other geometry. Each edge is cut at pixel
//!   boundaries and where other silhouette edges cross it (visibility only changes there, so
//!   each piece is tested once, at its midpoint); within a piece the adjoint is constant and the
//!   velocity linear along the edge, so the integral is exact (no Monte Carlo) and splits
//!   between the edge's two vertices by position along the edge. The screen-space gradients are
//!   then pulled back through the projection to object-space vertex positions and the
//!   [`ViewParams`](crate::camera::ViewParams).
//!
//! The gradient is that of the exact area coverage; tiny-skia's coverage approximates it with
//! 4×4 sub-samples (mean error ≈ 0.03 per boundary pixel, unbiased: see
//! `tests/render_forward.rs`), which is what finite differences of the product loss see.
//!
//! Also here: [`MultiViewLoss`] (eq. 1 over several views: the one implementation, which the
//! fit, the benches and the tests run),
//! [`LabelRenderer`] (front-most label per sub-sample, forward only), [`testmesh`] (known
//! shapes) and [`bench`](mod@bench) (the benchmark workload, also for timing in wasm).
//!
//! **The caller allocates**: a [`Renderer`] owns every scratch buffer for one image size and
//! reuses it on every call, so the per-iteration loop of a fit does not allocate (after the first
//! call has grown the buffers; tiny-skia clones its path once per fill). A [`Topology`] holds the
//! mesh's edge structure, computed once per triangle list.
//!
//! Determinism: every parallel stage (views in [`MultiViewLoss`]; inside one render, projection
//! per vertex and integrals per silhouette edge) writes one slot per item and the reductions run
//! sequentially in a fixed order, so results are bit-identical with and without rayon. Image
//! tiles are not split across threads: a whole render takes well under a millisecond at the
//! fit's sizes, less than rayon's overhead would eat.

pub mod bench;
pub mod labels;
pub mod multiview;
pub mod testmesh;

pub use labels::LabelRenderer;
pub use multiview::MultiViewLoss;

use crate::camera::{N_VIEW_PARAMS, View};
use glam::{DMat3, DVec2, DVec3, Vec3};
use rayon::prelude::*;
use std::fmt;

/// A render that cannot be done; the message says why.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderError(pub String);

impl fmt::Display for RenderError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for RenderError {}

impl From<crate::camera::CameraError> for RenderError {
    fn from(e: crate::camera::CameraError) -> Self {
        RenderError(e.0)
    }
}

/// Largest image side the renderer accepts. tiny-skia anti-aliases only while the path bounds
/// (the image plus our 1 px clamping margin) times its 4 sub-samples fit in 16 bits, i.e. below
/// 8191 px; beyond it silently fills aliased. Kept well below that.
pub const MAX_SIDE: u32 = 8000;

/// Largest projected coordinate (pixels) accepted.
const MAX_COORD: f64 = 1e8;

/// Distance (pixels) from a boundary point to where its outside winding number is sampled.
const OUTSIDE_PROBE: f64 = 1e-4;

/// Most visibility cuts kept within one pixel crossing of an edge.
const MAX_CUTS: usize = 8;

/// Edge structure of a triangle list: unique undirected edges and, per triangle, its three
/// edges with their direction. Depends only on the indices, so a fit computes it once per
/// discrete mesh structure and reuses it while positions change.
#[derive(Clone, Debug, Default)]
pub struct Topology {
    n_vertices: usize,
    /// Unique edges `[lo, hi]`, `lo < hi`.
    edges: Vec<[u32; 2]>,
    /// Triangles kept (those with three distinct indices).
    tris: Vec<[u32; 3]>,
    /// Per kept triangle, for corners `k → k+1`: `edge << 1 | 1` when it runs `hi → lo`.
    tri_edges: Vec<[u32; 3]>,
}

impl Topology {
    /// Builds the edge structure. Errors on an index `>= n_vertices`; triangles with a repeated
    /// index cover no area and are dropped.
    pub fn new(triangles: &[[u32; 3]], n_vertices: usize) -> Result<Topology, RenderError> {
        if n_vertices > u32::MAX as usize / 2 || triangles.len() > u32::MAX as usize / 4 {
            return Err(RenderError(format!(
                "mesh with {n_vertices} vertices / {} triangles is too large",
                triangles.len()
            )));
        }
        if let Some(t) = triangles
            .iter()
            .find(|t| t.iter().any(|&i| i as usize >= n_vertices))
        {
            return Err(RenderError(format!(
                "triangle {t:?} indexes past {n_vertices} vertices"
            )));
        }
        let tris: Vec<[u32; 3]> = triangles
            .iter()
            .copied()
            .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
            .collect();
        // Sort (lo, hi, slot) triples so equal edges are adjacent; slot = 3·triangle + corner.
        let mut keyed: Vec<(u32, u32, u32)> = Vec::with_capacity(3 * tris.len());
        for (ti, t) in tris.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                keyed.push((a.min(b), a.max(b), (3 * ti + k) as u32));
            }
        }
        keyed.sort_unstable();
        let mut edges: Vec<[u32; 2]> = Vec::new();
        let mut tri_edges = vec![[0u32; 3]; tris.len()];
        for (i, &(lo, hi, slot)) in keyed.iter().enumerate() {
            if i == 0 || (keyed[i - 1].0, keyed[i - 1].1) != (lo, hi) {
                edges.push([lo, hi]);
            }
            let e = (edges.len() - 1) as u32;
            let (ti, k) = (slot as usize / 3, slot as usize % 3);
            let reversed = u32::from(tris[ti][k] > tris[ti][(k + 1) % 3]);
            tri_edges[ti][k] = (e << 1) | reversed;
        }
        Ok(Topology {
            n_vertices,
            edges,
            tris,
            tri_edges,
        })
    }

    /// Number of vertices the triangles index.
    pub fn n_vertices(&self) -> usize {
        self.n_vertices
    }

    /// Number of unique edges.
    pub fn n_edges(&self) -> usize {
        self.edges.len()
    }

    /// Number of triangles kept (non-degenerate by index).
    pub fn n_triangles(&self) -> usize {
        self.tris.len()
    }
}

/// A silhouette edge left after cancellation: `a → b` with the covered side on its left
/// (positive cross product), `m` copies.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct RemEdge {
    a: u32,
    b: u32,
    m: u32,
}

/// Renders silhouettes of one image size and their gradients, owning all scratch buffers.
pub struct Renderer {
    width: u32,
    height: u32,
    parallel: bool,
    // Per-vertex projection (filled by `forward`, read by `backward`).
    screen: Vec<DVec2>,
    cam: Vec<DVec3>,
    // Edge cancellation.
    net: Vec<i32>,
    rem: Vec<RemEdge>,
    // Loop building for the fill: outgoing edge tokens per start vertex (CSR).
    out_start: Vec<u32>,
    out_tok: Vec<u32>,
    cursor: Vec<u32>,
    path: Option<tiny_skia::PathBuilder>,
    mask: tiny_skia::Mask,
    coverage: Vec<f32>,
    // Backward: rows → edges crossing them (CSR), per-edge vertex weights, screen gradients.
    row_start: Vec<u32>,
    row_edges: Vec<u32>,
    edge_w: Vec<[f64; 2]>,
    grad_screen: Vec<DVec2>,
    /// The view and vertex count of the last successful forward, which backward must match.
    last: Option<(View, usize)>,
}

impl fmt::Debug for Renderer {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Renderer")
            .field("width", &self.width)
            .field("height", &self.height)
            .field("parallel", &self.parallel)
            .finish_non_exhaustive()
    }
}

impl Renderer {
    /// A renderer for `width × height` images. Errors on a zero or too large size.
    pub fn new(width: u32, height: u32) -> Result<Renderer, RenderError> {
        if width == 0 || height == 0 || width > MAX_SIDE || height > MAX_SIDE {
            return Err(RenderError(format!(
                "image size {width}×{height} is not within 1..={MAX_SIDE} a side"
            )));
        }
        let mask = tiny_skia::Mask::new(width, height)
            .ok_or_else(|| RenderError(format!("cannot allocate a {width}×{height} mask")))?;
        Ok(Renderer {
            width,
            height,
            parallel: false,
            screen: Vec::new(),
            cam: Vec::new(),
            net: Vec::new(),
            rem: Vec::new(),
            out_start: Vec::new(),
            out_tok: Vec::new(),
            cursor: Vec::new(),
            path: Some(tiny_skia::PathBuilder::new()),
            mask,
            coverage: vec![0.0; width as usize * height as usize],
            row_start: Vec::new(),
            row_edges: Vec::new(),
            edge_w: Vec::new(),
            grad_screen: Vec::new(),
            last: None,
        })
    }

    /// Image width.
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Image height.
    pub fn height(&self) -> u32 {
        self.height
    }

    /// Uses rayon inside one render (projection, edge integrals). Results are bit-identical
    /// either way.
    pub fn set_parallel(&mut self, parallel: bool) {
        self.parallel = parallel;
    }

    /// The coverage of the last forward render, row-major, in `[0, 1]`.
    pub fn coverage(&self) -> &[f32] {
        &self.coverage
    }

    /// Number of silhouette edges (after cancellation) in the last forward render.
    pub fn n_silhouette_edges(&self) -> usize {
        self.rem.len()
    }

    /// Renders the anti-aliased silhouette coverage of `positions` (object space, indexed by
    /// `topo`) seen through `view`. Errors on a size mismatch, non-finite positions or a vertex
    /// on or behind the camera plane (camera inside or touching the object). An empty mesh or
    /// one entirely outside the image gives an all-zero image.
    pub fn forward(
        &mut self,
        topo: &Topology,
        positions: &[Vec3],
        view: &View,
    ) -> Result<&[f32], RenderError> {
        self.last = None;
        self.project(topo, positions, view)?;
        self.cancel_edges(topo);
        self.fill();
        self.last = Some((*view, positions.len()));
        Ok(&self.coverage)
    }

    fn project(
        &mut self,
        topo: &Topology,
        positions: &[Vec3],
        view: &View,
    ) -> Result<(), RenderError> {
        if view.width != self.width || view.height != self.height {
            return Err(RenderError(format!(
                "view is {}×{} but the renderer is {}×{}",
                view.width, view.height, self.width, self.height
            )));
        }
        if positions.len() != topo.n_vertices {
            return Err(RenderError(format!(
                "{} positions for a topology of {} vertices",
                positions.len(),
                topo.n_vertices
            )));
        }
        view.params.validate()?;
        if !(view.pose.rotation.is_finite() && view.pose.position.is_finite()) {
            return Err(RenderError("camera pose is not finite".into()));
        }
        let n = positions.len();
        self.screen.resize(n, DVec2::ZERO);
        self.cam.resize(n, DVec3::ZERO);
        let proj = view.projector();
        let one = |p: &Vec3, sc: &mut DVec2, cm: &mut DVec3| {
            *cm = proj.to_camera(*p);
            *sc = proj.to_pixel(*cm);
        };
        if self.parallel {
            positions
                .par_iter()
                .zip(self.screen.par_iter_mut().zip(self.cam.par_iter_mut()))
                .for_each(|(p, (sc, cm))| one(p, sc, cm));
        } else {
            for ((p, sc), cm) in positions.iter().zip(&mut self.screen).zip(&mut self.cam) {
                one(p, sc, cm);
            }
        }
        if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
            return Err(RenderError(format!("vertex {i} is not finite")));
        }
        // Clipping against the near plane is deliberately not supported: a fitted object is in
        // front of its camera, and a vertex behind it means the camera is inside the object.
        let near = 1e-9 * (1.0 + view.pose.position.length());
        if let Some(i) = self
            .cam
            .iter()
            .position(|c| (-c.z).partial_cmp(&near) != Some(std::cmp::Ordering::Greater))
        {
            return Err(RenderError(format!(
                "vertex {i} is on or behind the camera plane (camera inside or touching the object)"
            )));
        }
        // Far beyond the image, f64 can no longer step an edge pixel by pixel (a vertex there
        // sits almost on the camera plane).
        if let Some(i) = self
            .screen
            .iter()
            .position(|p| !p.is_finite() || p.abs().max_element() > MAX_COORD)
        {
            return Err(RenderError(format!(
                "vertex {i} projects more than {MAX_COORD:e} pixels away (almost on the camera plane)"
            )));
        }
        Ok(())
    }

    /// Orients every triangle positively on screen and keeps the edges that do not cancel.
    fn cancel_edges(&mut self, topo: &Topology) {
        self.net.clear();
        self.net.resize(topo.edges.len(), 0);
        let screen = &self.screen;
        for (t, te) in topo.tris.iter().zip(&topo.tri_edges) {
            let (a, b, c) = (
                screen[t[0] as usize],
                screen[t[1] as usize],
                screen[t[2] as usize],
            );
            let area = (b - a).perp_dot(c - a);
            // Zero-area triangles cover nothing; leaving them out is exact.
            let orient = if area > 0.0 {
                1
            } else if area < 0.0 {
                -1
            } else {
                continue;
            };
            for &code in te {
                let sign = if code & 1 == 0 { 1 } else { -1 };
                self.net[(code >> 1) as usize] += orient * sign;
            }
        }
        self.rem.clear();
        for (e, &n) in topo.edges.iter().zip(&self.net) {
            if n > 0 {
                self.rem.push(RemEdge {
                    a: e[0],
                    b: e[1],
                    m: n as u32,
                });
            } else if n < 0 {
                self.rem.push(RemEdge {
                    a: e[1],
                    b: e[0],
                    m: n.unsigned_abs(),
                });
            }
        }
    }

    /// Chains the remaining edges into closed loops and fills them with the non-zero rule.
    fn fill(&mut self) {
        let n = self.screen.len();
        self.out_start.clear();
        self.out_start.resize(n + 1, 0);
        for e in &self.rem {
            self.out_start[e.a as usize + 1] += e.m;
        }
        for i in 0..n {
            self.out_start[i + 1] += self.out_start[i];
        }
        self.cursor.clear();
        self.cursor.extend_from_slice(&self.out_start[..n]);
        self.out_tok.clear();
        self.out_tok.resize(self.out_start[n] as usize, 0);
        for (k, e) in self.rem.iter().enumerate() {
            for _ in 0..e.m {
                let c = &mut self.cursor[e.a as usize];
                self.out_tok[*c as usize] = k as u32;
                *c += 1;
            }
        }
        self.cursor.copy_from_slice(&self.out_start[..n]);

        let mut pb = self.path.take().unwrap_or_default();
        pb.clear();
        // Clamp to the image plus a margin: exact inside it (see `push_clamped`), and it keeps
        // tiny-skia's fixed-point arithmetic away from huge coordinates.
        let bounds = [
            -1.0,
            -1.0,
            f64::from(self.width) + 1.0,
            f64::from(self.height) + 1.0,
        ];
        // A balanced directed multigraph decomposes into closed walks: a walk on unused edges
        // can only get stuck at its start.
        for k0 in 0..self.rem.len() {
            let s = self.rem[k0].a as usize;
            while self.cursor[s] < self.out_start[s + 1] {
                let p0 = clamp_pt(self.screen[s], bounds);
                pb.move_to(p0.x as f32, p0.y as f32);
                let mut v = s;
                while self.cursor[v] < self.out_start[v + 1] {
                    let k = self.out_tok[self.cursor[v] as usize] as usize;
                    self.cursor[v] += 1;
                    let w = self.rem[k].b as usize;
                    push_clamped(&mut pb, self.screen[v], self.screen[w], bounds);
                    v = w;
                    if v == s {
                        break;
                    }
                }
                pb.close();
            }
        }
        self.mask.clear();
        match pb.finish() {
            Some(path) => {
                self.mask.fill_path(
                    &path,
                    tiny_skia::FillRule::Winding,
                    true,
                    tiny_skia::Transform::identity(),
                );
                self.path = Some(path.clear());
            }
            None => self.path = Some(tiny_skia::PathBuilder::new()),
        }
        for (c, &m) in self.coverage.iter_mut().zip(self.mask.data()) {
            *c = f32::from(m) * (1.0 / 255.0);
        }
    }

    /// Given `adjoint` = dL/dI per pixel (row-major, the size of the image) for the image of the
    /// last [`Renderer::forward`] call, **adds** dL/d(object-space vertex position) into
    /// `grad_pos` and dL/d(view parameter) into `grad_view` (in
    /// [`ViewParams::NAMES`](crate::camera::ViewParams::NAMES) order). `topo`, `positions` and
    /// `view` must be the ones given to that forward call.
    pub fn backward(
        &mut self,
        topo: &Topology,
        positions: &[Vec3],
        view: &View,
        adjoint: &[f32],
        grad_pos: &mut [Vec3],
        grad_view: &mut [f64; N_VIEW_PARAMS],
    ) -> Result<(), RenderError> {
        match self.last {
            Some((v, n)) if v == *view && n == positions.len() && n == topo.n_vertices => {}
            _ => {
                return Err(RenderError(
                    "backward needs a successful forward with the same view and mesh first".into(),
                ));
            }
        }
        let (w, h) = (self.width as usize, self.height as usize);
        if adjoint.len() != w * h {
            return Err(RenderError(format!(
                "adjoint has {} values for a {w}×{h} image",
                adjoint.len()
            )));
        }
        if grad_pos.len() != positions.len() {
            return Err(RenderError(format!(
                "gradient buffer has {} entries for {} vertices",
                grad_pos.len(),
                positions.len()
            )));
        }
        if let Some(i) = adjoint.iter().position(|a| !a.is_finite()) {
            return Err(RenderError(format!("adjoint at pixel {i} is not finite")));
        }
        self.bucket_rows();
        self.edge_integrals(adjoint);
        self.grad_screen.clear();
        self.grad_screen.resize(positions.len(), DVec2::ZERO);
        for (e, wts) in self.rem.iter().zip(&self.edge_w) {
            let d = self.screen[e.b as usize] - self.screen[e.a as usize];
            // Outward normal scaled by the edge length: (d.y, −d.x) points to the right of
            // a → b, away from the covered left side.
            let nrm = DVec2::new(d.y, -d.x);
            self.grad_screen[e.a as usize] += wts[0] * nrm;
            self.grad_screen[e.b as usize] += wts[1] * nrm;
        }
        self.pull_back(positions, view, grad_pos, grad_view);
        Ok(())
    }

    /// Registers every non-horizontal silhouette edge in the pixel rows it spans (rows −1 and
    /// H fold into the first and last), for winding queries.
    fn bucket_rows(&mut self) {
        let h = self.height as usize;
        let hf = self.height as f64;
        self.row_start.clear();
        self.row_start.resize(h + 1, 0);
        // Horizontal edges never change a winding number but can hide part of another edge,
        // so they are registered too (for the visibility cuts).
        let span = |a: DVec2, b: DVec2| -> Option<(usize, usize)> {
            let (y0, y1) = (a.y.min(b.y).max(-1.0), a.y.max(b.y).min(hf + 1.0));
            if y0 > y1 {
                return None;
            }
            let r0 = (y0.floor().max(0.0) as usize).min(h - 1);
            let r1 = (y1.floor().max(0.0) as usize).min(h - 1);
            Some((r0, r1))
        };
        for e in &self.rem {
            if let Some((r0, r1)) = span(self.screen[e.a as usize], self.screen[e.b as usize]) {
                for r in r0..=r1 {
                    self.row_start[r + 1] += 1;
                }
            }
        }
        for r in 0..h {
            self.row_start[r + 1] += self.row_start[r];
        }
        self.row_edges.clear();
        self.row_edges.resize(self.row_start[h] as usize, 0);
        // Fill using row_start[r] as a moving cursor, then shift back.
        for (k, e) in self.rem.iter().enumerate() {
            if let Some((r0, r1)) = span(self.screen[e.a as usize], self.screen[e.b as usize]) {
                for r in r0..=r1 {
                    self.row_edges[self.row_start[r] as usize] = k as u32;
                    self.row_start[r] += 1;
                }
            }
        }
        for r in (1..=h).rev() {
            self.row_start[r] = self.row_start[r - 1];
        }
        self.row_start[0] = 0;
    }

    /// Per silhouette edge, the adjoint-weighted integrals of `(1 − t)` and `t` over its
    /// visible pixel crossings.
    fn edge_integrals(&mut self, adjoint: &[f32]) {
        let ctx = EdgeCtx {
            screen: &self.screen,
            rem: &self.rem,
            row_start: &self.row_start,
            row_edges: &self.row_edges,
            adjoint,
            width: self.width,
            height: self.height,
        };
        if self.parallel {
            self.rem
                .par_iter()
                .map(|e| ctx.integrate(e))
                .collect_into_vec(&mut self.edge_w);
        } else {
            self.edge_w.clear();
            self.edge_w
                .extend(self.rem.iter().map(|e| ctx.integrate(e)));
        }
    }

    /// Chain rule from screen-space gradients to object-space positions and view parameters.
    fn pull_back(
        &self,
        positions: &[Vec3],
        view: &View,
        grad_pos: &mut [Vec3],
        grad_view: &mut [f64; N_VIEW_PARAMS],
    ) {
        let chain = ScreenChain::new(view);
        let mut acc = [0.0f64; N_VIEW_PARAMS];
        for (i, &g) in self.grad_screen.iter().enumerate() {
            if g == DVec2::ZERO {
                continue;
            }
            grad_pos[i] += chain.add(positions[i], self.cam[i], g, &mut acc);
        }
        for (g, a) in grad_view.iter_mut().zip(acc) {
            *g += a;
        }
    }
}

/// The chain rule of a [`View`]'s projection: from dL/d(pixel position) of a projected
/// object-space point to dL/d(that point) and dL/d(view parameters). The renderer's backward
/// pass and every other image-space term of a fit (the rim's edge) pull back through it.
pub struct ScreenChain {
    r: DMat3,
    dr: [DMat3; 3],
    s: f64,
    rc: DMat3,
    f: f64,
    h: f64,
    df_dfov: f64,
}

impl ScreenChain {
    /// The chain rule of `view`.
    pub fn new(view: &View) -> ScreenChain {
        let [r, dr_yaw, dr_pitch, dr_roll] = view.params.rotation_and_derivatives();
        let h = f64::from(view.height);
        let half = 0.5 * view.params.fov_y;
        ScreenChain {
            r,
            dr: [dr_yaw, dr_pitch, dr_roll],
            s: view.params.scale,
            rc: view.pose.rotation,
            f: view.focal(),
            h,
            df_dfov: -h / (4.0 * half.sin() * half.sin()),
        }
    }

    /// For object-space point `p`, at camera-space `c` (its
    /// [`Projector::to_camera`](crate::camera::Projector::to_camera)), with dL/d(its pixel
    /// position) `g`: **adds** dL/d(view parameters) into `acc` (in
    /// [`ViewParams::NAMES`](crate::camera::ViewParams::NAMES) order) and returns dL/dp.
    pub fn add(&self, p: Vec3, c: DVec3, g: DVec2, acc: &mut [f64; N_VIEW_PARAMS]) -> Vec3 {
        let (r, s, f, h) = (self.r, self.s, self.f, self.h);
        let z = -c.z;
        // x = cx + f·c.x/z, y = cy − f·c.y/z with z = −c.z.
        let dc = DVec3::new(
            f * g.x / z,
            -f * g.y / z,
            f * (g.x * c.x - g.y * c.y) / (z * z),
        );
        let dw = self.rc * dc;
        let p = p.as_dvec3();
        acc[0] += dw.dot(s * (self.dr[0] * p));
        acc[1] += dw.dot(s * (self.dr[1] * p));
        acc[2] += dw.dot(s * (self.dr[2] * p));
        acc[3] += dw.x;
        acc[4] += dw.y;
        acc[5] += dw.z;
        acc[6] += dw.dot(r * p);
        acc[7] += (g.x * c.x / z - g.y * c.y / z) * self.df_dfov;
        acc[8] += h * g.x;
        acc[9] += h * g.y;
        (s * (r.transpose() * dw)).as_vec3()
    }
}

/// Read-only inputs of the per-edge integration, shared across threads.
struct EdgeCtx<'a> {
    screen: &'a [DVec2],
    rem: &'a [RemEdge],
    row_start: &'a [u32],
    row_edges: &'a [u32],
    adjoint: &'a [f32],
    width: u32,
    height: u32,
}

impl EdgeCtx<'_> {
    /// Winding number of the silhouette cycle at `q` (ray towards +x, half-open in y).
    fn winding(&self, q: DVec2) -> i32 {
        let h = self.height as usize;
        let row = (q.y.floor().max(0.0) as usize).min(h - 1);
        let mut w = 0i32;
        for &k in &self.row_edges[self.row_start[row] as usize..self.row_start[row + 1] as usize] {
            let e = self.rem[k as usize];
            let (a, b) = (self.screen[e.a as usize], self.screen[e.b as usize]);
            let up = a.y <= q.y && q.y < b.y;
            let down = b.y <= q.y && q.y < a.y;
            if up || down {
                let x = a.x + (q.y - a.y) * (b.x - a.x) / (b.y - a.y);
                if x > q.x {
                    w += if up { e.m as i32 } else { -(e.m as i32) };
                }
            }
        }
        w
    }

    /// The parameters `t0 < cuts… < t1` where other silhouette edges cross `a + t·d` inside
    /// pixel row `row`, sorted, written into `out`; returns how many were written. Beyond
    /// [`MAX_CUTS`] crossings in one pixel the extra cuts are dropped (midpoint visibility).
    #[allow(
        clippy::too_many_arguments,
        reason = "hot inner helper over plain values"
    )]
    fn cuts(
        &self,
        e: &RemEdge,
        a: DVec2,
        d: DVec2,
        t0: f64,
        t1: f64,
        row: usize,
        out: &mut [f64; MAX_CUTS + 2],
    ) -> usize {
        out[0] = t0;
        let mut n = 1;
        for &k in &self.row_edges[self.row_start[row] as usize..self.row_start[row + 1] as usize] {
            let o = self.rem[k as usize];
            if o.a == e.a && o.b == e.b {
                continue;
            }
            let c = self.screen[o.a as usize];
            let f = self.screen[o.b as usize] - c;
            let den = d.perp_dot(f);
            if den == 0.0 {
                continue;
            }
            let ac = c - a;
            let t = ac.perp_dot(f) / den;
            let u = ac.perp_dot(d) / den;
            if t > t0 && t < t1 && (0.0..=1.0).contains(&u) && n <= MAX_CUTS {
                out[n] = t;
                n += 1;
            }
        }
        out[1..n].sort_unstable_by(f64::total_cmp);
        out[n] = t1;
        n + 1
    }

    /// `[∫ adj·(1 − t) dt, ∫ adj·t dt]` over the visible pixel crossings of one edge.
    fn integrate(&self, e: &RemEdge) -> [f64; 2] {
        let (a, b) = (self.screen[e.a as usize], self.screen[e.b as usize]);
        let d = b - a;
        let len = d.length();
        if len == 0.0 {
            return [0.0, 0.0];
        }
        let (wf, hf) = (f64::from(self.width), f64::from(self.height));
        // Liang–Barsky clip of t ∈ [0, 1] to the image rectangle.
        let (mut t_in, mut t_out) = (0.0f64, 1.0f64);
        for (p, q) in [(-d.x, a.x), (d.x, wf - a.x), (-d.y, a.y), (d.y, hf - a.y)] {
            if p == 0.0 {
                if q < 0.0 {
                    return [0.0, 0.0];
                }
            } else {
                let r = q / p;
                if p < 0.0 {
                    t_in = t_in.max(r);
                } else {
                    t_out = t_out.min(r);
                }
            }
        }
        if t_in >= t_out {
            return [0.0, 0.0];
        }
        let probe = DVec2::new(d.y, -d.x) * (OUTSIDE_PROBE / len);
        let first = a + d * t_in;
        // Next integer grid line along x and y, as a parameter t, and the step per line.
        let next_line = |start: f64, delta: f64, origin: f64| -> (f64, f64, f64) {
            if delta > 0.0 {
                let c = start.floor() + 1.0;
                (c, 1.0, (c - origin) / delta)
            } else if delta < 0.0 {
                let c = start.ceil() - 1.0;
                (c, -1.0, (c - origin) / delta)
            } else {
                (0.0, 0.0, f64::INFINITY)
            }
        };
        let (mut gx, sx, mut tx) = next_line(first.x, d.x, a.x);
        let (mut gy, sy, mut ty) = next_line(first.y, d.y, a.y);
        let (mut ia, mut ib) = (0.0f64, 0.0f64);
        let mut t0 = t_in;
        let w = self.width as usize;
        while t0 < t_out {
            let t1 = tx.min(ty).min(t_out);
            if t1 > t0 {
                let mid = a + d * (0.5 * (t0 + t1));
                let px = (mid.x.floor().max(0.0) as usize).min(w - 1);
                let py = (mid.y.floor().max(0.0) as usize).min(self.height as usize - 1);
                let adj = f64::from(self.adjoint[py * w + px]);
                if adj != 0.0 {
                    // Visibility can only change where another silhouette edge crosses this
                    // one: cut the crossing there and test each piece at its midpoint.
                    let mut cuts = [0.0f64; MAX_CUTS + 2];
                    let n = self.cuts(e, a, d, t0, t1, py, &mut cuts);
                    for piece in cuts[..n].windows(2) {
                        let (u0, u1) = (piece[0], piece[1]);
                        if self.winding(a + d * (0.5 * (u0 + u1)) + probe) == 0 {
                            let (l, sq) = (u1 - u0, 0.5 * (u1 * u1 - u0 * u0));
                            ia += adj * (l - sq);
                            ib += adj * sq;
                        }
                    }
                }
            }
            if tx <= t1 {
                gx += sx;
                tx = (gx - a.x) / d.x;
            }
            if ty <= t1 {
                gy += sy;
                ty = (gy - a.y) / d.y;
            }
            t0 = t1;
        }
        [ia, ib]
    }
}

fn clamp_pt(p: DVec2, b: [f64; 4]) -> DVec2 {
    DVec2::new(p.x.clamp(b[0], b[2]), p.y.clamp(b[1], b[3]))
}

/// Appends the segment `p → q` (whose start is already in the path) clamped to the rectangle
/// `b`. Cutting the segment where it crosses the rectangle's four lines first makes each piece
/// map to a straight piece under the clamp (the identity inside, a projection on a side, a point
/// at a corner); the clamp is then a retraction onto the rectangle that never sweeps a boundary
/// piece across the interior, so the winding number inside is unchanged (Skia's edge clipper
/// does the same).
fn push_clamped(pb: &mut tiny_skia::PathBuilder, p: DVec2, q: DVec2, b: [f64; 4]) {
    let d = q - p;
    let mut cuts = [f64::INFINITY; 4];
    let mut n = 0;
    for (lim, from, delta) in [
        (b[0], p.x, d.x),
        (b[2], p.x, d.x),
        (b[1], p.y, d.y),
        (b[3], p.y, d.y),
    ] {
        if delta != 0.0 {
            let t = (lim - from) / delta;
            if t > 0.0 && t < 1.0 {
                cuts[n] = t;
                n += 1;
            }
        }
    }
    let cuts = &mut cuts[..n];
    cuts.sort_unstable_by(f64::total_cmp);
    for &t in cuts.iter() {
        let c = clamp_pt(p + d * t, b);
        pb.line_to(c.x as f32, c.y as f32);
    }
    let c = clamp_pt(q, b);
    pb.line_to(c.x as f32, c.y as f32);
}
