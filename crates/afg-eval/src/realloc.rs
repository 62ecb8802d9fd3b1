//! Warm-start reallocation after robots or tasks changed, measured against solving
//! from scratch.

use std::time::Instant;

use afg_baseline::{Allocator, CentralisedDa, Method, Optimum};
use afg_game::realloc::PreviousAssignment;
use afg_game::{Assignment, GeneratorConfig, Instance, Preference, RobotId};
use serde::Serialize;

use crate::EvalError;

/// A warm-started reallocation and what it cost.
#[derive(Clone, Debug, Serialize)]
pub struct Reallocation {
    /// The reallocated assignment of the new instance.
    #[serde(skip)]
    pub assignment: Assignment,
    /// Its welfare.
    pub welfare: f64,
    /// OPT of the new instance, solved from scratch.
    pub opt_welfare: f64,
    /// [`percent_of_opt`](crate::percent_of_opt).
    pub percent_of_opt: Option<f64>,
    /// Robots carried over from the previous assignment.
    pub survivors: usize,
    /// Survivors that ended on another task.
    pub moved: usize,
    /// Robots without a task to start from (newcomers, or their task left).
    pub placed: usize,
    /// Survivors whose task OPT from scratch would change.
    pub opt_changes: usize,
    /// Survivors whose task the same dynamics from scratch (from the empty assignment)
    /// would change.
    pub scratch_changes: usize,
    /// The same dynamics from scratch: % of OPT.
    pub scratch_percent_of_opt: Option<f64>,
    /// Whether the result is stable under the balanced preference.
    pub stable_balanced: bool,
    /// Wall time of the warm start (carry over and dynamics), in seconds.
    pub seconds: f64,
}

/// Carries `previous` over to `instance`, places the unassigned robots by best response
/// and runs the best-response dynamics of `preference` to a stable assignment.
///
/// # Errors
/// A previous assignment that does not fit the instance, or an allocator failure.
///
/// # Examples
/// ```
/// use afg_baseline::Method;
/// use afg_eval::realloc::{after_removal, reallocate};
/// use afg_game::Preference;
/// let (now, previous) = after_removal(100, 10, 0, Method::Opt)?;
/// let r = reallocate(&now, &previous, Preference::Balanced)?;
/// assert!(r.stable_balanced && r.survivors == 90);
/// # Ok::<(), afg_eval::EvalError>(())
/// ```
pub fn reallocate(
    instance: &Instance,
    previous: &PreviousAssignment,
    preference: Preference,
) -> Result<Reallocation, EvalError> {
    let start = Instant::now();
    let (carried, assignment) = CentralisedDa::new(preference).warm_start(instance, previous)?;
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
        percent_of_opt: crate::percent_of_opt(welfare, opt_welfare),
        survivors,
        moved: changed(&assignment),
        placed: carried.tasks().iter().filter(|t| t.is_none()).count(),
        opt_changes: changed(&opt),
        scratch_changes: changed(&scratch),
        scratch_percent_of_opt: crate::percent_of_opt(instance.welfare(&scratch), opt_welfare),
        stable_balanced: instance.is_stable(&assignment, Preference::Balanced),
        seconds,
        assignment,
    })
}

/// The reallocation as `afg solve --from` prints it, one figure per line.
impl std::fmt::Display for Reallocation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (welfare, opt) = (self.welfare, self.opt_welfare);
        writeln!(
            f,
            "  welfare           {welfare:>12.3}   (OPT from scratch {opt:.3})"
        )?;
        writeln!(
            f,
            "  % of OPT          {:>12}",
            crate::solve::percent_text(self.percent_of_opt)
        )?;
        writeln!(
            f,
            "  survivors moved   {:>12}   of {} (from scratch: OPT would move {}, the same dynamics {})",
            self.moved, self.survivors, self.opt_changes, self.scratch_changes
        )?;
        writeln!(f, "  robots placed     {:>12}", self.placed)?;
        writeln!(f, "  balanced-stable   {:>12}", self.stable_balanced)?;
        writeln!(f, "  time              {:>10.3} ms", 1e3 * self.seconds)
    }
}

/// The best-response dynamics that warm-start an assignment made by `method`: balanced
/// after OPT or balanced DA, selfish after GRAPE DA; `None` for other methods.
pub fn dynamics_after(method: Method) -> Option<Preference> {
    match method {
        Method::Opt | Method::DaBalanced => Some(Preference::Balanced),
        Method::Da => Some(Preference::Selfish),
        _ => None,
    }
}

/// An instance of the paper's distribution (`n` robots, five tasks, `seed`) allocated by
/// `previous_method`, then `removed` robots (spread evenly over the indices) leave: the
/// instance as it is now, and the old assignment as the previous file.
///
/// # Errors
/// `n` or `removed` out of range for the generator, or an allocator failure.
pub fn after_removal(
    n: usize,
    removed: usize,
    seed: u64,
    previous_method: Method,
) -> Result<(Instance, PreviousAssignment), EvalError> {
    let old = GeneratorConfig::paper(n, GeneratorConfig::PAPER_TASKS, seed).generate()?;
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
    let now = old.with_robots(robots)?;
    let previous = PreviousAssignment {
        tasks: opt.tasks().to_vec(),
        left_robots: left,
        left_tasks: Vec::new(),
    };
    Ok((now, previous))
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
        let percent = r.percent_of_opt.unwrap();
        assert!(percent > 99.0, "{percent}");
        assert!(r.moved < r.survivors / 5, "moved {}", r.moved);
        now.check(&r.assignment).unwrap();
        let text = r.to_string();
        let moved = format!("survivors moved   {:>12}   of 270 (", r.moved);
        assert!(
            text.contains(&moved) && text.contains(&format!("robots placed     {:>12}", 0)),
            "{text}"
        );
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
            assert!(err.to_string().contains(needle), "{text}: {err}");
        }
    }

    #[test]
    fn the_dynamics_follow_the_previous_method() {
        assert_eq!(dynamics_after(Method::Opt), Some(Preference::Balanced));
        assert_eq!(
            dynamics_after(Method::DaBalanced),
            Some(Preference::Balanced)
        );
        assert_eq!(dynamics_after(Method::Da), Some(Preference::Selfish));
        assert_eq!(dynamics_after(Method::Greedy), None);
    }
}
