//! The params JSON: a generator's full state by name, shared by the CLI (`--params`,
//! `--params-out`), the page (open/save) and the GLB scene `extras`.
//!
//! ```json
//! { "generator": "dish", "version": 1, "params": { "height_scale": 0.8, ... }, "lod": 1, "seed": 7 }
//! ```
//!
//! `colors`, when present, holds per-part base colours (linear RGB in 0–1, by part name)
//! estimated from the photos ([`crate::colors`]); they replace the generator's default part
//! colours in every export and survive editing, refitting and reopening.
//!
//! Reading is strict where a mistake would silently change the model (unknown generator, a name
//! the generator does not have, a value that is not a finite number, a newer version) and lenient
//! where it cannot (a missing parameter takes its default; values out of range are clamped by the
//! generator).

use crate::generators::{self, Generator, Lod, Mesh, sanitize_params};
use crate::tree::carve::LeafCarve;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fmt;
use std::sync::Arc;

/// Per-part base colours by part name: linear RGB, each channel in 0–1 (glTF's
/// `baseColorFactor` without alpha). A part not named keeps its generator default.
pub type PartColors = BTreeMap<String, [f32; 3]>;

/// A generator's state as stored in params JSON and GLB extras.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ParamsDoc {
    /// Generator machine name.
    pub generator: String,
    /// Version of the generator's parameterisation.
    pub version: u32,
    /// Every parameter by name, in spec order.
    pub params: serde_json::Map<String, serde_json::Value>,
    /// Level of detail 0..=3, when known.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lod: Option<u8>,
    /// Random seed of the fit, when known.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
    /// Per-part base colours from the photos, when the model has them.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub colors: PartColors,
}

/// A params document that cannot be used.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelError(pub String);

impl fmt::Display for ModelError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for ModelError {}

/// A generator with a concrete, validated parameter vector.
#[derive(Clone)]
pub struct Model {
    /// The generator.
    pub generator: &'static dyn Generator,
    /// One value per parameter, validated and clamped.
    pub params: Vec<f64>,
    /// Level of detail.
    pub lod: Lod,
    /// Seed of the fit, when the model comes from one.
    pub seed: Option<u64>,
    /// Per-part base colours (from the photos); empty: the generator's defaults.
    pub colors: PartColors,
    /// A tree's photo, which carves its leaves, trunk and branches where it sees through the tree
    /// ([`crate::tree::carve`]); `None` for any other model, or a tree as generated. Not in the
    /// params document: the parameters regenerate the uncarved tree.
    pub carve: Option<Arc<LeafCarve>>,
}

impl fmt::Debug for Model {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Model")
            .field("generator", &self.generator.name())
            .field("params", &self.params)
            .field("lod", &self.lod)
            .field("seed", &self.seed)
            .field("colors", &self.colors)
            .field("carve", &self.carve.as_ref().map(|c| c.grid()))
            .finish()
    }
}

impl Model {
    /// A model from a generator name and a raw parameter vector (validated).
    pub fn new(generator: &str, params: &[f64], lod: Lod) -> Result<Model, ModelError> {
        let g = generators::by_name(generator)
            .ok_or_else(|| ModelError(format!("unknown generator `{generator}`")))?;
        let params = sanitize_params(g.params(), params).map_err(|e| ModelError(e.to_string()))?;
        Ok(Model {
            generator: g,
            params,
            lod,
            seed: None,
            colors: PartColors::new(),
            carve: None,
        })
    }

    /// The document form of this model.
    pub fn to_doc(&self) -> ParamsDoc {
        let params = self
            .generator
            .params()
            .iter()
            .zip(&self.params)
            .map(|(s, &v)| (s.name.to_string(), serde_json::Value::from(v)))
            .collect();
        ParamsDoc {
            generator: self.generator.name().to_string(),
            version: self.generator.version(),
            params,
            lod: Some(self.lod as u8),
            seed: self.seed,
            colors: self.colors.clone(),
        }
    }

    /// The model a document describes.
    pub fn from_doc(doc: &ParamsDoc) -> Result<Model, ModelError> {
        let g = generators::by_name(&doc.generator)
            .ok_or_else(|| ModelError(format!("unknown generator `{}`", doc.generator)))?;
        if doc.version > g.version() {
            return Err(ModelError(format!(
                "params are for {} version {}, this procfit knows version {}",
                g.name(),
                doc.version,
                g.version()
            )));
        }
        if let Some(unknown) = doc
            .params
            .keys()
            .find(|k| !g.params().iter().any(|s| s.name == *k))
        {
            return Err(ModelError(format!(
                "{} has no parameter `{unknown}`",
                g.name()
            )));
        }
        let mut values = Vec::with_capacity(g.params().len());
        for s in g.params() {
            let v = match doc.params.get(s.name) {
                None => s.default,
                Some(v) => v.as_f64().ok_or_else(|| {
                    ModelError(format!("parameter `{}` is not a number: {v}", s.name))
                })?,
            };
            values.push(v);
        }
        let params = sanitize_params(g.params(), &values).map_err(|e| ModelError(e.to_string()))?;
        let lod = match doc.lod {
            None => Lod::Medium,
            Some(i) => Lod::from_index(usize::from(i))
                .ok_or_else(|| ModelError(format!("lod {i} is not in 0..=3")))?,
        };
        let colors = checked_colors(g, &doc.colors)?;
        Ok(Model {
            generator: g,
            params,
            lod,
            seed: doc.seed,
            colors,
            carve: None,
        })
    }

    /// This model with `colors` as its part colours (checked like a document's: every name a
    /// part of the generator, every channel a finite number, clamped to 0–1).
    pub fn with_colors(self, colors: &PartColors) -> Result<Model, ModelError> {
        let colors = checked_colors(self.generator, colors)?;
        Ok(Model { colors, ..self })
    }

    /// Generates the model's mesh at its level of detail, its parts coloured by
    /// [`Model::colors`]: the mesh every export writes.
    pub fn mesh(&self) -> Result<Mesh, generators::GenError> {
        let mut mesh = self.generator.generate(&self.params, self.lod)?;
        if let Some(c) = &self.carve
            && self.generator.capabilities().fit == Some(generators::FitMethod::TreeGa)
        {
            mesh = c
                .apply(&mesh)
                .map_err(|e| generators::GenError::InvalidMesh(e.0))?
                .0;
        }
        self.paint(&mut mesh);
        Ok(mesh)
    }

    /// Sets the base colour (not the alpha) of each part of `mesh` that [`Model::colors`] names.
    pub fn paint(&self, mesh: &mut Mesh) {
        for part in &mut mesh.parts {
            if let Some(c) = self.colors.get(part.name) {
                part.color[..3].copy_from_slice(c);
            }
        }
    }

    /// Parses params JSON.
    pub fn from_json(text: &str) -> Result<Model, ModelError> {
        let doc: ParamsDoc =
            serde_json::from_str(text).map_err(|e| ModelError(format!("params JSON: {e}")))?;
        Model::from_doc(&doc)
    }

    /// The model a file holds: a procfit GLB (told by its `glTF` magic; its scene extras) or
    /// params JSON text — the one check the CLI's `--start` and the page's "open" share. A GLB
    /// from another tool, or JSON that is not procfit's, is an error saying so.
    pub fn from_file_bytes(bytes: &[u8]) -> Result<Model, ModelError> {
        if bytes.starts_with(b"glTF") {
            return crate::glb::import_glb(bytes)
                .and_then(|g| g.model())
                .map_err(|e| ModelError(e.to_string()));
        }
        let text = std::str::from_utf8(bytes)
            .map_err(|_| ModelError("the file is neither a GLB nor params JSON text".into()))?;
        Model::from_json(text)
    }

    /// Pretty params JSON.
    pub fn to_json(&self) -> String {
        // Serialising a struct of strings, numbers and maps cannot fail.
        serde_json::to_string_pretty(&self.to_doc()).unwrap_or_default()
    }
}

/// The names of `g`'s parts (every level of detail lists them all), found once per generator
/// by generating its defaults at [`Lod::Low`]: the page checks colours on every slider move.
fn part_names(g: &dyn Generator) -> Result<Vec<&'static str>, ModelError> {
    use std::collections::HashMap;
    use std::sync::{Mutex, OnceLock};
    static NAMES: OnceLock<Mutex<HashMap<&'static str, Vec<&'static str>>>> = OnceLock::new();
    let cache = NAMES.get_or_init(|| Mutex::new(HashMap::new()));
    if let Some(names) = cache.lock().ok().and_then(|c| c.get(g.name()).cloned()) {
        return Ok(names);
    }
    let mesh = g
        .generate(&g.defaults(), Lod::Low)
        .map_err(|e| ModelError(e.to_string()))?;
    let names: Vec<&'static str> = mesh.parts.iter().map(|p| p.name).collect();
    if let Ok(mut c) = cache.lock() {
        c.insert(g.name(), names.clone());
    }
    Ok(names)
}

/// `colors` checked against `g`'s parts: an unknown part name or a non-finite channel is an
/// error (it would silently change nothing, or make an invalid file); channels are clamped to
/// 0–1. The part names are the generator's mesh parts (every level of detail lists them all).
fn checked_colors(g: &dyn Generator, colors: &PartColors) -> Result<PartColors, ModelError> {
    if colors.is_empty() {
        return Ok(PartColors::new());
    }
    let names = part_names(g)?;
    let mut out = PartColors::new();
    for (name, c) in colors {
        if !names.iter().any(|p| p == name) {
            return Err(ModelError(format!(
                "{} has no part `{name}` to colour (parts: {})",
                g.name(),
                names.join(", ")
            )));
        }
        if c.iter().any(|v| !v.is_finite()) {
            return Err(ModelError(format!("the colour of `{name}` is not finite")));
        }
        out.insert(name.clone(), c.map(|v| v.clamp(0.0, 1.0)));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A dish saved before the saucer (version 1, no saucer parameters) opens as the same cup
    /// without a saucer, and a document of a newer version than this procfit knows is refused.
    #[test]
    fn dish_params_of_version_1_open_without_a_saucer() {
        let g = generators::by_name("dish").unwrap_or_else(|| panic!("dish"));
        let mug = g.presets()[0].values.clone();
        let mut doc = Model::new("dish", &mug, Lod::Low)
            .unwrap_or_else(|e| panic!("{e}"))
            .to_doc();
        doc.version = 1;
        doc.params
            .retain(|k, _| !k.starts_with("saucer_") && k != "has_saucer");
        let m = Model::from_doc(&doc).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(m.params, mug);
        doc.version = g.version() + 1;
        let Err(e) = Model::from_doc(&doc) else {
            panic!("a newer version was accepted")
        };
        assert!(e.0.contains("this procfit knows version"), "{e}");
    }
}
