//! `afg train` (and `cargo xtask train`, the same code): a Q network by DQN or Double DQN.

use std::path::PathBuf;
use std::time::Duration;

use afg_learn::{
    run::RunDir,
    train::{Session, TrainConfig},
};
use anyhow::{Context, Result, bail};
use clap::Args;

use crate::settings::TrainSettings;

/// `afg train`: the training settings and the run directory.
#[derive(Args, Default)]
pub struct TrainArgs {
    /// The training settings.
    #[command(flatten)]
    pub settings: TrainSettings,
    /// Run directory: config.json, log.jsonl, checkpoint/, and model.{json,mpk} at the end.
    #[arg(long, conflicts_with = "resume")]
    pub out: Option<PathBuf>,
    /// Continue the run in this directory from its last checkpoint.
    #[arg(long)]
    pub resume: Option<PathBuf>,
    /// Seconds between checkpoints.
    #[arg(long, default_value_t = 300)]
    pub checkpoint_secs: u64,
}

impl TrainArgs {
    fn config(&self) -> Result<TrainConfig> {
        Ok(self.settings.to_config()?)
    }
}

/// Trains (or resumes) a run, checkpointing as it goes. `program` is the command the
/// user ran (`afg train` or `cargo xtask train`), for the advice in messages.
///
/// # Errors
/// Bad settings, a directory that already holds a run, a resume that cannot continue,
/// or a failed write.
pub fn run(args: TrainArgs, program: &str) -> Result<()> {
    let mut session = match &args.resume {
        Some(dir) => {
            check_resume(&args, dir, program)?;
            if let Some(line) = RunDir::new(dir).torn_log_line()? {
                eprintln!("note: line {line} of the log was cut short by a crash; dropped");
            }
            let session =
                Session::resume(dir).with_context(|| format!("resuming {}", dir.display()))?;
            let step = session.trainer().steps_done();
            eprintln!("resuming {} at step {step}", dir.display());
            session
        }
        None => {
            let config = args.config()?;
            let dir = args
                .out
                .as_ref()
                .context("pass --out DIR for a new run (or --resume DIR)")?;
            Session::start(dir, config, git_revision())?
        }
    };
    let config = session.trainer().config().clone();
    let name = format!(
        "{}_{} N={}",
        config.network.name(),
        config.algo.name(),
        config.robots
    );
    let bar = afg_eval::report::progress(config.steps, &name);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{msg} [{bar:25}] {pos}/{len} {per_sec} eta {eta}")
            .expect("valid template")
            .progress_chars("=> "),
    );
    bar.set_position(session.trainer().steps_done());
    let mut last_val = f64::NAN;
    let every = Duration::from_secs(args.checkpoint_secs);
    let v = session.run(every, |report| {
        let (step, loss, epsilon) = (report.step, report.loss, report.epsilon);
        if let Some(result) = &report.validation {
            last_val = result.welfare;
            if result.collapsed() {
                bar.suspend(|| {
                    eprintln!(
                        "warning: step {step}: collapse — on average {:.0} % of the robots took one task",
                        100.0 * result.largest_task_share
                    )
                });
            }
        }
        bar.set_position(step);
        bar.set_message(format!(
            "{name} ε {epsilon:.2} loss {loss:.4} val {last_val:.2}"
        ));
    })?;
    bar.finish_and_clear();
    println!(
        "{name}: {} steps; validation welfare {:.3} ({:.2} % of OPT); model in {}",
        session.trainer().steps_done(),
        v.welfare,
        v.percent_of_opt,
        session.run_dir().weights().display()
    );
    Ok(())
}

/// Refuses what `--resume DIR` cannot do, saying what to do instead: extend a finished
/// run (its ε and learning-rate schedules are fixed by its budget), or change the
/// settings of an unfinished one.
fn check_resume(args: &TrainArgs, dir: &std::path::Path, program: &str) -> Result<()> {
    let run = RunDir::new(dir);
    let config = run.config()?;
    if run.has_weights() {
        bail!(
            "{} is a finished run ({} steps): a run cannot be extended, because its ε and \
             learning-rate schedules are fixed by its budget; start a new run from its \
             weights instead: {program} --init-from {} --steps K --out NEW_DIR \
             (with the run's other settings)",
            dir.display(),
            config.steps,
            dir.display()
        );
    }
    if !args.settings.is_empty() && args.settings.to_config().ok() != Some(config) {
        bail!(
            "{} holds a run with its own settings (config.json); resume it without \
             settings, or start a new run with --out",
            dir.display()
        );
    }
    Ok(())
}

/// The checked-out git revision, if there is one.
fn git_revision() -> Option<String> {
    std::process::Command::new("git")
        .args(["rev-parse", "HEAD"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_owned())
}

/// The command line of `program` (`afg train` or `cargo xtask train`, which take the
/// same flags) that reproduces a configuration: what a run's manifest records.
pub fn command_line(program: &str, config: &TrainConfig, dir: &std::path::Path) -> String {
    let settings = crate::command_args(&TrainSettings::from_config(config)).join(" ");
    format!("{program} {settings} --out {}", dir.display())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Command, afg, parse};
    use std::path::Path;

    fn train_args(line: &str) -> TrainArgs {
        let Ok(Command::Train(args)) = parse(line) else {
            unreachable!("a train command: {line}")
        };
        args
    }

    #[test]
    fn command_line_reproduces_the_configuration() {
        for flags in [
            "--scale 20",
            "--scale 60 --algo dqn --net s2v --steps 50 --seed 3",
            "--scale 20 --lr 0.001 --batch 64 --n-step 3",
            "--scale 20 --gain-residual",
            "--scale 100 --paper",
            "--scale 20 --constant-lr --lr 0.01",
            "--scale 60 --units mean-reward --target-sync 77 --parallel-envs 8",
            "--scale 60 --units bounded",
            "--scale 20 --paper --target-sync 50",
            "--scale 60 --no-shaping",
            "--scale 60 --shaping optimal",
            "--scale 20 --paper --shaping greedy",
            "--scale 100 --init-from models/paper/afgnet_ddqn_n60 --eps-start 0.1",
            "--scale 60 --price-head --algo qstar",
            "--scale 60 --tasks 50 --price-head --algo qstar",
            "--scale 60 --price-head --algo qstar --price-loss 0.5",
            "--scale 600 --tasks 50 --steps 100 --validation-instances 8 --validate-every 50",
            "--scale 60 --price-head --demos 64 --demo-margin 0.1 --demo-share 0.5",
        ] {
            let config = train_args(&format!("train {flags} --out models/x"))
                .config()
                .unwrap();
            let line = command_line("cargo xtask train", &config, Path::new("models/x"));
            let again = train_args(line.strip_prefix("cargo xtask ").unwrap());
            assert_eq!(again.config().unwrap(), config, "{line}");
            assert!(line.ends_with(" --out models/x"), "{line}");
        }
    }

    #[test]
    fn every_committed_manifest_records_the_command_its_config_gives() {
        let root = crate::repo_root();
        let mut checked = 0;
        for run in RunDir::find_all(&root.join("models")).unwrap() {
            let (Ok(manifest), Ok(config)) = (run.manifest(), run.config()) else {
                continue; // a price model, or a run without a manifest
            };
            let dir = run.path().strip_prefix(&root).unwrap();
            let line = command_line("cargo xtask train", &config, dir);
            assert_eq!(line, manifest.command, "{}", dir.display());
            checked += 1;
        }
        assert!(checked >= 20, "only {checked} manifests");
    }

    #[test]
    fn train_writes_log_checkpoint_model_and_a_plottable_curve() {
        let dir = std::env::temp_dir().join(format!("afg-cli-train-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let run_dir = dir.join("run");
        let out = run_dir.to_str().unwrap();
        afg(&format!(
            "train --scale 10 --steps 120 --batch 32 --net s2v --out {out}"
        ))
        .unwrap();
        // What the run directory holds is tested in afg-learn (Session).
        afg_learn::policy::LearnedPolicy::load(&run_dir.join("model")).unwrap();
        assert!(run_dir.join("checkpoint/state.json").exists());

        let svg = dir.join("curves.svg");
        afg(&format!("plot-curves {out} --out {}", svg.display())).unwrap();
        let text = std::fs::read_to_string(&svg).unwrap();
        assert!(text.starts_with("<svg") && text.trim_end().ends_with("</svg>"));
        assert!(text.contains("run (s2v_ddqn, N = 10)"));

        // A second run into the same directory is refused; nothing is overwritten.
        let before = std::fs::read(run_dir.join("model.mpk")).unwrap();
        let err = afg(&format!("train --scale 10 --steps 5 --out {out}")).unwrap_err();
        let message = err.to_string();
        assert!(
            message.contains("already holds a training run"),
            "{message}"
        );
        // Extending the finished run is refused, saying how to start from its weights.
        let err = afg(&format!("train --resume {out} --steps 500")).unwrap_err();
        let message = err.to_string();
        assert!(
            message.contains("finished run (120 steps)")
                && message.contains("afg train --init-from"),
            "{message}"
        );
        assert_eq!(std::fs::read(run_dir.join("model.mpk")).unwrap(), before);
        // An unfinished run resumed with other settings is refused too.
        std::fs::remove_file(run_dir.join("model.mpk")).unwrap();
        let err = afg(&format!("train --resume {out} --scale 20 --steps 5")).unwrap_err();
        assert!(err.to_string().contains("its own settings"), "{err}");
        // Unknown values are refused by the parser.
        assert!(afg(&format!("train --scale 20 --net gcn --out {out}")).is_err());
        assert!(afg(&format!("train --scale 20 --algo ppo --out {out}")).is_err());
        let err = afg(&format!("train --scale 33 --out {}/x", dir.display())).unwrap_err();
        assert!(err.to_string().contains("no default budget"), "{err}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
