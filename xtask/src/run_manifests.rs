//! A training run's reproducing command and its `manifest.json` (`cargo xtask manifest`).

use std::path::{Path, PathBuf};

use afg_cli::train::command_line;
use afg_learn::run::RunDir;
use anyhow::Result;
use clap::Args;

/// Writes `dir/manifest.json` from the run's config and log: the command, seed, steps,
/// wall time, git revision and final validation welfare.
pub fn write_manifest(dir: &Path) -> Result<()> {
    let run = RunDir::new(dir);
    let relative = dir.strip_prefix(crate::repo_root()).unwrap_or(dir);
    let manifest =
        run.manifest_from_log(command_line("cargo xtask train", &run.config()?, relative))?;
    run.write_manifest(&manifest)?;
    Ok(())
}

/// The options of `cargo xtask manifest`.
#[derive(Args)]
pub struct ManifestArgs {
    /// Finished run directories.
    #[arg(required = true)]
    dirs: Vec<PathBuf>,
}

/// Rewrites the manifests of finished runs.
pub fn run_manifest(args: ManifestArgs) -> Result<()> {
    for d in &args.dirs {
        write_manifest(d)?;
        println!("wrote {}", d.join("manifest.json").display());
    }
    Ok(())
}
