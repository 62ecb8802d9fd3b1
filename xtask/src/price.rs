//! `cargo xtask train-price`: the price-structured model (ours), trained on the exact Q*.

use std::path::{Path, PathBuf};
use std::time::Instant;

use afg_baseline::{Allocator, Method};
use afg_eval::{evaluate, optima};
use afg_game::Instance;
use afg_learn::{PriceMode, PriceModel, PricePolicy, PriceRound, PriceTrainConfig, PriceTrainer};
use anyhow::{Context, Result, bail};
use clap::Args;
use serde::{Deserialize, Serialize};

/// File names of a price-model run directory (besides the model's own,
/// `PriceModel::FILE_NAME`).
const LOG_FILE: &str = "log.jsonl";
const SUMMARY_FILE: &str = "summary.json";

#[derive(Args)]
pub struct PriceArgs {
    /// Robots per training instance N.
    #[arg(long, default_value_t = 60)]
    scale: usize,
    /// Tasks per training instance M.
    #[arg(long, default_value_t = 5)]
    tasks: usize,
    /// DAgger rounds (each: roll out, fit, validate).
    #[arg(long)]
    rounds: Option<usize>,
    /// Instances rolled out per round.
    #[arg(long)]
    episodes: Option<usize>,
    /// Adam steps per round.
    #[arg(long)]
    steps: Option<usize>,
    /// States per Adam step.
    #[arg(long)]
    batch: Option<usize>,
    /// Adam learning rate at the start (falls linearly to a tenth).
    #[arg(long)]
    lr: Option<f64>,
    /// Width of the two hidden layers.
    #[arg(long)]
    hidden: Option<usize>,
    /// The expert acts with probability DECAY^round in the rollouts.
    #[arg(long)]
    expert_decay: Option<f64>,
    /// Weight of the one-shot loss (the empty state's prices against the exact ones);
    /// 0 trains on Q* alone.
    #[arg(long)]
    one_shot_weight: Option<f64>,
    /// Seed of everything random in the run.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Run directory: price.json (weights and settings), log.jsonl (one line per round),
    /// summary.json (the command and its wall time). An existing model is not overwritten
    /// unless --force is given.
    #[arg(long)]
    out: PathBuf,
    /// Replace an existing model in --out.
    #[arg(long)]
    force: bool,
}

/// What `summary.json` records: enough to rerun the run and to say what it cost.
#[derive(Serialize, Deserialize)]
pub struct PriceSummary {
    /// The command that reproduces the run.
    pub command: String,
    /// Wall time of the whole run.
    pub wall_s: f64,
    /// The last round.
    pub last: PriceRound,
}

fn command_line(args: &PriceArgs) -> String {
    let mut c = format!(
        "cargo xtask train-price --scale {} --tasks {} --seed {}",
        args.scale, args.tasks, args.seed
    );
    let options: [(&str, Option<String>); 8] = [
        ("rounds", args.rounds.map(|v| v.to_string())),
        ("episodes", args.episodes.map(|v| v.to_string())),
        ("steps", args.steps.map(|v| v.to_string())),
        ("batch", args.batch.map(|v| v.to_string())),
        ("lr", args.lr.map(|v| v.to_string())),
        ("hidden", args.hidden.map(|v| v.to_string())),
        ("expert-decay", args.expert_decay.map(|v| v.to_string())),
        (
            "one-shot-weight",
            args.one_shot_weight.map(|v| v.to_string()),
        ),
    ];
    for (name, value) in options {
        if let Some(v) = value {
            c += &format!(" --{name} {v}");
        }
    }
    c + &format!(" --out {}", args.out.display())
}

pub fn run(args: PriceArgs) -> Result<()> {
    let model_path = args.out.join(PriceModel::FILE_NAME);
    if model_path.exists() && !args.force {
        bail!(
            "{} exists; pass --force to replace it",
            model_path.display()
        );
    }
    let mut config = PriceTrainConfig::new(args.scale, args.tasks, args.seed);
    config.rounds = args.rounds.unwrap_or(config.rounds);
    config.episodes_per_round = args.episodes.unwrap_or(config.episodes_per_round);
    config.steps_per_round = args.steps.unwrap_or(config.steps_per_round);
    config.batch = args.batch.unwrap_or(config.batch);
    config.lr = args.lr.unwrap_or(config.lr);
    config.network.hidden = args.hidden.unwrap_or(config.network.hidden);
    config.expert_decay = args.expert_decay.unwrap_or(config.expert_decay);
    config.one_shot_weight = args.one_shot_weight.unwrap_or(config.one_shot_weight);
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let start = Instant::now();
    let mut trainer = PriceTrainer::new(config)?;
    let bar = crate::progress(trainer.config().rounds as u64, "train-price");
    let mut log = String::new();
    let mut last = None;
    while !trainer.is_finished() {
        let round = trainer.round()?;
        bar.inc(1);
        bar.println(format!(
            "round {:>3}  states {:>7}  expert {:.3}  loss {:.5}  sequential {:.2} %  one-shot {:.2} %",
            round.round, round.states, round.expert_share, round.loss, round.sequential, round.one_shot
        ));
        log += &serde_json::to_string(&round)?;
        log.push('\n');
        afg_game::io::write_atomic(&args.out.join(LOG_FILE), log.as_bytes())?;
        last = Some(round);
    }
    bar.finish_and_clear();
    trainer.model().save(&model_path)?;
    let summary = PriceSummary {
        command: command_line(&args),
        wall_s: start.elapsed().as_secs_f64(),
        last: last.expect("at least one round"),
    };
    afg_game::io::write_atomic(
        &args.out.join(SUMMARY_FILE),
        serde_json::to_string_pretty(&summary)?.as_bytes(),
    )?;
    println!("wrote {} ({:.0} s)", model_path.display(), summary.wall_s);
    Ok(())
}

/// One ablation of the price model: what it was trained with, and where it lives.
struct Ablation {
    label: &'static str,
    /// Directory under the repository root; `None` for the untrained model (Nearest).
    dir: Option<&'static str>,
}

const ABLATIONS: [Ablation; 4] = [
    Ablation {
        label: "untrained (all prices 0: Nearest) — the structure alone",
        dir: None,
    },
    Ablation {
        label: "Q* regression on the expert's states only (no DAgger, no one-shot loss)",
        dir: Some("models/ablations/price_n60_expert"),
    },
    Ablation {
        label: "Q* regression with DAgger, no one-shot loss",
        dir: Some("models/ablations/price_n60_qstar"),
    },
    Ablation {
        label: "Q* regression with DAgger + one-shot price loss (the committed model)",
        dir: Some("models/price_n60"),
    },
];

/// The scales of the ablation table.
const ABLATION_SIZES: [usize; 4] = [20, 60, 100, 1000];

/// One row of the ablation table: % of OPT, sequential and one-shot, per scale.
#[derive(Serialize)]
pub struct AblationRow {
    pub method: String,
    pub command: Option<String>,
    /// `(N, sequential, one-shot)`.
    pub percent_of_opt: Vec<(usize, f64, f64)>,
}

/// The ablation rows whose models are committed, on the first `instances` of each
/// test set.
pub fn ablation(root: &Path, instances: usize) -> Result<Vec<AblationRow>> {
    let mut sets = Vec::new();
    for n in ABLATION_SIZES {
        let insts: Vec<Instance> = crate::datasets::load(n)?
            .into_iter()
            .take(instances)
            .collect();
        let opt = optima(&insts)?;
        sets.push((n, insts, opt));
    }
    let mut rows = Vec::new();
    for a in &ABLATIONS {
        let (policies, command): (Vec<Box<dyn Allocator>>, _) = match a.dir {
            None => (vec![Method::Nearest.allocator(0)], None),
            Some(dir) => {
                let path = root.join(dir).join(PriceModel::FILE_NAME);
                if !path.exists() {
                    continue;
                }
                let summary: PriceSummary = serde_json::from_str(
                    &std::fs::read_to_string(root.join(dir).join(SUMMARY_FILE))
                        .with_context(|| format!("{dir} has a model but no {SUMMARY_FILE}"))?,
                )?;
                let modes = [PriceMode::Sequential, PriceMode::OneShot];
                let policies = modes
                    .into_iter()
                    .map(|m| Ok(Box::new(PricePolicy::load(&path, m)?) as Box<dyn Allocator>))
                    .collect::<Result<_>>()?;
                (policies, Some(summary.command))
            }
        };
        let mut percent_of_opt = Vec::new();
        for (n, insts, opt) in &sets {
            let score = |p: &dyn Allocator| -> Result<f64> {
                Ok(evaluate(a.label, p, insts, opt)?.percent_of_opt)
            };
            let sequential = score(policies[0].as_ref())?;
            let one_shot = match policies.get(1) {
                Some(p) => score(p.as_ref())?,
                None => sequential,
            };
            percent_of_opt.push((*n, sequential, one_shot));
        }
        rows.push(AblationRow {
            method: a.label.to_owned(),
            command,
            percent_of_opt,
        });
    }
    Ok(rows)
}

/// The ablation table in Markdown (inside the block that `--verify` checks).
pub fn ablation_markdown(rows: &[AblationRow], instances: usize) -> String {
    let mut s = format!(
        "### The price model (ours): what each part adds — % of OPT, sequential / one-shot, first {instances} instances of each test set\n\n| method |"
    );
    for n in ABLATION_SIZES {
        s += &format!(" N = {n} sequential | N = {n} one-shot |");
    }
    s += "\n|---|";
    s += &"---|".repeat(2 * ABLATION_SIZES.len());
    s.push('\n');
    for r in rows {
        s += &format!("| {} |", r.method);
        for (_, seq, one) in &r.percent_of_opt {
            s += &format!(" {seq:.2} % | {one:.2} % |");
        }
        s.push('\n');
    }
    s += "\nCommands: ";
    let commands: Vec<String> = rows
        .iter()
        .filter_map(|r| r.command.as_ref().map(|c| format!("`{c}`")))
        .collect();
    s += &commands.join(", ");
    s += ".\n\n";
    s
}
