//! `cargo xtask bench-scale`: the learned policy (fast path, block rollout, repair),
//! AFGNet with a price head (ours, no repair) and the price model (ours, no repair)
//! against OPT, GRAPE DA and greedy from N = 100 to 100 000, with the peak memory of
//! each run. Every case runs in its own child process (this binary with `--case`), so
//! the peak resident set size it reports belongs to that case alone.

use std::path::PathBuf;
use std::process::Command;

use afg_repro::scale::{Case, Outcome, Plan, cases, label, markdown, run_case};
use anyhow::{Context, Result, bail};
use clap::Args;

#[derive(Args)]
pub struct ScaleArgs {
    #[command(flatten)]
    plan: PlanArgs,
    /// Print the results as JSON instead of a Markdown table.
    #[arg(long)]
    json: bool,
    /// Internal: run one case (JSON) and print its result.
    #[arg(long, hide = true)]
    case: Option<String>,
}

/// The flags of [`Plan`]: every size and task count, and the learned models to run.
#[derive(Args)]
struct PlanArgs {
    /// Robot counts N.
    #[arg(long, value_delimiter = ',', default_value = "100,1000,10000,100000")]
    sizes: Vec<usize>,
    /// Task counts M.
    #[arg(long, value_delimiter = ',', default_value = "5,50")]
    tasks: Vec<usize>,
    /// Numbers of network passes to try per rollout (block B = ⌈N / passes⌉), besides
    /// the exact rollout (B = 1).
    #[arg(long, value_delimiter = ',', default_value = "1000,100,10")]
    passes: Vec<usize>,
    /// Skip learned runs with more than this many robot-passes (N × passes), e.g. the
    /// exact rollout above N = 1000.
    #[arg(long, default_value_t = 20_000_000)]
    max_work: usize,
    /// Run the Burn reference path up to this N (M = 5 only).
    #[arg(long, default_value_t = 1000)]
    burn_up_to: usize,
    /// Run GRAPE's decentralised simulation (da-decentralised) up to this N: its
    /// synchronous rounds take time about quadratic in N (every change floods the graph).
    #[arg(long, default_value_t = 1000)]
    decentralised_up_to: usize,
    /// Trained run directory of the learned policy at M = 5; other M use untrained
    /// weights (timing only).
    #[arg(long, default_value = "models/paper/afgnet_ddqn_n20")]
    model: PathBuf,
    /// Price model (ours), run at every M in both modes without repair; skipped if the
    /// directory holds no price file.
    #[arg(long, default_value = "models/ours/price_n60")]
    price_model: PathBuf,
    /// AFGNet with a price head (ours): run directories, each used at the M its network
    /// was built for, without repair, with 10 network passes and in one pass
    /// (one-shot); a directory that holds no model is skipped.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "models/ours/afgnet_qstar_price_n60,models/ours/afgnet_qstar_price_m50_n60"
    )]
    price_headed: Vec<PathBuf>,
    /// Seed of the instances (one per N and M).
    #[arg(long, default_value_t = 0)]
    seed: u64,
}

impl From<PlanArgs> for Plan {
    fn from(a: PlanArgs) -> Plan {
        Plan {
            sizes: a.sizes,
            tasks: a.tasks,
            passes: a.passes,
            max_work: a.max_work,
            burn_up_to: a.burn_up_to,
            decentralised_up_to: a.decentralised_up_to,
            model: a.model,
            price_model: a.price_model,
            price_headed: a.price_headed,
            seed: a.seed,
        }
    }
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
    let plan = Plan::from(args.plan);
    if plan.tasks.contains(&5) && !afg_learn::run::RunDir::new(&plan.model).has_weights() {
        bail!(
            "{} holds no trained model (model.json); pass --model DIR",
            plan.model.display()
        );
    }
    let cases = cases(&plan)?;
    let bar = afg_eval::report::progress(cases.len() as u64, "bench-scale");
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
