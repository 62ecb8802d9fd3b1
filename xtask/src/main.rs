//! `cargo xtask <command>`: the maintainer's jobs — the tables, datasets, benchmarks,
//! studies — and `train`, the same code as `afg train` (the user's commands are in
//! `afg-cli`).

use anyhow::Result;
use clap::{Parser, Subcommand};
use xtask::{
    bench, bench_opt, bench_schedule, bench_staffing, bench_teams, crash, datasets, grape_fig7,
    mission_study, realloc_study, regret_study, run_manifests, scale, study_families, tables,
    train_all,
};

/// See the `mimalloc` feature in Cargo.toml.
#[cfg(feature = "mimalloc")]
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// afg maintainer tasks (the user's commands: `afg --help`). Run `cargo xtask <command> --help` for each command's options.
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
    /// Train a Q network with DQN or Double DQN (the same command as `afg train`).
    Train(afg_cli::train::TrainArgs),
    /// Train every model the tables use (AFGNet DDQN/DQN and S2V DDQN at N = 20, 60, 100).
    TrainAll(train_all::TrainAllArgs),
    /// Write the fixed test datasets under datasets/ (or verify them with --check).
    GenDatasets(datasets::GenArgs),
    /// Time the classical allocators over a sweep of N and print a Markdown table.
    BenchBaselines(bench::BenchArgs),
    /// Time the networks: batched forward pass, training step, greedy rollout.
    BenchModels(bench::ModelBenchArgs),
    /// The exact optimum against OR-Tools on the same files, each solution certified.
    BenchOpt(bench_opt::BenchOptArgs),
    /// The team-threshold game on scarce instances: afg's exact solver (bound and gap) beside CP-SAT and HiGHS, and every allocator that plays it.
    BenchTeams(bench_teams::BenchTeamsArgs),
    /// afg's scheduler and bound on DCMRTA's published test set, HeteroMRTA's skill family and at scale; CP-SAT beside it.
    BenchSchedule(bench_schedule::BenchScheduleArgs),
    /// The staffing model (ours) on held-out team games: against the optimum, every hand-written allocator, and afg, CP-SAT and HiGHS given its time.
    BenchStaffing(bench_staffing::BenchStaffingArgs),
    /// Staffing models (ours) trained on one family, on a mixture and on the mixture without each family, tested on every family (docs/families.md).
    StudyFamilies(study_families::StudyFamiliesArgs),
    /// The optimum re-solved after one event against from scratch; whole missions with allocators in the loop.
    BenchMission(bench::mission_loop::BenchMissionArgs),
    /// The learned policy (fast path, blocks, repair) against OPT, DA and greedy up to N = 100 000.
    BenchScale(scale::ScaleArgs),
    /// Robots leave an optimally allocated instance: warm-start reallocation against OPT from scratch.
    ReallocStudy(realloc_study::StudyArgs),
    /// GRAPE's published Fig. 7 runs (datasets/grape-fig7) beside afg's GRAPE and OPT.
    GrapeFig7(grape_fig7::GrapeArgs),
    /// Allocators in the loop of generated missions (waves, Poisson, attrition), from scratch and warm-started.
    MissionStudy(mission_study::MissionStudyArgs),
    /// Where a trained model loses welfare along its rollouts, against the exact Q*.
    Regret(regret_study::RegretArgs),
    /// (Re)write manifest.json of finished training runs from their config and log.
    Manifest(run_manifests::ManifestArgs),
    /// SIGKILL `afg train` and `afg train-price` at random moments, resume each time, and
    /// compare the final weights with an uninterrupted run's.
    CrashTest(crash::CrashArgs),
    /// An `afg` command run inside this binary (for crash-test, which kills it).
    #[command(hide = true)]
    Afg {
        /// The afg command.
        #[command(subcommand)]
        command: afg_cli::Command,
    },
}

/// Exit status 0 on success, 1 after one line `error: …` on stderr, 2 for a usage error.
fn main() -> std::process::ExitCode {
    afg_eval::report::exit_code(Cli::parse().command.run())
}

impl Command {
    fn run(self) -> Result<()> {
        match self {
            Command::ReproduceTables(args) => tables::run(args),
            Command::Train(args) => afg_cli::train::run(args, "cargo xtask train"),
            Command::TrainAll(args) => train_all::run_all(args),
            Command::GenDatasets(args) => datasets::run(args),
            Command::BenchBaselines(args) => bench::run(args),
            Command::BenchModels(args) => bench::run_models(args),
            Command::BenchOpt(args) => bench_opt::run(args),
            Command::BenchTeams(args) => bench_teams::run(args),
            Command::BenchSchedule(args) => bench_schedule::run(args),
            Command::BenchStaffing(args) => bench_staffing::run(args),
            Command::StudyFamilies(args) => study_families::run(args),
            Command::BenchMission(args) => bench::mission_loop::run(args),
            Command::BenchScale(args) => scale::run(args),
            Command::ReallocStudy(args) => realloc_study::run(args),
            Command::GrapeFig7(args) => grape_fig7::run(args),
            Command::MissionStudy(args) => mission_study::run(args),
            Command::Regret(args) => regret_study::run(args),
            Command::Manifest(args) => run_manifests::run_manifest(args),
            Command::CrashTest(args) => crash::run(args),
            Command::Afg { command } => command.run(),
        }
    }
}
