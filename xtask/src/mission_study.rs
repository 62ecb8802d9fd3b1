//! `cargo xtask mission-study`: allocators in the loop of generated missions, as the
//! Markdown tables of docs/missions.md.

use afg_baseline::Method;
use std::path::{Path, PathBuf};

use afg_mission::{MissionMethod, Preset, SwarmKnobs};
use afg_repro::mission_study::{CentralStudy, SwarmStudy, study, swarm_study};
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
    #[arg(long, default_value_t = SwarmKnobs::default().rounds_per_time)]
    rounds_per_time: f64,
    /// Instead of printing the tables, check that FILE shows them (every number but
    /// the compute times, which are the machine's) under the line `$ cargo xtask
    /// mission-study …` with these same arguments.
    #[arg(long, value_name = "FILE")]
    verify: Option<PathBuf>,
}

/// Runs the study and prints its tables.
pub fn run(args: MissionStudyArgs) -> Result<()> {
    if args.swarm {
        return run_swarm(args);
    }
    let plan = CentralStudy {
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
    show(&text, args.verify.as_deref())
}

/// The decentralised study.
fn run_swarm(args: MissionStudyArgs) -> Result<()> {
    let plan = SwarmStudy {
        robots: args.robots,
        tasks: args.tasks,
        count: args.count,
        presets: args.presets,
        radius_factors: args.radius_factors,
        losses: args.losses,
        methods: args
            .swarm_methods
            .iter()
            .map(|name| match name.parse() {
                Ok(m @ (MissionMethod::Grape | MissionMethod::Auction)) => Ok(m),
                _ => bail!("unknown decentralised method '{name}': grape or auction"),
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
    show(&text, args.verify.as_deref())
}

/// Prints `text`, or checks it against the block of `verify` under this command.
fn show(text: &str, verify: Option<&Path>) -> Result<()> {
    let Some(path) = verify else {
        print!("{text}");
        return Ok(());
    };
    // The command as the page shows it: these arguments without `--verify FILE`.
    let args: Vec<String> = std::env::args().skip(1).collect();
    let at = args
        .iter()
        .position(|a| a == "--verify")
        .unwrap_or(args.len());
    let shown: Vec<&str> = (args.iter().enumerate())
        .filter(|&(i, _)| i != at && i != at + 1)
        .map(|(_, a)| a.as_str())
        .collect();
    let command = format!("$ cargo xtask {}", shown.join(" "));
    let page = std::fs::read_to_string(path)?;
    verify_block(&page, &command, text).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    println!("{}: the tables under `{command}` match", path.display());
    Ok(())
}

/// Checks that the code block of `page` opened by the line `command` holds `text`,
/// compute times (cells ending in a unit of time) aside.
fn verify_block(page: &str, command: &str, text: &str) -> Result<()> {
    let mut lines = page.lines().skip_while(|l| l.trim_end() != command);
    if lines.next().is_none() {
        bail!("no line `{command}`");
    }
    let shown: Vec<String> = lines
        .take_while(|l| !l.starts_with("```"))
        .map(untimed)
        .collect();
    let computed: Vec<String> = text.lines().map(untimed).collect();
    let shown = shown.join("\n");
    let computed = computed.join("\n");
    if shown.trim_end() != computed.trim_end() {
        let first = (shown.lines().zip(computed.lines()))
            .find(|(a, b)| a != b)
            .map_or_else(String::new, |(a, b)| {
                format!(": the page shows\n  {a}\nthe command gives\n  {b}")
            });
        bail!(
            "the tables under `{command}` differ from what it gives{first}\n(rerun it and paste its output)"
        );
    }
    Ok(())
}

/// A table row with its compute times (`12.3 µs`, `4.5 ms`, `1.2 s`) masked.
fn untimed(line: &str) -> String {
    if !line.starts_with('|') {
        return line.trim_end().to_string();
    }
    line.split('|')
        .map(|cell| {
            let timed = ["ns", "µs", "ms", "s"].iter().any(|unit| {
                cell.trim()
                    .strip_suffix(unit)
                    .is_some_and(|v| v.trim_end().parse::<f64>().is_ok() && v.ends_with(' '))
            });
            if timed { " … " } else { cell }
        })
        .collect::<Vec<_>>()
        .join("|")
}

#[cfg(test)]
mod tests {
    use super::{untimed, verify_block};

    const PAGE: &str =
        "text\n```\n$ cargo xtask mission-study --count 1\n| a | 1.50 | 3.2 µs |\n```\n";

    #[test]
    fn a_block_matches_but_its_compute_times_and_nothing_else() {
        assert_eq!(
            untimed("| a | 1.50 | 3.2 µs | 4 s |"),
            "| a | 1.50 | … | … |"
        );
        let command = "$ cargo xtask mission-study --count 1";
        verify_block(PAGE, command, "| a | 1.50 | 9.9 ms |\n").unwrap();
        let err = verify_block(PAGE, command, "| a | 1.51 | 3.2 µs |\n").unwrap_err();
        assert!(err.to_string().contains("| a | 1.50 |"), "{err}");
        assert!(verify_block(PAGE, "$ cargo xtask mission-study", "").is_err());
    }
}
