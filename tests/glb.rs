//! GLB export and import: structure of the written file, exact round trips of the generator
//! state and geometry, vertex splitting, index widths, node transforms, OBJ, and clear errors on
//! bad input.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "a test binary: a failed step should stop it loudly"
)]

mod glb_support;

use glam::{Mat4, Vec2, Vec3};
use glb_support::{Prism, Rng, doc_of, edit_json, frame, strip, take_apart};
use procfit::generators::{self, Generator, Lod, Mesh, Part};
use procfit::glb::{
    ExportCamera, GlbError, export_model, import_glb, import_obj, import_reference, write_glb,
};
use procfit::model::Model;
use serde_json::{Value, json};

/// A lantern prism GLB with two cameras and its generator state.
fn lantern(lod: Lod) -> (Mesh, Vec<u8>) {
    let values = Prism.preset("lantern").unwrap().values;
    let mesh = Prism.generate(&values, lod).unwrap();
    let doc = doc_of(&Prism, &values, lod, Some(7));
    let glb = write_glb(&mesh, Some(&doc), &cameras()).unwrap();
    (mesh, glb)
}

fn cameras() -> Vec<ExportCamera> {
    let mut named = ExportCamera::look_at(Vec3::new(0.0, 0.4, 2.0), Vec3::ZERO, 0.8, 4.0 / 3.0);
    named.name = Some("IMG_0042.jpg".into());
    named.zfar = Some(100.0);
    vec![
        named,
        ExportCamera::look_at(Vec3::new(1.5, 1.0, -1.0), Vec3::Y * 0.2, 0.5, 0.75),
    ]
}

/// The corner positions of `mesh`'s triangles in the order the exporter writes them (part by
/// part, triangle order within a part).
fn corners_by_part(mesh: &Mesh) -> Vec<[Vec3; 3]> {
    (0..mesh.parts.len())
        .flat_map(|p| {
            mesh.triangles
                .iter()
                .zip(&mesh.tri_parts)
                .filter(move |(_, part)| usize::from(**part) == p)
                .map(|(t, _)| t.map(|i| mesh.positions[i as usize]))
        })
        .collect()
}

fn bits(v: &[[Vec3; 3]]) -> Vec<[u32; 9]> {
    v.iter()
        .map(|t| {
            let mut out = [0; 9];
            for (k, p) in t.iter().enumerate() {
                out[3 * k..3 * k + 3].copy_from_slice(&p.to_array().map(f32::to_bits));
            }
            out
        })
        .collect()
}

#[test]
fn round_trip_keeps_generator_state_cameras_and_geometry_exactly() {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    for lod in Lod::ALL {
        for _ in 0..5 {
            // Random values with full f64 precision: the state must survive JSON bit for bit.
            let values: Vec<f64> = Prism
                .params()
                .iter()
                .map(|s| rng.uniform(s.min, s.max))
                .collect();
            let values = generators::sanitize_params(Prism.params(), &values).unwrap();
            let mesh = Prism.generate(&values, lod).unwrap();
            let doc = doc_of(&Prism, &values, lod, Some(rng.next_u64()));
            let glb = write_glb(&mesh, Some(&doc), &cameras()).unwrap();
            let back = import_glb(&glb).unwrap();

            let got = back.doc().expect("procfit GLB carries its state");
            assert_eq!(got, &doc);
            for (s, &v) in Prism.params().iter().zip(&values) {
                let g = got.params[s.name].as_f64().unwrap();
                assert_eq!(g.to_bits(), v.to_bits(), "{} lost precision", s.name);
            }
            assert!(back.is_editable());
            assert_eq!(
                back.tool.as_deref(),
                Some(&*format!("procfit {}", procfit::VERSION))
            );

            // Geometry: the same triangles, corner positions bit-identical, no transform.
            let r = &back.reference;
            let imported: Vec<[Vec3; 3]> = r
                .triangles
                .iter()
                .map(|t| t.map(|i| r.positions[i as usize]))
                .collect();
            assert_eq!(bits(&imported), bits(&corners_by_part(&mesh)));
            // Welding on import gives back exactly the generator's welded vertices that are used.
            assert_eq!(r.positions.len(), mesh.positions.len(), "lod {lod:?}");
            let names: Vec<&str> = r.part_names.iter().map(String::as_str).collect();
            let want: Vec<&str> = ["body", "window_glass", "leaves"]
                .into_iter()
                .filter(|n| {
                    mesh.tri_parts
                        .iter()
                        .any(|&p| mesh.parts[usize::from(p)].name == *n)
                })
                .collect();
            assert_eq!(names, want);

            assert_eq!(back.cameras.len(), 2);
            for (a, b) in back.cameras.iter().zip(cameras()) {
                assert_eq!(
                    a.name.as_deref(),
                    Some(b.name.as_deref().unwrap_or("photo_1"))
                );
                assert_eq!(
                    (a.yfov, a.aspect, a.znear, a.zfar),
                    (b.yfov, b.aspect, b.znear, b.zfar)
                );
                let err = a
                    .camera_to_world
                    .iter()
                    .zip(b.camera_to_world)
                    .map(|(x, y)| (x - y).abs())
                    .fold(0.0f32, f32::max);
                assert!(err < 1e-6, "camera pose off by {err}");
            }
        }
    }
}

/// How many triangles of `mesh` repeat an earlier triangle of the same part reversed.
fn reversed_copies(mesh: &Mesh) -> usize {
    let canon = |t: [u32; 3]| {
        let k = (0..3).min_by_key(|&k| t[k]).unwrap();
        [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
    };
    let mut seen = std::collections::HashSet::new();
    let mut n = 0;
    for (t, &p) in mesh.triangles.iter().zip(&mesh.tri_parts) {
        if seen.contains(&(p, canon([t[0], t[2], t[1]]))) {
            n += 1;
        } else {
            seen.insert((p, canon(*t)));
        }
    }
    n
}

/// Issue 17: a tree's leaf cards are written once, one-sided with a double-sided material, not
/// as front and back triangles on top of `doubleSided`.
#[test]
fn leaf_cards_are_written_once_with_a_double_sided_material() {
    use procfit::generators::tree::PART_LEAF;
    let model = Model::new(
        "tree",
        &generators::by_name("tree").unwrap().defaults(),
        Lod::High,
    )
    .unwrap();
    let mesh = model.generator.generate(&model.params, model.lod).unwrap();
    let leaf_tris = mesh.tri_parts.iter().filter(|&&p| p == PART_LEAF).count();
    assert!(
        leaf_tris > 0 && reversed_copies(&mesh) == leaf_tris / 2,
        "the generator's cards are two-sided"
    );
    let imported = import_glb(&export_model(&model, &[]).unwrap()).unwrap();
    let leaf_part = imported
        .reference
        .part_names
        .iter()
        .position(|n| n == "leaf")
        .unwrap() as u32;
    let written = imported
        .reference
        .tri_parts
        .iter()
        .filter(|&&p| p == leaf_part)
        .count();
    assert_eq!(written, leaf_tris / 2, "each card once");
    let json = glb_json(&export_model(&model, &[]).unwrap());
    let leaf_material = json["materials"]
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["name"] == "leaf")
        .unwrap();
    assert_eq!(leaf_material["doubleSided"], true);
}

/// The JSON chunk of a GLB.
fn glb_json(glb: &[u8]) -> serde_json::Value {
    let len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    serde_json::from_slice(&glb[20..20 + len]).unwrap()
}

/// Every generator built in, every preset, every level: export → import → `Model` → regenerate
/// gives the identical model and a bit-identical mesh.
#[test]
fn real_generators_round_trip_to_identical_model_and_mesh() {
    let all = generators::all();
    let mut checked = 0;
    for g in &all {
        for preset in g.presets() {
            for lod in Lod::ALL {
                let mut model = Model::new(g.name(), &preset.values, lod).unwrap();
                model.seed = Some(42);
                let glb = export_model(&model, &[]).unwrap();
                let imported = import_glb(&glb).unwrap();
                let back = imported.model().unwrap();
                let what = format!("{} {} {lod:?}", g.name(), preset.name);
                // One named node per part that has triangles, in part order.
                let mesh = g.generate(&model.params, lod).unwrap();
                let parts: Vec<&str> = (0..mesh.parts.len())
                    .filter(|&p| mesh.tri_parts.iter().any(|&t| usize::from(t) == p))
                    .map(|p| mesh.parts[p].name)
                    .collect();
                assert_eq!(imported.reference.part_names, parts, "{what}");
                // Less the backs of double-sided cards (a reversed copy of an earlier triangle).
                assert_eq!(
                    imported.reference.triangles.len(),
                    mesh.triangles.len() - reversed_copies(&mesh),
                    "{what}"
                );
                assert_eq!(back.generator.name(), g.name(), "{what}");
                assert_eq!(
                    back.params.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                    model.params.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                    "{what}"
                );
                assert_eq!((back.lod, back.seed), (lod, Some(42)), "{what}");
                let a = g.generate(&model.params, lod).unwrap();
                let b = back.generator.generate(&back.params, back.lod).unwrap();
                let pos = |m: &Mesh| -> Vec<[u32; 3]> {
                    m.positions
                        .iter()
                        .map(|p| p.to_array().map(f32::to_bits))
                        .collect()
                };
                assert_eq!(pos(&a), pos(&b), "{what}");
                assert_eq!(a, b, "{what}");
                checked += 1;
            }
        }
    }
    // An empty registry would make this test vacuous.
    let want: usize = all.iter().map(|g| 4 * g.presets().len()).sum();
    assert!(
        checked > 0 && checked == want,
        "checked {checked} of {want}"
    );
}

#[test]
fn file_structure_names_materials_cameras_and_extras() {
    let (mesh, glb) = lantern(Lod::Medium);
    let (j, bin) = take_apart(&glb);
    assert_eq!(j["asset"]["version"], "2.0");
    let scene = &j["scenes"][j["scene"].as_u64().unwrap() as usize];
    assert_eq!(scene["name"], "test_prism_scene");
    // The extras are exactly params JSON.
    assert_eq!(scene["extras"]["generator"], "test_prism");
    assert_eq!(scene["extras"]["version"], 3);
    assert_eq!(scene["extras"]["lod"], 1);
    assert_eq!(scene["extras"]["seed"], 7);
    assert_eq!(scene["extras"]["params"]["sides"], 6.0);

    let nodes = j["nodes"].as_array().unwrap();
    let name = |i: &Value| {
        nodes[i.as_u64().unwrap() as usize]["name"]
            .as_str()
            .unwrap()
    };
    let roots: Vec<&str> = scene["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .map(name)
        .collect();
    assert_eq!(roots, ["test_prism", "IMG_0042.jpg", "photo_1"]);
    let object = &nodes[scene["nodes"][0].as_u64().unwrap() as usize];
    let parts: Vec<&str> = object["children"]
        .as_array()
        .unwrap()
        .iter()
        .map(name)
        .collect();
    // `unused` has no triangles and is left out (glTF forbids empty accessors).
    assert_eq!(parts, ["body", "window_glass", "leaves"]);

    let mats = j["materials"].as_array().unwrap();
    let mat = |n: &str| mats.iter().find(|m| m["name"] == n).unwrap();
    assert!(matches!(
        mat("body")["alphaMode"].as_str(),
        None | Some("OPAQUE")
    ));
    assert_eq!(mat("window_glass")["alphaMode"], "BLEND");
    let glass_alpha = mat("window_glass")["pbrMetallicRoughness"]["baseColorFactor"][3]
        .as_f64()
        .unwrap();
    assert!(
        glass_alpha > 0.1 && glass_alpha < 0.9,
        "glass alpha {glass_alpha}"
    );
    assert_eq!(mat("leaves")["alphaMode"], "MASK");
    let body_color = &mat("body")["pbrMetallicRoughness"]["baseColorFactor"];
    assert_eq!(
        body_color[0].as_f64().unwrap() as f32,
        mesh.parts[0].color[0]
    );

    assert_eq!(j["cameras"].as_array().unwrap().len(), 2);
    assert_eq!(j["cameras"][0]["type"], "perspective");
    assert_eq!(j["buffers"][0]["byteLength"], bin.len());

    // POSITION min/max equal the data's exact extremes.
    for m in j["meshes"].as_array().unwrap() {
        let prim = &m["primitives"][0];
        let acc = &j["accessors"][prim["attributes"]["POSITION"].as_u64().unwrap() as usize];
        let view = &j["bufferViews"][acc["bufferView"].as_u64().unwrap() as usize];
        let at = view["byteOffset"].as_u64().unwrap() as usize;
        let n = acc["count"].as_u64().unwrap() as usize;
        let floats: Vec<f32> = bin[at..at + 12 * n]
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
            .collect();
        for k in 0..3 {
            let col = floats.iter().skip(k).step_by(3);
            let lo = col.clone().copied().fold(f32::INFINITY, f32::min);
            let hi = col.copied().fold(f32::NEG_INFINITY, f32::max);
            assert_eq!(acc["min"][k].as_f64().unwrap() as f32, lo, "{}", m["name"]);
            assert_eq!(acc["max"][k].as_f64().unwrap() as f32, hi, "{}", m["name"]);
        }
    }
}

/// A cube on 8 welded positions with the given corner normals (flat or smooth) and UVs.
fn cube(smooth: bool, seam: bool) -> Mesh {
    let p: Vec<Vec3> = (0..8)
        .map(|i| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32) - 0.5)
        .collect();
    // Faces as quads, counter-clockwise from outside.
    let quads = [
        [0, 4, 6, 2],
        [1, 3, 7, 5],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 2, 3, 1],
        [4, 5, 7, 6],
    ];
    let mut m = Mesh {
        positions: p.clone(),
        parts: vec![Part {
            name: "body",
            color: [1.0; 4],
        }],
        ..Mesh::default()
    };
    for (f, q) in quads.iter().enumerate() {
        for t in [[q[0], q[1], q[2]], [q[0], q[2], q[3]]] {
            m.triangles.push(t);
            m.tri_parts.push(0);
            let face = (p[t[1] as usize] - p[t[0] as usize])
                .cross(p[t[2] as usize] - p[t[0] as usize])
                .normalize();
            for &i in &t {
                m.corner_normals.push(if smooth {
                    p[i as usize].normalize()
                } else {
                    face
                });
                // With a seam, every face has its own UV island.
                m.corner_uvs
                    .push(Vec2::new(i as f32, if seam { f as f32 } else { 0.0 }));
            }
        }
    }
    m
}

/// Number of vertices the exporter writes for `mesh` (its single part).
fn written_vertices(mesh: &Mesh) -> u64 {
    let glb = write_glb(mesh, None, &[]).unwrap();
    let (j, _) = take_apart(&glb);
    let prim = &j["meshes"][0]["primitives"][0];
    j["accessors"][prim["attributes"]["POSITION"].as_u64().unwrap() as usize]["count"]
        .as_u64()
        .unwrap()
}

#[test]
fn vertices_split_exactly_where_corner_attributes_differ() {
    let check = |smooth, seam, want| {
        assert_eq!(
            written_vertices(&cube(smooth, seam)),
            want,
            "smooth {smooth} seam {seam}"
        )
    };
    check(true, false, 8); // all corners of a position agree: no split
    check(false, false, 24); // hard edges: 3 normals per corner
    check(true, true, 24); // UV seams alone split as much
    check(false, true, 24);
}

#[test]
fn indices_are_u16_below_65535_vertices_and_u32_from_there() {
    let check = |n: usize, component: u64| {
        let mesh = strip(n);
        let glb = write_glb(&mesh, None, &[]).unwrap();
        let (j, _) = take_apart(&glb);
        let prim = &j["meshes"][0]["primitives"][0];
        let acc = &j["accessors"][prim["indices"].as_u64().unwrap() as usize];
        assert_eq!(written_vertices(&mesh), n as u64);
        assert_eq!(acc["componentType"], component, "{n} vertices");
        assert_eq!(written_vertices(&mesh), n as u64);
        // The indices read back to the same triangles.
        let back = import_glb(&glb).unwrap().reference;
        assert_eq!(back.triangles, mesh.triangles, "{n} vertices");
    };
    check(3, 5123);
    check(65_534, 5123);
    // 65535 needs index 65534 only, but u16's 65535 is reserved; from 65535 vertices on the
    // u16 range is too tight for comfort and u32 is used.
    check(65_535, 5125);
    check(70_000, 5125);
}

#[test]
fn node_transforms_are_applied_and_mirrors_keep_winding() {
    let mesh = cube(false, false);
    let glb = write_glb(&mesh, None, &[]).unwrap();
    let moved = edit_json(&glb, |j| {
        // The object's root node is the parent of the part node.
        let root = j["scenes"][0]["nodes"][0].as_u64().unwrap() as usize;
        j["nodes"][root]["translation"] = json!([1.0, 2.0, 3.0]);
        j["nodes"][root]["scale"] = json!([2.0, 2.0, -2.0]);
    });
    let r = import_glb(&moved).unwrap().reference;
    let (lo, hi) = r.bounds().unwrap();
    assert_eq!(lo, Vec3::new(0.0, 1.0, 2.0));
    assert_eq!(hi, Vec3::new(2.0, 3.0, 4.0));
    // Signed volume stays positive: triangles still counter-clockwise from outside.
    let volume: f32 = r
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| r.positions[i as usize]);
            a.dot(b.cross(c)) / 6.0
        })
        .sum();
    assert!((volume - 8.0).abs() < 1e-4, "volume {volume}");
}

#[test]
fn glb_without_procfit_state_opens_as_reference_but_is_not_editable() {
    let (_, glb) = lantern(Lod::Low);
    let foreign = edit_json(&glb, |j| {
        j["scenes"][0].as_object_mut().unwrap().remove("extras");
        j["asset"]["generator"] = json!("Blender");
    });
    let g = import_glb(&foreign).unwrap();
    assert!(!g.is_editable());
    assert!(!g.reference.triangles.is_empty());
    let err = g.model().unwrap_err();
    assert!(matches!(err, GlbError::NotEditable(_)));
    let text = err.to_string();
    assert!(
        text.contains("cannot be edited") && text.contains("reference mesh"),
        "{text}"
    );

    // Extras from another tool are not mistaken for a generator state.
    let other = edit_json(&glb, |j| j["scenes"][0]["extras"] = json!({"author": "me"}));
    let g = import_glb(&other).unwrap();
    assert!(!g.is_editable());
    assert!(
        g.model()
            .unwrap_err()
            .to_string()
            .contains("not a procfit generator state")
    );

    // A procfit state naming an unknown generator says so.
    let unknown = edit_json(&glb, |j| {
        j["scenes"][0]["extras"]["generator"] = json!("teapot")
    });
    let err = import_glb(&unknown)
        .unwrap()
        .model()
        .unwrap_err()
        .to_string();
    assert!(err.contains("teapot"), "{err}");
}

#[test]
fn obj_and_reference_sniffing() {
    let obj = b"# a quad and a triangle\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//1 4//1\nf -4/1 -3/2 -1/3\n";
    let m = import_obj(obj).unwrap();
    assert_eq!(m.positions.len(), 4);
    assert_eq!(m.triangles, [[0, 1, 2], [0, 2, 3], [0, 1, 3]]);
    assert_eq!(import_reference(obj).unwrap(), m);
    let (_, glb) = lantern(Lod::Low);
    assert_eq!(
        import_reference(&glb).unwrap(),
        import_glb(&glb).unwrap().reference
    );

    let check = |text: &[u8], want: &str| {
        let err = import_reference(text).unwrap_err().to_string();
        assert!(err.contains(want), "{err:?} does not say {want:?}");
    };
    check(
        b"v 0 0 0\nv 1 0 0\nf 1 2 3\n",
        "line 3: vertex 3 does not exist",
    );
    check(b"v 0 0\n", "line 1: a vertex needs x y z");
    check(b"v 0 nan 0\n", "not a finite number");
    check(b"v 0 0 0\nf 0 1 1\n", "vertex 0 does not exist");
    check(b"v 0 0 0\nf 1 1\n", "at least 3 vertices");
    check(b"v 0 0 0\n", "no faces");
    check(b"v 0 0 0\xff\n", "not UTF-8");
    check(b"  {\"asset\": {}}", "single binary .glb");
}

/// Expects `import_glb(bytes)` to fail with a message containing `want`.
fn check_err(what: &str, bytes: &[u8], want: &str) {
    match import_glb(bytes) {
        Ok(_) => panic!("{what}: imported"),
        Err(e) => {
            let text = e.to_string();
            assert!(
                text.contains(want),
                "{what}: {text:?} does not say {want:?}"
            );
        }
    }
}

#[test]
fn bad_input_gives_clear_errors() {
    let (_, glb) = lantern(Lod::Low);
    let (j, bin) = take_apart(&glb);
    let json_bytes = serde_json::to_vec(&j).unwrap();
    let set_u32 = |at: usize, v: u32| {
        let mut b = glb.clone();
        b[at..at + 4].copy_from_slice(&v.to_le_bytes());
        b
    };
    check_err("empty", b"", "truncated: 0 bytes");
    check_err("short", &glb[..11], "truncated: 11 bytes");
    check_err("magic", &[b"GLTF", &glb[4..]].concat(), "not a GLB file");
    check_err("version 1", &set_u32(4, 1), "version 1");
    check_err(
        "truncated body",
        &glb[..glb.len() - 4],
        "truncated: the header declares",
    );
    check_err(
        "length past end",
        &set_u32(8, glb.len() as u32 + 1),
        "the file has",
    );
    check_err("json chunk past end", &set_u32(12, 1 << 30), "GLB chunks");
    check_err("no chunk", &frame(b"", &[])[..12], "truncated");
    let mut not_utf8 = json_bytes.clone();
    not_utf8[10] = 0xff;
    check_err("non-UTF-8 JSON", &frame(&not_utf8, &bin), "not UTF-8");
    check_err("not JSON", &frame(b"{\"asset\": [", &bin), "glTF JSON");
    check_err("no asset", &frame(b"{}", &bin), "glTF JSON");

    let edited = |f: &dyn Fn(&mut Value)| edit_json(&glb, f);
    check_err(
        "absurd accessor count",
        &edited(&|j| j["accessors"][0]["count"] = json!(4_000_000_000u64)),
        "4000000000 elements",
    );
    check_err(
        "count overflows u64 arithmetic",
        &edited(&|j| j["accessors"][0]["count"] = json!(u64::MAX)),
        "do not fit",
    );
    check_err(
        "view past buffer",
        &edited(&|j| j["bufferViews"][0]["byteOffset"] = json!(1u64 << 40)),
        "outside the",
    );
    check_err(
        "buffer longer than BIN",
        &edited(&|j| j["buffers"][0]["byteLength"] = json!(1u64 << 33)),
        "the BIN chunk has",
    );
    check_err(
        "stride below element",
        &edited(&|j| j["bufferViews"][0]["byteStride"] = json!(4)),
        "byte stride 4",
    );
    check_err(
        "dangling accessor index",
        &edited(&|j| j["meshes"][0]["primitives"][0]["indices"] = json!(999)),
        "invalid glTF",
    );
    check_err(
        "index past vertices",
        &edit_json(&frame(&json_bytes, &bin), |j| {
            // Point the first index accessor at the position data, whose float bits are huge.
            let idx = j["meshes"][0]["primitives"][0]["indices"].as_u64().unwrap() as usize;
            j["accessors"][idx]["bufferView"] = json!(0);
            j["accessors"][idx]["componentType"] = json!(5125);
            j["accessors"][idx]["count"] = json!(3);
        }),
        "past the",
    );
    check_err(
        "node cycle",
        &edited(&|j| {
            let root = j["scenes"][0]["nodes"][0].clone();
            let child = j["nodes"][root.as_u64().unwrap() as usize]["children"][0].clone();
            j["nodes"][child.as_u64().unwrap() as usize]["children"] = json!([root]);
        }),
        "reached twice",
    );
    check_err(
        "external buffer",
        &edited(&|j| j["buffers"][0]["uri"] = json!("model.bin")),
        "external",
    );
    check_err(
        "sparse accessor",
        &edited(&|j| {
            j["accessors"][0]["sparse"] = json!({"count": 1,
                "indices": {"bufferView": 0, "componentType": 5125},
                "values": {"bufferView": 0}})
        }),
        "sparse",
    );
    check_err(
        "infinite scale",
        &edited(&|j| {
            // Each scale is finite; their product is not.
            let root = j["scenes"][0]["nodes"][0].as_u64().unwrap() as usize;
            j["nodes"][root]["scale"] = json!([3e38, 1.0, 1.0]);
            j["nodes"][0]["scale"] = json!([3e38, 1.0, 1.0]);
        }),
        "non-finite",
    );
    check_err(
        "required extension",
        &edited(&|j| j["extensionsRequired"] = json!(["KHR_draco_mesh_compression"])),
        "requires extension KHR_draco_mesh_compression",
    );
}

#[test]
fn json_chunk_padded_with_nuls_still_imports() {
    let (_, glb) = lantern(Lod::Low);
    let (j, bin) = take_apart(&glb);
    let mut text = serde_json::to_vec(&j).unwrap();
    text.resize(text.len().next_multiple_of(4) + 4, 0);
    let padded = frame(&text, &bin);
    let want = import_glb(&glb).unwrap();
    let got = import_glb(&padded).unwrap();
    assert_eq!(got.reference, want.reference);
    assert_eq!(got.doc(), want.doc());
}

#[test]
fn instancing_one_mesh_from_many_nodes_is_capped() {
    // 70 000 triangles instanced from 61 nodes: 4.27 M triangles, past the 4 Mi cap.
    let glb = write_glb(&strip(70_002), None, &[]).unwrap();
    let bomb = edit_json(&glb, |j| {
        let nodes = j["nodes"].as_array_mut().unwrap();
        for _ in 0..60 {
            nodes.push(json!({"mesh": 0}));
        }
        let n = nodes.len();
        let scene = j["scenes"][0]["nodes"].as_array_mut().unwrap();
        scene.extend((n - 60..n).map(|i| json!(i)));
    });
    check_err("instancing bomb", &bomb, "more than 4194304 triangles");
    // Fewer instances import.
    let fine = edit_json(&glb, |j| {
        j["nodes"].as_array_mut().unwrap().push(json!({"mesh": 0}));
        let n = j["nodes"].as_array().unwrap().len();
        j["scenes"][0]["nodes"]
            .as_array_mut()
            .unwrap()
            .push(json!(n - 1));
    });
    assert_eq!(
        import_glb(&fine).unwrap().reference.triangles.len(),
        140_000
    );
}

/// Regression: `gltf::binary::Glb::from_slice` subtracts 12 from the declared length without a
/// check, which panicked (overflow) on headers declaring fewer than 12 bytes.
#[test]
fn header_length_below_12_is_an_error_not_an_overflow() {
    let (_, glb) = lantern(Lod::Low);
    for declared in [0u32, 1, 11, 12, 19] {
        let mut b = glb.clone();
        b[8..12].copy_from_slice(&declared.to_le_bytes());
        check_err(&format!("declared {declared}"), &b, "too short");
    }
}

/// Regression: gltf-json 1.4.1's validation indexes the POSITION accessor without a bounds
/// check; a dangling POSITION index panicked inside `validate` (found by `glb_fuzz`).
#[test]
fn dangling_position_accessor_is_an_error_not_a_panic_in_gltf_json() {
    let (_, glb) = lantern(Lod::Low);
    let bad = edit_json(&glb, |j| {
        j["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(4096)
    });
    check_err(
        "dangling POSITION",
        &bad,
        "POSITION accessor 4096 does not exist",
    );
}

#[test]
fn export_rejects_bad_meshes_and_cameras() {
    let check = |mesh: &Mesh, cams: &[ExportCamera], want: &str| {
        let err = write_glb(mesh, None, cams).unwrap_err().to_string();
        assert!(err.contains(want), "{err:?} does not say {want:?}");
    };
    let good = cube(false, false);
    check(&Mesh::default(), &[], "no triangles");
    let mut nan = good.clone();
    nan.positions[3].x = f32::NAN;
    check(&nan, &[], "non-finite");
    let mut short = good.clone();
    short.tri_parts.pop();
    check(&short, &[], "part ids");

    let cam = ExportCamera::look_at(Vec3::Z * 3.0, Vec3::ZERO, 0.8, 1.0);
    let with = |f: &dyn Fn(&mut ExportCamera)| {
        let mut c = cam.clone();
        f(&mut c);
        vec![c]
    };
    check(&good, &with(&|c| c.yfov = 0.0), "yfov");
    check(&good, &with(&|c| c.yfov = f32::NAN), "yfov");
    check(&good, &with(&|c| c.aspect = -1.0), "aspect");
    check(&good, &with(&|c| c.znear = 0.0), "znear");
    check(&good, &with(&|c| c.zfar = Some(0.001)), "zfar");
    check(
        &good,
        &with(&|c| c.camera_to_world = Mat4::from_scale(Vec3::splat(2.0)).to_cols_array()),
        "not rigid",
    );
    check(
        &good,
        &with(&|c| c.camera_to_world = Mat4::from_scale(Vec3::new(1.0, 1.0, -1.0)).to_cols_array()),
        "mirrored",
    );
    check(
        &good,
        &with(&|c| c.camera_to_world[13] = f32::INFINITY),
        "non-finite",
    );
    // The good camera writes.
    assert!(write_glb(&good, None, &[cam]).is_ok());
}

#[test]
fn look_at_points_the_camera_down_its_minus_z_at_the_target() {
    let eye = Vec3::new(1.0, 2.0, 3.0);
    let c = ExportCamera::look_at(eye, Vec3::ZERO, 0.7, 1.5);
    let m = Mat4::from_cols_array(&c.camera_to_world);
    let forward = m.transform_vector3(Vec3::NEG_Z);
    assert!((forward - (-eye).normalize()).length() < 1e-6);
    assert!(
        m.transform_vector3(Vec3::X).y.abs() < 1e-6,
        "image x stays horizontal"
    );
    assert!(m.transform_vector3(Vec3::Y).y > 0.0, "image up points up");
    assert_eq!(m.transform_point3(Vec3::ZERO), eye);
}

#[test]
fn a_camera_goes_to_18_floats_and_back() {
    use procfit::glb::{CAMERA_FLOATS, ExportCamera};
    let c = ExportCamera::look_at(glam::Vec3::new(1.0, 2.0, 3.0), glam::Vec3::ZERO, 0.6, 1.5);
    let f = c.to_floats();
    assert_eq!(f.len(), CAMERA_FLOATS);
    assert_eq!((f[0], f[1]), (0.6, 1.5));
    assert_eq!(&f[2..], &c.camera_to_world);
    let back = ExportCamera::from_floats(&f, Some("photo 1".into()));
    assert_eq!(
        back,
        ExportCamera {
            name: Some("photo 1".into()),
            ..c
        }
    );
}

#[test]
fn a_model_file_is_a_procfit_glb_or_params_json() {
    let m = Model::new(
        "dish",
        &generators::by_name("dish").unwrap().defaults(),
        Lod::Low,
    )
    .unwrap();
    let glb = procfit::glb::export_model(&m, &[]).unwrap();
    for bytes in [glb, m.to_json().into_bytes()] {
        let back = Model::from_file_bytes(&bytes).unwrap();
        assert_eq!(back.to_doc(), m.to_doc());
    }
    let e = Model::from_file_bytes(&[0xff, 0xfe, 0x00])
        .unwrap_err()
        .to_string();
    assert!(e.contains("neither a GLB nor params JSON"), "{e}");
    let e = Model::from_file_bytes(b"{\"not\": 1}")
        .unwrap_err()
        .to_string();
    assert!(e.contains("params JSON"), "{e}");
}

#[test]
fn generator_specs_serialise_as_the_page_reads_them() {
    let dish = procfit::generators::by_name("dish").unwrap();
    let v = serde_json::to_value(dish.params()).unwrap();
    let first = &v[0];
    let s = &dish.params()[0];
    assert_eq!(first["name"], s.name);
    assert_eq!(first["min"], s.min);
    assert_eq!(first["default"], s.default);
    let kinds: Vec<&str> = v
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["kind"].as_str().unwrap())
        .collect();
    assert!(
        kinds
            .iter()
            .all(|k| ["continuous", "integer", "boolean", "categorical"].contains(k))
    );
    // A categorical parameter carries its choices; the others an empty list.
    for (p, spec) in v.as_array().unwrap().iter().zip(dish.params()) {
        let n = match spec.kind {
            procfit::generators::ParamKind::Categorical(c) => c.len(),
            _ => 0,
        };
        assert_eq!(p["choices"].as_array().unwrap().len(), n, "{}", spec.name);
    }
    let preset = serde_json::to_value(&dish.presets()[0]).unwrap();
    assert_eq!(preset["name"], dish.presets()[0].name);
    assert_eq!(
        preset["values"].as_array().unwrap().len(),
        dish.params().len()
    );
}

/// Issue 17: a compact GLB (`KHR_mesh_quantization`) opens again: the same model, and the same
/// welded mesh within the quantisation step (1/32767 of each part's half-size).
#[test]
fn compact_glbs_open_again_as_the_same_model() {
    use procfit::glb::{GlbOptions, write_glb_with};
    for g in generators::all() {
        let preset = g.presets().remove(0);
        let model = Model::new(g.name(), &preset.values, Lod::Medium).unwrap();
        let mesh = g.generate(&model.params, model.lod).unwrap();
        let doc = model.to_doc();
        let plain = import_glb(&write_glb(&mesh, Some(&doc), &[]).unwrap()).unwrap();
        let compact = GlbOptions { quantize: true };
        let small = import_glb(&write_glb_with(&mesh, Some(&doc), &[], compact).unwrap()).unwrap();
        let what = g.name();
        let back = small.model().unwrap();
        assert_eq!(back.generator.name(), g.name(), "{what}");
        assert_eq!(back.params, model.params, "{what}");
        assert_eq!(
            small.reference.triangles.len(),
            plain.reference.triangles.len(),
            "{what}"
        );
        assert_eq!(
            small.reference.part_names, plain.reference.part_names,
            "{what}"
        );
        let (lo, hi) = plain
            .reference
            .positions
            .iter()
            .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| {
                (lo.min(p), hi.max(p))
            });
        let step = (hi - lo).max_element() / 32767.0;
        // Welding can differ (two positions one step apart may fall together), so each
        // triangle's corners are compared through their own indices.
        let mut worst = 0.0f32;
        for (ta, tb) in small
            .reference
            .triangles
            .iter()
            .zip(&plain.reference.triangles)
        {
            for k in 0..3 {
                let a = small.reference.positions[ta[k] as usize];
                let b = plain.reference.positions[tb[k] as usize];
                worst = worst.max((a - b).abs().max_element());
            }
        }
        assert!(
            worst <= step,
            "{what}: a corner moved {worst} (step {step})"
        );
    }
}

/// A tree's leaf cards carry the leaf texture, alpha-masked, and its trunk and branches the
/// bark texture: two PNG images embedded once each, whatever the level of detail; a dish has
/// none (issue 17).
#[test]
fn trees_have_leaf_and_bark_textures_written_once() {
    let tree = generators::by_name("tree").unwrap();
    for lod in Lod::ALL {
        let model = Model::new("tree", &tree.presets()[0].values, lod).unwrap();
        let glb = procfit::glb::export_model(&model, &[]).unwrap();
        let gltf = gltf::Gltf::from_slice(&glb).unwrap();
        assert_eq!(gltf.images().count(), 2, "lod {}", lod.index());
        let bin = gltf.blob.as_deref().unwrap();
        for image in gltf.images() {
            let gltf::image::Source::View { view, mime_type } = image.source() else {
                panic!("image not embedded")
            };
            assert_eq!(mime_type, "image/png");
            let png = &bin[view.offset()..view.offset() + view.length()];
            image::load_from_memory(png).unwrap();
        }
        for m in gltf.materials() {
            let texture = m
                .pbr_metallic_roughness()
                .base_color_texture()
                .map(|t| t.texture().source().name().unwrap_or("").to_string());
            match m.name().unwrap() {
                "leaf" => {
                    assert_eq!(texture.as_deref(), Some("leaves"));
                    assert_eq!(m.alpha_mode(), gltf::material::AlphaMode::Mask);
                    assert!(m.double_sided());
                }
                "trunk" | "branch" => assert_eq!(texture.as_deref(), Some("bark")),
                other => panic!("unexpected tree part {other}"),
            }
        }
    }
    let dish = generators::by_name("dish").unwrap();
    let model = Model::new("dish", &dish.presets()[0].values, Lod::Medium).unwrap();
    let glb = procfit::glb::export_model(&model, &[]).unwrap();
    assert_eq!(gltf::Gltf::from_slice(&glb).unwrap().images().count(), 0);
}
