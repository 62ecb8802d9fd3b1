//! `afg solve`'s exact solver: its limits and progress line, and `--start`.

use afg_baseline::{Method, TeamOptimum};
use afg_game::realloc::PreviousAssignment;
use afg_game::{Assignment, Instance};
use anyhow::{Context, Result};

use super::SolveArgs;

/// `method`'s exact solver with `--time-limit` / `--gap` and the progress line (`None`
/// where the method is not exact and no limit is given).
pub(super) fn solver(args: &SolveArgs, method: Method) -> Result<Option<TeamOptimum>> {
    Ok((method.exact(args.time_limit, args.gap))
        .context("--time-limit / --gap")?
        .map(|exact| TeamOptimum {
            progress: Some(crate::exact_progress::print_progress),
            ..exact
        }))
}

/// `--start FILE`: the exact optimum of every instance from its line's assignment, with
/// the limits and the progress line of `--method opt` (`None` without `--start`).
pub(super) fn started(
    args: &SolveArgs,
    instances: &[Instance],
) -> Result<Option<Vec<TeamOptimum>>> {
    let Some(path) = &args.start else {
        return Ok(None);
    };
    let (Some(Method::Opt), None) = (args.method, &args.model) else {
        anyhow::bail!("--start is for the exact optimum (--method opt) only");
    };
    let shown = path.display();
    let text = std::fs::read_to_string(path).with_context(|| format!("--start {shown}"))?;
    let lines: Vec<&str> = text.lines().filter(|l| !l.trim().is_empty()).collect();
    if lines.len() != instances.len() {
        anyhow::bail!(
            "--start {shown}: {} assignment lines for {} instances (one per instance, in order)",
            lines.len(),
            instances.len()
        );
    }
    let exact = solver(args, Method::Opt)?.expect("method opt is always the exact solver");
    (lines.iter().zip(instances).enumerate())
        .map(|(k, (line, inst))| {
            let at = || format!("--start {shown} line {}", k + 1);
            let previous = PreviousAssignment::from_json(line).with_context(at)?;
            if !(previous.left_robots.is_empty() && previous.left_tasks.is_empty()) {
                anyhow::bail!("{}: names robots or tasks that left; a start is an assignment of this instance", at());
            }
            let start = Assignment::from_tasks(inst, previous.tasks).with_context(at)?;
            Ok(TeamOptimum {
                start: Some(start),
                ..exact.clone()
            })
        })
        .collect::<Result<_>>()
        .map(Some)
}
