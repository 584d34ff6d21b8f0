//! Tree impostors (paper §3.5.1): the semantic label image of a generated tree seen from a
//! camera, rendered with the silhouette renderer ([`crate::render::Renderer`]), and the fit of
//! the tree generator to a reference label image by the tree-structured GA.
//!
//! The renderer draws coverage, not labels, so an impostor is two coverage renders over the
//! same projected vertices: the leaf cards and the wood (trunk and branch tubes). A pixel is
//! leaf where leaves cover at least half of it, else branch where wood does, else background.
//! Leaves win because in a crown they hide most of the wood behind them, which is also what a
//! photo's colour segmentation sees.
//!
//! **The caller allocates**: a [`TreeImpostor`] owns its renderer and buffers and reuses them
//! for every tree; [`fit_tree`] keeps one per rayon thread so the GA's parallel evaluations
//! never share scratch space.

use super::ga::{GaConfig, GaResult, Mutation, tree_ga};
use super::similarity::{SimilarityConfig, TreeReference, TreeTraits};
use super::{BACKGROUND, BRANCH, LEAF, TreeError, genome_to_params};
use crate::camera::View;
use crate::generators::tree::{LEAF_CARD_TRIANGLES, PART_LEAF, TreeGenerator, skeleton};
use crate::generators::{Generator, Lod, Mesh};
use crate::mask::LabelImage;
use crate::render::{Renderer, Topology};
use glam::DVec3;
use std::sync::Mutex;

impl From<crate::render::RenderError> for TreeError {
    fn from(e: crate::render::RenderError) -> Self {
        TreeError(e.0)
    }
}

impl From<crate::mask::MaskError> for TreeError {
    fn from(e: crate::mask::MaskError) -> Self {
        TreeError(e.0)
    }
}

impl From<crate::camera::CameraError> for TreeError {
    fn from(e: crate::camera::CameraError) -> Self {
        TreeError(e.0)
    }
}

/// Renders label images of trees through one view, reusing its buffers.
pub struct TreeImpostor {
    view: View,
    renderer: Renderer,
    leaf: Vec<f32>,
    wood_tris: Vec<[u32; 3]>,
    leaf_tris: Vec<[u32; 3]>,
}

impl TreeImpostor {
    /// An impostor renderer for `view` (its size is the label image's size).
    pub fn new(view: View) -> Result<TreeImpostor, TreeError> {
        view.params.validate()?;
        Ok(TreeImpostor {
            view,
            renderer: Renderer::new(view.width, view.height)?,
            leaf: Vec::new(),
            wood_tris: Vec::new(),
            leaf_tris: Vec::new(),
        })
    }

    /// The view.
    pub fn view(&self) -> &View {
        &self.view
    }

    /// The label image ([`BACKGROUND`], [`BRANCH`], [`LEAF`]) of a tree mesh whose parts are
    /// the tree generator's (`trunk`, `branch`, `leaf`).
    pub fn render(&mut self, mesh: &Mesh) -> Result<LabelImage, TreeError> {
        self.wood_tris.clear();
        self.leaf_tris.clear();
        let mut leaf_index = 0;
        for (t, &p) in mesh.triangles.iter().zip(&mesh.tri_parts) {
            if p == PART_LEAF {
                // Front faces only: the back pair of a card covers the same pixels, and
                // skipping it halves the leaf work.
                if leaf_index % LEAF_CARD_TRIANGLES < 2 {
                    self.leaf_tris.push(*t);
                }
                leaf_index += 1;
            } else {
                self.wood_tris.push(*t);
            }
        }
        let n = mesh.positions.len();
        let leaf_topo = Topology::new(&self.leaf_tris, n)?;
        let wood_topo = Topology::new(&self.wood_tris, n)?;
        self.leaf.clear();
        self.leaf.extend_from_slice(self.renderer.forward(
            &leaf_topo,
            &mesh.positions,
            &self.view,
        )?);
        let wood = self
            .renderer
            .forward(&wood_topo, &mesh.positions, &self.view)?;
        let labels = self
            .leaf
            .iter()
            .zip(wood)
            .map(|(&l, &w)| {
                if l >= 0.5 {
                    LEAF
                } else if w >= 0.5 {
                    BRANCH
                } else {
                    BACKGROUND
                }
            })
            .collect();
        Ok(LabelImage::new(self.view.width, self.view.height, labels)?)
    }
}

/// A camera for tree impostors: on the +Z side looking at `(0, height / 2, 0)` from far enough
/// that a tree `height` tall fills about 80 % of the image height (vertical field of view 0.5
/// rad). Trees of other heights appear proportionally smaller or larger, so the GA recovers
/// the height from the image.
pub fn tree_view(width: u32, height: u32, tree_height: f64) -> Result<View, TreeError> {
    if !(tree_height.is_finite() && tree_height > 0.0) {
        return Err(TreeError(format!(
            "tree height {tree_height} must be a positive number"
        )));
    }
    let fov: f64 = 0.5;
    let distance = 0.5 * tree_height / 0.8 / (0.5 * fov).tan();
    Ok(View::turntable(
        width,
        height,
        0.0,
        distance,
        fov,
        DVec3::new(0.0, 0.5 * tree_height, 0.0),
    )?)
}

/// Settings of a tree fit.
#[derive(Clone, Copy, Debug)]
pub struct TreeFitConfig {
    /// The GA.
    pub ga: GaConfig,
    /// The similarity.
    pub similarity: SimilarityConfig,
    /// Level of detail of the generated trees during the fit.
    pub lod: Lod,
    /// Weigh in the branch-graph vertex count (the reference's in `traits`).
    pub use_graph_vertices: bool,
}

impl Default for TreeFitConfig {
    fn default() -> Self {
        TreeFitConfig {
            ga: GaConfig::default(),
            similarity: SimilarityConfig::default(),
            lod: Lod::Low,
            use_graph_vertices: false,
        }
    }
}

/// The result of a tree fit.
#[derive(Clone, Debug)]
pub struct TreeFit {
    /// The best parameter vector (tree generator order).
    pub params: Vec<f64>,
    /// Its similarity to the reference.
    pub similarity: f64,
    /// The GA's record (genomes in `[0, 1]`).
    pub ga: GaResult,
}

/// The fitness of one genome: tree similarity of its impostor to the reference (0 when the
/// genome cannot be built or rendered).
fn fitness(
    genome: &[f64],
    reference: &TreeReference,
    impostor: &mut TreeImpostor,
    cfg: &TreeFitConfig,
) -> Result<f64, TreeError> {
    let g = TreeGenerator;
    let params = genome_to_params(g.params(), genome)?;
    let mesh = g.generate(&params, cfg.lod)?;
    let labels = impostor.render(&mesh)?;
    let traits = if cfg.use_graph_vertices {
        TreeTraits {
            graph_vertices: Some(skeleton(&params, cfg.lod)?.graph_vertices() as f64),
            ..TreeTraits::default()
        }
    } else {
        TreeTraits::default()
    };
    reference.similarity(&labels, &traits)
}

/// Fits the tree generator to a reference label image seen through `view` (paper §3.5): the
/// tree-structured GA maximises the tree similarity of generated impostors. `mutation` is
/// Algorithm 3's statistics, or `None` for plain Gaussian mutation. Deterministic for
/// `cfg.ga.seed` on any number of threads.
pub fn fit_tree(
    reference: &LabelImage,
    traits: TreeTraits,
    view: View,
    cfg: &TreeFitConfig,
    mutation: Option<&super::mutation::MutationStats>,
) -> Result<TreeFit, TreeError> {
    if (reference.width(), reference.height()) != (view.width, view.height) {
        return Err(TreeError(format!(
            "reference is {}×{}, the view {}×{}",
            reference.width(),
            reference.height(),
            view.width,
            view.height
        )));
    }
    if cfg.use_graph_vertices && traits.graph_vertices.is_none() {
        return Err(TreeError(
            "weighing in the branch graph needs the reference's vertex count".into(),
        ));
    }
    let reference = TreeReference::new(reference, traits, cfg.similarity)?;
    // One impostor per rayon worker (and one for the calling thread): each is locked only by
    // its own thread, so the locks never wait.
    let slots = rayon::current_num_threads() + 1;
    let impostors: Vec<Mutex<TreeImpostor>> = (0..slots)
        .map(|_| TreeImpostor::new(view).map(Mutex::new))
        .collect::<Result<_, _>>()?;
    let f = |genome: &[f64]| -> f64 {
        let slot = rayon::current_thread_index().map_or(slots - 1, |i| i.min(slots - 2));
        let Ok(mut imp) = impostors[slot].lock() else {
            return 0.0;
        };
        fitness(genome, &reference, &mut imp, cfg).unwrap_or(0.0)
    };
    let n = TreeGenerator.params().len();
    let ga = match mutation {
        Some(stats) => tree_ga(n, &f, &cfg.ga, Mutation::Quality(stats))?,
        None => tree_ga(n, &f, &cfg.ga, Mutation::Gaussian)?,
    };
    let params = genome_to_params(TreeGenerator.params(), &ga.best.genome)?;
    Ok(TreeFit {
        params,
        similarity: ga.best.fitness,
        ga,
    })
}

/// The paper's evaluation metric (Table 2; notes "Evaluation as they did it"): the mean soft
/// silhouette IoU (`Σ min / Σ max` of the anti-aliased coverages) of two tree meshes over 64
/// turntable views (azimuth `2πi/64`, distance 3, vertical field of view 0.5 rad), rendered at
/// `size × size`, after normalising **each** mesh to its own bounding box (centre at the
/// origin, longest side 1; [`crate::reconstruct::eval::iou64`]).
///
/// The normalisation makes the metric blind to absolute size and placement: a fit from one
/// photo has no scale, so only the tree's proportions and outline count. Leaf cards and tubes
/// together form the silhouette. Errors on a mesh without vertices or extent, or a size
/// outside the renderer's range.
pub fn silhouette_iou64(a: &Mesh, b: &Mesh, size: u32) -> Result<f64, TreeError> {
    crate::reconstruct::eval::iou64(
        (&a.positions, &a.triangles),
        (&b.positions, &b.triangles),
        size,
    )
    .map_err(|e| TreeError(e.0))
}

/// Resamples a reference label image to `size × size` so that its tree sits where
/// [`tree_view`]`(size, size, 12.0)` puts a generated tree 12 units tall: the lowest tree pixels'
/// centre column at the image centre, the tree's top at 10 % and its foot at 90 % of the image
/// height (nearest neighbour, aspect kept). A photo has no scale, so this fixes it; the fit
/// then finds the tree's proportions, not its size in metres. Errors on an image without tree
/// pixels or a size outside 8..=4096.
pub fn frame_reference(labels: &LabelImage, size: u32) -> Result<LabelImage, TreeError> {
    if !(8..=4096).contains(&size) {
        return Err(TreeError(format!("frame size {size} is not in 8..=4096")));
    }
    let (w, h) = (labels.width() as usize, labels.height() as usize);
    let px = labels.labels();
    let is_tree = |l: u8| l == BRANCH || l == LEAF;
    let rows: Vec<usize> = (0..h)
        .filter(|&y| px[y * w..(y + 1) * w].iter().any(|&l| is_tree(l)))
        .collect();
    let (Some(&top), Some(&bottom)) = (rows.first(), rows.last()) else {
        return Err(TreeError(
            "the reference has no tree in it: no branch or leaf pixel".into(),
        ));
    };
    // Foot: the middle of the tree pixels on the lowest tree row.
    let foot_cols: Vec<usize> = (0..w).filter(|&x| is_tree(px[bottom * w + x])).collect();
    let foot_x = (foot_cols[0] + foot_cols[foot_cols.len() - 1] + 1) as f64 / 2.0;
    let n = f64::from(size);
    let scale = 0.8 * n / (bottom + 1 - top) as f64;
    let (dst_foot_x, dst_foot_y) = (0.5 * n, 0.9 * n);
    let mut out = vec![BACKGROUND; (size * size) as usize];
    for y in 0..size as usize {
        let sy = (bottom + 1) as f64 + (y as f64 + 0.5 - dst_foot_y) / scale;
        if sy < 0.0 || sy >= h as f64 {
            continue;
        }
        for x in 0..size as usize {
            let sx = foot_x + (x as f64 + 0.5 - dst_foot_x) / scale;
            if sx < 0.0 || sx >= w as f64 {
                continue;
            }
            out[y * size as usize + x] = px[sy as usize * w + sx as usize];
        }
    }
    Ok(LabelImage::new(size, size, out)?)
}
