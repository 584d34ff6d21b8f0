//! glTF 2.0 binary (GLB) export and import of procfit models and reference meshes.
//!
//! The download of a reconstruction is a GLB that every glTF tool opens, that keeps the object's
//! structure and that procfit itself can open again to keep editing (paper §1, §2.7: the result
//! is an *editable* procedural model, not just a mesh).
//!
//! - [`export`] writes a [`Mesh`](crate::generators::Mesh) with its parts as one node, mesh and
//!   PBR material per part, plus one perspective camera node per input photo
//!   ([`ExportCamera`]), and the generator state ([`ParamsDoc`](crate::model::ParamsDoc), the
//!   same shape as params JSON) in the scene's `extras`.
//! - [`import`] reads any GLB (or OBJ) back as a [`ReferenceMesh`] with node transforms applied,
//!   and a procfit GLB also as its generator state, so that [`ImportedGlb::model`] gives back
//!   the exact [`Model`](crate::model::Model) that was exported.
//! - [`textures`] makes the leaf and bark textures the export embeds for trees' leaf cards
//!   (alpha-masked) and stems.
//!
//! # Conventions and scale
//! glTF's own: Y up, right-handed, +Z toward the viewer, a camera looks down its local −Z with
//! +Y up. One unit is one metre: generator units are written unscaled, so an object whose
//! generator says it is 0.1 tall is 10 cm tall in Blender or a web viewer. Texture coordinates
//! are written as the generator made them (glTF convention: origin at the top-left of the
//! image).
//!
//! # Untrusted input
//! The importer treats every byte as hostile: every declared length, offset, count and index is
//! checked against the bytes actually present *before* anything is allocated from it, so the
//! memory an import can take is bounded by a small multiple of the file size; failures are
//! [`GlbError`]s with a message, never panics.

mod camera;
pub mod export;
pub mod import;
pub mod textures;

pub use camera::{CAMERA_FLOATS, ExportCamera};
pub use export::{GlbOptions, export_model, write_glb, write_glb_with};
pub(crate) use export::{is_bark, is_foliage, is_plain};
pub use import::{ImportedGlb, ReferenceMesh, import_glb, import_obj, import_reference};

use std::fmt;

/// Everything that can go wrong reading or writing a GLB.
#[derive(Clone, Debug, PartialEq)]
pub enum GlbError {
    /// The bytes are not a well-formed glTF / GLB / OBJ file (truncated, bad magic, lengths or
    /// indices out of range, invalid JSON…).
    Malformed(String),
    /// Well-formed, but uses something procfit does not read (external buffers, sparse
    /// accessors, compression extensions…).
    Unsupported(String),
    /// The file asks for more geometry than procfit will hold.
    TooLarge(String),
    /// The file opened as a reference mesh but carries no usable procfit generator state.
    NotEditable(String),
    /// The model or mesh given to the exporter cannot be written.
    Export(String),
}

impl fmt::Display for GlbError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            GlbError::Malformed(m) => write!(f, "malformed file: {m}"),
            GlbError::Unsupported(m) => write!(f, "unsupported glTF feature: {m}"),
            GlbError::TooLarge(m) => write!(f, "file too large: {m}"),
            GlbError::NotEditable(m) => write!(f, "cannot be edited: {m}"),
            GlbError::Export(m) => write!(f, "cannot export: {m}"),
        }
    }
}

impl std::error::Error for GlbError {}

/// Shorthand for a [`GlbError::Malformed`] result.
fn malformed<T>(message: impl Into<String>) -> Result<T, GlbError> {
    Err(GlbError::Malformed(message.into()))
}
