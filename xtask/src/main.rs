//! `cargo xtask <command>`: the project's jobs — datasets, solving, benchmarks.

mod datasets;
mod solve;

use anyhow::Result;
use clap::{Parser, Subcommand};

/// afg project tasks. Run `cargo xtask <command> --help` for each command's options.
#[derive(Parser)]
#[command(name = "cargo xtask", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Write the fixed test datasets under datasets/ (or verify them with --check).
    GenDatasets(datasets::GenArgs),
    /// Solve an instance or a dataset with one allocator and print welfare, % of OPT, NS_rate.
    Solve(solve::SolveArgs),
}

fn main() -> Result<()> {
    match Cli::parse().command {
        Command::GenDatasets(args) => datasets::run(args),
        Command::Solve(args) => solve::run(args),
    }
}

/// The repository root (xtask lives one level below it).
pub fn repo_root() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("xtask has a parent")
        .to_path_buf()
}
