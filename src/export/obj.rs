//! Wavefront OBJ + MTL: one object and one material per part (the GLB's colours), welded
//! positions written once, normals and texture coordinates shared where equal.

use crate::generators::Mesh;
use crate::glb::GlbError;
use std::collections::HashMap;
use std::fmt::Write as _;

/// The OBJ text and the MTL text it references as `mtl_name` (a file beside it).
pub fn write_obj(mesh: &Mesh, title: &str, mtl_name: &str) -> Result<(Vec<u8>, Vec<u8>), GlbError> {
    mesh.check().map_err(|e| GlbError::Export(e.to_string()))?;
    if mesh.triangles.is_empty() {
        return Err(GlbError::Export("the mesh has no triangles".into()));
    }
    if mtl_name.chars().any(char::is_whitespace) {
        // `mtllib` takes a whitespace-separated list: a space would name two files.
        return Err(GlbError::Export(format!(
            "the MTL file name `{mtl_name}` has a space: OBJ readers would split it"
        )));
    }
    let mut obj = String::new();
    // `fmt::Write` into a String never fails, so its results are ignored throughout.
    let _ = writeln!(
        obj,
        "# {title}, written by procfit {}; units: metres, Y up",
        crate::VERSION
    );
    let _ = writeln!(obj, "mtllib {mtl_name}");
    for p in &mesh.positions {
        let _ = writeln!(obj, "v {} {} {}", p.x, p.y, p.z);
    }
    // Corner attributes shared by exact bits, numbered in first-use order (deterministic).
    let mut uv_ids: HashMap<[u32; 2], usize> = HashMap::new();
    let mut normal_ids: HashMap<[u32; 3], usize> = HashMap::new();
    let mut corners = Vec::with_capacity(mesh.corner_uvs.len());
    for (uv, n) in mesh.corner_uvs.iter().zip(&mesh.corner_normals) {
        // OBJ's texture origin is the bottom-left, glTF's (the generators') the top-left.
        let uv = [uv.x, 1.0 - uv.y];
        let n = n.normalize_or(glam::Vec3::Y);
        let next = uv_ids.len();
        let vt = *uv_ids.entry(uv.map(f32::to_bits)).or_insert_with(|| {
            let _ = writeln!(obj, "vt {} {}", uv[0], uv[1]);
            next
        });
        let next = normal_ids.len();
        let vn = *normal_ids
            .entry(n.to_array().map(f32::to_bits))
            .or_insert_with(|| {
                let _ = writeln!(obj, "vn {} {} {}", n.x, n.y, n.z);
                next
            });
        corners.push((vt + 1, vn + 1));
    }
    let mut mtl = String::new();
    let _ = writeln!(mtl, "# materials of {title}, written by procfit");
    for (part_id, part) in mesh.parts.iter().enumerate() {
        let tris: Vec<usize> = (0..mesh.triangles.len())
            .filter(|&t| usize::from(mesh.tri_parts[t]) == part_id)
            .collect();
        if tris.is_empty() {
            continue;
        }
        let name = part.name;
        let _ = writeln!(obj, "o {name}\nusemtl {name}");
        for t in tris {
            let _ = write!(obj, "f");
            for (k, &v) in mesh.triangles[t].iter().enumerate() {
                let (vt, vn) = corners[3 * t + k];
                let _ = write!(obj, " {}/{vt}/{vn}", v + 1);
            }
            obj.push('\n');
        }
        let [r, g, b, a] = crate::glb::export::base_color(part);
        let _ = writeln!(
            mtl,
            "newmtl {name}\nKa 0 0 0\nKd {r} {g} {b}\nKs 0.04 0.04 0.04\nNs 50\nd {a}\nillum 2"
        );
    }
    Ok((obj.into_bytes(), mtl.into_bytes()))
}
