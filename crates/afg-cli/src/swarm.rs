//! `afg swarm`: GRAPE and the decentralised auction over a lossy, late,
//! range-limited network where robots fail mid-run; a grid of methods × robot counts ×
//! loss rates × failing shares, several seeds each, as a Markdown table, JSON lines
//! and an SVG of the runs against rounds.

use std::path::PathBuf;

use afg_baseline::{Failure, Network, Swarm, SwarmMethod, SwarmReport};
use afg_game::{GeneratorConfig, Instance, Preference};
use afg_graph::GraphKind;
use anyhow::{Context, Result, ensure};
use clap::{Args, ValueEnum};
use rayon::prelude::*;

/// `afg swarm`: the methods, the instances and the network's knobs (one run per
/// combination of the listed values).
#[derive(Args)]
pub struct SwarmArgs {
    /// Decentralised methods (comma-separated): grape (GRAPE with its distributed
    /// mutex) or auction (robots bid for task places; prices and winners spread by
    /// max-consensus).
    #[arg(long, value_enum, value_delimiter = ',', default_value = "grape")]
    method: Vec<MethodName>,
    /// GRAPE's preference: selfish (the paper's GRAPE DA) or balanced.
    #[arg(long, value_enum, default_value_t = Pref::Selfish)]
    preference: Pref,
    /// The auction's least price increment ε (its result is within 2N·ε of the optimum).
    #[arg(long, default_value_t = 1e-3)]
    epsilon: f64,
    /// Robot counts (comma-separated); instances drawn from the paper's distribution.
    #[arg(long, value_delimiter = ',', default_value = "1000")]
    robots: Vec<usize>,
    /// Tasks of each drawn instance.
    #[arg(long, default_value_t = 5)]
    tasks: usize,
    /// Seed of the drawn instances.
    #[arg(long, default_value_t = 1)]
    instance_seed: u64,
    /// Your instances instead (an instance JSON or JSON Lines file): each is run.
    #[arg(long, conflicts_with = "robots")]
    input: Option<PathBuf>,
    /// Link robots within this distance (the arena is the unit square) instead of to
    /// their 10 nearest.
    #[arg(long, conflicts_with = "knn")]
    radius: Option<f64>,
    /// Link each robot to its K nearest (kept in both directions) [default: 10].
    #[arg(long)]
    knn: Option<usize>,
    /// Long-run shares of messages lost (comma-separated: one run per value).
    #[arg(long, value_delimiter = ',', default_value = "0")]
    loss: Vec<f64>,
    /// Losses come in bursts of this mean length in rounds (Gilbert–Elliott) instead of
    /// independently.
    #[arg(long)]
    burst: Option<f64>,
    /// A delivered message arrives 0..=DELAY rounds late (uniform).
    #[arg(long, default_value_t = 0)]
    delay: u32,
    /// Asynchronous robots: each wakes in a round with this chance (1 = synchronous).
    #[arg(long = "async", default_value_t = 1.0)]
    activation: f64,
    /// Shares of the robots that crash (comma-separated: one run per value).
    #[arg(long, value_delimiter = ',', default_value = "0")]
    fail: Vec<f64>,
    /// The round they crash at [default: mid-run, half the rounds the same run takes
    /// without failures].
    #[arg(long)]
    fail_at: Option<u64>,
    /// Silent rounds before a neighbour removes a crashed robot.
    #[arg(long, default_value_t = 3)]
    detect_after: u64,
    /// Cut the links across the median x until this round.
    #[arg(long)]
    partition_until: Option<u64>,
    /// Seeds per grid cell (SEED, SEED + 1, …): the table shows their means.
    #[arg(long, default_value_t = 1, value_parser = crate::at_least_one)]
    seeds: usize,
    /// The first seed of each cell (GRAPE's stamps, the auction's ties and, on another
    /// stream, the network's draws).
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Stop a run unconverged after this many rounds [default: GRAPE's bound, stretched
    /// by the loss, delay and asynchrony].
    #[arg(long)]
    max_rounds: Option<u64>,
    /// Print one JSON line per run (with its trace if --svg is given) instead of the table.
    #[arg(long)]
    json: bool,
    /// Draw welfare and agreement against rounds, one line per grid cell (its first seed).
    #[arg(long)]
    svg: Option<PathBuf>,
}

#[derive(Clone, Copy, ValueEnum)]
enum MethodName {
    Grape,
    Auction,
}

#[derive(Clone, Copy, ValueEnum)]
enum Pref {
    Selfish,
    Balanced,
}

impl From<Pref> for Preference {
    fn from(p: Pref) -> Preference {
        match p {
            Pref::Selfish => Preference::Selfish,
            Pref::Balanced => Preference::Balanced,
        }
    }
}

/// One cell of the grid: a method, an instance and a network, run over the seeds.
struct Cell {
    method: SwarmMethod,
    instance: Instance,
    network: Network,
    /// Whether the crash round is left to mid-run.
    crash_mid_run: bool,
}

/// Runs every combination and prints the table (or JSON), with the figure if asked.
///
/// # Errors
/// A knob out of range, an unreadable input, or a failed write.
pub fn run(args: SwarmArgs) -> Result<()> {
    let cells = cells(&args)?;
    let seeds = args.seed..args.seed + args.seeds as u64;
    let jobs: Vec<(usize, u64)> = (0..cells.len())
        .flat_map(|c| seeds.clone().map(move |s| (c, s)))
        .collect();
    let bar = crate::progress(jobs.len() as u64, "swarm runs");
    // One run alone shows its rounds as they go.
    let single = jobs.len() == 1;
    let on_round = |round: u64| {
        if single && round.is_multiple_of(100) {
            bar.set_message(format!("swarm run, round {round}"));
        }
    };
    let reports: Vec<(usize, SwarmReport)> = jobs
        .par_iter()
        .map(|&(c, seed)| {
            let report = run_one(&args, &cells[c], seed, &on_round)?;
            bar.inc(1);
            Ok((c, report))
        })
        .collect::<Result<_>>()?;
    bar.finish_and_clear();
    if let Some(path) = &args.svg {
        let firsts: Vec<(String, SwarmReport)> = reports
            .iter()
            .filter(|(_, r)| r.seed == args.seed)
            .map(|(c, r)| (label(&cells[*c]), r.clone()))
            .collect();
        let title = format!(
            "Decentralised allocation over a failing network (GRAPE: {})",
            preference_name(args.preference)
        );
        crate::write_svg(path, &afg_eval::figures::swarm_svg(&firsts, &title)?)?;
    }
    if args.json {
        for (_, report) in &reports {
            println!("{}", serde_json::to_string(report)?);
        }
    } else {
        print!("{}", table(&cells, &reports));
    }
    Ok(())
}

fn preference_name(p: Pref) -> &'static str {
    match p {
        Pref::Selfish => "selfish",
        Pref::Balanced => "balanced",
    }
}

/// The grid: each method × instance × loss × failing share.
fn cells(args: &SwarmArgs) -> Result<Vec<Cell>> {
    let instances = match &args.input {
        Some(path) => crate::solve::read_instances(path)?,
        None => args
            .robots
            .iter()
            .map(|&n| {
                GeneratorConfig::paper(n, args.tasks, args.instance_seed)
                    .generate()
                    .with_context(|| format!("drawing an instance of {n} robots"))
            })
            .collect::<Result<_>>()?,
    };
    let graph = match (args.radius, args.knn) {
        (Some(radius), _) => GraphKind::Radius { radius },
        (None, Some(k)) => GraphKind::Knn { k },
        (None, None) => GraphKind::default(),
    };
    let methods: Vec<SwarmMethod> = args
        .method
        .iter()
        .map(|m| match m {
            MethodName::Grape => SwarmMethod::Grape {
                preference: args.preference.into(),
            },
            MethodName::Auction => SwarmMethod::Auction {
                epsilon: args.epsilon,
            },
        })
        .collect();
    let mut cells = Vec::new();
    for (&method, instance) in methods
        .iter()
        .flat_map(|m| instances.iter().map(move |i| (m, i)))
    {
        for &loss in &args.loss {
            for &fail in &args.fail {
                let failure = (fail > 0.0).then(|| Failure {
                    fraction: fail,
                    at_round: args.fail_at.unwrap_or(1),
                    detect_after: args.detect_after,
                });
                let network = Network {
                    graph,
                    loss,
                    burst: args.burst,
                    max_delay: args.delay,
                    activation: args.activation,
                    failure,
                    partition_until: args.partition_until,
                };
                network.check()?;
                cells.push(Cell {
                    method,
                    instance: instance.clone(),
                    network,
                    crash_mid_run: fail > 0.0 && args.fail_at.is_none(),
                });
            }
        }
    }
    ensure!(!cells.is_empty(), "nothing to run");
    Ok(cells)
}

/// One seed of one cell; a mid-run crash is placed at half the rounds of the same run
/// without failures.
fn run_one(
    args: &SwarmArgs,
    cell: &Cell,
    seed: u64,
    on_round: &(dyn Fn(u64) + Sync),
) -> Result<SwarmReport> {
    let swarm = |network: Network| {
        let mut swarm = match cell.method {
            SwarmMethod::Grape { preference } => Swarm::grape(preference, network, seed),
            SwarmMethod::Auction { epsilon } => Swarm::auction(epsilon, network, seed),
        };
        swarm.max_rounds = args.max_rounds.unwrap_or(0);
        swarm.trace = args.svg.is_some();
        swarm
    };
    let mut network = cell.network.clone();
    if cell.crash_mid_run {
        let intact = Network {
            failure: None,
            ..network.clone()
        };
        let rounds = swarm(intact).run(&cell.instance)?.rounds;
        if let Some(f) = network.failure.as_mut() {
            f.at_round = (rounds / 2).max(1);
        }
    }
    Ok(swarm(network).run_with(&cell.instance, on_round)?)
}

/// What a cell is, in a few words.
fn label(cell: &Cell) -> String {
    let network = &cell.network;
    let method = match cell.method {
        SwarmMethod::Grape { .. } => "GRAPE".to_string(),
        SwarmMethod::Auction { epsilon } => format!("auction (ε = {epsilon})"),
    };
    let mut parts = vec![method, format!("N = {}", cell.instance.num_robots())];
    match network.graph {
        GraphKind::Radius { radius } => parts.push(format!("radius {radius}")),
        GraphKind::Knn { k } if k != 10 => parts.push(format!("{k} nearest")),
        _ => {}
    }
    parts.push(format!("loss {:.0} %", 100.0 * network.loss));
    if let Some(b) = network.burst {
        parts.push(format!("bursts of {b}"));
    }
    if network.max_delay > 0 {
        parts.push(format!("delay ≤ {}", network.max_delay));
    }
    if network.activation < 1.0 {
        parts.push(format!("async {}", network.activation));
    }
    if let Some(f) = network.failure {
        parts.push(format!("{:.0} % fail", 100.0 * f.fraction));
    }
    if let Some(r) = network.partition_until {
        parts.push(format!("split until {r}"));
    }
    parts.join(", ")
}

/// The Markdown table: one row per cell, means over its seeds.
fn table(cells: &[Cell], reports: &[(usize, SwarmReport)]) -> String {
    let mut out = String::from(
        "| network | links added | runs converged | fail at | rounds | messages | MB (partitions) | MB (changes) | agreeing | % of OPT (survivors) | stable | NS_rate balanced | NS_rate selfish | time |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for (c, cell) in cells.iter().enumerate() {
        let runs: Vec<&SwarmReport> = reports
            .iter()
            .filter(|(k, _)| *k == c)
            .map(|(_, r)| r)
            .collect();
        let mean = |f: &dyn Fn(&SwarmReport) -> f64| {
            runs.iter().map(|r| f(r)).sum::<f64>() / runs.len() as f64
        };
        let count = |f: &dyn Fn(&SwarmReport) -> bool| runs.iter().filter(|r| f(r)).count();
        let fail_at = cell.network.failure.map_or("–".to_string(), |_| {
            let rounds: Vec<String> = runs
                .iter()
                .map(|r| r.network.failure.map_or(0, |f| f.at_round).to_string())
                .collect();
            rounds.join("/")
        });
        let percent = runs
            .iter()
            .map(|r| r.percent_of_opt)
            .collect::<Option<Vec<f64>>>()
            .map_or("–".to_string(), |p| {
                format!("{:.2} %", p.iter().sum::<f64>() / p.len() as f64)
            });
        out += &format!(
            "| {} | {:.0} | {}/{} | {} | {:.0} | {:.0} | {:.1} | {:.2} | {:.1} % | {} | {}/{} | {:.1} % | {:.1} % | {} |\n",
            label(cell),
            mean(&|r| r.added_edges as f64),
            count(&|r| r.converged),
            runs.len(),
            fail_at,
            mean(&|r| r.rounds as f64),
            mean(&|r| r.messages as f64),
            mean(&|r| r.bytes as f64) / 1e6,
            mean(&|r| r.delta_bytes as f64) / 1e6,
            100.0 * mean(&|r| r.agreeing),
            percent,
            count(&|r| r.stable),
            runs.len(),
            100.0 * mean(&|r| r.ns_rate_balanced),
            100.0 * mean(&|r| r.ns_rate_selfish),
            afg_eval::tables::duration(std::time::Duration::from_secs_f64(
                mean(&|r| r.wall_time_s)
            )),
        );
    }
    out
}

#[cfg(test)]
mod tests {
    /// A small grid runs end to end: one row per cell, the figure written.
    #[test]
    fn a_grid_runs_and_draws() {
        let dir = std::env::temp_dir().join(format!("afg-swarm-{}", std::process::id()));
        let svg = dir.join("runs.svg");
        let line = format!(
            "swarm --robots 30,40 --loss 0,0.3 --fail 0,0.2 --seeds 2 --svg {}",
            svg.display()
        );
        crate::afg(&line).unwrap();
        let text = std::fs::read_to_string(&svg).unwrap();
        assert!(text.contains("N = 40, loss 30 %, 20 % fail"));
        std::fs::remove_dir_all(dir).unwrap();
    }

    #[test]
    fn bad_knobs_say_what_is_wrong() {
        let err = crate::afg("swarm --robots 20 --loss 1.5").unwrap_err();
        assert!(
            err.to_string().contains("loss 1.5 must be in [0, 1)"),
            "{err}"
        );
        let err = crate::afg("swarm --robots 20 --async 0").unwrap_err();
        assert!(
            err.to_string().contains("activation 0 must be in (0, 1]"),
            "{err}"
        );
        assert!(crate::parse("swarm --radius 0.1 --knn 5").is_err());
        assert!(crate::parse("swarm --seeds 0").is_err());
        assert!(crate::parse("swarm --method grape,auction --seed 5 --seeds 2").is_ok());
        assert!(crate::parse("swarm --method bogus").is_err());
    }
}
