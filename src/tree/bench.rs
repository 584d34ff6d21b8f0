//! The independent tree benchmark (issue 14): trees procfit did not make, written by
//! `scripts/make-tree-bench.mjs` (ez-tree, rendered by three.js in Chromium) into one folder per
//! case (`photo.png`, `labels.png`, `camera.json`, `truth.bin`, `other.bin`), and their scoring:
//! the paper's IoU-64 of the fit against the truth's alpha-cut mesh, the photo-view IoU (the fit
//! through its own photo camera against the photo's object mask), and the baselines (a sphere,
//! an ellipsoid on the truth's crown box, the same species under another seed).
//!
//! The fit lives in its own frame ([`super::impostor::tree_view`]); [`to_truth_frame`] moves it
//! into the truth's through the two cameras of the same photo: the fit's photo camera
//! ([`super::impostor::Framing::photo_view`]) and the one that rendered the photo.
//! `cargo bench --bench tree_bench` prints the table; `tests/tree_bench.rs` runs two cases.

use super::TreeError;
use super::carve::CARVE_GRID;
use super::impostor::{PhotoFitOptions, silhouette_iou64, start_photo_fit_with};
use crate::camera::{CameraPose, View};
use crate::generators::Mesh;
use crate::generators::tree::TreeGenerator;
use crate::generators::{Generator, Lod};
use crate::mask::LabelImage;
use crate::render::testmesh::{mesh_from, transformed, uv_sphere};
use crate::render::{Renderer, Topology};
use glam::{DVec3, Vec3};
use serde::Deserialize;
use std::path::Path;

/// The photo's camera as the script wrote it (ez-tree's frame, Y up).
#[derive(Clone, Debug, Deserialize)]
pub struct BenchCamera {
    /// Case name.
    pub name: String,
    /// Kind of tree (broadleaf round, tall narrow, conifer, autumn, bush).
    pub kind: String,
    /// Image width and height.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// Vertical field of view, radians.
    pub fov_y: f64,
    /// Camera position.
    pub position: [f64; 3],
    /// The point it looks at.
    pub target: [f64; 3],
}

/// One benchmark case, loaded.
pub struct BenchCase {
    /// The photo's camera and names.
    pub camera: BenchCamera,
    /// The photo, RGBA.
    pub photo: (u32, u32, Vec<u8>),
    /// The true label image of the photo's view.
    pub labels: LabelImage,
    /// The truth's mesh, leaves alpha-cut (part 0 branch, 1 leaf).
    pub truth: Mesh,
    /// The same species under another seed.
    pub other: Mesh,
}

/// Reads a `PFTB` mesh (see the script's header).
pub fn read_mesh(path: &Path) -> Result<Mesh, TreeError> {
    let bytes = std::fs::read(path).map_err(|e| TreeError(format!("{}: {e}", path.display())))?;
    let bad = || TreeError(format!("{}: not a PFTB mesh", path.display()));
    if bytes.len() < 12 || &bytes[..4] != b"PFTB" {
        return Err(bad());
    }
    let u32_at =
        |o: usize| u32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]);
    let (nv, nt) = (u32_at(4) as usize, u32_at(8) as usize);
    if bytes.len() != 12 + 12 * nv + 12 * nt + nt {
        return Err(bad());
    }
    let f = |o: usize| f32::from_le_bytes([bytes[o], bytes[o + 1], bytes[o + 2], bytes[o + 3]]);
    let positions: Vec<Vec3> = (0..nv)
        .map(|i| Vec3::new(f(12 + 12 * i), f(16 + 12 * i), f(20 + 12 * i)))
        .collect();
    let o = 12 + 12 * nv;
    let triangles: Vec<[u32; 3]> = (0..nt)
        .map(|i| {
            [
                u32_at(o + 12 * i),
                u32_at(o + 12 * i + 4),
                u32_at(o + 12 * i + 8),
            ]
        })
        .collect();
    if triangles.iter().flatten().any(|&i| i as usize >= nv) {
        return Err(bad());
    }
    let mut mesh = mesh_from(positions, triangles, "tree");
    mesh.tri_parts = bytes[o + 12 * nt..].to_vec();
    Ok(mesh)
}

impl BenchCase {
    /// Loads the case in `dir`.
    pub fn load(dir: &Path) -> Result<BenchCase, TreeError> {
        let e = |p: &Path, m: String| TreeError(format!("{}: {m}", p.display()));
        let cam_path = dir.join("camera.json");
        let text = std::fs::read_to_string(&cam_path).map_err(|x| e(&cam_path, x.to_string()))?;
        let camera: BenchCamera =
            serde_json::from_str(&text).map_err(|x| e(&cam_path, x.to_string()))?;
        let read = |name: &str| {
            let p = dir.join(name);
            image::open(&p)
                .map(|i| i.to_rgba8())
                .map_err(|x| e(&p, x.to_string()))
        };
        let photo = read("photo.png")?;
        let lab = read("labels.png")?;
        let labels = LabelImage::new(
            lab.width(),
            lab.height(),
            lab.as_raw().chunks_exact(4).map(|p| p[0].min(2)).collect(),
        )?;
        Ok(BenchCase {
            photo: (photo.width(), photo.height(), photo.into_raw()),
            labels,
            truth: read_mesh(&dir.join("truth.bin"))?,
            other: read_mesh(&dir.join("other.bin"))?,
            camera,
        })
    }

    /// The photo's camera as a [`View`].
    pub fn view(&self) -> Result<View, TreeError> {
        let c = &self.camera;
        let mut view = View::turntable(c.width, c.height, 0.0, 1.0, c.fov_y, DVec3::ZERO)?;
        view.pose = CameraPose::look_at(
            DVec3::from_array(c.position),
            DVec3::from_array(c.target),
            DVec3::Y,
        )?;
        Ok(view)
    }
}

/// Moves a mesh seen by `from` (a camera in its frame) into the frame of `to`, a camera of the
/// same photo in another frame: the similarity that maps `from`'s pose onto `to`'s, scaled by
/// the ratio of their distances to what they look at (`from_depth`, `to_depth`).
pub fn to_truth_frame(mesh: &Mesh, from: &View, from_depth: f64, to: &View, to_depth: f64) -> Mesh {
    let r = to.pose.rotation * from.pose.rotation.transpose();
    let s = to_depth / from_depth;
    let mut out = mesh.clone();
    for p in &mut out.positions {
        let q = to.pose.position + s * (r * (p.as_dvec3() - from.pose.position));
        *p = q.as_vec3();
    }
    out
}

/// The binary silhouette IoU of a mesh through `view` (coverage ≥ 0.5) against `mask`
/// (object where the label is not background).
pub fn photo_view_iou(mesh: &Mesh, view: &View, mask: &LabelImage) -> Result<f64, TreeError> {
    let mut r = Renderer::new(view.width, view.height)?;
    let topo = Topology::new(&mesh.triangles, mesh.positions.len())?;
    let cov = r.forward(&topo, &mesh.positions, view)?;
    let (mut inter, mut union) = (0usize, 0usize);
    for (&c, &l) in cov.iter().zip(mask.labels()) {
        let (a, b) = (
            c >= 0.5,
            l != super::BACKGROUND && l != LabelImage::DONT_CARE,
        );
        inter += usize::from(a && b);
        union += usize::from(a || b);
    }
    Ok(if union > 0 {
        inter as f64 / union as f64
    } else {
        1.0
    })
}

/// Binary masks of one view: where a mesh covers a pixel (coverage ≥ 0.5), as
/// [`photo_view_iou`] counts it.
pub fn coverage_mask(mesh: &Mesh, view: &View) -> Result<Vec<bool>, TreeError> {
    let mut r = Renderer::new(view.width, view.height)?;
    let topo = Topology::new(&mesh.triangles, mesh.positions.len())?;
    Ok(r.forward(&topo, &mesh.positions, view)?
        .iter()
        .map(|&c| c >= 0.5)
        .collect())
}

/// The object pixels of a label image (not background, not don't-care).
pub fn object_mask(labels: &LabelImage) -> Vec<bool> {
    labels
        .labels()
        .iter()
        .map(|&l| l != super::BACKGROUND && l != LabelImage::DONT_CARE)
        .collect()
}

/// IoU of two binary masks (1 when both are empty).
pub fn mask_iou(a: &[bool], b: &[bool]) -> f64 {
    let (mut inter, mut union) = (0usize, 0usize);
    for (&x, &y) in a.iter().zip(b) {
        inter += usize::from(x && y);
        union += usize::from(x || y);
    }
    if union > 0 {
        inter as f64 / union as f64
    } else {
        1.0
    }
}

/// Morphological closing (dilation then erosion) of a `w`-wide mask by a disk of radius `r`
/// pixels: the gaps between leaves filled, the outline kept.
pub fn close_mask(mask: &[bool], w: usize, r: i64) -> Vec<bool> {
    let h = mask.len() / w;
    let disk: Vec<(i64, i64)> = (-r..=r)
        .flat_map(|dy| (-r..=r).map(move |dx| (dx, dy)))
        .filter(|(dx, dy)| dx * dx + dy * dy <= r * r)
        .collect();
    let morph = |m: &[bool], dilate: bool| -> Vec<bool> {
        (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as i64, (i / w) as i64);
                let hit = |&(dx, dy): &(i64, i64)| {
                    let (u, v) = (x + dx, y + dy);
                    // Outside the image counts as background for both steps.
                    let inside = u >= 0 && v >= 0 && (u as usize) < w && (v as usize) < h;
                    inside && m[v as usize * w + u as usize]
                };
                if dilate {
                    disk.iter().any(hit)
                } else {
                    disk.iter().all(hit)
                }
            })
            .collect()
    };
    morph(&morph(mask, true), false)
}

/// The convex hull of a `w`-wide mask's pixels, filled (pixel centres inside the hull of
/// the set pixels' corners).
pub fn hull_mask(mask: &[bool], w: usize) -> Vec<bool> {
    let h = mask.len() / w;
    let mut pts: Vec<(f64, f64)> = Vec::new();
    for (i, _) in mask.iter().enumerate().filter(|(_, m)| **m) {
        let (x, y) = ((i % w) as f64, (i / w) as f64);
        pts.extend([(x, y), (x + 1.0, y), (x, y + 1.0), (x + 1.0, y + 1.0)]);
    }
    pts.sort_by(|a, b| a.partial_cmp(b).unwrap_or(std::cmp::Ordering::Equal));
    pts.dedup();
    if pts.len() < 3 {
        return vec![false; mask.len()];
    }
    let cross = |o: (f64, f64), a: (f64, f64), b: (f64, f64)| {
        (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0)
    };
    // Andrew's monotone chain, counter-clockwise in image coordinates' sense of `cross`.
    let mut hull: Vec<(f64, f64)> = Vec::new();
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &(f64, f64)>> = if pass == 0 {
            Box::new(pts.iter())
        } else {
            Box::new(pts.iter().rev())
        };
        for &p in iter {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0
            {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop();
    }
    (0..w * h)
        .map(|i| {
            let p = ((i % w) as f64 + 0.5, (i / w) as f64 + 0.5);
            (0..hull.len()).all(|k| cross(hull[k], hull[(k + 1) % hull.len()], p) >= 0.0)
        })
        .collect()
}

/// Where a photo-view IoU is lost: the fit's and the photo's object masks compared as they
/// are, with their leaf gaps closed, and as convex hulls; plus each mask's fill (object
/// pixels over its closed area) and the fit's area over the photo's.
#[derive(Clone, Copy, Debug, Default)]
pub struct SilhouetteAnalysis {
    /// The photo-view IoU ([`photo_view_iou`]).
    pub iou: f64,
    /// IoU of the two masks closed by a disk ([`close_mask`], radius 1 % of the image height).
    pub closed_iou: f64,
    /// IoU of their convex hulls ([`hull_mask`]).
    pub hull_iou: f64,
    /// The photo's object pixels over its closed mask's.
    pub photo_fill: f64,
    /// The fit's covered pixels over its closed mask's.
    pub fit_fill: f64,
    /// The fit's covered pixels over the photo's object pixels.
    pub area_ratio: f64,
}

/// [`SilhouetteAnalysis`] of a mesh through `view` against `labels` (the photo's).
pub fn analyse_silhouette(
    mesh: &Mesh,
    view: &View,
    labels: &LabelImage,
) -> Result<SilhouetteAnalysis, TreeError> {
    let fit = coverage_mask(mesh, view)?;
    let photo = object_mask(labels);
    let w = view.width as usize;
    let r = (0.01 * f64::from(view.height)).round().max(1.0) as i64;
    let (fc, pc) = (close_mask(&fit, w, r), close_mask(&photo, w, r));
    let count = |m: &[bool]| m.iter().filter(|&&b| b).count() as f64;
    Ok(SilhouetteAnalysis {
        iou: mask_iou(&fit, &photo),
        closed_iou: mask_iou(&fc, &pc),
        hull_iou: mask_iou(&hull_mask(&fit, w), &hull_mask(&photo, w)),
        photo_fill: count(&photo) / count(&pc).max(1.0),
        fit_fill: count(&fit) / count(&fc).max(1.0),
        area_ratio: count(&fit) / count(&photo).max(1.0),
    })
}

/// A UV sphere (the baseline: any sphere, the metric normalises it).
pub fn sphere() -> Mesh {
    uv_sphere(1.0, 24, 48)
}

/// An ellipsoid on the bounding box of the truth's leaves (its crown), with the trunk's box
/// below it left out: the best a blob that knows the crown's extent does.
pub fn crown_ellipsoid(truth: &Mesh) -> Mesh {
    let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    for (t, &p) in truth.triangles.iter().zip(&truth.tri_parts) {
        if p == 1 {
            for &i in t {
                lo = lo.min(truth.positions[i as usize]);
                hi = hi.max(truth.positions[i as usize]);
            }
        }
    }
    let mut m = transformed(&sphere(), 1.0, Vec3::ZERO);
    let (c, h) = (0.5 * (lo + hi), 0.5 * (hi - lo));
    for p in &mut m.positions {
        *p = c + *p * h;
    }
    m
}

/// The scores of one fit of a case.
#[derive(Clone, Copy, Debug)]
pub struct BenchScore {
    /// The paper's similarity (eq. 3) of the fit.
    pub similarity: f64,
    /// The paper's IoU-64 against the truth (128², the fit at MEDIUM in the truth's frame).
    pub iou64: f64,
    /// The fit through its own photo camera against the photo's object mask.
    pub photo_iou: f64,
}

/// Fits `labels` (of the case's photo) as the CLI does, seed 1, with `budget` GA evaluations
/// (`None`: the default), carves its leaves by the labels as the CLI does
/// ([`CARVE_GRID`]), and scores the result (the caller times it).
pub fn fit_case(
    case: &BenchCase,
    labels: &LabelImage,
    budget: Option<usize>,
    options: &PhotoFitOptions,
) -> Result<BenchScore, String> {
    Ok(fit_case_mesh(case, labels, 1, budget, options, Some(CARVE_GRID))?.0)
}

/// A case's fitted tree as the CLI writes it, before it is scored ([`fit_case_tree`]).
pub struct FittedTree {
    /// The fitted tree (MEDIUM), carved when asked.
    pub mesh: Mesh,
    /// The photo's camera for it.
    pub photo_view: View,
    /// The fit's view (the fitted tree's frame).
    pub fit_view: View,
    /// The paper's similarity (eq. 3) of the fit.
    pub similarity: f64,
}

/// The fit of [`fit_case`] with the fit's seed and the carving's largest tiles per card side
/// (`None`: the tree as generated), without the scoring: what a user waits for.
pub fn fit_case_tree(
    labels: &LabelImage,
    seed: u64,
    budget: Option<usize>,
    options: &PhotoFitOptions,
    carve: Option<usize>,
) -> Result<FittedTree, String> {
    let mut f = start_photo_fit_with(labels, seed, budget, None, options).map_err(|e| e.0)?;
    while !f.session.done() {
        f.session.step();
    }
    let result = f.session.result().map_err(|e| e.0)?;
    let similarity = f.session.paper_similarity().map_err(|e| e.0)?;
    let mesh = TreeGenerator
        .generate(&result.params, Lod::Medium)
        .map_err(|e| e.to_string())?;
    let photo_view = f.framing.photo_view().map_err(|e| e.0)?;
    // The tree as the CLI writes it: carved by the photo's labels (the fit's input).
    let mesh = match carve {
        Some(grid) => {
            super::carve::LeafCarve::new(labels.clone(), photo_view, grid)
                .and_then(|c| c.apply(&mesh))
                .map_err(|e| e.0)?
                .0
        }
        None => mesh,
    };
    Ok(FittedTree {
        mesh,
        photo_view,
        fit_view: f.framing.fit_view().map_err(|e| e.0)?,
        similarity,
    })
}

/// Scores a [`FittedTree`] of `case`: IoU-64 in the truth's frame, photo-view IoU.
pub fn score_case(case: &BenchCase, fit: &FittedTree) -> Result<BenchScore, String> {
    let fit_depth = (fit.fit_view.pose.position - DVec3::new(0.0, 6.0, 0.0)).length();
    let truth_view = case.view().map_err(|e| e.0)?;
    let c = &case.camera;
    let truth_depth = (DVec3::from_array(c.position) - DVec3::from_array(c.target)).length();
    let moved = to_truth_frame(
        &fit.mesh,
        &fit.photo_view,
        fit_depth,
        &truth_view,
        truth_depth,
    );
    Ok(BenchScore {
        similarity: fit.similarity,
        iou64: silhouette_iou64(&case.truth, &moved, 128).map_err(|e| e.0)?,
        photo_iou: photo_view_iou(&fit.mesh, &fit.photo_view, &case.labels).map_err(|e| e.0)?,
    })
}

/// [`fit_case_tree`] then [`score_case`]: the scores, the fitted mesh (MEDIUM, carved) and its
/// photo camera, for [`analyse_silhouette`].
pub fn fit_case_mesh(
    case: &BenchCase,
    labels: &LabelImage,
    seed: u64,
    budget: Option<usize>,
    options: &PhotoFitOptions,
    carve: Option<usize>,
) -> Result<(BenchScore, Mesh, View), String> {
    let fit = fit_case_tree(labels, seed, budget, options, carve)?;
    let score = score_case(case, &fit)?;
    Ok((score, fit.mesh, fit.photo_view))
}
