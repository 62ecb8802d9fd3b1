//! The scale benchmark (`cargo xtask bench-scale`): one measurement ([`Case`]) per
//! allocator, N and M, each meant to run in its own process so that its peak memory
//! ([`Outcome::peak_rss_mib`]) is its own.
//!
//! `cargo xtask bench-scale`: the learned policy (fast path, block rollout, repair),
//! AFGNet with a price head (ours, no repair) and the price model (ours, no repair)
//! against OPT, GRAPE DA and greedy from N = 100 to 100 000, with the peak memory of
//! each run. Every case runs in its own child process (this binary with `--case`), so
//! the peak resident set size it reports belongs to that case alone.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use afg_baseline::{Allocator, Method};
use afg_game::{GeneratorConfig, Instance};
use afg_learn::{
    nets::NetworkConfig,
    policy::LearnedPolicy,
    price::{PriceMode, PriceModel, PricePolicy},
    run::RunDir,
};
use serde::{Deserialize, Serialize};

use afg_eval::EvalError;
use afg_eval::report::duration;

/// What to measure: every size and task count, and the learned models to run (the
/// flags of `cargo xtask bench-scale`).
#[derive(Clone, Debug)]
pub struct Plan {
    /// Robot counts N.
    pub sizes: Vec<usize>,
    /// Task counts M.
    pub tasks: Vec<usize>,
    /// Numbers of network passes to try per rollout (block B = ⌈N / passes⌉), besides
    /// the exact rollout (B = 1).
    pub passes: Vec<usize>,
    /// Skip learned runs with more than this many robot-passes (N × passes), e.g. the
    /// exact rollout above N = 1000.
    pub max_work: usize,
    /// Run the Burn reference path up to this N (M = 5 only).
    pub burn_up_to: usize,
    /// Run GRAPE's decentralised simulation (da-decentralised) up to this N: its
    /// synchronous rounds take time about quadratic in N (every change floods the graph).
    pub decentralised_up_to: usize,
    /// Trained run directory of the learned policy at M = 5; other M use untrained
    /// weights (timing only).
    pub model: PathBuf,
    /// Price model (ours), run at every M in both modes without repair; skipped if the
    /// directory holds no price file.
    pub price_model: PathBuf,
    /// AFGNet with a price head (ours): run directories, each used at the M its network
    /// was built for, without repair, with 10 network passes and in one pass
    /// (one-shot); a directory that holds no model is skipped.
    pub price_headed: Vec<PathBuf>,
    /// Seed of the instances (one per N and M).
    pub seed: u64,
}

/// One measurement, meant to run in a child process ([`run_case`]).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Case {
    /// Robots N of the instance.
    pub robots: usize,
    /// Tasks M of the instance.
    pub tasks: usize,
    /// Seed of the instance (paper distribution).
    pub seed: u64,
    /// A classical method, or None for the learned policy.
    pub method: Option<Method>,
    /// Learned policies: robots per network evaluation.
    #[serde(default)]
    pub block: usize,
    /// Learned policy: the Burn reference path instead of the fast path.
    #[serde(default)]
    pub exact_burn: bool,
    /// Learned policy: its run directory (None: untrained weights, timing only).
    #[serde(default)]
    pub model: Option<PathBuf>,
    /// The price model's file and mode, instead of the Q network.
    #[serde(default)]
    pub price: Option<(PathBuf, PriceMode)>,
    /// Learned policy: no repair after the rollout.
    #[serde(default)]
    pub no_repair: bool,
}

/// What one case measured.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Outcome {
    /// The case.
    pub case: Case,
    /// Whole run: graph, rollout and repair for the learned policy.
    pub seconds: f64,
    /// Welfare of the result.
    pub welfare: f64,
    /// Learned policy: welfare before the repair.
    pub rollout_welfare: Option<f64>,
    /// Learned policy: network passes.
    pub passes: Option<usize>,
    /// Learned policy with repair: moves of the repair.
    pub repair_moves: Option<u64>,
    /// Learned policy with repair: its wall time.
    pub repair_seconds: Option<f64>,
    /// Peak resident set size of the process (instance and graph included).
    pub peak_rss_mib: Option<f64>,
}

fn instance(case: &Case) -> Result<Instance, EvalError> {
    Ok(GeneratorConfig::paper(case.robots, case.tasks, case.seed).generate()?)
}

/// Runs one case in this process and measures it.
///
/// # Errors
/// An instance that cannot be generated, a model that cannot be loaded, or a failed
/// allocation.
pub fn run_case(case: Case) -> Result<Outcome, EvalError> {
    let inst = instance(&case)?;
    let mut out = Outcome {
        case: case.clone(),
        seconds: 0.0,
        welfare: 0.0,
        rollout_welfare: None,
        passes: None,
        repair_moves: None,
        repair_seconds: None,
        peak_rss_mib: None,
    };
    match (case.method, &case.price) {
        (_, Some((path, mode))) => {
            let policy = PricePolicy::load(path, *mode)?.with_block(case.block)?;
            let start = Instant::now();
            let assignment = policy.allocate(&inst)?.assignment;
            out.seconds = start.elapsed().as_secs_f64();
            out.welfare = inst.welfare(&assignment);
        }
        (Some(method), None) => {
            let alloc = method.allocator(case.seed).allocate(&inst)?;
            out.seconds = alloc.stats.wall_time.as_secs_f64();
            out.welfare = inst.welfare(&alloc.assignment);
        }
        (None, None) => {
            let policy = match &case.model {
                Some(dir) => afg_learn::run::load_q_network(dir)?,
                None => LearnedPolicy::new(NetworkConfig::afgnet(case.tasks, 0)),
            };
            let policy = if case.exact_burn {
                policy.exact_burn()
            } else {
                policy.with_block(case.block)?.with_repair(!case.no_repair)
            };
            let start = Instant::now();
            let run = policy.run(&inst)?;
            out.seconds = start.elapsed().as_secs_f64();
            out.welfare = inst.welfare(&run.assignment);
            out.rollout_welfare = Some(run.rollout_welfare);
            out.passes = Some(run.passes);
            if policy.repairs() {
                out.repair_moves = Some(run.repair_moves);
                out.repair_seconds = Some(run.repair_time.as_secs_f64());
            }
        }
    }
    out.peak_rss_mib = crate::bench::peak_rss_mib();
    Ok(out)
}

/// The cases of `plan`, in the order of the table.
///
/// # Errors
/// [`EvalError::BadOptions`] for a size, task count or pass count of 0; a price-headed
/// run directory with weights but no readable config.
pub fn cases(plan: &Plan) -> Result<Vec<Case>, EvalError> {
    if plan.sizes.contains(&0) || plan.tasks.contains(&0) || plan.passes.contains(&0) {
        return Err(EvalError::BadOptions(
            "sizes, task counts and passes must be at least 1",
        ));
    }
    // The committed price-headed models and the M each was built for.
    let mut price_headed = Vec::new();
    for dir in &plan.price_headed {
        let run = RunDir::new(dir);
        if run.has_weights() {
            let tasks = run.config()?.network.tasks();
            price_headed.push((dir.clone(), tasks));
        }
    }
    let mut cases = Vec::new();
    for &tasks in &plan.tasks {
        for &robots in &plan.sizes {
            let base = Case {
                robots,
                tasks,
                seed: plan.seed,
                method: None,
                block: 1,
                exact_burn: false,
                model: (tasks == 5).then(|| plan.model.clone()),
                price: None,
                no_repair: false,
            };
            cases.extend(price_cases(plan, &price_headed, &base));
            let decentralised =
                (robots <= plan.decentralised_up_to).then_some(Method::DaDecentralised);
            let methods = [Method::Opt, Method::Da, Method::DaBalanced, Method::Greedy];
            for method in methods.into_iter().chain(decentralised) {
                cases.push(Case {
                    method: Some(method),
                    ..base.clone()
                });
            }
            if tasks == 5 && robots <= plan.burn_up_to {
                cases.push(Case {
                    exact_burn: true,
                    ..base.clone()
                });
            }
            let mut blocks: Vec<usize> = std::iter::once(1)
                .chain(plan.passes.iter().map(|&p| robots.div_ceil(p.max(1))))
                .filter(|&b| robots.div_ceil(b) * robots <= plan.max_work)
                .collect();
            blocks.dedup();
            for block in blocks {
                cases.push(Case {
                    block,
                    ..base.clone()
                });
            }
        }
    }
    Ok(cases)
}

/// The price-headed models' cases (M as built) and the price model's of one size.
fn price_cases(plan: &Plan, price_headed: &[(PathBuf, usize)], base: &Case) -> Vec<Case> {
    let (robots, tasks) = (base.robots, base.tasks);
    let mut cases = Vec::new();
    for dir in price_headed.iter().filter(|(_, m)| *m == tasks) {
        for block in [robots.div_ceil(10), robots] {
            cases.push(Case {
                model: Some(dir.0.clone()),
                block,
                no_repair: true,
                ..base.clone()
            });
        }
    }
    let price = plan.price_model.join(PriceModel::FILE_NAME);
    if price.exists() {
        let modes = [
            (PriceMode::Sequential, 1),
            (PriceMode::Sequential, robots.div_ceil(100)),
            (PriceMode::OneShot, 1),
        ];
        for (mode, block) in modes {
            cases.push(Case {
                price: Some((price.clone(), mode)),
                block,
                ..base.clone()
            });
        }
    }
    cases
}

/// The row label of a case.
pub fn label(case: &Case) -> String {
    if let Some((_, mode)) = &case.price {
        let block = if case.block > 1 {
            format!(", prices every {} robots", case.block)
        } else {
            String::new()
        };
        return format!("price model (ours), {}{block}, no repair", mode.name());
    }
    if case.no_repair {
        let mode = if case.block >= case.robots {
            "one-shot (one pass)".to_owned()
        } else {
            format!("network every {} robots", case.block)
        };
        return format!("AFGNet + price head (ours), {mode}, no repair");
    }
    match (case.method, case.exact_burn) {
        (Some(m), _) => m.to_string(),
        (None, true) => "learned, Burn path".into(),
        (None, false) => format!("learned, fast, B = {} + repair", case.block),
    }
}

/// The outcomes as a Markdown table, with % of OPT against the OPT case of the same N
/// and M.
pub fn markdown(outcomes: &[Outcome]) -> String {
    use std::fmt::Write;
    let mut out = String::new();
    let _ = writeln!(
        out,
        "| N | M | method | passes | time | % of OPT | rollout alone, % of OPT | repair moves | repair time | peak RSS |"
    );
    let _ = writeln!(out, "|---|---|---|---|---|---|---|---|---|---|");
    for o in outcomes {
        let opt = outcomes
            .iter()
            .find(|p| {
                p.case.method == Some(Method::Opt)
                    && (p.case.robots, p.case.tasks) == (o.case.robots, o.case.tasks)
            })
            .map_or(f64::NAN, |p| p.welfare);
        let percent = |w: f64| format!("{:.2} %", 100.0 * w / opt);
        let trained = if o.case.method.is_none() && o.case.model.is_none() && o.case.price.is_none()
        {
            " (untrained)"
        } else {
            ""
        };
        let _ = writeln!(
            out,
            "| {} | {} | {}{} | {} | {} | {} | {} | {} | {} | {} |",
            o.case.robots,
            o.case.tasks,
            label(&o.case),
            trained,
            o.passes.map_or("–".into(), |p| p.to_string()),
            duration(Duration::from_secs_f64(o.seconds)),
            percent(o.welfare),
            o.rollout_welfare
                .filter(|_| o.repair_moves.is_some())
                .map_or("–".into(), percent),
            o.repair_moves.map_or("–".into(), |m| m.to_string()),
            o.repair_seconds
                .map_or("–".into(), |s| duration(Duration::from_secs_f64(s))),
            o.peak_rss_mib.map_or("–".into(), |m| format!("{m:.0} MiB")),
        );
    }
    out
}

// The command.
use std::process::Command;

use anyhow::{Context, Result, bail};
use clap::Args;

/// The options of `cargo xtask bench-scale`.
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

/// Runs `cargo xtask bench-scale` and prints its table.
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
