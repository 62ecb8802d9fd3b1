//! `cargo xtask mission-study`: allocators in the loop of generated missions, as the
//! Markdown tables of docs/missions.md.

use afg_baseline::Method;
use afg_eval::mission::MissionMethod;
use afg_game::Preference;
use afg_mission::Preset;
use afg_repro::mission_study::{MissionPlan, SwarmPlan, study, swarm_study};
use anyhow::{Result, bail};
use clap::Args;

/// The study's missions and allocators.
#[derive(Args)]
pub struct MissionStudyArgs {
    /// Robots N.
    #[arg(long, default_value_t = 100)]
    robots: usize,
    /// Tasks K over each mission.
    #[arg(long, default_value_t = 40)]
    tasks: usize,
    /// Missions per preset (seeds 0..count).
    #[arg(long, default_value_t = 5)]
    count: u64,
    /// The presets, comma-separated.
    #[arg(long, value_delimiter = ',', value_parser = afg_cli::choice::<Preset>(), default_value = "waves,poisson,attrition")]
    presets: Vec<Preset>,
    /// The allocators, comma-separated (each from scratch and warm-started).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = afg_eval::mission::DEFAULT_METHODS
    )]
    methods: Vec<Method>,
    /// Also run every mission with each decision this many time units late.
    #[arg(long)]
    latency: Option<f64>,
    /// The decentralised study instead: GRAPE and the auction run by the robots over
    /// the radio beside the central optimum and GRAPE's centralised twin (warm-started).
    #[arg(long, conflicts_with_all = ["methods", "latency"])]
    swarm: bool,
    /// Communication radii as multiples of the connectivity radius sqrt(ln N / (π N)) (--swarm).
    #[arg(long, value_delimiter = ',', default_value = "1,2")]
    radius_factors: Vec<f64>,
    /// Shares of messages lost (--swarm).
    #[arg(long, value_delimiter = ',', default_value = "0,0.3")]
    losses: Vec<f64>,
    /// The decentralised methods (--swarm), comma-separated: grape, auction.
    #[arg(long, value_delimiter = ',', default_value = "grape,auction")]
    swarm_methods: Vec<String>,
    /// Rounds per time unit (--swarm).
    #[arg(long, default_value_t = 100.0)]
    rounds_per_time: f64,
}

/// Runs the study and prints its tables.
pub fn run(args: MissionStudyArgs) -> Result<()> {
    if args.swarm {
        return run_swarm(args);
    }
    let plan = MissionPlan {
        robots: args.robots,
        tasks: args.tasks,
        count: args.count,
        presets: args.presets,
        methods: args.methods,
        latency: args.latency,
    };
    let runs = plan.presets.len() as u64
        * plan.count
        * 2
        * plan.methods.len() as u64
        * (1 + u64::from(plan.latency.is_some()));
    let bar = afg_eval::report::progress(runs, "missions");
    let text = study(&plan, || bar.inc(1))?;
    bar.finish_and_clear();
    print!("{text}");
    Ok(())
}

/// The decentralised study.
fn run_swarm(args: MissionStudyArgs) -> Result<()> {
    let plan = SwarmPlan {
        robots: args.robots,
        tasks: args.tasks,
        count: args.count,
        presets: args.presets,
        radius_factors: args.radius_factors,
        losses: args.losses,
        methods: args
            .swarm_methods
            .iter()
            .map(|name| {
                let method: Option<MissionMethod> = name.parse().ok();
                match method.and_then(|m| m.swarm(Preference::Selfish, 1e-3)) {
                    Some(swarm) => Ok(swarm),
                    None => bail!("unknown decentralised method '{name}': grape or auction"),
                }
            })
            .collect::<Result<_>>()?,
        rounds_per_time: args.rounds_per_time,
    };
    let runs = plan.presets.len() as u64
        * plan.count
        * (2 + (plan.methods.len() * plan.radius_factors.len() * plan.losses.len()) as u64);
    let bar = afg_eval::report::progress(runs, "missions");
    let text = swarm_study(&plan, || bar.inc(1))?;
    bar.finish_and_clear();
    print!("{text}");
    Ok(())
}
