//! The JavaScript edge: the only module that knows about wasm-bindgen. It takes and returns flat
//! typed arrays and serde values, keeps sessions behind opaque handles, turns every error into a
//! JS error and never unwraps. Compiled for wasm32 only; runs inside `www/worker.js`.
#![deny(clippy::unwrap_used, clippy::expect_used)]

mod bench;

use std::sync::Mutex;
use wasm_bindgen::prelude::*;

mod fit;
mod mask;
mod tree;

pub use fit::FitSession;
pub use mask::MaskSession;
pub use tree::{TreeFitSession, tree_labels};

#[cfg(feature = "threads")]
pub use wasm_bindgen_rayon::init_thread_pool;

/// The message of the last panic, kept for the worker to report: with `panic=abort` a panic
/// traps the instance, and the worker reads this after catching the trap.
static LAST_PANIC: Mutex<Option<String>> = Mutex::new(None);

/// Installs the panic hook. Called once by the worker right after instantiation.
#[wasm_bindgen(start)]
pub fn start() {
    std::panic::set_hook(Box::new(|info| {
        let message = info.to_string();
        web_sys::console::error_1(&JsValue::from_str(&format!("procfit panicked: {message}")));
        if let Ok(mut slot) = LAST_PANIC.lock() {
            *slot = Some(message);
        }
    }));
}

/// The last panic message, taken (the worker calls this after a trap).
#[wasm_bindgen(js_name = takePanicMessage)]
pub fn take_panic_message() -> Option<String> {
    LAST_PANIC.lock().ok().and_then(|mut slot| slot.take())
}

/// The crate version.
#[wasm_bindgen]
pub fn version() -> String {
    crate::VERSION.to_string()
}

/// Whether this build runs rayon on a thread pool.
#[wasm_bindgen]
pub fn threaded() -> bool {
    cfg!(feature = "threads")
}

/// Runs `jobs` busy jobs through rayon and returns how many distinct pool threads ran them:
/// proof that the pool really works in parallel (the browser test asserts > 1).
#[wasm_bindgen(js_name = threadProbe)]
pub fn thread_probe(jobs: u32) -> u32 {
    use rayon::prelude::*;
    let mut seen: Vec<usize> = (0..jobs)
        .into_par_iter()
        .map(|i| {
            // A few milliseconds of arithmetic so that idle threads get to steal work.
            let mut x = u64::from(i) | 1;
            for _ in 0..400_000 {
                x = x
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
            }
            std::hint::black_box(x);
            rayon::current_thread_index().unwrap_or(usize::MAX)
        })
        .collect();
    seen.sort_unstable();
    seen.dedup();
    seen.len() as u32
}

/// Panics on purpose, so the browser test can check that a panic becomes an error message and
/// the worker comes back.
#[wasm_bindgen(js_name = debugPanic)]
pub fn debug_panic() {
    let v: Vec<u8> = Vec::new();
    // Index past the end: the panic the hook reports.
    std::hint::black_box(v.get(std::hint::black_box(3)).copied()).unwrap_or_else(|| {
        panic!("debugPanic: deliberate panic for the error-path test");
    });
}

/// The generators as a serde value: names, labels, parameter specs and presets, for the page's
/// generator choice and sliders.
#[wasm_bindgen(js_name = generatorSpecs)]
pub fn generator_specs() -> Result<JsValue, JsError> {
    #[derive(serde::Serialize)]
    struct Spec {
        name: &'static str,
        label: &'static str,
        version: u32,
        differentiable: bool,
        /// `gradients`, `tree_ga` or `null` (not fitted): how the page fits it.
        fit: Option<&'static str>,
        /// The name the page's generator choice shows.
        display_name: &'static str,
        /// The least level of detail (0..=3) a fitted model opens at.
        fitted_lod: u8,
        /// `none`, `windows` or `tree_labels`: the mask tools its fit reads.
        mask_extra: &'static str,
        /// The automatic mask's outline smoothing for this kind (a photo's mask is cut again
        /// when the kind changes to one with another).
        outline_smoothing: f32,
        /// Serialised by the generators crate (`ParamSpec`, `Preset`).
        params: &'static [crate::generators::ParamSpec],
        presets: Vec<crate::generators::Preset>,
    }
    let specs: Vec<Spec> = crate::generators::all()
        .into_iter()
        .map(|g| (g, g.capabilities()))
        .map(|(g, caps)| Spec {
            name: g.name(),
            label: g.label(),
            version: g.version(),
            differentiable: g.differentiable(),
            fit: caps.fit.map(|f| f.as_str()),
            display_name: caps.display_name,
            fitted_lod: caps.fitted_lod as u8,
            mask_extra: caps.mask_extra.as_str(),
            outline_smoothing: caps.outline_smoothing,
            params: g.params(),
            presets: g.presets(),
        })
        .collect();
    serde_wasm_bindgen::to_value(&specs).map_err(js)
}

/// The model a params JSON text or a procfit GLB describes, as the page keeps it.
#[derive(serde::Serialize)]
struct ModelOut {
    generator: &'static str,
    params: Vec<f64>,
    lod: u8,
    seed: Option<u64>,
    /// Part colours by part name (linear RGB), `{}` when the model has none.
    colors: crate::model::PartColors,
}

impl From<&crate::model::Model> for ModelOut {
    fn from(m: &crate::model::Model) -> Self {
        ModelOut {
            generator: m.generator.name(),
            params: m.params.clone(),
            lod: m.lod as u8,
            seed: m.seed,
            colors: m.colors.clone(),
        }
    }
}

/// The validated model for the page's `(generator, params, lod)`; every mistake is a message.
fn model_of(generator: &str, params: &[f64], lod: u8) -> Result<crate::model::Model, JsError> {
    let lod = crate::generators::Lod::from_index(usize::from(lod))
        .ok_or_else(|| JsError::new(&format!("level of detail {lod} is not in 0..=3")))?;
    crate::model::Model::new(generator, params, lod).map_err(js)
}

/// [`model_of`] with part colours: `colors` is `{ part: [r, g, b] }` (linear, 0–1), or
/// `null`/`undefined` for the generator's defaults.
fn colored_model_of(
    generator: &str,
    params: &[f64],
    lod: u8,
    colors: JsValue,
) -> Result<crate::model::Model, JsError> {
    let model = model_of(generator, params, lod)?;
    if colors.is_null() || colors.is_undefined() {
        return Ok(model);
    }
    let colors: crate::model::PartColors = serde_wasm_bindgen::from_value(colors)
        .map_err(|e| JsError::new(&format!("part colours: {e}")))?;
    model.with_colors(&colors).map_err(js)
}

/// Part colours measured in the photos as the page takes them: `{ colors: { part: [r, g, b] },
/// parts: [{ part, color, source, from }], note }` — `colors` what the model takes (measured or
/// borrowed), `parts` where each part's colour comes from (`photo`, `neighbour` of `from`, or
/// `default`), `note` a sentence on the parts the photos do not show, or `null`.
pub(crate) fn colors_out(found: &[crate::colors::PartColor]) -> Result<JsValue, JsError> {
    use crate::colors::{self, Source};
    #[derive(serde::Serialize)]
    struct PartOut {
        part: &'static str,
        color: [f32; 3],
        source: &'static str,
        from: Option<&'static str>,
    }
    #[derive(serde::Serialize)]
    struct ColorsOut {
        colors: crate::model::PartColors,
        parts: Vec<PartOut>,
        note: Option<String>,
    }
    let out = ColorsOut {
        colors: colors::to_part_colors(found),
        parts: found
            .iter()
            .map(|c| {
                let (source, from) = match c.source {
                    Source::Photo { .. } => ("photo", None),
                    Source::Neighbour(f) => ("neighbour", Some(f)),
                    Source::Default => ("default", None),
                };
                PartOut {
                    part: c.part,
                    color: c.color,
                    source,
                    from,
                }
            })
            .collect(),
        note: colors::unseen_note(found),
    };
    to_js(&out)
}

/// A value for JavaScript with maps as plain objects (the page stores them in IndexedDB and
/// sends them back as objects).
pub(crate) fn to_js<T: serde::Serialize>(value: &T) -> Result<JsValue, JsError> {
    value
        .serialize(&serde_wasm_bindgen::Serializer::json_compatible())
        .map_err(js)
}

pub use crate::glb::CAMERA_FLOATS;

/// Every error crosses into JavaScript as a `JsError` with its message: the one conversion the
/// edge's modules share.
pub(crate) fn js(e: impl std::fmt::Display) -> JsError {
    JsError::new(&e.to_string())
}

/// Generates the model's mesh and writes it as the very GLB the page downloads (generator state
/// in the scene extras, one camera node per photo from `cameras`, see [`CAMERA_FLOATS`]). The
/// viewer loads these bytes, so what is shown is what is saved. `colors`: the part colours (see
/// `colored_model_of`), or `null`.
#[wasm_bindgen(js_name = generateGlb)]
pub fn generate_glb(
    generator: &str,
    params: &[f64],
    lod: u8,
    cameras: &[f32],
    colors: JsValue,
) -> Result<Vec<u8>, JsError> {
    let model = colored_model_of(generator, params, lod, colors)?;
    let cameras = cameras_of(cameras)?;
    crate::glb::export_model(&model, &cameras).map_err(js)
}

/// [`generate_glb`] of a tree whose leaves `carve` carves (a fitted tree's photo,
/// [`tree::TreeFitSession::carve`]); any other generator is written as [`generate_glb`] does.
#[wasm_bindgen(js_name = generateCarvedGlb)]
pub fn generate_carved_glb(
    generator: &str,
    params: &[f64],
    lod: u8,
    cameras: &[f32],
    colors: JsValue,
    carve: &tree::TreeCarve,
) -> Result<Vec<u8>, JsError> {
    let mut model = colored_model_of(generator, params, lod, colors)?;
    model.carve = Some(carve.0.clone());
    let cameras = cameras_of(cameras)?;
    crate::glb::export_model(&model, &cameras).map_err(js)
}

/// The page's download menu: the model in `format` (`glb`, `obj` or `stl`; `compact` for a
/// quantised GLB), as the files to save: `[main]`, or for OBJ `[obj, mtl]`, the OBJ naming its
/// MTL after `file_name` (the name the main file is saved as).
#[wasm_bindgen(js_name = exportFiles)]
#[allow(
    clippy::too_many_arguments,
    reason = "flat values are what crosses the wasm boundary cheaply"
)]
pub fn export_files(
    generator: &str,
    params: &[f64],
    lod: u8,
    cameras: &[f32],
    colors: JsValue,
    format: &str,
    compact: bool,
    file_name: &str,
) -> Result<js_sys::Array, JsError> {
    let model = colored_model_of(generator, params, lod, colors)?;
    export_model_files(&model, cameras, format, compact, file_name)
}

/// [`export_files`] of a tree whose leaves `carve` carves (see [`generate_carved_glb`]).
#[wasm_bindgen(js_name = exportCarvedFiles)]
#[allow(
    clippy::too_many_arguments,
    reason = "flat values are what crosses the wasm boundary cheaply"
)]
pub fn export_carved_files(
    generator: &str,
    params: &[f64],
    lod: u8,
    cameras: &[f32],
    colors: JsValue,
    format: &str,
    compact: bool,
    file_name: &str,
    carve: &tree::TreeCarve,
) -> Result<js_sys::Array, JsError> {
    let mut model = colored_model_of(generator, params, lod, colors)?;
    model.carve = Some(carve.0.clone());
    export_model_files(&model, cameras, format, compact, file_name)
}

/// The files of [`export_files`] for a model.
fn export_model_files(
    model: &crate::model::Model,
    cameras: &[f32],
    format: &str,
    compact: bool,
    file_name: &str,
) -> Result<js_sys::Array, JsError> {
    use crate::export::{ExportOptions, Format};
    let cameras = cameras_of(cameras)?;
    let format = Format::parse(format).map_err(|e| JsError::new(&e))?;
    let (files, _) = crate::export::write_model(
        model,
        &cameras,
        format,
        ExportOptions { compact },
        std::path::Path::new(file_name),
    )
    .map_err(|e| JsError::new(&e.to_string()))?;
    let out = js_sys::Array::new();
    out.push(&js_sys::Uint8Array::from(files.main.as_slice()));
    if let Some(companion) = files.companion {
        out.push(&js_sys::Uint8Array::from(companion.as_slice()));
    }
    Ok(out)
}

/// The photo cameras of [`generate_glb`] and [`export_files`] (see [`CAMERA_FLOATS`]).
fn cameras_of(cameras: &[f32]) -> Result<Vec<crate::glb::ExportCamera>, JsError> {
    if !cameras.len().is_multiple_of(CAMERA_FLOATS) {
        return Err(JsError::new(&format!(
            "{} camera numbers is not a multiple of {CAMERA_FLOATS}",
            cameras.len()
        )));
    }
    let cameras: Vec<crate::glb::ExportCamera> = cameras
        .as_chunks::<CAMERA_FLOATS>()
        .0
        .iter()
        .enumerate()
        .map(|(i, c)| crate::glb::ExportCamera::from_floats(c, Some(format!("photo {}", i + 1))))
        .collect();
    Ok(cameras)
}

/// The paper's IoU-64 (mean silhouette IoU over 64 turntable views at `side`², both meshes
/// normalised to a unit box) between two models at level of detail `lod`: the benchmark's
/// measure of how well a fit recovered a known shape.
#[wasm_bindgen(js_name = iou64Models)]
pub fn iou64_models(
    generator_a: &str,
    params_a: &[f64],
    generator_b: &str,
    params_b: &[f64],
    lod: u8,
    side: u32,
) -> Result<f64, JsError> {
    if !(16..=1024).contains(&side) {
        return Err(JsError::new("side must be in 16..=1024"));
    }
    let mesh = |g: &str, p: &[f64]| {
        let m = model_of(g, p, lod)?;
        m.generator.generate(&m.params, m.lod).map_err(js)
    };
    let a = mesh(generator_a, params_a)?;
    let b = mesh(generator_b, params_b)?;
    crate::reconstruct::iou64(
        (&a.positions, &a.triangles),
        (&b.positions, &b.triangles),
        side,
    )
    .map_err(js)
}

/// The params JSON of a model (what "download params" saves), with its part colours (or
/// `null`).
#[wasm_bindgen(js_name = paramsJson)]
pub fn params_json(
    generator: &str,
    params: &[f64],
    lod: u8,
    colors: JsValue,
) -> Result<String, JsError> {
    Ok(colored_model_of(generator, params, lod, colors)?.to_json())
}

/// Opens a file the user gave to continue editing: a procfit GLB (told by its magic) or params
/// JSON. Returns `{ generator, params, lod, seed, colors }` with the parameters validated and clamped;
/// a GLB from another tool, or JSON that is not procfit's, is an error saying so.
#[wasm_bindgen(js_name = openModel)]
pub fn open_model(bytes: &[u8]) -> Result<JsValue, JsError> {
    let model = crate::model::Model::from_file_bytes(bytes).map_err(js)?;
    to_js(&ModelOut::from(&model))
}

/// The 35 mm-equivalent focal length from a photo file's EXIF (the original bytes: the page's
/// downscaled bitmap has lost its EXIF), or 0 when the file has none.
#[wasm_bindgen(js_name = focal35mmFromFile)]
pub fn focal_35mm_from_file(bytes: &[u8]) -> f64 {
    crate::reconstruct::views::focal_35mm_from_file(bytes).unwrap_or(0.0)
}

/// The vertical field of view (radians) of a `width × height` photo taken at a 35 mm-equivalent
/// focal length, or 0 when an argument is not positive.
#[wasm_bindgen(js_name = fovFromFocal35mm)]
pub fn fov_from_focal_35mm(focal_35mm: f64, width: u32, height: u32) -> f64 {
    crate::reconstruct::fov_from_focal_35mm(focal_35mm, width, height).unwrap_or(0.0)
}
