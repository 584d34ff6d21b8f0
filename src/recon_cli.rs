//! The CLI's reconstruction subcommands: `reconstruct`, `render` and `eval` (kept apart from
//! `main.rs` so the subcommands of other rooms merge cleanly). Every error is one line.

use crate::format_cli::Target;
use crate::outputs::{Outputs, write_atomic};
use clap::Args;
use procfit::generators::{self, Lod, Mesh};
use procfit::glb::{self, ExportCamera};
use procfit::mask::Mask;
use procfit::model::Model;
use procfit::reconstruct::views::ViewVars;
use procfit::reconstruct::{self, FitConfig, Luma, Session, eval};
use procfit::segment::{self, Photo};
use procfit::tree::carve::{CARVE_GRID, LeafCarve};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

/// `procfit reconstruct`.
#[derive(Args)]
pub struct ReconstructArgs {
    /// Generator: dish, building, tree, or auto (tries every differentiable generator). A
    /// tree is fitted by the tree GA to one image: a photo (labelled by colour: green → leaf,
    /// brown/grey → branch) or a grey label image (0 background, 1 branch, 2 leaf, 255 don't
    /// care).
    #[arg(long, default_value = "auto")]
    generator: String,
    /// Seed of the fit (same seed, same result).
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Stage-1 evaluations (default 5000 × quality; for a tree, the GA's, default 1152 ×
    /// quality, plus the seed trials and the local search).
    #[arg(long)]
    budget: Option<usize>,
    /// Whole fits from different seeds, run side by side; the lowest final loss wins (not for
    /// trees). Default: 3, 6 for a building, or 1 below quality 0.5 (a quick preview), as on
    /// the page.
    #[arg(long)]
    restarts: Option<usize>,
    /// Quality/speed knob: multiplies every stage's budget, in (0, 16].
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    quality: f64,
    /// Vertical field of view of every image, radians (default: from the photo's EXIF 35 mm
    /// focal length, else 0.47, a 50 mm lens).
    #[arg(long, allow_negative_numbers = true)]
    fov: Option<f64>,
    /// Photos (segmented automatically) or mask images (white or opaque = object), one per
    /// view, all the same size.
    #[arg(required = true)]
    images: Vec<PathBuf>,
    /// Output path: .glb (with the photos' cameras and the generator state), .obj (+ .mtl
    /// beside it) or .stl.
    #[arg(short, long)]
    output: PathBuf,
    /// Output format (default: from the output's extension).
    #[arg(long, value_parser = ["glb", "obj", "stl"])]
    format: Option<String>,
    /// GLB only: quantised attributes (KHR_mesh_quantization), about half the size.
    #[arg(long)]
    compact: bool,
    /// Level of detail of the written model, 0..=3 (default: the generator's export detail,
    /// 2 or finer).
    #[arg(long, value_parser = clap::value_parser!(u8).range(0..=3))]
    lod: Option<u8>,
    /// Also write the parameters as params JSON here.
    #[arg(long)]
    params_out: Option<PathBuf>,
    /// Trees: the colour rules that label a photo, as JSON with any of the fields leafHue,
    /// leafMinSaturation, leafMinValue, barkHue, barkSaturation, barkValue, greyMaxSaturation,
    /// restAsBranch (hues in degrees, a range that starts above its end wraps through red; the
    /// rest within 0–1), e.g. '{"leafHue":[330,170],"leafMinValue":0.45}' for autumn leaves.
    #[arg(long)]
    tree_colors: Option<String>,
    /// Trees: write the tree as the generator makes it. By default the written tree is carved
    /// by the photo: leaf cards are added where the photo's foliage is uncovered, then leaves,
    /// trunk and branches are cut into tiles, a tile dropped where the photo sees through the
    /// tree (nothing lies on such a pixel's ray); the params JSON regenerates the uncarved tree.
    #[arg(long)]
    no_carve: bool,
    /// Refit from a model: a params JSON or a GLB written by procfit (the page's "Refit from
    /// here"). Its generator is the one fitted (`--generator` may be left out or must agree);
    /// a tree keeps its seed and never ends less like the photo than the start.
    #[arg(long)]
    start: Option<PathBuf>,
    /// Keep the generator's default part colours instead of the colours measured in the
    /// photos (a refit keeps `--start`'s colours).
    #[arg(long)]
    default_colors: bool,
    /// Buildings: a window mask per image, in the images' order (white = window; as
    /// `procfit segment --generator building` writes it, at the mask's working size), so the
    /// fit gets the floors and window columns right. Give the flag once per image.
    #[arg(long)]
    windows: Vec<PathBuf>,
}

/// The model `--start` names: a params JSON or a procfit GLB.
fn load_start(path: &Path) -> Result<Model, String> {
    let bytes = read(path)?;
    Model::from_file_bytes(&bytes).map_err(|e| format!("--start {}: {e}", path.display()))
}

/// `procfit render`.
#[derive(Args)]
pub struct RenderArgs {
    /// Generator machine name.
    #[arg(long)]
    generator: String,
    /// A preset of the generator.
    #[arg(long, conflicts_with = "params", required_unless_present = "params")]
    preset: Option<String>,
    /// A params JSON file.
    #[arg(long)]
    params: Option<PathBuf>,
    /// Camera JSON: {"yaw", "pitch", "roll", "tx", "ty", "log_scale", "fov_y"} (object spin,
    /// camera elevation and tilt in radians, translation, log of the object scale; the camera
    /// is 3 units in front of the object's origin). Missing fields take defaults.
    #[arg(long)]
    camera: PathBuf,
    /// Image size: W or WxH.
    #[arg(long)]
    size: String,
    /// Output PNG path.
    #[arg(short, long)]
    output: PathBuf,
}

/// `procfit eval`.
#[derive(Args)]
pub struct EvalArgs {
    /// Reference mesh (OBJ or GLB).
    #[arg(long)]
    reference: PathBuf,
    /// The model GLB (e.g. written by `procfit reconstruct`).
    model: PathBuf,
    /// The mask of input view 0, to also print the input-view IoU through the model's first
    /// camera.
    #[arg(long)]
    mask: Option<PathBuf>,
}

fn read(path: &Path) -> Result<Vec<u8>, String> {
    std::fs::read(path).map_err(|e| format!("cannot read {}: {e}", path.display()))
}

/// The vertical field of view from a photo's EXIF `FocalLengthIn35mmFilm`, for an image of
/// `width × height` (after orientation), when the file has one.
fn exif_fov(bytes: &[u8], width: u32, height: u32) -> Option<f64> {
    let focal = reconstruct::views::focal_35mm_from_file(bytes)?;
    reconstruct::fov_from_focal_35mm(focal, width, height)
}

/// A mask from an image file: a mask image when it is grey and nearly binary or has
/// transparency, else a photo segmented automatically with `opts`.
fn load_mask(path: &Path, opts: &segment::Options) -> Result<Mask, String> {
    Ok(load_view(path, opts)?.mask)
}

/// An image file's bytes and its pixels as RGBA, at full size (the tree labels' path); a
/// one-line error when it is not an image or is cut off.
fn read_image(path: &Path) -> Result<(Vec<u8>, image::RgbaImage), String> {
    let bytes = read(path)?;
    segment::decode::check_complete(&bytes).map_err(|e| format!("{}: {e}", path.display()))?;
    let img = image::load_from_memory(&bytes)
        .map_err(|e| format!("{}: not a readable image ({e})", path.display()))?;
    Ok((bytes, img.to_rgba8()))
}

/// One view as loaded: its mask at the working size, the file's own size in pixels (upright),
/// for a photo with EXIF its field of view, and for a photo (or a cut-out with transparency)
/// its sRGB RGBA pixels at the mask's size, for the part colours.
pub(crate) struct LoadedView {
    /// The mask the fit uses, at the working size.
    pub mask: Mask,
    /// The file's own size (upright).
    pub file_size: (u32, u32),
    /// The field of view from the photo's EXIF, when it has one.
    pub fov: Option<f64>,
    /// The photo's sRGB RGBA pixels at the mask's size, for the part colours (`None` for a
    /// grey mask image: no colours to take).
    pub rgba: Option<Vec<u8>>,
    /// The decoded image at the working size (the photo, or the mask image itself).
    pub photo: Photo,
    /// The automatic segmentation when the file is a photo (its confidence, its object mask);
    /// `None` for a mask image or a photo with transparency.
    pub segmentation: Option<segment::Segmentation>,
    /// What to tell the user about the mask (automatic or given) before the fit.
    pub warnings: Vec<String>,
}

/// In a grey mask image, this exact level is don't care, as [`Mask::to_luma8`] (and so
/// `procfit segment`) writes the outline's band; every other level is coverage.
const DONT_CARE_LEVEL: u8 = 128;

/// A view's mask, warnings printed on stderr (see [`read_view`]).
fn load_view(path: &Path, opts: &segment::Options) -> Result<LoadedView, String> {
    let view = read_view(path, opts)?;
    for w in &view.warnings {
        eprintln!("procfit: {}: {w}", path.display());
    }
    Ok(view)
}

/// A view's mask. The file is decoded once, straight to the working size (a large JPEG by a
/// scaled DCT decode), so a 4000×3000 mask costs what a 512² one does: a mask image (grey and
/// nearly binary, or with transparency) becomes soft coverage — the share of object pixels
/// under each working pixel — with grey [`DONT_CARE_LEVEL`] as don't care, and a photo is
/// segmented automatically with `opts` (the object kind's, [`segment::Options::for_generator`]).
/// Nothing is printed: the warnings are returned.
pub(crate) fn read_view(path: &Path, opts: &segment::Options) -> Result<LoadedView, String> {
    let bytes = read(path)?;
    let at = |e: &dyn std::fmt::Display| format!("{}: {e}", path.display());
    let photo = Photo::decode(&bytes, segment::WORKING_SIDE)
        .map_err(|e| format!("{}: not a readable image ({e})", path.display()))?;
    let (w, h) = (photo.width(), photo.height());
    let file_size = photo.source_size();
    let px = photo.rgba();
    let coverage = |v: &[u8], dont_care: bool| {
        let values = v
            .iter()
            .map(|&c| {
                if dont_care && c == DONT_CARE_LEVEL {
                    Mask::DONT_CARE
                } else {
                    f32::from(c) / 255.0
                }
            })
            .collect();
        Mask::new(w, h, values).map_err(|e| at(&e))
    };
    let mut rgba = Some(px.to_vec());
    let mut segmentation = None;
    let mut warnings = Vec::new();
    let mask = if photo.has_alpha() && px.chunks_exact(4).any(|p| p[3] < 128) {
        coverage(&px.chunks_exact(4).map(|p| p[3]).collect::<Vec<_>>(), false)?
    } else if px.chunks_exact(4).all(|p| p[0] == p[1] && p[1] == p[2])
        && px
            .chunks_exact(4)
            .filter(|p| p[0] < 16 || p[0] > 239 || p[0] == DONT_CARE_LEVEL)
            .count()
            >= px.len() / 4 * 95 / 100
    {
        // A grey mask image: no colours to take.
        rgba = None;
        coverage(&px.chunks_exact(4).map(|p| p[0]).collect::<Vec<_>>(), true)?
    } else {
        let seg = segment::segment_auto_with(&photo, opts).map_err(|e| at(&e))?;
        warnings.clone_from(&seg.warnings);
        let mask = seg.mask.clone();
        segmentation = Some(seg);
        mask
    };
    if segmentation.is_none() {
        // A mask image the fit cannot use is refused here, by the fit's own check
        // (`views::check_mask`), naming the file and what to do; the rest is said here.
        use reconstruct::views::MaskProblem;
        match reconstruct::views::check_mask(&mask) {
            Err(MaskProblem::Empty) => {
                return Err(at(
                    &"no object in this mask image: no pixel is white or opaque (the \
                     object), grey 128 is don't care; draw the object in white, or give the \
                     photo",
                ));
            }
            Err(p @ MaskProblem::AllObject(_)) => {
                return Err(at(&format!(
                    "this mask image {p}; nothing black or transparent around the object: \
                     crop wider or mark the background black"
                )));
            }
            Err(p) => return Err(at(&format!("this mask image {p}"))),
            Ok(_) => {}
        }
        let obj: Vec<bool> = mask.values().iter().map(|&v| v >= 0.5).collect();
        warnings = segment::mask_warnings(&obj, w as usize, h as usize);
    }
    let fov = exif_fov(&bytes, mask.width(), mask.height());
    Ok(LoadedView {
        mask,
        file_size,
        fov,
        rgba,
        photo,
        segmentation,
        warnings,
    })
}

/// The views' masks, all at one size. Views of one aspect ratio but different sizes are brought
/// to the smallest; views of different aspect ratios are refused, naming the files' own sizes.
fn load_views(paths: &[PathBuf], opts: &segment::Options) -> Result<Vec<LoadedView>, String> {
    let mut views = paths
        .iter()
        .map(|p| load_view(p, opts))
        .collect::<Result<Vec<_>, _>>()?;
    let Some(first) = views.first() else {
        return Ok(views);
    };
    let (fw, fh) = first.file_size;
    for (v, p) in views.iter().zip(paths).skip(1) {
        let (w, h) = v.file_size;
        // Aspect ratios agree when the sizes are proportional up to a pixel of rounding.
        let cross = (i64::from(w) * i64::from(fh) - i64::from(h) * i64::from(fw)).abs();
        if cross > i64::from(fw.max(w)) + i64::from(fh.max(h)) {
            return Err(format!(
                "{} is {w}×{h} but {} is {fw}×{fh}: all views must have the same aspect ratio (the same size, or one size scaled): crop them alike",
                p.display(),
                paths[0].display()
            ));
        }
    }
    let (tw, th) = views
        .iter()
        .map(|v| (v.mask.width(), v.mask.height()))
        .min()
        .unwrap_or((0, 0));
    for v in &mut views {
        let (w, h) = (v.mask.width(), v.mask.height());
        if (w, h) != (tw, th) {
            v.mask = resample_mask(&v.mask, tw, th);
            v.rgba = v
                .rgba
                .take()
                .map(|px| segment::decode::area_resample(&px, w, h, 4, tw, th).0);
        }
    }
    Ok(views)
}

/// `mask` area-averaged to `tw × th`; a working pixel is don't-care when most of what it covers
/// is.
fn resample_mask(mask: &Mask, tw: u32, th: u32) -> Mask {
    let (w, h) = (mask.width(), mask.height());
    // Two channels: coverage (don't-care as 0) and whether the pixel counts.
    let mut two = Vec::with_capacity(mask.values().len() * 2);
    for &v in mask.values() {
        let cares = v != Mask::DONT_CARE;
        two.push(if cares { (v * 255.0).round() as u8 } else { 0 });
        two.push(if cares { 255 } else { 0 });
    }
    // Averaged with the "counts" channel as alpha: grey = coverage among the pixels that
    // count, alpha = their share.
    let (small, _) = segment::decode::area_resample(&two, w, h, 2, tw, th);
    let values = small
        .chunks_exact(4)
        .map(|p| {
            if p[3] < 128 {
                Mask::DONT_CARE
            } else {
                f32::from(p[0]) / 255.0
            }
        })
        .collect();
    Mask::new(tw, th, values).unwrap_or_else(|_| mask.clone())
}

fn seconds(s: f64) -> String {
    if s < 60.0 {
        format!("{s:.0}s")
    } else {
        format!("{}m{:02.0}s", (s / 60.0).floor(), s % 60.0)
    }
}

/// `procfit reconstruct`: fit, progress on stderr, GLB (and params JSON) out.
pub fn reconstruct(a: &ReconstructArgs) -> Result<(), String> {
    // Every output is checked before any work: a bad path fails now, not after the fit.
    let target = Target::new(&a.output, a.format.as_deref(), a.compact);
    let mut plan = Target::declare_any(&target, &a.output, Outputs::new().inputs(&a.images));
    if let Some(p) = &a.start {
        plan = plan.input(p);
    }
    plan = plan.inputs(&a.windows);
    if let Some(p) = &a.params_out {
        plan = plan.output("--params-out", p);
    }
    plan.check()?;
    let target = target.as_ref().map_err(Clone::clone)?;
    let start = a.start.as_deref().map(load_start).transpose()?;
    let generator = match &start {
        Some(m) if a.generator == "auto" || a.generator == m.generator.name() => {
            m.generator.name().to_string()
        }
        Some(m) => {
            return Err(format!(
                "--start is a {} model, --generator says {}",
                m.generator.name(),
                a.generator
            ));
        }
        None => a.generator.clone(),
    };
    let start_colors = start.as_ref().map(|m| m.colors.clone()).unwrap_or_default();
    let start = start.map(|m| m.params);
    // How the generator is fitted is its own declaration, not a name check here.
    if let Some(g) = generators::by_name(&generator)
        .filter(|g| g.capabilities().fit == Some(generators::FitMethod::TreeGa))
    {
        if !a.windows.is_empty() {
            return Err(format!(
                "--windows is for a generator with windows, not `{}`",
                g.name()
            ));
        }
        return reconstruct_tree(a, g, target, start.as_deref());
    }
    if a.tree_colors.is_some() {
        return Err("--tree-colors is for --generator tree".into());
    }
    // A photo is cut for the object kind when it is named (`auto` chooses it after the cut).
    let seg_opts = segment::Options::for_generator(generators::by_name(&generator));
    let views = load_views(&a.images, &seg_opts)?;
    // --fov wins, then the photo's EXIF focal length, then the default.
    let fov_y = views.iter().map(|v| a.fov.or(v.fov)).collect();
    let (masks, pixels): (Vec<Mask>, Vec<Option<Vec<u8>>>) =
        views.into_iter().map(|v| (v.mask, v.rgba)).unzip();
    let windows = load_windows(a, &generator, &masks)?;
    // The photos' brightness, for a rim on the photo's edges (mask images have none).
    let photos = pixels
        .iter()
        .zip(&masks)
        .map(|(px, m)| {
            px.as_ref()
                .and_then(|px| Luma::from_rgba(m.width(), m.height(), px).ok())
        })
        .collect();
    let restarts = a
        .restarts
        .unwrap_or_else(|| FitConfig::restarts_for(&generator, a.quality));
    let config = FitConfig {
        generator,
        start,
        seed: a.seed,
        quality: a.quality,
        budget: a.budget,
        restarts,
        fov_y,
        windows,
        photos,
        ..FitConfig::default()
    };
    let mut session = Session::new(config, masks.clone()).map_err(|e| e.to_string())?;
    let start = Instant::now();
    step_with_progress(|| {
        let p = session.step();
        Tick {
            done: p.done,
            name: format!("{} ×{}", p.generator, p.runs),
            stage: p.stage,
            frac: if p.work_total > 0.0 {
                p.work_done / p.work_total
            } else {
                0.0
            },
            rest: format!("{} evals, loss {:.5}", p.evaluations, p.best_loss),
        }
    });
    let result = session.result().map_err(|e| e.to_string())?;
    let agreement = session.agreement().map_err(|e| e.to_string())?;
    let front_only = session.front_only().map_err(|e| e.to_string())?;
    let colors = if a.default_colors {
        procfit::model::PartColors::new()
    } else {
        photo_colors(&result.model, &result.views, &pixels, &masks)?.unwrap_or(start_colors)
    };
    let model = Model {
        lod: lod_of(a, result.model.generator)?,
        ..result.model.clone()
    }
    .with_colors(&colors)
    .map_err(|e| e.to_string())?;
    let cameras: Vec<ExportCamera> = result
        .views
        .iter()
        .zip(&a.images)
        .map(|(v, p)| {
            let name = p.file_name().map(|n| n.to_string_lossy().into_owned());
            reconstruct::export_camera(v, name)
        })
        .collect();
    let summary = write_outputs(a, target, &model, &cameras)?;
    println!(
        "wrote {}: {} fitted to {} view(s) in {:.1} s, {} evaluations, loss {:.5}; lod {}, {summary}",
        a.output.display(),
        model.generator.name(),
        result.views.len(),
        start.elapsed().as_secs_f64(),
        result.evaluations,
        result.loss,
        model.lod.index()
    );
    report_rescue(&session, &result);
    report_photo_match(&result, model.lod, &masks, &a.images)?;
    report_agreement(agreement, front_only);
    if let Some(note) = eval::windows_left_out_note(session.windows_left_out()) {
        println!("{note}");
    }
    if let Some(note) = eval::one_view_caveat(&result) {
        println!("note: {note}");
    }
    Ok(())
}

/// Says when the fit added runs from other shapes because its first runs' best model did not
/// match a photo ([`Session::rescue_runs`]), and whether one of them was kept (`result`, the
/// fit's).
fn report_rescue(session: &Session, result: &reconstruct::FitResult) {
    let added = session.rescue_runs();
    if added == 0 {
        return;
    }
    let first = session.run_results().len() - added;
    let kept = match session.kept_run() {
        Some(k) if k >= first => "the model is from one of them",
        _ => "none matched better, the model is from the first",
    };
    let ious: Vec<String> = session
        .rescued_from()
        .iter()
        .map(|iou| format!("{iou:.3}"))
        .collect();
    println!(
        "the best of the first {first} fits did not match the photos (photo-view IoU {}, below \
         {:.2}): {added} more fits from other shapes ran; {kept}",
        ious.join(", "),
        eval::photo_match_level(result.model.generator),
    );
}

/// Prints how well the photos fix the shape (the 3D agreement of the runs that matched them
/// about as well as the kept one, [`eval::agreement`]) and, when they do not, a warning saying
/// what to try (about the depth when the photos show only the front, `front_only`).
fn report_agreement(agreement: Option<f64>, front_only: bool) {
    if let Some(a) = agreement {
        println!(
            "3D agreement of the runs that match the photos as well: {a:.3} (1 = the same shape)"
        );
    }
    if let Some(w) = eval::agreement_warning(agreement, front_only) {
        eprintln!("procfit: warning: {w}");
    }
}

/// `--windows`: the window labels of each view (background, façade, window, don't care) from
/// its window mask and its object mask; an error for a generator without windows, more
/// window masks than images, or a window mask whose size is not its view's.
fn load_windows(
    a: &ReconstructArgs,
    generator: &str,
    masks: &[Mask],
) -> Result<Vec<Option<procfit::mask::LabelImage>>, String> {
    use procfit::segment::windows::{LABEL_BACKGROUND, LABEL_FACADE, LABEL_WINDOW};
    if a.windows.is_empty() {
        return Ok(Vec::new());
    }
    let has_windows = generators::by_name(generator)
        .is_some_and(|g| g.capabilities().mask_extra == generators::MaskExtra::Windows);
    if !has_windows {
        return Err(format!(
            "--windows is for a generator with windows, not `{generator}` (name it with --generator)"
        ));
    }
    if a.windows.len() > masks.len() {
        return Err(format!(
            "{} window masks for {} images: give one per image, in their order",
            a.windows.len(),
            masks.len()
        ));
    }
    a.windows
        .iter()
        .zip(masks)
        .map(|(path, mask)| {
            let bytes = read(path)?;
            let img = Photo::decode(&bytes, segment::WORKING_SIDE)
                .map_err(|e| format!("{}: not a readable image ({e})", path.display()))?;
            let (w, h) = (mask.width(), mask.height());
            if (img.width(), img.height()) != (w, h) {
                return Err(format!(
                    "{}: the window mask is {}×{} at the working size but its view's mask is {w}×{h}: write it with `procfit segment` from the same photo",
                    path.display(),
                    img.width(),
                    img.height()
                ));
            }
            let labels = mask
                .values()
                .iter()
                .zip(img.rgba().chunks_exact(4))
                .map(|(&m, p)| {
                    if m == Mask::DONT_CARE {
                        procfit::mask::LabelImage::DONT_CARE
                    } else if m < 0.5 {
                        LABEL_BACKGROUND
                    } else if p[0] >= 128 {
                        LABEL_WINDOW
                    } else {
                        LABEL_FACADE
                    }
                })
                .collect();
            procfit::mask::LabelImage::new(w, h, labels)
                .map(Some)
                .map_err(|e| format!("{}: {e}", path.display()))
        })
        .collect()
}

/// The part colours measured in the photos (the views that have one; `None` when none has),
/// printed, with a note on stderr for the parts the photos do not show.
fn photo_colors(
    model: &Model,
    views: &[procfit::camera::View],
    pixels: &[Option<Vec<u8>>],
    masks: &[Mask],
) -> Result<Option<procfit::model::PartColors>, String> {
    use procfit::colors;
    let mut seen = (Vec::new(), Vec::new(), Vec::new());
    for ((view, px), mask) in views.iter().zip(pixels).zip(masks) {
        if let Some(px) = px {
            seen.0.push(*view);
            seen.1.push(colors::Rgba {
                width: view.width,
                height: view.height,
                pixels: px,
            });
            seen.2.push(mask.clone());
        }
    }
    if seen.0.is_empty() {
        return Ok(None);
    }
    let mesh = model
        .generator
        .generate(&model.params, model.lod)
        .map_err(|e| e.to_string())?;
    let found = colors::estimate(&mesh, &seen.0, &seen.1, &seen.2).map_err(|e| e.to_string())?;
    print_colors(&found);
    Ok(Some(colors::to_part_colors(&found)))
}

/// The level of detail a fit is written at: [`Lod::High`], or the generator's
/// [`generators::Capabilities::fitted_lod`] when that is finer.
fn fitted_lod(generator: &dyn generators::Generator) -> Lod {
    generator.capabilities().fitted_lod.max(Lod::High)
}

/// Prints how well the fitted model, at the detail `lod` it is written at, matches each photo
/// (its photo-view IoU) and, when it does not, a warning saying what to try (issue 16: never a
/// confident wrong answer).
fn report_photo_match(
    result: &reconstruct::FitResult,
    lod: Lod,
    masks: &[Mask],
    paths: &[PathBuf],
) -> Result<(), String> {
    let ious = eval::result_photo_ious_at(result, masks, lod).map_err(|e| e.to_string())?;
    let names: Vec<String> = paths.iter().map(|p| p.display().to_string()).collect();
    let each: Vec<String> = ious
        .iter()
        .zip(&names)
        .map(|(iou, n)| format!("{n} {iou:.3}"))
        .collect();
    println!("photo-view IoU: {}", each.join(", "));
    let level = eval::photo_match_level(result.model.generator);
    if let Some(w) = eval::photo_match_warning(&ious, &names, level) {
        eprintln!("procfit: warning: {w}");
    }
    Ok(())
}

/// Where a fit stands after one step, for its progress line.
struct Tick {
    done: bool,
    name: String,
    stage: u8,
    frac: f64,
    rest: String,
}

/// Steps a fit to its end with `step`, redrawing its progress line ([`progress_bar`]) on
/// stderr at the first step, every 0.2 s after and at the end.
fn step_with_progress(mut step: impl FnMut() -> Tick) {
    let start = Instant::now();
    let mut last_draw = -1.0f64;
    let mut stderr = std::io::stderr();
    loop {
        let p = step();
        let t = start.elapsed().as_secs_f64();
        if p.done || t - last_draw > 0.2 {
            last_draw = t;
            let line = progress_bar(&p.name, p.stage, p.frac, t, &p.rest);
            let _ = write!(stderr, "{line}");
            let _ = stderr.flush();
        }
        if p.done {
            break;
        }
    }
    let _ = writeln!(stderr);
}

/// The progress line of a fit: `name stage s/3 [####....] pct …, ETA`.
fn progress_bar(name: &str, stage: u8, frac: f64, t: f64, rest: &str) -> String {
    let frac = frac.clamp(0.0, 1.0);
    let eta = if frac > 0.02 {
        seconds(t / frac - t)
    } else {
        "?".into()
    };
    let bar: String = (0..30)
        .map(|i| if (i as f64) < frac * 30.0 { '#' } else { '.' })
        .collect();
    format!(
        "\r{name} stage {stage}/3 [{bar}] {:>3.0}% {rest}, ETA {eta}   ",
        100.0 * frac
    )
}

/// A tree's label image from a file: a grey image holding only the label values 0, 1, 2 and
/// 255 is taken as labels, anything else as a photo labelled by colour.
fn load_tree_labels(
    path: &Path,
    colors: Option<&str>,
) -> Result<procfit::mask::LabelImage, String> {
    let (labels, note) = read_tree_labels(path, colors)?;
    if let Some(n) = note {
        eprintln!("procfit: {}: {n}", path.display());
    }
    // Implausible labels are said, not fitted into a leafless stick.
    if let Some(problem) = procfit::tree::labels::foliage_problem(&labels) {
        return Err(format!("{}: {problem}", path.display()));
    }
    Ok(labels)
}

/// [`load_tree_labels`] without its checks or messages: the labels at the file's own size,
/// and how a photo was labelled when it was not by the colour rules.
pub(crate) fn read_tree_labels(
    path: &Path,
    colors: Option<&str>,
) -> Result<(procfit::mask::LabelImage, Option<String>), String> {
    use procfit::tree::labels;
    let thresholds = match colors {
        None => labels::ColorThresholds::default(),
        Some(text) => {
            labels::ColorThresholds::from_json(text).map_err(|e| format!("--tree-colors: {e}"))?
        }
    };
    let (_, rgba) = read_image(path)?;
    let (w, h) = rgba.dimensions();
    labels::labels_from_image(w, h, rgba.as_raw(), &thresholds)
        .map_err(|e| format!("{}: {e}", path.display()))
}

/// A fitted tree's part colours from its photo's leaf and branch pixels, printed; none for a
/// grey label image (its pixels are labels, not colours).
fn tree_photo_colors(
    model: &Model,
    path: &Path,
    labels: &procfit::mask::LabelImage,
) -> Result<procfit::model::PartColors, String> {
    use procfit::colors;
    let (_, rgba) = read_image(path)?;
    if rgba.pixels().all(|p| p[0] == p[1] && p[1] == p[2]) {
        return Ok(procfit::model::PartColors::new());
    }
    let mesh = model
        .generator
        .generate(&model.params, model.lod)
        .map_err(|e| e.to_string())?;
    let photo = colors::Rgba {
        width: rgba.width(),
        height: rgba.height(),
        pixels: rgba.as_raw(),
    };
    let found = colors::from_tree_labels(&mesh, labels, &photo).map_err(|e| e.to_string())?;
    print_colors(&found);
    Ok(colors::to_part_colors(&found))
}

/// Prints the part colours a fit measured (sRGB hex), and a note for the parts not seen.
fn print_colors(found: &[procfit::colors::PartColor]) {
    use procfit::colors;
    let each: Vec<String> = found
        .iter()
        .map(|c| {
            let [r, g, b] = c
                .color
                .map(|v| (colors::linear_to_srgb(v) * 255.0).round() as u8);
            format!("{} #{r:02x}{g:02x}{b:02x}", c.part)
        })
        .collect();
    println!("colours from the photos: {}", each.join(", "));
    if let Some(note) = colors::unseen_note(found) {
        eprintln!("procfit: note: {note}");
    }
}

/// `procfit reconstruct --generator tree`: the tree GA on one image, progress on stderr, the
/// GLB with the photo's camera (and params JSON) out.
fn reconstruct_tree(
    a: &ReconstructArgs,
    generator: &'static dyn generators::Generator,
    target: &Target,
    from: Option<&[f64]>,
) -> Result<(), String> {
    let [image] = &a.images[..] else {
        return Err(format!(
            "a tree is fitted to one image, not {}",
            a.images.len()
        ));
    };
    let labels = load_tree_labels(image, a.tree_colors.as_deref())?;
    let procfit::tree::impostor::PhotoTreeFit {
        mut session,
        framing,
    } = procfit::tree::impostor::start_photo_fit_with(
        &labels,
        a.seed,
        // `--budget` wins; else the core's policy for the quality, as on the page.
        match a.budget {
            Some(b) => Some(b),
            None => procfit::tree::impostor::ga_budget_for_quality(a.quality)
                .map_err(|e| e.to_string())?,
        },
        from,
        &procfit::tree::impostor::PhotoFitOptions {
            fov_y: a.fov,
            ..Default::default()
        },
    )
    .map_err(|e| format!("{}: {e}", image.display()))?;
    let start = Instant::now();
    step_with_progress(|| {
        let p = session.step();
        Tick {
            done: p.done,
            name: generator.name().into(),
            stage: p.stage,
            frac: p.evaluations as f64 / p.total_evaluations.max(1) as f64,
            rest: format!(
                "{} evals, similarity {:.3}",
                p.evaluations, p.best_similarity
            ),
        }
    });
    let fit = session.result().map_err(|e| e.to_string())?;
    let mut model = Model::new(generator.name(), &fit.params, lod_of(a, generator)?)
        .map_err(|e| e.to_string())?;
    model.seed = Some(a.seed);
    if !a.default_colors {
        let colors = tree_photo_colors(&model, image, &labels)?;
        model = model.with_colors(&colors).map_err(|e| e.to_string())?;
    }
    let photo_view = framing.photo_view().map_err(|e| e.to_string())?;
    let carved = if a.no_carve {
        None
    } else {
        let carve =
            LeafCarve::new(labels.clone(), photo_view, CARVE_GRID).map_err(|e| e.to_string())?;
        let whole = model.mesh().map_err(|e| e.to_string())?;
        let (mesh, carving) = carve.apply(&whole).map_err(|e| e.to_string())?;
        let iou = |m: &Mesh| {
            procfit::tree::bench::photo_view_iou(m, &photo_view, &labels).map_err(|e| e.to_string())
        };
        let ious = (iou(&whole)?, iou(&mesh)?);
        model.carve = Some(Arc::new(carve));
        Some((carving, ious))
    };
    let name = image.file_name().map(|n| n.to_string_lossy().into_owned());
    let cameras = [reconstruct::export_camera(&photo_view, name)];
    let summary = write_outputs(a, target, &model, &cameras)?;
    let from = session
        .start_similarity()
        .map(|s| format!(" (the start's {s:.3})"))
        .unwrap_or_default();
    let paper = session.paper_similarity().map_err(|e| e.to_string())?;
    let iou = session.silhouette_iou().map_err(|e| e.to_string())?;
    let fov = match a.fov {
        Some(f) => format!("field of view {f:.3} rad"),
        None => "field of view unknown: the fit assumed its default".into(),
    };
    println!(
        "wrote {}: {} fitted to 1 view in {:.1} s, {} evaluations, similarity {paper:.3}, \
         photo-view IoU {iou:.3}, fitness {:.3}{from}, {fov}; lod {}, {summary}",
        a.output.display(),
        generator.name(),
        start.elapsed().as_secs_f64(),
        fit.ga.evaluations,
        fit.similarity,
        model.lod.index()
    );
    if let Some((c, (whole, carved))) = carved {
        println!(
            "carved by the photo: {} leaf cards added where the crown missed its \
             foliage, {} of {} leaf tiles ({} cards cut into up to {CARVE_GRID}×{CARVE_GRID}) \
             dropped where it sees through the crown, {} trunk and branch triangles cut where \
             it sees sky; photo-view IoU at the photo's size {whole:.3} → {carved:.3} \
             (--no-carve keeps the tree as generated)",
            c.added, c.tiles_removed, c.tiles, c.cards, c.stems
        );
    }
    if let Some(w) = eval::tree_match_warning(
        iou,
        eval::photo_match_level(&generators::tree::TreeGenerator),
        "--tree-colors, or give a label image of 0 background, 1 branch, 2 leaf",
    ) {
        eprintln!("warning: {w}");
    }
    Ok(())
}

/// `--lod` as a level of detail; without it, the generator's export detail ([`fitted_lod`]).
fn lod_of(a: &ReconstructArgs, generator: &dyn generators::Generator) -> Result<Lod, String> {
    match a.lod {
        None => Ok(fitted_lod(generator)),
        Some(l) => {
            Lod::from_index(usize::from(l)).ok_or_else(|| format!("lod {l} is not in 0..=3"))
        }
    }
}

/// Writes the model (with its cameras, in a GLB) to `-o` in the target's format and the params
/// JSON to `--params-out`; returns the export's summary.
fn write_outputs(
    a: &ReconstructArgs,
    target: &Target,
    model: &Model,
    cameras: &[procfit::glb::ExportCamera],
) -> Result<String, String> {
    let summary = target.write(model, cameras)?;
    if let Some(path) = &a.params_out {
        write_atomic(path, model.to_json().as_bytes())?;
    }
    Ok(summary)
}

fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let bad = || format!("size `{s}` is not W or WxH with sides in 1..=8192");
    let (w, h) = match s.split_once(['x', 'X']) {
        Some((w, h)) => (w.parse::<u32>(), h.parse::<u32>()),
        None => (s.parse::<u32>(), s.parse::<u32>()),
    };
    let (w, h) = (w.map_err(|_| bad())?, h.map_err(|_| bad())?);
    if !(1..=8192).contains(&w) || !(1..=8192).contains(&h) {
        return Err(bad());
    }
    Ok((w, h))
}

fn model_from(
    generator: &str,
    preset: Option<&str>,
    params: Option<&Path>,
) -> Result<Model, String> {
    let g = generators::by_name(generator)
        .ok_or_else(|| format!("unknown generator `{generator}` (see `procfit generators`)"))?;
    match (preset, params) {
        (Some(name), _) => {
            let p = g
                .preset(name)
                .ok_or_else(|| format!("{generator} has no preset `{name}`"))?;
            Model::new(generator, &p.values, Lod::High).map_err(|e| e.to_string())
        }
        (None, Some(path)) => Ok(load_params(path, generator)?.0),
        (None, None) => Err("give --preset or --params".into()),
    }
}

/// The params JSON file `path` for `generator` (the CLI's `--params`), and the document as
/// written (whether it gave a level of detail, say); a file for another generator is an error.
pub fn load_params(
    path: &Path,
    generator: &str,
) -> Result<(Model, procfit::model::ParamsDoc), String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let doc: procfit::model::ParamsDoc =
        serde_json::from_str(&text).map_err(|e| format!("{}: params JSON: {e}", path.display()))?;
    let m = Model::from_doc(&doc).map_err(|e| format!("{}: {e}", path.display()))?;
    if m.generator.name() != generator {
        return Err(format!(
            "{} holds parameters for `{}`, not `{generator}`",
            path.display(),
            m.generator.name()
        ));
    }
    Ok((m, doc))
}

/// `procfit render`: a silhouette PNG (white object on black).
pub fn render(a: &RenderArgs) -> Result<(), String> {
    let mut plan = Outputs::new().input(&a.camera).output("-o", &a.output);
    if let Some(p) = &a.params {
        plan = plan.input(p);
    }
    plan.check()?;
    let format = image::ImageFormat::from_path(&a.output)
        .map_err(|_| format!("-o {}: name it .png", a.output.display()))?;
    let model = model_from(&a.generator, a.preset.as_deref(), a.params.as_deref())?;
    let text = std::fs::read_to_string(&a.camera)
        .map_err(|e| format!("cannot read {}: {e}", a.camera.display()))?;
    let vars: ViewVars = serde_json::from_str(&text)
        .map_err(|e| format!("{}: camera JSON: {e}", a.camera.display()))?;
    let (w, h) = parse_size(&a.size)?;
    let view = vars.view(w, h);
    view.params
        .validate()
        .map_err(|e| format!("{}: {e}", a.camera.display()))?;
    let mesh = model
        .generator
        .generate(&model.params, model.lod)
        .map_err(|e| e.to_string())?;
    let coverage = reconstruct::render_coverage(&mesh, &view)?;
    let luma: Vec<u8> = coverage
        .iter()
        .map(|&c| (c * 255.0).round() as u8)
        .collect();
    let img = image::GrayImage::from_raw(w, h, luma).ok_or("internal: image size mismatch")?;
    let mut png = std::io::Cursor::new(Vec::new());
    img.write_to(&mut png, format)
        .map_err(|e| format!("cannot encode {}: {e}", a.output.display()))?;
    write_atomic(&a.output, png.get_ref())?;
    println!("wrote {}: {w}×{h}", a.output.display());
    Ok(())
}

/// `procfit eval`: IoU-64 between a model GLB and a reference.
pub fn eval(a: &EvalArgs) -> Result<(), String> {
    let reference = glb::import_reference(&read(&a.reference)?)
        .map_err(|e| format!("{}: {e}", a.reference.display()))?;
    let model =
        glb::import_glb(&read(&a.model)?).map_err(|e| format!("{}: {e}", a.model.display()))?;
    let m = &model.reference;
    if m.triangles.is_empty() {
        return Err(format!("{}: the model has no triangles", a.model.display()));
    }
    // Without a known pose of the reference both are taken upright (Y up) and the model's turn
    // about Y is found by search at low resolution.
    let turned = |angle: f32| -> Vec<glam::Vec3> {
        let q = glam::Quat::from_rotation_y(angle);
        m.positions.iter().map(|&p| q * p).collect()
    };
    let r = (&reference.positions[..], &reference.triangles[..]);
    let mut best = (0.0f32, -1.0f64);
    for k in 0..16 {
        let angle = std::f32::consts::TAU * k as f32 / 16.0;
        let iou = eval::turntable_iou((&turned(angle), &m.triangles), r, 64, 16)
            .map_err(|e| e.to_string())?;
        if iou > best.1 {
            best = (angle, iou);
        }
    }
    let iou = eval::iou64((&turned(best.0), &m.triangles), r, eval::EVAL_SIDE)
        .map_err(|e| e.to_string())?;
    println!(
        "IoU-64: {iou:.4} (model turned {:.1}° about Y)",
        best.0.to_degrees()
    );
    if let Some(mask_path) = &a.mask {
        // A photo is cut for the kind of object the model is, when the file says.
        let kind = model.doc().and_then(|d| generators::by_name(&d.generator));
        let mask = load_mask(mask_path, &segment::Options::for_generator(kind))?;
        let cam = model
            .cameras
            .first()
            .ok_or_else(|| format!("{}: the model has no camera", a.model.display()))?;
        let view = reconstruct::camera_view(cam, mask.width(), mask.height());
        let mesh = Mesh {
            positions: m.positions.clone(),
            triangles: m.triangles.clone(),
            ..Mesh::default()
        };
        let v = eval::view_iou(&mesh, &view, &mask).map_err(|e| e.to_string())?;
        println!("input-view IoU: {v:.4}");
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("procfit-recon-cli-{}", std::process::id()));
        std::fs::create_dir_all(&d).expect("scratch dir");
        d.join(name)
    }

    /// A white disc on black, `w × h`.
    fn disc_png(name: &str, w: u32, h: u32) -> PathBuf {
        let p = scratch(name);
        let (cx, cy, r) = (w as f32 / 2.0, h as f32 / 2.0, h as f32 / 4.0);
        image::GrayImage::from_fn(w, h, |x, y| {
            let d = ((x as f32 - cx).powi(2) + (y as f32 - cy).powi(2)).sqrt();
            image::Luma([if d < r { 255 } else { 0 }])
        })
        .save(&p)
        .expect("write png");
        p
    }

    /// Issue 19: a 4000×3000 mask took 8× a 512² one; it is now brought to the working size at
    /// decode, as soft coverage.
    #[test]
    fn a_large_mask_is_loaded_at_the_working_size() {
        let v = load_view(
            &disc_png("big.png", 4000, 3000),
            &segment::Options::default(),
        )
        .expect("loads");
        assert_eq!((v.mask.width(), v.mask.height()), (512, 384));
        assert_eq!(v.file_size, (4000, 3000));
        let soft = v
            .mask
            .values()
            .iter()
            .filter(|&&c| c > 0.0 && c < 1.0)
            .count();
        assert!(soft > 0, "edge pixels keep partial coverage");
        let area = v.mask.area() / (512.0 * 384.0);
        let truth = std::f64::consts::PI * 0.25f64.powi(2) * 0.75;
        assert!((area - truth).abs() < 0.005, "area {area} vs {truth}");
    }

    /// Issue 19: 640×480 + 320×240 failed naming internal sizes; same aspect is now brought to
    /// one size, another aspect is refused naming the files' own sizes.
    #[test]
    fn views_of_one_aspect_share_a_size_and_other_aspects_are_refused() {
        let (a, b) = (disc_png("a.png", 640, 480), disc_png("b.png", 320, 240));
        let opts = segment::Options::default();
        let views = load_views(&[a.clone(), b], &opts).expect("same aspect");
        for v in &views {
            assert_eq!((v.mask.width(), v.mask.height()), (320, 240));
        }
        let c = disc_png("c.png", 480, 480);
        let err = load_views(&[a, c], &opts).err().expect("other aspect");
        assert!(err.contains("480×480") && err.contains("640×480"), "{err}");
        assert!(err.contains("aspect ratio"), "{err}");
    }

    #[test]
    fn resampling_keeps_dont_care_where_most_of_it_is() {
        let mut values = vec![1.0; 8 * 8];
        for v in &mut values[..32] {
            *v = Mask::DONT_CARE;
        }
        let m = Mask::new(8, 8, values).expect("mask");
        let small = resample_mask(&m, 4, 4);
        assert!(small.values()[..8].iter().all(|&v| v == Mask::DONT_CARE));
        assert!(small.values()[8..].iter().all(|&v| v == 1.0));
    }
}
