//! The fixed test datasets: `datasets/n{N}.jsonl`, 100 instances each.

use std::path::PathBuf;

use afg_game::io::{dataset_to_jsonl, read_dataset, write_atomic};
use afg_game::{GeneratorConfig, Instance};
use anyhow::{Context, Result, bail};
use clap::Args;

/// Robot counts of the committed datasets (Table I: 20, 60, 100; Table II: 500, 1000).
pub const SIZES: [usize; 5] = [20, 60, 100, 500, 1000];
/// Instances per dataset.
pub const INSTANCES: usize = 100;
/// Tasks per instance (the paper's M).
pub const TASKS: usize = 5;

#[derive(Args)]
pub struct GenArgs {
    /// Verify that the committed files are byte-for-byte what the generator makes; write nothing.
    #[arg(long)]
    check: bool,
}

/// Seed of instance `index` of the dataset with `n` robots: `n * 1_000_000 + index`.
pub fn seed(n: usize, index: usize) -> u64 {
    (n * 1_000_000 + index) as u64
}

/// The generated dataset for `n` robots (paper distribution, SPEC defaults).
pub fn generate(n: usize) -> Result<Vec<Instance>> {
    (0..INSTANCES)
        .map(|i| Ok(GeneratorConfig::paper(n, TASKS, seed(n, i)).generate()?))
        .collect()
}

/// Path of the committed dataset for `n` robots.
pub fn path(n: usize) -> PathBuf {
    crate::repo_root()
        .join("datasets")
        .join(format!("n{n}.jsonl"))
}

/// Loads the committed dataset for `n` robots, with a hint if it is missing.
pub fn load(n: usize) -> Result<Vec<Instance>> {
    let p = path(n);
    read_dataset(&p).with_context(|| {
        format!(
            "reading {} (regenerate with `cargo xtask gen-datasets`)",
            p.display()
        )
    })
}

pub fn run(args: GenArgs) -> Result<()> {
    let mut stale = Vec::new();
    for n in SIZES {
        let text = dataset_to_jsonl(&generate(n)?);
        let p = path(n);
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
            println!(
                "wrote {} ({INSTANCES} instances, N = {n}, M = {TASKS}, {} bytes)",
                p.display(),
                text.len()
            );
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
