//! `cargo xtask bench-scale`: the learned policy (fast path, block rollout, repair),
//! AFGNet with a price head (ours, no repair) and the price model (ours, no repair)
//! against OPT, GRAPE DA and greedy from N = 100 to 100 000, with the peak memory of
//! each run. Every case runs in its own child process (this binary with `--case`), so
//! the peak resident set size it reports belongs to that case alone.

use std::process::Command;

use afg_eval::scale::{Case, Outcome, Plan, cases, label, markdown, run_case};
use anyhow::{Context, Result, bail};
use clap::Args;

#[derive(Args)]
pub struct ScaleArgs {
    #[command(flatten)]
    plan: Plan,
    /// Print the results as JSON instead of a Markdown table.
    #[arg(long)]
    json: bool,
    /// Internal: run one case (JSON) and print its result.
    #[arg(long, hide = true)]
    case: Option<String>,
}

fn spawn(case: &Case) -> Result<Outcome> {
    let exe = std::env::current_exe()?;
    let output = Command::new(exe)
        .args(["bench-scale", "--case", &serde_json::to_string(case)?])
        .output()
        .context("running a benchmark case")?;
    if !output.status.success() {
        bail!(
            "case {} failed: {}",
            serde_json::to_string(case)?,
            String::from_utf8_lossy(&output.stderr)
        );
    }
    Ok(serde_json::from_slice(&output.stdout)?)
}

pub fn run(args: ScaleArgs) -> Result<()> {
    if let Some(case) = &args.case {
        let case: Case = serde_json::from_str(case).context("--case is JSON")?;
        println!("{}", serde_json::to_string(&run_case(case)?)?);
        return Ok(());
    }
    let plan = &args.plan;
    if plan.tasks.contains(&5) && !afg_learn::run::RunDir::new(&plan.model).has_weights() {
        bail!(
            "{} holds no trained model (model.json); pass --model DIR",
            plan.model.display()
        );
    }
    let cases = cases(&args.plan)?;
    let bar = afg_cli::progress(cases.len() as u64, "bench-scale");
    let mut outcomes = Vec::new();
    for case in &cases {
        bar.set_message(format!(
            "N = {}, M = {}: {}",
            case.robots,
            case.tasks,
            label(case)
        ));
        outcomes.push(spawn(case)?);
        bar.inc(1);
    }
    bar.finish_and_clear();
    if args.json {
        println!("{}", serde_json::to_string_pretty(&outcomes)?);
        return Ok(());
    }
    print!("{}", markdown(&outcomes));
    Ok(())
}
