//! The `afg` command line as a library: [`Cli`] parses a command, [`Command::run`] runs it.
//!
//! `cargo install --path crates/afg-cli` installs the `afg` binary (or run it in place with
//! `cargo afg …`). Its commands:
//!
//! | command | what it does | module |
//! |---|---|---|
//! | `afg solve` | one allocator (or a trained model) on your instances or a committed dataset | [`solve`] |
//! | `afg score` | anyone's assignment against the game: % of OPT, stability, who would move | [`score`] |
//! | `afg gen` | your own instances from the paper's distribution | [`generate`] |
//! | `afg swarm` | GRAPE and a decentralised auction over a failing network | [`swarm`] |
//! | `afg mission` | missions over time: draw one, run allocators in the loop, compare them | [`mission`] |
//! | `afg train` | a Q network by DQN or Double DQN, resumable | [`train`] |
//! | `afg train-price` | the price model (ours) | [`price`] |
//! | `afg train-staffing` | the staffing model (ours), team games | [`staffing`] |
//! | `afg plot-curves`, `afg training-report` | training runs as an SVG or a Markdown table | [`curves`] |
//! | `afg migrate` | run directories of an older afg brought to the current format | [`migrate`] |
//!
//! The maintainer's commands (`cargo xtask reproduce-tables`, benchmarks, the dataset
//! check) live in the repository's `xtask` and call this library.
//!
//! # Examples
//! ```
//! use afg_cli::Cli;
//! use clap::Parser;
//! let cli = Cli::try_parse_from(["afg", "gen", "--robots", "20", "--out", "x.jsonl"])?;
//! assert!(matches!(cli.command, afg_cli::Command::Gen(_)));
//! # Ok::<(), clap::Error>(())
//! ```

pub mod curves;
mod exact_progress;
pub mod generate;
pub mod migrate;
pub mod mission;
pub mod price;
pub mod realloc;
pub mod schedule;
pub mod score;
pub mod settings;
pub mod solve;
pub mod staffing;
pub mod swarm;
pub mod train;

#[cfg(test)]
use std::path::Path;

use afg_game::Named;
use anyhow::Result;
use clap::{Parser, Subcommand};

/// Multi-robot task allocation as an alliance formation game: solve, draw, simulate, train.
/// Run `afg <command> --help` for each command's options.
#[derive(Parser)]
#[command(name = "afg", version, about)]
pub struct Cli {
    /// The command.
    #[command(subcommand)]
    pub command: Command,
}

/// The commands of `afg`.
#[derive(Subcommand)]
pub enum Command {
    /// Solve an instance or a dataset with one allocator and print welfare, % of OPT, NS_rate.
    Solve(solve::SolveArgs),
    /// Score any assignment file against its instances: welfare, % of OPT, coalitions, stability, who would move.
    Score(score::ScoreArgs),
    /// Draw your own instances (the paper's distribution, every knob) into a JSON Lines file.
    Gen(generate::GenArgs),
    /// GRAPE and a decentralised auction over a lossy, late, range-limited network where robots fail mid-run.
    Swarm(swarm::SwarmArgs),
    /// Missions over time: tasks appear and are worked off, robots travel and fail, an allocator decides at every event.
    #[command(subcommand)]
    Mission(mission::MissionCommand),
    /// Schedules over time: robots perform sequences of team and skill tasks from depots, scored by the makespan (DCMRTA's test set).
    #[command(subcommand)]
    Schedule(schedule::ScheduleCommand),
    /// Train a Q network with DQN or Double DQN (resumable, seeded, with validation curves).
    Train(train::TrainArgs),
    /// Train the price-structured model (ours) by regression on the exact Q* (DAgger).
    TrainPrice(price::PriceArgs),
    /// Train the staffing model (ours) for team games on the staffing of certified optima.
    TrainStaffing(staffing::StaffingArgs),
    /// Draw validation curves of training runs as an SVG (Fig. 1 style).
    PlotCurves(curves::PlotArgs),
    /// Summarise finished training runs against the classical methods (Markdown).
    TrainingReport(curves::ReportArgs),
    /// Bring run directories written by an older afg to the current format, in place.
    Migrate(migrate::MigrateArgs),
}

impl Command {
    /// Runs the command.
    ///
    /// # Errors
    /// Whatever the command refuses or fails at, with the file or flag to fix.
    pub fn run(self) -> Result<()> {
        match self {
            Command::Solve(args) => solve::run(args),
            Command::Score(args) => score::run(args),
            Command::Gen(args) => generate::run(args),
            Command::Swarm(args) => swarm::run(args),
            Command::Mission(command) => mission::run(command),
            Command::Schedule(command) => schedule::run(command),
            Command::Train(args) => train::run(args, "afg train"),
            Command::TrainPrice(args) => price::run(args),
            Command::TrainStaffing(args) => staffing::run(args),
            Command::PlotCurves(args) => curves::run_plot(args),
            Command::TrainingReport(args) => curves::run_report(args),
            Command::Migrate(args) => migrate::run(args),
        }
    }
}

/// Parses `afg LINE` (arguments separated by single spaces).
#[cfg(test)]
fn parse(line: &str) -> Result<Command> {
    let argv = ["afg"].into_iter().chain(line.split(' '));
    Ok(Cli::try_parse_from(argv)?.command)
}

/// Runs `afg LINE` (arguments separated by single spaces).
#[cfg(test)]
fn afg(line: &str) -> Result<()> {
    parse(line)?.run()
}

/// The repository root, where the tests find the committed datasets and models.
#[cfg(test)]
fn repo_root() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The command-line arguments that give `args` back, in the order its flags are
/// declared: `--flag` for a set switch, `--flag value` for a given value, nothing for an
/// unset option or switch. Values are read through `args`' serde form, whose field names
/// are the flags' ids.
///
/// # Panics
/// If `args` does not serialise to a JSON object of strings, numbers and booleans.
///
/// # Examples
/// ```
/// #[derive(clap::Args, serde::Serialize)]
/// struct Knobs {
///     #[arg(long)]
///     robots: usize,
///     #[arg(long)]
///     repair: bool,
/// }
/// let line = afg_cli::command_args(&Knobs { robots: 20, repair: true });
/// assert_eq!(line, ["--robots", "20", "--repair"]);
/// ```
pub fn command_args<A: clap::Args + serde::Serialize>(args: &A) -> Vec<String> {
    use serde_json::Value;
    let values = serde_json::to_value(args).expect("arguments serialise to JSON");
    let flags = A::augment_args(clap::Command::new("args"));
    let mut out = Vec::new();
    for flag in flags.get_arguments() {
        let (Some(long), Some(value)) = (flag.get_long(), values.get(flag.get_id().as_str()))
        else {
            continue;
        };
        let value = match value {
            Value::Null | Value::Bool(false) => continue,
            Value::Bool(true) => None,
            Value::String(s) => Some(s.clone()),
            Value::Number(n) => Some(n.as_u64().map_or_else(
                || n.as_f64().expect("a finite number").to_string(),
                |u| u.to_string(),
            )),
            other => unreachable!("arguments hold no {other}"),
        };
        out.push(format!("--{long}"));
        out.extend(value);
    }
    out
}

/// Refuses an output path (`--flag`, where given) that names one of the `inputs`:
/// writing it would destroy what the command reads.
///
/// # Errors
/// One line naming the flag and the path.
pub(crate) fn refuse_overwriting_inputs(
    outputs: &[(&str, Option<&std::path::Path>)],
    inputs: &[&std::path::Path],
) -> Result<()> {
    let inputs: Vec<_> = inputs
        .iter()
        .filter_map(|p| p.canonicalize().ok())
        .collect();
    for &(flag, path) in outputs {
        let Some(path) = path else { continue };
        if path.canonicalize().is_ok_and(|out| inputs.contains(&out)) {
            anyhow::bail!(
                "--{flag} {} is an input of this command; writing it would overwrite it: choose another path",
                path.display()
            );
        }
    }
    Ok(())
}

/// Warns on standard error about the tasks of `instances` that no team can ever staff
/// (a threshold above N or the capacity, a skill nobody holds enough of): legal, they
/// earn nothing.
pub(crate) fn warn_unstaffable(instances: &[afg_game::Instance]) {
    let unstaffable: Vec<Vec<usize>> = (instances.iter())
        .map(|inst| inst.unstaffable_tasks().iter().map(|j| j.index()).collect())
        .collect();
    warn_unstaffable_tasks("instance", &unstaffable);
}

/// Warns of the tasks no team can staff in each of several games (`unstaffable[g]`,
/// by task index), naming the game (`what` and its index) where there are several.
pub(crate) fn warn_unstaffable_tasks(what: &str, unstaffable: &[Vec<usize>]) {
    for (index, tasks) in unstaffable.iter().enumerate() {
        if let Some(warning) = afg_game::unstaffable_warning(tasks) {
            let which = if unstaffable.len() > 1 {
                format!("{what} {index}: ")
            } else {
                String::new()
            };
            eprintln!("warning: {which}{warning}");
        }
    }
}

/// Parses a count that must be at least 1 (clap's `value_parser`).
///
/// # Errors
/// A message for zero or for text that is not a count.
///
/// # Examples
/// ```
/// assert_eq!(afg_cli::at_least_one("3"), Ok(3));
/// assert!(afg_cli::at_least_one("0").is_err());
/// ```
pub fn at_least_one(text: &str) -> Result<usize, String> {
    match text.parse::<usize>() {
        Ok(0) => Err("must be at least 1".into()),
        Ok(k) => Ok(k),
        Err(e) => Err(e.to_string()),
    }
}

/// A value parser for an enum a user names ([`Named`]): its names are the possible
/// values that `--help` lists and that a typo is told about.
///
/// # Examples
/// ```
/// use afg_game::Preference;
/// #[derive(clap::Parser)]
/// struct Args {
///     #[arg(long, value_parser = afg_cli::choice::<Preference>())]
///     preference: Preference,
/// }
/// use clap::Parser;
/// let args = Args::try_parse_from(["x", "--preference", "selfish"])?;
/// assert_eq!(args.preference, Preference::Selfish);
/// assert!(Args::try_parse_from(["x", "--preference", "greedy"]).is_err());
/// # Ok::<(), clap::Error>(())
/// ```
pub fn choice<T: Named + Send + Sync>() -> impl clap::builder::TypedValueParser<Value = T> {
    use clap::builder::TypedValueParser as _;
    clap::builder::PossibleValuesParser::new(T::ALL.iter().map(|v| v.name()))
        .map(|name| T::from_name(&name).expect("clap checked the name"))
}

/// Sets each named field of a configuration to the value given for it, where one was
/// given: `set_given!(config; lr = args.lr, network.hidden = args.hidden)`.
macro_rules! set_given {
    ($config:expr; $($($field:ident).+ = $value:expr),* $(,)?) => {
        $(if let Some(value) = $value {
            $config$(.$field)+ = value;
        })*
    };
}
pub(crate) use set_given;
