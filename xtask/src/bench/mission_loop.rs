//! The mission benchmarks (`cargo xtask bench-mission`): the exact optimum re-solved
//! after one event — from the previous optimum's prices, and by the solver that kept
//! its state ([`IncrementalOptimum`]) — against a solve from scratch, and whole
//! missions with an allocator in the loop.
//!
//! `cargo xtask bench-mission`: the exact optimum re-solved after one event against a
//! solve from scratch, and whole missions with allocators in the loop.

use std::fmt::Write as _;
use std::time::{Duration, Instant};

use afg_baseline::{AllocError, IncrementalOptimum, Optimum, verify_optimal};
use afg_eval::EvalError;
use afg_eval::report::duration;
use afg_game::{GeneratorConfig, Instance, Point, RobotId, Task, TaskId};
use afg_mission::{Mission, Planner};

use super::median_of;

/// The game after one event, the prices to start from, and the event itself.
struct Event {
    name: &'static str,
    after: Instance,
    start: Vec<f64>,
    change: Change,
}

/// An event as the kept solver takes it.
enum Change {
    Appears(Task),
    Done(TaskId),
    Fail(Vec<RobotId>),
}

impl Change {
    fn apply(&self, opt: &mut IncrementalOptimum) -> Result<(), AllocError> {
        match self {
            Change::Appears(task) => opt.add_task(*task).map(|_| ()),
            Change::Done(task) => opt.remove_task(*task),
            Change::Fail(robots) => opt.remove_robots(robots),
        }
    }
}

/// The three events of a mission on `inst` (solved with prices `prices`): a task
/// appears (drawn from the same distribution), a task is done, 1 % of the robots fail.
fn events(inst: &Instance, prices: &[f64], seed: u64) -> Result<Vec<Event>, EvalError> {
    let (n, m) = (inst.num_robots(), inst.num_tasks());
    let other = GeneratorConfig::paper(n, m + 1, seed ^ 1).generate()?;
    let mut tasks = inst.tasks().to_vec();
    tasks.push(other.tasks()[m]);
    let appears = Instance::new(inst.robots().to_vec(), tasks, inst.beta())?;
    let mut start = prices.to_vec();
    start.push(Optimum::start_price(&appears, TaskId(m as u32)));
    let done = Instance::new(
        inst.robots().to_vec(),
        inst.tasks()[1..].to_vec(),
        inst.beta(),
    )?;
    let survivors: Vec<Point> = inst
        .robots()
        .iter()
        .enumerate()
        .filter(|(i, _)| i % 100 != 0)
        .map(|(_, &p)| p)
        .collect();
    let failed = (0..n as u32).step_by(100).map(RobotId).collect();
    Ok(vec![
        Event {
            name: "a task appears",
            after: appears,
            start,
            change: Change::Appears(other.tasks()[m]),
        },
        Event {
            name: "a task is done",
            after: done,
            start: prices[1..].to_vec(),
            change: Change::Done(TaskId(0)),
        },
        Event {
            name: "1 % of the robots fail",
            after: inst.with_robots(survivors)?,
            start: prices.to_vec(),
            change: Change::Fail(failed),
        },
    ])
}

/// The re-solve after each event at N robots and M tasks, from scratch, from the
/// previous optimum's prices, and by the solver that kept its state (the event applied
/// and its assignment and prices read out; the state is built anew before each
/// measurement, untimed): median times (at most `budget_s` per measurement), the kept solver's
/// speed-up over from scratch, all three certified and of equal welfare; a Markdown
/// table.
///
/// # Errors
/// The generator's and the optimum's errors; [`EvalError::BadOptions`] if a solution is
/// not certified or the two welfares differ.
///
/// # Examples
/// ```
/// let text = xtask::bench::mission_loop::incremental(2_000, 10, 1, 0.01)?;
/// assert!(text.contains("| a task appears |") && text.contains("| yes |"));
/// # Ok::<(), afg_eval::EvalError>(())
/// ```
pub fn incremental(
    robots: usize,
    tasks: usize,
    seed: u64,
    budget_s: f64,
) -> Result<String, EvalError> {
    let inst = GeneratorConfig::paper(robots, tasks, seed).generate()?;
    let (_, prices) = Optimum.with_prices(&inst);
    let mut out = format!(
        "N = {robots}, M = {tasks}, seed {seed}: the optimum after one event\n\n| event | from scratch | from the previous prices | kept solver state | speed-up (kept) | units routed (kept) | certified, same welfare |\n|---|---|---|---|---|---|---|\n"
    );
    for event in events(&inst, &prices, seed)? {
        let game = &event.after;
        let (scratch, (a, p)) = median_of(budget_s, 20, || {
            let start = Instant::now();
            let solved = Optimum.with_prices(game);
            Ok::<_, EvalError>((start.elapsed(), solved))
        })?;
        let (warm, (b, q)) = median_of(budget_s, 20, || {
            let start = Instant::now();
            let solved = Optimum.with_prices_from(game, &event.start)?;
            Ok::<_, EvalError>((start.elapsed(), solved))
        })?;
        let (incremental, (c, r, routed)) = median_of(budget_s, 20, || {
            let mut opt = IncrementalOptimum::new(&inst);
            let start = Instant::now();
            event.change.apply(&mut opt)?;
            let solved = (opt.assignment(), opt.prices());
            Ok::<_, EvalError>((start.elapsed(), (solved.0, solved.1, opt.routed())))
        })?;
        let x = verify_optimal(game, &a, &p)?;
        for y in [verify_optimal(game, &b, &q)?, verify_optimal(game, &c, &r)?] {
            if (x.welfare - y.welfare).abs() > 1e-9 * x.welfare.abs().max(1.0) {
                return Err(EvalError::BadOptions("the optima differ"));
            }
        }
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} | {:.1}× | {routed} | yes |",
            event.name,
            duration(scratch),
            duration(warm),
            duration(incremental),
            scratch.as_secs_f64() / incremental.as_secs_f64()
        );
    }
    Ok(out)
}

/// Whole missions: each planner on `mission` once, its wall time (the simulation
/// included) and its allocator's compute time, beside the floor of any exact method —
/// reading every robot–task distance of every decision's game once.
///
/// # Errors
/// The simulator's errors.
pub fn missions(mission: &Mission, planners: &[Planner]) -> Result<String, EvalError> {
    let mut out = String::from(
        "| method | wall time | allocator compute | decisions | distance floor | tasks done | reward done, % of all |\n|---|---|---|---|---|---|---|\n",
    );
    for planner in planners {
        let start = Instant::now();
        let run = planner.run(mission, Default::default(), |_| {})?;
        let wall = start.elapsed();
        let m = &run.metrics;
        let floor = distance_floor(mission, m.pairs);
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} | {} | {} / {} | {:.2} % |",
            planner.name(),
            duration(wall),
            duration(Duration::from_secs_f64(m.compute_total_s)),
            m.decisions,
            duration(floor),
            m.tasks_done,
            m.tasks,
            100.0 * m.reward_done / m.reward_total
        );
    }
    Ok(out)
}

/// The time to read `pairs` robot–task distances (every decision's N × M once),
/// from the time to read all of `mission`'s once, measured here.
fn distance_floor(mission: &Mission, pairs: u64) -> Duration {
    let robots: Vec<Point> = mission.robots.iter().map(|r| r.position).collect();
    let tasks: Vec<Point> = mission.tasks.iter().map(|t| t.position).collect();
    let start = Instant::now();
    let mut sum = 0.0;
    for r in &robots {
        for t in &tasks {
            sum += r.distance(*t);
        }
    }
    std::hint::black_box(sum);
    let per_pair = start.elapsed().as_secs_f64() / (robots.len() * tasks.len()) as f64;
    Duration::from_secs_f64(per_pair * pairs as f64)
}

// The command.
use afg_baseline::Method;
use afg_eval::mission::planner;
use afg_mission::{MissionConfig, MissionMethod, MissionPlan, Preset};
use anyhow::Result;
use clap::Args;

/// The sizes to measure.
#[derive(Args)]
pub struct BenchMissionArgs {
    /// Robots of the one-event re-solve.
    #[arg(long, default_value_t = 100_000)]
    resolve_robots: usize,
    /// Tasks of the one-event re-solve.
    #[arg(long, default_value_t = 50)]
    resolve_tasks: usize,
    /// Robots of the whole mission (Poisson arrivals).
    #[arg(long, default_value_t = 10_000)]
    robots: usize,
    /// Tasks arriving over the whole mission.
    #[arg(long, default_value_t = 200)]
    tasks: usize,
    /// The allocators of the whole mission, comma-separated (opt runs from scratch and
    /// incrementally).
    #[arg(long, value_delimiter = ',', default_value = "opt,greedy,da-balanced")]
    methods: Vec<Method>,
    /// A trained model to run in the mission too (e.g. models/ours/price_n60).
    #[arg(long)]
    model: Option<std::path::PathBuf>,
    /// Seconds per timing (the median of repeated runs within it).
    #[arg(long, default_value_t = 2.0)]
    budget: f64,
    /// Seed of the instances and the mission.
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

/// Prints both tables.
pub fn run(args: BenchMissionArgs) -> Result<()> {
    println!(
        "{}",
        incremental(
            args.resolve_robots,
            args.resolve_tasks,
            args.seed,
            args.budget
        )?
    );
    let mission =
        MissionConfig::new(Preset::Poisson, args.robots, args.tasks, args.seed).generate()?;
    let plan = |method, warm| MissionPlan {
        method: MissionMethod::Central(method),
        warm,
        seed: args.seed,
        ..MissionPlan::default()
    };
    let mut planners = vec![planner(&plan(Method::Opt, true), None)?];
    for &method in &args.methods {
        planners.push(planner(&plan(method, false), None)?);
    }
    if let Some(dir) = &args.model {
        planners.push(planner(&plan(Method::Opt, false), Some(dir))?);
    }
    println!(
        "A mission of {} robots and {} tasks arriving at rate {} (seed {}), one run each, on {} core(s):\n",
        args.robots,
        args.tasks,
        args.tasks as f64 / 20.0,
        args.seed,
        rayon::current_num_threads()
    );
    print!("{}", missions(&mission, &planners)?);
    Ok(())
}
