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
    /// The fit's runs ([`FitConfig::restarts`](crate::reconstruct::FitConfig)), `None` for
    /// what the page and the CLI make
    /// ([`FitConfig::restarts_for`](crate::reconstruct::FitConfig::restarts_for)).
    pub runs: Option<usize>,
    /// Buildings: whether a photo's fit also gets the window labels found in it
    /// ([`crate::segment::windows::detect_windows`]), as the page's "Find windows" gives them;
    /// by default the fit has the mask only, as the CLI without `--windows`.
    pub windows: bool,
}

impl BenchFit {
    /// The settings a benchmark's arguments ask for: `--quality Q` (as the CLI's `--quality`,
    /// [`check_quality`](crate::reconstruct::check_quality); `--quick` is 0.4; else 1),
    /// `--seed N` (else the fit's default seed, 0), `--runs N` (else the page's), `--each` and
    /// `--windows`.
    pub fn from_args(args: &[String]) -> Result<BenchFit, String> {
        let has = |flag: &str| args.iter().any(|a| a == flag);
        let number = |flag: &str| -> Result<Option<u64>, String> {
            let Some(k) = args.iter().position(|a| a == flag) else {
                return Ok(None);
            };
            let v = args.get(k + 1).ok_or(format!("{flag} needs a number"))?;
            v.parse()
                .map(Some)
                .map_err(|_| format!("{flag} takes a whole number ≥ 0, not '{v}'"))
        };
        let runs = match number("--runs")? {
            Some(0) => return Err("--runs takes a whole number ≥ 1, not '0'".into()),
            r => r.map(|r| usize::try_from(r).unwrap_or(usize::MAX)),
        };
        let quality = match args.iter().position(|a| a == "--quality") {
            Some(k) => {
                let v = args.get(k + 1).ok_or("--quality needs a number")?;
                match v.parse::<f64>() {
                    Ok(q) if crate::reconstruct::check_quality(q).is_ok() => q,
                    _ => {
                        let max = crate::reconstruct::MAX_QUALITY;
                        return Err(format!("--quality takes a number in (0, {max}], not '{v}'"));
                    }
                }
            }
            None if has("--quick") => 0.4,
            None => 1.0,
        };
        Ok(BenchFit {
            quality,
            seed: number("--seed")?.unwrap_or(0),
            each: has("--each"),
            runs,
            windows: has("--windows"),
        })
    }

    /// The runs of a fit of `generator` with these settings.
    pub fn runs_for(&self, generator: &str) -> usize {
        self.runs
            .unwrap_or_else(|| crate::reconstruct::FitConfig::restarts_for(generator, self.quality))
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
                each: false,
                runs: None,
                windows: false,
            }
        );
        let f = BenchFit::from_args(&args(&[
            "--quick",
            "--seed",
            "7",
            "--each",
            "--runs",
            "12",
            "--windows",
            "tower",
        ]))
        .unwrap();
        assert_eq!(
            f,
            BenchFit {
                quality: 0.4,
                seed: 7,
                each: true,
                runs: Some(12),
                windows: true,
            }
        );
        assert!(BenchFit::from_args(&args(&["--runs", "0"])).is_err());
        let q = BenchFit::from_args(&args(&["--quality", "2.5"])).unwrap();
        assert_eq!(q.quality, 2.5);
        for bad in ["0", "17", "NaN", "-1", "x"] {
            let e = BenchFit::from_args(&args(&["--quality", bad])).unwrap_err();
            assert!(e.contains(&format!("'{bad}'")), "{e}");
        }
        assert!(BenchFit::from_args(&args(&["--quality"])).is_err());
        assert!(BenchFit::from_args(&args(&["--seed"])).is_err());
        let e = BenchFit::from_args(&args(&["--seed", "-1"])).unwrap_err();
        assert!(e.contains("'-1'"), "{e}");
    }
}
