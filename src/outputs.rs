//! The CLI's output files: checked before any work starts, written atomically.
//!
//! A command names its inputs and outputs once ([`Outputs::check`]); that refuses, in one line,
//! an output that is one of the inputs (by path, or by device and inode where the platform has
//! them, so `./a.jpg` and `a.jpg` or a hard link are caught), two outputs that share a path, and
//! an output whose folder is missing, is not a folder or cannot be written — all before the
//! fit, so a typo does not cost a minute of fitting. [`write_atomic`] writes a temporary file
//! beside the target and renames it over, so an interrupted or failed write never leaves half a
//! file where the old one was.

use std::io::Write;
use std::path::{Path, PathBuf};

/// The paths a command reads and writes.
#[derive(Default)]
pub struct Outputs<'a> {
    inputs: Vec<&'a Path>,
    outputs: Vec<(&'a str, &'a Path)>,
}

impl<'a> Outputs<'a> {
    /// Starts an empty plan.
    pub fn new() -> Self {
        Self::default()
    }

    /// A file the command reads.
    pub fn input(mut self, path: &'a Path) -> Self {
        self.inputs.push(path);
        self
    }

    /// Files the command reads.
    pub fn inputs(mut self, paths: impl IntoIterator<Item = &'a PathBuf>) -> Self {
        self.inputs.extend(paths.into_iter().map(PathBuf::as_path));
        self
    }

    /// A file the command writes; `what` names it in messages (`-o`, `--params-out`).
    pub fn output(mut self, what: &'a str, path: &'a Path) -> Self {
        self.outputs.push((what, path));
        self
    }

    /// Checks the plan: one line naming the first problem found.
    pub fn check(&self) -> Result<(), String> {
        for (i, &(what, out)) in self.outputs.iter().enumerate() {
            if let Some(&input) = self.inputs.iter().find(|&&input| same_file(input, out)) {
                return Err(format!(
                    "{what} {} is an input of this command ({}): procfit never overwrites its inputs, choose another output path",
                    out.display(),
                    input.display()
                ));
            }
            if let Some(&(other, _)) = self.outputs[..i]
                .iter()
                .find(|&&(_, earlier)| same_file(earlier, out))
            {
                return Err(format!(
                    "{other} and {what} are the same file ({}): give them different paths",
                    out.display()
                ));
            }
            check_writable(what, out)?;
        }
        Ok(())
    }
}

/// Whether two paths name the same file: the same file on disk when both exist, else the same
/// absolute path once the folder is resolved.
fn same_file(a: &Path, b: &Path) -> bool {
    if let (Ok(ma), Ok(mb)) = (std::fs::metadata(a), std::fs::metadata(b)) {
        #[cfg(unix)]
        {
            use std::os::unix::fs::MetadataExt;
            return ma.dev() == mb.dev() && ma.ino() == mb.ino();
        }
        #[cfg(not(unix))]
        {
            let _ = (ma, mb);
        }
    }
    match (resolved(a), resolved(b)) {
        (Some(a), Some(b)) => a == b,
        _ => a == b,
    }
}

/// `path` with its folder made absolute and symlink-free (the file itself may not exist yet).
fn resolved(path: &Path) -> Option<PathBuf> {
    if let Ok(p) = std::fs::canonicalize(path) {
        return Some(p);
    }
    let name = path.file_name()?;
    let parent = parent_of(path);
    Some(std::fs::canonicalize(parent).ok()?.join(name))
}

/// The folder a path's file lives in (`.` for a bare file name).
fn parent_of(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// The output's folder exists, is a folder, and a file can be created in it; the output itself,
/// if it exists, is a regular file.
fn check_writable(what: &str, out: &Path) -> Result<(), String> {
    if out.file_name().is_none() {
        return Err(format!("{what} {} is not a file path", out.display()));
    }
    if let Ok(m) = std::fs::metadata(out)
        && !m.is_file()
    {
        return Err(format!("{what} {} exists and is not a file", out.display()));
    }
    let dir = parent_of(out);
    match std::fs::metadata(dir) {
        Err(_) => {
            return Err(format!(
                "{what} {}: the folder {} does not exist",
                out.display(),
                dir.display()
            ));
        }
        Ok(m) if !m.is_dir() => {
            return Err(format!(
                "{what} {}: {} is not a folder",
                out.display(),
                dir.display()
            ));
        }
        Ok(_) => {}
    }
    // Permissions bits lie (root, ACLs, read-only mounts): try it.
    let probe = temp_path(out);
    match std::fs::File::create(&probe) {
        Ok(_) => {
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        Err(e) => Err(format!(
            "{what} {}: cannot write in {} ({e})",
            out.display(),
            dir.display()
        )),
    }
}

/// A temporary file beside `out`, unique to this process.
fn temp_path(out: &Path) -> PathBuf {
    let name = out
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    parent_of(out).join(format!(".{name}.procfit-{}.tmp", std::process::id()))
}

/// Writes `bytes` to `path` atomically: a temporary file beside it, flushed to disk, then
/// renamed over it. On failure the old file (if any) is untouched and the temporary is removed.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), String> {
    let tmp = temp_path(path);
    let written = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    written.map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        format!("cannot write {}: {e}", path.display())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("procfit-outputs-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&d).expect("scratch dir");
        d
    }

    #[test]
    fn an_input_is_never_an_output_even_by_another_name() {
        let d = dir("input");
        let photo = d.join("a.jpg");
        std::fs::write(&photo, b"x").expect("write");
        let other_name = d.join(".").join("a.jpg");
        let err = Outputs::new()
            .input(&photo)
            .output("-o", &other_name)
            .check()
            .unwrap_err();
        assert!(err.contains("is an input"), "{err}");
        #[cfg(unix)]
        {
            let link = d.join("b.jpg");
            let _ = std::fs::remove_file(&link);
            std::fs::hard_link(&photo, &link).expect("hard link");
            let err = Outputs::new()
                .input(&photo)
                .output("-o", &link)
                .check()
                .unwrap_err();
            assert!(err.contains("is an input"), "{err}");
        }
    }

    #[test]
    fn two_outputs_never_share_a_path() {
        let d = dir("twice");
        let a = d.join("x.glb");
        let b = d.join("./x.glb");
        let err = Outputs::new()
            .output("-o", &a)
            .output("--params-out", &b)
            .check()
            .unwrap_err();
        assert!(err.contains("-o and --params-out"), "{err}");
    }

    #[test]
    fn a_missing_folder_is_refused_and_an_existing_one_accepted() {
        let d = dir("folder");
        let missing = d.join("nope").join("x.glb");
        let err = Outputs::new().output("-o", &missing).check().unwrap_err();
        assert!(err.contains("does not exist"), "{err}");
        let ok = d.join("x.glb");
        Outputs::new().output("-o", &ok).check().expect("writable");
        assert!(!ok.exists(), "the check leaves nothing behind");
        assert_eq!(std::fs::read_dir(&d).expect("list").count(), 0);
    }

    #[test]
    fn atomic_write_replaces_and_leaves_no_temporary() {
        let d = dir("atomic");
        let p = d.join("out.json");
        write_atomic(&p, b"one").expect("write");
        write_atomic(&p, b"two").expect("rewrite");
        assert_eq!(std::fs::read(&p).expect("read"), b"two");
        assert_eq!(std::fs::read_dir(&d).expect("list").count(), 1);
        let err = write_atomic(&d.join("no").join("x"), b"x").unwrap_err();
        assert!(err.starts_with("cannot write"), "{err}");
    }
}
