//! The CLI's `--format` / `--compact`: which format an output path gets, the second file an OBJ
//! writes (declared to [`Outputs`] with the rest, so it is checked before any work), and the
//! atomic write of every file of the export.

use crate::outputs::{Outputs, write_atomic};
use procfit::export::{self, ExportOptions, Format};
use procfit::glb::ExportCamera;
use procfit::model::Model;
use std::path::{Path, PathBuf};

/// What `-o PATH [--format F] [--compact]` asks for.
pub struct Target {
    /// The output path.
    pub path: PathBuf,
    /// Its format: `--format`, else the extension.
    pub format: Format,
    /// Encoding options.
    pub options: ExportOptions,
    /// The OBJ's MTL file beside it.
    pub companion: Option<PathBuf>,
}

impl Target {
    /// Resolves the format: `--format` when given (it must not contradict a known extension),
    /// else the path's extension.
    pub fn new(path: &Path, format: Option<&str>, compact: bool) -> Result<Target, String> {
        let by_extension = Format::from_path(path);
        let format = match (format.map(Format::parse).transpose()?, by_extension) {
            (Some(f), Some(e)) if f != e => {
                return Err(format!(
                    "--format {} but -o {} ends in .{}: make them agree",
                    f.name(),
                    path.display(),
                    e.name()
                ));
            }
            (Some(f), _) => f,
            (None, Some(e)) => e,
            (None, None) => {
                return Err(format!(
                    "-o {}: say the format with --format glb|obj|stl or an extension .glb, .obj, .stl",
                    path.display()
                ));
            }
        };
        if compact && format != Format::Glb {
            return Err(format!(
                "--compact is for GLB output, not {}",
                format.name()
            ));
        }
        Ok(Target {
            path: path.to_path_buf(),
            format,
            options: ExportOptions { compact },
            companion: format.companion(path),
        })
    }

    /// Adds this target's files to a command's plan.
    pub fn declare<'a>(&'a self, plan: Outputs<'a>) -> Outputs<'a> {
        let plan = plan.output("-o", &self.path);
        match &self.companion {
            Some(mtl) => plan.output("the OBJ's material file", mtl),
            None => plan,
        }
    }

    /// Adds a target's files to `plan`, or only `-o` when the target is not valid: checking
    /// the plan first names an output that is an input (`-o photo.jpg`) as such, before its
    /// unknown format is.
    pub fn declare_any<'a>(
        target: &'a Result<Target, String>,
        output: &'a Path,
        plan: Outputs<'a>,
    ) -> Outputs<'a> {
        match target {
            Ok(t) => t.declare(plan),
            Err(_) => plan.output("-o", output),
        }
    }

    /// Writes `model` (at its level of detail) and returns a summary for the CLI's line:
    /// triangles, non-empty parts, bytes and, for OBJ and STL, whether it is watertight.
    pub fn write(&self, model: &Model, cameras: &[ExportCamera]) -> Result<String, String> {
        let (files, mesh) =
            export::write_model(model, cameras, self.format, self.options, &self.path)
                .map_err(|e| e.to_string())?;
        write_atomic(&self.path, &files.main)?;
        let mut bytes = files.main.len();
        if let (Some(path), Some(mtl)) = (&self.companion, &files.companion) {
            write_atomic(path, mtl)?;
            bytes += mtl.len();
        }
        let parts = export::nonempty_parts(&mesh);
        let mut line = format!(
            "{} triangles in {parts} part{}, {bytes} bytes",
            mesh.triangles.len(),
            if parts == 1 { "" } else { "s" }
        );
        if let Some(mtl) = &self.companion {
            line += &format!(" (with {})", mtl.display());
        }
        match self.format {
            Format::Glb if self.options.compact => {
                line += ", compact (KHR_mesh_quantization: readers must support it)";
            }
            Format::Glb => {}
            Format::Obj | Format::Stl => match export::open_edges(&mesh) {
                0 => line += ", watertight",
                n => {
                    line += &format!(
                        ", not watertight: {n} edges are not shared by exactly two triangles{}",
                        if has_leaves(&mesh) {
                            " (leaf cards have no thickness)"
                        } else {
                            ""
                        }
                    )
                }
            },
        }
        Ok(line)
    }
}

/// Whether the mesh has leaf triangles (open cards, never watertight).
fn has_leaves(mesh: &procfit::generators::Mesh) -> bool {
    mesh.tri_parts.iter().any(|&p| {
        mesh.parts
            .get(usize::from(p))
            .is_some_and(|part| part.name.contains("leaf") || part.name.contains("leaves"))
    })
}
