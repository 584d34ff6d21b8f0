//! `procfit generate`: the CLI writes a GLB that imports back to the requested model, and bad
//! arguments end with a one-line message and a failure exit code.
#![allow(
    clippy::unwrap_used,
    clippy::expect_used,
    reason = "a test binary: a failed step should stop it loudly"
)]

use procfit::generators::{self, Lod};
use procfit::glb::import_glb;
use std::path::PathBuf;
use std::process::Command;

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

fn tmp(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("glb-cli");
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

#[test]
fn generate_writes_a_glb_that_imports_back_to_the_preset() {
    let g = generators::all()[0];
    let preset = g.presets().remove(0);
    let out = tmp("preset.glb");
    let path = out.to_str().unwrap();
    let (ok, text) = procfit(&[
        "generate",
        "--generator",
        g.name(),
        "--preset",
        preset.name,
        "--lod",
        "1",
        "--seed",
        "99",
        "-o",
        path,
    ]);
    assert!(ok, "{text}");
    let model = import_glb(&std::fs::read(&out).unwrap())
        .unwrap()
        .model()
        .unwrap();
    let want = generators::sanitize_params(g.params(), &preset.values).unwrap();
    assert_eq!(model.generator.name(), g.name());
    assert_eq!(model.params, want);
    assert_eq!((model.lod, model.seed), (Lod::Medium, Some(99)));

    // The params JSON of that model gives the same file.
    let json = tmp("params.json");
    std::fs::write(&json, model.to_json()).unwrap();
    let again = tmp("again.glb");
    let (ok, text) = procfit(&[
        "generate",
        "--generator",
        g.name(),
        "--params",
        json.to_str().unwrap(),
        "-o",
        again.to_str().unwrap(),
    ]);
    assert!(ok, "{text}");
    assert_eq!(std::fs::read(&again).unwrap(), std::fs::read(&out).unwrap());
}

#[test]
fn generate_rejects_bad_arguments_with_a_message() {
    let out = tmp("never.glb");
    let o = out.to_str().unwrap();
    let check = |args: &[&str], want: &str| {
        let (ok, text) = procfit(args);
        assert!(!ok && text.contains(want), "{args:?}: {text}");
    };
    let g = generators::all()[0].name();
    check(
        &["generate", "--generator", "nope", "-o", o],
        "unknown generator `nope`",
    );
    check(
        &["generate", "--generator", g, "--preset", "nope", "-o", o],
        "no preset `nope`",
    );
    check(
        &["generate", "--generator", g, "--lod", "4", "-o", o],
        "4 is not in 0..=3",
    );
    check(
        &[
            "generate",
            "--generator",
            g,
            "--params",
            "/nonexistent.json",
            "-o",
            o,
        ],
        "cannot read",
    );
    let json = tmp("other.json");
    std::fs::write(&json, r#"{"generator":"teapot","version":1,"params":{}}"#).unwrap();
    check(
        &[
            "generate",
            "--generator",
            g,
            "--params",
            json.to_str().unwrap(),
            "-o",
            o,
        ],
        "unknown generator `teapot`",
    );
    assert!(!out.exists());
}
