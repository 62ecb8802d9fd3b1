//! `cargo xtask grape-fig7`: GRAPE's published Fig. 7 runs beside afg's, as the
//! Markdown table of docs/baselines.md.

use std::path::PathBuf;

use afg_repro::grape_fig7::{DATASET, source, table};
use anyhow::Result;
use clap::Args;

/// Where the converted runs are.
#[derive(Args)]
pub struct GrapeArgs {
    /// The directory of the converted runs (written by scripts/grape_fig7.py).
    #[arg(long, default_value = DATASET)]
    dataset: PathBuf,
}

/// Prints the source of the runs and the table.
pub fn run(args: GrapeArgs) -> Result<()> {
    println!("GRAPE's runs: {}\n", source(&args.dataset)?);
    print!("{}", table(&args.dataset)?);
    Ok(())
}
