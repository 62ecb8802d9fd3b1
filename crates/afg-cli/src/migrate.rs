//! `afg migrate`: run directories written by an older afg brought to the current format
//! once ([`afg_learn::run::migrate_run`]).

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;

/// The options of `afg migrate`.
#[derive(Args)]
pub struct MigrateArgs {
    /// Run directories (each holding config.json, log.jsonl or model.json). Every file in
    /// an older format is rewritten in place, atomically; current files are left alone,
    /// so running it twice is harmless.
    #[arg(required = true, value_name = "DIR")]
    pub dirs: Vec<PathBuf>,
}

/// Runs `afg migrate`: one line per directory naming the files rewritten.
///
/// # Errors
/// A directory that is missing, or a file in it that cannot be read or rewritten.
pub fn run(args: MigrateArgs) -> Result<()> {
    for dir in &args.dirs {
        anyhow::ensure!(dir.is_dir(), "{} is not a directory", dir.display());
        let run_files = ["config.json", "log.jsonl", "model.json", "price.json"];
        if !run_files.iter().any(|f| dir.join(f).exists()) {
            println!(
                "{}: holds no run (no {}); skipped",
                dir.display(),
                run_files.join(", ")
            );
            continue;
        }
        let rewritten = afg_learn::run::migrate_run(dir)
            .with_context(|| format!("migrating {}", dir.display()))?;
        let names: Vec<String> = rewritten
            .iter()
            .map(|p| p.strip_prefix(dir).unwrap_or(p).display().to_string())
            .collect();
        if names.is_empty() {
            println!(
                "{}: already in format {}",
                dir.display(),
                afg_learn::run::RUN_FORMAT_VERSION
            );
        } else {
            println!("{}: rewrote {}", dir.display(), names.join(", "));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use crate::afg;

    #[test]
    fn a_missing_directory_is_refused() {
        let err = afg("migrate /nonexistent/afg-run").unwrap_err();
        assert!(err.to_string().contains("is not a directory"), "{err}");
    }
}
