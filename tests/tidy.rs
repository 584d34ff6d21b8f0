//! Tidy checks: the invariants ARCHITECTURE.md states as absences, enforced over the source tree
//! (after rust-analyzer's tidy test). Each check names the files that break it.

use std::fs;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Every `.rs` file under `dir`, skipping build output.
fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let Ok(entries) = fs::read_dir(dir) else {
        return out;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        let name = entry.file_name();
        if name == "target" || name == "node_modules" || name == "pkg" {
            continue;
        }
        if path.is_dir() {
            out.extend(rust_files(&path));
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
    out.sort();
    out
}

fn source_dirs() -> Vec<PathBuf> {
    ["src", "generators", "tests", "benches", "fuzz/fuzz_targets"]
        .iter()
        .map(|d| root().join(d))
        .collect()
}

fn read(path: &Path) -> String {
    fs::read_to_string(path).unwrap_or_default()
}

fn rel(path: &Path) -> String {
    path.strip_prefix(root())
        .unwrap_or(path)
        .display()
        .to_string()
}

/// Lines of `text` that are code (not comments), trimmed.
fn code_lines(text: &str) -> impl Iterator<Item = &str> {
    text.lines()
        .map(str::trim)
        .filter(|l| !l.starts_with("//") && !l.starts_with("*") && !l.starts_with("/*"))
}

#[test]
fn every_rust_file_opens_with_a_module_doc() {
    let offenders: Vec<String> = source_dirs()
        .iter()
        .flat_map(|d| rust_files(d))
        .filter(|p| !read(p).trim_start().starts_with("//!"))
        .map(|p| rel(&p))
        .collect();
    assert!(
        offenders.is_empty(),
        "files without a leading //! doc: {offenders:#?}"
    );
}

#[test]
fn only_src_web_talks_to_javascript() {
    let web = root().join("src").join("web");
    let offenders: Vec<String> = source_dirs()
        .iter()
        .flat_map(|d| rust_files(d))
        .filter(|p| !p.starts_with(&web))
        .filter(|p| {
            code_lines(&read(p)).any(|l| {
                ["wasm_bindgen", "web_sys", "js_sys", "serde_wasm_bindgen"]
                    .iter()
                    .any(|c| l.contains(&format!("{c}::")) || l.contains(&format!("use {c}")))
            })
        })
        .map(|p| rel(&p))
        .collect();
    assert!(
        offenders.is_empty(),
        "JS bindings outside src/web/: {offenders:#?}"
    );
}

#[test]
fn library_code_never_reads_the_clock() {
    // `std::time::Instant::now()` panics on wasm32-unknown-unknown; timing belongs to benchmarks,
    // tests, the CLI and the JS side.
    let lib_dirs = [root().join("src"), root().join("generators").join("src")];
    // The CLI binary may time things: `src/main.rs` and the modules it declares itself.
    let main_rs = root().join("src").join("main.rs");
    let mut allowed = vec![main_rs.clone()];
    for line in code_lines(&read(&main_rs)) {
        if let Some(name) = line.strip_prefix("mod ").and_then(|l| l.strip_suffix(';')) {
            allowed.push(root().join("src").join(format!("{name}.rs")));
            allowed.push(root().join("src").join(name));
        }
    }
    let offenders: Vec<String> = lib_dirs
        .iter()
        .flat_map(|d| rust_files(d))
        .filter(|p| !allowed.iter().any(|a| p.starts_with(a)))
        .filter(|p| {
            let text = read(p);
            // Test modules may time things; only non-test code counts.
            let code = text.split("#[cfg(test)]").next().unwrap_or("");
            code_lines(code).any(|l| l.contains("Instant::now") || l.contains("SystemTime::now"))
        })
        .map(|p| rel(&p))
        .collect();
    assert!(
        offenders.is_empty(),
        "library code reading the clock: {offenders:#?}"
    );
}

#[test]
fn the_web_edge_denies_unwrap() {
    let text = read(&root().join("src").join("web").join("mod.rs"));
    assert!(
        text.contains("#![deny(clippy::unwrap_used, clippy::expect_used)]"),
        "src/web/mod.rs must deny unwrap and expect"
    );
}

#[test]
fn no_unlicensed_paper_data_in_the_repository() {
    // ../shared/data/paper/ carries no licence: its files must never be copied in. Their names
    // are distinctive; their contents start with the authors' block format.
    let markers = [
        "building_test_2",
        "dishes_gen_presets",
        "buildings_2_gen",
        "ge_gen_param_borders",
    ];
    let mut offenders = Vec::new();
    let mut stack = vec![root()];
    while let Some(dir) = stack.pop() {
        let Ok(entries) = fs::read_dir(&dir) else {
            continue;
        };
        for entry in entries.flatten() {
            let path = entry.path();
            let name = entry.file_name().to_string_lossy().to_string();
            if [
                ".git",
                "target",
                "node_modules",
                "pkg",
                "pkg-st",
                "dist",
                "test-artifacts",
            ]
            .contains(&name.as_str())
            {
                continue;
            }
            if path.is_dir() {
                stack.push(path);
            } else if name.ends_with(".blk") || markers.iter().any(|m| name.contains(m)) {
                offenders.push(rel(&path));
            }
        }
    }
    assert!(
        offenders.is_empty(),
        "files that look like the unlicensed paper data: {offenders:#?}"
    );
}

/// Files under `dir` (recursively) whose name ends with one of `exts`, skipping build output.
fn files_with(dir: &Path, exts: &[&str]) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let Ok(entries) = fs::read_dir(dir) else {
        return out;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        let name = entry.file_name().to_string_lossy().to_string();
        if ["target", "node_modules", "pkg", "pkg-st", "samples"].contains(&name.as_str()) {
            continue;
        }
        if path.is_dir() {
            out.extend(files_with(&path, exts));
        } else if exts.iter().any(|e| name.ends_with(e)) {
            out.push(path);
        }
    }
    out.sort();
    out
}

#[test]
fn no_generator_name_outside_registration() {
    // What a generator can do is data in its spec (`Generator::capabilities`); the CLI, the
    // worker and the page read that and never check a generator's name. A name may appear as a
    // string literal only in the generators crate (its own file and `all()`), in tests, in
    // comments, and in these files, each for the reason given.
    let allowed: &[(&str, &str)] = &[
        (
            "src/tree/bench.rs",
            "`\"tree\"` names the part of the ez-tree benchmark's reference mesh",
        ),
        (
            "www/bench-worker.js",
            "the wasm benchmark's fixed workloads, (generator, preset) pairs like benches/",
        ),
    ];
    let names: Vec<&str> = procfit::generators::all()
        .iter()
        .map(|g| g.name())
        .collect();
    assert!(names.len() >= 3, "{names:?}");
    let mut files = files_with(&root().join("src"), &[".rs"]);
    files.extend(files_with(&root().join("www"), &[".js"]));
    files.push(root().join("index.html"));
    let mut offenders = Vec::new();
    for path in files {
        let r = rel(&path);
        if allowed.iter().any(|(a, _)| *a == r) {
            continue;
        }
        let text = read(&path);
        // Unit tests may name generators; only the code before them counts.
        let code = text.split("#[cfg(test)]").next().unwrap_or("");
        for line in code_lines(code) {
            for n in &names {
                let quoted = [format!("\"{n}\""), format!("'{n}'"), format!("`{n}`")];
                if quoted.iter().any(|q| line.contains(q.as_str())) {
                    offenders.push(format!("{r}: {line}"));
                }
            }
        }
    }
    assert!(
        offenders.is_empty(),
        "generator names outside registration (use the spec's capabilities): {offenders:#?}"
    );
}
