//! `cargo xtask <command>`: the project's jobs — datasets, solving, benchmarks.

mod bench;
mod bench_opt;
mod crash;
mod curves;
mod datasets;
mod manifest;
mod price;
mod realloc;
mod regret;
mod scale;
mod solve;
mod swarm;
mod tables;
mod train;
mod train_all;

use anyhow::Result;
use clap::{Parser, Subcommand};

/// See the `mimalloc` feature in Cargo.toml.
#[cfg(feature = "mimalloc")]
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// The global allocator this build uses, for benchmark headers.
pub const ALLOCATOR_NAME: &str = if cfg!(feature = "mimalloc") {
    "mimalloc"
} else {
    "system"
};

/// afg project tasks. Run `cargo xtask <command> --help` for each command's options.
#[derive(Parser)]
#[command(name = "cargo xtask", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// The main job: Tables I and II, Fig. 1 and docs/RESULTS.md from committed datasets and weights.
    ReproduceTables(tables::TablesArgs),
    /// Write the fixed test datasets under datasets/ (or verify them with --check).
    GenDatasets(datasets::GenArgs),
    /// Draw your own instances (the paper's distribution, every knob) into a JSON Lines file.
    Gen(datasets::GenCustomArgs),
    /// Solve an instance or a dataset with one allocator and print welfare, % of OPT, NS_rate.
    Solve(solve::SolveArgs),
    /// GRAPE and a decentralised auction over a lossy, late, range-limited network where robots fail mid-run.
    Swarm(swarm::SwarmArgs),
    /// Time the classical allocators over a sweep of N and print a Markdown table.
    BenchBaselines(bench::BenchArgs),
    /// Time the networks: batched forward pass, training step, greedy rollout.
    BenchModels(bench::ModelBenchArgs),
    /// The exact optimum against OR-Tools on the same files, each solution certified.
    BenchOpt(bench_opt::BenchOptArgs),
    /// The learned policy (fast path, blocks, repair) against OPT, DA and greedy up to N = 100 000.
    BenchScale(scale::ScaleArgs),
    /// Train a Q network with DQN or Double DQN (resumable, seeded, with validation curves).
    Train(train::TrainArgs),
    /// Draw validation curves of training runs as an SVG (Fig. 1 style).
    PlotCurves(curves::PlotArgs),
    /// Summarise finished training runs against the classical methods (Markdown).
    TrainingReport(curves::ReportArgs),
    /// Train the price-structured model (ours) by regression on the exact Q* (DAgger).
    TrainPrice(price::PriceArgs),
    /// Train every model the tables use (AFGNet DDQN/DQN and S2V DDQN at N = 20, 60, 100).
    TrainAll(train_all::TrainAllArgs),
    /// Robots leave an optimally allocated instance: warm-start reallocation against OPT from scratch.
    ReallocStudy(realloc::StudyArgs),
    /// Where a trained model loses welfare along its rollouts, against the exact Q*.
    Regret(regret::RegretArgs),
    /// (Re)write manifest.json of finished training runs from their config and log.
    Manifest(manifest::ManifestArgs),
    /// SIGKILL train and train-price at random moments, resume each time, and compare
    /// the final weights with an uninterrupted run's.
    CrashTest(crash::CrashArgs),
}

fn main() -> Result<()> {
    Cli::parse().command.run()
}

impl Command {
    fn run(self) -> Result<()> {
        match self {
            Command::ReproduceTables(args) => tables::run(args),
            Command::GenDatasets(args) => datasets::run(args),
            Command::Gen(args) => datasets::run_custom(args),
            Command::Solve(args) => solve::run(args),
            Command::Swarm(args) => swarm::run(args),
            Command::BenchBaselines(args) => bench::run(args),
            Command::BenchModels(args) => bench::run_models(args),
            Command::BenchOpt(args) => bench_opt::run(args),
            Command::BenchScale(args) => scale::run(args),
            Command::Train(args) => train::run(args),
            Command::PlotCurves(args) => curves::run_plot(args),
            Command::TrainingReport(args) => curves::run_report(args),
            Command::TrainPrice(args) => price::run(args),
            Command::TrainAll(args) => train_all::run_all(args),
            Command::Manifest(args) => manifest::run_manifest(args),
            Command::Regret(args) => regret::run(args),
            Command::ReallocStudy(args) => realloc::run_study(args),
            Command::CrashTest(args) => crash::run(args),
        }
    }
}

/// Parses `cargo xtask LINE` (arguments separated by single spaces).
#[cfg(test)]
fn parse(line: &str) -> Result<Command> {
    let argv = ["cargo xtask"].into_iter().chain(line.split(' '));
    Ok(Cli::try_parse_from(argv)?.command)
}

/// Runs `cargo xtask LINE` (arguments separated by single spaces).
#[cfg(test)]
fn xtask(line: &str) -> Result<()> {
    parse(line)?.run()
}

/// The command-line arguments that give `args` back, in the order its flags are
/// declared: `--flag` for a set switch, `--flag value` for a given value, nothing for an
/// unset option or switch. Values are read through `args`' serde form, whose field names
/// are the flags' ids.
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

/// Parses a count that must be at least 1 (clap's `value_parser`).
pub fn at_least_one(text: &str) -> Result<usize, String> {
    match text.parse::<usize>() {
        Ok(0) => Err("must be at least 1".into()),
        Ok(k) => Ok(k),
        Err(e) => Err(e.to_string()),
    }
}

/// A progress bar on stderr (hidden when stderr is not a terminal).
pub fn progress(len: u64, message: &str) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(len);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} ({eta})")
            .expect("valid template")
            .progress_chars("=> "),
    );
    bar.set_message(message.to_owned());
    bar
}

/// The repository root (xtask lives one level below it).
pub fn repo_root() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("xtask has a parent")
        .to_path_buf()
}

/// Writes an SVG atomically, creating its folder.
pub fn write_svg(out: &std::path::Path, svg: &str) -> Result<()> {
    if let Some(parent) = out.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent)?;
    }
    afg_game::io::write_atomic(out, svg.as_bytes())?;
    Ok(())
}

#[cfg(test)]
mod tests {
    /// The committed price runs' commands are written back as they were given.
    #[test]
    fn command_args_write_a_command_back() {
        for run in [
            "price_n60",
            "ablations/price_n60_expert",
            "ablations/price_n60_qstar",
        ] {
            let dir = crate::repo_root().join("models").join(run);
            let command = afg_learn::PriceRunSummary::load(&dir).unwrap().command;
            let Ok(super::Command::TrainPrice(args)) =
                super::parse(command.strip_prefix("cargo xtask ").unwrap())
            else {
                unreachable!("a train-price command")
            };
            let again = format!(
                "cargo xtask train-price {}",
                super::command_args(&args).join(" ")
            );
            assert_eq!(again, command);
        }
    }
}
