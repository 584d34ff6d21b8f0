//! What the benchmarks share: the case folders of the file-based ones (the ez-tree trees, the
//! Mitsuba dish photos: one folder per case, known by its `camera.json`), and how the fitting
//! benchmarks fit ([`BenchFit`], read from their command line).

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

/// How a fitting benchmark fits each case.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BenchFit {
    /// Scales every stage's budget ([`FitConfig::quality`](crate::reconstruct::FitConfig)).
    pub quality: f64,
    /// The fit's seed ([`FitConfig::seed`](crate::reconstruct::FitConfig)). A benchmark's mean
    /// IoU-64 moves by about 0.015–0.02 from one seed to another, so a change is judged over
    /// several.
    pub seed: u64,
    /// Whether every run of each fit is scored, not only the kept one.
    pub each: bool,
}

impl BenchFit {
    /// The settings a benchmark's arguments ask for: `--quick` (quality 0.4, else 1),
    /// `--seed N` (else the fit's default seed, 0) and `--each`.
    pub fn from_args(args: &[String]) -> Result<BenchFit, String> {
        let has = |flag: &str| args.iter().any(|a| a == flag);
        let seed = match args.iter().position(|a| a == "--seed") {
            None => 0,
            Some(k) => {
                let v = args.get(k + 1).ok_or("--seed needs a number")?;
                v.parse()
                    .map_err(|_| format!("--seed takes a whole number ≥ 0, not '{v}'"))?
            }
        };
        Ok(BenchFit {
            quality: if has("--quick") { 0.4 } else { 1.0 },
            seed,
            each: has("--each"),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::BenchFit;

    fn args(a: &[&str]) -> Vec<String> {
        a.iter().map(|s| s.to_string()).collect()
    }

    #[test]
    fn bench_settings_come_from_the_arguments() {
        let d = BenchFit::from_args(&args(&["--bench"])).unwrap();
        assert_eq!(
            d,
            BenchFit {
                quality: 1.0,
                seed: 0,
                each: false
            }
        );
        let f = BenchFit::from_args(&args(&["--quick", "--seed", "7", "--each", "tower"])).unwrap();
        assert_eq!(
            f,
            BenchFit {
                quality: 0.4,
                seed: 7,
                each: true
            }
        );
        assert!(BenchFit::from_args(&args(&["--seed"])).is_err());
        let e = BenchFit::from_args(&args(&["--seed", "-1"])).unwrap_err();
        assert!(e.contains("'-1'"), "{e}");
    }
}
