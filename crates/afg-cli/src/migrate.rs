//! `afg migrate`: run directories written by an older afg brought to the current format
//! once ([`afg_learn::run::migrate_run`]).

use std::path::{Path, PathBuf};

use afg_learn::run::RunDir;

use anyhow::{Context, Result};
use clap::Args;

/// The options of `afg migrate`.
#[derive(Args)]
pub struct MigrateArgs {
    /// Run directories (each holding config.json, log.jsonl, model.json or price.json),
    /// or folders of runs, such as `models/`, searched for every run below them. Every
    /// file in an older format is rewritten in place, atomically; current files are left
    /// alone, so running it twice is harmless.
    #[arg(required = true, value_name = "DIR")]
    pub dirs: Vec<PathBuf>,
}

/// Runs `afg migrate`: one line per run directory naming the files rewritten.
///
/// # Errors
/// A directory that is missing or holds no run, or a file in it that cannot be read or
/// rewritten.
pub fn run(args: MigrateArgs) -> Result<()> {
    for dir in &args.dirs {
        anyhow::ensure!(dir.is_dir(), "{} is not a directory", dir.display());
        let runs = RunDir::find_all(dir)?;
        anyhow::ensure!(
            !runs.is_empty(),
            "{} holds no run (no {} in it or below it)",
            dir.display(),
            RunDir::RUN_FILES.join(", ")
        );
        for run in runs {
            migrate(run.path())?;
        }
    }
    Ok(())
}

/// Migrates one run directory and says what was rewritten.
fn migrate(dir: &Path) -> Result<()> {
    let rewritten =
        afg_learn::run::migrate_run(dir).with_context(|| format!("migrating {}", dir.display()))?;
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

    /// A folder is searched for the runs below it; a folder with none is refused.
    #[test]
    fn a_folder_of_runs_migrates_each_run_below_it() {
        let root = std::env::temp_dir().join(format!("afg-cli-migrate-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        let run = root.join("runs/deep/run");
        std::fs::create_dir_all(&run).unwrap();
        let committed = crate::repo_root().join("models/paper/afgnet_ddqn_n60/config.json");
        let committed = std::fs::read_to_string(committed).unwrap();
        let mut old: serde_json::Value = serde_json::from_str(&committed).unwrap();
        old.as_object_mut().unwrap().remove("version");
        std::fs::write(run.join("config.json"), old.to_string()).unwrap();

        afg(&format!("migrate {}", root.join("runs").display())).unwrap();
        let migrated = std::fs::read_to_string(run.join("config.json")).unwrap();
        assert_eq!(migrated.trim_end(), committed.trim_end());

        std::fs::create_dir_all(root.join("empty/sub")).unwrap();
        let err = afg(&format!("migrate {}", root.join("empty").display())).unwrap_err();
        assert!(err.to_string().contains("holds no run"), "{err}");
        std::fs::remove_dir_all(&root).unwrap();
    }
}
