//! `cargo xtask bench-baselines`: a Markdown table of allocator times and welfare.

use std::time::Duration;

use afg_baseline::{Allocator, Method, Optimum};
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

/// Median wall time of repeated runs.
fn median_time(
    alloc: &dyn Allocator,
    inst: &afg_game::Instance,
    budget: f64,
) -> Result<(Duration, f64)> {
    let mut times = Vec::new();
    let mut welfare = 0.0;
    let mut spent = 0.0;
    while times.is_empty() || (spent < budget && times.len() < 20) {
        let out = alloc.allocate(inst)?;
        welfare = inst.welfare(&out.assignment);
        spent += out.stats.wall_time.as_secs_f64();
        times.push(out.stats.wall_time);
    }
    times.sort();
    Ok((times[times.len() / 2], welfare))
}

fn fmt_time(d: Duration) -> String {
    let s = d.as_secs_f64();
    if s < 1e-3 {
        format!("{:.1} µs", s * 1e6)
    } else if s < 1.0 {
        format!("{:.2} ms", s * 1e3)
    } else {
        format!("{s:.2} s")
    }
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
            let (t, w) = median_time(m.allocator(0).as_ref(), &inst, args.seconds)?;
            print!(" {} ({:.2} %) |", fmt_time(t), 100.0 * w / opt);
        }
        println!();
    }
    Ok(())
}
