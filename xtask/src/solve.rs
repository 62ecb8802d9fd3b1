//! `cargo xtask solve`: one allocator on an instance file or a committed dataset.

use std::path::PathBuf;

use afg_baseline::{Allocator, Method, Optimum};
use afg_game::{Instance, Preference};
use anyhow::{Context, Result};
use clap::Args;
use serde::Serialize;

#[derive(Args)]
#[command(group = clap::ArgGroup::new("source").required(true))]
#[command(group = clap::ArgGroup::new("allocator").required(true))]
pub struct SolveArgs {
    /// Allocator: opt, da (GRAPE, centralised), da-decentralised, da-balanced, greedy, nearest, random.
    #[arg(long, short, group = "allocator")]
    method: Option<Method>,
    /// A learned policy instead: a trained run directory (holding model.json and
    /// model.mpk), e.g. models/afgnet_ddqn_n20.
    #[arg(long, group = "allocator")]
    model: Option<PathBuf>,
    /// Learned policy: robots per network evaluation [default: 1, the exact greedy rollout].
    #[arg(long)]
    block: Option<usize>,
    /// Learned policy: balanced best-response sweeps after the rollout (Def. 3 stable result).
    #[arg(long)]
    repair: bool,
    /// Learned policy: roll out with the Burn network (the slow reference path).
    #[arg(long)]
    exact_burn: bool,
    /// An instance JSON file (format "afg-instance").
    #[arg(long, group = "source")]
    input: Option<PathBuf>,
    /// A committed dataset by robot count: 20, 60, 100, 500 or 1000.
    #[arg(long, group = "source")]
    dataset: Option<usize>,
    /// Use only the first K instances of the dataset.
    #[arg(long)]
    limit: Option<usize>,
    /// Seed of the randomised methods (random, da-decentralised).
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Print JSON (per instance and mean) instead of text.
    #[arg(long)]
    json: bool,
}

/// One instance's result.
#[derive(Serialize)]
pub struct Row {
    pub welfare: f64,
    pub opt_welfare: f64,
    pub percent_of_opt: f64,
    pub ns_rate_balanced: f64,
    pub ns_rate_selfish: f64,
    pub stats: afg_baseline::AllocStats,
}

impl Row {
    /// Runs `method` and OPT on `inst`.
    pub fn compute(inst: &Instance, method: &dyn Allocator) -> Result<Row> {
        let out = method.allocate(inst)?;
        let opt = Optimum.allocate(inst)?;
        let (welfare, opt_welfare) = (inst.welfare(&out.assignment), inst.welfare(&opt.assignment));
        Ok(Row {
            welfare,
            opt_welfare,
            percent_of_opt: 100.0 * welfare / opt_welfare,
            ns_rate_balanced: inst.ns_rate(&out.assignment, Preference::Balanced),
            ns_rate_selfish: inst.ns_rate(&out.assignment, Preference::Selfish),
            stats: out.stats,
        })
    }
}

#[derive(Serialize)]
struct Report {
    method: String,
    source: String,
    instances: usize,
    mean: Mean,
    rows: Vec<Row>,
}

#[derive(Serialize)]
struct Mean {
    welfare: f64,
    opt_welfare: f64,
    percent_of_opt: f64,
    ns_rate_balanced: f64,
    ns_rate_selfish: f64,
    iterations: f64,
    rounds: f64,
    messages: f64,
    seconds: f64,
}

pub fn run(args: SolveArgs) -> Result<()> {
    if args.model.is_none() && (args.block.is_some() || args.repair || args.exact_burn) {
        anyhow::bail!("--block, --repair and --exact-burn apply to a learned policy (--model DIR)");
    }
    let (source, mut instances) = match (&args.input, args.dataset) {
        (Some(p), _) => (
            p.display().to_string(),
            vec![Instance::read(p).with_context(|| format!("reading {}", p.display()))?],
        ),
        (None, Some(n)) => (format!("datasets/n{n}.jsonl"), crate::datasets::load(n)?),
        (None, None) => unreachable!("clap requires a source"),
    };
    if let Some(k) = args.limit {
        instances.truncate(k);
    }
    let (name, method): (String, Box<dyn Allocator>) = match (&args.method, &args.model) {
        (Some(m), _) => (m.to_string(), m.allocator(args.seed)),
        (None, Some(dir)) => {
            let mut policy = afg_learn::LearnedPolicy::load(&dir.join("model"))
                .with_context(|| format!("loading the policy in {}", dir.display()))?;
            policy.block = args.block.unwrap_or(1);
            policy.repair = args.repair;
            policy.exact_burn = args.exact_burn;
            (dir.display().to_string(), Box::new(policy))
        }
        (None, None) => unreachable!("clap requires an allocator"),
    };
    let bar = crate::progress(instances.len() as u64, &format!("{name} on {source}"));
    let rows = instances
        .iter()
        .map(|inst| {
            let row = Row::compute(inst, method.as_ref());
            bar.inc(1);
            row
        })
        .collect::<Result<Vec<_>>>()?;
    bar.finish_and_clear();
    let k = rows.len() as f64;
    let mean = |f: &dyn Fn(&Row) -> f64| rows.iter().map(f).sum::<f64>() / k;
    let m = Mean {
        welfare: mean(&|r| r.welfare),
        opt_welfare: mean(&|r| r.opt_welfare),
        percent_of_opt: mean(&|r| r.percent_of_opt),
        ns_rate_balanced: mean(&|r| r.ns_rate_balanced),
        ns_rate_selfish: mean(&|r| r.ns_rate_selfish),
        iterations: mean(&|r| r.stats.iterations as f64),
        rounds: mean(&|r| r.stats.rounds as f64),
        messages: mean(&|r| r.stats.messages as f64),
        seconds: mean(&|r| r.stats.wall_time.as_secs_f64()),
    };
    let report = Report {
        method: name,
        source,
        instances: rows.len(),
        mean: m,
        rows,
    };
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
        return Ok(());
    }
    let m = &report.mean;
    println!(
        "{} on {} ({} instance{})",
        report.method,
        report.source,
        report.instances,
        if report.instances == 1 { "" } else { "s" }
    );
    println!(
        "  welfare           {:>12.3}   (OPT {:.3})",
        m.welfare, m.opt_welfare
    );
    println!("  % of OPT          {:>12.2}", m.percent_of_opt);
    println!("  NS_rate balanced  {:>11.1} %", 100.0 * m.ns_rate_balanced);
    println!("  NS_rate selfish   {:>11.1} %", 100.0 * m.ns_rate_selfish);
    println!("  iterations        {:>12.1}", m.iterations);
    println!("  rounds            {:>12.1}", m.rounds);
    if m.messages > 0.0 {
        println!("  messages          {:>12.0}", m.messages);
    }
    println!("  time / instance   {:>10.3} ms", 1e3 * m.seconds);
    if report.instances > 1 {
        println!("  (means over instances; --json for each one)");
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use clap::Parser;

    fn solve(args: &[&str]) -> anyhow::Result<()> {
        let mut argv = vec!["cargo xtask", "solve"];
        argv.extend_from_slice(args);
        match crate::Cli::try_parse_from(argv)?.command {
            crate::Command::Solve(a) => super::run(a),
            _ => unreachable!("only solve here"),
        }
    }

    #[test]
    fn learned_policies_solve_and_bad_options_are_refused() {
        let model = crate::repo_root().join("models/afgnet_ddqn_n20");
        let model = model.to_str().unwrap();
        solve(&[
            "--model",
            model,
            "--dataset",
            "20",
            "--limit",
            "2",
            "--json",
        ])
        .unwrap();
        solve(&[
            "--model",
            model,
            "--dataset",
            "100",
            "--limit",
            "1",
            "--block",
            "7",
            "--repair",
        ])
        .unwrap();
        let err = solve(&[
            "--model",
            model,
            "--dataset",
            "20",
            "--exact-burn",
            "--block",
            "3",
        ])
        .unwrap_err();
        assert!(format!("{err:#}").contains("block 1"), "{err:#}");
        let err = solve(&["--model", "/nonexistent", "--dataset", "20"]).unwrap_err();
        assert!(format!("{err:#}").contains("/nonexistent"), "{err:#}");
        // A method and a model at once, or --block without a model: usage errors.
        assert!(solve(&["--method", "opt", "--model", model, "--dataset", "20"]).is_err());
        assert!(solve(&["--method", "opt", "--block", "2", "--dataset", "20"]).is_err());
    }
}
