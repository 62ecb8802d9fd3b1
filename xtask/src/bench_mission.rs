//! `cargo xtask bench-mission`: the exact optimum re-solved after one event against a
//! solve from scratch, and whole missions with allocators in the loop.

use afg_baseline::Method;
use afg_eval::mission::planner;
use afg_mission::{MissionConfig, MissionMethod, MissionPlan, Preset};
use afg_repro::bench::mission::{incremental, missions};
use anyhow::Result;
use clap::Args;

/// The sizes to measure.
#[derive(Args)]
pub struct BenchMissionArgs {
    /// Robots of the one-event re-solve.
    #[arg(long, default_value_t = 100_000)]
    resolve_robots: usize,
    /// Tasks of the one-event re-solve.
    #[arg(long, default_value_t = 50)]
    resolve_tasks: usize,
    /// Robots of the whole mission (Poisson arrivals).
    #[arg(long, default_value_t = 10_000)]
    robots: usize,
    /// Tasks arriving over the whole mission.
    #[arg(long, default_value_t = 200)]
    tasks: usize,
    /// The allocators of the whole mission, comma-separated (opt runs from scratch and
    /// incrementally).
    #[arg(long, value_delimiter = ',', default_value = "opt,greedy,da-balanced")]
    methods: Vec<Method>,
    /// A trained model to run in the mission too (e.g. models/ours/price_n60).
    #[arg(long)]
    model: Option<std::path::PathBuf>,
    /// Seconds per timing (the median of repeated runs within it).
    #[arg(long, default_value_t = 2.0)]
    budget: f64,
    /// Seed of the instances and the mission.
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

/// Prints both tables.
pub fn run(args: BenchMissionArgs) -> Result<()> {
    println!(
        "{}",
        incremental(
            args.resolve_robots,
            args.resolve_tasks,
            args.seed,
            args.budget
        )?
    );
    let mission =
        MissionConfig::new(Preset::Poisson, args.robots, args.tasks, args.seed).generate()?;
    let plan = |method, warm| MissionPlan {
        method: MissionMethod::Central(method),
        warm,
        seed: args.seed,
        ..MissionPlan::default()
    };
    let mut planners = vec![planner(&plan(Method::Opt, true), None)?];
    for &method in &args.methods {
        planners.push(planner(&plan(method, false), None)?);
    }
    if let Some(dir) = &args.model {
        planners.push(planner(&plan(Method::Opt, false), Some(dir))?);
    }
    println!(
        "A mission of {} robots and {} tasks arriving at rate {} (seed {}), one run each, on {} core(s):\n",
        args.robots,
        args.tasks,
        args.tasks as f64 / 20.0,
        args.seed,
        rayon::current_num_threads()
    );
    print!("{}", missions(&mission, &planners)?);
    Ok(())
}
