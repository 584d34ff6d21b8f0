//! The file formats a model can be written in: GLB (plain or compact), OBJ + MTL and binary STL.
//!
//! The GLB ([`crate::glb`]) is the one procfit opens again for editing: it keeps the parts, the
//! photos' cameras and the generator state. OBJ + MTL and STL are for tools that do not read
//! glTF (slicers, older modellers): OBJ keeps the parts as objects with one material each, STL
//! is the bare triangle soup a 3D printer wants. Neither carries the generator state.
//!
//! A mesh is *watertight* when every edge (by vertex position) is shared by exactly two
//! triangles, which is what a slicer needs. Dishes are (body and handle are closed solids that
//! interpenetrate); buildings are not (their elements touch along shared edges) nor are trees
//! (leaf cards have no thickness). [`open_edges`] says how far from it a mesh is, so the CLI can
//! say so on every OBJ and STL it writes.

mod obj;
mod stl;

pub use obj::write_obj;
pub use stl::write_stl;

use crate::generators::Mesh;
use crate::glb::{ExportCamera, GlbError, GlbOptions};
use crate::model::Model;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// An output file format.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// Binary glTF 2.0 with the generator state (procfit opens it again).
    Glb,
    /// Wavefront OBJ with a companion MTL file of the parts' materials.
    Obj,
    /// Binary STL: triangles only, no parts, no colours.
    Stl,
}

impl Format {
    /// Every format, in the order the CLI lists them.
    pub const ALL: [Format; 3] = [Format::Glb, Format::Obj, Format::Stl];

    /// The name used by `--format` and the file extension.
    pub fn name(self) -> &'static str {
        match self {
            Format::Glb => "glb",
            Format::Obj => "obj",
            Format::Stl => "stl",
        }
    }

    /// The format `--format NAME` names.
    pub fn parse(name: &str) -> Result<Format, String> {
        Format::ALL
            .into_iter()
            .find(|f| f.name().eq_ignore_ascii_case(name))
            .ok_or_else(|| format!("unknown format `{name}` (formats: glb, obj, stl)"))
    }

    /// The format a path's extension names, if any.
    pub fn from_path(path: &Path) -> Option<Format> {
        let ext = path.extension()?.to_str()?;
        Format::parse(ext).ok()
    }

    /// The second file this format writes beside `main` (the OBJ's `.mtl`), if any.
    pub fn companion(self, main: &Path) -> Option<PathBuf> {
        (self == Format::Obj).then(|| main.with_extension("mtl"))
    }
}

/// What to write and how.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ExportOptions {
    /// GLB only: quantised attributes (`KHR_mesh_quantization`), about half the size.
    pub compact: bool,
}

/// The bytes of an export: the main file and, for OBJ, the MTL file it references.
#[derive(Clone, Debug, PartialEq)]
pub struct Exported {
    /// The file the user named.
    pub main: Vec<u8>,
    /// The companion file ([`Format::companion`]), when the format has one.
    pub companion: Option<Vec<u8>>,
}

/// Writes `model`'s mesh at its level of detail in `format`. `main` is the path the main file
/// will have: an OBJ references its MTL by that file's name.
pub fn write_model(
    model: &Model,
    cameras: &[ExportCamera],
    format: Format,
    options: ExportOptions,
    main: &Path,
) -> Result<(Exported, Mesh), GlbError> {
    let mesh = model.mesh().map_err(|e| GlbError::Export(e.to_string()))?;
    let exported = write_mesh(&mesh, Some(model), cameras, format, options, main)?;
    Ok((exported, mesh))
}

/// Writes `mesh` in `format` (see [`write_model`]); `model`, when given, is the generator
/// state the GLB carries and names the OBJ's header.
pub fn write_mesh(
    mesh: &Mesh,
    model: Option<&Model>,
    cameras: &[ExportCamera],
    format: Format,
    options: ExportOptions,
    main: &Path,
) -> Result<Exported, GlbError> {
    if options.compact && format != Format::Glb {
        return Err(GlbError::Export(format!(
            "compact is a GLB option, not {}",
            format.name()
        )));
    }
    let title = model.map_or("procfit", |m| m.generator.name());
    match format {
        Format::Glb => {
            let doc = model.map(Model::to_doc);
            let glb_options = GlbOptions {
                quantize: options.compact,
            };
            Ok(Exported {
                main: crate::glb::write_glb_with(mesh, doc.as_ref(), cameras, glb_options)?,
                companion: None,
            })
        }
        Format::Obj => {
            let mtl_path = Format::Obj.companion(main).unwrap_or_default();
            let mtl_name = mtl_path
                .file_name()
                .and_then(|n| n.to_str())
                .ok_or_else(|| {
                    GlbError::Export(format!(
                        "{}: the MTL file name is not UTF-8 text",
                        main.display()
                    ))
                })?;
            let (obj, mtl) = write_obj(mesh, title, mtl_name)?;
            Ok(Exported {
                main: obj,
                companion: Some(mtl),
            })
        }
        Format::Stl => Ok(Exported {
            main: write_stl(mesh, title)?,
            companion: None,
        }),
    }
}

/// How many edges of `mesh` are not shared by exactly two triangles, with vertices told apart by
/// their position (as an STL reader sees them): 0 for a watertight mesh.
pub fn open_edges(mesh: &Mesh) -> usize {
    // The same position written twice is one vertex to a slicer.
    let mut canonical: HashMap<[u32; 3], u32> = HashMap::new();
    let ids: Vec<u32> = mesh
        .positions
        .iter()
        .map(|p| {
            let next = canonical.len() as u32;
            *canonical
                .entry(p.to_array().map(f32::to_bits))
                .or_insert(next)
        })
        .collect();
    let mut uses: HashMap<(u32, u32), u32> = HashMap::new();
    for t in &mesh.triangles {
        let v = t.map(|i| ids[i as usize]);
        for k in 0..3 {
            let (a, b) = (v[k], v[(k + 1) % 3]);
            if a != b {
                *uses.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
    }
    uses.values().filter(|&&n| n != 2).count()
}

/// How many of `mesh`'s parts have triangles (a part can be empty at a level of detail).
pub fn nonempty_parts(mesh: &Mesh) -> usize {
    let mut used = vec![false; mesh.parts.len()];
    for &p in &mesh.tri_parts {
        if let Some(u) = used.get_mut(usize::from(p)) {
            *u = true;
        }
    }
    used.into_iter().filter(|&u| u).count()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn formats_come_from_names_and_extensions() {
        assert_eq!(Format::parse("OBJ"), Ok(Format::Obj));
        assert!(Format::parse("fbx").unwrap_err().contains("glb, obj, stl"));
        assert_eq!(Format::from_path(Path::new("a/b.stl")), Some(Format::Stl));
        assert_eq!(Format::from_path(Path::new("a/b.GLB")), Some(Format::Glb));
        assert_eq!(Format::from_path(Path::new("a/b")), None);
        assert_eq!(
            Format::Obj.companion(Path::new("out/mug.obj")),
            Some(PathBuf::from("out/mug.mtl"))
        );
        assert_eq!(Format::Stl.companion(Path::new("mug.stl")), None);
    }
}
