//! `procfit`, the native command line: the same core as the page, for batch work and tests.
//!
//! Every subcommand has `--help`; bad input ends with a one-line message on stderr and a
//! non-zero exit code.

use clap::{Parser, Subcommand};
use std::process::ExitCode;

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
    /// Recompute the tree generator's Algorithm 3 mutation statistics (src/tree/mutation_stats.json).
    TreeStats {
        /// Where to write the JSON (default: print to stdout).
        #[arg(long)]
        out: Option<std::path::PathBuf>,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Generators { name } => list_generators(name.as_deref()),
        Command::TreeStats { out } => tree_stats(out.as_deref()),
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

fn tree_stats(out: Option<&std::path::Path>) -> Result<(), String> {
    let stats = procfit::tree::mutation::tree_stats().map_err(|e| e.to_string())?;
    let text = stats.to_json() + "\n";
    match out {
        Some(path) => {
            std::fs::write(path, text).map_err(|e| format!("cannot write {}: {e}", path.display()))
        }
        None => {
            print!("{text}");
            Ok(())
        }
    }
}
