//! `afg solve --from`: warm-start reallocation after robots or tasks changed.

use std::path::Path;

use afg_baseline::{Allocator, Method, Optimum};
use afg_eval::realloc::{after_removal, dynamics_after, reallocate, study_markdown};
use afg_game::realloc::PreviousAssignment;
use afg_game::{Instance, Preference};
use anyhow::{Context, Result, bail};

use crate::solve::SolveArgs;

/// `afg solve --from FILE`: the warm start from a previous assignment, against OPT
/// from scratch.
///
/// # Errors
/// More than one instance, a method other than da / da-balanced, or an assignment
/// file that does not fit the instance.
pub fn run(args: &SolveArgs, from: &Path, instances: &[Instance]) -> Result<()> {
    let Some(preference) = args
        .method
        .filter(|&m| m != Method::Opt)
        .and_then(dynamics_after)
    else {
        bail!("--from warm-starts best-response dynamics: use --method da-balanced or --method da")
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
        afg_game::fs::write_atomic(out, format!("{line}\n").as_bytes())?;
    }
    if let Some(svg) = &args.svg {
        let opt = Optimum.allocate(instance)?.assignment;
        crate::write_svg(
            svg,
            &afg_eval::figures::assignments_svg(
                instance,
                &[("OPT from scratch", &opt), ("warm start", &r.assignment)],
            )?,
        )?;
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&r)?);
        return Ok(());
    }
    print!("{name}\n{r}");
    Ok(())
}

/// `cargo xtask realloc-study`: the sizes, instances and departures to study.
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
    let Some(preference) = dynamics_after(args.previous) else {
        bail!("--previous {}: use opt, da-balanced or da", args.previous)
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
    println!(
        "N = {} robots, {} leave (spread over the indices), M = {}, {} instances; the previous assignment is {}'s.\n",
        args.robots,
        removed.max(1),
        afg_eval::dataset::TASKS,
        rows.len(),
        args.previous
    );
    print!("{}", study_markdown(&rows, dynamics));
    Ok(())
}
