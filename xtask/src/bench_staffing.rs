//! `cargo xtask bench-staffing`: the staffing model (ours) on held-out scarce team
//! games (thresholds, and skills with `--skills`) against the certified optimum (or its bound), every hand-written allocator
//! (the model's own pipeline with no network, a knapsack over each task's nearest
//! robots, included), afg's exact solver, CP-SAT and HiGHS given the model's own time
//! on each instance.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use afg_baseline::{AllocError, Allocator, TeamOptimum};
use afg_game::fs::write_atomic;
use afg_game::io::dataset_to_jsonl;
use afg_game::{GameSize, Instance};
use afg_learn::price::PriceNetConfig;
use afg_learn::run::{ModelOptions, load_model};
use afg_learn::staffing::StaffingPolicy;
use anyhow::{Context, Result};
use clap::Args;
use serde::Serialize;

use crate::bench::runs::{check_python, measure_rows, scratch_dir};
use crate::bench_teams::{ALLOCATORS, SkillFlags, peer, scarce};

/// The options of `cargo xtask bench-staffing`.
#[derive(Args)]
pub struct BenchStaffingArgs {
    /// The staffing model's run directory.
    #[arg(long, default_value = "models/ours/staffing_teams")]
    model: PathBuf,
    /// Sizes as NxM; thresholds uniform in [N/M, 2N/M] (the training games' kind).
    #[arg(long, value_delimiter = ',', default_values = ["100x10", "1000x50", "10000x100"])]
    cases: Vec<GameSize>,
    /// The games' skills (give the model's own training skills: `train-staffing
    /// --skills`).
    #[command(flatten)]
    skills: SkillFlags,
    /// Instances per size (seeds seed, seed + 1, …; training used seeds from 2^62 and
    /// validation from 2^63, so these are held out).
    #[arg(long, default_value_t = 5)]
    instances: usize,
    /// Seed of the first instance.
    #[arg(long, default_value_t = 54)]
    seed: u64,
    /// afg's exact solver's time limit per instance, seconds (the reference: its
    /// proven optimum, or its bound where it stops).
    #[arg(long, default_value_t = 10.0)]
    time_limit: f64,
    /// A Python with ortools, highspy and numpy for CP-SAT and HiGHS given the model's
    /// time (see `cargo xtask bench-teams --help`).
    #[arg(long)]
    python: Option<PathBuf>,
    /// Threads of CP-SAT's and HiGHS' own search (default: every core).
    #[arg(long)]
    threads: Option<usize>,
    /// Run the peers on sizes up to this N only.
    #[arg(long, default_value_t = 1000)]
    peers_up_to: usize,
    /// Folder for the instance files (kept); default: a temporary folder.
    #[arg(long)]
    dir: Option<PathBuf>,
    /// Print JSON lines (one per instance) instead of the Markdown table.
    #[arg(long)]
    json: bool,
}

/// One method's welfare (`None`: refused or unsettled) and seconds.
#[derive(Serialize)]
struct Run {
    name: String,
    welfare: Option<f64>,
    seconds: f64,
}

/// One instance's measurements.
#[derive(Serialize)]
struct Row {
    robots: usize,
    tasks: usize,
    seed: u64,
    /// The exact solver's proven bound (its welfare where proven).
    bound: f64,
    proven: bool,
    /// The model, then the hand-written allocators, then the solvers at the model's time.
    runs: Vec<Run>,
}

fn timed(name: &str, f: impl FnOnce() -> Result<Option<f64>>) -> Result<Run> {
    let start = Instant::now();
    let welfare = f()?;
    Ok(Run {
        name: name.to_owned(),
        welfare,
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// Runs `cargo xtask bench-staffing`.
pub fn run(args: BenchStaffingArgs) -> Result<()> {
    let dir = scratch_dir(args.dir.as_deref(), "bench-staffing")?;
    if let Some(python) = &args.python {
        check_python(python, &["ortools", "highspy", "numpy"])?;
    }
    let model = load_model(&args.model, ModelOptions::default())
        .with_context(|| format!("--model {}", args.model.display()))?;
    let runs: Vec<(GameSize, u64)> = args
        .cases
        .iter()
        .flat_map(|&c| (args.seed..args.seed + args.instances as u64).map(move |s| (c, s)))
        .collect();
    let rows = measure_rows(
        "bench-staffing",
        &runs,
        args.json,
        |(c, seed)| format!("{c} seed {seed}"),
        |&(case, seed)| measure(case, seed, model.as_ref(), &args, &dir),
    )?;
    if !args.json {
        print!("{}", markdown(&rows, &args));
    }
    Ok(())
}

fn measure(
    case: GameSize,
    seed: u64,
    model: &dyn Allocator,
    args: &BenchStaffingArgs,
    dir: &Path,
) -> Result<Row> {
    let inst = scarce(case, seed, args.skills.knobs()?.as_ref())?;
    let one_core = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    let exact = TeamOptimum::with_time_limit(args.time_limit).context("--time-limit")?;
    let exact = one_core.install(|| exact.solve(&inst))?;
    let skills = args.skills.knobs()?.is_some();
    let mut runs = one_core.install(|| hand_written(&inst, case, seed, model, skills))?;
    let equal = Duration::from_secs_f64(runs[0].seconds);
    runs.push(one_core.install(|| {
        timed("afg opt at the model's time", || {
            Ok(Some(
                TeamOptimum {
                    time_limit: Some(equal),
                    ..TeamOptimum::default()
                }
                .solve(&inst)?
                .welfare,
            ))
        })
    })?);
    if let Some(python) = args
        .python
        .as_ref()
        .filter(|_| case.robots <= args.peers_up_to)
    {
        let file = dir.join(format!(
            "staffing_n{}_m{}_seed{seed}.jsonl",
            case.robots, case.tasks
        ));
        write_atomic(
            &file,
            dataset_to_jsonl(std::slice::from_ref(&inst)).as_bytes(),
        )?;
        for (solver, name) in [("cpsat", "CP-SAT"), ("highs", "HiGHS")] {
            let found = peer(
                python,
                solver,
                equal.as_secs_f64(),
                args.threads,
                &file,
                &inst,
            )?;
            runs.push(Run {
                name: format!("{name} at the model's time"),
                welfare: found.welfare,
                seconds: found.seconds,
            });
        }
    }
    Ok(Row {
        robots: case.robots,
        tasks: case.tasks,
        seed,
        bound: exact.bound,
        proven: exact.proven,
        runs,
    })
}

/// The model, then every hand-written allocator: the model's pipeline with no
/// network (reading skills where the games have them), `opt`'s own first answer (its
/// dive), and every allocator that plays the game (GRAPE DA decentralised up to
/// N = 1 000: it grows as N²).
fn hand_written(
    inst: &Instance,
    case: GameSize,
    seed: u64,
    model: &dyn Allocator,
    skills: bool,
) -> Result<Vec<Run>> {
    let welfare_of = |a: Result<afg_baseline::Allocation, AllocError>| -> Result<Option<f64>> {
        match a {
            Ok(out) => Ok(Some(inst.welfare(&out.assignment))),
            Err(AllocError::NotConverged { .. } | AllocError::TeamsNotSupported { .. }) => Ok(None),
            Err(e) => Err(e.into()),
        }
    };
    let hand = StaffingPolicy::untrained(PriceNetConfig { hidden: 1, seed: 0 }, skills);
    let mut runs = vec![
        timed("staffing model (ours)", || welfare_of(model.allocate(inst)))?,
        timed("knapsack over nearest robots (ours)", || {
            welfare_of(hand.allocate(inst))
        })?,
        timed("opt's dive", || {
            let half =
                |root: &_, fractional: &_| TeamOptimum::half_rounding(inst, root, fractional);
            Ok(Some(TeamOptimum::dive(inst, half).1))
        })?,
    ];
    for method in ALLOCATORS
        .iter()
        .filter(|m| case.robots <= 1000 || !m.label().contains("decentralised"))
    {
        runs.push(timed(method.label(), || {
            welfare_of(method.allocator(seed).allocate(inst))
        })?);
    }
    Ok(runs)
}

fn markdown(rows: &[Row], args: &BenchStaffingArgs) -> String {
    let mut md = format!(
        "Held-out {}{} per size, seeds from {}); % of afg's proven \
         bound (the optimum where proven: {}s limit, one core), mean, and time per instance. \
         The solvers at the model's time get, on each instance, the time the model took.\n\n| N | M | proven |",
        match args.skills.knobs() {
            Ok(Some(_)) => format!("scarce games ({}; ", args.skills.game_text()),
            _ => "scarce threshold games (".to_owned(),
        },
        args.instances,
        args.seed,
        args.time_limit
    );
    let Some(first) = rows.first() else {
        return md;
    };
    let names: Vec<String> = first.runs.iter().map(|r| r.name.clone()).collect();
    for name in &names {
        md += &format!(" {name} |");
    }
    md += "\n|---|---|---|";
    md += &"---|".repeat(names.len());
    md.push('\n');
    for case in &args.cases {
        let rows: Vec<&Row> = rows
            .iter()
            .filter(|r| (r.robots, r.tasks) == (case.robots, case.tasks))
            .collect();
        if rows.is_empty() {
            continue;
        }
        let proven = rows.iter().filter(|r| r.proven).count();
        md += &format!(
            "| {} | {} | {proven}/{} |",
            case.robots,
            case.tasks,
            rows.len()
        );
        for name in &names {
            let cells: Vec<(Option<f64>, f64, f64)> = rows
                .iter()
                .filter_map(|r| {
                    r.runs
                        .iter()
                        .find(|x| &x.name == name)
                        .map(|x| (x.welfare, x.seconds, r.bound))
                })
                .collect();
            md += &cell(&cells, rows.len());
        }
        md.push('\n');
    }
    md
}

/// A method's cell: the mean % of the bound and time, "none found on k/n" where it
/// found nothing on some instances, "—" where it did not run.
fn cell(cells: &[(Option<f64>, f64, f64)], instances: usize) -> String {
    if cells.len() < instances {
        return " — |".into();
    }
    let missing = cells.iter().filter(|c| c.0.is_none()).count();
    if missing > 0 {
        return format!(" none found or refused on {missing}/{instances} |");
    }
    let n = cells.len() as f64;
    let share = cells
        .iter()
        .map(|c| 100.0 * c.0.unwrap_or(0.0) / c.2)
        .sum::<f64>()
        / n;
    let seconds = cells.iter().map(|c| c.1).sum::<f64>() / n;
    format!(" {share:.2} % ({}) |", duration(seconds))
}

/// Seconds as read: milliseconds below one second.
fn duration(seconds: f64) -> String {
    if seconds < 1.0 {
        format!("{:.1} ms", 1e3 * seconds)
    } else {
        format!("{seconds:.2} s")
    }
}
