//! `cargo xtask bench-scale`: the learned policy (fast path, block rollout, repair),
//! AFGNet with a price head (ours, no repair) and the price model (ours, no repair)
//! against OPT, GRAPE DA and greedy from N = 100 to 100 000, with the peak memory of
//! each run. Every case runs in its own child process (this binary with `--case`), so
//! the peak resident set size it reports belongs to that case alone.

use std::path::PathBuf;
use std::process::Command;
use std::time::{Duration, Instant};

use afg_baseline::Allocator;
use afg_baseline::Method;
use afg_game::{GeneratorConfig, Instance};
use afg_learn::{LearnedPolicy, NetworkConfig, PriceMode, PriceModel, PricePolicy, RunDir};
use anyhow::{Context, Result, bail};
use clap::Args;
use serde::{Deserialize, Serialize};

use afg_eval::tables::duration;

#[derive(Args)]
pub struct ScaleArgs {
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
    /// Trained run directory used for M = 5; other M use untrained weights (timing only).
    #[arg(long, default_value = "models/afgnet_ddqn_n20")]
    model: PathBuf,
    /// Price model (ours) run at every M, both modes, without repair; skipped if the
    /// directory holds no price.json.
    #[arg(long, default_value = "models/price_n60")]
    price_model: PathBuf,
    /// AFGNet with a price head (ours): run directories, each used at the M its network
    /// was built for, without repair, with 10 network passes and in one pass (one-shot);
    /// a directory that holds no model is skipped.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "models/afgnet_qstar_price_n60,models/afgnet_qstar_price_m50_n60"
    )]
    price_headed: Vec<PathBuf>,
    /// Seed of the instances (one per N and M).
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Print the results as JSON instead of a Markdown table.
    #[arg(long)]
    json: bool,
    /// Internal: run one case (JSON) and print its result.
    #[arg(long, hide = true)]
    case: Option<String>,
}

/// One measurement, run in a child process.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Case {
    robots: usize,
    tasks: usize,
    seed: u64,
    /// A classical method, or None for the learned policy.
    method: Option<Method>,
    #[serde(default)]
    block: usize,
    #[serde(default)]
    exact_burn: bool,
    #[serde(default)]
    model: Option<PathBuf>,
    /// The price model's file and mode, instead of the Q network.
    #[serde(default)]
    price: Option<(PathBuf, PriceMode)>,
    /// Learned policy: no repair after the rollout.
    #[serde(default)]
    no_repair: bool,
}

#[derive(Clone, Debug, Serialize, Deserialize)]
struct Outcome {
    case: Case,
    /// Whole run: graph, rollout and repair for the learned policy.
    seconds: f64,
    welfare: f64,
    /// Learned policy: welfare before the repair, passes, repair cost.
    rollout_welfare: Option<f64>,
    passes: Option<usize>,
    repair_moves: Option<u64>,
    repair_seconds: Option<f64>,
    /// Peak resident set size of the child process (instance and graph included).
    peak_rss_mib: Option<f64>,
}

fn instance(case: &Case) -> Result<Instance> {
    Ok(GeneratorConfig::paper(case.robots, case.tasks, case.seed).generate()?)
}

fn peak_rss_mib() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib / 1024.0)
}

fn run_case(case: Case) -> Result<Outcome> {
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
                Some(dir) => LearnedPolicy::load(&RunDir::new(dir).weights())
                    .with_context(|| format!("loading {}", dir.display()))?,
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
    out.peak_rss_mib = peak_rss_mib();
    Ok(out)
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

fn cases(args: &ScaleArgs) -> Result<Vec<Case>> {
    // The committed price-headed models and the M each was built for.
    let mut price_headed = Vec::new();
    for dir in &args.price_headed {
        let run = RunDir::new(dir);
        if run.has_weights() {
            let tasks = run
                .config()
                .with_context(|| format!("reading {}", dir.display()))?
                .network
                .tasks();
            price_headed.push((dir.clone(), tasks));
        }
    }
    let mut cases = Vec::new();
    for &tasks in &args.tasks {
        for &robots in &args.sizes {
            let base = Case {
                robots,
                tasks,
                seed: args.seed,
                method: None,
                block: 1,
                exact_burn: false,
                model: (tasks == 5).then(|| args.model.clone()),
                price: None,
                no_repair: false,
            };
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
            let price = args.price_model.join(PriceModel::FILE_NAME);
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
            for method in [Method::Opt, Method::Da, Method::DaBalanced, Method::Greedy] {
                cases.push(Case {
                    method: Some(method),
                    ..base.clone()
                });
            }
            if tasks == 5 && robots <= args.burn_up_to {
                cases.push(Case {
                    exact_burn: true,
                    ..base.clone()
                });
            }
            let mut blocks: Vec<usize> = std::iter::once(1)
                .chain(args.passes.iter().map(|&p| robots.div_ceil(p.max(1))))
                .filter(|&b| robots.div_ceil(b) * robots <= args.max_work)
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

fn label(case: &Case) -> String {
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

pub fn run(args: ScaleArgs) -> Result<()> {
    if let Some(case) = &args.case {
        let case: Case = serde_json::from_str(case).context("--case is JSON")?;
        println!("{}", serde_json::to_string(&run_case(case)?)?);
        return Ok(());
    }
    if args.tasks.contains(&5) && !args.model.join("model.json").exists() {
        bail!(
            "{} holds no trained model (model.json); pass --model DIR",
            args.model.display()
        );
    }
    let cases = cases(&args)?;
    let bar = crate::progress(cases.len() as u64, "bench-scale");
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
    println!(
        "| N | M | method | passes | time | % of OPT | rollout alone, % of OPT | repair moves | repair time | peak RSS |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for o in &outcomes {
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
        println!(
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
    Ok(())
}
