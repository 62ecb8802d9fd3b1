//! `afg schedule`: robots performing sequences of team and skill tasks over time, scored
//! by the makespan (DCMRTA's and HeteroMRTA's problem): draw instances, plan schedules
//! with a certified lower bound, score anyone's schedule, draw one.

use std::path::{Path, PathBuf};

use afg_game::fs::write_atomic_making_dirs;
use afg_schedule::{
    Family, Generate, Schedule, ScheduleInstance, ScheduleRecord, SolveOptions, TimeUse,
    read_instances, read_schedules,
};
use anyhow::{Context, Result, bail};
use clap::{Args, Subcommand};
use serde::Serialize;

/// The subcommands of `afg schedule`.
#[derive(Subcommand)]
pub enum ScheduleCommand {
    /// Draw instances of DCMRTA's family (robots at one depot, tasks needing 1–5 robots) or
    /// HeteroMRTA's (5 species with a skill and a depot each, tasks requiring 1–5 skills).
    Gen(GenArgs),
    /// Plan a schedule for every instance (anytime search under a time limit), with a
    /// certified lower bound on the makespan and the gap between them.
    Solve(SolveArgs),
    /// Play anyone's schedules (one ordered list of task ids per robot) under the
    /// instance's rules: makespan, travel, waiting, and who breaks `max_wait` or deadlocks.
    Score(ScoreArgs),
    /// Draw one schedule as an SVG: a Gantt chart of the robots beside a map of their routes.
    Show(ShowArgs),
}

/// `afg schedule gen`.
#[derive(Args)]
pub struct GenArgs {
    /// "dcmrta" or "heteromrta".
    #[arg(long, default_value = "dcmrta")]
    family: String,
    /// Robots per instance.
    #[arg(long, default_value_t = 20)]
    robots: usize,
    /// Tasks per instance.
    #[arg(long, default_value_t = 50)]
    tasks: usize,
    /// How many instances (seeds seed, seed + 1, …).
    #[arg(long, default_value_t = 1)]
    count: u64,
    /// The first seed.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Where to write the instances (JSON Lines).
    #[arg(long)]
    out: PathBuf,
}

/// `afg schedule solve`.
#[derive(Args)]
pub struct SolveArgs {
    /// The instances (JSON Lines, DCMRTA's layout: `datasets/dcmrta-20a50t/dcmrta-20a50t.jsonl`).
    #[arg(long)]
    input: PathBuf,
    /// Seconds of search per instance (default 1 unless --steps is given).
    #[arg(long, allow_negative_numbers = true)]
    time_limit: Option<f64>,
    /// Search steps per instance: the same seed and steps give the same schedule on any machine.
    #[arg(long)]
    steps: Option<u64>,
    /// The search's seed.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// The longest any robot may wait for its team (default: each instance's `max_wait`;
    /// 10 is the rule DCMRTA's learned policies were tested under).
    #[arg(long, allow_negative_numbers = true)]
    max_wait: Option<f64>,
    /// Write the schedules here (JSON Lines, the layout `score` and `show` read).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Print one JSON object per instance instead of text.
    #[arg(long)]
    json: bool,
    /// Schedules to improve, one per instance (JSON Lines, as `--out` writes them): the
    /// search starts from each, and keeps it where it finds nothing better.
    #[arg(long)]
    start: Option<PathBuf>,
    /// Instances solved at once, each on one core (0: one per core). Results come out
    /// in the order of the input whatever the number.
    #[arg(long, default_value_t = 1)]
    jobs: usize,
}

/// `afg schedule score`.
#[derive(Args)]
pub struct ScoreArgs {
    /// The instances (JSON Lines).
    #[arg(long)]
    input: PathBuf,
    /// The schedules, one per line in the order of the instances: `{"routes": [[…], …]}`
    /// (optionally with `index` and `method`), as `solve --out` writes them.
    #[arg(long)]
    schedule: PathBuf,
    /// Check waits against this rule instead of each instance's `max_wait`.
    #[arg(long, allow_negative_numbers = true)]
    max_wait: Option<f64>,
    /// Print one JSON object per instance instead of text.
    #[arg(long)]
    json: bool,
}

/// `afg schedule show`.
#[derive(Args)]
pub struct ShowArgs {
    /// The instances (JSON Lines).
    #[arg(long)]
    input: PathBuf,
    /// The schedules, one per line in the order of the instances.
    #[arg(long)]
    schedule: PathBuf,
    /// Which line to draw (0-based).
    #[arg(long, default_value_t = 0)]
    line: usize,
    /// The SVG to write.
    #[arg(long)]
    out: PathBuf,
}

/// Runs an `afg schedule` subcommand.
///
/// # Errors
/// A file that cannot be read or written, an instance or schedule that is not well
/// formed (named by line and field), a schedule that deadlocks, a setting out of range.
pub fn run(command: ScheduleCommand) -> Result<()> {
    match command {
        ScheduleCommand::Gen(args) => generate(&args),
        ScheduleCommand::Solve(args) => solve(&args),
        ScheduleCommand::Score(args) => score(&args),
        ScheduleCommand::Show(args) => show(&args),
    }
}

fn generate(args: &GenArgs) -> Result<()> {
    let family = Family::from_name(&args.family)?;
    let mut text = String::new();
    for k in 0..args.count {
        let seed = args
            .seed
            .checked_add(k)
            .context("the seeds run past 2^64")?;
        let inst = Generate {
            family,
            robots: args.robots,
            tasks: args.tasks,
            seed,
        }
        .instance()?;
        text.push_str(&inst.to_json());
        text.push('\n');
    }
    write_atomic_making_dirs(&args.out, text.as_bytes())?;
    eprintln!(
        "wrote {} instance(s) of {} to {}",
        args.count,
        family.name(),
        args.out.display()
    );
    Ok(())
}

fn read(input: &Path) -> Result<Vec<ScheduleInstance>> {
    read_instances(input).with_context(|| format!("reading {}", input.display()))
}

/// One solved instance, as `--json` prints it.
#[derive(Serialize)]
struct SolvedLine {
    line: usize,
    index: Option<usize>,
    makespan: f64,
    bound: f64,
    gap: f64,
    travel: f64,
    waiting: f64,
    longest_wait: f64,
    max_wait: f64,
    /// Where the robots' time goes: means per robot that add up to the makespan.
    time_use: TimeUse,
    steps: u64,
    seconds: f64,
}

/// The instances, each with the schedule `--start` gives it (None without).
fn with_starts(args: &SolveArgs) -> Result<Vec<(ScheduleInstance, Option<Schedule>)>> {
    Ok(match &args.start {
        Some(start) => {
            let (instances, records) = paired(&args.input, start)?;
            let starts = records.iter().map(|r| Some(r.schedule()));
            instances.into_iter().zip(starts).collect()
        }
        None => read(&args.input)?.into_iter().map(|i| (i, None)).collect(),
    })
}

fn solve(args: &SolveArgs) -> Result<()> {
    let work = with_starts(args)?;
    let mut records = String::new();
    let (mut makespans, mut bounds) = (0.0, 0.0);
    let solve_one = |(inst, start): &(ScheduleInstance, Option<Schedule>)| -> Result<(SolvedLine, ScheduleRecord)> {
        let solved = inst.solve(&SolveOptions {
            time_limit: args.time_limit,
            steps: args.steps,
            seed: args.seed,
            max_wait: args.max_wait,
            start: start.clone(),
        })?;
        let run = &solved.run;
        let bound = inst.lower_bound();
        let out = SolvedLine {
            line: 0,
            index: inst.index,
            makespan: run.makespan,
            bound: bound.makespan,
            gap: bound.gap(run.makespan),
            travel: run.travel,
            waiting: run.waiting,
            longest_wait: run.longest_wait,
            max_wait: run.max_wait,
            time_use: run.time_use(),
            steps: solved.steps,
            seconds: solved.seconds,
        };
        let record = ScheduleRecord {
            index: inst.index,
            method: Some("afg".into()),
            routes: solved.schedule.routes,
        };
        Ok((out, record))
    };
    in_order(&work, args.jobs, solve_one, |line, result| {
        let (mut out, record) = result.with_context(|| {
            let at = format!("{} line {}", args.input.display(), line + 1);
            match &args.start {
                Some(start) => format!("{at}, started from {} line {}", start.display(), line + 1),
                None => at,
            }
        })?;
        out.line = line;
        makespans += out.makespan;
        bounds += out.bound;
        if args.json {
            println!("{}", serde_json::to_string(&out)?);
        } else {
            print_solved(&out);
        }
        records.push_str(&serde_json::to_string(&record)?);
        records.push('\n');
        Ok(())
    })?;
    if !args.json && work.len() > 1 {
        let n = work.len() as f64;
        println!(
            "mean of {} instances: makespan {:.3}, bound {:.3}",
            work.len(),
            makespans / n,
            bounds / n
        );
    }
    if let Some(out) = &args.out {
        write_atomic_making_dirs(out, records.as_bytes())?;
    }
    Ok(())
}

/// One solved instance, in words.
fn print_solved(out: &SolvedLine) {
    println!(
        "line {}: makespan {:.3}  bound {:.3}  gap {:.1} %  travel {:.3}  mean wait {:.3}  longest wait {:.3} (max_wait {})  {} steps in {:.2} s",
        out.line,
        out.makespan,
        out.bound,
        100.0 * out.gap,
        out.travel,
        out.waiting,
        out.longest_wait,
        out.max_wait,
        out.steps,
        out.seconds
    );
    println!("  {}", per_robot(&out.time_use));
}

/// Runs `work` on every item, `jobs` at a time (0: one per core), and hands each result
/// to `report` in the items' order as soon as it and every one before it are done. The
/// first error `report` returns stops the work (items already started finish).
fn in_order<I: Sync, T: Send>(
    items: &[I],
    jobs: usize,
    work: impl Fn(&I) -> T + Sync,
    mut report: impl FnMut(usize, T) -> Result<()>,
) -> Result<()> {
    use std::collections::BTreeMap;
    use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
    let jobs = match jobs {
        0 => std::thread::available_parallelism().map_or(1, |n| n.get()),
        j => j,
    }
    .min(items.len().max(1));
    let (next, stop) = (AtomicUsize::new(0), AtomicBool::new(false));
    std::thread::scope(|scope| {
        let (send, receive) = std::sync::mpsc::channel();
        for _ in 0..jobs {
            let send = send.clone();
            let (next, stop, work) = (&next, &stop, &work);
            scope.spawn(move || {
                while !stop.load(Ordering::Relaxed) {
                    let k = next.fetch_add(1, Ordering::Relaxed);
                    let Some(item) = items.get(k) else { return };
                    if send.send((k, work(item))).is_err() {
                        return;
                    }
                }
            });
        }
        drop(send);
        let (mut waiting, mut due) = (BTreeMap::new(), 0);
        for (k, result) in receive {
            waiting.insert(k, result);
            while let Some(result) = waiting.remove(&due) {
                if let Err(e) = report(due, result) {
                    stop.store(true, Ordering::Relaxed);
                    return Err(e);
                }
                due += 1;
            }
        }
        Ok(())
    })
}

/// Where the robots' time goes, in words.
fn per_robot(use_: &TimeUse) -> String {
    format!(
        "per robot: working {:.3}  driving {:.3}  waiting {:.3}  idle {:.3}",
        use_.working, use_.driving, use_.waiting, use_.idle
    )
}

/// The schedules of a file, one per instance.
fn paired(input: &Path, schedule: &Path) -> Result<(Vec<ScheduleInstance>, Vec<ScheduleRecord>)> {
    let instances = read(input)?;
    let records =
        read_schedules(schedule).with_context(|| format!("reading {}", schedule.display()))?;
    if records.len() != instances.len() {
        bail!(
            "{} holds {} schedule(s) for the {} instance(s) of {}",
            schedule.display(),
            records.len(),
            instances.len(),
            input.display()
        );
    }
    Ok((instances, records))
}

fn score(args: &ScoreArgs) -> Result<()> {
    let (instances, records) = paired(&args.input, &args.schedule)?;
    for (line, (inst, record)) in instances.iter().zip(&records).enumerate() {
        let where_ = || format!("{} line {}", args.schedule.display(), line + 1);
        let run = inst
            .evaluate_with(&record.schedule(), args.max_wait.unwrap_or(inst.max_wait))
            .with_context(where_)?;
        if args.json {
            let value = serde_json::json!({
                "line": line, "index": inst.index, "valid": run.is_valid(), "makespan": run.makespan,
                "bound": inst.lower_bound().makespan,
                "travel": run.travel, "waiting": run.waiting, "longest_wait": run.longest_wait,
                "max_wait": run.max_wait, "long_waits": run.long_waits,
                "released_before_arrival": run.released_before_arrival,
                "time_use": run.time_use(),
            });
            println!("{value}");
            continue;
        }
        println!(
            "line {line}: makespan {:.6}  travel {:.6}  mean wait {:.6}  longest wait {:.3}  {}",
            run.makespan,
            run.travel,
            run.waiting,
            run.longest_wait,
            if run.is_valid() { "valid" } else { "INVALID" }
        );
        println!("  {}", per_robot(&run.time_use()));
        for w in &run.long_waits {
            println!(
                "  robot {} waits {:.3} at task {}, longer than max_wait {}",
                w.robot, w.wait, w.task, run.max_wait
            );
        }
        for (robot, task) in &run.released_before_arrival {
            println!(
                "  robot {robot} is sent to task {task} after its team is complete and released before it arrives"
            );
        }
    }
    Ok(())
}

fn show(args: &ShowArgs) -> Result<()> {
    let (instances, records) = paired(&args.input, &args.schedule)?;
    let Some((inst, record)) = instances.iter().zip(&records).nth(args.line) else {
        bail!(
            "--line {} is past the last of {} line(s)",
            args.line,
            instances.len()
        );
    };
    let run = inst.evaluate(&record.schedule())?;
    let name = record.method.clone().unwrap_or_else(|| "schedule".into());
    let title = match inst.index {
        Some(i) => format!("{name}, instance {i}"),
        None => format!("{name}, line {}", args.line),
    };
    let svg = afg_eval::schedule_figure::schedule_svg(inst, &run, &title)?;
    write_atomic_making_dirs(&args.out, svg.as_bytes())?;
    eprintln!("wrote {}", args.out.display());
    Ok(())
}
