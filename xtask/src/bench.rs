//! `cargo xtask bench-baselines`: a Markdown table of allocator times and welfare.

use afg_baseline::{Allocator, Method, Optimum};
use afg_eval::bench::{allocator_time, network_timings, plain_timings, rollout_timings};
use afg_eval::tables::duration;
use afg_game::GeneratorConfig;
use anyhow::Result;
use clap::Args;

#[derive(Args)]
pub struct BenchArgs {
    /// Robot counts to sweep.
    #[arg(long, value_delimiter = ',', default_values_t = [100, 1_000, 10_000, 100_000])]
    sizes: Vec<usize>,
    /// Number of tasks M.
    #[arg(long, default_value_t = 5)]
    tasks: usize,
    /// Largest N for the decentralised DA (its simulation keeps N views).
    #[arg(long, default_value_t = 1_000)]
    max_decentralised: usize,
    /// Time budget per measurement: repeat until it is spent (at least once, at most 20 runs).
    #[arg(long, default_value_t = 1.0)]
    seconds: f64,
}

pub fn run(args: BenchArgs) -> Result<()> {
    let methods = [
        Method::Opt,
        Method::Da,
        Method::DaBalanced,
        Method::Greedy,
        Method::Nearest,
        Method::DaDecentralised,
    ];
    println!(
        "M = {}; instance seed 7, paper distribution; median wall time on one core, welfare as % of OPT.\n",
        args.tasks
    );
    print!("| N |");
    for m in methods {
        print!(" {m} |");
    }
    println!();
    println!("|---|{}", "---|".repeat(methods.len()));
    for &n in &args.sizes {
        let inst = GeneratorConfig::paper(n, args.tasks, 7).generate()?;
        let opt = inst.welfare(&Optimum.allocate(&inst)?.assignment);
        print!("| {n} |");
        for m in methods {
            if m == Method::DaDecentralised && n > args.max_decentralised {
                print!(" – |");
                continue;
            }
            let (t, w) = allocator_time(m.allocator(0).as_ref(), &inst, args.seconds)?;
            print!(" {} ({:.2} %) |", duration(t), 100.0 * w / opt);
        }
        println!();
    }
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
    println!(
        "Median of {} runs; batch of {} states from random partial episodes (M = 5); CPU ndarray back end; {} allocator.\n",
        args.repeats,
        args.batch,
        crate::ALLOCATOR_NAME
    );
    println!(
        "| network | N | forward, edge lists | forward, dense | train step, edge lists | train step, dense | speed-up of the step |"
    );
    println!("|---|---|---|---|---|---|---|");
    for t in network_timings(&args.sizes, args.batch, args.repeats)? {
        println!(
            "| {} | {} | {} | {} | {} | {} | {:.1}× |",
            t.network,
            t.robots,
            duration(t.forward[0]),
            duration(t.forward[1]),
            duration(t.step[0]),
            duration(t.step[1]),
            t.step[0].as_secs_f64() / t.step[1].as_secs_f64()
        );
    }
    println!(
        "\nAFGNet's training step against the plain model of the first Burn notes of this project \
         (neighbours padded to the largest degree, gather + reshape + sum; same parameters, \
         same Q values: tested in crates/afg-eval/src/bench/plain.rs), in the same run:\n"
    );
    println!("| N | train step, plain (padded gather) | train step, ours (dense) | speed-up |");
    println!("|---|---|---|---|");
    for (n, plain, ours) in plain_timings(&args.sizes, args.batch, args.repeats)? {
        println!(
            "| {n} | {} | {} | {:.1}× |",
            duration(plain),
            duration(ours),
            plain.as_secs_f64() / ours.as_secs_f64()
        );
    }
    println!(
        "\n| network | greedy rollout, N = {}, Burn path | fast path (B = 1) | speed-up |",
        args.rollout
    );
    println!("|---|---|---|---|");
    for (network, burn, fast) in rollout_timings(args.rollout)? {
        println!(
            "| {network} | {} | {} | {:.1}× |",
            duration(burn),
            duration(fast),
            burn.as_secs_f64() / fast.as_secs_f64()
        );
    }
    Ok(())
}
