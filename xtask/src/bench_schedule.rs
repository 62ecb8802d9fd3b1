//! `cargo xtask bench-schedule`: afg's scheduler and bound on DCMRTA's published test set
//! (the four published methods beside it, instance by instance), on HeteroMRTA's skill
//! family, and at scale; OR-Tools CP-SAT (2 workers) at the same times where a Python
//! with ortools is given.

use std::path::{Path, PathBuf};
use std::process::Command;

use afg_schedule::{
    Family, Generate, Schedule, ScheduleInstance, SolveOptions, Solved, TimeUse, read_instances,
    read_schedules,
};
use anyhow::{Context, Result, bail};
use clap::Args;
use serde::Deserialize;

use crate::bench::runs::{check_python, scratch_dir};

/// `cargo xtask bench-schedule`.
#[derive(Args)]
pub struct BenchScheduleArgs {
    /// afg's time limits per instance, in seconds (one core).
    #[arg(long, value_delimiter = ',', default_value = "0.1,1,10")]
    times: Vec<f64>,
    /// The longest wait any schedule may keep (10: the rule DCMRTA's learned policies were tested under).
    #[arg(long, default_value_t = 10.0)]
    max_wait: f64,
    /// How many instances of the published set (the first ones).
    #[arg(long, default_value_t = 50)]
    instances: usize,
    /// How many instances of the skill family (HeteroMRTA's: 5 species of 3 robots, 40 tasks; seeds 0, 1, …).
    #[arg(long, default_value_t = 10)]
    skill_instances: usize,
    /// A Python with ortools for the CP-SAT columns (`scripts/schedule_cpsat.py`); without it they are left out.
    #[arg(long)]
    python: Option<PathBuf>,
    /// CP-SAT's time limits, in seconds (2 workers).
    #[arg(long, value_delimiter = ',', default_value = "1,10,60")]
    cpsat_times: Vec<f64>,
    /// On how many instances of each set CP-SAT runs (the first ones).
    #[arg(long, default_value_t = 5)]
    cpsat_instances: usize,
    /// Sizes for the scale rows, ROBOTSxTASKS (both families).
    #[arg(long, value_delimiter = ',', default_value = "200x500")]
    scale: Vec<String>,
    /// afg's time limit at scale, in seconds.
    #[arg(long, default_value_t = 10.0)]
    scale_time: f64,
    /// Draw instance 0's schedule (afg at the middle time limit) into this SVG.
    #[arg(long)]
    figure: Option<PathBuf>,
    /// Scratch directory for the peers' files (default: a fresh one under the temp dir).
    #[arg(long)]
    dir: Option<PathBuf>,
}

/// The four published methods, as the published file names them.
const PUBLISHED: [&str; 4] = ["CTAS-D_300s", "OR-Tools", "REINFORCE_IA", "REINFORCE_LF"];

/// One instance's numbers: the bound, afg at each time, CP-SAT at each time (None: not run,
/// or no schedule found or a replay that breaks max_wait), the published makespans.
struct Row {
    bound: f64,
    /// The load bound's parts per robot: the work, the least driving.
    load: (f64, f64),
    afg: Vec<f64>,
    /// Where afg's robots' time goes, at each time.
    time_use: Vec<TimeUse>,
    /// Where the published CTAS-D routes' time goes, replayed (the published set only).
    published_use: Option<TimeUse>,
    cpsat: Vec<Option<f64>>,
    published: Vec<f64>,
}

/// Runs the benchmark and prints its tables (Markdown).
///
/// # Errors
/// A dataset that cannot be read, a Python without ortools, a peer that fails.
pub fn run(args: BenchScheduleArgs) -> Result<()> {
    let dir = scratch_dir(args.dir.as_deref(), "bench-schedule")?;
    if let Some(python) = &args.python {
        check_python(python, &["ortools"])?;
    }
    let root = crate::repo_root().join("datasets/dcmrta-20a50t");
    let set = root.join("dcmrta-20a50t.jsonl");
    let instances = read_instances(&set)?;
    let published: Vec<serde_json::Value> =
        std::fs::read_to_string(root.join("dcmrta-20a50t-published.jsonl"))?
            .lines()
            .map(serde_json::from_str)
            .collect::<Result<_, _>>()?;
    let routes = read_schedules(&root.join("dcmrta-20a50t-routes.jsonl"))?;
    let count = args.instances.min(instances.len());
    let bar = afg_eval::report::progress((count + args.skill_instances) as u64, "bench-schedule");
    let mut rows = Vec::new();
    for (k, inst) in instances.iter().take(count).enumerate() {
        bar.set_message(format!("published instance {k}"));
        let mut row = measure(inst, k, &set, &args, &dir)?;
        row.published_use = Some(inst.evaluate(&routes[k].schedule())?.time_use());
        row.published = PUBLISHED
            .iter()
            .map(|m| {
                published[k]["methods"][m]["makespan"]
                    .as_f64()
                    .context("a published makespan")
            })
            .collect::<Result<_>>()?;
        rows.push(row);
        bar.inc(1);
    }
    let skill_file = dir.join("heteromrta.jsonl");
    let skill_set: Vec<ScheduleInstance> = (0..args.skill_instances as u64)
        .map(|seed| {
            Generate {
                family: Family::Heteromrta,
                robots: 15,
                tasks: 40,
                seed,
            }
            .instance()
        })
        .collect::<Result<_, _>>()?;
    std::fs::write(
        &skill_file,
        skill_set
            .iter()
            .map(|i| i.to_json() + "\n")
            .collect::<String>(),
    )?;
    let mut skill_rows = Vec::new();
    for (k, inst) in skill_set.iter().enumerate() {
        bar.set_message(format!("skill instance {k}"));
        skill_rows.push(measure(inst, k, &skill_file, &args, &dir)?);
        bar.inc(1);
    }
    bar.finish_and_clear();
    if let Some(figure) = &args.figure {
        draw(&instances[0], &args, figure)?;
    }
    if !rows.is_empty() {
        print!("{}", published_tables(&rows, &args));
    }
    print!("{}", skill_table(&skill_rows, &args));
    print!("{}", scale_table(&args)?);
    Ok(())
}

/// afg's schedule within `seconds`, valid under `max_wait` (the scheduler checks it with
/// the evaluator before returning it).
fn solve(inst: &ScheduleInstance, seconds: f64, max_wait: f64) -> Result<Solved> {
    Ok(inst.solve(&SolveOptions {
        time_limit: Some(seconds),
        max_wait: Some(max_wait),
        ..SolveOptions::default()
    })?)
}

fn measure(
    inst: &ScheduleInstance,
    line: usize,
    file: &Path,
    args: &BenchScheduleArgs,
    dir: &Path,
) -> Result<Row> {
    let solved = args
        .times
        .iter()
        .map(|&t| solve(inst, t, args.max_wait))
        .collect::<Result<Vec<_>>>()?;
    let cpsat = match &args.python {
        Some(python) if line < args.cpsat_instances => args
            .cpsat_times
            .iter()
            .map(|&t| cpsat(python, file, line, t, args.max_wait, inst, dir))
            .collect::<Result<_>>()?,
        _ => vec![None; args.cpsat_times.len()],
    };
    let bound = inst.lower_bound();
    let n = inst.num_robots() as f64;
    Ok(Row {
        bound: bound.makespan,
        load: (bound.work / n, bound.driving / n),
        afg: solved.iter().map(Solved::makespan).collect(),
        time_use: solved.iter().map(|s| s.run.time_use()).collect(),
        published_use: None,
        cpsat,
        published: Vec::new(),
    })
}

/// Runs `scripts/schedule_cpsat.py`; its routes replayed by afg's evaluator (None when
/// it found none, or its replay breaks max_wait).
fn cpsat(
    python: &Path,
    file: &Path,
    line: usize,
    seconds: f64,
    max_wait: f64,
    inst: &ScheduleInstance,
    dir: &Path,
) -> Result<Option<f64>> {
    #[derive(Deserialize)]
    struct Found {
        routes: Option<Vec<Vec<usize>>>,
    }
    let out = dir.join(format!(
        "cpsat-{}-{line}-{seconds}.json",
        file.file_stem().and_then(|s| s.to_str()).unwrap_or("set")
    ));
    let script = crate::repo_root().join("scripts/schedule_cpsat.py");
    let status = Command::new(python)
        .arg(&script)
        .arg(file)
        .arg(line.to_string())
        .arg(&out)
        .args([
            "--time-limit",
            &seconds.to_string(),
            "--workers",
            "2",
            "--max-wait",
            &max_wait.to_string(),
        ])
        .status()
        .with_context(|| format!("running {}", script.display()))?;
    if !status.success() {
        bail!(
            "{} failed on {} line {line}",
            script.display(),
            file.display()
        );
    }
    let found: Found = serde_json::from_slice(&std::fs::read(&out)?)?;
    let Some(routes) = found.routes else {
        return Ok(None);
    };
    let run = inst.evaluate_with(&Schedule { routes }, max_wait)?;
    Ok(run.is_valid().then_some(run.makespan))
}

fn draw(inst: &ScheduleInstance, args: &BenchScheduleArgs, figure: &Path) -> Result<()> {
    let seconds = args.times[args.times.len() / 2];
    let solved = solve(inst, seconds, args.max_wait)?;
    let svg = afg_eval::schedule_figure::schedule_svg(
        inst,
        &solved.run,
        &format!("afg ({seconds} s), DCMRTA instance 0"),
    )?;
    afg_game::fs::write_atomic_making_dirs(figure, svg.as_bytes())?;
    Ok(())
}

fn mean(values: impl IntoIterator<Item = f64>) -> f64 {
    let (sum, n) = values
        .into_iter()
        .fold((0.0, 0usize), |(s, n), v| (s + v, n + 1));
    sum / n.max(1) as f64
}

fn published_tables(rows: &[Row], args: &BenchScheduleArgs) -> String {
    let best = |r: &Row| r.published.iter().copied().fold(f64::INFINITY, f64::min);
    let mut out = format!(
        "DCMRTA's test set, {} instances (20 robots, 50 tasks), every afg schedule valid under max_wait {}.\n\n\
         | method | mean makespan | below the best published | mean makespan / bound |\n|---|---|---|---|\n",
        rows.len(),
        args.max_wait
    );
    for (k, t) in args.times.iter().enumerate() {
        let below = rows.iter().filter(|r| r.afg[k] < best(r)).count();
        out += &format!(
            "| afg (ours), {t} s | {:.3} | {below}/{} | {:.3} |\n",
            mean(rows.iter().map(|r| r.afg[k])),
            rows.len(),
            mean(rows.iter().map(|r| r.afg[k] / r.bound))
        );
    }
    for (k, name) in PUBLISHED.iter().enumerate() {
        out += &format!(
            "| {name} (published) | {:.3} | — | {:.3} |\n",
            mean(rows.iter().map(|r| r.published[k])),
            mean(rows.iter().map(|r| r.published[k] / r.bound))
        );
    }
    out += &format!(
        "| lower bound (ours) | {:.3} | — | 1 |\n\n",
        mean(rows.iter().map(|r| r.bound))
    );
    out += &time_table(rows, args);
    out += &cpsat_lines(rows, args);
    out += "Instance by instance (makespans):\n\n| # | bound |";
    for t in &args.times {
        out += &format!(" afg {t} s |");
    }
    out += " CTAS-D | OR-Tools | RL IA | RL LF |\n|---|---|";
    out += &"---|".repeat(args.times.len() + 4);
    out += "\n";
    for (i, r) in rows.iter().enumerate() {
        out += &format!("| {i} | {:.3} |", r.bound);
        for v in r.afg.iter().chain(&r.published) {
            out += &format!(" {v:.3} |");
        }
        out += "\n";
    }
    out + "\n"
}

/// CP-SAT beside afg on the instances it ran on.
fn cpsat_lines(rows: &[Row], args: &BenchScheduleArgs) -> String {
    let ran: Vec<&Row> = rows
        .iter()
        .filter(|r| r.cpsat.iter().any(Option::is_some) || args.python.is_some())
        .take(args.cpsat_instances)
        .collect();
    if args.python.is_none() || ran.is_empty() {
        return String::new();
    }
    let mut out = format!(
        "CP-SAT (2 workers) on the first {} instances, beside afg (one core) on the same:\n\n| time | CP-SAT: valid schedules found | CP-SAT mean makespan (where found) | afg mean makespan on those |\n|---|---|---|---|\n",
        ran.len()
    );
    for (k, t) in args.cpsat_times.iter().enumerate() {
        let found: Vec<&&Row> = ran.iter().filter(|r| r.cpsat[k].is_some()).collect();
        // afg at the same time, or at the longest of its times below it (said so)
        let afg_at = (0..args.times.len())
            .filter(|&a| args.times[a] <= *t)
            .max_by(|&a, &b| args.times[a].total_cmp(&args.times[b]));
        let afg = match afg_at {
            Some(a) if !found.is_empty() => {
                let value = mean(found.iter().map(|r| r.afg[a]));
                if args.times[a] == *t {
                    format!("{value:.3}")
                } else {
                    format!("{value:.3} (afg at {} s)", args.times[a])
                }
            }
            _ => "—".into(),
        };
        let cp = if found.is_empty() {
            "—".into()
        } else {
            format!(
                "{:.3}",
                mean(found.iter().map(|r| r.cpsat[k].unwrap_or(f64::NAN)))
            )
        };
        out += &format!("| {t} s | {}/{} | {cp} | {afg} |\n", found.len(), ran.len());
    }
    out + "\n"
}

fn skill_table(rows: &[Row], args: &BenchScheduleArgs) -> String {
    if rows.is_empty() {
        return String::new();
    }
    let mut out = format!(
        "HeteroMRTA's family (5 species of 3 robots, one skill and one depot each; 40 tasks requiring 1–5 skills; seeds 0–{}), max_wait {}:\n\n| method | mean makespan | mean makespan / bound |\n|---|---|---|\n",
        rows.len() - 1,
        args.max_wait
    );
    for (k, t) in args.times.iter().enumerate() {
        out += &format!(
            "| afg (ours), {t} s | {:.3} | {:.3} |\n",
            mean(rows.iter().map(|r| r.afg[k])),
            mean(rows.iter().map(|r| r.afg[k] / r.bound))
        );
    }
    out += &format!(
        "| lower bound (ours) | {:.3} | 1 |\n\n",
        mean(rows.iter().map(|r| r.bound))
    );
    out + &time_table(rows, args) + &cpsat_lines(rows, args)
}

/// Where afg's robots' time goes at its longest time, beside the load bound's own parts.
fn time_table(rows: &[Row], args: &BenchScheduleArgs) -> String {
    let Some(last) = args.times.len().checked_sub(1) else {
        return String::new();
    };
    let line = |name: String, uses: Vec<TimeUse>| {
        let part = |f: fn(&TimeUse) -> f64| mean(uses.iter().map(f));
        format!(
            "| {name} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} |\n",
            part(|u| u.working),
            part(|u| u.driving),
            part(|u| u.waiting),
            part(|u| u.idle),
            part(|u| u.working + u.driving + u.waiting + u.idle),
        )
    };
    let mut out = String::from(
        "Where the time goes, per robot (means over the instances; the parts add up to the makespan):\n\n\
         | | working | driving | waiting | idle | makespan |\n|---|---|---|---|---|---|\n",
    );
    out += &line(
        format!("afg (ours), {} s", args.times[last]),
        rows.iter().map(|r| r.time_use[last]).collect(),
    );
    let published: Vec<TimeUse> = rows.iter().filter_map(|r| r.published_use).collect();
    if published.len() == rows.len() {
        out += &line(
            "CTAS-D_300s (published routes, replayed under max_wait 100)".into(),
            published,
        );
    }
    let (work, driving) = (
        mean(rows.iter().map(|r| r.load.0)),
        mean(rows.iter().map(|r| r.load.1)),
    );
    out += &format!(
        "| all robots' load (ours): the fewest robots' work, the least driving | {work:.3} | {driving:.3} | 0 | 0 | {:.3} |\n\n",
        work + driving
    );
    out
}

fn scale_table(args: &BenchScheduleArgs) -> Result<String> {
    let mut out = format!(
        "At scale (one instance each, seed 0; the bound first, then afg searches for what is left of {} s, one core):\n\n\
         | family | robots × tasks | makespan | bound | gap | bound time | total time |\n|---|---|---|---|---|---|---|\n",
        args.scale_time
    );
    for size in &args.scale {
        let (robots, tasks) = size
            .split_once('x')
            .and_then(|(r, t)| Some((r.parse().ok()?, t.parse().ok()?)))
            .with_context(|| format!("--scale {size}: ROBOTSxTASKS"))?;
        for family in [Family::Dcmrta, Family::Heteromrta] {
            let inst = Generate {
                family,
                robots,
                tasks,
                seed: 0,
            }
            .instance()?;
            let clock = std::time::Instant::now();
            let bound = inst.lower_bound();
            let bound_seconds = clock.elapsed().as_secs_f64();
            let left = args.scale_time - bound_seconds;
            if left <= 0.0 {
                bail!(
                    "the bound alone took {bound_seconds:.2} s of the {} s given at {size}",
                    args.scale_time
                );
            }
            let makespan = solve(&inst, left, args.max_wait)?.makespan();
            let total = clock.elapsed().as_secs_f64();
            out += &format!(
                "| {} | {robots} × {tasks} | {makespan:.3} | {:.3} | {:.1} % | {bound_seconds:.2} s | {total:.2} s |\n",
                family.name(),
                bound.makespan,
                100.0 * bound.gap(makespan)
            );
        }
    }
    Ok(out + "\n")
}
