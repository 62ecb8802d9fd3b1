//! `cargo xtask bench-opt`: afg's exact optimum against OR-Tools' SimpleMinCostFlow on
//! the same instance files, every timed solution certified by its prices.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

use crate::bench::runs::{check_python, measure_rows, scratch_dir};
use crate::bench::{clocked, median_of};
use afg_baseline::{Allocator, Greedy, Nearest, Optimum, verify_optimal};
use afg_eval::report::duration;
use afg_game::fs::write_atomic;
use afg_game::io::{dataset_to_jsonl, read_dataset};
use afg_game::{Assignment, GeneratorConfig, Instance, TaskId};
use anyhow::{Context, Result, bail};
use clap::Args;
use serde::Serialize;

/// The options of `cargo xtask bench-opt`.
#[derive(Args)]
pub struct BenchOptArgs {
    /// Sizes as N x M.
    #[arg(long, value_delimiter = ',', default_values = [
        "1000x5", "1000x50", "10000x5", "10000x50", "10000x500",
        "100000x5", "100000x50", "1000000x5", "1000000x50",
    ])]
    cases: Vec<Case>,
    /// Seed of every instance: the files are `afg gen --robots N --tasks M --seed S`.
    #[arg(long, default_value_t = 11)]
    seed: u64,
    /// A Python with OR-Tools and numpy, for the OR-Tools column (e.g. after
    /// `python3 -m venv .venv-bench && .venv-bench/bin/pip install ortools numpy`,
    /// pass `.venv-bench/bin/python`). Without it the column is left out.
    #[arg(long)]
    python: Option<PathBuf>,
    /// Time budget per measurement: repeat until it is spent (at least once, at most 20 runs).
    #[arg(long, default_value_t = 1.0)]
    seconds: f64,
    /// Largest N for the reference solver (robot by robot, O(N M² log N)).
    #[arg(long, default_value_t = 100_000)]
    reference_up_to: usize,
    /// Folder for the instance files (kept); default: a temporary folder.
    #[arg(long)]
    dir: Option<PathBuf>,
    /// Print JSON lines (one per case) instead of the Markdown table.
    #[arg(long)]
    json: bool,
}

/// One size of a benchmark, written `NxM`.
pub type Case = afg_game::GameSize;

/// What one case measured; times are medians over the repeats.
#[derive(Serialize)]
struct Row {
    robots: usize,
    tasks: usize,
    /// Peak RSS of generating the instance and solving it once (nothing else held).
    opt_peak_rss_mib: Option<f64>,
    #[serde(with = "secs")]
    opt: Duration,
    #[serde(with = "secs")]
    opt_one_thread: Duration,
    /// The same solver from zero prices (the nearest-task balance), no subsample levels.
    #[serde(with = "secs")]
    opt_from_zero: Duration,
    /// The largest duality gap over every timed solution.
    certified_gap: f64,
    /// Units the multi-scale solver routed at the finest level.
    units_routed: u64,
    #[serde(with = "secs_opt")]
    reference: Option<Duration>,
    ortools: Option<OrTools>,
    #[serde(with = "secs")]
    read_distances: Duration,
    #[serde(with = "secs")]
    greedy: Duration,
    #[serde(with = "secs")]
    nearest: Duration,
}

/// OR-Tools' time and how its optimum compares.
#[derive(Serialize)]
struct OrTools {
    #[serde(with = "secs")]
    solve: Duration,
    /// |W(afg) − W(OR-Tools)| / |W(afg)|.
    welfare_difference: f64,
    cost_scale: f64,
}

/// Runs `cargo xtask bench-opt`: the exact optimum against OR-Tools, every solution certified.
pub fn run(args: BenchOptArgs) -> Result<()> {
    let scratch = scratch_dir(args.dir.as_deref(), "bench-opt")?;
    if let Some(python) = &args.python {
        check_python(python, &["ortools", "numpy"])?;
    }
    let describe = |c: &Case| format!("N = {} M = {}", c.robots, c.tasks);
    let rows = measure_rows("bench-opt", &args.cases, args.json, describe, |&case| {
        measure(case, &args, &scratch)
    })?;
    if !args.json {
        print!("{}", markdown(&rows, rayon::current_num_threads()));
    }
    Ok(())
}

fn measure(case: Case, args: &BenchOptArgs, dir: &Path) -> Result<Row> {
    crate::bench::reset_peak_rss();
    let opt_peak_rss_mib = peak_rss_of_optimum(case, args.seed)?;
    let file = dir.join(format!(
        "n{}_m{}_seed{}.jsonl",
        case.robots, case.tasks, args.seed
    ));
    let generated = GeneratorConfig::paper(case.robots, case.tasks, args.seed).generate()?;
    write_atomic(&file, dataset_to_jsonl(&[generated]).as_bytes())?;
    let inst = read_dataset(&file)?.remove(0);
    let budget = args.seconds;
    let multi_scale = || Ok(Optimum.with_prices(&inst));
    let (opt, gap, welfare) = time_optimum(&inst, budget, multi_scale)?;
    let one = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    let (opt_one_thread, ..) = one.install(|| time_optimum(&inst, budget, multi_scale))?;
    let zeros = vec![0.0; case.tasks];
    let from_zero = || Ok(Optimum.with_prices_from(&inst, &zeros)?);
    let (opt_from_zero, zero_gap, _) = time_optimum(&inst, budget, from_zero)?;
    let units_routed = Optimum.allocate(&inst)?.stats.iterations;
    let reference = (case.robots <= args.reference_up_to)
        .then(|| timed(args.seconds, || Optimum.complete(&inst, &empty(&inst))));
    let reference = match reference {
        Some(r) => Some(r?.0),
        None => None,
    };
    let ortools = match &args.python {
        Some(python) => Some(ortools(python, &file, &inst, welfare)?),
        None => None,
    };
    let (read_distances, _) = timed(args.seconds, || {
        anyhow::Ok(std::hint::black_box(nearest_pass(&inst)))
    })?;
    let (greedy, _) = timed(args.seconds, || Greedy.allocate(&inst))?;
    let (nearest, _) = timed(args.seconds, || Nearest.allocate(&inst))?;
    Ok(Row {
        robots: case.robots,
        tasks: case.tasks,
        opt_peak_rss_mib,
        opt,
        opt_one_thread,
        opt_from_zero,
        certified_gap: gap.max(zero_gap),
        units_routed,
        reference,
        ortools,
        read_distances,
        greedy,
        nearest,
    })
}

/// The peak RSS (MiB) of making the instance and solving it once, before anything
/// else of the case is in memory.
fn peak_rss_of_optimum(case: Case, seed: u64) -> Result<Option<f64>> {
    let inst = GeneratorConfig::paper(case.robots, case.tasks, seed).generate()?;
    std::hint::black_box(Optimum.with_prices(&inst));
    Ok(crate::bench::peak_rss_mib())
}

fn empty(inst: &Instance) -> Assignment {
    Assignment::unassigned(inst.num_robots(), inst.num_tasks())
}

/// Median time of `solve` (an exact solver returning its prices) after one untimed
/// run, and the largest duality gap of the solutions timed (each certified), and the
/// welfare.
fn time_optimum(
    inst: &Instance,
    budget_s: f64,
    solve: impl Fn() -> Result<(Assignment, Vec<f64>)>,
) -> Result<(Duration, f64, f64)> {
    let mut gap = 0.0f64;
    // The first touch of fresh memory is not the solver's work.
    std::hint::black_box(solve()?);
    let (time, welfare) = median_of(budget_s, 20, || {
        let (took, (assignment, prices)) = clocked(&solve)?;
        let proof = verify_optimal(inst, &assignment, &prices)?;
        gap = gap.max(proof.gap());
        Ok::<_, anyhow::Error>((took, proof.welfare))
    })?;
    Ok((time, gap, welfare))
}

/// Median time of `job` over repeats within `budget_s` (at least one, at most 20).
fn timed<T, E: Into<anyhow::Error>>(
    budget_s: f64,
    mut job: impl FnMut() -> Result<T, E>,
) -> Result<(Duration, T)> {
    median_of(budget_s, 20, || clocked(&mut job)).map_err(Into::into)
}

/// The floor of any method that looks at every robot–task pair: one pass computing
/// the N · M distances, keeping each robot's nearest task.
fn nearest_pass(inst: &Instance) -> usize {
    inst.robot_ids()
        .map(|i| {
            inst.task_ids()
                .map(|j| inst.distance(i, j))
                .enumerate()
                .fold(
                    (0, f64::INFINITY),
                    |b, (j, d)| if d < b.1 { (j, d) } else { b },
                )
                .0
        })
        .sum()
}

/// Runs `scripts/ortools_opt.py` on `file` and compares its optimum's welfare.
fn ortools(python: &Path, file: &Path, inst: &Instance, welfare: f64) -> Result<OrTools> {
    #[derive(serde::Deserialize)]
    struct Solved {
        seconds: f64,
        scale: f64,
        tasks: Vec<u32>,
    }
    let out = file.with_extension("ortools.json");
    let repeats = if inst.num_robots() >= 100_000 {
        "1"
    } else {
        "3"
    };
    let script = crate::repo_root().join("scripts").join("ortools_opt.py");
    let status = Command::new(python)
        .arg(&script)
        .args([file, &out])
        .args(["--repeats", repeats])
        .status()?;
    if !status.success() {
        bail!("{} failed on {}", script.display(), file.display());
    }
    let mut solved: Vec<Solved> = serde_json::from_slice(&std::fs::read(&out)?)?;
    let solved = solved.pop().context("OR-Tools returned no solution")?;
    let tasks = solved.tasks.iter().map(|&j| Some(TaskId(j))).collect();
    let theirs = inst.welfare(&Assignment::from_tasks(inst, tasks)?);
    Ok(OrTools {
        solve: Duration::from_secs_f64(solved.seconds),
        welfare_difference: (welfare - theirs).abs() / welfare.abs().max(1e-300),
        cost_scale: solved.scale,
    })
}

fn markdown(rows: &[Row], threads: usize) -> String {
    let mut md = format!(
        "| N | M | afg OPT ({threads} threads) | afg OPT (1 thread) | OR-Tools solve() | OR-Tools / afg \
         | welfare rel. diff. | certified gap | units routed | from zero prices | reference (robot by robot) \
         | read N·M distances | OPT / read | greedy | greedy / read | nearest | OPT peak RSS |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n"
    );
    let ratio = |a: Duration, b: Duration| format!("{:.1}×", a.as_secs_f64() / b.as_secs_f64());
    for r in rows {
        let (ort, vs, diff) = match &r.ortools {
            Some(o) => (
                duration(o.solve),
                ratio(o.solve, r.opt),
                format!("{:.1e}", o.welfare_difference),
            ),
            None => ("—".into(), "—".into(), "—".into()),
        };
        let reference = r.reference.map_or("—".into(), duration);
        let rss = r
            .opt_peak_rss_mib
            .map_or("—".into(), |m| format!("{m:.0} MiB"));
        md += &format!(
            "| {} | {} | {} | {} | {ort} | {vs} | {diff} | {:.1e} | {} | {} | {reference} | {} | {} | {} | {} | {} | {rss} |\n",
            r.robots,
            r.tasks,
            duration(r.opt),
            duration(r.opt_one_thread),
            r.certified_gap,
            r.units_routed,
            duration(r.opt_from_zero),
            duration(r.read_distances),
            ratio(r.opt, r.read_distances),
            duration(r.greedy),
            ratio(r.greedy, r.read_distances),
            duration(r.nearest),
        );
    }
    md
}

mod secs {
    use std::time::Duration;

    pub fn serialize<S: serde::Serializer>(d: &Duration, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_f64(d.as_secs_f64())
    }
}

mod secs_opt {
    use std::time::Duration;

    pub fn serialize<S: serde::Serializer>(d: &Option<Duration>, s: S) -> Result<S::Ok, S::Error> {
        match d {
            Some(d) => s.serialize_some(&d.as_secs_f64()),
            None => s.serialize_none(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Case;

    #[test]
    fn sizes_parse_and_bad_ones_say_how_to_write_them() {
        let case: Case = "1000x50".parse().unwrap();
        assert_eq!((case.robots, case.tasks), (1000, 50));
        let err = "1000".parse::<Case>().unwrap_err();
        assert_eq!(err, "`1000`: write a size as NxM, e.g. 1000x5");
        let err = "0x5".parse::<Case>().unwrap_err();
        assert_eq!(err, "`0x5`: must be at least 1");
        #[derive(clap::Parser)]
        struct Cli {
            #[command(flatten)]
            args: super::BenchOptArgs,
        }
        let parsed = <Cli as clap::Parser>::try_parse_from(["bench-opt", "--cases", "10x"]);
        assert!(parsed.is_err());
    }
}
