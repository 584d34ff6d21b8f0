//! `procfit`, the native command line: the same core as the page, for batch work and tests.
//!
//! Every subcommand has `--help`; bad input ends with a one-line message on stderr and a
//! non-zero exit code.

use clap::{Parser, Subcommand};
use procfit::generators::Lod;
use procfit::model::Model;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

mod format_cli;
mod outputs;
mod recon_cli;
mod segment_cli;

#[derive(Parser)]
#[command(
    name = "procfit",
    version,
    about = "Photo to editable procedural 3D model"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// List the generators, their parameters and presets.
    Generators {
        /// Only this generator.
        name: Option<String>,
    },
    /// Write a generator's mesh as a GLB (glTF 2.0) with its parameters in the scene extras, so
    /// that procfit can open it again for editing; or as OBJ + MTL or binary STL (mesh only).
    Generate {
        /// Generator machine name (see `procfit generators`).
        #[arg(long)]
        generator: String,
        /// Start from this preset instead of the defaults.
        #[arg(long, conflicts_with = "params")]
        preset: Option<String>,
        /// Start from this params JSON (its `generator` must match).
        #[arg(long)]
        params: Option<PathBuf>,
        /// Level of detail 0..=3; default: the params file's, else 3 (the export level).
        #[arg(long, value_parser = clap::value_parser!(u8).range(0..=3))]
        lod: Option<u8>,
        /// Seed recorded in the file; default: the params file's, else none.
        #[arg(long)]
        seed: Option<u64>,
        /// Output path: .glb, .obj (+ .mtl beside it) or .stl.
        #[arg(short, long)]
        output: PathBuf,
        /// Output format (default: from the output's extension).
        #[arg(long, value_parser = ["glb", "obj", "stl"])]
        format: Option<String>,
        /// GLB only: quantised attributes (KHR_mesh_quantization), about half the size.
        #[arg(long)]
        compact: bool,
    },
    /// Recompute the tree generator's Algorithm 3 mutation statistics (src/tree/mutation_stats.json).
    TreeStats {
        /// Where to write the JSON (default: print to stdout).
        #[arg(long)]
        out: Option<std::path::PathBuf>,
    },
    /// Fit a generator to one or more photos (or mask images) of an object and write the model
    /// as a GLB with one camera per image.
    Reconstruct(recon_cli::ReconstructArgs),
    /// Render a generator's silhouette through a camera to a mask PNG.
    Render(recon_cli::RenderArgs),
    /// Write the automatic mask a fit would use (and a building's windows, a tree's labels),
    /// with its confidence, to see and correct before `reconstruct`.
    Segment(segment_cli::SegmentArgs),
    /// IoU over 64 turntable views between a model GLB and a reference mesh (OBJ or GLB).
    Eval(recon_cli::EvalArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Generators { name } => list_generators(name.as_deref()),
        Command::Generate {
            generator,
            preset,
            params,
            lod,
            seed,
            output,
            format,
            compact,
        } => generate(
            &generator,
            preset.as_deref(),
            params.as_deref(),
            lod,
            seed,
            (&output, format.as_deref(), compact),
        ),
        Command::TreeStats { out } => tree_stats(out.as_deref()),
        Command::Reconstruct(args) => recon_cli::reconstruct(&args),
        Command::Render(args) => recon_cli::render(&args),
        Command::Eval(args) => recon_cli::eval(&args),
        Command::Segment(args) => segment_cli::segment(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(message) => {
            eprintln!("procfit: {message}");
            ExitCode::FAILURE
        }
    }
}

fn list_generators(only: Option<&str>) -> Result<(), String> {
    let all = procfit::generators::all();
    let chosen: Vec<_> = all
        .iter()
        .filter(|g| only.is_none_or(|n| g.name() == n))
        .collect();
    if chosen.is_empty() {
        return Err(match only {
            Some(n) => format!("unknown generator `{n}`"),
            None => "no generators built in".into(),
        });
    }
    for g in chosen {
        println!("{} — {} (version {})", g.name(), g.label(), g.version());
        for p in g.params() {
            println!(
                "  {:<28} {:<10} [{}, {}] {:?}",
                p.name, p.group, p.min, p.max, p.kind
            );
        }
        let presets: Vec<_> = g.presets().iter().map(|p| p.name).collect();
        println!("  presets: {}", presets.join(", "));
    }
    Ok(())
}

fn generate(
    generator: &str,
    preset: Option<&str>,
    params: Option<&Path>,
    lod: Option<u8>,
    seed: Option<u64>,
    (output, format, compact): (&Path, Option<&str>, bool),
) -> Result<(), String> {
    let target = format_cli::Target::new(output, format, compact);
    let mut plan = format_cli::Target::declare_any(&target, output, outputs::Outputs::new());
    if let Some(p) = params {
        plan = plan.input(p);
    }
    plan.check()?;
    let target = target.as_ref().map_err(Clone::clone)?;
    let g = procfit::generators::by_name(generator)
        .ok_or_else(|| format!("unknown generator `{generator}` (see `procfit generators`)"))?;
    let mut model = match (preset, params) {
        (Some(name), _) => {
            let p = g.preset(name).ok_or_else(|| {
                let names: Vec<_> = g.presets().iter().map(|p| p.name).collect();
                format!(
                    "{generator} has no preset `{name}` (presets: {})",
                    names.join(", ")
                )
            })?;
            Model::new(generator, &p.values, Lod::Ultra).map_err(|e| e.to_string())?
        }
        (None, Some(path)) => {
            let (m, doc) = recon_cli::load_params(path, generator)?;
            // A params file without a lod gets the export level, like the other sources.
            Model {
                lod: if doc.lod.is_some() { m.lod } else { Lod::Ultra },
                ..m
            }
        }
        (None, None) => {
            Model::new(generator, &g.defaults(), Lod::Ultra).map_err(|e| e.to_string())?
        }
    };
    if let Some(i) = lod {
        model.lod =
            Lod::from_index(usize::from(i)).ok_or_else(|| format!("lod {i} is not in 0..=3"))?;
    }
    if seed.is_some() {
        model.seed = seed;
    }
    let summary = target.write(&model, &[])?;
    println!(
        "wrote {}: {}{} lod {}, {summary}",
        target.path.display(),
        model.generator.name(),
        preset.map(|p| format!(" {p}")).unwrap_or_default(),
        model.lod.index(),
    );
    Ok(())
}

fn tree_stats(out: Option<&std::path::Path>) -> Result<(), String> {
    if let Some(path) = out {
        outputs::Outputs::new().output("--out", path).check()?;
    }
    let stats = procfit::tree::mutation::tree_stats().map_err(|e| e.to_string())?;
    let text = stats.to_json() + "\n";
    write_or_print(out, &text)
}

/// Writes `text` to `out`, or to stdout when no path is given.
fn write_or_print(out: Option<&std::path::Path>, text: &str) -> Result<(), String> {
    match out {
        Some(path) => outputs::write_atomic(path, text.as_bytes()),
        None => {
            print!("{text}");
            Ok(())
        }
    }
}
