//! `cargo xtask solve --from`: warm-start reallocation after robots or tasks changed.

use std::path::Path;
use std::time::Instant;

use afg_baseline::{Allocator, CentralisedDa, Method, Optimum};
use afg_game::io::PreviousAssignment;
use afg_game::{Assignment, GeneratorConfig, Instance, Preference, RobotId};
use anyhow::{Context, Result, bail};
use serde::Serialize;

use crate::solve::SolveArgs;

/// A warm-started reallocation and what it cost.
#[derive(Debug, Serialize)]
pub struct Reallocation {
    #[serde(skip)]
    pub assignment: Assignment,
    pub welfare: f64,
    /// OPT of the new instance, solved from scratch.
    pub opt_welfare: f64,
    pub percent_of_opt: f64,
    /// Robots carried over from the previous assignment.
    pub survivors: usize,
    /// Survivors that ended on another task.
    pub moved: usize,
    /// Robots without a task to start from (newcomers, or their task left).
    pub placed: usize,
    /// Survivors whose task OPT from scratch would change.
    pub opt_changes: usize,
    /// Survivors whose task the same dynamics from scratch (from the empty assignment)
    /// would change, and that assignment's % of OPT.
    pub scratch_changes: usize,
    pub scratch_percent_of_opt: f64,
    pub stable_balanced: bool,
    pub seconds: f64,
}

/// Carries `previous` over to `instance`, places the unassigned robots by best response
/// and runs the best-response dynamics of `preference` to a stable assignment.
pub fn reallocate(
    instance: &Instance,
    previous: &PreviousAssignment,
    preference: Preference,
) -> Result<Reallocation> {
    let start = Instant::now();
    let carried = previous.carry_over(instance)?;
    let mut assignment = carried.clone();
    CentralisedDa::new(preference).improve(instance, &mut assignment);
    let seconds = start.elapsed().as_secs_f64();
    let opt = Optimum.allocate(instance)?.assignment;
    let survivors = previous.survivors();
    let changed = |a: &Assignment| {
        (0..survivors)
            .filter(|&i| carried.tasks()[i].is_some() && a.tasks()[i] != carried.tasks()[i])
            .count()
    };
    let (welfare, opt_welfare) = (instance.welfare(&assignment), instance.welfare(&opt));
    let scratch = CentralisedDa::new(preference)
        .allocate(instance)?
        .assignment;
    Ok(Reallocation {
        welfare,
        opt_welfare,
        percent_of_opt: 100.0 * welfare / opt_welfare,
        survivors,
        moved: changed(&assignment),
        placed: carried.tasks().iter().filter(|t| t.is_none()).count(),
        opt_changes: changed(&opt),
        scratch_changes: changed(&scratch),
        scratch_percent_of_opt: 100.0 * instance.welfare(&scratch) / opt_welfare,
        stable_balanced: instance.is_stable(&assignment, Preference::Balanced),
        seconds,
        assignment,
    })
}

/// An instance of the paper's distribution solved optimally, then `removed` robots
/// (spread evenly over the indices) leave: the instance as it is now, and the OPT
/// assignment as the previous file.
pub fn after_removal(
    n: usize,
    removed: usize,
    seed: u64,
    previous_method: Method,
) -> Result<(Instance, PreviousAssignment)> {
    let old = GeneratorConfig::paper(n, 5, seed).generate()?;
    let opt = previous_method.allocator(seed).allocate(&old)?.assignment;
    let left: Vec<RobotId> = (0..removed)
        .map(|k| RobotId((k * n / removed) as u32))
        .collect();
    let robots = old
        .robots()
        .iter()
        .enumerate()
        .filter(|(i, _)| !left.contains(&RobotId(*i as u32)))
        .map(|(_, p)| *p)
        .collect();
    let now = Instance::new(robots, old.tasks().to_vec(), old.beta())?;
    let previous = PreviousAssignment {
        tasks: opt.tasks().to_vec(),
        left_robots: left,
        left_tasks: Vec::new(),
    };
    Ok((now, previous))
}

pub fn run(args: &SolveArgs, from: &Path, instances: &[Instance]) -> Result<()> {
    let preference = match args.method {
        Some(Method::DaBalanced) => Preference::Balanced,
        Some(Method::Da) => Preference::Selfish,
        _ => bail!(
            "--from warm-starts best-response dynamics: use --method da-balanced or --method da"
        ),
    };
    let [instance] = instances else {
        bail!(
            "--from reallocates one instance; the input holds {}",
            instances.len()
        );
    };
    let text =
        std::fs::read_to_string(from).with_context(|| format!("reading {}", from.display()))?;
    let previous = PreviousAssignment::from_json(&text)
        .with_context(|| format!("reading {}", from.display()))?;
    let r = reallocate(instance, &previous, preference)
        .with_context(|| format!("carrying {} over", from.display()))?;
    let name = format!(
        "{} warm-started from {}",
        args.method.expect("checked"),
        from.display()
    );
    if let Some(out) = &args.out {
        let line = r
            .assignment
            .to_json_with_summary(Some(serde_json::to_value(&r)?));
        afg_game::io::write_atomic(out, format!("{line}\n").as_bytes())?;
    }
    if let Some(svg) = &args.svg {
        let opt = Optimum.allocate(instance)?.assignment;
        crate::map::draw_assignments(
            instance,
            &[("OPT from scratch", &opt), ("warm start", &r.assignment)],
            svg,
        )?;
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&r)?);
        return Ok(());
    }
    println!("{name}");
    println!(
        "  welfare           {:>12.3}   (OPT from scratch {:.3})",
        r.welfare, r.opt_welfare
    );
    println!("  % of OPT          {:>12.2}", r.percent_of_opt);
    println!(
        "  survivors moved   {:>12}   of {} (from scratch: OPT would move {}, the same dynamics {})",
        r.moved, r.survivors, r.opt_changes, r.scratch_changes
    );
    println!("  robots placed     {:>12}", r.placed);
    println!("  balanced-stable   {:>12}", r.stable_balanced);
    println!("  time              {:>10.3} ms", 1e3 * r.seconds);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn warm_start_moves_few_robots_and_stays_near_the_optimum() {
        let (now, previous) = after_removal(300, 30, 4, Method::Opt).unwrap();
        let r = reallocate(&now, &previous, Preference::Balanced).unwrap();
        assert!(r.stable_balanced);
        assert_eq!((r.survivors, r.placed), (270, 0));
        assert!(r.percent_of_opt > 99.0, "{}", r.percent_of_opt);
        assert!(r.moved < r.survivors / 5, "moved {}", r.moved);
        now.check(&r.assignment).unwrap();
    }

    #[test]
    fn newcomers_and_a_removed_task_are_placed() {
        let old = GeneratorConfig::paper(20, 3, 2).generate().unwrap();
        let opt = Optimum.allocate(&old).unwrap().assignment;
        // Task 1 leaves; two robots join at the end.
        let now = GeneratorConfig::paper(22, 2, 5).generate().unwrap();
        let previous = PreviousAssignment {
            tasks: opt.tasks().to_vec(),
            left_robots: Vec::new(),
            left_tasks: vec![afg_game::TaskId(1)],
        };
        let r = reallocate(&now, &previous, Preference::Balanced).unwrap();
        let on_task_1 = opt.size(afg_game::TaskId(1));
        assert_eq!(r.placed, 2 + on_task_1);
        assert!(r.assignment.is_complete());
    }

    #[test]
    fn a_previous_file_that_does_not_fit_is_a_clear_error() {
        let now = GeneratorConfig::paper(5, 2, 1).generate().unwrap();
        for (text, needle) in [
            (
                r#"{"format":"afg-assignment","version":1,"tasks":[0,1,0,1,0,1,0]}"#,
                "only 5",
            ),
            (
                r#"{"format":"afg-assignment","version":1,"tasks":[0,1],"left_robots":[4]}"#,
                "out of range",
            ),
            (
                r#"{"format":"afg-assignment","version":1,"tasks":[0,1],"left_robots":[1,1]}"#,
                "twice",
            ),
        ] {
            let previous = PreviousAssignment::from_json(text).unwrap();
            let err = reallocate(&now, &previous, Preference::Balanced).unwrap_err();
            assert!(format!("{err:#}").contains(needle), "{text}: {err:#}");
        }
    }
}

#[derive(clap::Args)]
pub struct StudyArgs {
    /// Robots before the removal.
    #[arg(long, default_value_t = 1000)]
    robots: usize,
    /// Share of the robots that leave.
    #[arg(long, default_value_t = 0.1)]
    remove: f64,
    /// Instances (seeds 0..count).
    #[arg(long, default_value_t = 20)]
    count: u64,
    /// The allocator of the previous assignment: opt or da-balanced (then the warm start
    /// runs balanced best-response dynamics), or da (GRAPE: selfish dynamics).
    #[arg(long, default_value_t = Method::Opt)]
    previous: Method,
}

/// `cargo xtask realloc-study`: robots leave an optimally allocated instance; the warm
/// start against solving from scratch, as a Markdown table.
pub fn run_study(args: StudyArgs) -> Result<()> {
    if !(0.0..1.0).contains(&args.remove) || args.count == 0 {
        bail!("--remove must lie in [0, 1) and --count be positive");
    }
    let removed = (args.robots as f64 * args.remove).round() as usize;
    let preference = match args.previous {
        Method::Opt | Method::DaBalanced => Preference::Balanced,
        Method::Da => Preference::Selfish,
        other => bail!("--previous {other}: use opt, da-balanced or da"),
    };
    let dynamics = if preference == Preference::Selfish {
        Method::Da.label()
    } else {
        Method::DaBalanced.label()
    };
    let mut rows = Vec::new();
    for seed in 0..args.count {
        let (now, previous) = after_removal(args.robots, removed.max(1), seed, args.previous)?;
        rows.push(reallocate(&now, &previous, preference)?);
    }
    let k = rows.len() as f64;
    let mean = |f: &dyn Fn(&Reallocation) -> f64| rows.iter().map(f).sum::<f64>() / k;
    let min_pct = rows
        .iter()
        .map(|r| r.percent_of_opt)
        .fold(f64::INFINITY, f64::min);
    println!(
        "N = {} robots, {} leave (spread over the indices), M = 5, {} instances; the previous assignment is {}'s.\n",
        args.robots,
        removed.max(1),
        rows.len(),
        args.previous
    );
    println!(
        "| method | survivors moved (mean) | % of OPT (mean / worst) | balanced-stable | time (ms, mean) |"
    );
    println!("|---|---|---|---|---|");
    println!(
        "| warm start ({dynamics} from the old assignment) | {:.1} | {:.3} / {:.3} | {} of {} | {:.2} |",
        mean(&|r| r.moved as f64),
        mean(&|r| r.percent_of_opt),
        min_pct,
        rows.iter().filter(|r| r.stable_balanced).count(),
        rows.len(),
        1e3 * mean(&|r| r.seconds)
    );
    println!(
        "| {dynamics} from scratch | {:.1} | {:.3} / {:.3} | – | – |",
        mean(&|r| r.scratch_changes as f64),
        mean(&|r| r.scratch_percent_of_opt),
        rows.iter()
            .map(|r| r.scratch_percent_of_opt)
            .fold(f64::INFINITY, f64::min)
    );
    println!(
        "| OPT from scratch | {:.1} | 100 / 100 | – | – |",
        mean(&|r| r.opt_changes as f64)
    );
    Ok(())
}
