//! The removal study (`cargo xtask realloc-study`): robots leave optimally (or by
//! GRAPE) allocated instances; the warm start against the same dynamics and OPT from
//! scratch, as a Markdown table.
//!
//! `cargo xtask realloc-study`: robots leave an optimally allocated instance; the warm
//! start against solving from scratch, as a Markdown table.

use afg_baseline::Method;
use afg_eval::EvalError;
use afg_eval::realloc::{Reallocation, after_removal, dynamics_after, reallocate};
use afg_game::Preference;

/// The study's sizes, instances and departures.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StudyPlan {
    /// Robots before the removal.
    pub robots: usize,
    /// Share of the robots that leave, in `[0, 1)` (at least one leaves).
    pub remove: f64,
    /// Instances (seeds `0..count`).
    pub count: u64,
    /// The allocator of the previous assignment: OPT or balanced DA (then the warm start
    /// runs balanced best-response dynamics), or GRAPE DA (selfish dynamics).
    pub previous: Method,
}

/// Runs the study: its header line and its table.
///
/// # Errors
/// [`EvalError::BadOptions`] for a share outside `[0, 1)`, no instances or a previous
/// method without dynamics to warm-start; the allocators' errors.
///
/// # Examples
/// ```
/// use afg_baseline::Method;
/// use xtask::realloc_study::{StudyPlan, study};
/// let plan = StudyPlan { robots: 60, remove: 0.1, count: 2, previous: Method::Opt };
/// let text = study(plan)?;
/// assert!(text.contains("6 leave") && text.contains("| OPT from scratch |"));
/// # Ok::<(), afg_eval::EvalError>(())
/// ```
pub fn study(plan: StudyPlan) -> Result<String, EvalError> {
    if !(0.0..1.0).contains(&plan.remove) || plan.count == 0 {
        return Err(EvalError::BadOptions(
            "the share removed must lie in [0, 1) and the count be positive",
        ));
    }
    let removed = ((plan.robots as f64 * plan.remove).round() as usize).max(1);
    let Some(preference) = dynamics_after(plan.previous) else {
        return Err(EvalError::BadOptions(
            "the previous method must be opt, da-balanced or da",
        ));
    };
    let dynamics = if preference == Preference::Selfish {
        Method::Da.label()
    } else {
        Method::DaBalanced.label()
    };
    let mut rows = Vec::new();
    for seed in 0..plan.count {
        let (now, previous) = after_removal(plan.robots, removed, seed, plan.previous)?;
        rows.push(reallocate(&now, &previous, preference)?);
    }
    Ok(format!(
        "N = {} robots, {removed} leave (spread over the indices), M = {}, {} instances; the previous assignment is {}'s.\n\n{}",
        plan.robots,
        afg_eval::dataset::TASKS,
        rows.len(),
        plan.previous,
        study_markdown(&rows, dynamics)
    ))
}

/// The removal study's Markdown table: the warm start (`dynamics` run from the old
/// assignment) against the same dynamics and OPT from scratch, over `rows` (one per
/// instance, none empty).
fn study_markdown(rows: &[Reallocation], dynamics: &str) -> String {
    let k = rows.len() as f64;
    let mean = |f: &dyn Fn(&Reallocation) -> f64| rows.iter().map(f).sum::<f64>() / k;
    let worst = |f: &dyn Fn(&Reallocation) -> f64| rows.iter().map(f).fold(f64::INFINITY, f64::min);
    // An undefined % of OPT shows as NaN in the means it enters.
    let pct = |p: Option<f64>| p.unwrap_or(f64::NAN);
    let mut md = String::from(
        "| method | survivors moved (mean) | % of OPT (mean / worst) | balanced-stable | time (ms, mean) |\n|---|---|---|---|---|\n",
    );
    md += &format!(
        "| warm start ({dynamics} from the old assignment) | {:.1} | {:.3} / {:.3} | {} of {} | {:.2} |\n",
        mean(&|r| r.moved as f64),
        mean(&|r| pct(r.percent_of_opt)),
        worst(&|r| pct(r.percent_of_opt)),
        rows.iter().filter(|r| r.stable_balanced).count(),
        rows.len(),
        1e3 * mean(&|r| r.seconds)
    );
    md += &format!(
        "| {dynamics} from scratch | {:.1} | {:.3} / {:.3} | – | – |\n",
        mean(&|r| r.scratch_changes as f64),
        mean(&|r| pct(r.scratch_percent_of_opt)),
        worst(&|r| pct(r.scratch_percent_of_opt))
    );
    md + &format!(
        "| OPT from scratch | {:.1} | 100 / 100 | – | – |\n",
        mean(&|r| r.opt_changes as f64)
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_table_of_two_copies_has_the_row_as_mean_and_worst() {
        let (now, previous) = after_removal(300, 30, 4, Method::Opt).unwrap();
        let r = reallocate(&now, &previous, Preference::Balanced).unwrap();
        let percent = r.percent_of_opt.unwrap();
        let md = study_markdown(&[r.clone(), r.clone()], "balanced DA");
        let warm = md.lines().nth(2).unwrap();
        let pct = format!("{percent:.3} / {percent:.3}");
        assert!(warm.contains(&pct) && warm.contains("| 2 of 2 |"), "{md}");
        assert!(
            md.lines()
                .nth(3)
                .unwrap()
                .starts_with("| balanced DA from scratch |")
        );
        assert_eq!(md.lines().count(), 5);
    }

    #[test]
    fn bad_plans_are_refused() {
        let plan = StudyPlan {
            robots: 60,
            remove: 1.0,
            count: 2,
            previous: Method::Opt,
        };
        assert!(study(plan).is_err());
        assert!(
            study(StudyPlan {
                remove: 0.1,
                previous: Method::Greedy,
                ..plan
            })
            .is_err()
        );
    }
}

// The command.
use anyhow::Result;
use clap::Args;

/// The sizes, instances and departures to study.
#[derive(Args)]
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

/// Runs the study and prints its table.
pub fn run(args: StudyArgs) -> Result<()> {
    let plan = StudyPlan {
        robots: args.robots,
        remove: args.remove,
        count: args.count,
        previous: args.previous,
    };
    print!("{}", study(plan)?);
    Ok(())
}
