//! Shared by the CLI tests (`tests/reconstruct_cli.rs`, `tests/tree_cli.rs`): run the `procfit`
//! binary, scratch paths under the target directory, and the two outcomes a test asserts — a
//! run that succeeds, and a failure with a one-line message.

#![allow(dead_code, reason = "each test binary uses a different subset")]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs `procfit` with `args`.
pub fn procfit(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_procfit"))
        .args(args)
        .output()
        .expect("procfit runs")
}

/// A path for `name` in the test's own scratch folder `dir`, under target/tmp (`cargo clean`
/// removes it), not the system temp dir.
pub fn scratch(dir: &str, name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir.join(name)
}

/// A path as an argument.
pub fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// Runs `procfit` and asserts it succeeds (showing its stderr if not); its stdout and stderr.
pub fn run_ok(args: &[&str]) -> (String, String) {
    let out = procfit(args);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(out.status.success(), "{args:?} failed: {err}");
    (String::from_utf8_lossy(&out.stdout).to_string(), err)
}

/// Runs `procfit` and asserts it fails with one line of stderr that contains `needle`.
pub fn fails_with(args: &[&str], needle: &str) {
    let out = procfit(args);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(!out.status.success(), "{args:?} should fail");
    assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
    assert!(err.contains(needle), "{args:?}: `{err}` lacks `{needle}`");
}
