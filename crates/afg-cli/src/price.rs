//! `afg train-price`: the price-structured model (ours), trained on the exact Q*.

use std::path::PathBuf;

use afg_learn::price::{PriceModel, PriceTrainConfig, PriceTrainer};
use anyhow::{Result, bail};
use clap::Args;
use serde::Serialize;

/// `afg train-price`: the price model's training settings and run directory.
#[derive(Args, Serialize)]
pub struct PriceArgs {
    /// Robots per training instance N.
    #[arg(long, default_value_t = 60)]
    scale: usize,
    /// Tasks per training instance M.
    #[arg(long, default_value_t = afg_game::GeneratorConfig::PAPER_TASKS)]
    tasks: usize,
    /// Seed of everything random in the run.
    #[arg(long, default_value_t = 0)]
    seed: u64,
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
    /// Run directory: price.json (weights and settings), log.jsonl (one line per round),
    /// manifest.json (the kind of model, the command and its wall time). An existing model is not overwritten
    /// unless --force is given.
    #[arg(long)]
    out: PathBuf,
    /// Replace an existing model in --out.
    #[arg(long)]
    #[serde(skip)]
    force: bool,
}

/// Trains a price model into its run directory.
///
/// # Errors
/// Bad settings, a directory that already holds a run, or a failed write.
pub fn run(args: PriceArgs) -> Result<()> {
    let model_path = args.out.join(PriceModel::FILE_NAME);
    if model_path.exists() && !args.force {
        bail!(
            "{} exists; pass --force to replace it",
            model_path.display()
        );
    }
    let mut config = PriceTrainConfig::new(args.scale, args.tasks, args.seed);
    crate::set_given!(config;
        rounds = args.rounds,
        episodes_per_round = args.episodes,
        steps_per_round = args.steps,
        batch = args.batch,
        lr = args.lr,
        network.hidden = args.hidden,
        expert_decay = args.expert_decay,
        one_shot_weight = args.one_shot_weight,
    );
    let trainer = PriceTrainer::new(config)?;
    let bar = afg_eval::report::progress(trainer.config().rounds as u64, "train-price");
    let command = format!("afg train-price {}", crate::command_args(&args).join(" "));
    let manifest = trainer.run_in(&args.out, command, |round| {
        bar.inc(1);
        bar.println(format!(
            "round {:>3}  states {:>7}  expert {:.3}  loss {:.5}  sequential {:.2} %  one-shot {:.2} %",
            round.round, round.states, round.expert_share, round.loss, round.sequential, round.one_shot
        ));
    })?;
    bar.finish_and_clear();
    let seconds = manifest.wall_time_s.unwrap_or_default();
    println!("wrote {} ({seconds:.0} s)", model_path.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    /// The committed price runs' commands are written back as they were given.
    #[test]
    fn command_args_write_a_command_back() {
        for run in [
            "ours/price_n60",
            "ablations/price_expert_n60",
            "ablations/price_dagger_n60",
        ] {
            let dir = crate::repo_root().join("models").join(run);
            let command = afg_learn::run::RunDir::new(&dir)
                .manifest()
                .unwrap()
                .command;
            let Ok(crate::Command::TrainPrice(args)) =
                crate::parse(command.strip_prefix("afg ").unwrap())
            else {
                unreachable!("a train-price command")
            };
            let again = format!("afg train-price {}", crate::command_args(&args).join(" "));
            assert_eq!(again, command);
        }
    }
}
