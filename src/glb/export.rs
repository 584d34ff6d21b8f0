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
use std::collections::{HashMap, HashSet};

/// Base-colour alpha of glass parts whose colour is opaque: "slightly transparent".
const GLASS_ALPHA: f32 = 0.35;
/// Alpha cutoff of alpha-masked parts (leaves), the glTF default.
const MASK_CUTOFF: f32 = 0.5;

/// Writes `model`'s mesh (at the model's level of detail, its parts in the model's colours) as a GLB, with its generator state in
/// the scene extras and one camera node per entry of `cameras`.
pub fn export_model(model: &Model, cameras: &[ExportCamera]) -> Result<Vec<u8>, GlbError> {
    let mesh = model.mesh().map_err(|e| GlbError::Export(e.to_string()))?;
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
    write_glb_with(mesh, doc, cameras, GlbOptions::default())
}

/// How a GLB is encoded.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct GlbOptions {
    /// `KHR_mesh_quantization`: positions as normalised int16 with the dequantising scale and
    /// offset in each part's node, normals as normalised int8, texture coordinates as
    /// normalised u16 (float where a part's lie outside 0–1): 16 bytes a vertex instead of 32.
    /// The extension is then required, so only readers that know it open the file (three.js,
    /// Blender, Babylon.js and glTF-Transform do).
    pub quantize: bool,
}

/// Writes `mesh` as a GLB like [`write_glb`], encoded as `options` say.
pub fn write_glb_with(
    mesh: &Mesh,
    doc: Option<&ParamsDoc>,
    cameras: &[ExportCamera],
    options: GlbOptions,
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
    // Each procedural texture is written once, for the first part that uses it.
    let mut textures: HashMap<Texture, json::Index<json::Texture>> = HashMap::new();
    for (part_id, part) in mesh.parts.iter().enumerate() {
        let Some(split) = split_part(mesh, part_id) else {
            // A part without triangles at this level of detail: glTF forbids empty accessors.
            continue;
        };
        let texture = match texture_of(part) {
            Some(kind) => match textures.get(&kind) {
                Some(&t) => Some(t),
                None => {
                    let t = write_texture(&mut root, &mut bin, kind);
                    if let Some(t) = t {
                        textures.insert(kind, t);
                    }
                    t
                }
            },
            None => None,
        };
        let material = root.push(material_with(part, texture));
        let (primitive, transform) =
            write_primitive(&mut root, &mut bin, &split, material, options.quantize)?;
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
            translation: transform.map(|(t, _)| t.to_array()),
            scale: transform.map(|(_, s)| [s; 3]),
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
    if options.quantize {
        let name = "KHR_mesh_quantization".to_string();
        root.extensions_used.push(name.clone());
        root.extensions_required.push(name);
    }

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
    // A double-sided material shows both faces of each triangle, so a triangle that is an
    // earlier one's reverse (the back of a leaf card) would be drawn twice: it is left out.
    let double_sided = material(&mesh.parts[part_id]).double_sided;
    let mut faces: HashSet<[u32; 3]> = HashSet::new();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        if usize::from(mesh.tri_parts[t]) != part_id {
            continue;
        }
        if double_sided {
            if faces.contains(&rotated_min_first([tri[0], tri[2], tri[1]])) {
                continue;
            }
            faces.insert(rotated_min_first(*tri));
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

/// A triangle's corners rotated (winding kept) so the smallest index comes first: equal for
/// the three rotations of one triangle.
fn rotated_min_first(t: [u32; 3]) -> [u32; 3] {
    let k = (0..3).min_by_key(|&k| t[k]).unwrap_or(0);
    [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
}

/// Appends the part's attributes and indices to `bin` (one buffer view each, 4-byte aligned)
/// and returns the primitive that uses them; when `quantize`, also the part node's dequantising
/// translation and uniform scale (uniform, so normals keep their directions).
fn write_primitive(
    root: &mut json::Root,
    bin: &mut Vec<u8>,
    part: &SplitPart,
    material: json::Index<json::Material>,
    quantize: bool,
) -> Result<(json::mesh::Primitive, Option<(Vec3, f32)>), GlbError> {
    use json::accessor::{ComponentType, GenericComponentType, Type};
    use json::buffer::Target;

    let (lo, hi) = part
        .positions
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| {
            (lo.min(p), hi.max(p))
        });
    let numbers = |v: &[f32]| Some(json::Value::from(v.to_vec()));

    // Vertex attributes in one view each; `stride` is set where an element is not a multiple
    // of 4 bytes (glTF aligns every vertex attribute element to 4).
    let mut view = |root: &mut json::Root, bytes: &[u8], target: Target, stride: Option<usize>| {
        let offset = bin.len();
        bin.extend_from_slice(bytes);
        bin.resize(bin.len().next_multiple_of(4), 0);
        root.push(json::buffer::View {
            buffer: json::Index::new(0),
            byte_length: USize64::from(bytes.len()),
            byte_offset: Some(USize64::from(offset)),
            byte_stride: stride.map(json::buffer::Stride),
            name: None,
            target: Some(Valid(target)),
            extensions: None,
            extras: None,
        })
    };
    struct Layout {
        component: ComponentType,
        type_: Type,
        normalized: bool,
        min: Option<json::Value>,
        max: Option<json::Value>,
    }
    let accessor =
        |root: &mut json::Root, view: json::Index<json::buffer::View>, count: usize, l: Layout| {
            root.push(json::Accessor {
                buffer_view: Some(view),
                byte_offset: None,
                count: USize64::from(count),
                component_type: Valid(GenericComponentType(l.component)),
                extensions: None,
                extras: None,
                type_: Valid(l.type_),
                min: l.min,
                max: l.max,
                name: None,
                normalized: l.normalized,
                sparse: None,
            })
        };
    let float = |type_: Type| Layout {
        component: ComponentType::F32,
        type_,
        normalized: false,
        min: None,
        max: None,
    };
    let f32_bytes = |values: &mut dyn Iterator<Item = f32>| -> Vec<u8> {
        values.flat_map(f32::to_le_bytes).collect()
    };

    let n = part.positions.len();
    let (positions, transform) = if quantize {
        // p = centre + scale · q / 32767 with q in int16: the node carries centre and scale.
        let centre = (lo + hi) * 0.5;
        let half = ((hi - lo) * 0.5).max_element();
        let scale = if half > 0.0 && half.is_finite() {
            half
        } else {
            1.0
        };
        let q: Vec<[i16; 3]> = part
            .positions
            .iter()
            .map(|&p| {
                ((p - centre) / scale * 32767.0)
                    .round()
                    .clamp(Vec3::splat(-32767.0), Vec3::splat(32767.0))
                    .to_array()
                    .map(|x| x as i16)
            })
            .collect();
        let (qlo, qhi) = q
            .iter()
            .fold(([i16::MAX; 3], [i16::MIN; 3]), |(lo, hi), v| {
                (
                    [0, 1, 2].map(|k| lo[k].min(v[k])),
                    [0, 1, 2].map(|k| hi[k].max(v[k])),
                )
            });
        // Each element padded to 8 bytes.
        let bytes: Vec<u8> = q
            .iter()
            .flat_map(|v| [v[0], v[1], v[2], 0])
            .flat_map(i16::to_le_bytes)
            .collect();
        let v = view(root, &bytes, Target::ArrayBuffer, Some(8));
        let ints = |v: [i16; 3]| Some(json::Value::from(v.map(i64::from).to_vec()));
        let a = accessor(
            root,
            v,
            n,
            Layout {
                component: ComponentType::I16,
                type_: Type::Vec3,
                normalized: true,
                min: ints(qlo),
                max: ints(qhi),
            },
        );
        (a, Some((centre, scale)))
    } else {
        let bytes = f32_bytes(&mut part.positions.iter().flat_map(|p| p.to_array()));
        let v = view(root, &bytes, Target::ArrayBuffer, None);
        let layout = Layout {
            min: numbers(&lo.to_array()),
            max: numbers(&hi.to_array()),
            ..float(Type::Vec3)
        };
        (accessor(root, v, n, layout), None)
    };

    let normals = if quantize {
        let bytes: Vec<u8> = part
            .normals
            .iter()
            .flat_map(|nrm| {
                let q = (*nrm * 127.0).round().to_array().map(|x| x as i8 as u8);
                [q[0], q[1], q[2], 0]
            })
            .collect();
        let v = view(root, &bytes, Target::ArrayBuffer, Some(4));
        let layout = Layout {
            component: ComponentType::I8,
            normalized: true,
            ..float(Type::Vec3)
        };
        accessor(root, v, n, layout)
    } else {
        let bytes = f32_bytes(&mut part.normals.iter().flat_map(|p| p.to_array()));
        let v = view(root, &bytes, Target::ArrayBuffer, None);
        accessor(root, v, n, float(Type::Vec3))
    };

    let unit_uvs = part
        .uvs
        .iter()
        .all(|uv| (0.0..=1.0).contains(&uv.x) && (0.0..=1.0).contains(&uv.y));
    let uvs = if quantize && unit_uvs {
        let bytes: Vec<u8> = part
            .uvs
            .iter()
            .flat_map(|uv| (*uv * 65535.0).round().to_array())
            .flat_map(|x| (x as u16).to_le_bytes())
            .collect();
        let v = view(root, &bytes, Target::ArrayBuffer, None);
        let layout = Layout {
            component: ComponentType::U16,
            normalized: true,
            ..float(Type::Vec2)
        };
        accessor(root, v, n, layout)
    } else {
        let bytes = f32_bytes(&mut part.uvs.iter().flat_map(|p| p.to_array()));
        let v = view(root, &bytes, Target::ArrayBuffer, None);
        accessor(root, v, n, float(Type::Vec2))
    };

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
    let v = view(root, &bytes, Target::ElementArrayBuffer, None);
    let layout = Layout {
        component,
        ..float(Type::Scalar)
    };
    let indices = accessor(root, v, part.indices.len(), layout);

    let attributes = [
        (json::mesh::Semantic::Positions, positions),
        (json::mesh::Semantic::Normals, normals),
        (json::mesh::Semantic::TexCoords(0), uvs),
    ]
    .into_iter()
    .map(|(s, a)| (Valid(s), a))
    .collect();
    let primitive = json::mesh::Primitive {
        attributes,
        extensions: None,
        extras: None,
        indices: Some(indices),
        material: Some(material),
        mode: Valid(json::mesh::Mode::Triangles),
        targets: None,
    };
    Ok((primitive, transform))
}

/// A procedural texture ([`super::textures`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum Texture {
    /// Leaf clusters with an alpha cut-out, for leaf cards (UVs 0–1 over the card).
    Leaves,
    /// Tiling bark, for trunks and branches (u around the stem, v along it in metres).
    Bark,
}

/// The texture a part's look calls for, if any.
fn texture_of(part: &Part) -> Option<Texture> {
    match look(part) {
        Look::Foliage => Some(Texture::Leaves),
        Look::Bark => Some(Texture::Bark),
        _ => None,
    }
}

/// Embeds `kind`'s PNG in `bin` (its own buffer view) as an image with a sampler and returns
/// the texture; `None` if the PNG could not be made (the part is then untextured).
fn write_texture(
    root: &mut json::Root,
    bin: &mut Vec<u8>,
    kind: Texture,
) -> Option<json::Index<json::Texture>> {
    use json::texture::{MagFilter, MinFilter, Sampler, WrappingMode};
    let (png, name, wrap) = match kind {
        Texture::Leaves => (
            super::textures::leaf_png(),
            "leaves",
            WrappingMode::ClampToEdge,
        ),
        Texture::Bark => (super::textures::bark_png(), "bark", WrappingMode::Repeat),
    };
    if png.is_empty() {
        return None;
    }
    let offset = bin.len();
    bin.extend_from_slice(png);
    bin.resize(bin.len().next_multiple_of(4), 0);
    let view = root.push(json::buffer::View {
        buffer: json::Index::new(0),
        byte_length: USize64::from(png.len()),
        byte_offset: Some(USize64::from(offset)),
        byte_stride: None,
        name: None,
        target: None,
        extensions: None,
        extras: None,
    });
    let image = root.push(json::Image {
        buffer_view: Some(view),
        mime_type: Some(json::image::MimeType("image/png".into())),
        name: Some(name.into()),
        uri: None,
        extensions: None,
        extras: None,
    });
    let sampler = root.push(Sampler {
        mag_filter: Some(Valid(MagFilter::Linear)),
        min_filter: Some(Valid(MinFilter::LinearMipmapLinear)),
        name: None,
        wrap_s: Valid(wrap),
        wrap_t: Valid(wrap),
        extensions: None,
        extras: None,
    });
    Some(root.push(json::Texture {
        name: Some(name.into()),
        sampler: Some(sampler),
        source: image,
        extensions: None,
        extras: None,
    }))
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
    /// Bark (trunks, branches): opaque, rough, with the bark texture.
    Bark,
}

fn look(part: &Part) -> Look {
    let name = part.name.to_ascii_lowercase();
    if name.contains("glass") {
        Look::Glass
    } else if name.contains("leaf") || name.contains("leaves") || name.contains("foliage") {
        Look::Foliage
    } else if part.color[3] < 1.0 {
        Look::Translucent
    } else if name.contains("trunk") || name.contains("branch") || name.contains("bark") {
        Look::Bark
    } else {
        Look::Opaque
    }
}

/// Whether a part is an ordinary opaque surface (not glass, leaves or translucent; bark is):
/// one whose colour may be lent to or borrowed from a neighbour ([`crate::colors`]).
pub(crate) fn is_plain(part: &Part) -> bool {
    matches!(look(part), Look::Opaque | Look::Bark)
}

/// Whether a part is leaves (alpha-masked, with the leaf texture).
pub(crate) fn is_foliage(part: &Part) -> bool {
    look(part) == Look::Foliage
}

/// Whether a part is bark (a trunk or branches, with the bark texture).
pub(crate) fn is_bark(part: &Part) -> bool {
    look(part) == Look::Bark
}

/// A part's linear RGBA base colour as every format writes it: [`Part::color`] clamped to
/// 0–1, and glass given [`GLASS_ALPHA`] where its colour is opaque.
pub(crate) fn base_color(part: &Part) -> [f32; 4] {
    // Colours come from code, but a NaN or an out-of-range value must not make an invalid file.
    let mut color = part.color.map(|c| {
        if c.is_finite() {
            c.clamp(0.0, 1.0)
        } else {
            1.0
        }
    });
    if look(part) == Look::Glass && color[3] >= 1.0 {
        color[3] = GLASS_ALPHA;
    }
    color
}

/// The PBR material of a part: base colour from [`base_color`], dielectric, untextured.
fn material(part: &Part) -> json::Material {
    material_with(part, None)
}

/// [`material`] with `texture` as its base colour texture (multiplied by the base colour).
fn material_with(part: &Part, texture: Option<json::Index<json::Texture>>) -> json::Material {
    use json::material::{AlphaCutoff, AlphaMode, PbrBaseColorFactor, StrengthFactor};
    let color = base_color(part);
    let look = look(part);
    let (alpha_mode, alpha_cutoff, roughness, double_sided) = match look {
        Look::Opaque => (AlphaMode::Opaque, None, 0.6, false),
        Look::Glass => (AlphaMode::Blend, None, 0.05, true),
        Look::Foliage => (AlphaMode::Mask, Some(AlphaCutoff(MASK_CUTOFF)), 0.7, true),
        Look::Translucent => (AlphaMode::Blend, None, 0.3, false),
        Look::Bark => (AlphaMode::Opaque, None, 0.9, false),
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
            base_color_texture: texture.map(|index| json::texture::Info {
                index,
                tex_coord: 0,
                extensions: None,
                extras: None,
            }),
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
        check(part("trunk", 1.0), Look::Bark);
        check(part("branch", 1.0), Look::Bark);
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
