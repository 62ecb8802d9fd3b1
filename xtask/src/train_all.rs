//! `cargo xtask train-all`: every paper-form model of the tables, with the default
//! budgets.

use crate::ModelSpec;
use afg_cli::settings::TrainSettings;
use anyhow::Result;
use clap::Args;

use afg_cli::train::{TrainArgs, run};

/// The options of `cargo xtask train-all`.
#[derive(Args)]
pub struct TrainAllArgs {
    /// Scales to train.
    #[arg(long, value_delimiter = ',', default_values_t = afg_eval::dataset::TABLE1_SIZES)]
    scales: Vec<usize>,
    /// Retrain models that already exist (their directories are replaced).
    #[arg(long)]
    force: bool,
}

/// Trains every model the tables use, one after the other, with the default budgets.
pub fn run_all(args: TrainAllArgs) -> Result<()> {
    for scale in &args.scales {
        // The paper's three models (ours are trained by hand, see docs/training.md).
        for spec in ModelSpec::table1(*scale)
            .into_iter()
            .filter(|m| !m.is_ours())
        {
            let name = spec.dir_name();
            let run_dir = spec.run_dir(&crate::repo_root());
            if run_dir.has_weights() && !args.force {
                eprintln!("{name}: exists, skipped (--force retrains)");
                continue;
            }
            let dir = run_dir.path().to_path_buf();
            if dir.exists() {
                std::fs::remove_dir_all(&dir)?;
            }
            run(
                TrainArgs {
                    settings: TrainSettings {
                        scale: Some(*scale),
                        algo: Some(spec.algo),
                        net: Some(spec.net),
                        seed: Some(0),
                        ..TrainSettings::default()
                    },
                    out: Some(dir),
                    checkpoint_secs: 300,
                    ..TrainArgs::default()
                },
                "cargo xtask train",
            )?;
        }
    }
    Ok(())
}
