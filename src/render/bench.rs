//! The renderer's benchmark workload as a library type, so the native bench binary
//! (`benches/render.rs`) and the page (timing it in wasm with the browser's clock) run the same
//! thing. No timing here: `std::time::Instant` panics on wasm32.
//!
//! The scene: a welded, closed, thick-walled cup ([`testmesh::cup`]) of about 3.8k or 20k
//! vertices, seen from `n_views` turntable cameras; each target mask is the cup slightly moved
//! and scaled, so the adjoint is non-zero along the whole silhouette as in a fit.

use super::testmesh;
use super::{MultiViewLoss, RenderError, Renderer, Topology};
use crate::camera::{CameraPose, N_VIEW_PARAMS, View};
use crate::generators::Mesh;
use crate::mask::Mask;
use glam::{DVec3, Vec3};

/// Mesh sizes of the benchmark.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BenchMesh {
    /// About 3.8k vertices (the paper's LOW dish is ~3k).
    Small,
    /// About 20k vertices.
    Large,
}

/// One benchmark configuration with all its buffers.
#[derive(Debug)]
pub struct BenchScene {
    mesh: Mesh,
    topo: Topology,
    views: Vec<View>,
    masks: Vec<Mask>,
    renderer: Renderer,
    loss: MultiViewLoss,
    adjoint: Vec<f32>,
    grad_pos: Vec<Vec3>,
    grad_view: [f64; N_VIEW_PARAMS],
    grad_views: Vec<[f64; N_VIEW_PARAMS]>,
}

impl BenchScene {
    /// Builds the scene for `size × size` images and `n_views` views (≥ 1). Errors on a bad
    /// size or no views.
    pub fn new(mesh: BenchMesh, size: u32, n_views: usize) -> Result<BenchScene, RenderError> {
        let mesh = match mesh {
            BenchMesh::Small => testmesh::cup(27, 64),
            BenchMesh::Large => testmesh::cup(75, 128),
        };
        if n_views == 0 {
            return Err(RenderError("the benchmark needs at least one view".into()));
        }
        let topo = Topology::new(&mesh.triangles, mesh.positions.len())?;
        let mut views = Vec::with_capacity(n_views);
        for i in 0..n_views {
            let mut v = View::turntable(size, size, 0.5, 3.0, 0.5, DVec3::ZERO)?;
            v.pose = CameraPose::turntable(0.5 + 1.5 * i as f64, 3.0, DVec3::ZERO)?;
            v.params.pitch = 0.35;
            views.push(v);
        }
        let mut renderer = Renderer::new(size, size)?;
        let mut masks = Vec::with_capacity(n_views);
        for v in &views {
            let mut target = *v;
            target.params.translation.x += 0.02;
            target.params.scale = 1.03;
            let cov = renderer.forward(&topo, &mesh.positions, &target)?.to_vec();
            masks.push(Mask::new(size, size, cov).map_err(|e| RenderError(e.0))?);
        }
        Ok(BenchScene {
            loss: MultiViewLoss::new(size, size, n_views)?,
            adjoint: vec![0.0; size as usize * size as usize],
            grad_pos: vec![Vec3::ZERO; mesh.positions.len()],
            grad_view: [0.0; N_VIEW_PARAMS],
            grad_views: vec![[0.0; N_VIEW_PARAMS]; n_views],
            mesh,
            topo,
            views,
            masks,
            renderer,
        })
    }

    /// Vertex count of the mesh.
    pub fn n_vertices(&self) -> usize {
        self.mesh.positions.len()
    }

    /// Silhouette edges of the first view after the last [`BenchScene::forward`].
    pub fn n_silhouette_edges(&self) -> usize {
        self.renderer.n_silhouette_edges()
    }

    /// Parallelism: inside the single-view renderer and over the views of the loss.
    pub fn set_parallel(&mut self, parallel: bool) {
        self.renderer.set_parallel(parallel);
        self.loss.set_parallel(parallel);
    }

    /// Forward render of the first view.
    pub fn forward(&mut self) -> Result<(), RenderError> {
        self.renderer
            .forward(&self.topo, &self.mesh.positions, &self.views[0])?;
        Ok(())
    }

    /// Forward, MSE adjoint and backward of the first view alone; returns its loss.
    pub fn forward_backward(&mut self) -> Result<f64, RenderError> {
        let cov = self
            .renderer
            .forward(&self.topo, &self.mesh.positions, &self.views[0])?;
        let l = crate::loss::mse_with_adjoint(cov, &self.masks[0], 1.0, &mut self.adjoint)
            .map_err(|e| RenderError(e.0))?;
        self.grad_pos.fill(Vec3::ZERO);
        self.grad_view = [0.0; N_VIEW_PARAMS];
        self.renderer.backward(
            &self.topo,
            &self.mesh.positions,
            &self.views[0],
            &self.adjoint,
            &mut self.grad_pos,
            &mut self.grad_view,
        )?;
        Ok(l)
    }

    /// The full multi-view loss and gradient ([`MultiViewLoss::evaluate`]) over all views.
    pub fn evaluate(&mut self) -> Result<f64, RenderError> {
        self.loss.evaluate(
            &self.topo,
            &self.mesh.positions,
            &self.views,
            &self.masks,
            &mut self.grad_pos,
            &mut self.grad_views,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn workload_runs_and_has_a_silhouette_to_fit() {
        let mut s = BenchScene::new(BenchMesh::Small, 64, 2).unwrap();
        assert!((3700..3900).contains(&s.n_vertices()));
        s.forward().unwrap();
        assert!(s.n_silhouette_edges() > 100);
        assert!(s.forward_backward().unwrap() > 0.0);
        assert!(s.grad_pos.iter().any(|g| *g != Vec3::ZERO));
        assert!(s.evaluate().unwrap() > 0.0);
        assert!(BenchScene::new(BenchMesh::Small, 64, 0).is_err());
        assert!(BenchScene::new(BenchMesh::Small, 0, 1).is_err());
    }
}
