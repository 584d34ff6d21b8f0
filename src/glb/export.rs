//! The GLB writer: a generator [`Mesh`] with its parts, the photos' cameras and the generator
//! state, as one binary glTF 2.0 file.
//!
//! Layout of the file (every object named, so tools show the structure):
//! - scene `<generator>_scene` with the generator state in `extras` (same shape as params JSON);
//! - root node `<generator>` whose children are one node per part (`body`, `handle`,
//!   `window_glass`…), each with its own mesh (one triangle primitive) and PBR material;
//! - one camera node per photo at the scene root, so moving the object does not move the
//!   photos' viewpoints.
//!
//! The [`Mesh`] stores welded positions and per-corner normals/UVs; glTF needs one attribute set
//! per vertex, so a vertex is split wherever the corners that share a position disagree (UV
//! seams, hard edges) and shared wherever they agree.

use super::{ExportCamera, GlbError};
use crate::generators::{Mesh, Part};
use crate::model::{Model, ParamsDoc};
use glam::{Vec2, Vec3};
use gltf_json as json;
use json::validation::{Checked::Valid, USize64};
use std::borrow::Cow;
use std::collections::HashMap;

/// Base-colour alpha of glass parts whose colour is opaque: "slightly transparent".
const GLASS_ALPHA: f32 = 0.35;
/// Alpha cutoff of alpha-masked parts (leaves), the glTF default.
const MASK_CUTOFF: f32 = 0.5;

/// Writes `model`'s mesh (at the model's level of detail) as a GLB, with its generator state in
/// the scene extras and one camera node per entry of `cameras`.
pub fn export_model(model: &Model, cameras: &[ExportCamera]) -> Result<Vec<u8>, GlbError> {
    let mesh = model
        .generator
        .generate(&model.params, model.lod)
        .map_err(|e| GlbError::Export(e.to_string()))?;
    write_glb(&mesh, Some(&model.to_doc()), cameras)
}

/// Writes `mesh` as a GLB. `doc`, when given, goes into the scene's `extras` so that the file can
/// be opened again for editing (see [`super::ImportedGlb::model`]); `cameras` become perspective
/// camera nodes named after them (or `photo_<i>`).
pub fn write_glb(
    mesh: &Mesh,
    doc: Option<&ParamsDoc>,
    cameras: &[ExportCamera],
) -> Result<Vec<u8>, GlbError> {
    mesh.check().map_err(|e| GlbError::Export(e.to_string()))?;
    if mesh.triangles.is_empty() {
        return Err(GlbError::Export("the mesh has no triangles".into()));
    }
    let title = doc.map_or("procfit", |d| d.generator.as_str()).to_string();

    let mut root = json::Root {
        asset: json::Asset {
            generator: Some(format!("procfit {}", crate::VERSION)),
            version: "2.0".into(),
            ..Default::default()
        },
        ..Default::default()
    };
    let mut bin = Vec::new();

    let mut part_nodes = Vec::new();
    for (part_id, part) in mesh.parts.iter().enumerate() {
        let Some(split) = split_part(mesh, part_id) else {
            // A part without triangles at this level of detail: glTF forbids empty accessors.
            continue;
        };
        let material = root.push(material(part));
        let primitive = write_primitive(&mut root, &mut bin, &split, material)?;
        let mesh_index = root.push(json::Mesh {
            extensions: None,
            extras: None,
            name: Some(part.name.to_string()),
            primitives: vec![primitive],
            weights: None,
        });
        part_nodes.push(root.push(json::Node {
            mesh: Some(mesh_index),
            name: Some(part.name.to_string()),
            ..Default::default()
        }));
    }
    let object = root.push(json::Node {
        children: Some(part_nodes),
        name: Some(title.clone()),
        ..Default::default()
    });

    let mut scene_nodes = vec![object];
    for (i, camera) in cameras.iter().enumerate() {
        let name = camera.name.clone().unwrap_or_else(|| format!("photo_{i}"));
        let (rotation, translation) = camera.checked_pose(&format!("camera `{name}`"))?;
        let camera_index = root.push(json::Camera {
            name: Some(name.clone()),
            orthographic: None,
            perspective: Some(json::camera::Perspective {
                aspect_ratio: Some(camera.aspect),
                yfov: camera.yfov,
                zfar: camera.zfar,
                znear: camera.znear,
                extensions: None,
                extras: None,
            }),
            type_: Valid(json::camera::Type::Perspective),
            extensions: None,
            extras: None,
        });
        scene_nodes.push(root.push(json::Node {
            camera: Some(camera_index),
            name: Some(name),
            rotation: Some(json::scene::UnitQuaternion(rotation.to_array())),
            translation: Some(translation.to_array()),
            ..Default::default()
        }));
    }

    let extras = doc
        .map(|d| {
            serde_json::value::to_raw_value(d)
                .map_err(|e| GlbError::Export(format!("generator state: {e}")))
        })
        .transpose()?;
    let scene = root.push(json::Scene {
        extensions: None,
        extras,
        // Not the root node's name: three.js would rename one of two equal names.
        name: Some(format!("{title}_scene")),
        nodes: scene_nodes,
    });
    root.scene = Some(scene);

    // The BIN chunk is padded to 4 bytes by the framing; the buffer length is the unpadded one.
    let buffer_length = bin.len();
    root.push(json::Buffer {
        byte_length: USize64::from(buffer_length),
        name: None,
        uri: None,
        extensions: None,
        extras: None,
    });

    let json_bytes = root
        .to_vec()
        .map_err(|e| GlbError::Export(format!("glTF JSON: {e}")))?;
    // GLB lengths are u32: header 12 + two chunk headers 8 + padding.
    let total = 12 + 8 + json_bytes.len().next_multiple_of(4) + 8 + bin.len().next_multiple_of(4);
    if u32::try_from(total).is_err() {
        return Err(GlbError::Export(format!(
            "{total} bytes do not fit in a GLB (4 GiB limit)"
        )));
    }
    let glb = gltf::binary::Glb {
        header: gltf::binary::Header {
            magic: *b"glTF",
            version: 2,
            length: total as u32,
        },
        json: Cow::Owned(json_bytes),
        bin: Some(Cow::Owned(bin)),
    };
    glb.to_vec()
        .map_err(|e| GlbError::Export(format!("GLB framing: {e}")))
}

/// One part's triangles with vertices split where corner attributes differ.
struct SplitPart {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    uvs: Vec<Vec2>,
    indices: Vec<u32>,
}

/// The vertices and indices of part `part_id`, or `None` when it has no triangles.
fn split_part(mesh: &Mesh, part_id: usize) -> Option<SplitPart> {
    let mut out = SplitPart {
        positions: Vec::new(),
        normals: Vec::new(),
        uvs: Vec::new(),
        indices: Vec::new(),
    };
    // Key: welded position index + exact bits of the corner's normal and uv. Insertion order
    // (first use) keeps the output deterministic.
    let mut seen: HashMap<(u32, [u32; 3], [u32; 2]), u32> = HashMap::new();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        if usize::from(mesh.tri_parts[t]) != part_id {
            continue;
        }
        let corners = tri.map(|i| mesh.positions[i as usize]);
        let face = (corners[1] - corners[0])
            .cross(corners[2] - corners[0])
            .normalize_or(Vec3::Y);
        for (k, &vi) in tri.iter().enumerate() {
            // glTF requires unit normals; a degenerate corner normal falls back to the face's.
            let normal = mesh.corner_normals[3 * t + k].normalize_or(face);
            let uv = mesh.corner_uvs[3 * t + k];
            let key = (
                vi,
                normal.to_array().map(f32::to_bits),
                uv.to_array().map(f32::to_bits),
            );
            let index = *seen.entry(key).or_insert_with(|| {
                out.positions.push(mesh.positions[vi as usize]);
                out.normals.push(normal);
                out.uvs.push(uv);
                (out.positions.len() - 1) as u32
            });
            out.indices.push(index);
        }
    }
    (!out.indices.is_empty()).then_some(out)
}

/// Appends the part's attributes and indices to `bin` (one buffer view each, 4-byte aligned)
/// and returns the primitive that uses them.
fn write_primitive(
    root: &mut json::Root,
    bin: &mut Vec<u8>,
    part: &SplitPart,
    material: json::Index<json::Material>,
) -> Result<json::mesh::Primitive, GlbError> {
    use json::accessor::{ComponentType, GenericComponentType, Type};
    use json::buffer::Target;

    let (lo, hi) = part
        .positions
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| {
            (lo.min(p), hi.max(p))
        });
    let floats = |v: Vec3| Some(json::Value::from(v.to_array().to_vec()));

    let mut view = |root: &mut json::Root, bytes: &[u8], target: Target| {
        let offset = bin.len();
        bin.extend_from_slice(bytes);
        bin.resize(bin.len().next_multiple_of(4), 0);
        root.push(json::buffer::View {
            buffer: json::Index::new(0),
            byte_length: USize64::from(bytes.len()),
            byte_offset: Some(USize64::from(offset)),
            byte_stride: None,
            name: None,
            target: Some(Valid(target)),
            extensions: None,
            extras: None,
        })
    };
    let accessor = |root: &mut json::Root,
                    view: json::Index<json::buffer::View>,
                    count: usize,
                    component: ComponentType,
                    type_: Type,
                    min: Option<json::Value>,
                    max: Option<json::Value>| {
        root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: USize64::from(count),
            component_type: Valid(GenericComponentType(component)),
            extensions: None,
            extras: None,
            type_: Valid(type_),
            min,
            max,
            name: None,
            normalized: false,
            sparse: None,
        })
    };

    let n = part.positions.len();
    let bytes: Vec<u8> = part
        .positions
        .iter()
        .flat_map(|p| p.to_array())
        .flat_map(f32::to_le_bytes)
        .collect();
    let v = view(root, &bytes, Target::ArrayBuffer);
    let positions = accessor(
        root,
        v,
        n,
        ComponentType::F32,
        Type::Vec3,
        floats(lo),
        floats(hi),
    );

    let bytes: Vec<u8> = part
        .normals
        .iter()
        .flat_map(|p| p.to_array())
        .flat_map(f32::to_le_bytes)
        .collect();
    let v = view(root, &bytes, Target::ArrayBuffer);
    let normals = accessor(root, v, n, ComponentType::F32, Type::Vec3, None, None);

    let bytes: Vec<u8> = part
        .uvs
        .iter()
        .flat_map(|p| p.to_array())
        .flat_map(f32::to_le_bytes)
        .collect();
    let v = view(root, &bytes, Target::ArrayBuffer);
    let uvs = accessor(root, v, n, ComponentType::F32, Type::Vec2, None, None);

    // u16 indices when every index fits below 65535: the largest value of the type is reserved
    // (primitive restart) and glTF forbids it in index data.
    let (bytes, component) = if n < usize::from(u16::MAX) {
        let bytes: Vec<u8> = part
            .indices
            .iter()
            .flat_map(|&i| (i as u16).to_le_bytes())
            .collect();
        (bytes, ComponentType::U16)
    } else if n < u32::MAX as usize {
        let bytes: Vec<u8> = part.indices.iter().flat_map(|&i| i.to_le_bytes()).collect();
        (bytes, ComponentType::U32)
    } else {
        return Err(GlbError::Export(format!("{n} vertices in one part")));
    };
    let v = view(root, &bytes, Target::ElementArrayBuffer);
    let indices = accessor(
        root,
        v,
        part.indices.len(),
        component,
        Type::Scalar,
        None,
        None,
    );

    let attributes = [
        (json::mesh::Semantic::Positions, positions),
        (json::mesh::Semantic::Normals, normals),
        (json::mesh::Semantic::TexCoords(0), uvs),
    ]
    .into_iter()
    .map(|(s, a)| (Valid(s), a))
    .collect();
    Ok(json::mesh::Primitive {
        attributes,
        extensions: None,
        extras: None,
        indices: Some(indices),
        material: Some(material),
        mode: Valid(json::mesh::Mode::Triangles),
        targets: None,
    })
}

/// What a part's material looks like, decided from its name and default colour.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Look {
    /// Ordinary opaque surface.
    Opaque,
    /// Glass: slightly transparent, smooth, alpha-blended.
    Glass,
    /// Leaves: alpha-masked cards (so a leaf texture's cut-outs work), seen from both sides.
    Foliage,
    /// Any other part whose default colour is translucent: alpha-blended.
    Translucent,
}

fn look(part: &Part) -> Look {
    let name = part.name.to_ascii_lowercase();
    if name.contains("glass") {
        Look::Glass
    } else if name.contains("leaf") || name.contains("leaves") || name.contains("foliage") {
        Look::Foliage
    } else if part.color[3] < 1.0 {
        Look::Translucent
    } else {
        Look::Opaque
    }
}

/// The PBR material of a part: base colour from [`Part::color`], dielectric.
fn material(part: &Part) -> json::Material {
    use json::material::{AlphaCutoff, AlphaMode, PbrBaseColorFactor, StrengthFactor};
    // Colours come from code, but a NaN or an out-of-range value must not make an invalid file.
    let mut color = part.color.map(|c| {
        if c.is_finite() {
            c.clamp(0.0, 1.0)
        } else {
            1.0
        }
    });
    let look = look(part);
    let (alpha_mode, alpha_cutoff, roughness, double_sided) = match look {
        Look::Opaque => (AlphaMode::Opaque, None, 0.6, false),
        Look::Glass => {
            if color[3] >= 1.0 {
                color[3] = GLASS_ALPHA;
            }
            (AlphaMode::Blend, None, 0.05, true)
        }
        Look::Foliage => (AlphaMode::Mask, Some(AlphaCutoff(MASK_CUTOFF)), 0.7, true),
        Look::Translucent => (AlphaMode::Blend, None, 0.3, false),
    };
    json::Material {
        alpha_cutoff,
        alpha_mode: Valid(alpha_mode),
        double_sided,
        name: Some(part.name.to_string()),
        pbr_metallic_roughness: json::material::PbrMetallicRoughness {
            base_color_factor: PbrBaseColorFactor(color),
            metallic_factor: StrengthFactor(0.0),
            roughness_factor: StrengthFactor(roughness),
            ..Default::default()
        },
        ..Default::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn part(name: &'static str, alpha: f32) -> Part {
        Part {
            name,
            color: [0.5, 0.5, 0.5, alpha],
        }
    }

    #[test]
    fn looks_follow_part_names_and_alpha() {
        let check = |p: Part, want: Look| assert_eq!(look(&p), want, "{}", p.name);
        check(part("body", 1.0), Look::Opaque);
        check(part("window_glass", 1.0), Look::Glass);
        check(part("Glass", 0.2), Look::Glass);
        check(part("leaves", 1.0), Look::Foliage);
        check(part("leaf_cards", 1.0), Look::Foliage);
        check(part("veil", 0.5), Look::Translucent);
    }

    #[test]
    fn glass_gets_transparent_blend_and_keeps_its_own_alpha() {
        let m = material(&part("window_glass", 1.0));
        assert_eq!(m.pbr_metallic_roughness.base_color_factor.0[3], GLASS_ALPHA);
        assert_eq!(m.alpha_mode, Valid(json::material::AlphaMode::Blend));
        let m = material(&part("window_glass", 0.2));
        assert_eq!(m.pbr_metallic_roughness.base_color_factor.0[3], 0.2);
        let m = material(&part("leaves", 1.0));
        assert_eq!(m.alpha_mode, Valid(json::material::AlphaMode::Mask));
        assert!(m.double_sided);
    }
}
