//! `procfit segment`: the automatic mask a fit would use, written as a PNG so a CLI user can
//! see it, correct it in any image editor and give it back to `reconstruct` (issue 16).
//!
//! The mask is the very one `reconstruct` makes from the photo ([`recon_cli::read_view`]), at
//! the same working size (512 px on the longest side, or the photo's own size when smaller):
//! white object, black background, grey 128 don't care (where a semi-transparent alpha leaves a
//! pixel unsure, or where the user paints it), which
//! `reconstruct` reads back as it was written. A generator's mask extras come with it: a
//! building's window mask (white = window, at the same size; `reconstruct --windows`), a
//! tree's label image (0 background, 1 branch, 2 leaf, 255 don't care, at the photo's own size,
//! what `reconstruct --generator tree` takes instead of the photo).

use crate::outputs::{Outputs, write_atomic};
use crate::recon_cli;
use clap::Args;
use procfit::generators::{self, MaskExtra};
use procfit::mask::LabelImage;
use procfit::segment::{self, windows};
use std::path::{Path, PathBuf};

/// `procfit segment`.
#[derive(Args)]
pub struct SegmentArgs {
    /// The photo (JPEG, PNG or WebP); a mask image or a photo with transparency is read as
    /// `reconstruct` reads it.
    image: PathBuf,
    /// The mask PNG: white object, black background, grey 128 don't care, at the working size
    /// (512 px on the longest side, or the photo's own size when smaller).
    #[arg(short, long)]
    output: PathBuf,
    /// The kind of object: a generator's name (see `procfit generators`) or auto. A generator
    /// with windows also gets its window mask, a tree its label image.
    #[arg(long, default_value = "auto")]
    generator: String,
    /// Where to write the window mask (generators with windows; default: beside -o, with
    /// `.windows.png` for its `.png`).
    #[arg(long)]
    windows_out: Option<PathBuf>,
    /// Where to write the tree's label image (default: beside -o, with `.labels.png` for its
    /// `.png`).
    #[arg(long)]
    labels_out: Option<PathBuf>,
    /// Trees: the colour rules that label the photo, as for `reconstruct --tree-colors`.
    #[arg(long)]
    tree_colors: Option<String>,
}

/// `path` with its `.png` replaced by `.{suffix}.png`.
fn beside(path: &Path, suffix: &str) -> PathBuf {
    let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned());
    path.with_file_name(format!("{}.{suffix}.png", stem.unwrap_or_default()))
}

/// A path's extension is `.png`, since the don't-care grey must survive the file.
fn check_png(what: &str, path: &Path) -> Result<(), String> {
    let png = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("png"));
    if png {
        Ok(())
    } else {
        Err(format!(
            "{what} {}: name it .png (a mask must be lossless)",
            path.display()
        ))
    }
}

/// Encodes grey levels as a PNG and writes it atomically.
fn write_grey(path: &Path, width: u32, height: u32, levels: Vec<u8>) -> Result<(), String> {
    let img =
        image::GrayImage::from_raw(width, height, levels).ok_or("internal: image size mismatch")?;
    let mut png = std::io::Cursor::new(Vec::new());
    img.write_to(&mut png, image::ImageFormat::Png)
        .map_err(|e| format!("cannot encode {}: {e}", path.display()))?;
    write_atomic(path, png.get_ref())
}

/// `procfit segment`: the mask (and the generator's extras) out, confidence and warnings said.
pub fn segment(a: &SegmentArgs) -> Result<(), String> {
    let kind = if a.generator == "auto" {
        None
    } else {
        Some(generators::by_name(&a.generator).ok_or_else(|| {
            format!(
                "unknown generator `{}` (see `procfit generators`)",
                a.generator
            )
        })?)
    };
    let extra = kind.map_or(MaskExtra::None, |g| g.capabilities().mask_extra);
    if a.tree_colors.is_some() && extra != MaskExtra::TreeLabels {
        return Err("--tree-colors is for a generator fitted to tree labels".into());
    }
    let windows_out = (extra == MaskExtra::Windows).then(|| {
        a.windows_out
            .clone()
            .unwrap_or_else(|| beside(&a.output, "windows"))
    });
    let labels_out = (extra == MaskExtra::TreeLabels).then(|| {
        a.labels_out
            .clone()
            .unwrap_or_else(|| beside(&a.output, "labels"))
    });
    if a.windows_out.is_some() && windows_out.is_none() {
        return Err(format!("--windows-out: `{}` has no windows", a.generator));
    }
    if a.labels_out.is_some() && labels_out.is_none() {
        return Err(format!(
            "--labels-out: `{}` has no tree labels",
            a.generator
        ));
    }
    // Every output is checked before any work, and none may be the photo.
    let mut plan = Outputs::new().input(&a.image).output("-o", &a.output);
    let mut named = vec![("-o", &a.output)];
    if let Some(p) = &windows_out {
        plan = plan.output("--windows-out", p);
        named.push(("--windows-out", p));
    }
    if let Some(p) = &labels_out {
        plan = plan.output("--labels-out", p);
        named.push(("--labels-out", p));
    }
    plan.check()?;
    for (what, p) in named {
        check_png(what, p)?;
    }
    let name = a.image.display();
    match &labels_out {
        Some(path) => write_tree(a, path)?,
        None => {
            // Cut as `reconstruct --generator` of the same kind cuts it.
            let view = recon_cli::read_view(&a.image, &segment::Options::for_generator(kind))?;
            for w in &view.warnings {
                eprintln!("procfit: {name}: {w}");
            }
            let mask = &view.mask;
            let (w, h) = (mask.width(), mask.height());
            write_grey(&a.output, w, h, mask.to_luma8())?;
            let cares = mask
                .values()
                .iter()
                .filter(|&&v| v != procfit::mask::Mask::DONT_CARE)
                .count()
                .max(1);
            let how = match &view.segmentation {
                Some(seg) => format!("automatic, confidence {:.2}", seg.confidence),
                None => "read from the image".into(),
            };
            println!(
                "wrote {}: {w}×{h} mask ({how}), object {:.1} % of the pixels that count",
                a.output.display(),
                100.0 * mask.area() / cares as f64
            );
            if let Some(fov) = view.fov {
                println!(
                    "field of view from the photo's EXIF: {fov:.4} rad; a mask image has none, so give reconstruct --fov {fov:.4} with it"
                );
            }
            if let Some(path) = &windows_out {
                write_windows(&view, path)?;
            }
        }
    }
    Ok(())
}

/// A building's window mask: windows found in the photo inside its mask, white on black.
fn write_windows(view: &recon_cli::LoadedView, path: &Path) -> Result<(), String> {
    let name = path.display();
    let seg = match &view.segmentation {
        Some(seg) => seg.clone(),
        None if view.photo.has_alpha() => {
            segment::segment_alpha(&view.photo).map_err(|e| format!("{name}: {e}"))?
        }
        None => {
            return Err(
                "windows are found in a photo's colours: give the photo, not a mask image".into(),
            );
        }
    };
    let labels = windows::detect_windows(&view.photo, &seg).map_err(|e| format!("{name}: {e}"))?;
    let levels: Vec<u8> = labels
        .labels()
        .iter()
        .map(|&l| if l == windows::LABEL_WINDOW { 255 } else { 0 })
        .collect();
    let share = levels.iter().filter(|&&v| v == 255).count() as f64 / levels.len().max(1) as f64;
    write_grey(path, labels.width(), labels.height(), levels)?;
    println!(
        "wrote {name}: window mask, windows {:.1} % of the image",
        100.0 * share
    );
    Ok(())
}

/// A tree's label image (what the tree fit uses) and its object mask (branch or leaf, don't
/// care kept), both at the photo's own size.
fn write_tree(a: &SegmentArgs, labels_path: &Path) -> Result<(), String> {
    let name = a.image.display();
    let (labels, note) = recon_cli::read_tree_labels(&a.image, a.tree_colors.as_deref())?;
    if let Some(n) = note {
        eprintln!("procfit: {name}: {n}");
    }
    if let Some(problem) = procfit::tree::labels::foliage_problem(&labels) {
        eprintln!("procfit: {name}: warning: {problem}");
    }
    let (w, h) = (labels.width(), labels.height());
    let mask: Vec<u8> = labels
        .labels()
        .iter()
        .map(|&l| match l {
            LabelImage::DONT_CARE => 128,
            procfit::tree::BACKGROUND => 0,
            _ => 255,
        })
        .collect();
    write_grey(&a.output, w, h, mask)?;
    write_grey(labels_path, w, h, labels.labels().to_vec())?;
    let count = |v: u8| labels.labels().iter().filter(|&&l| l == v).count();
    let n = labels.labels().len().max(1) as f64;
    println!(
        "wrote {} (the tree's mask) and {} (its labels: 0 background, 1 branch, 2 leaf, 255 don't care), {w}×{h}: branch {:.1} %, leaf {:.1} % of the image",
        a.output.display(),
        labels_path.display(),
        100.0 * count(procfit::tree::BRANCH) as f64 / n,
        100.0 * count(procfit::tree::LEAF) as f64 / n,
    );
    Ok(())
}
