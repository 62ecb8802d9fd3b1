//! `cargo xtask realloc-study`: robots leave an optimally allocated instance; the warm
//! start against solving from scratch, as a Markdown table.

use afg_baseline::Method;
use afg_repro::realloc_study::{StudyPlan, study};
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
