//! OBJ + MTL and binary STL export (issue 17): a dish's STL is watertight, read back as a
//! triangle soup; a tree's is not, and the CLI says so; the OBJ parses back to the mesh and
//! references its MTL, which the CLI checks and writes like any output; the CLI picks the
//! format from `--format` or the extension and counts only parts that have triangles.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "a test binary: a failed step should stop it loudly"
)]

use procfit::export::{self, ExportOptions, Format, open_edges, write_mesh, write_obj, write_stl};
use procfit::generators::{self, Lod, Mesh};
use procfit::glb::import_obj;
use procfit::model::Model;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;

fn tmp(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("export");
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn procfit(args: &[&str]) -> (bool, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_procfit"))
        .args(args)
        .output()
        .unwrap();
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    (out.status.success(), text)
}

fn mesh_of(generator: &str, preset: &str, lod: Lod) -> Mesh {
    let g = generators::by_name(generator).unwrap();
    let values = g.preset(preset).unwrap().values;
    g.generate(&values, lod).unwrap()
}

/// Reads a binary STL as triangles of corner positions.
fn read_stl(bytes: &[u8]) -> Vec<[[f32; 3]; 3]> {
    assert!(
        !bytes.starts_with(b"solid"),
        "a binary STL header starting with `solid`"
    );
    let count = u32::from_le_bytes(bytes[80..84].try_into().unwrap()) as usize;
    assert_eq!(
        bytes.len(),
        84 + 50 * count,
        "STL length for {count} triangles"
    );
    let f = |at: usize| f32::from_le_bytes(bytes[at..at + 4].try_into().unwrap());
    (0..count)
        .map(|t| {
            let at = 84 + 50 * t + 12;
            [0, 1, 2].map(|k| [0, 1, 2].map(|c| f(at + 12 * k + 4 * c)))
        })
        .collect()
}

/// Edges of a triangle soup (vertices equal by exact position) not used by exactly two
/// triangles, and edges used twice in the same direction (a flipped triangle).
fn soup_defects(tris: &[[[f32; 3]; 3]]) -> (usize, usize) {
    let mut uses: HashMap<([u32; 3], [u32; 3]), i32> = HashMap::new();
    let mut count: HashMap<([u32; 3], [u32; 3]), u32> = HashMap::new();
    for t in tris {
        let v = t.map(|p| p.map(f32::to_bits));
        for k in 0..3 {
            let (a, b) = (v[k], v[(k + 1) % 3]);
            let key = if a < b { (a, b) } else { (b, a) };
            *count.entry(key).or_default() += 1;
            *uses.entry(key).or_default() += if a < b { 1 } else { -1 };
        }
    }
    let open = count.values().filter(|&&n| n != 2).count();
    let flipped = uses.values().filter(|&&d| d != 0).count();
    (open, flipped)
}

#[test]
fn every_dish_stl_is_watertight_and_consistently_wound() {
    let g = generators::by_name("dish").unwrap();
    for preset in g.presets() {
        for lod in [Lod::Low, Lod::Ultra] {
            let mesh = g.generate(&preset.values, lod).unwrap();
            let tris = read_stl(&write_stl(&mesh, "dish").unwrap());
            assert_eq!(tris.len(), mesh.triangles.len());
            let (open, flipped) = soup_defects(&tris);
            let what = format!("dish {} lod {}", preset.name, lod.index());
            assert_eq!(open, 0, "{what}: {open} edges not shared by two triangles");
            assert_eq!(
                flipped, 0,
                "{what}: {flipped} edges wound the same way twice"
            );
            assert_eq!(open_edges(&mesh), 0, "{what}: open_edges disagrees");
        }
    }
}

#[test]
fn a_tree_is_not_watertight_and_open_edges_says_so() {
    let mesh = mesh_of("tree", "oak", Lod::Low);
    let tris = read_stl(&write_stl(&mesh, "tree").unwrap());
    let (open, _) = soup_defects(&tris);
    assert!(
        open > 0,
        "leaf cards have no thickness: their diagonals are used four times"
    );
    assert_eq!(
        open_edges(&mesh),
        open,
        "open_edges counts what an STL reader sees"
    );
}

#[test]
fn obj_parses_back_to_the_mesh_and_references_its_mtl() {
    for (generator, preset) in [("dish", "mug"), ("building", "townhouse_row")] {
        let mesh = mesh_of(generator, preset, Lod::High);
        let (obj, mtl) = write_obj(&mesh, generator, "model.mtl").unwrap();
        let back = import_obj(&obj).unwrap();
        assert_eq!(back.positions.len(), mesh.positions.len(), "{generator}");
        // Faces come grouped by part: the same faces with the same winding, in another order.
        let mut want = mesh.triangles.clone();
        let mut got = back.triangles.clone();
        want.sort_unstable();
        got.sort_unstable();
        assert!(
            got == want,
            "{generator}: the OBJ's faces differ from the mesh's"
        );
        for (a, b) in back.positions.iter().zip(&mesh.positions) {
            assert!(
                (*a - *b).abs().max_element() < 1e-6,
                "{generator}: {a} vs {b}"
            );
        }
        let obj = String::from_utf8(obj).unwrap();
        let mtl = String::from_utf8(mtl).unwrap();
        assert!(obj.lines().any(|l| l == "mtllib model.mtl"), "{generator}");
        let used: Vec<&str> = obj
            .lines()
            .filter_map(|l| l.strip_prefix("usemtl "))
            .collect();
        let defined: Vec<&str> = mtl
            .lines()
            .filter_map(|l| l.strip_prefix("newmtl "))
            .collect();
        assert_eq!(
            used, defined,
            "{generator}: one material per non-empty part"
        );
        // Exactly the parts that have triangles, each with its own colour.
        let nonempty = export::nonempty_parts(&mesh);
        assert_eq!(used.len(), nonempty, "{generator}");
        for part in mesh.parts.iter().filter(|p| used.contains(&p.name)) {
            let at = mtl.find(&format!("newmtl {}\n", part.name)).unwrap();
            let kd = mtl[at..]
                .lines()
                .find_map(|l| l.strip_prefix("Kd "))
                .unwrap();
            let kd: Vec<f32> = kd.split(' ').map(|x| x.parse().unwrap()).collect();
            for c in 0..3 {
                assert!(
                    (kd[c] - part.color[c]).abs() < 1e-6,
                    "{}: Kd {kd:?}",
                    part.name
                );
            }
        }
        // Texture coordinates flipped to OBJ's bottom-left origin.
        let first_vt = obj.lines().find_map(|l| l.strip_prefix("vt ")).unwrap();
        let vt: Vec<f32> = first_vt.split(' ').map(|x| x.parse().unwrap()).collect();
        let uv = mesh.corner_uvs[0];
        assert!((vt[0] - uv.x).abs() < 1e-6 && (vt[1] - (1.0 - uv.y)).abs() < 1e-6);
    }
}

#[test]
fn write_mesh_refuses_compact_for_other_formats() {
    let mesh = mesh_of("dish", "mug", Lod::Low);
    let compact = ExportOptions { compact: true };
    let err = write_mesh(&mesh, None, &[], Format::Stl, compact, Path::new("a.stl")).unwrap_err();
    assert!(err.to_string().contains("compact"), "{err}");
    let ok = write_mesh(&mesh, None, &[], Format::Glb, compact, Path::new("a.glb")).unwrap();
    assert!(ok.main.starts_with(b"glTF") && ok.companion.is_none());
}

#[test]
fn cli_writes_obj_with_its_mtl_and_stl_by_extension_or_format() {
    let obj = tmp("mug.obj");
    let mtl = tmp("mug.mtl");
    let _ = std::fs::remove_file(&mtl);
    let (ok, text) = procfit(&[
        "generate",
        "--generator",
        "dish",
        "--preset",
        "mug",
        "--lod",
        "1",
        "-o",
        obj.to_str().unwrap(),
    ]);
    assert!(ok, "{text}");
    assert!(
        text.contains("watertight") && !text.contains("not watertight"),
        "{text}"
    );
    let back = import_obj(&std::fs::read(&obj).unwrap()).unwrap();
    let model = Model::new(
        "dish",
        &generators::by_name("dish")
            .unwrap()
            .preset("mug")
            .unwrap()
            .values,
        Lod::Medium,
    )
    .unwrap();
    let mesh = model.generator.generate(&model.params, model.lod).unwrap();
    assert_eq!(back.triangles.len(), mesh.triangles.len());
    let mtl_text = std::fs::read_to_string(&mtl).unwrap();
    assert!(mtl_text.contains("newmtl body"), "{mtl_text}");

    // `--format` without an extension; the byte count printed is the file's.
    let stl = tmp("mug-printable");
    let (ok, text) = procfit(&[
        "generate",
        "--generator",
        "dish",
        "--preset",
        "mug",
        "--format",
        "stl",
        "-o",
        stl.to_str().unwrap(),
    ]);
    assert!(ok, "{text}");
    let bytes = std::fs::read(&stl).unwrap();
    assert!(text.contains(&format!("{} bytes", bytes.len())), "{text}");
    assert_eq!(soup_defects(&read_stl(&bytes)).0, 0);

    // A tree's STL is written, with the reason it is not watertight.
    let tree = tmp("oak.stl");
    let (ok, text) = procfit(&[
        "generate",
        "--generator",
        "tree",
        "--preset",
        "oak",
        "--lod",
        "0",
        "-o",
        tree.to_str().unwrap(),
    ]);
    assert!(ok, "{text}");
    assert!(
        text.contains("not watertight") && text.contains("leaf cards have no thickness"),
        "{text}"
    );
}

#[test]
fn cli_refuses_unclear_formats_and_checks_the_mtl_before_work() {
    let check = |args: &[&str], want: &str| {
        let (ok, text) = procfit(args);
        assert!(!ok, "{args:?} succeeded: {text}");
        assert!(text.contains(want), "{args:?}: {text}");
        assert_eq!(text.trim().lines().count(), 1, "one line: {text}");
    };
    let glb = tmp("x.glb");
    let glb = glb.to_str().unwrap();
    check(
        &[
            "generate",
            "--generator",
            "dish",
            "--format",
            "stl",
            "-o",
            glb,
        ],
        "make them agree",
    );
    let bare = tmp("noext");
    check(
        &[
            "generate",
            "--generator",
            "dish",
            "-o",
            bare.to_str().unwrap(),
        ],
        "--format glb|obj|stl",
    );
    let stl = tmp("x.stl");
    check(
        &[
            "generate",
            "--generator",
            "dish",
            "--compact",
            "-o",
            stl.to_str().unwrap(),
        ],
        "--compact is for GLB",
    );
    // The OBJ's material file would overwrite the params input: refused before any work.
    let params = tmp("state.mtl");
    let model = Model::new(
        "dish",
        &generators::by_name("dish").unwrap().defaults(),
        Lod::Low,
    )
    .unwrap();
    std::fs::write(&params, model.to_json()).unwrap();
    let before = std::fs::read(&params).unwrap();
    let out = tmp("state.obj");
    let _ = std::fs::remove_file(&out);
    check(
        &[
            "generate",
            "--generator",
            "dish",
            "--params",
            params.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
        ],
        "is an input",
    );
    assert_eq!(
        std::fs::read(&params).unwrap(),
        before,
        "the input is untouched"
    );
    assert!(!out.exists(), "nothing written when the check fails");
}

#[test]
fn cli_parts_count_only_parts_with_triangles() {
    // The dish's handle and saucer parts are empty for a bare bowl; the line must not count
    // them.
    let bowl = mesh_of("dish", "bowl", Lod::Low);
    assert_eq!(
        export::nonempty_parts(&bowl),
        bowl.parts.len() - 2,
        "the bowl has no handle and no saucer"
    );
    let g = generators::by_name("dish").unwrap();
    for preset in g.presets() {
        let mesh = g.generate(&preset.values, Lod::Low).unwrap();
        let out = tmp(&format!("parts-{}.glb", preset.name));
        let (ok, text) = procfit(&[
            "generate",
            "--generator",
            "dish",
            "--preset",
            preset.name,
            "--lod",
            "0",
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(ok, "{text}");
        let want = export::nonempty_parts(&mesh);
        let plural = if want == 1 { "" } else { "s" };
        assert!(
            text.contains(&format!("in {want} part{plural},")),
            "{}: {want} non-empty of {} parts: {text}",
            preset.name,
            mesh.parts.len()
        );
    }
}
