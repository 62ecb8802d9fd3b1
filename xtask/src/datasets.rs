//! The fixed test datasets: `datasets/n{N}.jsonl`, 100 instances each, and the team
//! games' `datasets/teams-{thresholds,skills,both}.jsonl`, each with the certified
//! optimum of every instance beside it (`teams-*.optima.json`).

use std::path::PathBuf;

use afg_baseline::TeamOptimum;
use afg_eval::dataset;
use afg_game::fs::write_atomic;
use afg_game::io::dataset_to_jsonl;
use afg_game::{GeneratorKnobs, Instance};
use anyhow::{Result, bail};
use clap::Args;
use serde::Serialize;

use crate::bench_opt::Case;

/// Instances per size of a team dataset (seeds 0..10).
const TEAM_INSTANCES: u64 = 10;

/// One team dataset: its name, its sizes (N, M) and its game.
struct TeamDataset {
    name: &'static str,
    sizes: &'static [(usize, usize)],
    thresholds: bool,
    skills: bool,
}

/// The team datasets. Thresholds are uniform in [N/M, 2N/M] (scarce); skills are 2,
/// each robot holding each with probability 0.5, each task requiring 1 or 2 of each.
const TEAM_DATASETS: [TeamDataset; 3] = [
    TeamDataset {
        name: "thresholds",
        sizes: &[(20, 4), (100, 10), (300, 20)],
        thresholds: true,
        skills: false,
    },
    TeamDataset {
        name: "skills",
        sizes: &[(20, 4), (60, 10)],
        thresholds: false,
        skills: true,
    },
    TeamDataset {
        name: "both",
        sizes: &[(20, 4), (60, 10)],
        thresholds: true,
        skills: true,
    },
];

/// The instance of a team dataset.
fn team_instance(case: Case, seed: u64, thresholds: bool, skills: bool) -> Result<Instance> {
    let skill_knobs = GeneratorKnobs {
        skills: Some(2),
        skill_share: Some(0.5),
        requires: Some((1, 2)),
        ..GeneratorKnobs::default()
    };
    let skill_knobs = skills.then_some(&skill_knobs);
    if thresholds {
        return crate::bench_teams::scarce(case, seed, skill_knobs);
    }
    let knobs = skill_knobs.copied().unwrap_or_default();
    Ok(knobs.config(case.robots, case.tasks, seed)?.generate()?)
}

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

/// The team datasets and their certified optima, as the files hold them.
fn team_files() -> Result<Vec<(PathBuf, String)>> {
    let dir = crate::repo_root().join("datasets");
    let mut files = Vec::new();
    for set in &TEAM_DATASETS {
        let mut instances = Vec::new();
        let mut optima = Vec::new();
        for &(robots, tasks) in set.sizes {
            for seed in 0..TEAM_INSTANCES {
                let inst = team_instance(Case { robots, tasks }, seed, set.thresholds, set.skills)?;
                let best = TeamOptimum::default().solve(&inst)?;
                let certified = Certified {
                    robots,
                    tasks,
                    seed,
                    welfare: best.welfare,
                    bound: best.bound,
                    proven: best.proven,
                    sizes: best.assignment.sizes().to_vec(),
                };
                optima.push(serde_json::to_string(&certified)?);
                instances.push(inst);
            }
        }
        files.push((
            dir.join(format!("teams-{}.jsonl", set.name)),
            dataset_to_jsonl(&instances),
        ));
        files.push((
            dir.join(format!("teams-{}.optima.json", set.name)),
            format!("[\n{}\n]\n", optima.join(",\n")),
        ));
    }
    Ok(files)
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
