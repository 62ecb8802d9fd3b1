//! `cargo xtask solve --from`: warm-start reallocation after robots or tasks changed.

use std::path::Path;
use std::time::Instant;

use afg_baseline::{Allocator, CentralisedDa, Method, Optimum};
use afg_game::io::PreviousAssignment;
use afg_game::{Assignment, Instance, Preference};
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
    Ok(Reallocation {
        welfare,
        opt_welfare,
        percent_of_opt: 100.0 * welfare / opt_welfare,
        survivors,
        moved: changed(&assignment),
        placed: carried.tasks().iter().filter(|t| t.is_none()).count(),
        opt_changes: changed(&opt),
        stable_balanced: instance.is_stable(&assignment, Preference::Balanced),
        seconds,
        assignment,
    })
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
        crate::tables::draw_assignments(
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
        "  survivors moved   {:>12}   of {} (OPT from scratch would move {})",
        r.moved, r.survivors, r.opt_changes
    );
    println!("  robots placed     {:>12}", r.placed);
    println!("  balanced-stable   {:>12}", r.stable_balanced);
    println!("  time              {:>10.3} ms", 1e3 * r.seconds);
    Ok(())
}

#[cfg(test)]
mod tests {
    use afg_game::{GeneratorConfig, RobotId};

    use super::*;

    /// The OPT assignment of an instance with some robots removed, as a previous file.
    fn after_removal(n: usize, removed: usize, seed: u64) -> (Instance, PreviousAssignment) {
        let old = GeneratorConfig::paper(n, 5, seed).generate().unwrap();
        let opt = Optimum.allocate(&old).unwrap().assignment;
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
        let now = Instance::new(robots, old.tasks().to_vec(), old.beta()).unwrap();
        let previous = PreviousAssignment {
            tasks: opt.tasks().to_vec(),
            left_robots: left,
            left_tasks: Vec::new(),
        };
        (now, previous)
    }

    #[test]
    fn warm_start_moves_few_robots_and_stays_near_the_optimum() {
        let (now, previous) = after_removal(300, 30, 4);
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
