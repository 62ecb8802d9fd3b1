//! `afg plot-curves` and `afg training-report`: what training runs' logs show.

use std::path::PathBuf;

use afg_eval::figures::runs_curves_svg;
use afg_eval::runs::report_markdown;
use afg_game::fs::write_atomic_making_dirs;
use anyhow::Result;
use clap::Args;

/// `afg plot-curves`: run directories and the SVG to draw.
#[derive(Args)]
pub struct PlotArgs {
    /// Run directories (each with a log.jsonl).
    #[arg(required = true)]
    dirs: Vec<PathBuf>,
    /// Output SVG.
    #[arg(long, default_value = "docs/figures/curves.svg")]
    out: PathBuf,
}

/// Draws the runs' validation curves.
///
/// # Errors
/// A run without a readable log, or the SVG not written.
pub fn run_plot(args: PlotArgs) -> Result<()> {
    let svg = runs_curves_svg(
        &args.dirs,
        "Validation welfare during training (dashed: classical methods)",
    )?;
    write_atomic_making_dirs(&args.out, svg.as_bytes())?;
    println!("wrote {}", args.out.display());
    Ok(())
}

/// `afg training-report`: finished run directories.
#[derive(Args)]
pub struct ReportArgs {
    /// Run directories (each with a log.jsonl).
    #[arg(required = true)]
    dirs: Vec<PathBuf>,
    /// Read each log only up to this gradient step (compare runs at equal steps).
    #[arg(long)]
    at_step: Option<u64>,
}

/// A Markdown table of finished runs against the classical methods (from their logs).
pub fn run_report(args: ReportArgs) -> Result<()> {
    print!("{}", report_markdown(&args.dirs, args.at_step)?);
    Ok(())
}
