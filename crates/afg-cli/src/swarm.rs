//! `afg swarm`: GRAPE and the decentralised auction over a lossy, late,
//! range-limited network where robots fail mid-run; the flags make afg-eval's grid of
//! methods × robot counts × loss rates × failing shares ([`SwarmGrid`]), printed as a
//! Markdown table or JSON lines, with an SVG of the runs against rounds.

use std::path::PathBuf;

use afg_baseline::{Network, SwarmMethod, SwarmReport};
use afg_eval::swarm::{SwarmGrid, summary, table};
use afg_game::fs::write_atomic_making_dirs;
use afg_game::io::read_instances;
use afg_game::{GeneratorConfig, Named, Preference};
use afg_mission::{RadioKnobs, SwarmKnobs};
use anyhow::{Context, Result};
use clap::{Args, ValueEnum};

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
    #[arg(long, value_parser = crate::choice::<Preference>(), default_value = SwarmKnobs::default().preference.name())]
    preference: Preference,
    /// The auction's least price increment ε (its result is within 2N·ε of the optimum;
    /// team games want 0.01–0.1: docs/teams.md) [default: 0.01 where a task needs a
    /// team or a skill, 0.001 otherwise, as in `afg mission`].
    #[arg(long)]
    epsilon: Option<f64>,
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
    #[command(flatten)]
    radio: RadioArgs,
    /// Long-run shares of messages lost (comma-separated: one run per value).
    #[arg(long, value_delimiter = ',', default_value = "0")]
    loss: Vec<f64>,
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

/// The radio's knobs but the loss: who hears whom, bursts, delays and asynchrony
/// (shared by `afg swarm` and `afg mission`; defaults of [`RadioKnobs::default`]).
#[derive(Args)]
pub struct RadioArgs {
    /// Link robots within this distance (the arena is the unit square) instead of to
    /// their 10 nearest.
    #[arg(long, conflicts_with = "knn")]
    radius: Option<f64>,
    /// Link each robot to its K nearest (kept in both directions).
    #[arg(long, default_value_t = RadioKnobs::default().knn)]
    knn: usize,
    /// Losses come in bursts of this mean length in rounds (Gilbert–Elliott) instead of
    /// independently.
    #[arg(long)]
    burst: Option<f64>,
    /// A delivered message arrives 0..=DELAY rounds late (uniform).
    #[arg(long, default_value_t = RadioKnobs::default().delay)]
    delay: u32,
    /// Asynchronous robots: each wakes in a round with this chance (1 = synchronous;
    /// `--async` is its old spelling).
    #[arg(long, alias = "async", default_value_t = RadioKnobs::default().activation)]
    activation: f64,
}

impl RadioArgs {
    /// The radio of these knobs with a share `loss` of messages lost.
    pub fn knobs(&self, loss: f64) -> RadioKnobs {
        RadioKnobs {
            radius: self.radius,
            knn: self.knn,
            loss,
            burst: self.burst,
            delay: self.delay,
            activation: self.activation,
        }
    }
}

#[derive(Clone, Copy, ValueEnum)]
enum MethodName {
    Grape,
    Auction,
}

/// Runs every combination and prints the table (or JSON), with the figure if asked.
///
/// # Errors
/// A knob out of range, an unreadable input, or a failed write.
pub fn run(args: SwarmArgs) -> Result<()> {
    let grid = grid(&args)?;
    let runs = grid.run_count();
    let bar = afg_eval::report::progress(runs as u64, "swarm runs");
    let on_round = |round: u64| {
        if round.is_multiple_of(100) {
            bar.set_message(format!("swarm run, round {round}"));
        }
    };
    let (cells, reports) = grid.run(|| bar.inc(1), &on_round)?;
    bar.finish_and_clear();
    if let Some(path) = &args.svg {
        let firsts: Vec<(String, SwarmReport)> = reports
            .iter()
            .filter(|(_, r)| r.seed == args.seed)
            .map(|(c, r)| (cells[*c].label(), r.clone()))
            .collect();
        let title = format!(
            "Decentralised allocation over a failing network (GRAPE: {})",
            args.preference.name()
        );
        let svg = afg_eval::figures::swarm_svg(&firsts, &title)?;
        write_atomic_making_dirs(path, svg.as_bytes())?;
    }
    if args.json {
        for (_, report) in &reports {
            println!("{}", serde_json::to_string(report)?);
        }
    } else {
        print!("{}", table(&cells, &reports));
        if let Some(summary) = summary(&cells, &reports) {
            println!("\nBy method, size and network, over the instances:\n\n{summary}");
        }
    }
    Ok(())
}

/// The grid the flags ask for: each method × instance × loss × failing share.
fn grid(args: &SwarmArgs) -> Result<SwarmGrid> {
    let instances = match &args.input {
        Some(path) => read_instances(path)?,
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
    let needs_teams = instances.iter().any(afg_game::Instance::has_teams);
    let methods = args
        .method
        .iter()
        .map(|m| match m {
            MethodName::Grape => SwarmMethod::Grape {
                preference: args.preference,
            },
            MethodName::Auction => SwarmMethod::Auction {
                epsilon: args.epsilon.unwrap_or_else(|| {
                    SwarmKnobs::default_epsilon(afg_mission::MissionMethod::Auction, needs_teams)
                }),
            },
        })
        .collect();
    Ok(SwarmGrid {
        methods,
        instances,
        network: Network {
            partition_until: args.partition_until,
            ..args.radio.knobs(0.0).network()
        },
        losses: args.loss.clone(),
        failing: args.fail.clone(),
        fail_at: args.fail_at,
        detect_after: args.detect_after,
        seeds: args.seed..args.seed + args.seeds as u64,
        max_rounds: args.max_rounds.unwrap_or(0),
        trace: args.svg.is_some(),
    })
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

    /// The auction's ε defaults by the rule `afg mission` and Python use: 0.01 on team
    /// games, 0.001 on the paper's; a given ε is kept.
    #[test]
    fn the_auction_epsilon_defaults_by_the_game() {
        let epsilon = |line: &str| -> f64 {
            let crate::Command::Swarm(args) = crate::parse(line).unwrap() else {
                unreachable!("a swarm command")
            };
            match super::grid(&args).unwrap().methods[..] {
                [afg_baseline::SwarmMethod::Auction { epsilon }] => epsilon,
                _ => unreachable!("one auction"),
            }
        };
        let teams = crate::repo_root().join("datasets/teams-thresholds.jsonl");
        let teams = format!("swarm --method auction --input {}", teams.display());
        assert_eq!(epsilon(&teams), 0.01);
        assert_eq!(epsilon(&format!("{teams} --epsilon 0.05")), 0.05);
        assert_eq!(epsilon("swarm --method auction --robots 20"), 0.001);
    }

    /// Rows that read alike (instances of one size) are summed up by size: two of the
    /// committed threshold games at N = 20 and two at N = 100 give two lines, whose
    /// run counts add up to every run.
    #[test]
    fn instances_of_one_size_are_summed_up() {
        let teams = crate::repo_root().join("datasets/teams-thresholds.jsonl");
        let lines: Vec<String> = std::fs::read_to_string(teams)
            .unwrap()
            .lines()
            .map(str::to_owned)
            .collect();
        let dir = std::env::temp_dir().join(format!("afg-swarm-sizes-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("four.jsonl");
        let four = [0, 1, 10, 11].map(|k| lines[k].clone()).join("\n");
        std::fs::write(&file, four).unwrap();
        let line = format!("swarm --method auction --input {}", file.display());
        let crate::Command::Swarm(args) = crate::parse(&line).unwrap() else {
            unreachable!("a swarm command")
        };
        let (cells, reports) = super::grid(&args).unwrap().run(|| (), &|_| ()).unwrap();
        let text = super::summary(&cells, &reports).expect("a summary");
        let lines: Vec<&str> = text.lines().skip(2).collect();
        assert_eq!(lines.len(), 2, "{text}");
        let runs: usize = (lines.iter())
            .map(|l| {
                l.split('|')
                    .nth(2)
                    .unwrap()
                    .trim()
                    .parse::<usize>()
                    .unwrap()
            })
            .sum();
        assert_eq!(runs, reports.len());
        assert!(
            lines[0].contains("N = 20") && lines[1].contains("N = 100"),
            "{text}"
        );
        assert!(lines[0].contains(" % ("), "{text}");
        // One instance per size: nothing to sum up.
        let one = &cells[..1];
        assert!(super::summary(one, &reports[..1]).is_none());
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
