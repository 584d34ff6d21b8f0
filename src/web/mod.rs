//! The JavaScript edge: the only module that knows about wasm-bindgen. It takes and returns flat
//! typed arrays and serde values, keeps sessions behind opaque handles, turns every error into a
//! JS error and never unwraps. Compiled for wasm32 only; runs inside `www/worker.js`.
#![deny(clippy::unwrap_used, clippy::expect_used)]

mod bench;

use std::sync::Mutex;
use wasm_bindgen::prelude::*;

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
    struct Param {
        name: &'static str,
        label: &'static str,
        group: &'static str,
        unit: &'static str,
        min: f64,
        max: f64,
        default: f64,
        kind: &'static str,
        choices: Vec<&'static str>,
    }
    #[derive(serde::Serialize)]
    struct Preset {
        name: &'static str,
        label: &'static str,
        values: Vec<f64>,
    }
    #[derive(serde::Serialize)]
    struct Spec {
        name: &'static str,
        label: &'static str,
        version: u32,
        differentiable: bool,
        params: Vec<Param>,
        presets: Vec<Preset>,
    }
    use crate::generators::ParamKind;
    let specs: Vec<Spec> = crate::generators::all()
        .into_iter()
        .map(|g| Spec {
            name: g.name(),
            label: g.label(),
            version: g.version(),
            differentiable: g.differentiable(),
            params: g
                .params()
                .iter()
                .map(|p| {
                    let (kind, choices) = match p.kind {
                        ParamKind::Continuous => ("continuous", vec![]),
                        ParamKind::Integer => ("integer", vec![]),
                        ParamKind::Boolean => ("boolean", vec![]),
                        ParamKind::Categorical(c) => ("categorical", c.to_vec()),
                    };
                    Param {
                        name: p.name,
                        label: p.label,
                        group: p.group,
                        unit: p.unit,
                        min: p.min,
                        max: p.max,
                        default: p.default,
                        kind,
                        choices,
                    }
                })
                .collect(),
            presets: g
                .presets()
                .into_iter()
                .map(|p| Preset {
                    name: p.name,
                    label: p.label,
                    values: p.values,
                })
                .collect(),
        })
        .collect();
    serde_wasm_bindgen::to_value(&specs).map_err(|e| JsError::new(&e.to_string()))
}
