//! The fixed test datasets: `datasets/n{N}.jsonl`, 100 instances each, and the team
//! games' `datasets/teams-thresholds.jsonl` with the certified optimum of every
//! instance beside it (`teams-thresholds.optima.json`).

use std::path::PathBuf;

use afg_baseline::TeamOptimum;
use afg_eval::dataset;
use afg_game::Instance;
use afg_game::fs::write_atomic;
use afg_game::io::dataset_to_jsonl;
use anyhow::{Result, bail};
use clap::Args;
use serde::Serialize;

use crate::bench_opt::Case;

/// The sizes of the team-threshold dataset: 10 scarce instances each (thresholds
/// uniform in [N/M, 2N/M]), seeds 0..10.
const TEAM_SIZES: [(usize, usize); 3] = [(20, 4), (100, 10), (300, 20)];
/// Instances per size of the team dataset.
const TEAM_INSTANCES: u64 = 10;

/// The certified optimum of one instance of a team dataset.
#[derive(Serialize)]
struct Certified {
    robots: usize,
    tasks: usize,
    seed: u64,
    welfare: f64,
    bound: f64,
    proven: bool,
    /// The optimum's coalition sizes.
    sizes: Vec<usize>,
}

/// The team-threshold dataset and its certified optima, as the files hold them.
fn team_files() -> Result<Vec<(PathBuf, String)>> {
    let mut instances = Vec::new();
    let mut optima = Vec::new();
    for (robots, tasks) in TEAM_SIZES {
        for seed in 0..TEAM_INSTANCES {
            let inst = crate::bench_teams::scarce(Case { robots, tasks }, seed, None)?;
            let best = TeamOptimum::default().solve(&inst)?;
            optima.push(Certified {
                robots,
                tasks,
                seed,
                welfare: best.welfare,
                bound: best.bound,
                proven: best.proven,
                sizes: best.assignment.sizes().to_vec(),
            });
            instances.push(inst);
        }
    }
    let dir = crate::repo_root().join("datasets");
    let optima: Vec<String> = optima
        .iter()
        .map(|c| serde_json::to_string(c).expect("a record"))
        .collect();
    Ok(vec![
        (
            dir.join("teams-thresholds.jsonl"),
            dataset_to_jsonl(&instances),
        ),
        (
            dir.join("teams-thresholds.optima.json"),
            format!("[\n{}\n]\n", optima.join(",\n")),
        ),
    ])
}

/// The options of `cargo xtask gen-datasets`.
#[derive(Args)]
pub struct GenArgs {
    /// Verify that the committed files are byte-for-byte what the generator makes (and
    /// the team dataset's optima what the exact solver proves now); write nothing.
    #[arg(long)]
    check: bool,
}

/// Loads the committed dataset for `n` robots.
pub fn load(n: usize) -> Result<Vec<Instance>> {
    Ok(dataset::load(&crate::repo_root(), n)?)
}

/// Runs `cargo xtask gen-datasets`: writes the datasets, or checks them with `--check`.
pub fn run(args: GenArgs) -> Result<()> {
    let mut stale = Vec::new();
    let mut files = dataset::SIZES
        .into_iter()
        .map(|n| {
            let text = dataset_to_jsonl(&dataset::generate(n)?);
            Ok((dataset::path(&crate::repo_root(), n), text))
        })
        .collect::<Result<Vec<_>>>()?;
    files.extend(team_files()?);
    for (p, text) in files {
        if args.check {
            let committed = std::fs::read_to_string(&p).unwrap_or_default();
            let ok = committed == text;
            println!("{} {}", if ok { "ok   " } else { "STALE" }, p.display());
            if !ok {
                stale.push(p);
            }
        } else {
            std::fs::create_dir_all(p.parent().expect("datasets dir"))?;
            write_atomic(&p, text.as_bytes())?;
            println!("wrote {} ({} bytes)", p.display(), text.len());
        }
    }
    if !stale.is_empty() {
        bail!(
            "{} dataset(s) differ from the generator; run `cargo xtask gen-datasets`",
            stale.len()
        );
    }
    Ok(())
}
