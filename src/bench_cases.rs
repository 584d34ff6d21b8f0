//! The case folders of the file-based benchmarks (the ez-tree trees, the Mitsuba dish photos):
//! one folder per case, known by its `camera.json`.

use std::path::{Path, PathBuf};

/// The case folders under `root` (those with a `camera.json`), sorted by name, only those named
/// in `names` when it is not empty; empty when `root` does not exist.
pub fn case_dirs(root: &Path, names: &[String]) -> Vec<PathBuf> {
    let mut dirs: Vec<_> = std::fs::read_dir(root)
        .into_iter()
        .flatten()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.join("camera.json").is_file())
        .filter(|p| {
            names.is_empty()
                || names
                    .iter()
                    .any(|n| p.file_name().is_some_and(|f| f == n.as_str()))
        })
        .collect();
    dirs.sort();
    dirs
}
