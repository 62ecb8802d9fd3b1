//! `cargo xtask bench-baselines`: a Markdown table of allocator times and welfare.

use afg_repro::bench::{allocators_markdown, networks_markdown};
use anyhow::Result;
use clap::Args;

#[derive(Args)]
pub struct BenchArgs {
    /// Robot counts to sweep.
    #[arg(long, value_delimiter = ',', default_values_t = [100, 1_000, 10_000, 100_000])]
    sizes: Vec<usize>,
    /// Number of tasks M.
    #[arg(long, default_value_t = afg_eval::dataset::TASKS)]
    tasks: usize,
    /// Largest N for the decentralised DA (its synchronous rounds take time about quadratic in N).
    #[arg(long, default_value_t = 1_000)]
    max_decentralised: usize,
    /// Time budget per measurement: repeat until it is spent (at least once, at most 20 runs).
    #[arg(long, default_value_t = 1.0)]
    seconds: f64,
}

pub fn run(args: BenchArgs) -> Result<()> {
    let (tasks, max_decentralised) = (args.tasks, args.max_decentralised);
    let md = allocators_markdown(&args.sizes, tasks, max_decentralised, args.seconds)?;
    print!("{md}");
    Ok(())
}

#[derive(Args)]
pub struct ModelBenchArgs {
    /// Robot counts for the batched forward pass and training step.
    #[arg(long, value_delimiter = ',', default_values_t = [20, 60, 100])]
    sizes: Vec<usize>,
    /// States per batch.
    #[arg(long, default_value_t = 256)]
    batch: usize,
    /// Robot count of the greedy rollout.
    #[arg(long, default_value_t = 1_000)]
    rollout: usize,
    /// Repetitions per measurement (the median is reported).
    #[arg(long, default_value_t = 5)]
    repeats: usize,
}

pub fn run_models(args: ModelBenchArgs) -> Result<()> {
    let (sizes, batch, rollout) = (&args.sizes, args.batch, args.rollout);
    let md = networks_markdown(sizes, batch, rollout, args.repeats, crate::ALLOCATOR_NAME)?;
    print!("{md}");
    Ok(())
}
