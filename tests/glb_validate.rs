//! Writes a GLB for every built-in generator's presets × levels of detail, each plain and compact
//! (`KHR_mesh_quantization`, `<name>.compact.glb`) (plus the test prism with cameras and a mesh
//! that needs u32 indices) and runs the Khronos glTF-Validator on them
//! through `node tests/gltf_validate.mjs`: 0 errors and 0 warnings required; then loads them
//! with three.js's GLTFLoader (`node tests/gltf_three.mjs`), which must find every named part and
//! camera, and must place every compact file's parts where the plain file has them.
//!
//! Needs `node` and `npm ci` (for `node_modules/gltf-validator`). Where node is truly absent, set
//! `PROCFIT_SKIP_NODE=1` to skip the validator run explicitly; otherwise a missing node fails.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "a test binary: a failed step should stop it loudly"
)]

mod glb_support;

use glb_support::{Prism, doc_of, strip};
use procfit::generators::{self, Generator, Lod};
use procfit::glb::{ExportCamera, GlbOptions, export_model, write_glb, write_glb_with};
use procfit::model::Model;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Length of a GLB's BIN chunk (the geometry), after the JSON chunk.
fn bin_len(glb: &[u8]) -> usize {
    let word = |at: usize| u32::from_le_bytes(glb[at..at + 4].try_into().unwrap()) as usize;
    word(20 + word(12))
}

/// Writes every GLB under test into `dir` and returns how many.
fn write_all(dir: &Path) -> usize {
    let mut n = 0;
    let mut put = |name: String, bytes: Vec<u8>| {
        std::fs::write(dir.join(format!("{name}.glb")), bytes).unwrap();
        n += 1;
    };
    for g in generators::all() {
        for preset in g.presets() {
            for lod in Lod::ALL {
                let model = Model::new(g.name(), &preset.values, lod).unwrap();
                let glb = export_model(&model, &[]).unwrap();
                let name = format!("{}-{}-lod{}", g.name(), preset.name, lod.index());
                let mesh = g.generate(&model.params, lod).unwrap();
                let compact = GlbOptions { quantize: true };
                let small = write_glb_with(&mesh, Some(&model.to_doc()), &[], compact).unwrap();
                assert!(
                    bin_len(&small) * 10 < bin_len(&glb) * 7,
                    "{name}: compact geometry {} bytes, plain {}",
                    bin_len(&small),
                    bin_len(&glb)
                );
                put(format!("{name}.compact"), small);
                put(name, glb);
            }
        }
    }
    let cameras = [
        ExportCamera::look_at(glam::Vec3::new(0.0, 0.5, 2.0), glam::Vec3::ZERO, 0.8, 1.5),
        ExportCamera::look_at(glam::Vec3::new(0.0, 3.0, 0.0), glam::Vec3::ZERO, 0.6, 1.0),
    ];
    for preset in Prism.presets() {
        for lod in Lod::ALL {
            let mesh = Prism.generate(&preset.values, lod).unwrap();
            let doc = doc_of(&Prism, &preset.values, lod, Some(1));
            let glb = write_glb(&mesh, Some(&doc), &cameras).unwrap();
            let name = format!("test_prism-{}-lod{}", preset.name, lod.index());
            let compact = GlbOptions { quantize: true };
            let small = write_glb_with(&mesh, Some(&doc), &cameras, compact).unwrap();
            put(format!("{name}.compact"), small);
            put(name, glb);
        }
    }
    // A mug in colours from a photo (baseColorFactor from `Model::colors`), plain and compact.
    let mug = generators::by_name("dish").unwrap().presets()[0]
        .values
        .clone();
    let mut colors = procfit::model::PartColors::new();
    colors.insert("body".into(), [0.06, 0.22, 0.62]);
    colors.insert("handle".into(), [0.86, 0.86, 0.84]);
    let model = Model::new("dish", &mug, Lod::Medium)
        .unwrap()
        .with_colors(&colors)
        .unwrap();
    put(
        "dish-coloured".into(),
        export_model(&model, &cameras).unwrap(),
    );
    let mesh = model.mesh().unwrap();
    let compact = GlbOptions { quantize: true };
    put(
        "dish-coloured.compact".into(),
        write_glb_with(&mesh, Some(&model.to_doc()), &cameras, compact).unwrap(),
    );
    // One part of 70 000 vertices: u32 indices.
    put(
        "strip-70000".into(),
        write_glb(&strip(70_000), None, &[]).unwrap(),
    );
    n
}

#[test]
fn khronos_validator_and_three_js_accept_every_preset_and_lod() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("glb-validate");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let n = write_all(&dir);
    assert!(n >= 8, "wrote {n} files");

    if std::env::var_os("PROCFIT_SKIP_NODE").is_some() {
        eprintln!("PROCFIT_SKIP_NODE set: wrote {n} GLBs to {dir:?}, validator not run");
        return;
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = Command::new("node")
        .arg(root.join("tests/gltf_validate.mjs"))
        .arg(&dir)
        .current_dir(root)
        .output()
        .expect("`node` must be installed to run the glTF validator (or set PROCFIT_SKIP_NODE=1)");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    println!("{stdout}");
    assert!(
        out.status.success(),
        "validator failed:\n{stderr}\n{stdout}"
    );
    assert!(
        stdout.contains(&format!("**{n} files**")),
        "validator did not see all {n} files:\n{stdout}"
    );

    // The same files through three.js's GLTFLoader: every part and camera found by name.
    let out = Command::new("node")
        .arg(root.join("tests/gltf_three.mjs"))
        .arg(&dir)
        .current_dir(root)
        .output()
        .expect("`node` must be installed");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    println!("{stdout}");
    assert!(
        out.status.success(),
        "three.js check failed:\n{stderr}\n{stdout}"
    );
    assert!(
        stdout.contains(&format!("{n} files")) && stdout.contains(" 0 failed"),
        "{stdout}"
    );
}
