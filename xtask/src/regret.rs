//! `cargo xtask regret`: where along a rollout a trained model loses welfare, measured
//! against the exact Q* (`afg_learn::policy::regret_trace`).

use std::path::PathBuf;

use afg_repro::regret::{markdown, summarise};
use anyhow::Result;
use clap::Args;

#[derive(Args)]
pub struct RegretArgs {
    /// Run directories (each with config.json and model.*).
    #[arg(required = true)]
    dirs: Vec<PathBuf>,
    /// Robots N of the committed dataset to roll out on (datasets/n{N}.jsonl).
    #[arg(long)]
    dataset: usize,
    /// Use the first K instances only (each costs N·M optimal completions).
    #[arg(long, default_value_t = 20)]
    instances: usize,
    /// Also write the summaries as JSON to this file.
    #[arg(long)]
    json: Option<PathBuf>,
}

pub fn run(args: RegretArgs) -> Result<()> {
    let mut instances = crate::datasets::load(args.dataset)?;
    instances.truncate(args.instances.max(1));
    let rows = args
        .dirs
        .iter()
        .map(|d| {
            let bar = afg_eval::report::progress(
                instances.len() as u64,
                &format!("regret {}", d.display()),
            );
            let summary = summarise(d, &instances, || bar.inc(1));
            bar.finish_and_clear();
            summary
        })
        .collect::<Result<Vec<_>, _>>()?;
    print!("{}", markdown(&rows));
    if let Some(path) = &args.json {
        afg_game::fs::write_atomic(path, serde_json::to_string_pretty(&rows)?.as_bytes())?;
    }
    Ok(())
}
