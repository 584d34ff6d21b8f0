//! The importer: any GLB (or Wavefront OBJ) as a reference mesh, and a procfit GLB also as the
//! generator state it was exported with.
//!
//! Every length, offset, count and index in the file is checked against the bytes actually
//! present before it is used or allocated from (see the module doc of [`crate::glb`]); the
//! geometry a file may expand to through node instancing is capped by [`MAX_TRIANGLES`].

use super::{ExportCamera, GlbError, malformed};
use crate::model::{Model, ParamsDoc};
use glam::{Mat4, Quat, Vec3};
use gltf_json as json;
use json::accessor::{ComponentType, Type};
use json::validation::Checked::Valid;
use std::borrow::Cow;
use std::collections::HashMap;

/// Most triangles (and vertices) an import produces, after node instancing. A small hostile file
/// can instance one mesh from thousands of nodes; 4 Mi triangles (~70 MB of geometry) is far
/// beyond any model procfit fits or overlays and still fits a browser tab.
pub const MAX_TRIANGLES: usize = 1 << 22;

/// A triangle soup for evaluation and overlays: positions in world space (node transforms
/// applied), exactly equal positions welded, triangles counter-clockwise seen from outside when
/// the source was.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ReferenceMesh {
    /// Vertex positions, Y up.
    pub positions: Vec<Vec3>,
    /// Triangles as indices into `positions`.
    pub triangles: Vec<[u32; 3]>,
    /// For each triangle, the index into `part_names` of the node it came from.
    pub tri_parts: Vec<u32>,
    /// Name of each mesh node that contributed triangles, in scene order (`node <i>` when the
    /// node has no name). For a procfit GLB these are the part names.
    pub part_names: Vec<String>,
}

impl ReferenceMesh {
    /// Axis-aligned bounding box `(min, max)` of the positions, or `None` when empty.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let first = *self.positions.first()?;
        Some(
            self.positions
                .iter()
                .fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p))),
        )
    }
}

/// What a GLB holds: always a reference mesh and the cameras; the generator state when the file
/// is procfit's.
#[derive(Clone, Debug)]
pub struct ImportedGlb {
    /// The geometry of the default scene.
    pub reference: ReferenceMesh,
    /// Perspective camera nodes of the scene, with their world poses.
    pub cameras: Vec<ExportCamera>,
    /// The tool that wrote the file (`asset.generator`), when it says.
    pub tool: Option<String>,
    /// The generator state from the scene extras, or why there is none.
    state: Result<ParamsDoc, String>,
}

impl ImportedGlb {
    /// The generator state stored in the scene extras, when the file has one.
    pub fn doc(&self) -> Option<&ParamsDoc> {
        self.state.as_ref().ok()
    }

    /// Whether the file carries a procfit generator state (it may still name a generator this
    /// build does not know; [`ImportedGlb::model`] says so).
    pub fn is_editable(&self) -> bool {
        self.state.is_ok()
    }

    /// The model the file was exported from: generator, parameters, lod and seed exactly as
    /// written. A GLB that is not procfit's gives [`GlbError::NotEditable`] saying so; its
    /// geometry is still in [`ImportedGlb::reference`].
    pub fn model(&self) -> Result<Model, GlbError> {
        match &self.state {
            Ok(doc) => Model::from_doc(doc).map_err(|e| {
                GlbError::NotEditable(format!("the procfit state in this GLB cannot be used: {e}"))
            }),
            Err(why) => Err(GlbError::NotEditable(format!(
                "{why}; it opens as a reference mesh only"
            ))),
        }
    }
}

/// The one required extension the importer reads (integer vertex attributes).
const QUANTIZATION: &str = "KHR_mesh_quantization";

/// Reads a reference mesh from GLB or OBJ bytes, told apart by the GLB magic.
pub fn import_reference(bytes: &[u8]) -> Result<ReferenceMesh, GlbError> {
    if bytes.starts_with(b"glTF") {
        let mesh = import_glb(bytes)?.reference;
        if mesh.triangles.is_empty() {
            return malformed("the GLB's default scene has no triangles");
        }
        return Ok(mesh);
    }
    if bytes.iter().find(|b| !b.is_ascii_whitespace()) == Some(&b'{') {
        return Err(GlbError::Unsupported(
            "a .gltf JSON file: save it as a single binary .glb".into(),
        ));
    }
    import_obj(bytes)
}

/// Reads a GLB file.
pub fn import_glb(bytes: &[u8]) -> Result<ImportedGlb, GlbError> {
    let (json_chunk, bin) = split_glb(bytes)?;
    if let Err(e) = std::str::from_utf8(json_chunk) {
        return malformed(format!(
            "the JSON chunk is not UTF-8 text (invalid byte at offset {})",
            e.valid_up_to()
        ));
    }
    // The chunk is padded with spaces; some writers pad with NULs, which JSON parsers reject.
    let end = json_chunk
        .iter()
        .rposition(|&b| b != 0)
        .map_or(0, |i| i + 1);
    let root = json::Root::from_slice(&json_chunk[..end])
        .map_err(|e| GlbError::Malformed(format!("glTF JSON: {e}")))?;
    validate(&root)?;

    let scene = match root.scene {
        Some(s) => root.scenes.get(s.value()),
        None => root.scenes.first(),
    };
    let roots: Vec<usize> = match scene {
        Some(s) => s.nodes.iter().map(|n| n.value()).collect(),
        None => {
            // No scene: every node that is nobody's child is a root.
            let mut child = vec![false; root.nodes.len()];
            for n in &root.nodes {
                for c in n.children.iter().flatten() {
                    if let Some(flag) = child.get_mut(c.value()) {
                        *flag = true;
                    }
                }
            }
            (0..root.nodes.len()).filter(|&i| !child[i]).collect()
        }
    };

    let mut builder = Builder {
        root: &root,
        bin,
        mesh: ReferenceMesh::default(),
        cameras: Vec::new(),
        weld: HashMap::new(),
        quantization: root.extensions_used.iter().any(|e| e == QUANTIZATION),
    };
    let mut visited = vec![false; root.nodes.len()];
    let mut stack: Vec<(usize, Mat4)> = roots.iter().rev().map(|&n| (n, Mat4::IDENTITY)).collect();
    while let Some((index, parent)) = stack.pop() {
        let Some(node) = root.nodes.get(index) else {
            return malformed(format!("node {index} does not exist"));
        };
        if std::mem::replace(&mut visited[index], true) {
            return malformed(format!(
                "node {index} is reached twice (glTF nodes have at most one parent)"
            ));
        }
        let world = parent * local_transform(node);
        if !world.is_finite() {
            return malformed(format!("node {index} has a non-finite transform"));
        }
        if let Some(m) = node.mesh {
            let name = node.name.clone().unwrap_or_else(|| format!("node {index}"));
            builder.add_mesh(m.value(), world, name)?;
        }
        if let Some(c) = node.camera {
            builder.add_camera(c.value(), world, node.name.as_deref());
        }
        for c in node.children.iter().flatten().rev() {
            stack.push((c.value(), world));
        }
    }

    let state = match scene.and_then(|s| s.extras.as_ref()) {
        None => Err("the file has no procfit generator state in its scene extras".to_string()),
        Some(raw) => serde_json::from_str::<ParamsDoc>(raw.get())
            .map_err(|e| format!("the scene extras are not a procfit generator state ({e})")),
    };
    Ok(ImportedGlb {
        reference: builder.mesh,
        cameras: builder.cameras,
        tool: root.asset.generator.clone(),
        state,
    })
}

/// Checks the GLB framing and returns the JSON chunk and the BIN chunk, if any.
fn split_glb(bytes: &[u8]) -> Result<(&[u8], Option<&[u8]>), GlbError> {
    if bytes.len() < 12 {
        return malformed(format!(
            "truncated: {} bytes, a GLB header alone is 12",
            bytes.len()
        ));
    }
    if &bytes[0..4] != b"glTF" {
        return malformed(format!(
            "not a GLB file (magic {:?}, expected \"glTF\")",
            String::from_utf8_lossy(&bytes[0..4])
        ));
    }
    let word =
        |at: usize| u32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]);
    let version = word(4);
    if version != 2 {
        return Err(GlbError::Unsupported(format!(
            "GLB container version {version} (only 2 is read)"
        )));
    }
    let declared = word(8) as usize;
    // Checked here rather than trusted to `Glb::from_slice`, which subtracts the header size
    // from the declared length without a check and reads past it.
    if declared < 20 {
        return malformed(format!(
            "the header declares {declared} bytes, too short for a JSON chunk"
        ));
    }
    if declared > bytes.len() {
        return malformed(format!(
            "truncated: the header declares {declared} bytes, the file has {}",
            bytes.len()
        ));
    }
    let glb = gltf::binary::Glb::from_slice(&bytes[..declared])
        .map_err(|e| GlbError::Malformed(format!("GLB chunks: {e}")))?;
    // Parsing a slice borrows from it, so both chunks are plain borrows of `bytes`.
    let (Cow::Borrowed(json), bin) = (glb.json, glb.bin) else {
        return malformed("GLB JSON chunk was copied");
    };
    let bin = match bin {
        None => None,
        Some(Cow::Borrowed(b)) => Some(b),
        Some(Cow::Owned(_)) => return malformed("GLB BIN chunk was copied"),
    };
    Ok((json, bin))
}

/// Runs gltf-json's index and enum validation and reports the first few problems.
fn validate(root: &json::Root) -> Result<(), GlbError> {
    use json::validation::Validate;
    // KHR_mesh_quantization only widens the accessor types positions may have, which the
    // reader handles; anything else required is refused.
    if let Some(ext) = root
        .extensions_required
        .iter()
        .find(|e| e.as_str() != QUANTIZATION)
    {
        return Err(GlbError::Unsupported(format!(
            "the file requires extension {ext}, which procfit does not read (re-export it without compression)"
        )));
    }
    // gltf-json 1.4.1's primitive validation indexes `accessors[POSITION]` without a bounds
    // check and panics on a dangling index, so that index is checked first.
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let position = primitive
                .attributes
                .get(&Valid(json::mesh::Semantic::Positions));
            if let Some(a) = position
                && a.value() >= root.accessors.len()
            {
                return malformed(format!(
                    "invalid glTF: mesh {m} primitive {p}: POSITION accessor {} does not exist",
                    a.value()
                ));
            }
        }
    }
    let mut errors = Vec::new();
    root.validate(root, json::Path::new, &mut |path, error| {
        let path = path();
        // gltf-json does not know KHR_mesh_quantization and calls it unsupported; it is read.
        if path.as_str().starts_with("extensionsRequired")
            && root
                .extensions_required
                .iter()
                .all(|e| e.as_str() == QUANTIZATION)
        {
            return;
        }
        if errors.len() < 5 {
            errors.push(format!("{path}: {error}"));
        }
    });
    if errors.is_empty() {
        Ok(())
    } else {
        malformed(format!("invalid glTF: {}", errors.join("; ")))
    }
}

/// The node's local transform: its matrix, or translation · rotation · scale.
fn local_transform(node: &json::Node) -> Mat4 {
    if let Some(m) = node.matrix {
        return Mat4::from_cols_array(&m);
    }
    let t = Vec3::from_array(node.translation.unwrap_or([0.0; 3]));
    let s = Vec3::from_array(node.scale.unwrap_or([1.0; 3]));
    let r = Quat::from_array(node.rotation.map_or([0.0, 0.0, 0.0, 1.0], |q| q.0));
    // glTF requires unit quaternions; tolerate float noise and reject nothing here (a zero
    // quaternion gives a non-finite matrix, which the caller reports).
    let r = r.normalize();
    Mat4::from_scale_rotation_translation(s, r, t)
}

/// Collects the geometry and cameras while walking the node tree.
struct Builder<'a> {
    root: &'a json::Root,
    bin: Option<&'a [u8]>,
    mesh: ReferenceMesh,
    cameras: Vec<ExportCamera>,
    /// Exact position bits → welded index.
    weld: HashMap<[u32; 3], u32>,
    /// The file uses `KHR_mesh_quantization`: integer positions are allowed.
    quantization: bool,
}

impl Builder<'_> {
    fn add_camera(&mut self, index: usize, world: Mat4, node_name: Option<&str>) {
        let Some(camera) = self.root.cameras.get(index) else {
            return;
        };
        let Some(p) = &camera.perspective else {
            return;
        };
        self.cameras.push(ExportCamera {
            name: node_name
                .map(str::to_string)
                .or_else(|| camera.name.clone()),
            yfov: p.yfov,
            // glTF leaves the aspect ratio to the viewport when absent; 1 is a neutral stand-in.
            aspect: p.aspect_ratio.unwrap_or(1.0),
            znear: p.znear,
            zfar: p.zfar,
            camera_to_world: world.to_cols_array(),
        });
    }

    fn add_mesh(&mut self, index: usize, world: Mat4, name: String) -> Result<(), GlbError> {
        let Some(mesh) = self.root.meshes.get(index) else {
            return malformed(format!("mesh {index} does not exist"));
        };
        let part = self.mesh.part_names.len() as u32;
        // A mirroring transform turns counter-clockwise into clockwise: swap two corners back.
        let mirrored = world.determinant() < 0.0;
        let mut added = false;
        for (pi, primitive) in mesh.primitives.iter().enumerate() {
            let what = format!("mesh {index} primitive {pi}");
            let mode = match primitive.mode {
                Valid(m) => m,
                _ => return malformed(format!("{what}: invalid mode")),
            };
            use json::mesh::Mode;
            if !matches!(
                mode,
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
            ) {
                // Points and lines have no surface to compare silhouettes with.
                continue;
            }
            let Some(&pos_accessor) = primitive
                .attributes
                .get(&Valid(json::mesh::Semantic::Positions))
            else {
                continue;
            };
            // Refuse before reading when the declared sizes already exceed the cap.
            let declared = |a: json::Index<json::Accessor>| {
                self.root.accessors.get(a.value()).map_or(0, |a| a.count.0)
            };
            let declared_corners = primitive.indices.map_or(declared(pos_accessor), declared);
            if (self.mesh.triangles.len() as u64).saturating_add(declared_corners / 3)
                > MAX_TRIANGLES as u64
            {
                return Err(GlbError::TooLarge(format!(
                    "more than {MAX_TRIANGLES} triangles after node instancing"
                )));
            }
            let positions = self.read_positions(pos_accessor.value(), &what)?;
            let indices = match primitive.indices {
                Some(a) => self.read_indices(a.value(), positions.len(), &what)?,
                None => (0..positions.len() as u32).collect(),
            };
            let corners = triangulate(mode, &indices);
            if self.mesh.triangles.len() + corners.len() / 3 > MAX_TRIANGLES
                || self.mesh.positions.len() + positions.len() > MAX_TRIANGLES
            {
                return Err(GlbError::TooLarge(format!(
                    "more than {MAX_TRIANGLES} triangles or vertices after node instancing"
                )));
            }
            let mut remap = Vec::with_capacity(positions.len());
            let identity = world == Mat4::IDENTITY;
            for p in positions {
                // Untransformed positions keep their exact bits (−0.0 included).
                let w = if identity {
                    p
                } else {
                    world.transform_point3(p)
                };
                if !w.is_finite() {
                    return malformed(format!("{what}: a transformed position is not finite"));
                }
                // +0.0 folds −0.0 into 0.0 so the two weld together.
                let key = (w + Vec3::ZERO).to_array().map(f32::to_bits);
                let next = self.mesh.positions.len() as u32;
                let id = *self.weld.entry(key).or_insert(next);
                if id == next {
                    self.mesh.positions.push(w);
                }
                remap.push(id);
            }
            for c in corners.chunks_exact(3) {
                let t = [
                    remap[c[0] as usize],
                    remap[c[1] as usize],
                    remap[c[2] as usize],
                ];
                self.mesh
                    .triangles
                    .push(if mirrored { [t[0], t[2], t[1]] } else { t });
                self.mesh.tri_parts.push(part);
            }
            added |= !corners.is_empty();
        }
        if added {
            self.mesh.part_names.push(name);
        }
        Ok(())
    }

    fn read_positions(&self, accessor: usize, what: &str) -> Result<Vec<Vec3>, GlbError> {
        let a = self.accessor(accessor, what)?;
        // KHR_mesh_quantization also allows (normalised or not) 8- and 16-bit integers; the
        // node's transform dequantises them, as it does any position.
        let quantized = self.quantization
            && matches!(
                a.component,
                ComponentType::I8 | ComponentType::U8 | ComponentType::I16 | ComponentType::U16
            );
        if a.type_ != Type::Vec3
            || !(quantized || (a.component == ComponentType::F32 && !a.normalized))
        {
            return malformed(format!(
                "{what}: POSITION must be a VEC3 float accessor{}",
                if self.quantization {
                    " or an 8/16-bit integer one (KHR_mesh_quantization)"
                } else {
                    ""
                }
            ));
        }
        let mut out = Vec::with_capacity(a.count);
        for i in 0..a.count {
            let f = |k: usize| {
                let d = &a.data;
                let at = i * a.stride + a.component.size() * k;
                // glTF 2.0 §3.11: normalised integers map to [−1, 1] (signed, clamped) or [0, 1].
                match (a.component, a.normalized) {
                    (ComponentType::I8, n) => {
                        let v = f32::from(d[at] as i8);
                        if n { (v / 127.0).max(-1.0) } else { v }
                    }
                    (ComponentType::U8, n) => f32::from(d[at]) / if n { 255.0 } else { 1.0 },
                    (ComponentType::I16, n) => {
                        let v = f32::from(i16::from_le_bytes([d[at], d[at + 1]]));
                        if n { (v / 32767.0).max(-1.0) } else { v }
                    }
                    (ComponentType::U16, n) => {
                        f32::from(u16::from_le_bytes([d[at], d[at + 1]]))
                            / if n { 65535.0 } else { 1.0 }
                    }
                    _ => f32::from_le_bytes([d[at], d[at + 1], d[at + 2], d[at + 3]]),
                }
            };
            let p = Vec3::new(f(0), f(1), f(2));
            if !p.is_finite() {
                return malformed(format!("{what}: position {i} is not finite"));
            }
            out.push(p);
        }
        Ok(out)
    }

    fn read_indices(
        &self,
        accessor: usize,
        vertex_count: usize,
        what: &str,
    ) -> Result<Vec<u32>, GlbError> {
        let a = self.accessor(accessor, what)?;
        if a.type_ != Type::Scalar || a.normalized {
            return malformed(format!("{what}: indices must be a SCALAR accessor"));
        }
        let mut out = Vec::with_capacity(a.count);
        for i in 0..a.count {
            let at = i * a.stride;
            let d = &a.data;
            let v = match a.component {
                ComponentType::U8 => u32::from(d[at]),
                ComponentType::U16 => u32::from(u16::from_le_bytes([d[at], d[at + 1]])),
                ComponentType::U32 => u32::from_le_bytes([d[at], d[at + 1], d[at + 2], d[at + 3]]),
                other => {
                    return malformed(format!("{what}: index component type {other:?}"));
                }
            };
            if v as usize >= vertex_count {
                return malformed(format!(
                    "{what}: index {v} past the {vertex_count} vertices"
                ));
            }
            out.push(v);
        }
        Ok(out)
    }

    /// The bytes of accessor `index`, every element checked to lie inside the BIN chunk.
    fn accessor(&self, index: usize, what: &str) -> Result<AccessorData<'_>, GlbError> {
        let what = format!("{what}, accessor {index}");
        let Some(a) = self.root.accessors.get(index) else {
            return malformed(format!("{what} does not exist"));
        };
        if a.sparse.is_some() {
            return Err(GlbError::Unsupported(format!("{what} is sparse")));
        }
        let (Valid(component), Valid(type_)) = (a.component_type, a.type_) else {
            return malformed(format!("{what} has an invalid type"));
        };
        let component = component.0;
        let elem = component.size() * type_.multiplicity();
        let count = a.count.0;
        let Some(view_index) = a.buffer_view else {
            return Err(GlbError::Unsupported(format!(
                "{what} has no buffer view (all zeros)"
            )));
        };
        let Some(view) = self.root.buffer_views.get(view_index.value()) else {
            return malformed(format!("{what}: buffer view does not exist"));
        };
        let buffer_index = view.buffer.value();
        let Some(buffer) = self.root.buffers.get(buffer_index) else {
            return malformed(format!("{what}: buffer {buffer_index} does not exist"));
        };
        if buffer.uri.is_some() {
            return Err(GlbError::Unsupported(format!(
                "{what} reads buffer {buffer_index}, an external or data: URI; only self-contained GLBs are read"
            )));
        }
        let Some(bin) = self.bin.filter(|_| buffer_index == 0) else {
            return malformed(format!(
                "{what} reads buffer {buffer_index} without a URI, but there is no BIN chunk for it"
            ));
        };
        let buffer_len = buffer.byte_length.0;
        if buffer_len > bin.len() as u64 {
            return malformed(format!(
                "buffer 0 declares {buffer_len} bytes, the BIN chunk has {}",
                bin.len()
            ));
        }
        let view_offset = view.byte_offset.map_or(0, |o| o.0);
        let view_len = view.byte_length.0;
        if view_offset
            .checked_add(view_len)
            .is_none_or(|end| end > buffer_len)
        {
            return malformed(format!(
                "{what}: buffer view [{view_offset}, +{view_len}) lies outside the {buffer_len}-byte buffer"
            ));
        }
        let stride = view.byte_stride.map_or(elem, |s| s.0);
        if stride < elem {
            return malformed(format!(
                "{what}: byte stride {stride} is smaller than an element ({elem} bytes)"
            ));
        }
        let offset = a.byte_offset.map_or(0, |o| o.0);
        // The last element must end inside the view; computed in u64 with overflow checks so an
        // absurd count is an error, not an allocation.
        let end = if count == 0 {
            Some(offset)
        } else {
            (count - 1)
                .checked_mul(stride as u64)
                .and_then(|x| x.checked_add(offset))
                .and_then(|x| x.checked_add(elem as u64))
        };
        if end.is_none_or(|end| end > view_len) {
            return malformed(format!(
                "{what}: {count} elements of {elem} bytes (stride {stride}, offset {offset}) do not fit in its {view_len}-byte buffer view"
            ));
        }
        // Every bound above is ≤ bin.len(), so these casts and the slice are in range.
        let start = (view_offset + offset) as usize;
        let stop = (view_offset + view_len) as usize;
        Ok(AccessorData {
            data: &bin[start..stop],
            stride,
            count: count as usize,
            component,
            type_,
            normalized: a.normalized,
        })
    }
}

/// A checked accessor: `count` elements, element `i` starting at `i * stride` in `data`.
struct AccessorData<'a> {
    data: &'a [u8],
    stride: usize,
    count: usize,
    component: ComponentType,
    type_: Type,
    normalized: bool,
}

/// Triangle corner list of a primitive (glTF 2.0 §3.7.2.1 topology rules).
fn triangulate(mode: json::mesh::Mode, idx: &[u32]) -> Vec<u32> {
    use json::mesh::Mode;
    match mode {
        Mode::Triangles => idx[..idx.len() / 3 * 3].to_vec(),
        // Strip: triangle i is (i, i+1+i%2, i+2-i%2), which keeps every triangle's winding.
        Mode::TriangleStrip => (0..idx.len().saturating_sub(2))
            .flat_map(|i| [idx[i], idx[i + 1 + i % 2], idx[i + 2 - i % 2]])
            .collect(),
        // Fan: triangle i is (i+1, i+2, 0).
        Mode::TriangleFan => (0..idx.len().saturating_sub(2))
            .flat_map(|i| [idx[i + 1], idx[i + 2], idx[0]])
            .collect(),
        _ => Vec::new(),
    }
}

/// Reads a Wavefront OBJ file's `v` and `f` records as a reference mesh (polygons
/// fan-triangulated, negative indices relative, everything else ignored).
pub fn import_obj(bytes: &[u8]) -> Result<ReferenceMesh, GlbError> {
    let text = std::str::from_utf8(bytes).map_err(|e| {
        GlbError::Malformed(format!(
            "OBJ is not UTF-8 text (invalid byte at offset {})",
            e.valid_up_to()
        ))
    })?;
    let mut mesh = ReferenceMesh::default();
    for (n, line) in text.lines().enumerate() {
        let at = |m: String| GlbError::Malformed(format!("OBJ line {}: {m}", n + 1));
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                let mut xyz = [0.0f32; 3];
                for v in &mut xyz {
                    let word = words
                        .next()
                        .ok_or_else(|| at("a vertex needs x y z".into()))?;
                    *v = word
                        .parse::<f32>()
                        .ok()
                        .filter(|v| v.is_finite())
                        .ok_or_else(|| at(format!("`{word}` is not a finite number")))?;
                }
                if mesh.positions.len() >= MAX_TRIANGLES {
                    return Err(GlbError::TooLarge(format!(
                        "more than {MAX_TRIANGLES} vertices"
                    )));
                }
                mesh.positions.push(Vec3::from_array(xyz));
            }
            Some("f") => {
                let count = mesh.positions.len() as i64;
                let corners = words
                    .map(|w| {
                        let first = w.split('/').next().unwrap_or("");
                        let i: i64 = first
                            .parse()
                            .map_err(|_| at(format!("`{w}` is not a vertex reference")))?;
                        // OBJ is 1-based; negative counts back from the latest vertex.
                        let resolved = if i < 0 { count + i } else { i - 1 };
                        if i == 0 || !(0..count).contains(&resolved) {
                            return Err(at(format!("vertex {i} does not exist ({count} so far)")));
                        }
                        Ok(resolved as u32)
                    })
                    .collect::<Result<Vec<u32>, GlbError>>()?;
                if corners.len() < 3 {
                    return Err(at("a face needs at least 3 vertices".into()));
                }
                if mesh.triangles.len() + corners.len() > MAX_TRIANGLES {
                    return Err(GlbError::TooLarge(format!(
                        "more than {MAX_TRIANGLES} triangles"
                    )));
                }
                for i in 1..corners.len() - 1 {
                    mesh.triangles
                        .push([corners[0], corners[i], corners[i + 1]]);
                    mesh.tri_parts.push(0);
                }
            }
            _ => {}
        }
    }
    if mesh.triangles.is_empty() {
        return malformed("OBJ has no faces");
    }
    mesh.part_names.push("obj".into());
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;
    use json::mesh::Mode;

    #[test]
    fn strips_and_fans_become_triangles_with_the_first_triangles_winding() {
        let check = |mode, idx: &[u32], want: &[u32]| {
            assert_eq!(triangulate(mode, idx), want, "{mode:?} {idx:?}");
        };
        check(Mode::Triangles, &[0, 1, 2, 3, 4], &[0, 1, 2]);
        check(Mode::Triangles, &[], &[]);
        check(
            Mode::TriangleStrip,
            &[0, 1, 2, 3, 4],
            &[0, 1, 2, 1, 3, 2, 2, 3, 4],
        );
        check(Mode::TriangleStrip, &[5, 6], &[]);
        check(Mode::TriangleFan, &[0, 1, 2, 3], &[1, 2, 0, 2, 3, 0]);
        check(Mode::TriangleFan, &[7], &[]);
        check(Mode::Lines, &[0, 1, 2], &[]);
    }
}
