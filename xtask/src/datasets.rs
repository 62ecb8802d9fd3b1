//! The fixed test datasets: `datasets/n{N}.jsonl`, 100 instances each.

use afg_eval::dataset;
use afg_game::Instance;
use afg_game::fs::write_atomic;
use afg_game::io::dataset_to_jsonl;
use anyhow::{Result, bail};
use clap::Args;

/// The options of `cargo xtask gen-datasets`.
#[derive(Args)]
pub struct GenArgs {
    /// Verify that the committed files are byte-for-byte what the generator makes; write nothing.
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
    for n in dataset::SIZES {
        let text = dataset_to_jsonl(&dataset::generate(n)?);
        let p = dataset::path(&crate::repo_root(), n);
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
                "wrote {} ({} instances, N = {n}, M = {}, {} bytes)",
                p.display(),
                dataset::INSTANCES,
                dataset::TASKS,
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
