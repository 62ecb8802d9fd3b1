//! `afg train-staffing`: the staffing model (ours) for the team games (thresholds, and
//! skills with `--skills`), trained on the staffing of certified optima.

use std::path::PathBuf;

use afg_game::{Family, GameSize, GeneratorKnobs, SkillDraw};
use afg_learn::staffing::{StaffingModel, StaffingTrainConfig, StaffingTrainer};
use anyhow::{Result, bail};
use clap::Args;
use serde::Serialize;

/// `afg train-staffing`: the staffing model's training settings and run directory.
#[derive(Args, Serialize)]
pub struct StaffingArgs {
    /// Sizes of the training games as NxM (thresholds uniform in [N/M, 2N/M]).
    #[arg(long, value_delimiter = ',')]
    #[serde(serialize_with = "joined")]
    sizes: Vec<GameSize>,
    /// Skill games: S binary skills, each robot holding each with probability
    /// --skill-share, each task requiring each skill in an amount uniform in
    /// --requires (as `afg gen --skills`). A model trained with skills plays skill games
    /// (it reads three more features per task); without, it refuses them.
    #[arg(long, value_name = "S")]
    skills: Option<usize>,
    /// With --skills: the probability that a robot holds a skill (default 0.5).
    #[arg(long, value_name = "P")]
    skill_share: Option<f64>,
    /// With --skills: each task requires each skill in an amount uniform in LO..=HI
    /// (default 1,2).
    #[arg(long, value_delimiter = ',', num_args = 1, value_names = ["LO,HI"])]
    #[serde(serialize_with = "joined")]
    requires: Vec<usize>,
    /// Draw the games from these named families instead of the scarce game, --games of
    /// each per size (as `afg gen --family`; docs/families.md): a model for games
    /// drawn unlike ours. It reads the skill features where any family draws skills;
    /// not with --skills (the families draw their own).
    #[arg(long, value_delimiter = ',', value_name = "NAMES")]
    #[serde(serialize_with = "joined")]
    families: Vec<Family>,
    /// Training games per size (per family and size, with --families).
    #[arg(long)]
    games: Option<usize>,
    /// Validation games per size (other seeds).
    #[arg(long)]
    validation_games: Option<usize>,
    /// The exact solver's time limit per game, seconds.
    #[arg(long)]
    label_time_limit: Option<f64>,
    /// Passes over the labelled games.
    #[arg(long)]
    epochs: Option<usize>,
    /// Games per Adam step.
    #[arg(long)]
    batch: Option<usize>,
    /// Adam learning rate at the start (falls linearly to a tenth).
    #[arg(long)]
    lr: Option<f64>,
    /// The structured loss's margin per task (in units of k / (N/M)).
    #[arg(long)]
    margin: Option<f64>,
    /// Width of the two hidden layers.
    #[arg(long)]
    hidden: Option<usize>,
    /// Seed of everything random in the run.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Run directory: labels.jsonl (the labelled games; a stopped run resumes from it),
    /// log.jsonl (one line per epoch), staffing.json (weights and settings),
    /// manifest.json. An existing model is not overwritten unless --force is given.
    #[arg(long)]
    out: PathBuf,
    /// Replace an existing model in --out.
    #[arg(long)]
    #[serde(skip)]
    force: bool,
}

/// A list flag as written: `100x10,300x20` (nothing where none was given).
fn joined<S: serde::Serializer, T: std::fmt::Display>(
    items: &[T],
    out: S,
) -> Result<S::Ok, S::Error> {
    if items.is_empty() {
        return out.serialize_none();
    }
    let text: Vec<String> = items.iter().map(T::to_string).collect();
    out.serialize_str(&text.join(","))
}

/// The skills of `--skills`, `--skill-share` and `--requires`, as `afg gen` draws them.
fn skill_draw(args: &StaffingArgs) -> Result<Option<SkillDraw>> {
    let requires = (!args.requires.is_empty()).then_some(args.requires.as_slice());
    let knobs = GeneratorKnobs {
        skills: args.skills,
        skill_share: args.skill_share,
        requires: crate::generate::pair("--requires", requires)?,
        ..GeneratorKnobs::default()
    };
    Ok(knobs.skill_draw()?)
}

/// Trains a staffing model into its run directory.
///
/// # Errors
/// Bad settings, a directory that already holds a model (or another run's labels), or a
/// failed write.
pub fn run(args: StaffingArgs) -> Result<()> {
    let model_path = args.out.join(StaffingModel::FILE_NAME);
    if model_path.exists() && !args.force {
        bail!(
            "{} exists; pass --force to replace it",
            model_path.display()
        );
    }
    let mut config = StaffingTrainConfig::new(args.seed);
    if !args.sizes.is_empty() {
        config.sizes.clone_from(&args.sizes);
    }
    config.skills = skill_draw(&args)?;
    config.families.clone_from(&args.families);
    crate::set_given!(config;
        games = args.games,
        validation_games = args.validation_games,
        label_time_limit = args.label_time_limit,
        epochs = args.epochs,
        batch = args.batch,
        lr = args.lr,
        margin = args.margin,
        network.hidden = args.hidden,
    );
    let trainer = StaffingTrainer::new(config)?;
    let games = trainer.config().training_game_count() as u64;
    let bar = afg_eval::report::progress(games, "label games");
    let command = format!(
        "afg train-staffing {}",
        crate::command_args(&args).join(" ")
    );
    let epochs = std::cell::Cell::new(false);
    let manifest = trainer.run_in(
        &args.out,
        command,
        |_| bar.inc(1),
        |epoch| {
            if !epochs.replace(true) {
                bar.finish_and_clear();
            }
            println!(
                "epoch {:>3}  loss {:.4}  staffed as the label {:.1} %  validation {:.2} % of OPT",
                epoch.epoch, epoch.loss, epoch.agree, epoch.percent_of_opt
            );
        },
    )?;
    let seconds = manifest.wall_time_s.unwrap_or_default();
    println!("wrote {} ({seconds:.0} s)", model_path.display());
    Ok(())
}

#[cfg(test)]
mod tests {
    /// The committed staffing run's command is written back as it was given.
    #[test]
    fn command_args_write_a_command_back() {
        let dir = crate::repo_root().join("models/ours/staffing_teams");
        let command = afg_learn::run::RunDir::new(&dir)
            .manifest()
            .unwrap()
            .command;
        let with_sizes = format!("{command} --sizes 100x10,300x20");
        for line in [command.as_str(), with_sizes.as_str()] {
            let Ok(crate::Command::TrainStaffing(args)) =
                crate::parse(line.strip_prefix("afg ").unwrap())
            else {
                unreachable!("a train-staffing command")
            };
            let again = format!(
                "afg train-staffing {}",
                crate::command_args(&args).join(" ")
            );
            let mut words: Vec<&str> = line.split(' ').collect();
            let mut back: Vec<&str> = again.split(' ').collect();
            words.sort_unstable();
            back.sort_unstable();
            assert_eq!(back, words, "{again}");
        }
    }
}
